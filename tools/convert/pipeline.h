/* The converter pipeline stages, one job each (docs/ARCHITECTURE.md §1, §4):
 * tetrahedralize -> orient (exact) -> reorder (space-filling curve) -> connect (face matching)
 * -> folds (exact, TPK-M06; unfold.c applies the policy) -> layouts (Tet32/20/16) -> shell. */
#ifndef TPK_PIPELINE_H
#define TPK_PIPELINE_H

#include <stdint.h>

#include "base/diag.h"
#include "base/parallel.h" /* TPK_MAX_THREADS */
#include "base/predicates.h" /* tpk_orient3d_exact, for the stages' users */
#include "mesh/face_buckets.h" /* tpk_face_parity */
#include "mesh/mesh.h"
#include "tetpack.h"

/* Source cells -> tets. Tetrahedra pass through; voxels, hexahedra, wedges and pyramids are split
 * conformally without new points (tools/convert/cell_split.h); a cell the split would fold (warped, non-convex,
 * degenerate), and a polyhedron, gets points added at its centre and at face centres where the exact
 * predicates find the result valid, else (with TetGen) is tetrahedralized inside its fixed boundary
 * (tools/convert/steiner.h); a cell even that cannot split is an error naming
 * it, or is left out and counted with TPK_TETRA_SKIP_BAD_CELLS. Prisms of more sides are refused by name. Point fields are kept, cell fields become
 * per-tet fields via the source map. `field_names` (count n, may be NULL = all scalar point fields)
 * selects fields. */
#define TPK_TETRA_SKIP_BAD_CELLS 0x1
/* Cell fields become point fields: each point takes the mean over the volume cells around it (points
 * in no cell get NaN); without field_names, scalar cell fields are then kept along with point fields. */
#define TPK_TETRA_CELL_TO_POINT 0x2
/* A mirrored cell (its node order is the mirror image of VTK's, so every tet of its split is inverted)
 * is an error naming it and counting them all, instead of being turned over and counted in
 * mirrored_cells. The converter sets this with --strict-orientation. */
#define TPK_TETRA_REFUSE_MIRRORED 0x4
/* Decide on the coordinates the file stores: the points are first moved onto the float32 grid relative to
 * the centre of their bounding box (out->grid_origin), and every added point is put on it as it is made, so
 * that a tet found positive (exactly) stays positive in the file. The converter sets this. */
#define TPK_TETRA_FILE_GRID 0x8
/* All-tet input taken over whole leaves tet_source NULL, the identity (as orient, unfold and reorder read a
 * NULL map), rather than a 4-byte-a-tet array filled with it: for a caller whose next stage is tpk_reorder,
 * which writes the map in the new order anyway (grid 120: 41 MB of fresh pages and a pass over them). */
#define TPK_TETRA_IDENTITY_SOURCE_NULL 0x10
int tpk_tetrahedralize(const tpk_mesh *src, const char *const *field_names, int field_name_count, int flags,
                       tpk_tetmesh *out, tpk_diag *diag);
/* The same, taking over src's points and (for all-tet input) its connectivity instead of copying them;
 * src stays valid for tpk_mesh_free but must not be used otherwise. */
int tpk_tetrahedralize_consume(tpk_mesh *src, const char *const *field_names, int field_name_count, int flags,
                               tpk_tetmesh *out, tpk_diag *diag);
/* Who watches a long split: fn(user, fraction of the source cells done) every 65536 cells, from the
 * calling thread (all-tet input is taken over whole and reports nothing). */
typedef struct tpk_tetra_progress {
    void (*fn)(void *user, double fraction);
    void *user;
} tpk_tetra_progress;
/* tpk_tetrahedralize_consume on `threads` workers (<= 0: all cores; the result does not depend on it),
 * reporting to `progress` (may be NULL). The others split on all cores. */
int tpk_tetrahedralize_watched(tpk_mesh *src, const char *const *field_names, int field_name_count, int flags,
                               int threads, const tpk_tetra_progress *progress, tpk_tetmesh *out, tpk_diag *diag);

typedef struct tpk_orient_stats {
    int64_t inverted_fixed;   /* negative tets made positive by a swap (found, with REFUSE_INVERTED) */
    int64_t degenerate;       /* zero-volume tets (found; dropped only with drop_degenerate) */
    int64_t repeated_vertex;  /* tets naming a vertex twice (counted in degenerate too) */
} tpk_orient_stats;

