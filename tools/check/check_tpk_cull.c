/* Check 616 (TPK-B01, spec §17.2): the culling blocks of a CULL chunk against the reference tets and
 * neighbors the other passes use (Tet32's stored ids, or the walk's), never a walk of its own. Per block:
 * each seed's ids an even permutation of its tet's positive order and its n3 the neighbor opposite the
 * largest id; every tet of the block reached from its seeds across faces inside the block; every vertex
 * of its tets inside one of its intervals. The structure (rule 17) is the library's (tpk_load_cull): a
 * verified file passed it, so a refusal here is reported under 616 with the library's message. */
#include <inttypes.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>

#include "check_tpk_internal.h"

typedef struct cull_blocks_job {
    const tpk_cull *cull;
    atomic_int out_of_memory; /* set by any worker that could not allocate its scratch */
} cull_blocks_job;

static int64_t block_end(const tpkc *c, const tpk_cull *cull, int64_t k)
{
    int64_t end = (k + 1) * (int64_t)cull->block_tets;
    return end < c->T ? end : c->T;
}

/* 1 when `ids` holds the same four ids as `q`, with *odd set to the parity of the permutation. */
static int same_ids(const int32_t q[4], const int32_t ids[4], int *odd)
{
    int at[4];
    for (int i = 0; i < 4; i++) {
        at[i] = -1;
        for (int j = 0; j < 4; j++)
            if (q[j] == ids[i])
                at[i] = j;
        if (at[i] < 0)
            return 0;
    }
    int inversions = 0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            inversions += at[i] > at[j];
    *odd = inversions & 1;
    return 1;
}

static tpk_example *block_hit(tpkc_sink *sink, int64_t block, int64_t tet, int64_t seed)
{
    tpk_example *ex = tpkc_hit(sink, 616, "block");
    int64_t ids[3] = {block, tet, seed};
    tpk_example_ids(ex, seed < 0 ? 2 : 3, ids);
    return ex;
}

/* A seed's ids and n3 against its tet (the reference ids are positive: 602 found nothing). */
static void check_seed(const tpkc *c, tpkc_sink *sink, int64_t block, int64_t s, const int32_t *w)
{
    int32_t q[4], n[4];
    if (!tpkc_usable(c, w[0], q))
        return;
    int odd = 0;
    if (!same_ids(q, w + 1, &odd)) {
        tpk_example_note(block_hit(sink, block, w[0], s),
                         "seed %" PRId64 " (tet %d): ids (%d, %d, %d, %d) are not the tet's (%d, %d, %d, %d)", s,
                         w[0], w[1], w[2], w[3], w[4], q[0], q[1], q[2], q[3]);
        return;
    }
    if (odd) {
        tpk_example_note(block_hit(sink, block, w[0], s),
                         "seed %" PRId64 " (tet %d): ids (%d, %d, %d, %d) are an odd permutation of its positive "
                         "order (%d, %d, %d, %d)", s, w[0], w[1], w[2], w[3], w[4], q[0], q[1], q[2], q[3]);
        return;
    }
    tpkc_neighbors(c, w[0], q, n);
    int largest = 0;
    for (int k = 1; k < 4; k++)
        largest = q[k] > q[largest] ? k : largest;
    if (w[5] != n[largest])
        tpk_example_note(block_hit(sink, block, w[0], s),
                         "seed %" PRId64 " (tet %d): n3 is %d, but the tet across the face opposite its largest id %d "
                         "is %d", s, w[0], w[5], q[largest], n[largest]);
}

/* Whether one of `intervals[0..count)` (sorted, disjoint, count >= 1) holds v: the first interval whose
 * end is above v, found without branches on the data (a branchy search spent most of this pass in
 * mispredictions), must start at or below v. */
static int in_intervals(const int32_t *intervals, int64_t count, int32_t v)
{
    int64_t lo = 0, n = count;
    while (n > 1) {
        int64_t half = n / 2;
        lo = intervals[2 * (lo + half) + 1] <= v ? lo + half : lo;
        n -= half;
    }
    lo += intervals[2 * lo + 1] <= v;
    return lo < count && intervals[2 * lo] <= v;
}

/* Block k: its seeds, then a walk from them across faces inside the block (reached[] and queue[] hold
 * the block's tets), then every tet's vertices against the intervals. */
