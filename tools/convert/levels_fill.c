/* Levels of detail (levels_internal.h): the parallel fill helpers, on all threads with results that do not
 * depend on the thread count: fill and zero an array, bounds of points, counts into offsets. */
#include <math.h>
#include <string.h>

#include "base/parallel.h"
#include "levels_internal.h"

/* a[0..n) = value, on all threads (the per-vertex maps each level sets up: 32 MB each on grid 200). */
typedef struct fill_job {
    int32_t *a;
    int32_t value;
} fill_job;

static void fill_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const fill_job *j = ctx;
    (void)worker;
    for (int64_t i = begin; i < end; i++)
        j->a[i] = j->value;
}

void levels_fill_i32(int32_t *a, int64_t n, int32_t value, int threads)
{
    fill_job job = {a, value};
    tpk_parallel_for(n, tpk_threads_for(n, threads, 1 << 18), fill_range, &job);
}

/* a[0..n) = 0, bytes, on all threads. */
static void zero_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    (void)worker;
    memset((uint8_t *)ctx + begin, 0, (size_t)(end - begin));
}

void levels_zero_bytes(uint8_t *a, int64_t n, int threads)
{
    tpk_parallel_for(n, tpk_threads_for(n, threads, 1 << 22), zero_range, a);
}

/* The bounds of n points (each origin + point, origin NULL: 0), on all threads: each worker's, then the
 * least and greatest of those, which are the ones one thread finds. */
typedef struct bounds_job {
    const double *points, *origin;
    double lo[TPK_MAX_THREADS][3], hi[TPK_MAX_THREADS][3];
} bounds_job;

static void bounds_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    bounds_job *j = ctx;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = begin; v < end; v++)
        for (int a = 0; a < 3; a++) {
            double w = j->origin ? j->origin[a] + j->points[3 * v + a] : j->points[3 * v + a];
            lo[a] = w < lo[a] ? w : lo[a];
            hi[a] = w > hi[a] ? w : hi[a];
        }
    memcpy(j->lo[worker], lo, sizeof lo);
    memcpy(j->hi[worker], hi, sizeof hi);
}

void levels_bounds_of(const double *points, const double *origin, int64_t n, int threads, double lo[3], double hi[3])
{
    bounds_job j; /* 3 KB */
    j.points = points, j.origin = origin;
    int parts = tpk_threads_for(n, threads, 1 << 16);
    tpk_parallel_for(n, parts, bounds_range, &j);
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY, hi[a] = -INFINITY;
        for (int w = 0; w < parts; w++) {
            lo[a] = j.lo[w][a] < lo[a] ? j.lo[w][a] : lo[a];
            hi[a] = j.hi[w][a] > hi[a] ? j.hi[w][a] : hi[a];
        }
    }
}

/* Counts per worker into offsets: c[w] becomes the sum of c[0..w). */
void levels_offsets(int64_t *c, int parts)
{
    int64_t at = 0;
    for (int w = 0; w < parts; w++) {
        int64_t n = c[w];
        c[w] = at;
        at += n;
    }
    c[parts] = at;
}
