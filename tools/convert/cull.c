/* The CULL chunk (spec §17, format 1.4) from the converter's positive tets and their neighbors: per block
 * of TPK_CONVERT_CULL_BLOCK tets in file order, seeds of a walk inside the block and the intervals of
 * vertex ids its tets use (exactly: the maximal runs of consecutive ids among them). Blocks are independent, so workers take contiguous runs of them and the runs
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
    int64_t tet_count, vertex_count, block_tets, block_count;
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

/* Bit v of a worker's vertex bitmap. */
static inline int bit(const uint64_t *bits, int64_t v)
{
    return (int)(bits[v >> 6] >> (v & 63)) & 1;
}

/* runs[0 .. n) (first, end pairs, disjoint) by first, ascending: a block has a few dozen. */
static void sort_runs(int32_t *runs, int64_t n)
{
    for (int64_t i = 1; i < n; i++) {
        int32_t a = runs[2 * i], e = runs[2 * i + 1];
        int64_t k = i;
        for (; k > 0 && runs[2 * k - 2] > a; k--)
            runs[2 * k] = runs[2 * k - 2], runs[2 * k + 1] = runs[2 * k - 1];
        runs[2 * k] = a, runs[2 * k + 1] = e;
    }
}

/* The even permutation of v with the smallest id first, then the smallest of the other three. */
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
    int32_t *queue = malloc(sizeof *queue * (size_t)B);
    uint64_t *bits = calloc((size_t)(j->vertex_count / 64 + 1), sizeof *bits); /* all clear between blocks */
    unsigned char *reached = malloc((size_t)B);
    ru->per_block = malloc(sizeof *ru->per_block * 2 * (size_t)(end - begin > 0 ? end - begin : 1));
    if (!queue || !bits || !reached || !ru->per_block) {
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
        /* the maximal runs of consecutive ids among the block's vertices: each id's bit set, then from
         * each id still set its run found by walking its neighbours' bits, which are cleared (no sort) */
        const int32_t *ids = j->tets + 4 * t0;
        for (int64_t i = 0; i < 4 * n; i++)
            bits[ids[i] >> 6] |= 1ull << (ids[i] & 63);
        for (int64_t i = 0; i < 4 * n; i++) {
            int64_t first = ids[i], end = ids[i] + 1;
            if (!bit(bits, first))
                continue; /* in a run already found */
            while (first > 0 && bit(bits, first - 1))
                first--;
            while (end < j->vertex_count && bit(bits, end))
                end++;
            for (int64_t v = first; v < end; v++)
                bits[v >> 6] &= ~(1ull << (v & 63));
            if (!grow(&ru->intervals, &ru->interval_cap, 2 * (ru->interval_count + 1))) {
                ru->failed = 1;
                goto done;
            }
            ru->intervals[2 * ru->interval_count] = (int32_t)first;
            ru->intervals[2 * ru->interval_count++ + 1] = (int32_t)end;
        }
        sort_runs(ru->intervals + 2 * intervals_before, ru->interval_count - intervals_before);
        ru->per_block[2 * (k - begin)] = (int32_t)(ru->seed_count - seeds_before);
        ru->per_block[2 * (k - begin) + 1] = (int32_t)(ru->interval_count - intervals_before);
    }
done:
    free(queue);
    free(bits);
    free(reached);
}

int32_t *tpk_build_cull(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, int64_t vertex_count,
                        int threads, uint64_t *word_count)
{
    cull_job *j = calloc(1, sizeof *j);
    if (!j)
        return NULL;
    j->tets = tets, j->neighbors = neighbors, j->tet_count = tet_count, j->vertex_count = vertex_count;
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
