/* The selected tree of the range culling (tpk_range_bvh_select, tetpack.h): the tets whose scalar range
 * holds one of the iso values, clustered bottom-up in file order (tpki_range_tree_build, range_build.c;
 * leaves of up to ACTIVE_LEAF tets), folded into a four-wide tree (tpki_wide_node) whose children a ray
 * tests at once, with each tet's vertices and positions copied into leaf order.
 *
 * Measured on the 998k-tet grid of bench/make_grid_vtk.py 55, iso 0.3 (17% of the tets hold it), 1024^2,
 * one thread, leaves of up to 4: the file-order tree tests 28 tets per ray, the selected tree (then a
 * binned-SAH one, whose rays the clustered tree matches) 7.4. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_range.h"
#include "internal_threads.h"

/* Up to 6 tets a leaf, not 4: the packets' float tests sift a leaf's tets cheaply, and fewer nodes mean
 * fewer node tests and queue steps (grid 120, iso 0.3: 181k wide nodes, not 297k); grid 55 512^2 under
 * callgrind: 706M -> 694M instructions, 3.42M -> 3.10M simulated mispredicts; 7 is no better. At most 7
 * (tpki_leaf_ref). */
#define ACTIVE_LEAF 6

static float half_area(const float lo[3], const float hi[3])
{
    float d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
}

/* Fold the binary tree `bin` (root 0) into b->wide, four children a node: each wide node takes its binary
 * node's children, then splits the largest inner one among them into its two children while it has
 * fewer than four. Returns TPK_OK or TPK_ERR_OUT_OF_MEMORY. */
