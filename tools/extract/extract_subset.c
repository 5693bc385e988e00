/* The tets extract keeps and their new connectivity. Selection is by bounding box against the clip
 * box, and by tpk_probe_may_show against the probes; the adjacency of the kept tets is rebuilt by the converter's own stages (connect, then the exact
 * fold test), not patched by hand, so the invariants hold by the same code that makes every file. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "convert/pipeline.h"
#include "extract_internal.h"

/* The tet's box (world: origin + stored float) meets the closed clip box. */
static int meets_box(const tpk_mesh_arrays *mesh, const int32_t *v, const tpk_extract_options *o)
{
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (int j = 0; j < 4; j++) {
            double x = mesh->origin[k] + (double)mesh->positions[3 * (size_t)v[j] + k];
            lo = x < lo ? x : lo;
            hi = x > hi ? x : hi;
        }
        if (hi < o->clip_min[k] || lo > o->clip_max[k])
            return 0;
    }
    return 1;
}

/* The tet may show through the probes (render.h: tpk_probe_may_show, on its world corners). */
static int may_show(const tpk_mesh_arrays *mesh, const int32_t *v, const tpk_extract_options *o)
{
    double corner[4][3];
    for (int j = 0; j < 4; j++)
        for (int k = 0; k < 3; k++)
            corner[j][k] = mesh->origin[k] + (double)mesh->positions[3 * (size_t)v[j] + k];
    return tpk_probe_may_show(o->probes, o->probe_count, corner);
}

/* Mark the kept tets and their vertices; new ids in old order. */
static int select_tets(const tpk_mesh_arrays *mesh, const int32_t *tets, const tpk_extract_options *o,
                       int32_t *vertex_new, tpk_subset *s, tpk_diag *diag)
{
    int64_t T = (int64_t)mesh->tet_count, V = (int64_t)mesh->vertex_count;
    s->tet_old = malloc(sizeof *s->tet_old * (size_t)(T ? T : 1));
    if (!s->tet_old)
        return tpk_diag_fail(diag, "out of memory for the selection of %lld tets", (long long)T);
    for (int64_t v = 0; v < V; v++)
        vertex_new[v] = -1;
    for (int64_t t = 0; t < T; t++) {
        if ((o->clip && !meets_box(mesh, tets + 4 * t, o)) || (o->probe_count > 0 && !may_show(mesh, tets + 4 * t, o)))
            continue;
        s->tet_old[s->tet_count++] = (int32_t)t;
        for (int j = 0; j < 4; j++)
            vertex_new[tets[4 * t + j]] = 0;
    }
    if (s->tet_count == 0 && o->probe_count > 0)
        return tpk_diag_fail(diag, "no tet meets the clip box and shows through the probes");
    if (s->tet_count == 0)
        return tpk_diag_fail(diag, "no tet meets the clip box [%g, %g, %g] .. [%g, %g, %g]", o->clip_min[0],
                             o->clip_min[1], o->clip_min[2], o->clip_max[0], o->clip_max[1], o->clip_max[2]);
    for (int64_t v = 0; v < V; v++)
        if (vertex_new[v] == 0)
            vertex_new[v] = (int32_t)s->vertex_count++;
    return 0;
}

static int renumber(const tpk_mesh_arrays *mesh, const int32_t *tets, const int32_t *vertex_new, tpk_subset *s,
                    tpk_diag *diag)
{
    s->vertex_old = malloc(sizeof *s->vertex_old * (size_t)s->vertex_count);
    s->positions = malloc(sizeof *s->positions * 3 * (size_t)s->vertex_count);
    s->tets = malloc(sizeof *s->tets * 4 * (size_t)s->tet_count);
    s->neighbors = malloc(sizeof *s->neighbors * 4 * (size_t)s->tet_count);
    if (!s->vertex_old || !s->positions || !s->tets || !s->neighbors)
        return tpk_diag_fail(diag, "out of memory for %lld kept tets", (long long)s->tet_count);
    for (int64_t v = 0; v < (int64_t)mesh->vertex_count; v++)
        if (vertex_new[v] >= 0) {
            s->vertex_old[vertex_new[v]] = (int32_t)v;
            memcpy(s->positions + 3 * (size_t)vertex_new[v], mesh->positions + 3 * (size_t)v, 3 * sizeof(float));
        }
    for (int64_t t = 0; t < s->tet_count; t++)
        for (int j = 0; j < 4; j++)
            s->tets[4 * t + j] = vertex_new[tets[4 * (int64_t)s->tet_old[t] + j]];
    return 0;
}

/* Face matching on the kept tets, then the source's cut folds cut again: the source has no fold
 * stored as a neighbour pair (TPK-M06), so a fold between kept tets is one the source cut (spec §6.7). */
static int connect_subset(tpk_subset *s, int threads, tpk_diag *diag)
{
    if (tpk_connect(s->tets, s->tet_count, s->vertex_count, s->neighbors, threads, diag) != 0)
        return -1;
    double *points = malloc(sizeof *points * 3 * (size_t)s->vertex_count);
    if (!points)
        return tpk_diag_fail(diag, "out of memory for %lld points", (long long)s->vertex_count);
    for (int64_t i = 0; i < 3 * s->vertex_count; i++)
        points[i] = (double)s->positions[i]; /* the stored frame: orientation is decided on these */
    int64_t *slots = NULL, count = 0;
    int rc = tpk_find_folds(s->tets, s->neighbors, s->tet_count, points, threads, &slots, &count, diag);
    if (rc == 0 && count > 0)
        tpk_cut_folds(s->tets, s->neighbors, slots, count);
    free(slots);
    free(points);
    return rc;
}

int tpk_subset_build(const tpk_mesh_arrays *mesh, const int32_t *tets, const tpk_extract_options *o,
                     tpk_subset *s, tpk_diag *diag)
{
    memset(s, 0, sizeof *s);
    int32_t *vertex_new = malloc(sizeof *vertex_new * (size_t)(mesh->vertex_count ? mesh->vertex_count : 1));
    if (!vertex_new)
        return tpk_diag_fail(diag, "out of memory for %llu vertex ids", (unsigned long long)mesh->vertex_count);
    int rc = select_tets(mesh, tets, o, vertex_new, s, diag);
    if (rc == 0)
        rc = renumber(mesh, tets, vertex_new, s, diag);
    free(vertex_new);
    if (rc == 0)
        rc = connect_subset(s, o->threads, diag);
    if (rc != 0)
        tpk_subset_free(s);
    return rc;
}

void tpk_subset_free(tpk_subset *s)
{
    free(s->tet_old);
    free(s->vertex_old);
    free(s->tets);
    free(s->neighbors);
    free(s->positions);
    memset(s, 0, sizeof *s);
}
