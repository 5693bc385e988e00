/* The CULL chunk (spec §17, format 1.4) from the converter's positive tets and their neighbors: per block
 * of TPK_CONVERT_CULL_BLOCK tets in file order, seeds of a walk inside the block and the intervals of
 * vertex ids its tets use. Blocks are independent, so workers take contiguous runs of them and the runs
 * are joined in order: the same words for any thread count. */
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "pipeline.h"
#include "tetpack_format.h"

typedef struct run {
    int32_t *seeds, *intervals; /* TPK_CULL_SEED_WORDS per seed, 2 per interval */
    int64_t seed_count, interval_count, seed_cap, interval_cap;
    int32_t *per_block;         /* per block of the run: its seeds, then its intervals (counts) */
    int failed;
} run;

typedef struct cull_job {
    const int32_t *tets, *neighbors;
    int64_t tet_count, block_tets, block_count;
    run runs[TPK_MAX_THREADS];
} cull_job;

static int grow(int32_t **items, int64_t *cap, int64_t need)
{
    if (need <= *cap)
        return 1;
    int64_t cap2 = *cap ? *cap : 1024;
    while (cap2 < need)
        cap2 *= 2;
    int32_t *grown = realloc(*items, sizeof *grown * (size_t)cap2);
    if (!grown)
        return 0;
    *items = grown, *cap = cap2;
    return 1;
}

/* ids[0 .. n) (non-negative) in ascending order, by 11-bit digits of id - smallest, as many passes as the
 * span needs (a block's ids lie close together along the Hilbert curve: one or two passes); tmp holds n. */
static void sort_ids(int32_t *ids, int32_t *tmp, int64_t n)
{
    int32_t lo = INT32_MAX, hi = 0;
    for (int64_t i = 0; i < n; i++)
        lo = ids[i] < lo ? ids[i] : lo, hi = ids[i] > hi ? ids[i] : hi;
    uint32_t span = n ? (uint32_t)(hi - lo) : 0;
    int32_t *from = ids, *to = tmp;
    for (int shift = 0; shift == 0 || (shift < 32 && (span >> shift) != 0); shift += 11) {
        int64_t count[2049] = {0};
        for (int64_t i = 0; i < n; i++)
            count[(((uint32_t)(from[i] - lo) >> shift) & 2047u) + 1]++;
        for (int d = 0; d < 2048; d++)
            count[d + 1] += count[d];
        for (int64_t i = 0; i < n; i++)
            to[count[((uint32_t)(from[i] - lo) >> shift) & 2047u]++] = from[i];
        int32_t *swap = from;
        from = to, to = swap;
    }
    if (from != ids)
        memcpy(ids, from, sizeof *ids * (size_t)n);
}

/* The even permutation of q with the smallest id first, then the smallest of the other three. */
static void canonical(const int32_t v[4], int32_t q[4])
{
    int r[4], odd = 0;
    int32_t s[4];
    for (int k = 0; k < 4; k++)
        r[k] = (v[0] < v[k]) + (v[1] < v[k]) + (v[2] < v[k]) + (v[3] < v[k]);
    for (int k = 0; k < 4; k++)
        s[r[k]] = v[k];
    for (int a = 0; a < 4; a++)
        for (int b = a + 1; b < 4; b++)
            odd += r[a] > r[b];
    q[0] = s[0], q[1] = s[1], q[2] = s[2 + (odd & 1)], q[3] = s[3 - (odd & 1)];
}

