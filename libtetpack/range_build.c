/* The selected tree's binary hierarchy (tpki_range_tree_build, internal_range.h), built bottom-up over
 * the active tets in file order: locally-ordered clustering (PLOC: Meister and Bittner, "Parallel
 * Locally-Ordered Clustering for Bounding Volume Hierarchy Construction", 2018). The file's tets follow
 * a Hilbert curve (spec §6.4), so a tet's best partner is among its near neighbours in that order: each
 * round, every cluster finds the one of the PLOC_RADIUS clusters on either side whose union box has the
 * least area, mutual pairs merge, and the rest wait for the next round. Each round costs O(radius) a
 * cluster and removes a fixed share of them, so the build is linear in the active tets, where the
 * binned-SAH top-down build it replaces sorted them level by level.
 *
 * Every step is a function of the items' order and boxes alone: the areas are computed block by block
 * on any number of threads, the merges in one pass in order, so the tree is the same bytes for any
 * thread count. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "internal_range.h"
#include "internal_threads.h"

/* Clusters compared on each side: 8, two vectors of 4 in areas_of (which assumes it). The rays on these
 * trees are within 2% of those on the binned-SAH tree (bench/README, issue 39 item 4); other radii were
 * not measured. */
#define PLOC_RADIUS 8
/* Clusters per block of the area pass, fixed so that the blocks never depend on the thread count. */
#define PLOC_BLOCK 4096

typedef struct ploc_node {
    float lo[3], hi[3];
    int32_t child[2]; /* a leaf: child[0] = -1 - its item, child[1] = 1 */
    int32_t count;    /* items below */
} ploc_node;

/* The clusters of a round, one array per coordinate (the area pass reads 8 neighbours' boxes as two
 * vectors), PLOC_RADIUS infinite boxes past the end. */
typedef struct ploc_job {
    float *box[6];    /* lo x, y, z, hi x, y, z */
    int32_t *node;    /* the tree node of each cluster */
    int32_t *items;   /* the items below it */
    int64_t count;
    float *area;      /* area[PLOC_RADIUS * i + k - 1]: half area of the union of clusters i and i + k */
    int32_t *nearest; /* per cluster: its best partner */
    int pass;         /* 0: areas, 1: nearest */
    int64_t next_block;
    pthread_mutex_t lock;
} ploc_job;

static void areas_of(ploc_job *job, int64_t begin, int64_t end)
{
    for (int64_t i = begin; i < end; i++) {
        tpki_v4f d[2][3];
        for (int k = 0; k < 3; k++)
            for (int h = 0; h < 2; h++) {
                tpki_v4f lo, hi;
                memcpy(&lo, job->box[k] + i + 1 + 4 * h, sizeof lo);
                memcpy(&hi, job->box[k + 3] + i + 1 + 4 * h, sizeof hi);
                tpki_v4f ilo = {job->box[k][i], job->box[k][i], job->box[k][i], job->box[k][i]};
                tpki_v4f ihi = {job->box[k + 3][i], job->box[k + 3][i], job->box[k + 3][i], job->box[k + 3][i]};
                d[h][k] = tpki_v4_max(hi, ihi) - tpki_v4_min(lo, ilo);
            }
        for (int h = 0; h < 2; h++) {
            tpki_v4f a = d[h][0] * d[h][1] + d[h][1] * d[h][2] + d[h][2] * d[h][0];
            tpki_v4i nan = a != a; /* NaN (hostile positions) last, so the order of pairs stays total */
            a = (tpki_v4f)(((tpki_v4i)a & ~nan) | ((tpki_v4i)(tpki_v4f){INFINITY, INFINITY, INFINITY, INFINITY} & nan));
            memcpy(job->area + PLOC_RADIUS * i + 4 * h, &a, sizeof a);
        }
    }
}

/* The partner of least union area; equal areas go to the smaller index, so that pairs are in one total
 * order (area, then first index, then second) and the least pair of all is always mutual. Clusters
 * past the end have infinite boxes, hence infinite areas, and lose every tie. */
