/* libtetpack private declarations of the range culling of iso rays (tetpack.h: tpk_range_bvh_*,
 * tpk_march_ray_values). Not installed.
 * Owners: range_select.c builds the selected tree (tpk_range_bvh_select); range_bvh.c creates the
 * file-order tree, walks both trees and holds tpki_range_holds. */
#ifndef TPK_INTERNAL_RANGE_H
#define TPK_INTERNAL_RANGE_H

#include <math.h>
#include <stdint.h>

#include "internal_march.h"

/* Four floats or ints, one per child of a wide node: GCC's and Clang's vector extensions, which the
 * compiler maps to SSE on x86-64 and NEON on arm64 (and to scalar code elsewhere). */
typedef float tpki_v4f __attribute__((vector_size(16)));
typedef int32_t tpki_v4i __attribute__((vector_size(16)));

/* A node of the selected tree, four children wide (a binary SAH tree with every other level folded in):
 * the children's boxes, lane by lane (lo x, y, z, then hi x, y, z; an empty lane has lo +inf, hi -inf),
 * and what each child is: count 0 an inner node (child: its index), count > 0 a leaf of `count` slots
 * from `child` on, count -1 no child. */
typedef struct tpki_wide_node {
    tpki_v4f box[6];
    int32_t child[4];
    int32_t count[4];
} tpki_wide_node;

/* A tet of the selected tree, in leaf order: its vertices (positive order) and their positions, copied
 * so that a leaf's tets are read from one run of memory. */
typedef struct tpki_active_slot {
    int32_t v[4];
    tpki_v4f pos[3]; /* pos[k][c]: coordinate k of vertex v[c] */
} tpki_active_slot;

struct tpk_range_bvh {
    const tpk_marcher *marcher;
    int32_t *tets;            /* 4 per tet, positive order (tpk_recover_tets) */
    float *tet_range;         /* 2 per tet: the vertex scalars' min and max, rounded outward */
    tpk_bvh_node *nodes;      /* the file-order tree, every level, leaves first: leaf j holds tets from
                               * TPK_RANGE_BVH_LEAF j on; an inner node with one child is a copy of it */
    float *node_range;        /* 2 per node: its tets' scalar min and max */
    int64_t level_start[40];  /* first node of each level */
    int64_t level_count[40];
    int levels;
    double pad;               /* added around boxes in the slab test: 1e-6 of the extent */
    /* tpk_range_bvh_select's tree over the tets that hold one of active_values (none: wide_count 0) */
    tpki_wide_node *wide;     /* root first */
    int64_t wide_count;
    int32_t *active_tets;     /* leaf slot -> tet */
    tpki_active_slot *active_slots;
    double *active_values;
    int active_value_count;   /* 0: none selected */
};

/* The float at or below x, and at or above it: the trees' boxes and ranges are rounded outward. */
static inline float tpki_round_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

static inline float tpki_round_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

/* A value of values[0 .. count) in [lo, hi]. */
int tpki_range_holds(double lo, double hi, const double *values, int count);

#endif
