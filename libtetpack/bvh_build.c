/* The binned-SAH BVH builder (tpki_bvh_build, internal_march.h) that the shell BVH (shell_bvh.c) and the
 * active-tet tree of iso rays (range_bvh.c) share: items with boxes and centroids in, nodes in the
 * tpk_bvh_node form (root first, an inner node's children at first and first + 1) out. */
#include <float.h>
#include <stdlib.h>

#include "internal_march.h"

#define SAH_BINS 16

typedef struct build_task {
    int32_t node, begin, end, depth;
} build_task;

static void grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = plo[k] < lo[k] ? plo[k] : lo[k];
        hi[k] = phi[k] > hi[k] ? phi[k] : hi[k];
    }
}

static float half_area(const float lo[3], const float hi[3])
{
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    if (dx < 0)
        return 0.0f;
    return dx * dy + dy * dz + dz * dx;
}

/* Bin of a centroid coordinate; NaN (hostile positions) goes to bin 0, never through an int cast. */
static inline int bin_of(float x, float lo, float scale)
{
    float f = (x - lo) * scale;
    return f >= 1.0f ? (f < (float)SAH_BINS ? (int)f : SAH_BINS - 1) : 0;
}

/* Best binned-SAH split of items [begin, end); returns the split position, or -1 when no split
 * separates the centroids. */
static int32_t sah_split(tpki_bvh_item *items, int32_t begin, int32_t end)
{
    float clo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, chi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (int32_t i = begin; i < end; i++)
        grow(clo, chi, items[i].centroid, items[i].centroid);
    int best_axis = -1, best_bin = 0;
    float best_cost = FLT_MAX;
    for (int axis = 0; axis < 3; axis++) {
        float extent = chi[axis] - clo[axis];
        if (!(extent > 0))
            continue;
        float scale = SAH_BINS / extent;
        int count[SAH_BINS] = {0};
        float blo[SAH_BINS][3], bhi[SAH_BINS][3];
        for (int b = 0; b < SAH_BINS; b++)
            for (int k = 0; k < 3; k++) {
                blo[b][k] = FLT_MAX;
                bhi[b][k] = -FLT_MAX;
            }
        for (int32_t i = begin; i < end; i++) {
            int b = bin_of(items[i].centroid[axis], clo[axis], scale);
            count[b]++;
            grow(blo[b], bhi[b], items[i].lo, items[i].hi);
        }
        /* Sweep from the right to get the right-hand costs, then from the left. */
        float right_cost[SAH_BINS];
        float rlo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, rhi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
        int rcount = 0;
        for (int b = SAH_BINS - 1; b > 0; b--) {
            grow(rlo, rhi, blo[b], bhi[b]);
            rcount += count[b];
            right_cost[b] = rcount ? half_area(rlo, rhi) * (float)rcount : 0.0f;
        }
        float llo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, lhi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
        int lcount = 0;
        for (int b = 0; b < SAH_BINS - 1; b++) {
            grow(llo, lhi, blo[b], bhi[b]);
            lcount += count[b];
            if (lcount == 0 || lcount == end - begin)
                continue;
            float cost = half_area(llo, lhi) * (float)lcount + right_cost[b + 1];
            if (cost < best_cost) {
                best_cost = cost;
                best_axis = axis;
                best_bin = b;
            }
        }
    }
    if (best_axis < 0)
        return -1;
    float extent = chi[best_axis] - clo[best_axis];
    float scale = SAH_BINS / extent;
    int32_t i = begin, j = end - 1;
    while (i <= j) {
        int b = bin_of(items[i].centroid[best_axis], clo[best_axis], scale);
        if (b <= best_bin) {
            i++;
        } else {
            tpki_bvh_item swap = items[i];
            items[i] = items[j];
            items[j] = swap;
            j--;
        }
    }
    return (i > begin && i < end) ? i : -1;
}

tpk_result tpki_bvh_build(tpki_bvh_item *items, int32_t n, int leaf_size, tpk_bvh_node *nodes, int32_t *node_count_out)
{
    *node_count_out = 0;
    if (n <= 0)
        return TPK_OK;
    build_task *tasks = malloc(((size_t)TPK_BVH_STACK + 64) * sizeof *tasks);
    if (!tasks)
        return TPK_ERR_OUT_OF_MEMORY;
    /* Depth-first with an explicit stack: the second child waits on the stack while the first is
     * built, so the stack holds at most one entry per level. */
    int32_t task_count = 0, node_count = 1;
    tasks[task_count++] = (build_task){0, 0, n, 0};
    while (task_count > 0) {
        build_task t = tasks[--task_count];
        tpk_bvh_node *node = &nodes[t.node];
        for (int k = 0; k < 3; k++) {
            node->lo[k] = FLT_MAX;
            node->hi[k] = -FLT_MAX;
        }
        for (int32_t i = t.begin; i < t.end; i++)
            grow(node->lo, node->hi, items[i].lo, items[i].hi);
        int32_t count = t.end - t.begin;
        if (count <= leaf_size) {
            node->first = t.begin;
            node->count = count;
            continue;
        }
        int32_t mid = t.depth < TPK_BVH_SAH_DEPTH ? sah_split(items, t.begin, t.end) : -1;
        if (mid < 0)
            mid = t.begin + count / 2; /* coincident centroids, or too deep: balanced by count */
        node->first = node_count;
        node->count = 0;
        tasks[task_count++] = (build_task){node_count + 1, mid, t.end, t.depth + 1};
        tasks[task_count++] = (build_task){node_count, t.begin, mid, t.depth + 1};
        node_count += 2;
    }
    free(tasks);
    *node_count_out = node_count;
    return TPK_OK;
}