static void check_block(const tpkc *c, const tpk_cull *cull, tpkc_sink *sink, int64_t k, uint8_t *reached,
                        int32_t *queue)
{
    int64_t t0 = k * (int64_t)cull->block_tets, t1 = block_end(c, cull, k);
    memset(reached, 0, (size_t)(t1 - t0));
    int64_t head = 0, tail = 0;
    for (int64_t s = cull->seed_start[k]; s < cull->seed_start[k + 1]; s++) {
        const int32_t *w = cull->seeds + TPK_CULL_SEED_WORDS * s;
        check_seed(c, sink, k, s, w);
        if (!reached[w[0] - t0]) { /* rule 17 put the seed's tet in the block */
            reached[w[0] - t0] = 1;
            queue[tail++] = w[0];
        }
    }
    while (head < tail) {
        int32_t t = queue[head++], q[4], n[4];
        if (!tpkc_usable(c, t, q))
            continue;
        tpkc_neighbors(c, t, q, n);
        for (int f = 0; f < 4; f++)
            if (n[f] >= t0 && n[f] < t1 && !reached[n[f] - t0]) {
                reached[n[f] - t0] = 1;
                queue[tail++] = n[f];
            }
    }
    const int32_t *intervals = cull->intervals + 2 * (int64_t)cull->interval_start[k];
    int64_t interval_count = cull->interval_start[k + 1] - cull->interval_start[k];
    for (int64_t t = t0; t < t1; t++) {
        if (!reached[t - t0])
            tpk_example_note(block_hit(sink, k, t, -1),
                             "tet %" PRId64 " is not reached from block %" PRId64 "'s %d seeds across faces inside "
                             "the block [%" PRId64 ", %" PRId64 ")", t, k,
                             cull->seed_start[k + 1] - cull->seed_start[k], t0, t1);
        int32_t q[4];
        if (!tpkc_usable(c, t, q))
            continue;
        for (int j = 0; j < 4; j++)
            if (!in_intervals(intervals, interval_count, q[j])) {
                tpk_example_note(block_hit(sink, k, t, -1),
                                 "tet %" PRId64 ": vertex %d lies in none of block %" PRId64 "'s %" PRId64
                                 " intervals (ids %d to %d)", t, q[j], k, interval_count, intervals[0],
                                 intervals[2 * interval_count - 1] - 1);
                break;
            }
    }
}

static void cull_blocks(void *ctx, int64_t begin, int64_t end, int worker)
{
    tpkc_pass *pass = ctx;
    cull_blocks_job *job = pass->user;
    size_t B = job->cull->block_tets;
    uint8_t *reached = malloc(B);
    int32_t *queue = malloc(B * sizeof *queue);
    if (!reached || !queue)
        atomic_store(&job->out_of_memory, 1);
    else
        for (int64_t k = begin; k < end; k++)
            check_block(pass->c, job->cull, &pass->sinks[worker], k, reached, queue);
    free(reached);
    free(queue);
}

/* Content needs reference ids and neighbors the other checks found sound. */
static int reference_sound(const tpkc *c)
{
    if (c->unrecovered)
        return 0;
    for (int id = 601; id <= 610; id++)
        if (tpk_check_finding(c->report, id)->count)
            return 0;
    return 1;
}

int tpkc_check_cull(tpkc *c, tpk_diag *diag)
{
    tpk_cull cull;
    tpk_result r = tpk_load_cull(c->file, &cull);
    if (r == TPK_ERR_NOT_FOUND)
        return 0;
    if (r == TPK_ERR_OUT_OF_MEMORY)
        return tpk_diag_fail(diag, "out of memory loading the CULL chunk: %s", tpk_error_text(c->file));
    tpk_finding *finding = tpk_check_finding(c->report, 616);
    if (r != TPK_OK) {
        tpk_example_note(tpk_check_hit(c->report, 616, "chunk"), "TPK-R17 (%s): %s", tpk_result_string(r),
                         tpk_error_text(c->file));
        snprintf(finding->summary, sizeof finding->summary, "the CULL chunk is refused by readers (%s)",
                 tpk_result_string(r));
        return 0;
    }
    if (!reference_sound(c)) {
        snprintf(finding->summary, sizeof finding->summary,
                 "not checked: the tets break checks 601-610, which the blocks are checked against");
        return 0;
    }
    cull_blocks_job job = {&cull, 0};
    if (tpkc_run_pass(c, (int64_t)cull.block_count, 1 << 8, cull_blocks, &job, diag))
        return -1;
    if (atomic_load(&job.out_of_memory))
        return tpk_diag_fail(diag, "out of memory checking %" PRIu64 " culling blocks of %u tets", cull.block_count,
                             cull.block_tets);
    if (finding->count)
        snprintf(finding->summary, sizeof finding->summary,
                 "%" PRId64 " seeds and tets at fault in %" PRIu64 " blocks of %u tets", finding->count,
                 cull.block_count, cull.block_tets);
    return 0;
}