/* tpk_orient flags. 0 and 1 keep their old meaning (swap inverted tets; 1 = drop degenerate ones). */
#define TPK_ORIENT_DROP_DEGENERATE 0x1
#define TPK_ORIENT_REFUSE_INVERTED 0x2 /* inverted tets are an error (the converter with --strict-orientation) */

/* Exact orientation (CGAL): swap v2,v3 of inverted tets (or, with TPK_ORIENT_REFUSE_INVERTED, fail
 * naming the first one and the count); zero-volume tets are an error naming the first one (source
 * cell, source point ids, coordinates), or are removed with TPK_ORIENT_DROP_DEGENERATE.
 * threads <= 0: all cores (here and in tpk_reorder); the result does not depend on it. */
int tpk_orient(tpk_tetmesh *mesh, int flags, int threads, tpk_orient_stats *stats, tpk_diag *diag);
/* The same, and turned_over[t] (tet_count bytes, given by the caller; may be NULL) set to 1 for each tet it
 * turned over, 0 for the others, indexed as the tets are after it (degenerate ones dropped). */
int tpk_orient_marked(tpk_tetmesh *mesh, int flags, int threads, tpk_orient_stats *stats, uint8_t *turned_over,
                      tpk_diag *diag);
/* Removes the tets with drop[t] != 0 in place, with their tet_source entries and per-tet field values;
 * the order of the others is kept. Returns how many were removed. */
int64_t tpk_drop_tets(tpk_tetmesh *mesh, const uint8_t *drop);

/* Reorder vertices along a Hilbert curve, then tets by their smallest vertex (so they follow it); fields,
 * vertex_source and tet_source follow. Deterministic. A tet id out of range is an error naming the first
 * one, found as the tets are renumbered: the mesh is then left partly reordered (fit only to be freed). */
int tpk_reorder(tpk_tetmesh *mesh, int threads, tpk_diag *diag);

/* Face matching. neighbors[4*t+k] = tet across the face opposite tets[4*t+k], or -1. A face shared by
 * more than two tets is an error naming the face's vertices and the tets. threads <= 0: all cores. */
int tpk_connect(const int32_t *tets, int64_t tet_count, int64_t vertex_count, int32_t *neighbors,
                int threads, tpk_diag *diag);

/* tpk_connect in `windows` passes over ranges of vertex ids (tpk_connect takes 2 from 2^20 tets on, 1
 * below): less scratch at once, the same neighbors. */
int tpk_connect_windows(const int32_t *tets, int64_t tet_count, int64_t vertex_count, int32_t *neighbors,
                        int windows, int threads, tpk_diag *diag);

/* Layouts from positively oriented tets and their neighbors (as tpk_connect gives them). */
void tpk_build_tet32(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet32 *dst);
void tpk_build_tet20(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet20 *dst);
void tpk_build_tet16(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, tpk_tet16 *dst);

/* The CULL chunk's words (spec §17) for `convert --cull` (cull.c): blocks of TPK_CONVERT_CULL_BLOCK tets;
 * seeds in tet order, each the first tet of its block not reached from the seeds before, given in the
 * canonical rotation (smallest id first, then the smallest of the other three) with its neighbor opposite
 * its largest id; intervals: the maximal runs of consecutive ids among the block's vertices, so exactly
 * its vertices (grid 55, iso 0.99: 12% of the blocks hold it, against 16% and 22% with runs joined
 * across gaps of 8 and 32 ids, for 0.93 against 0.49 and 0.36 bytes a tet). Needs tet_count >= 1.
 * malloc'd (*word_count words; the same for any `threads`), or NULL when out of memory. */
#define TPK_CONVERT_CULL_BLOCK 256
int32_t *tpk_build_cull(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, int64_t vertex_count,
                        int threads, uint64_t *word_count);

/* Folds (TPK-M06): interior faces whose two tets lie on the same side of the face's plane (overlapping
 * cells). One exact orientation test per interior face, on `points` (the stored frame in the converter).
 * On success *slots (malloc'd, the caller frees; NULL when none) lists each folded face once, as 4*t+k
 * with t the lower of its two tets, ascending, and *count says how many. threads <= 0: all cores; the
 * result does not depend on it. */
int tpk_find_folds(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, const double *points,
                   int threads, int64_t **slots, int64_t *count, tpk_diag *diag);