static void nearest_of(ploc_job *job, int64_t begin, int64_t end)
{
    for (int64_t i = begin; i < end; i++) {
        float best = INFINITY;
        int64_t partner = i + 1 < job->count ? i + 1 : i - 1;
        for (int k = PLOC_RADIUS; k >= 1; k--) {
            float a = i - k >= 0 ? job->area[PLOC_RADIUS * (i - k) + k - 1] : INFINITY;
            int better = a < best;
            best = better ? a : best;
            partner = better ? i - k : partner;
        }
        for (int k = 1; k <= PLOC_RADIUS; k++) {
            float a = job->area[PLOC_RADIUS * i + k - 1]; /* infinite past the end */
            int better = a < best;
            best = better ? a : best;
            partner = better ? i + k : partner;
        }
        job->nearest[i] = (int32_t)partner;
    }
}

/* Blocks taken in turn until none is left: any share may do any block (the areas and partners are the
 * same whoever computes them). */
static void ploc_worker(void *arg, int share, int shares)
{
    (void)share, (void)shares;
    ploc_job *job = arg;
    for (;;) {
        pthread_mutex_lock(&job->lock);
        int64_t block = job->next_block++;
        pthread_mutex_unlock(&job->lock);
        int64_t begin = block * PLOC_BLOCK;
        if (begin >= job->count)
            return;
        int64_t end = begin + PLOC_BLOCK < job->count ? begin + PLOC_BLOCK : job->count;
        if (job->pass == 0)
            areas_of(job, begin, end);
        else
            nearest_of(job, begin, end);
    }
}

/* One pass over all clusters, on up to `threads` threads (the calling one among them), no more than
 * there are blocks. */
static void run_pass(ploc_job *job, int pass, int threads)
{
    job->pass = pass;
    job->next_block = 0;
    int64_t blocks = (job->count + PLOC_BLOCK - 1) / PLOC_BLOCK;
    tpki_run_threads(threads < blocks ? threads : (int)blocks, ploc_worker, job);
}

/* Cluster j into cluster i as tree node `at`, the union kept at position `to` (<= i). */
static void merge_into(ploc_job *job, ploc_node *nodes, int32_t at, int64_t i, int64_t j, int64_t to)
{
    ploc_node *n = &nodes[at];
    for (int k = 0; k < 3; k++) {
        float lo = job->box[k][i] < job->box[k][j] ? job->box[k][i] : job->box[k][j];
        float hi = job->box[k + 3][i] > job->box[k + 3][j] ? job->box[k + 3][i] : job->box[k + 3][j];
        n->lo[k] = job->box[k][to] = lo;
        n->hi[k] = job->box[k + 3][to] = hi;
    }
    n->child[0] = job->node[i], n->child[1] = job->node[j];
    n->count = job->items[to] = job->items[i] + job->items[j];
    job->node[to] = at;
}

static void keep_at(ploc_job *job, int64_t i, int64_t to)
{
    for (int k = 0; k < 6; k++)
        job->box[k][to] = job->box[k][i];
    job->node[to] = job->node[i];
    job->items[to] = job->items[i];
}

/* Rounds of clustering of the first `count` nodes until one cluster is left; returns the root, or -1 out
 * of memory. */
static int32_t cluster_all(ploc_node *nodes, int32_t count, int threads)
{
    ploc_job job = {.count = count, .lock = PTHREAD_MUTEX_INITIALIZER};
    int ok = 1;
    for (int k = 0; k < 6; k++)
        ok &= (job.box[k] = malloc(sizeof *job.box[k] * ((size_t)count + PLOC_RADIUS))) != NULL;
    job.node = malloc(sizeof *job.node * (size_t)count);
    job.items = malloc(sizeof *job.items * (size_t)count);
    job.area = malloc(sizeof *job.area * PLOC_RADIUS * (size_t)count);
    job.nearest = malloc(sizeof *job.nearest * (size_t)count);
    ok &= job.node && job.items && job.area && job.nearest;
    for (int32_t i = 0; ok && i < count; i++) {
        for (int k = 0; k < 3; k++)
            job.box[k][i] = nodes[i].lo[k], job.box[k + 3][i] = nodes[i].hi[k];
        job.node[i] = i, job.items[i] = nodes[i].count;
    }
    int32_t next = count;
    while (ok && job.count > 1) {
        for (int k = 0; k < 6; k++)
            for (int e = 0; e < PLOC_RADIUS; e++)
                job.box[k][job.count + e] = k < 3 ? -INFINITY : INFINITY;
        run_pass(&job, 0, threads);
        run_pass(&job, 1, threads);
        int64_t kept = 0, merges = 0;
        for (int64_t i = 0; i < job.count; i++)
            merges += job.nearest[job.nearest[i]] == i && job.nearest[i] > i;
        /* too few mutual pairs (equal boxes everywhere: hostile input) would take quadratic time: pair
         * neighbours in order instead, which halves the clusters */
        int pairs = merges * 16 < job.count;
        for (int64_t i = 0; i < job.count; i++) {
            int64_t j = !pairs ? job.nearest[i] : i % 2 ? i - 1 : i + 1 < job.count ? i + 1 : -1;
            int mutual = pairs ? j >= 0 : job.nearest[j] == i;
            if (!mutual)
                keep_at(&job, i, kept++);
            else if (j > i)
                merge_into(&job, nodes, next++, i, j, kept++);
        }
        job.count = kept;
    }
    int32_t root = ok ? job.node[0] : -1;
    for (int k = 0; k < 6; k++)
        free(job.box[k]);
    free(job.node);
    free(job.items);
    free(job.area);
    free(job.nearest);
    pthread_mutex_destroy(&job.lock);
    return root;
}

