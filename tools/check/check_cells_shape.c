/* Geometry checks of voxels, hexahedra, wedges and pyramids (203..208), exact where they decide.
 *
 * What the words mean for a cell that is not a tet (the registry explanations say the same):
 * - its conformal split is the one `tetpack convert` makes (tpk_split_cell: quad faces cut along the
 *   diagonal through their smallest vertex id; 5 or 6 tets for a hexahedron, 3 for a wedge, 2 for a
 *   pyramid), with each tet ordered so that it is positive on the reference cell;
 * - inverted (204): every tet of that split is negative: the node order is mirrored (the converter turns
 *   such a cell over, but the input is wrong);
 * - zero volume (203): some tet of that split is exactly flat (a collapsed edge or face, or a corner in
 *   the plane of a face it does not belong to): the converter cannot split it into valid tets;
 * - split inverts (208): the tets of the split are not all positive or all negative (tpk_split_cell
 *   returns -1): the converter needs a centre point or --skip-bad-cells. A flat split tet counts here too.
 * - non-convex (206): a corner lies strictly outside the plane of a triangle of a face it is not on
 *   (quad faces: the triangles of both diagonals), relative to the cell's orientation;
 * - self-intersecting (207): two boundary triangles (quads cut as the converter cuts them) share a point
 *   outside their common vertices and edge. A strictly convex cell (every corner off a face strictly
 *   inside all its triangle planes) cannot have one: each face then meets the others only in their
 *   common corners and edges, so the pairwise test runs only on the other cells. */
#include <math.h>
#include <string.h>

#include "convert/cell_split.h"
#include "mesh/cell_types.h"
#include "check_cells_internal.h"
#include "convert/pipeline.h"
#include "base/exact_triangles.h"
#include "base/predicates.h"

/* mesh/cell_types.h: corners, faces (VTK node order, outward on a positively oriented cell) and a valid
 * positively oriented cell with these nodes (VTK parametric corners). */
typedef tpk_cell_shape cell_shape;

typedef struct cell_view {
    const cell_shape *s;
    int type;
    int64_t cell;
    int32_t ids[8];
    const double *p[8];
    int orientation; /* +1 valid split, -1 mirrored, 0 neither */
} cell_view;

/* Exact sign of det[b-a, c-a, d-a]: the inline filter decides almost every call, CGAL the rest. */
static int orient(const cell_view *v, int a, int b, int c, int d)
{
    int s = tpk_orient3d_filter(v->p[a], v->p[b], v->p[c], v->p[d]);
    return s ? s : tpk_orient3d_exact(v->p[a], v->p[b], v->p[c], v->p[d]);
}

static void cell_point(const tpk_mesh *mesh, const cell_view *v, tpk_example *ex)
{
    if (!ex)
        return;
    double centre[3];
    tpk_cell_centre(mesh, v->cell, centre);
    tpk_example_point(ex, centre);
}

/* The split recomputed on the reference corners (where it is always valid), its tets then signed on
 * the real ones: says which tets fold when tpk_split_cell refuses the cell. The split depends only on
 * the order of the ids, so ranks stand in for them. */
static void explain_split(const tpk_mesh *mesh, cell_view *v, tpk_cell_hits *hits)
{
    int32_t rank[8], out[6 * 4];
    int corner_of_rank[8], mirrored = 0;
    double ref[8][3];
    for (int i = 0; i < v->s->corners; i++) {
        rank[i] = 0;
        for (int j = 0; j < v->s->corners; j++)
            rank[i] += v->ids[j] < v->ids[i];
        corner_of_rank[rank[i]] = i;
        memcpy(ref[rank[i]], v->s->ref[i], sizeof ref[0]);
    }
    int n = tpk_split_cell(v->type, rank, &ref[0][0], out, &mirrored);
    int positive = 0, negative = 0, flat = 0, first_flat = -1;
    for (int t = 0; t < n && !mirrored; t++) {
        const int32_t *q = out + 4 * t;
        int s = orient(v, corner_of_rank[q[0]], corner_of_rank[q[1]], corner_of_rank[q[2]], corner_of_rank[q[3]]);
        positive += s > 0;
        negative += s < 0;
        flat += s == 0;
        if (s == 0 && first_flat < 0)
            first_flat = t;
    }
    if (flat) {
        tpk_example *ex = tpk_cell_hit(hits, 203, v->cell);
        tpk_cell_example_vertices(ex, mesh, v->cell);
        cell_point(mesh, v, ex);
        tpk_example_note(ex, "det = 0 for tet %d of %d of its split (%d flat)", first_flat + 1, n, flat);
    }
    tpk_example *ex = tpk_cell_hit(hits, 208, v->cell);
    tpk_cell_example_vertices(ex, mesh, v->cell);
    cell_point(mesh, v, ex);
    tpk_example_note(ex, "tets of its split: %d positive, %d negative, %d flat", positive, negative, flat);
}

