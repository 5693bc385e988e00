/* libtetpack private declarations of the range culling of iso rays (tetpack.h: tpk_range_bvh_*,
 * tpk_march_ray_values, tpk_march_packet_values). Not installed.
 * Owners: range_select.c builds the selected tree (tpk_range_bvh_select) on range_build.c's hierarchy
 * (tpki_range_tree_build); range_bvh.c creates the file-order tree, reads a new field into it, walks
 * both trees one ray at a time and holds tpki_range_holds, tpki_range_drop_selection and tpki_tet_piece;
 * range_packet.c walks the selected tree with packets of rays. */
#ifndef TPK_INTERNAL_RANGE_H
#define TPK_INTERNAL_RANGE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "internal_march.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

/* Four floats or ints, one per child of a wide node: GCC's and Clang's vector extensions, which the
 * compiler maps to SSE on x86-64 and NEON on arm64 (and to scalar code elsewhere). */
typedef float tpki_v4f __attribute__((vector_size(16)));
typedef int32_t tpki_v4i __attribute__((vector_size(16)));

/* A queued child of the selected tree: a wide node (>= 0) or a leaf (its first slot and count, < 8),
 * negative. */
static inline int64_t tpki_leaf_ref(int32_t first, int32_t count)
{
    return -((int64_t)first * 8 + count) - 1;
}

static inline int64_t tpki_leaf_first(int64_t ref)
{
    return (-ref - 1) / 8;
}

static inline int64_t tpki_leaf_count(int64_t ref)
{
    return (-ref - 1) % 8;
}

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
    tpki_v4f *active_scalars; /* leaf slot -> the scalars of its vertices, in v's order (the packets'
                               * float scalar test reads them from one run of memory) */
    double *active_values;
    int active_value_count;   /* 0: none selected */
    double active_corner_max; /* the largest |coordinate| of the selected tree's boxes */
    int threads;              /* for the builds (tpk_range_bvh_set_threads); the trees never depend on it */
    /* tpk_range_bvh_create_cull: no file-order tree (levels 0); the blocks of the file's CULL chunk, each
     * walked (tets and tet_range filled for it) only when tpk_range_bvh_select needs it */
    int culled;
    tpk_cull cull;
    float *block_range;       /* 2 per block: the scalars' min and max over its intervals, outward */
    unsigned char *block_state; /* per block: BLOCK_WALKED (its tets known), BLOCK_RANGED (their ranges) */
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

/* The selected tree's binary hierarchy over items[0 .. n) in file order (range_build.c), in
 * tpki_bvh_build's form: nodes root first, an inner node's children at first and first + 1, leaves of
 * at most leaf_size items, items permuted into leaf order; the same for any thread count. */
tpk_result tpki_range_tree_build(tpki_bvh_item *items, int32_t n, int leaf_size, int threads, tpk_bvh_node *out,
                                 int32_t *node_count);

/* Culling blocks (range_bvh.c): does block k's range over its intervals hold a value? Block k walked
 * and its tets' ranges read for the current field (tpk_recover_block's errors). */
int tpki_range_block_holds(const tpk_range_bvh *b, uint64_t k, const double *values, int count);
tpk_result tpki_range_ready_block(tpk_range_bvh *b, uint64_t k);

/* Free the selected tree (range_bvh.c): none is selected. */
void tpki_range_drop_selection(tpk_range_bvh *b);

/* Is the selected tree the one for these values (tpk_range_bvh_select's)? */
int tpki_range_selected(const tpk_range_bvh *b, const double *values, int count);

/* a > b ? a : b and a < b ? a : b, lane by lane (a NaN in either gives b): SSE's maxps and minps do just
 * that in one instruction, which the compilers do not find in the masks of the general form. */
static inline tpki_v4f tpki_v4_max(tpki_v4f a, tpki_v4f b)
{
#if defined(__SSE__)
    return (tpki_v4f)_mm_max_ps((__m128)a, (__m128)b);
#else
    tpki_v4i m = a > b;
    return (tpki_v4f)(((tpki_v4i)a & m) | ((tpki_v4i)b & ~m));
#endif
}

