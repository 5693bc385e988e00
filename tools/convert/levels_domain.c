/* Levels of detail (levels_internal.h): the domain check: a level's volume and shell area against the
 * full mesh's. */
#include <math.h>

#include "base/parallel.h"
#include "levels_internal.h"
#include "tetpack_format.h"

/* size_of's sums in chunks of a number of tets that depends on the count alone (at least SIZE_CHUNK, at
 * most SIZE_CHUNKS of them), side by side, added in chunk order: the same sums whatever the thread count. */
#define SIZE_CHUNK ((int64_t)1 << 16)
#define SIZE_CHUNKS 2048

typedef struct size_job {
    const double *points;
    const int32_t *tets, *neighbors;
    int64_t tet_count, chunk;
    domain_size part[SIZE_CHUNKS];
} size_job;

static void size_chunks(void *ctx, int64_t begin, int64_t end, int worker)
{
    size_job *j = ctx;
    const double *points = j->points;
    (void)worker;
    for (int64_t c = begin; c < end; c++) {
        domain_size d = {0, 0};
        int64_t last = (c + 1) * j->chunk < j->tet_count ? (c + 1) * j->chunk : j->tet_count;
        for (int64_t t = c * j->chunk; t < last; t++) {
            const int32_t *v = j->tets + 4 * t;
            const double *a = points + 3 * (size_t)v[0];
            double ab[3], ac[3], ad[3];
            edge(a, points + 3 * (size_t)v[1], ab);
            edge(a, points + 3 * (size_t)v[2], ac);
            edge(a, points + 3 * (size_t)v[3], ad);
            d.volume += ab[0] * (ac[1] * ad[2] - ac[2] * ad[1]) - ab[1] * (ac[0] * ad[2] - ac[2] * ad[0]) +
                        ab[2] * (ac[0] * ad[1] - ac[1] * ad[0]);
            for (int k = 0; k < 4; k++)
                if (j->neighbors[4 * t + k] < 0) {
                    const double *p = points + 3 * (size_t)v[tpk_tet_faces[k][0]];
                    double e1[3], e2[3];
                    edge(p, points + 3 * (size_t)v[tpk_tet_faces[k][1]], e1);
                    edge(p, points + 3 * (size_t)v[tpk_tet_faces[k][2]], e2);
                    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
                           z = e1[0] * e2[1] - e1[1] * e2[0];
                    d.area += sqrt(x * x + y * y + z * z);
                }
        }
        j->part[c] = d;
    }
}

domain_size levels_size_of(const double *points, const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                           int threads)
{
    size_job job = {points, tets, neighbors, tet_count, SIZE_CHUNK, {{0, 0}}}; /* 32 KB */
    if (tet_count > SIZE_CHUNK * SIZE_CHUNKS)
        job.chunk = (tet_count + SIZE_CHUNKS - 1) / SIZE_CHUNKS;
    int64_t chunks = (tet_count + job.chunk - 1) / job.chunk;
    tpk_parallel_for(chunks, tpk_threads_for(chunks, threads, 1), size_chunks, &job);
    domain_size d = {0, 0};
    for (int64_t c = 0; c < chunks; c++)
        d.volume += job.part[c].volume, d.area += job.part[c].area;
    return d;
}

/* With the shell kept (tolerance 0), the same volume and area up to rounding; else the volume changed by
 * at most the shell's area times how far it moved. */
int levels_same_size(domain_size full, domain_size level, double tolerance)
{
    if (tolerance > 0)
        return fabs(level.volume - full.volume) / 6 <= tolerance * full.area / 2 + 1e-9 * fabs(full.volume) / 6;
    return fabs(level.volume - full.volume) <= 1e-9 * fabs(full.volume) &&
           fabs(level.area - full.area) <= 1e-9 * fabs(full.area);
}
