/* Levels of detail (levels_internal.h): the error measure: the full mesh's field at the vertices a level
 * removed against the level's, interpolated in the level tet that holds each. */
#include <math.h>
#include <stdlib.h>

#include "base/parallel.h"
#include "base/predicates.h"
#include "levels_internal.h"

/* p's barycentric weights in level tet t (unnormalised: each a 6V, summing to *total). */
static void weights(const tpk_tetmesh *lvl, int64_t t, const double *p, double lambda[4], double *total)
{
    const int32_t *v = lvl->tets + 4 * t;
    /* The corners from p: lambda[k] is the 6V of the tet with p in place of corner k, a triple
     * product of the other three, two cross products for the four */
    const double *c0 = lvl->points + 3 * (size_t)v[0], *c1 = lvl->points + 3 * (size_t)v[1];
    const double *c2 = lvl->points + 3 * (size_t)v[2], *c3 = lvl->points + 3 * (size_t)v[3];
    double x0 = c0[0] - p[0], y0 = c0[1] - p[1], z0 = c0[2] - p[2];
    double x1 = c1[0] - p[0], y1 = c1[1] - p[1], z1 = c1[2] - p[2];
    double x2 = c2[0] - p[0], y2 = c2[1] - p[1], z2 = c2[2] - p[2];
    double x3 = c3[0] - p[0], y3 = c3[1] - p[1], z3 = c3[2] - p[2];
    double abx = y0 * z1 - z0 * y1, aby = z0 * x1 - x0 * z1, abz = x0 * y1 - y0 * x1;
    double cdx = y2 * z3 - z2 * y3, cdy = z2 * x3 - x2 * z3, cdz = x2 * y3 - y2 * x3;
    lambda[0] = x1 * cdx + y1 * cdy + z1 * cdz;
    lambda[1] = -(x0 * cdx + y0 * cdy + z0 * cdz);
    lambda[2] = abx * x3 + aby * y3 + abz * z3;
    lambda[3] = -(abx * x2 + aby * y2 + abz * z2);
    *total = lambda[0] + lambda[1] + lambda[2] + lambda[3];
}

/* The level tet that holds point p, by a walk from tet t across a face p is beyond (exactly; one with a
 * neighbour first, so that a walk near a non-convex shell stays inside), with p's barycentric weights
 * (unnormalised: each a 6V, summing to *total); -1 when the walk leaves the mesh or takes 4096 steps. */
static int64_t locate(const tpk_tetmesh *lvl, const int32_t *neighbors, const double *p, int64_t t, double lambda[4],
                      double *total)
{
    for (int steps = 0; steps < 4096 && t >= 0; steps++) {
        const int32_t *v = lvl->tets + 4 * t;
        weights(lvl, t, p, lambda, total);
        int beyond = -1, outside = 0;
        for (int k = 0; k < 4 && beyond < 0; k++) {
            if (!(lambda[k] < 0))
                continue;
            const double *q[4];
            for (int j = 0; j < 4; j++)
                q[j] = j == k ? p : lvl->points + 3 * (size_t)v[j];
            if (tpk_orient3d_exact(q[0], q[1], q[2], q[3]) < 0) {
                if (neighbors[4 * t + k] >= 0)
                    beyond = k;
                else
                    outside = 1;
            }
        }
        if (beyond < 0)
            return outside ? -1 : t;
        t = neighbors[4 * t + beyond];
    }
    return -1;
}

/* The error sampling's vertices go in chunks of fixed size, side by side, each walk starting from the tet
 * of the chunk's first kept vertex: the sums do not depend on the thread count. */
#define MEASURE_CHUNK ((int64_t)1 << 15)

typedef struct measure_job {
    const simplifier *s;
    const tpk_tetmesh *lvl;
    const int32_t *vertex_old, *neighbors, *near_tet, *tet_of;
    double *sum, *worst; /* per chunk */
    int64_t *count;
} measure_job;

