/* Boundary faces (pipeline stage 6) as outward int4 records: each face of a tet with no neighbor, in
 * the outward order of tpk_tet_faces (format/tetpack_format.h, which says why it is outward). Tests
 * check it exactly. */
#include "pipeline.h"

#include <stdlib.h>
#include <string.h>

#include "base/grow.h"
#include "base/parallel.h"

int64_t tpk_count_shell_faces(const int32_t *neighbors, int64_t tet_count)
{
    int64_t count = 0;
    for (int64_t i = 0; i < 4 * tet_count; i++)
        count += neighbors[i] < 0;
    return count;
}

/* Tet t's faces with no neighbor (v its ids, n its neighbors, at least one < 0) into dst, in face order;
 * returns how many. */
static int tet_shell_faces(const int32_t *v, const int32_t *n, int32_t t, tpk_shell_face *dst)
{
    int out = 0;
    for (int k = 0; k < 4; k++)
        if (n[k] < 0)
            dst[out++] = (tpk_shell_face){v[tpk_tet_faces[k][0]], v[tpk_tet_faces[k][1]], v[tpk_tet_faces[k][2]], t};
    return out;
}

void tpk_build_shell(const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                     tpk_shell_face *dst)
{
    int64_t out = 0;
    for (int64_t t = 0; t < tet_count; t++) {
        const int32_t *n = neighbors + 4 * t;
        if ((n[0] | n[1] | n[2] | n[3]) >= 0) /* no face on the shell: most tets, one test (sign bits) */
            continue;
        out += tet_shell_faces(tets + 4 * t, n, (int32_t)t, dst + out);
    }
}

/* tpk_make_shell: each worker counts the shell faces of its contiguous range of tets, the prefix sums of
 * the counts place each range's faces, and each worker writes its own: the order of one pass. */
typedef struct shell_job {
    const int32_t *tets, *neighbors;
    tpk_shell_face *dst;
    int64_t count[TPK_MAX_THREADS];
} shell_job;

static void count_range(void *ctx, int64_t begin, int64_t end, int w)
{
    shell_job *job = ctx;
    job->count[w] = tpk_count_shell_faces(job->neighbors + 4 * begin, end - begin);
}

static void build_range(void *ctx, int64_t begin, int64_t end, int w)
{
    shell_job *job = ctx;
    tpk_build_shell(job->tets + 4 * begin, job->neighbors + 4 * begin, end - begin, job->dst + job->count[w]);
    for (int64_t i = 0; i < job->count[w + 1] - job->count[w]; i++)
        job->dst[job->count[w] + i].t += (int32_t)begin;
}

tpk_shell_face *tpk_make_shell(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, int threads,
                               int64_t *count)
{
    shell_job *job = malloc(sizeof *job);
    if (!job)
        return NULL;
    job->tets = tets;
    job->neighbors = neighbors;
    threads = tpk_threads_for(tet_count, tpk_thread_count(threads), (int64_t)1 << 16);
    if (threads >= TPK_MAX_THREADS)
        threads = TPK_MAX_THREADS - 1; /* count[threads] holds the total */
    tpk_parallel_for(tet_count, threads, count_range, job);
    int64_t total = 0;
    for (int w = 0; w < threads; w++) {
        int64_t n = job->count[w];
        job->count[w] = total;
        total += n;
    }
    job->count[threads] = total;
    job->dst = malloc(sizeof *job->dst * (size_t)(total ? total : 1));
    if (job->dst)
        tpk_parallel_for(tet_count, threads, build_range, job);
    tpk_shell_face *dst = job->dst;
    free(job);
    *count = total;
    return dst;
}

void tpk_shell_gather_range(tpk_shell_gather *g, const int32_t *tets, const int32_t *neighbors, int64_t first,
                            int64_t count, int worker)
{
    /* One pass: the faces are appended as found (a count first read the neighbours twice). */
    tpk_shell_gather_worker *me = &g->worker[worker];
    if (me->failed)
        return;
    for (int64_t t = first; t < first + count; t++) {
        const int32_t *n = neighbors + 4 * t;
        if ((n[0] | n[1] | n[2] | n[3]) >= 0)
            continue;
        if (me->count + 4 > me->capacity) {
            tpk_shell_face *grown = tpk_grow(me->faces, &me->capacity, me->count + 4, sizeof *grown, 4096);
            if (!grown) {
                me->failed = 1;
                return;
            }
            me->faces = grown;
        }
        me->count += tet_shell_faces(tets + 4 * t, n, (int32_t)t, me->faces + me->count);
    }
}

void tpk_shell_gather_block(tpk_shell_gather *g)
{
    int64_t found = 0;
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        found += g->worker[w].count;
        g->failed |= g->worker[w].failed;
    }
    if (!g->failed && g->count + found > g->capacity) {
        tpk_shell_face *grown = tpk_grow(g->faces, &g->capacity, g->count + found, sizeof *grown, 4096);
        if (grown)
            g->faces = grown;
        else
            g->failed = 1;
    }
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        if (!g->failed && g->worker[w].count > 0) {
            memcpy(g->faces + g->count, g->worker[w].faces, sizeof *g->faces * (size_t)g->worker[w].count);
            g->count += g->worker[w].count;
        }
        g->worker[w].count = 0;
    }
}

void tpk_shell_gather_done(tpk_shell_gather *g)
{
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        free(g->worker[w].faces);
        g->worker[w].faces = NULL;
        g->worker[w].count = g->worker[w].capacity = 0;
    }
}