static void check_split(const tpk_mesh *mesh, cell_view *v, tpk_cell_hits *hits)
{
    int32_t out[6 * 4];
    int mirrored = 0;
    int n = tpk_split_cell(v->type, v->ids, mesh->points, out, &mirrored);
    if (n > 0) {
        v->orientation = mirrored ? -1 : 1;
        if (mirrored) {
            tpk_example *ex = tpk_cell_hit(hits, 204, v->cell);
            tpk_cell_example_vertices(ex, mesh, v->cell);
            cell_point(mesh, v, ex);
            tpk_example_note(ex, "all %d tets of its split are negative (mirrored node order)", n);
        }
        return;
    }
    v->orientation = 0;
    explain_split(mesh, v, hits);
}

/* Cosine of the angle between the normals of triangles (a, b, c) and (a, c, d); 1 when one is
 * degenerate. (Cosines are compared; acos only for a reported face.) */
static double fold_cos(const double *a, const double *b, const double *c, const double *d)
{
    double u[3], w[3], x[3], n1[3], n2[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        w[k] = c[k] - a[k];
        x[k] = d[k] - a[k];
    }
    n1[0] = u[1] * w[2] - u[2] * w[1], n1[1] = u[2] * w[0] - u[0] * w[2], n1[2] = u[0] * w[1] - u[1] * w[0];
    n2[0] = w[1] * x[2] - w[2] * x[1], n2[1] = w[2] * x[0] - w[0] * x[2], n2[2] = w[0] * x[1] - w[1] * x[0];
    double l1 = sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
    double l2 = sqrt(n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2]);
    if (!(l1 > 0) || !(l2 > 0))
        return 1;
    double c12 = (n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]) / (l1 * l2);
    return c12 > 1 ? 1 : c12 < -1 ? -1 : c12;
}

/* 205: the warp of a quad is the larger fold over its two diagonals (as Verdict's warpage); an exactly
 * planar quad (exact orientation 0) has none, whatever rounding the normals would show. */
static void check_warp(const tpk_mesh *mesh, const cell_view *v, double limit, tpk_cell_hits *hits)
{
    double limit_cos = cos(limit * (M_PI / 180.0));
    for (int f = 0; f < v->s->face_count; f++) {
        if (v->s->face_size[f] != 4)
            continue;
        const int *q = v->s->faces[f];
        if (orient(v, q[0], q[1], q[2], q[3]) == 0)
            continue;
        const double *a = v->p[q[0]], *b = v->p[q[1]], *c = v->p[q[2]], *d = v->p[q[3]];
        double c1 = fold_cos(a, b, c, d), c2 = fold_cos(b, c, d, a), warp_cos = c1 < c2 ? c1 : c2;
        if (!(warp_cos < limit_cos))
            continue;
        double warp = acos(warp_cos) * (180.0 / M_PI);
        if (!(warp > limit)) /* the rounding of cos near the limit: the angle decides */
            continue;
        tpk_example *ex = tpk_cell_hit(hits, 205, v->cell);
        if (!ex)
            continue;
        int64_t ids[5] = {v->cell, v->ids[q[0]], v->ids[q[1]], v->ids[q[2]], v->ids[q[3]]};
        tpk_example_ids(ex, 5, ids);
        double centre[3];
        for (int k = 0; k < 3; k++)
            centre[k] = 0.25 * (a[k] + b[k] + c[k] + d[k]);
        tpk_example_point(ex, centre);
        tpk_example_note(ex, "face %d warped by %.1f deg", f, warp);
    }
    (void)mesh;
}