static void measure_chunks(void *ctx, int64_t begin, int64_t end, int worker)
{
    const measure_job *j = ctx;
    const simplifier *s = j->s;
    const tpk_tetmesh *m = s->mesh, *lvl = j->lvl;
    const int32_t *vertex_old = j->vertex_old, *tet_of = j->tet_of, *near_tet = j->near_tet;
    (void)worker;
    for (int64_t c = begin; c < end; c++) {
        int64_t first = c * MEASURE_CHUNK, last = first + MEASURE_CHUNK;
        last = last < m->vertex_count ? last : m->vertex_count;
        double sum = 0, worst = 0;
        int64_t count = 0, hint = 0;
        for (int64_t u = first; u < last; u++)
            if (tet_of[u] >= 0) {
                hint = tet_of[u];
                break;
            }
        for (int64_t u = first; u < last; u++) {
            if (tet_of[u] >= 0)
                continue;
            const double *p = m->points + 3 * (size_t)u;
            double lambda[4], total = 0;
            int64_t t = locate(lvl, j->neighbors, p, hint, lambda, &total);
            int32_t w = t < 0 && s->removed[u] ? survivor(s, (int32_t)u) : -1;
            if (w >= 0 && tet_of[w] >= 0 && tet_of[w] != hint)
                t = locate(lvl, j->neighbors, p, tet_of[w], lambda, &total);
            int outside = t < 0 && near_tet && near_tet[u] >= 0;
            if (outside) { /* a shell vertex the level's shell moved past: the weights of the nearest shell face's tet */
                t = near_tet[u];
                weights(lvl, t, p, lambda, &total);
            }
            if (t < 0)
                continue;
            const int32_t *v = lvl->tets + 4 * t;
            double value = 0, sum_w = 0;
            for (int k = 0; k < 4 && outside; k++) /* clamped to the tet: its nearest value to p, about */
                sum_w += (lambda[k] = lambda[k] > 0 ? lambda[k] : 0);
            total = outside ? sum_w : total;
            for (int k = 0; k < 4 && total > 0; k++)
                value += lambda[k] / total * (double)s->field[vertex_old[v[k]]];
            double d = fabs(value - (double)s->field[u]);
            worst = d > worst ? d : worst;
            sum += d * d;
            count++;
            hint = t;
        }
        j->sum[c] = sum, j->worst[c] = worst, j->count[c] = count;
    }
}

/* The field of the full mesh at the vertices this level removed against the level's value there (linear
 * in the level tet that holds the point, found by locate(): from the tet found for the removed vertex
 * before, vertices being in Hilbert order, else from a tet of the vertex it ended on, which is in the
 * same part of the mesh: a walk does not cross from one block of a mesh to another that only lies
 * against it). A point neither walk reaches is not sampled; a shell vertex the level's shell moved past is
 * sampled in the tet of its nearest shell face. */
void levels_measure(const simplifier *s, const tpk_tetmesh *lvl, const int32_t *vertex_old, const int32_t *neighbors,
                    const int32_t *near_tet, tpk_level *r)
{
    const tpk_tetmesh *m = s->mesh;
    int64_t chunks = (m->vertex_count + MEASURE_CHUNK - 1) / MEASURE_CHUNK;
    /* per full mesh vertex: a level tet that holds it, or -1 (not kept) */
    int32_t *tet_of = s->field ? malloc(sizeof *tet_of * (size_t)(m->vertex_count ? m->vertex_count : 1)) : NULL;
    double *sums = tet_of ? malloc(sizeof *sums * 2 * (size_t)(chunks ? chunks : 1)) : NULL;
    int64_t *counts = sums ? malloc(sizeof *counts * (size_t)(chunks ? chunks : 1)) : NULL;
    if (!counts) {
        free(tet_of);
        free(sums);
        return;
    }
    levels_fill_i32(tet_of, m->vertex_count, -1, s->threads);
    for (int64_t i = 0; i < 4 * lvl->tet_count; i++)
        tet_of[vertex_old[lvl->tets[i]]] = (int32_t)(i / 4);
    measure_job job = {s, lvl, vertex_old, neighbors, near_tet, tet_of, sums, sums + chunks, counts};
    tpk_parallel_for(chunks, tpk_threads_for(chunks, s->threads, 1), measure_chunks, &job);
    double sum = 0, worst = 0;
    int64_t count = 0;
    for (int64_t c = 0; c < chunks; c++) { /* in chunk order */
        sum += sums[c];
        worst = job.worst[c] > worst ? job.worst[c] : worst;
        count += counts[c];
    }
    r->error_samples = count;
    r->error_max = worst;
    r->error_rms = count ? sqrt(sum / (double)count) : 0;
    free(tet_of);
    free(sums);
    free(counts);
}