static inline tpki_v4f tpki_v4_min(tpki_v4f a, tpki_v4f b)
{
#if defined(__SSE__)
    return (tpki_v4f)_mm_min_ps((__m128)a, (__m128)b);
#else
    tpki_v4i m = a < b;
    return (tpki_v4f)(((tpki_v4i)a & m) | ((tpki_v4i)b & ~m));
#endif
}

/* The lanes of a mask (each lane 0 or -1) as bits, lane i bit i: SSE's movmskps in one instruction, where
 * the compilers reduce the lanes one by one otherwise. */
static inline int tpki_v4_bits(tpki_v4i m)
{
#if defined(__SSE__)
    return _mm_movemask_ps((__m128)m);
#else
    return (m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8);
#endif
}

/* How much the float box tests of the selected tree widen each slab (in length; times |1/d| in t): the
 * padding plus the floats' rounding of (box - origin) * 1/d, at most 2^-21 (|box| + |origin|) |1/d| all
 * told. o_max: the largest |coordinate| of the ray's local origin. */
static inline double tpki_box_widen(double pad, double extent, double o_max)
{
    return pad + ldexp(extent + o_max, -20);
}

/* The piece of tet t (positive order) that the ray of `frame` crosses, as the marcher computes it; 0
 * when the ray misses the tet. slot: the tet's copy in the selected tree, or NULL (range_bvh.c). */
int tpki_tet_piece(const tpk_range_bvh *b, const tpk_ray_frame *frame, int64_t t, const tpki_active_slot *slot,
                   tpk_segment *seg);

/* The marcher's clipping of a piece to [tmin, tmax] (march.c's report); 0 when nothing is left. */
static inline int tpki_clip_piece(tpk_segment *seg, double tmin, double tmax)
{
    double t_in = seg->t_in, t_out = seg->t_out, s_in = seg->scalar_in, s_out = seg->scalar_out;
    if (t_out < tmin || t_in > tmax)
        return 0;
    double len = t_out - t_in;
    if (t_in < tmin) {
        seg->t_in = tmin;
        seg->scalar_in = s_in + (s_out - s_in) * ((tmin - t_in) / len);
    }
    if (t_out > tmax) {
        seg->t_out = tmax;
        seg->scalar_out = s_in + (s_out - s_in) * ((tmax - t_in) / len);
    }
    return 1;
}

/* A crossing by the renderers' rule (render_integrate.c's ri_point_crossings): s_in < v <= s_out or
 * s_in > v >= s_out. */
static inline int tpki_crosses(double s_in, double s_out, const double *values, int count)
{
    for (int j = 0; j < count; j++) {
        double v = values[j];
        if ((s_in < v && v <= s_out) || (s_in > v && v >= s_out))
            return 1;
    }
    return 0;
}

/* The order in which a ray's pieces are handed on: by t_in, then (pieces of one t, where the ray meets a
 * vertex or an edge) by t_out, then by tet, so that the order does not hang on the order the tree's walk
 * found them in: one ray alone and the same ray in a packet hand on the same sequence. */
static inline int tpki_piece_before(const tpk_segment *a, const tpk_segment *b)
{
    if (a->t_in != b->t_in)
        return a->t_in < b->t_in;
    if (a->t_out != b->t_out)
        return a->t_out < b->t_out;
    return a->tet < b->tet;
}

/* The walks' arrays start in a buffer on the caller's stack and move to the heap when they fill: double
 * *cap, keeping the first `count` of *items (elem bytes each); the stack buffer is never freed. 0, or
 * -1 out of memory (then *items and *cap are unchanged). */
static inline int tpki_grow(void **items, const void *stack, int64_t count, int64_t *cap, size_t elem)
{
    void *grown = malloc(elem * (size_t)(2 * *cap));
    if (!grown)
        return -1;
    memcpy(grown, *items, elem * (size_t)count);
    if (*items != stack)
        free(*items);
    *items = grown;
    *cap *= 2;
    return 0;
}

#endif