/* tpk_connect and tpk_find_folds in one pass, with the same results (tets all positive, exactly): the
 * face matching compares the two tets' vertex orders of each face it pairs, and only a pair whose orders
 * agree gets the exact test (tpk_face_folded). */
int tpk_connect_folds(const int32_t *tets, int64_t tet_count, int64_t vertex_count, const double *points,
                      int32_t *neighbors, int threads, int64_t **slots, int64_t *count, tpk_diag *diag);
/* Face k of positive tet t and its neighbour u, exactly: u's fourth vertex on the plane or on t's side. */
int tpk_face_folded(const int32_t *tets, const double *points, int64_t t, int k, int64_t u);
/* Cuts the adjacency at the listed faces: both tets get neighbor -1 there, so both faces become shell
 * faces (spec §6.7 allows this only at a fold). */
void tpk_cut_folds(const int32_t *tets, int32_t *neighbors, const int64_t *slots, int64_t count);
/* Face j of neighbour u that is face k of tet t (the position in u of the vertex not on that face). */
int tpk_face_across(const int32_t *tets, int64_t t, int k, int64_t u);
/* "the face of points P, Q, R is shared by cell C (tet t, fourth point X) and cell D (...), both fourth
 * points on the same side of it", in source point ids and world coordinates, for the fold at `slot`. */
void tpk_describe_fold(const tpk_tetmesh *mesh, const int32_t *neighbors, int64_t slot, char *text, size_t cap);

/* tpk_connect_unfolded flags */
#define TPK_UNFOLD_SKIP_BAD_TETS 0x1 /* leave out tets turned over into a fold, instead of failing */
#define TPK_UNFOLD_CUT_FOLDS 0x2     /* cut the source's folds (tpk_cut_folds), instead of failing */
typedef struct tpk_unfold_stats {
    int64_t bad_tets;  /* tets turned over into a fold, left out (SKIP_BAD_TETS) */
    int64_t folds_cut; /* folded faces cut (CUT_FOLDS) */
} tpk_unfold_stats;
/* tpk_connect, then no fold left (TPK-M06): a tet with turned_over[t] (tpk_orient_marked; NULL: none) that
 * folds against a neighbour is a bad cell: an error naming it, or left out (mesh compacted, connected
 * again); the other folds are an error naming the count and the first face (its cells and points), or
 * are cut. `neighbors` holds 4 * tet_count. */
int tpk_connect_unfolded(tpk_tetmesh *mesh, const uint8_t *turned_over, int flags, int threads, int32_t *neighbors,
                         tpk_unfold_stats *stats, tpk_diag *diag);

/* Number of boundary faces (neighbor -1). */
int64_t tpk_count_shell_faces(const int32_t *neighbors, int64_t tet_count);
/* Boundary faces as outward int4 records, in tet order then face order. dst holds the count above. */
void tpk_build_shell(const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                     tpk_shell_face *dst);
/* Both on `threads` threads (tpk_thread_count's rule), the same records for any count: a malloc'ed array
 * of *count faces (the caller frees), or NULL when out of memory. */
tpk_shell_face *tpk_make_shell(const int32_t *tets, const int32_t *neighbors, int64_t tet_count, int threads,
                               int64_t *count);

/* The same records gathered beside another pass over the tets in blocks (the writer's first layout), so
 * the tets and neighbours are read once: tpk_shell_gather_range from each worker on its contiguous range
 * of a block (ranges in worker order, as tpk_parallel_for gives them), then tpk_shell_gather_block once
 * the block's workers are done, which appends their faces in worker order: the order of
 * tpk_build_shell, for any thread count. Zero-initialise the struct first; faces/count are the result
 * (malloc'ed: the caller frees faces); failed is set when out of memory (by tpk_shell_gather_block). */
typedef struct tpk_shell_gather_worker {
    tpk_shell_face *faces; /* this block's, in tet order */
    int64_t count, capacity;
    int failed;
} tpk_shell_gather_worker;
typedef struct tpk_shell_gather {
    tpk_shell_face *faces;
    int64_t count, capacity;
    tpk_shell_gather_worker worker[TPK_MAX_THREADS];
    int failed;
} tpk_shell_gather;
void tpk_shell_gather_range(tpk_shell_gather *g, const int32_t *tets, const int32_t *neighbors, int64_t first,
                            int64_t count, int worker);
void tpk_shell_gather_block(tpk_shell_gather *g);
/* Frees the workers' buffers (not faces). */
void tpk_shell_gather_done(tpk_shell_gather *g);

#endif
