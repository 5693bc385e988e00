/* Surfaces and point clouds -> tets with TetGen (mesher.h): the self-intersection
 * check (TetGen -d), the meshing run, and the hand-over to a tpk_mesh of tets with point fields. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/predicates.h"
#include "mesher.h"
#include "tetpack_format.h"
#include "tetgen_guard.h"

#ifndef TPK_WITH_TETGEN
#define TPK_WITH_TETGEN 0
#endif

int tpk_tetgen_available(const char *name, tpk_diag *diag)
{
    if (TPK_WITH_TETGEN)
        return 0;
    return tpk_diag_fail(diag, "%s: tetpack was built without TetGen (TETPACK_WITH_TETGEN=OFF), so it cannot "
                         "tetrahedralize surfaces (STL, OFF, PLY) or point clouds (CSV, PLY)", name);
}

/* Keep only the points `keep` marks (map[old] = new id or -1), with their field values. */
static void compact_points(tpk_mesh *m, const int32_t *map, int64_t kept)
{
    for (int64_t i = 0; i < m->point_count; i++)
        if (map[i] >= 0)
            memmove(m->points + 3 * map[i], m->points + 3 * i, 3 * sizeof(double));
    for (int f = 0; f < m->field_count; f++)
        for (int64_t i = 0; i < m->point_count; i++)
            if (map[i] >= 0)
                m->fields[f].values[map[i]] = m->fields[f].values[i];
    for (int64_t k = 0; m->cell_offsets && k < m->cell_offsets[m->cell_count]; k++)
        m->cell_conn[k] = map[m->cell_conn[k]];
    m->point_count = kept;
}

/* Drop vertices no face uses (TetGen would keep them as loose points). Returns how many. */
static int64_t drop_unused_vertices(tpk_mesh *m, tpk_diag *diag)
{
    int32_t *map = calloc((size_t)(m->point_count ? m->point_count : 1), sizeof(int32_t));
    if (!map)
        return tpk_diag_fail(diag, "out of memory for %lld vertices", (long long)m->point_count);
    for (int64_t i = 0; i < m->point_count; i++)
        map[i] = -1;
    for (int64_t k = 0; k < m->cell_offsets[m->cell_count]; k++)
        map[m->cell_conn[k]] = 0;
    int64_t kept = 0;
    for (int64_t i = 0; i < m->point_count; i++)
        if (map[i] == 0)
            map[i] = (int32_t)kept++;
    int64_t dropped = m->point_count - kept;
    compact_points(m, map, kept);
    free(map);
    return dropped;
}

typedef struct point_key {
    double xyz[3];
    int32_t index;
} point_key;

static int point_key_cmp(const void *pa, const void *pb)
{
    const point_key *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->xyz[k] != b->xyz[k])
            return a->xyz[k] < b->xyz[k] ? -1 : 1;
    return a->index < b->index ? -1 : a->index > b->index;
}

/* Merge points with identical coordinates, keeping the first one (and its values). Returns how many
 * were merged, or -1. */
static int64_t merge_duplicate_points(tpk_mesh *m, tpk_diag *diag)
{
    size_t n = (size_t)m->point_count;
    point_key *keys = malloc(sizeof *keys * (n ? n : 1));
    int32_t *map = malloc(sizeof(int32_t) * (n ? n : 1));
    if (!keys || !map) {
        free(keys);
        free(map);
        return tpk_diag_fail(diag, "out of memory for %zu points", n);
    }
    for (size_t i = 0; i < n; i++) {
        memcpy(keys[i].xyz, m->points + 3 * i, sizeof keys[i].xyz);
        keys[i].index = (int32_t)i;
        map[i] = 0;
    }
    qsort(keys, n, sizeof *keys, point_key_cmp);
    for (size_t i = 1; i < n; i++)
        if (keys[i].xyz[0] == keys[i - 1].xyz[0] && keys[i].xyz[1] == keys[i - 1].xyz[1] &&
            keys[i].xyz[2] == keys[i - 1].xyz[2])
            map[keys[i].index] = -1;
    int64_t kept = 0;
    for (size_t i = 0; i < n; i++)
        if (map[i] == 0)
            map[i] = (int32_t)kept++;
    int64_t merged = (int64_t)n - kept;
    compact_points(m, map, kept);
    free(keys);
    free(map);
    return merged;
}

