/* Conformal split of voxels, hexahedra, wedges and pyramids into tets (docs/ARCHITECTURE.md §5). Each shape
 * (tpk_cell_shape_of) has its VTK parametric corner coordinates and its faces, oriented outward there; tets are
 * first ordered so they are positive on that reference cell, then checked on the real coordinates with
 * the exact predicate. */
#include "cell_split.h"

#include <string.h>

#include "mesh/cell_types.h"
#include "mesh/mesh.h"
#include "pipeline.h"

typedef tpk_cell_shape shape; /* mesh/cell_types.h: corners, outward faces, reference corners */

int tpk_split_max_tets(int type)
{
    switch (type) {
    case TPK_CELL_VOXEL:
    case TPK_CELL_HEXAHEDRON: return 6;
    case TPK_CELL_WEDGE: return 3;
    case TPK_CELL_PYRAMID: return 2;
    default: return 0;
    }
}

/* Sign of det[b-a, c-a, d-a] on the reference corners: small integers, so exact in double. */
static int ref_sign(const shape *s, const int *t)
{
    const double *a = s->ref[t[0]], *b = s->ref[t[1]], *c = s->ref[t[2]], *d = s->ref[t[3]];
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                 u[2] * (v[0] * w[1] - v[1] * w[0]);
    return (det > 0) - (det < 0);
}

/* Local index of the corner with the smallest global id among `count` corners listed in `local`. */
static int smallest(const int32_t *nodes, const int *local, int count)
{
    int best = local[0];
    for (int i = 1; i < count; i++)
        if (nodes[local[i]] < nodes[best])
            best = local[i];
    return best;
}

/* The 5-tet split of a hexahedron whose face diagonals all join corners of one alternating set. */
static int hex_five(const int32_t *nodes, int (*tets)[4])
{
    static const int set_a[4] = {0, 2, 5, 7}, set_b[4] = {1, 3, 4, 6};
    static const int five_a[5][4] = {{0, 2, 5, 7}, {1, 0, 2, 5}, {3, 2, 0, 7}, {4, 5, 7, 0}, {6, 7, 5, 2}};
    static const int five_b[5][4] = {{1, 3, 4, 6}, {0, 1, 3, 4}, {2, 3, 1, 6}, {5, 4, 6, 1}, {7, 6, 4, 3}};
    int in_a = 0;
    for (int f = 0; f < 6; f++) {
        int m = smallest(nodes, tpk_cell_shape_of(TPK_CELL_HEXAHEDRON)->faces[f], 4);
        in_a += m == set_a[0] || m == set_a[1] || m == set_a[2] || m == set_a[3];
    }
    (void)set_b;
    if (in_a != 0 && in_a != 6)
        return 0;
    memcpy(tets, in_a ? five_a : five_b, sizeof five_a);
    return 5;
}

/* Cone from the smallest corner over the triangles of the faces that do not contain it; quads are cut
 * along the diagonal through their smallest corner. Triangles are outward, so (a, c, b, apex) is
 * positive on the reference cell. */
