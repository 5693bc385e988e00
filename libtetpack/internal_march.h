/* libtetpack private declarations of the reference CPU marcher: the shell-face BVH and the marcher
 * handle, on top of the ray frame and edge test of internal_ray.h. Not installed.
 * Owners, top to bottom (a file calls only files below it):
 *   range_bvh.c  tpk_range_bvh_*, tpk_march_ray_values (public, tetpack.h): iso rays by range culling,
 *                each tet's piece as march.c computes it (on the marcher's mesh; tpk_recover_tets)
 *   march_set.c  tpk_set_marcher_* (public, tetpack.h): rays across the parts of a set, on tpki_march_run
 *   march.c      tpk_marcher_create, tpk_marcher_destroy, tpk_march_ray (public, tetpack.h), tpki_march_run
 *   shell_bvh.c  tpki_shell_bvh_build, tpki_shell_entries, tpki_shell_face_entry
 *   bvh_build.c  tpki_bvh_build: the binned-SAH builder of both BVHs
 *   ray.c        see internal_ray.h */
#ifndef TPK_INTERNAL_MARCH_H
#define TPK_INTERNAL_MARCH_H

#include <pthread.h>
#include <stdint.h>

#include "internal_ray.h"
#include "tetpack.h"

/* BVH node over shell faces: the public tpk_shell_bvh_node (tetpack.h), which says what it holds. */
typedef tpk_shell_bvh_node tpk_bvh_node;

/* A traversal stack this deep always suffices: the builder forces balanced splits past
 * TPK_BVH_SAH_DEPTH levels, so no leaf is deeper than TPK_BVH_SAH_DEPTH + 32. */
#define TPK_BVH_SAH_DEPTH 48
#define TPK_BVH_STACK TPK_SHELL_BVH_STACK
#define TPK_BVH_LEAF_SIZE 4

struct tpk_marcher {
    tpk_mesh_arrays mesh;        /* a copy of the caller's struct; the arrays stay the caller's */
    tpk_bvh_node *nodes;         /* the shell BVH: built on its first use (tpki_shell_ready), since rays */
    int64_t node_count;          /* that never enter from the shell (range-culled iso rays) need none */
    tpk_shell_face *faces;       /* shell faces in BVH leaf order */
    int64_t face_count;
    double extent;               /* largest extent or coordinate magnitude of the positions */
    pthread_mutex_t shell_lock;  /* held while the BVH is built */
    int shell_built;             /* atomic: 1 once the build finished, with shell_result */
    tpk_result shell_result;
};

/* Test shell face (a,b,c) (outward winding) against the line: returns 1 if the line enters the volume
 * through it (then *hit is filled with v = (a,b,c) and t), 0 otherwise. */
int tpki_shell_face_entry(const float *positions, const tpk_ray_frame *frame, const tpk_shell_face *face,
                         tpk_face_hit *hit);

/* An item of tpki_bvh_build: its box (rounded outward, padded as the caller's queries need), the
 * centroid the splits sort by, and the caller's id. */
typedef struct tpki_bvh_item {
    float lo[3], hi[3];
    float centroid[3];
    int32_t id;
} tpki_bvh_item;

/* Binned-SAH BVH over items[0 .. n) into nodes (room for 2n), root first; an inner node has count 0
 * and children first, first + 1; a leaf holds items [first, first + count), at most leaf_size (>= 1),
 * and items come back permuted into leaf order. No leaf is deeper than TPK_BVH_SAH_DEPTH + 32.
 * *node_count gets the nodes used. TPK_ERR_OUT_OF_MEMORY, or TPK_OK. */
tpk_result tpki_bvh_build(tpki_bvh_item *items, int32_t n, int leaf_size, tpk_bvh_node *nodes, int32_t *node_count);

/* The extent and face count of a new marcher (its shell records validated), the BVH not yet built. */
void tpki_shell_prepare(tpk_marcher *marcher);

/* The BVH over mesh->shell into marcher->nodes/faces, built by the first caller (others wait for it);
 * its result (TPK_OUT_OF_MEMORY when the build failed) to every caller. */
tpk_result tpki_shell_ready(const tpk_marcher *marcher);

/* An entry crossing found by the BVH: its t and its index in marcher->faces. */
typedef struct tpk_entry {
    double t;
    int64_t face;
} tpk_entry;

/* Collect the entry crossings of the line org + t dir with t <= tmax that can matter for [tmin, tmax]:
 * every entry at or after the last entry before tmin. Returns the count (entries sorted by t, then
 * face index) in *out, which is `stack_buf` (capacity stack_cap) or a malloc'ed array the caller frees
 * when it differs from stack_buf. Returns TPK_ERR_OUT_OF_MEMORY on allocation failure. */
tpk_result tpki_shell_entries(const tpk_marcher *marcher, const tpk_ray_frame *frame, const double dir[3],
                             double tmin, double tmax, tpk_entry *stack_buf, int64_t stack_cap,
                             tpk_entry **out, int64_t *out_count);

/* One inside-run of a ray through one marcher's mesh. */
typedef struct march_params {
    const tpk_marcher *m;
    const tpk_ray_frame *frame;
    double tmin, tmax;
    tpk_segment_fn fn;
    void *user;
    uint64_t steps;
    int stop;      /* set when the callback asked to stop or tmax was reached */
    double exit_t; /* t of the face the run left through (when it reached a neighbor -1) */
    int32_t exit_tet;       /* the tet it left from, and the face (ids and projections), there */
    tpk_face_hit exit_face;
} march_params;

/* March from the face `in` (ids, projections, edge values, t) into `tet` until the ray leaves through a
 * face with neighbor -1 (exit_* set), the callback stops it or tmax is reached (stop set). Returns
 * TPK_ERR_MESH on inconsistent connectivity. */
tpk_result tpki_march_run(march_params *p, const tpk_face_hit *in, int32_t tet);

#endif
