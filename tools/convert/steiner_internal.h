/* Internal to the Steiner stage (steiner.h): what steiner.c and steiner_decide.c share.
 *
 * Who defines what. steiner.c, the entry (tpk_steiner_stage), sits on top: it runs the rounds, then
 * emits each decided cell's tets and points (push_tet, emit_cell, emit_fixed). steiner_decide.c, below
 * it, decides: the geometry of one cell's faces and fans, the face table's points, each cell's cone,
 * star or fixed boundary, the rounds until no cell asks for a new face point, and the added points'
 * numbering (steiner_push_point, steiner_face_point), which both use. Nothing in steiner_decide.c calls
 * up into steiner.c. */
#ifndef TPK_STEINER_INTERNAL_H
#define TPK_STEINER_INTERNAL_H

#include <stdint.h>

#include "face_table.h"
#include "pipeline.h"
#include "steiner.h"
#include "mesh/polyhedron.h"

/* Per-cell state: a mode, and flags. */
enum { S_NONE, S_PENDING, S_STAR, S_CONE, S_BAD, S_FIXED, S_MODE = 7, S_FORCED = 8, S_MIRRORED = 16 };
enum { NEEDS_CENTRE = -2 }; /* cell_work.entry: a face this cell wants split at its centre */

typedef struct cell_work {
    tpk_polygons faces;   /* the cell's boundary, outward */
    int64_t *entry;       /* per face: its face-table entry, -1, or NEEDS_CENTRE */
    int64_t entry_cap;
    int32_t *key;         /* one face's ids, ascending */
    int64_t key_cap;
    int32_t *ring;        /* one face's ids in the order both its cells share (canonical_ring) */
    int64_t ring_cap;
    int mirrored;
    double centre[3];
    char why[320];
} cell_work;

typedef struct stage {
    const tpk_mesh *src;
    tpk_tetmesh *out;
    tpk_added_points *added;
    int64_t *tet_capacity;
    int64_t point_capacity;
    int flags;
    uint8_t *state;
    tpk_face_table table;
    cell_work w;
} stage;

/* A cell's boundary triangles in the cell's own numbering, for tools/convert/fixed_boundary.h: ids[k] is
 * local point k's vertex id, or -2 - e for the not yet numbered point of face-table entry e. */
typedef struct local_boundary {
    int32_t *triangles; /* 3 local ids each, outward */
    int64_t triangle_count;
    int32_t *ids;
    int64_t id_count;
    double *points;     /* 3 * id_count */
} local_boundary;

/* q moved onto the grid the file stores (TPK_TETRA_FILE_GRID), as every point decided on is. */
void steiner_to_file_grid(const stage *st, double q[3]);
/* Face f of the loaded cell: its corner count, where its fan starts (the smallest id, or the first end of
 * its entry's diagonal), and fan triangle i (0 .. n-3) from position m, outward. */
int64_t steiner_face_size(const cell_work *w, int64_t f);
int64_t steiner_fan_start(const stage *st, int64_t f);
void steiner_fan_triangle(const cell_work *w, int64_t f, int64_t m, int64_t i, int32_t tri[3]);
/* Does face-table entry e (or -1) give its face a point? */
int steiner_has_point(const stage *st, int64_t e);

/* A new vertex at q, the mean of `corners`, serving `cell`: its id, or -1 (out of memory or past the
 * 2^31-1 vertex limit). */
int32_t steiner_push_point(stage *st, const double q[3], const int32_t *corners, int64_t count, int64_t cell);
/* The face point of face-table entry `at`, numbered when cell c is the first to use it; -1 as above. */
int32_t steiner_face_point(stage *st, int64_t at, int64_t c);

/* Boundary (outward), centre and scratch of cell c into st->w: 0, 1 for a cell with no valid boundary,
 * -1 when out of memory. */
int steiner_load_cell(stage *st, int64_t c);
/* st->w.entry per face from the face table; returns how many faces carry a centre point. */
int64_t steiner_lookup_faces(stage *st);
/* Cell c's (loaded, looked up) boundary triangles, in its own numbering; with `number`, face points get
 * their vertex ids. 0 or -1 (out of memory). */
int steiner_local_boundary_build(stage *st, int64_t c, int number, local_boundary *b);
void steiner_local_boundary_free(local_boundary *b);

/* Decide the hard cells, then every cell on a face given a new point, until none asks for another.
 * 0 or -1 (out of memory). */
int steiner_run_rounds(stage *st, const int64_t *hard, int64_t hard_count);
/* Drop the plain tets of cells that now take a face point. */
void steiner_drop_forced_tets(stage *st);
/* The first bad cell is an error naming it and saying why (-2), unless bad cells are skipped (0). */
int steiner_report_bad(stage *st, tpk_diag *diag);

#endif