#if TPK_WITH_TETGEN
static tpk_tetgen_input tetgen_input(const tpk_mesh *m)
{
    return (tpk_tetgen_input){(int32_t)m->point_count, m->points, (int32_t)m->cell_count, m->cell_offsets,
                              m->cell_conn};
}

/* The options' limits for one TetGen run (defaults: mesher.h). */
static tpk_tetgen_guard tetgen_guard(const tpk_tetgen_options *o, const char *what)
{
    static const tpk_tetgen_options defaults;
    if (!o)
        o = &defaults;
    tpk_tetgen_guard g = {what, o->time_limit ? o->time_limit : TPK_TETGEN_DEFAULT_TIME_LIMIT, o->memory_limit,
                          o->progress};
    long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
    if (g.memory_limit == 0 && pages > 0 && page_size > 0)
        g.memory_limit = (int64_t)pages * page_size;
    return g;
}

/* A failed run as a message naming the file: TetGen's own errors with the switches; a crash with what
 * usually causes one. */
static int tetgen_failed(const char *name, const char *switches, const char *what, int code, const char *message,
                         tpk_diag *diag)
{
    if (code == TPK_TETGEN_CRASHED)
        return tpk_diag_fail(diag, "%s: %s; TetGen fails like this on input that is flat within its tolerance "
                             "(1e-8 of the bounding box) or spans very different scales", name, message);
    if (code >= TPK_TETGEN_CRASHED)
        return tpk_diag_fail(diag, "%s: %s", name, message);
    return tpk_diag_fail(diag, "%s: TetGen (switches %s) could not %s: %s", name, switches, what, message);
}

static int face_has(const tpk_mesh *m, int64_t f, int32_t v)
{
    for (int64_t k = m->cell_offsets[f]; k < m->cell_offsets[f + 1]; k++)
        if (m->cell_conn[k] == v)
            return 1;
    return 0;
}

/* The input face holding all three corners of a triangle TetGen reported (the first such), or -1. */
static int64_t face_of_triangle(const tpk_mesh *m, const int32_t *tri)
{
    for (int64_t f = 0; f < m->cell_count; f++)
        if (face_has(m, f, tri[0]) && face_has(m, f, tri[1]) && face_has(m, f, tri[2]))
            return f;
    return -1;
}

static void describe_face(const tpk_mesh *m, int64_t f, char *buf, size_t cap)
{
    int at = snprintf(buf, cap, "face %lld (vertices", (long long)f);
    for (int64_t k = m->cell_offsets[f]; k < m->cell_offsets[f + 1] && at < (int)cap; k++)
        at += snprintf(buf + at, cap - (size_t)at, " %d", m->cell_conn[k]);
    const double *p = m->points + 3 * (int64_t)m->cell_conn[m->cell_offsets[f]];
    if (at < (int)cap)
        snprintf(buf + at, cap - (size_t)at, ", first at (%.9g, %.9g, %.9g))", p[0], p[1], p[2]);
}

/* TetGen -d listed the triangles of intersecting faces: name the first few input faces. */
static int report_intersections(const char *name, const tpk_mesh *m, const tpk_tetgen_output *d, tpk_diag *diag)
{
    char text[700] = "", one[200];
    int64_t named = 0, last = -1;
    for (int32_t t = 0; t < d->triangle_count && named < 3; t++) {
        int64_t f = face_of_triangle(m, d->triangles + 3 * t);
        if (f < 0 || f == last)
            continue;
        describe_face(m, f, one, sizeof one);
        size_t at = strlen(text);
        snprintf(text + at, sizeof text - at, "%s%s", named ? "; " : "", one);
        named++, last = f;
    }
    return tpk_diag_fail(diag, "%s: the surface intersects itself: TetGen -d reports %d intersecting face "
                         "triangles, among them %s", name, d->triangle_count, named ? text : "(faces not found)");
}

static int check_self_intersections(const char *name, const tpk_mesh *m, const tpk_tetgen_options *options,
                                    tpk_diag *diag)
{
    tpk_tetgen_input in = tetgen_input(m);
    tpk_tetgen_output d;
    char message[1024];
    tpk_tetgen_guard guard = tetgen_guard(options, "checking the surface for self-intersections (switches dzQ)");
    int code = tpk_tetgen_run_guarded("dzQ", &in, &guard, &d, message, sizeof message);
    if (code)
        return tetgen_failed(name, "dzQ", "check the surface for self-intersections", code, message, diag);
    int rc = d.triangle_count > 0 ? report_intersections(name, m, &d, diag) : 0;
    tpk_tetgen_output_free(&d);
    return rc;
}