static tpk_result fold_wide(tpk_range_bvh *b, const tpk_bvh_node *bin, int32_t bin_count)
{
    b->wide = malloc(sizeof *b->wide * (size_t)bin_count);
    int32_t *pending = malloc(sizeof *pending * (size_t)bin_count); /* binary node of each wide node */
    if (!b->wide || !pending) {
        free(pending);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    int64_t count = 1;
    pending[0] = 0;
    for (int64_t w = 0; w < count; w++) {
        int32_t lane[4], lanes = 0;
        const tpk_bvh_node *top = &bin[pending[w]];
        if (top->count > 0) {
            lane[lanes++] = pending[w]; /* a root that is a leaf */
        } else {
            lane[lanes++] = top->first;
            lane[lanes++] = top->first + 1;
        }
        while (lanes < 4) {
            int best = -1;
            float best_area = -1.0f;
            for (int i = 0; i < lanes; i++) {
                const tpk_bvh_node *n = &bin[lane[i]];
                if (n->count == 0 && half_area(n->lo, n->hi) > best_area)
                    best = i, best_area = half_area(n->lo, n->hi);
            }
            if (best < 0)
                break;
            int32_t split = lane[best];
            lane[best] = bin[split].first;
            lane[lanes++] = bin[split].first + 1;
        }
        tpki_wide_node *node = &b->wide[w];
        for (int i = 0; i < 4; i++) {
            for (int k = 0; k < 3; k++) {
                node->box[k][i] = i < lanes ? bin[lane[i]].lo[k] : INFINITY;
                node->box[k + 3][i] = i < lanes ? bin[lane[i]].hi[k] : -INFINITY;
            }
            if (i >= lanes) {
                node->child[i] = 0, node->count[i] = -1;
            } else if (bin[lane[i]].count > 0) {
                node->child[i] = bin[lane[i]].first, node->count[i] = bin[lane[i]].count;
            } else {
                node->child[i] = (int32_t)count, node->count[i] = 0;
                pending[count++] = lane[i];
            }
        }
    }
    b->wide_count = count;
    free(pending);
    return TPK_OK;
}

/* Blocks to walk, shared out in contiguous slices; each share stops at its first error. */
typedef struct ready_job {
    tpk_range_bvh *b;
    int64_t *blocks, count;
    tpk_result result[TPKI_THREADS_MAX];
} ready_job;

static void ready_share(void *arg, int share, int shares)
{
    ready_job *j = arg;
    int64_t i0 = j->count * share / shares, i1 = j->count * (share + 1) / shares;
    for (int64_t i = i0; i < i1 && j->result[share] == TPK_OK; i++)
        j->result[share] = tpki_range_ready_block(j->b, (uint64_t)j->blocks[i]);
}

/* The runs of tets [span[2i], span[2i + 1]) that may hold a value, in file order: all tets, or with
 * culling blocks the blocks whose range holds one, each walked and its tets' ranges read (the tets
 * outside them hold none). *spans malloc'd. */
static tpk_result candidate_spans(tpk_range_bvh *b, const double *values, int count, int64_t **spans, int64_t *n)
{
    const int64_t tet_count = (int64_t)b->marcher->mesh.tet_count;
    const uint64_t blocks = b->culled ? b->cull.block_count : 1;
    *n = 0;
    *spans = malloc(sizeof **spans * 2 * (size_t)(blocks ? blocks : 1));
    if (!*spans)
        return TPK_ERR_OUT_OF_MEMORY;
    if (!b->culled) {
        (*spans)[0] = 0, (*spans)[1] = tet_count, *n = 1;
        return TPK_OK;
    }
    const int64_t B = b->cull.block_tets;
    ready_job job = {b, malloc(sizeof *job.blocks * (size_t)(blocks ? blocks : 1)), 0, {0}};
    if (!job.blocks)
        return TPK_ERR_OUT_OF_MEMORY;
    for (uint64_t k = 0; k < blocks; k++)
        if (tpki_range_block_holds(b, k, values, count))
            job.blocks[job.count++] = (int64_t)k;
    tpki_run_threads(job.count >= 64 ? b->threads : 1, ready_share, &job);
    tpk_result r = TPK_OK;
    for (int i = 0; i < TPKI_THREADS_MAX && r == TPK_OK; i++)
        r = job.result[i]; /* the first share's error: the lowest block's, for any thread count */
    for (int64_t i = 0; r == TPK_OK && i < job.count; i++) {
        int64_t t0 = job.blocks[i] * B, t1 = t0 + B < tet_count ? t0 + B : tet_count;
        if (*n > 0 && (*spans)[2 * *n - 1] == t0)
            (*spans)[2 * *n - 1] = t1; /* joined to the run before */
        else
            (*spans)[2 * *n] = t0, (*spans)[2 * *n + 1] = t1, ++*n;
    }
    free(job.blocks);
    return r;
}

/* The binary tree's items: the box (rounded outward, padded as the file-order tree's leaves) and
 * centroid of each tet that holds a value, in file order. */
static void active_items(const tpk_range_bvh *b, const double *values, int count, const int64_t *spans,
                         int64_t span_count, tpki_bvh_item *items)
{
    const float *pos = b->marcher->mesh.positions;
    for (int64_t sp = 0, i = 0; sp < span_count; sp++)
    for (int64_t t = spans[2 * sp]; t < spans[2 * sp + 1]; t++) {
        if (!tpki_range_holds(b->tet_range[2 * t], b->tet_range[2 * t + 1], values, count))
            continue;
        tpki_bvh_item *it = &items[i++];
        it->id = (int32_t)t;
        for (int k = 0; k < 3; k++) {
            float lo = INFINITY, hi = -INFINITY;
            double sum = 0.0;
            for (int c = 0; c < 4; c++) {
                float x = pos[3 * (int64_t)b->tets[4 * t + c] + k];
                lo = x < lo ? x : lo;
                hi = x > hi ? x : hi;
                sum += x;
            }
            it->lo[k] = tpki_round_down((double)lo - b->pad);
            it->hi[k] = tpki_round_up((double)hi + b->pad);
            it->centroid[k] = (float)(0.25 * sum);
        }
    }
}

tpk_result tpk_range_bvh_select(tpk_range_bvh *b, const double *values, int count)
{
    if (!b || count < 0 || (count > 0 && !values))
        return TPK_ERR_INVALID_ARGUMENT;
    tpki_range_drop_selection(b);
    if (count == 0)
        return TPK_OK;
    int64_t *spans = NULL, span_count = 0, n = 0;
    tpk_result sr = candidate_spans(b, values, count, &spans, &span_count);
    if (sr != TPK_OK) {
        free(spans);
        return sr;
    }
    for (int64_t sp = 0; sp < span_count; sp++)
        for (int64_t t = spans[2 * sp]; t < spans[2 * sp + 1]; t++)
            n += tpki_range_holds(b->tet_range[2 * t], b->tet_range[2 * t + 1], values, count);
    const size_t room = (size_t)(n ? n : 1);
    tpki_bvh_item *items = malloc(sizeof *items * room);
    tpk_bvh_node *bin = malloc(sizeof *bin * 2 * room);
    b->active_tets = malloc(sizeof *b->active_tets * room);
    b->active_slots = malloc(sizeof *b->active_slots * room);
    b->active_scalars = malloc(sizeof *b->active_scalars * room);
    b->active_values = malloc(sizeof *b->active_values * (size_t)count);
    tpk_result r = items && bin && b->active_tets && b->active_slots && b->active_scalars && b->active_values
                       ? TPK_OK
                       : TPK_ERR_OUT_OF_MEMORY;
    int32_t bin_count = 0;
    if (r == TPK_OK && n > 0) {
        active_items(b, values, count, spans, span_count, items);
        r = tpki_range_tree_build(items, (int32_t)n, ACTIVE_LEAF, b->threads, bin, &bin_count);
    }
    if (r == TPK_OK && n > 0)
        r = fold_wide(b, bin, bin_count);
    b->active_corner_max = 0;
    for (int k = 0; r == TPK_OK && n > 0 && k < 6; k++)
        for (int i = 0; i < 4; i++)
            if (b->wide[0].count[i] >= 0)
                b->active_corner_max = fmax(b->active_corner_max, fabs((double)b->wide[0].box[k][i]));
    if (r == TPK_OK) {
        const float *pos = b->marcher->mesh.positions, *sc = b->marcher->mesh.scalars;
        for (int64_t i = 0; i < n; i++) {
            int32_t t = items[i].id;
            b->active_tets[i] = t;
            for (int c = 0; c < 4; c++) {
                int32_t v = b->tets[4 * (int64_t)t + c];
                b->active_slots[i].v[c] = v;
                b->active_scalars[i][c] = sc[v];
                for (int k = 0; k < 3; k++)
                    b->active_slots[i].pos[k][c] = pos[3 * (int64_t)v + k];
            }
        }
        memcpy(b->active_values, values, sizeof *values * (size_t)count);
        b->active_value_count = count;
    }
    free(items);
    free(bin);
    free(spans);
    if (r != TPK_OK)
        tpki_range_drop_selection(b);
    return r;
}