static int on_face(const cell_shape *s, int f, int corner)
{
    for (int i = 0; i < s->face_size[f]; i++)
        if (s->faces[f][i] == corner)
            return 1;
    return 0;
}

/* One face triangle's plane for the convexity test, which signs every corner against it: the filter of
 * tpk_orient3d_filter (same expression, same bound: det = w . (u x v) with u, v the triangle's edges
 * and w = x - a) with u x v and its absolute counterpart computed once per triangle. */
typedef struct tri_plane {
    const double *a, *b, *c;
    double n[3], n_abs[3];
} tri_plane;

static void plane_of(const double *a, const double *b, const double *c, tri_plane *pl)
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    pl->a = a, pl->b = b, pl->c = c;
    pl->n[0] = u[1] * v[2] - u[2] * v[1];
    pl->n[1] = u[2] * v[0] - u[0] * v[2];
    pl->n[2] = u[0] * v[1] - u[1] * v[0];
    pl->n_abs[0] = fabs(u[1] * v[2]) + fabs(u[2] * v[1]);
    pl->n_abs[1] = fabs(u[2] * v[0]) + fabs(u[0] * v[2]);
    pl->n_abs[2] = fabs(u[0] * v[1]) + fabs(u[1] * v[0]);
}

static int plane_side(const tri_plane *pl, const double *x)
{
    const double eps = 1.1102230246251565e-16, bound_factor = (7.0 + 56.0 * eps) * eps;
    double w[3] = {x[0] - pl->a[0], x[1] - pl->a[1], x[2] - pl->a[2]};
    double det = w[0] * pl->n[0] + w[1] * pl->n[1] + w[2] * pl->n[2];
    double permanent = fabs(w[0]) * pl->n_abs[0] + fabs(w[1]) * pl->n_abs[1] + fabs(w[2]) * pl->n_abs[2];
    if (permanent > 1e-280 && permanent < 1e300) {
        double bound = bound_factor * permanent;
        if (det > bound)
            return 1;
        if (-det > bound)
            return -1;
    }
    return tpk_orient3d_exact(pl->a, pl->b, pl->c, x);
}

/* 206. Returns 1 when the cell is strictly convex (see the top of the file). */
static int check_convex(const tpk_mesh *mesh, const cell_view *v, tpk_cell_hits *hits)
{
    static const int quad_tris[4][3] = {{0, 1, 2}, {0, 2, 3}, {1, 2, 3}, {1, 3, 0}};
    int sign = v->orientation < 0 ? -1 : 1, strict = 1, reported = 0;
    for (int f = 0; f < v->s->face_count; f++) {
        const int *q = v->s->faces[f];
        int tri_count = v->s->face_size[f] == 4 ? 4 : 1;
        for (int t = 0; t < tri_count; t++) {
            const int *tri = quad_tris[t];
            tri_plane pl;
            plane_of(v->p[q[tri[0]]], v->p[q[tri[1]]], v->p[q[tri[2]]], &pl);
            for (int x = 0; x < v->s->corners; x++) {
                if (on_face(v->s, f, x))
                    continue;
                int side = sign * plane_side(&pl, v->p[x]);
                strict &= side < 0;
                if (side <= 0 || reported)
                    continue;
                reported = 1;
                tpk_example *ex = tpk_cell_hit(hits, 206, v->cell);
                tpk_cell_example_vertices(ex, mesh, v->cell);
                tpk_example_point(ex, v->p[x]);
                tpk_example_note(ex, "corner %d (vertex %d) lies outside the plane of face %d", x, v->ids[x], f);
            }
        }
    }
    return strict;
}