/* Remove the tets that are flat in exact arithmetic: TetGen's symbolic perturbation can leave such
 * slivers between four coplanar points on the convex hull of a point cloud (seen on the flat ends of
 * sfepy/cylinder.vtk's vertices read as float32). Inverted tets would be a TetGen bug: refused. */
static int drop_flat_tets(const char *name, tpk_tetgen_output *t, tpk_diag *diag)
{
    int64_t kept = 0;
    for (int64_t i = 0; i < t->tet_count; i++) {
        const int32_t *v = t->tets + 4 * i;
        const double *p = t->points;
        int sign = tpk_orient3d_exact(p + 3 * v[0], p + 3 * v[1], p + 3 * v[2], p + 3 * v[3]);
        if (sign < 0)
            return tpk_diag_fail(diag, "%s: TetGen returned tet %lld (%d %d %d %d) inverted", name, (long long)i,
                                 v[0], v[1], v[2], v[3]);
        if (sign > 0)
            memmove(t->tets + 4 * kept++, v, 4 * sizeof(int32_t));
    }
    if (kept < t->tet_count)
        tpk_diag_warn(diag, "%s: %lld of TetGen's tets are flat (four coplanar points on the hull); left out", name,
                      (long long)(t->tet_count - kept));
    t->tet_count = kept;
    return 0;
}

/* TetGen's output as the pipeline's source mesh: tets, points, and the input's point fields on the
 * input points (TetGen keeps them first, in order; checked) with NaN on the points it added. */
static int mesh_from_tetgen(const char *name, const tpk_mesh *in, tpk_tetgen_output *t, tpk_mesh *out,
                            tpk_diag *diag)
{
    if (t->point_count < in->point_count || memcmp(t->points, in->points, sizeof(double) * 3 * (size_t)in->point_count))
        return tpk_diag_fail(diag, "%s: TetGen returned %d points, not the %lld input points first and unchanged "
                             "(duplicate input points?)", name, t->point_count, (long long)in->point_count);
    for (int64_t i = 0; i < 4 * t->tet_count; i++)
        if (t->tets[i] < 0 || t->tets[i] >= t->point_count)
            return tpk_diag_fail(diag, "%s: TetGen returned tet %lld with vertex %d out of range", name,
                                 (long long)(i / 4), t->tets[i]);
    if (drop_flat_tets(name, t, diag))
        return -1;
    if (t->tet_count <= 0)
        return tpk_diag_fail(diag, "%s: TetGen made no tetrahedra (all points on one plane?)", name);
    out->cell_types = malloc((size_t)t->tet_count);
    out->cell_offsets = malloc(sizeof(int64_t) * (size_t)(t->tet_count + 1));
    if (!out->cell_types || !out->cell_offsets)
        return tpk_diag_fail(diag, "%s: out of memory for %lld tets", name, (long long)t->tet_count);
    memset(out->cell_types, 10, (size_t)t->tet_count);
    for (int64_t i = 0; i <= t->tet_count; i++)
        out->cell_offsets[i] = 4 * i;
    out->point_count = t->point_count, out->points = t->points, t->points = NULL;
    out->cell_count = t->tet_count, out->cell_conn = t->tets, t->tets = NULL;
    for (int f = 0; f < in->field_count; f++) {
        float *values = malloc(sizeof(float) * (size_t)out->point_count);
        if (!values)
            return tpk_diag_fail(diag, "%s: out of memory for field '%s'", name, in->fields[f].name);
        memcpy(values, in->fields[f].values, sizeof(float) * (size_t)in->point_count);
        for (int64_t i = in->point_count; i < out->point_count; i++)
            values[i] = NAN;
        if (tpk_mesh_add_field(out, in->fields[f].name, TPK_ASSOC_POINT, 1, 1, values)) {
            free(values);
            return tpk_diag_fail(diag, "%s: out of memory for field '%s'", name, in->fields[f].name);
        }
    }
    return 0;
}

