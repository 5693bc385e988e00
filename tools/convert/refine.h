/* convert --max-error E: the tets refined, conformingly, until inside every source cell each chosen point
 * field (every step) differs from the cell's own interpolant by at most E x its range, and the tets'
 * geometry from the cell's map by at most E x the bounds diagonal; proved per tet by the Bernstein
 * bound (mesh/bernstein.h), not sampled (docs/ARCHITECTURE.md §5). */
#ifndef TPK_REFINE_H
#define TPK_REFINE_H

#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* The source cells as imported (before the higher-order split): what each tet's tet_source names. */
typedef struct tpk_refine_cells {
    int64_t cell_count;
    uint8_t *types;
    int64_t *offsets; /* cell_count + 1 */
    int32_t *conn;    /* source point ids, VTK node order */
} tpk_refine_cells;

/* A copy of mesh's cells (types, offsets, connectivity) into out. Returns 0 or -1 (out of memory). */
int tpk_refine_cells_copy(const tpk_mesh *mesh, tpk_refine_cells *out);
void tpk_refine_cells_free(tpk_refine_cells *cells);
/* The first cell whose functions the bound does not cover (polyhedra, pyramids, other kinds), or -1. */
int64_t tpk_refine_unbounded_cell(const tpk_refine_cells *cells);

typedef struct tpk_refine_options {
    double max_error;           /* 0 < E < 1 */
    const char *const *fields;  /* point fields bounded; NULL: every point field */
    int field_count;
    int threads;                /* <= 0: all cores; the result does not depend on it */
    int64_t max_tets;           /* refuse to grow past this many tets (0: 64 x the tets given, at least 2^24) */
    int uniform_levels;         /* > 0: instead, every tet cut into 8 at its edges' midpoints (red refinement:
                                   every edge halved) this many times, and the bound over the result
                                   measured, not enforced (convert --subdivide) */
} tpk_refine_options;

typedef struct tpk_refine_report {
    int64_t tets_before, tets_after, vertices_added;
    int rounds;                 /* outer passes (bound, mark, bisect) */
    int fields_bounded;         /* point fields bounded (constant ones need none and are not counted) */
    double field_error;         /* the largest bound over the final tets, a fraction of the field's range */
    double geometry_error;      /* the same for the geometry, a fraction of the bounds diagonal */
    char worst_field[64];       /* the field of field_error */
} tpk_refine_report;

/* Refines `mesh` (tets from tpk_tetrahedralize with TPK_TETRA_FILE_GRID, tet_source and vertex_source
 * already naming the source file's cells and points, before tpk_quantize_points) in place. New points
 * lie on the file's float32 grid; every point field gets every step's value there from the cell's own
 * interpolant; cell fields and tet_source copy to the pieces; vertex_source is -1 for new points.
 * Every piece keeps its parent's exact orientation, else the conversion fails naming the cell. Fails
 * (-1, a message) on an unknown field, a cell the bound does not cover, a growth past max_tets. */
int tpk_refine_max_error(tpk_tetmesh *mesh, const tpk_refine_cells *cells, const tpk_refine_options *options,
                         tpk_refine_report *report, tpk_diag *diag);

#endif