/* The binary tree in tpk_bvh_node form, depth first (root 0, an inner node's children at first and
 * first + 1): a subtree of at most leaf_size items becomes a leaf, its items taken into the next slots
 * of *order. Returns the node count. */
static int32_t emit(const ploc_node *nodes, int32_t root, int leaf_size, tpk_bvh_node *out, int32_t *stack,
                    int32_t *order)
{
    int32_t out_count = 1, slots = 0, top = 0;
    stack[top++] = root, stack[top++] = 0; /* pairs: tree node, out node */
    while (top > 0) {
        int32_t at = stack[--top], node = stack[--top];
        const ploc_node *n = &nodes[node];
        tpk_bvh_node *o = &out[at];
        memcpy(o->lo, n->lo, sizeof o->lo);
        memcpy(o->hi, n->hi, sizeof o->hi);
        if (n->count <= leaf_size) {
            o->first = slots, o->count = n->count;
            int32_t leaf_stack[64], leaf_top = 0; /* a subtree of at most leaf_size (< 64) items */
            leaf_stack[leaf_top++] = node;
            while (leaf_top > 0) {
                const ploc_node *l = &nodes[leaf_stack[--leaf_top]];
                if (l->child[0] < 0) {
                    for (int32_t i = 0; i < l->child[1]; i++)
                        order[slots++] = -1 - l->child[0] + i;
                } else {
                    leaf_stack[leaf_top++] = l->child[1];
                    leaf_stack[leaf_top++] = l->child[0];
                }
            }
            continue;
        }
        o->first = out_count, o->count = 0;
        stack[top++] = n->child[1], stack[top++] = out_count + 1;
        stack[top++] = n->child[0], stack[top++] = out_count;
        out_count += 2;
    }
    return out_count;
}

tpk_result tpki_range_tree_build(tpki_bvh_item *items, int32_t n, int leaf_size, int threads,
                                 tpk_bvh_node *out, int32_t *node_count)
{
    *node_count = 0;
    if (n <= 0)
        return TPK_OK;
    ploc_node *nodes = malloc(sizeof *nodes * (2 * (size_t)n - 1));
    int32_t *stack = malloc(sizeof *stack * 4 * (size_t)n);
    int32_t *order = malloc(sizeof *order * (size_t)n);
    tpki_bvh_item *sorted = malloc(sizeof *sorted * (size_t)n);
    tpk_result r = TPK_ERR_OUT_OF_MEMORY;
    if (nodes && stack && order && sorted) {
        for (int32_t i = 0; i < n; i++) {
            ploc_node *l = &nodes[i];
            memcpy(l->lo, items[i].lo, sizeof l->lo);
            memcpy(l->hi, items[i].hi, sizeof l->hi);
            l->child[0] = -1 - i, l->child[1] = 1, l->count = 1;
        }
        int32_t root = cluster_all(nodes, n, threads > 0 ? threads : 1);
        if (root >= 0) {
            *node_count = emit(nodes, root, leaf_size, out, stack, order);
            for (int32_t i = 0; i < n; i++)
                sorted[i] = items[order[i]];
            memcpy(items, sorted, sizeof *items * (size_t)n);
            r = TPK_OK;
        }
    }
    free(nodes);
    free(stack);
    free(order);
    free(sorted);
    return r;
}