static int run_and_build(const char *name, const char *what, const char *switches, const tpk_mesh *in,
                         const tpk_tetgen_options *options, tpk_mesh *out, tpk_diag *diag)
{
    tpk_tetgen_input input = tetgen_input(in);
    tpk_tetgen_output t;
    char message[1024], doing[256], task[64];
    snprintf(doing, sizeof doing, "tetrahedralizing the %s (switches %s)", what, switches);
    snprintf(task, sizeof task, "tetrahedralize the %s", what);
    tpk_tetgen_guard guard = tetgen_guard(options, doing);
    int code = tpk_tetgen_run_guarded(switches, &input, &guard, &t, message, sizeof message);
    if (code)
        return tetgen_failed(name, switches, task, code, message, diag);
    int rc = mesh_from_tetgen(name, in, &t, out, diag);
    tpk_tetgen_output_free(&t);
    if (rc == 0)
        snprintf(out->format, sizeof out->format, "%.20s+tetgen", in->format);
    return rc;
}

static int tetgen_surface(const char *name, const tpk_mesh *in, const tpk_tetgen_options *options, tpk_mesh *out,
                          tpk_diag *diag)
{
    char switches[160];
    if (tpk_tetgen_surface_switches(options, switches, sizeof switches, diag))
        return -1;
    if (in->point_count > INT32_MAX || in->cell_count > INT32_MAX)
        return tpk_diag_fail(diag, "%s: too large for TetGen (more than 2^31-1 points or faces)", name);
    if (tpk_tetgen_check_points(name, in->points, in->point_count, diag) ||
        tpk_tetgen_check_tet_estimate(name, in, switches, options ? options->max_tets : 0, diag) ||
        check_self_intersections(name, in, options, diag))
        return -1;
    return run_and_build(name, "surface", switches, in, options, out, diag);
}

static int tetgen_point_cloud(const char *name, const tpk_mesh *in, const tpk_tetgen_options *options,
                              tpk_mesh *out, tpk_diag *diag)
{
    if (options && (options->switches || options->radius_edge_ratio || options->min_dihedral || options->max_volume))
        return tpk_diag_fail(diag, "%s: a point cloud is tetrahedralized as it is (Delaunay, no new points); the "
                             "--tetgen-* options apply to closed surfaces", name);
    if (in->point_count < 4 || in->point_count > INT32_MAX)
        return tpk_diag_fail(diag, "%s: %lld distinct points; a point cloud needs from 4 to 2^31-1", name,
                             (long long)in->point_count);
    if (tpk_tetgen_check_points(name, in->points, in->point_count, diag))
        return -1;
    return run_and_build(name, "point cloud", "zQ", in, options, out, diag);
}
#else
static int tetgen_surface(const char *name, const tpk_mesh *in, const tpk_tetgen_options *options, tpk_mesh *out,
                          tpk_diag *diag)
{
    (void)in, (void)options, (void)out;
    return tpk_tetgen_available(name, diag);
}

static int tetgen_point_cloud(const char *name, const tpk_mesh *in, const tpk_tetgen_options *options,
                              tpk_mesh *out, tpk_diag *diag)
{
    return tetgen_surface(name, in, options, out, diag);
}
#endif

int tpk_surface_tetrahedralize(const char *name, tpk_mesh *in, const tpk_tetgen_options *options, tpk_mesh *out,
                               tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    int rc;
    if (!TPK_WITH_TETGEN) {
        rc = tpk_tetgen_available(name, diag);
    } else if (in->cell_count == 0) {
        int64_t merged = merge_duplicate_points(in, diag);
        if (merged > 0)
            tpk_diag_warn(diag, "%s: %lld points repeat an earlier point's coordinates; merged (the first one's "
                          "values kept)", name, (long long)merged);
        rc = merged < 0 ? -1 : tetgen_point_cloud(name, in, options, out, diag);
    } else {
        rc = tpk_surface_check_closed(name, in, diag);
        int64_t dropped = rc ? 0 : drop_unused_vertices(in, diag);
        if (dropped > 0)
            tpk_diag_warn(diag, "%s: %lld vertices are in no face; left out", name, (long long)dropped);
        rc = rc || dropped < 0 ? -1 : tetgen_surface(name, in, options, out, diag);
    }
    tpk_mesh_free(in);
    if (rc)
        tpk_mesh_free(out);
    return rc;
}