static int cone(const shape *s, const int32_t *nodes, int (*tets)[4])
{
    int all[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    int apex = smallest(nodes, all, s->corners), n = 0;
    for (int f = 0; f < s->face_count; f++) {
        const int *v = s->faces[f];
        int size = s->face_size[f], touches = 0;
        for (int i = 0; i < size; i++)
            touches |= v[i] == apex;
        if (touches)
            continue;
        int tri[2][3], count = 1;
        if (size == 3) {
            memcpy(tri[0], v, sizeof tri[0]);
        } else {
            int m = smallest(nodes, v, 4), at = 0;
            while (v[at] != m)
                at++;
            /* From the smallest corner m: triangles (m, next, opposite) and (m, opposite, previous). */
            int next = v[(at + 1) % 4], opposite = v[(at + 2) % 4], previous = v[(at + 3) % 4];
            int first[3] = {m, next, opposite}, second[3] = {m, opposite, previous};
            memcpy(tri[0], first, sizeof first);
            memcpy(tri[1], second, sizeof second);
            count = 2;
        }
        for (int i = 0; i < count; i++) {
            int t[4] = {tri[i][0], tri[i][2], tri[i][1], apex};
            memcpy(tets[n++], t, sizeof t);
        }
    }
    return n;
}

/* The cell's shape and its corners in that shape's order (voxels become hexahedra). */
static const shape *shape_of(int type, const int32_t *cell_nodes, int32_t *nodes)
{
    static const int voxel_to_hex[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    const shape *s = type == TPK_CELL_VOXEL || type == TPK_CELL_HEXAHEDRON ? tpk_cell_shape_of(TPK_CELL_HEXAHEDRON)
                     : type == TPK_CELL_WEDGE || type == TPK_CELL_PYRAMID  ? tpk_cell_shape_of(type)
                                                                          : NULL;
    for (int i = 0; s && i < s->corners; i++)
        nodes[i] = cell_nodes[type == TPK_CELL_VOXEL ? voxel_to_hex[i] : i];
    return s;
}

int tpk_split_cell(int type, const int32_t *cell_nodes, const double *points, int32_t *out, int *mirrored)
{
    int32_t nodes[8];
    const shape *s = shape_of(type, cell_nodes, nodes);
    *mirrored = 0;
    if (!s)
        return -1;
    for (int i = 0; i < s->corners; i++)
        for (int j = 0; j < i; j++)
            if (nodes[i] == nodes[j])
                return -1; /* a repeated corner: degenerate */
    int tets[6][4];
    int n = s->type == TPK_CELL_HEXAHEDRON ? hex_five(nodes, tets) : 0;
    if (n == 0)
        n = cone(s, nodes, tets);
    int positive = 0, negative = 0;
    for (int i = 0; i < n; i++) {
        int *t = tets[i];
        if (ref_sign(s, t) < 0) { /* order every tet positive on the reference cell */
            int swap = t[2];
            t[2] = t[3];
            t[3] = swap;
        }
        const double *a = points + 3 * (int64_t)nodes[t[0]], *b = points + 3 * (int64_t)nodes[t[1]];
        const double *c = points + 3 * (int64_t)nodes[t[2]], *d = points + 3 * (int64_t)nodes[t[3]];
        int sign = tpk_orient3d_filter(a, b, c, d); /* inline; the exact call only where it cannot tell */
        if (sign == 0)
            sign = tpk_orient3d_exact(a, b, c, d);
        positive += sign > 0;
        negative += sign < 0;
    }
    if (positive != n && negative != n)
        return -1;
    *mirrored = negative == n;
    for (int i = 0; i < n; i++) {
        const int *t = tets[i];
        int order[4] = {t[0], t[1], *mirrored ? t[3] : t[2], *mirrored ? t[2] : t[3]};
        for (int k = 0; k < 4; k++)
            out[4 * i + k] = nodes[order[k]];
    }
    return n;
}

int tpk_star_max_tets(int type)
{
    switch (type) {
    case TPK_CELL_VOXEL:
    case TPK_CELL_HEXAHEDRON: return 12;
    case TPK_CELL_WEDGE: return 8;
    case TPK_CELL_PYRAMID: return 6;
    default: return 0;
    }
}

int tpk_star_cell(int type, const int32_t *cell_nodes, const double *points, const double centre[3],
                  int32_t centre_id, int32_t *out, int *mirrored)
{
    int32_t nodes[8];
    const shape *s = shape_of(type, cell_nodes, nodes);
    *mirrored = 0;
    if (!s)
        return -1;
    int n = 0, positive = 0, negative = 0;
    int32_t tets[12][4];
    for (int f = 0; f < s->face_count; f++) {
        const int *v = s->faces[f];
        int tri[2][3] = {{v[0], v[1], v[2]}, {0, 0, 0}}, count = 1;
        if (s->face_size[f] == 4) { /* the same diagonal the neighbouring cell uses */
            int m = smallest(nodes, v, 4), at = 0;
            while (v[at] != m)
                at++;
            int a[3] = {m, v[(at + 1) % 4], v[(at + 2) % 4]}, b[3] = {m, v[(at + 2) % 4], v[(at + 3) % 4]};
            memcpy(tri[0], a, sizeof a);
            memcpy(tri[1], b, sizeof b);
            count = 2;
        }
        for (int i = 0; i < count; i++) {
            /* Outward triangle (a, b, c) and an inner point: (a, c, b, centre) is positive. */
            const double *a = points + 3 * (int64_t)nodes[tri[i][0]], *b = points + 3 * (int64_t)nodes[tri[i][1]];
            const double *c = points + 3 * (int64_t)nodes[tri[i][2]];
            int sign = tpk_orient3d_exact(a, c, b, centre);
            positive += sign > 0;
            negative += sign < 0;
            int32_t t[4] = {nodes[tri[i][0]], nodes[tri[i][2]], nodes[tri[i][1]], centre_id};
            memcpy(tets[n++], t, sizeof t);
        }
    }
    /* The faces above are outward on the reference cell: a valid star is all positive, a mirrored
     * cell's all negative; anything else, and the centre does not see every face. */
    if (positive != n && negative != n)
        return -1;
    *mirrored = negative == n;
    for (int i = 0; i < n; i++) {
        out[4 * i] = tets[i][0];
        out[4 * i + 1] = tets[i][*mirrored ? 2 : 1];
        out[4 * i + 2] = tets[i][*mirrored ? 1 : 2];
        out[4 * i + 3] = tets[i][3];
    }
    return n;
}
