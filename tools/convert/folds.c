/* Folds (pipeline stage 4b, after connect): interior faces whose two tets lie on the same side of the
 * face's plane, which TPK-M06 forbids. They come from overlapping cells in the source (gmsh boundary
 * layers) or from a tet turned over against its neighbours. Every caller passes tets that are all
 * positive, exactly (orient ran first): then the side is decided by the vertex order alone (is_folded),
 * and the exact test on the points as the file stores them confirms each fold, so what passes here
 * passes `tetpack check` 606. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "base/strbuf.h"
#include "pipeline.h"

typedef struct fold_job {
    const int32_t *tets, *neighbors;
    const double *points;
    int64_t *found[TPK_MAX_THREADS]; /* per worker: folded slots, ascending */
    int64_t count[TPK_MAX_THREADS], cap[TPK_MAX_THREADS];
    int failed[TPK_MAX_THREADS];
} fold_job;

int tpk_face_across(const int32_t *tets, int64_t t, int k, int64_t u)
{
    const int32_t *v = tets + 4 * t, *w = tets + 4 * u;
    for (int j = 0; j < 4; j++)
        if (w[j] != v[(k + 1) & 3] && w[j] != v[(k + 2) & 3] && w[j] != v[(k + 3) & 3])
            return j;
    return -1; /* not a neighbour: connect never gives this */
}

/* Face k of positive tet t in outward order (a, b, c): the neighbour's fourth vertex y lies beyond the
 * face exactly when det[b-a, c-a, y-a] > 0. Zero counts as a fold too: y on the plane is not "the
 * other side" (and orient lets no flat tet through).
 * As u is positive too, y lies on the inner side of u's own outward face, which holds a, b and c: in
 * the opposite cyclic order (a, c, b) when y is beyond, in the same order (a, b, c) when the face is
 * folded. So only a face whose orders agree needs the points; the exact sign then decides. */
static int is_folded(const fold_job *job, int64_t t, int k, int64_t u)
{
    int j = tpk_face_across(job->tets, t, k, u);
    if (j >= 0 && tpk_face_parity(job->tets + 4 * t, k) != tpk_face_parity(job->tets + 4 * u, j))
        return 0; /* (a, c, b) cyclically: opposite sides */
    return tpk_face_folded(job->tets, job->points, t, k, u);
}

int tpk_face_folded(const int32_t *tets, const double *p, int64_t t, int k, int64_t u)
{
    const int32_t *v = tets + 4 * t, *w = tets + 4 * u;
    int32_t ia = v[tpk_tet_faces[k][0]], ib = v[tpk_tet_faces[k][1]], ic = v[tpk_tet_faces[k][2]];
    int32_t iy = w[0] ^ w[1] ^ w[2] ^ w[3] ^ ia ^ ib ^ ic; /* u's fourth vertex (spec §6.2, vx) */
    return tpk_orient3d_exact(p + 3 * (int64_t)ia, p + 3 * (int64_t)ib, p + 3 * (int64_t)ic, p + 3 * (int64_t)iy) <= 0;
}

static void fold_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    fold_job *job = ctx;
    for (int64_t t = begin; t < end && !job->failed[worker]; t++)
        for (int k = 0; k < 4; k++) {
            int64_t u = job->neighbors[4 * t + k];
            if (u <= t || !is_folded(job, t, k, u)) /* each interior face once, from its lower tet */
                continue;
            if (job->count[worker] == job->cap[worker]) {
                int64_t cap = job->cap[worker] ? 2 * job->cap[worker] : 64;
                int64_t *grown = realloc(job->found[worker], sizeof *grown * (size_t)cap);
                if (!grown) {
                    job->failed[worker] = 1;
                    return;
                }
                job->found[worker] = grown;
                job->cap[worker] = cap;
            }
            job->found[worker][job->count[worker]++] = 4 * t + k;
        }
}

int tpk_find_folds(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, const double *points,
                   int threads_requested, int64_t **slots, int64_t *count, tpk_diag *diag)
{
    *slots = NULL;
    *count = 0;
    fold_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "folds: out of memory");
    job->tets = tets;
    job->neighbors = neighbors;
    job->points = points;
    int threads = tpk_threads_for(tet_count, tpk_thread_count(threads_requested), 65536);
    tpk_parallel_for(tet_count, threads, fold_range, job);
    int64_t total = 0;
    int failed = 0;
    for (int w = 0; w < threads; w++) {
        total += job->count[w];
        failed |= job->failed[w];
    }
    int64_t *all = total && !failed ? malloc(sizeof *all * (size_t)total) : NULL;
    int rc = 0;
    if (failed || (total && !all)) {
        rc = tpk_diag_fail(diag, "folds: out of memory for the folded faces");
    } else {
        for (int w = 0, at = 0; w < threads; at += (int)job->count[w], w++) /* worker ranges ascend */
            if (job->count[w])
                memcpy(all + at, job->found[w], sizeof *all * (size_t)job->count[w]);
        *slots = all;
        *count = total;
    }
    for (int w = 0; w < threads; w++)
        free(job->found[w]);
    free(job);
    return rc;
}

void tpk_cut_folds(const int32_t *tets, int32_t *neighbors, const int64_t *slots, int64_t count)
{
    for (int64_t i = 0; i < count; i++) {
        int64_t t = slots[i] / 4, u = neighbors[slots[i]];
        int j = tpk_face_across(tets, t, (int)(slots[i] % 4), u);
        neighbors[slots[i]] = -1;
        neighbors[4 * u + j] = -1;
    }
}

/* "S (x, y, z)": vertex v by its source id (-1 for an added point) and world coordinates. */
static void describe_vertex(tpk_strbuf *sb, const tpk_tetmesh *mesh, int32_t v)
{
    const double *p = mesh->points + 3 * (int64_t)v;
    tpk_strbuf_printf(sb, "%d (%.17g, %.17g, %.17g)", mesh->vertex_source ? mesh->vertex_source[v] : v,
                      mesh->origin[0] + p[0], mesh->origin[1] + p[1], mesh->origin[2] + p[2]);
}

void tpk_describe_fold(const tpk_tetmesh *mesh, const int32_t *neighbors, int64_t slot, char *text, size_t cap)
{
    int64_t t = slot / 4, u = neighbors[slot];
    int k = (int)(slot % 4), j = tpk_face_across(mesh->tets, t, k, u);
    const int32_t *v = mesh->tets + 4 * t;
    tpk_strbuf sb = {0};
    tpk_strbuf_printf(&sb, "the face of points ");
    for (int i = 0; i < 3; i++) {
        tpk_strbuf_printf(&sb, "%s", i ? ", " : "");
        describe_vertex(&sb, mesh, v[tpk_tet_faces[k][i]]);
    }
    tpk_strbuf_printf(&sb, " is shared by cell %d (tet %lld, fourth point ",
                      mesh->tet_source ? mesh->tet_source[t] : (int32_t)t, (long long)t);
    describe_vertex(&sb, mesh, v[k]);
    tpk_strbuf_printf(&sb, ") and cell %d (tet %lld, fourth point ", mesh->tet_source ? mesh->tet_source[u] : (int32_t)u,
                      (long long)u);
    describe_vertex(&sb, mesh, mesh->tets[4 * u + j]);
    tpk_strbuf_printf(&sb, "), both fourth points on the same side of it");
    snprintf(text, cap, "%s", sb.failed || !sb.data ? "a folded face (out of memory to describe it)" : sb.data);
    tpk_strbuf_free(&sb);
}