static void cull_blocks(void *ctx, int64_t begin, int64_t end, int worker)
{
    cull_job *j = ctx;
    run *ru = &j->runs[worker];
    const int64_t B = j->block_tets;
    int32_t *queue = malloc(sizeof *queue * (size_t)B), *ids = malloc(sizeof *ids * 8 * (size_t)B);
    unsigned char *reached = malloc((size_t)B);
    ru->per_block = malloc(sizeof *ru->per_block * 2 * (size_t)(end - begin > 0 ? end - begin : 1));
    if (!queue || !ids || !reached || !ru->per_block) {
        ru->failed = 1;
        goto done;
    }
    for (int64_t k = begin; k < end; k++) {
        const int64_t t0 = k * B, t1 = t0 + B < j->tet_count ? t0 + B : j->tet_count, n = t1 - t0;
        memset(reached, 0, (size_t)n);
        int64_t seeds_before = ru->seed_count, intervals_before = ru->interval_count;
        for (int64_t s = 0; s < n; s++) {
            if (reached[s])
                continue;
            /* a seed: the first tet not reached from the seeds before, then all it reaches in the block */
            const int32_t *v = j->tets + 4 * (t0 + s);
            int top = 0;
            for (int c = 1; c < 4; c++)
                top = v[c] > v[top] ? c : top;
            if (!grow(&ru->seeds, &ru->seed_cap, TPK_CULL_SEED_WORDS * (ru->seed_count + 1))) {
                ru->failed = 1;
                goto done;
            }
            int32_t *seed = ru->seeds + TPK_CULL_SEED_WORDS * ru->seed_count++;
            seed[0] = (int32_t)(t0 + s);
            canonical(v, seed + 1);
            seed[5] = j->neighbors[4 * (t0 + s) + top];
            int64_t head = 0, tail = 0;
            queue[tail++] = (int32_t)s, reached[s] = 1;
            while (head < tail) {
                int64_t c = t0 + queue[head++];
                for (int f = 0; f < 4; f++) {
                    int64_t u = j->neighbors[4 * c + f];
                    if (u >= t0 && u < t1 && !reached[u - t0])
                        reached[u - t0] = 1, queue[tail++] = (int32_t)(u - t0);
                }
            }
        }
        memcpy(ids, j->tets + 4 * t0, sizeof *ids * 4 * (size_t)n);
        sort_ids(ids, ids + 4 * B, 4 * n);
        for (int64_t i = 0; i < 4 * n;) {
            int32_t first = ids[i], last = ids[i];
            while (i < 4 * n && ids[i] <= last + 1 + TPK_CONVERT_CULL_GAP)
                last = ids[i++];
            if (!grow(&ru->intervals, &ru->interval_cap, 2 * (ru->interval_count + 1))) {
                ru->failed = 1;
                goto done;
            }
            ru->intervals[2 * ru->interval_count] = first;
            ru->intervals[2 * ru->interval_count++ + 1] = last + 1;
        }
        ru->per_block[2 * (k - begin)] = (int32_t)(ru->seed_count - seeds_before);
        ru->per_block[2 * (k - begin) + 1] = (int32_t)(ru->interval_count - intervals_before);
    }
done:
    free(queue);
    free(ids);
    free(reached);
}

int32_t *tpk_build_cull(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, int threads,
                        uint64_t *word_count)
{
    cull_job *j = calloc(1, sizeof *j);
    if (!j)
        return NULL;
    j->tets = tets, j->neighbors = neighbors, j->tet_count = tet_count;
    j->block_tets = TPK_CONVERT_CULL_BLOCK;
    j->block_count = (tet_count + j->block_tets - 1) / j->block_tets;
    threads = tpk_threads_for(j->block_count, tpk_thread_count(threads), 64);
    tpk_parallel_for(j->block_count, threads, cull_blocks, j);
    int64_t S = 0, I = 0, K = j->block_count;
    int failed = 0;
    for (int w = 0; w < threads; w++)
        S += j->runs[w].seed_count, I += j->runs[w].interval_count, failed |= j->runs[w].failed;
    uint64_t n = TPK_CULL_HEADER_WORDS + 2 * ((uint64_t)K + 1) + TPK_CULL_SEED_WORDS * (uint64_t)S + 2 * (uint64_t)I;
    int32_t *words = failed || S > INT32_MAX || I > INT32_MAX ? NULL : malloc(sizeof *words * n);
    if (words) {
        words[0] = (int32_t)j->block_tets, words[1] = (int32_t)K, words[2] = (int32_t)S, words[3] = (int32_t)I;
        int32_t *seed_start = words + TPK_CULL_HEADER_WORDS, *interval_start = seed_start + K + 1;
        int32_t *seeds = interval_start + K + 1, *intervals = seeds + TPK_CULL_SEED_WORDS * S;
        int64_t k = 0, s = 0, i = 0;
        seed_start[0] = interval_start[0] = 0;
        for (int w = 0; w < threads; w++) {
            const run *ru = &j->runs[w];
            int64_t begin, end;
            tpk_parallel_range(K, threads, w, &begin, &end);
            for (int64_t b = 0; b < end - begin; b++, k++) {
                s += ru->per_block[2 * b], i += ru->per_block[2 * b + 1];
                seed_start[k + 1] = (int32_t)s, interval_start[k + 1] = (int32_t)i;
            }
            memcpy(seeds, ru->seeds, sizeof *seeds * TPK_CULL_SEED_WORDS * (size_t)ru->seed_count);
            memcpy(intervals, ru->intervals, sizeof *intervals * 2 * (size_t)ru->interval_count);
            seeds += TPK_CULL_SEED_WORDS * ru->seed_count, intervals += 2 * ru->interval_count;
        }
        *word_count = n;
    }
    for (int w = 0; w < threads; w++)
        free(j->runs[w].seeds), free(j->runs[w].intervals), free(j->runs[w].per_block);
    free(j);
    return words;
}