/* Boundary triangles, quads cut along the diagonal through their smallest id (as the converter cuts). */
static int boundary_triangles(const cell_view *v, int tris[12][3], int face_of[12])
{
    int n = 0;
    for (int f = 0; f < v->s->face_count; f++) {
        const int *q = v->s->faces[f];
        if (v->s->face_size[f] == 3) {
            memcpy(tris[n], q, sizeof tris[n]);
            face_of[n++] = f;
            continue;
        }
        int m = 0;
        for (int i = 1; i < 4; i++)
            if (v->ids[q[i]] < v->ids[q[m]])
                m = i;
        int first[3] = {q[m], q[(m + 1) % 4], q[(m + 2) % 4]}, second[3] = {q[m], q[(m + 2) % 4], q[(m + 3) % 4]};
        memcpy(tris[n], first, sizeof first);
        face_of[n++] = f;
        memcpy(tris[n], second, sizeof second);
        face_of[n++] = f;
    }
    return n;
}

/* Do two boundary triangles share a point besides their common corners and edge? */
static int triangles_cross(const cell_view *v, const int *s, const int *t)
{
    int shared_s[3], shared_t[3], n = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (s[i] == t[j]) {
                shared_s[n] = i;
                shared_t[n++] = j;
            }
    if (n == 0)
        return tpk_exact_triangles_meet(v->p[s[0]], v->p[s[1]], v->p[s[2]], v->p[t[0]], v->p[t[1]], v->p[t[2]]);
    if (n == 1) { /* (c, a, b) and (c, d, e): beyond c only if ab meets the other or de meets the first */
        int i = shared_s[0], j = shared_t[0];
        const double *a = v->p[s[(i + 1) % 3]], *b = v->p[s[(i + 2) % 3]];
        const double *d = v->p[t[(j + 1) % 3]], *e = v->p[t[(j + 2) % 3]];
        return tpk_exact_segment_meets_triangle(a, b, v->p[t[0]], v->p[t[1]], v->p[t[2]]) ||
               tpk_exact_segment_meets_triangle(d, e, v->p[s[0]], v->p[s[1]], v->p[s[2]]);
    }
    if (n == 2) { /* common edge: they overlap only when coplanar with both on one side of it */
        int p = s[3 - shared_s[0] - shared_s[1]], q = t[3 - shared_t[0] - shared_t[1]];
        return tpk_exact_coplanar_side(v->p[s[shared_s[0]]], v->p[s[shared_s[1]]], v->p[p], v->p[q]) == 1;
    }
    return 1; /* two faces on the same three corners */
}

static void check_crossing(const tpk_mesh *mesh, const cell_view *v, tpk_cell_hits *hits)
{
    int tris[12][3], face_of[12];
    int n = boundary_triangles(v, tris, face_of);
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            if (!triangles_cross(v, tris[i], tris[j]))
                continue;
            tpk_example *ex = tpk_cell_hit(hits, 207, v->cell);
            tpk_cell_example_vertices(ex, mesh, v->cell);
            cell_point(mesh, v, ex);
            if (face_of[i] == face_of[j])
                tpk_example_note(ex, "face %d folds over itself (a bow-tie)", face_of[i]);
            else
                tpk_example_note(ex, "faces %d and %d cross", face_of[i], face_of[j]);
            return;
        }
}

void tpk_check_split_cell(const tpk_mesh *mesh, int64_t cell, double warp_deg, tpk_cell_hits *hits)
{
    cell_view v;
    v.type = mesh->cell_types[cell];
    /* Called for voxels, hexahedra, wedges and pyramids only (tpk_check_cells). */
    v.s = tpk_cell_shape_of(v.type);
    v.cell = cell;
    const int32_t *conn = mesh->cell_conn + mesh->cell_offsets[cell];
    for (int i = 0; i < v.s->corners; i++) {
        v.ids[i] = conn[i];
        v.p[i] = mesh->points + 3 * (int64_t)conn[i];
    }
    check_split(mesh, &v, hits);
    check_warp(mesh, &v, warp_deg, hits);
    if (!check_convex(mesh, &v, hits))
        check_crossing(mesh, &v, hits);
}
