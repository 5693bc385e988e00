/* Duplicate-vertex merging on a source mesh, before tetrahedralization (`tetpack convert
 * --merge-duplicates[=TOL]`): meshes written cell by cell (every cell with its own copies of its corner
 * points) become one connected mesh again. */
#ifndef TPK_MERGE_VERTICES_H
#define TPK_MERGE_VERTICES_H

#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"

typedef struct tpk_merge_report {
    int64_t merged_vertices; /* points folded into a kept twin (source points - kept points) */
    int64_t collapsed_cells; /* volume cells that named one point twice after the merge, removed */
    int32_t *point_source;   /* kept point -> source point id; NULL when nothing was merged */
    int32_t *cell_source;    /* kept cell -> source cell id; NULL when no cell was removed */
} tpk_merge_report;

/* The smallest relative tolerance accepted: below it the hash grid's cell indices (diagonal / cell
 * size) would no longer fit the 53 bits a double counts exactly. */
#define TPK_MERGE_MIN_TOLERANCE 1e-15

/* Merges points of `mesh` in place.
 * tolerance 0: points with exactly equal coordinates (== on each axis, so -0 equals +0; NaN equals
 * nothing). tolerance > 0: points within tolerance * (bounding-box diagonal), Euclidean, found with a
 * spatial hash. Deterministic: points are visited in id order; a point joins the lowest-id kept point
 * within reach, else it is kept. Chains are NOT followed: a point near a merged point but out of reach
 * of that point's kept twin stays, so no point ever moves by more than the tolerance.
 * Kept points keep their relative order; cells are renumbered; point fields take the kept point's value.
 * A volume cell that names one point twice afterwards has collapsed: an error naming it and the two
 * source points, unless drop_collapsed, which removes such cells (and their cell-field values).
 * On error the mesh is unchanged. report->point_source / cell_source are the caller's to free
 * (tpk_merge_report_free). Returns 0 or -1 with a message. */
int tpk_merge_vertices(tpk_mesh *mesh, double tolerance, int drop_collapsed, tpk_merge_report *report,
                       tpk_diag *diag);

void tpk_merge_report_free(tpk_merge_report *report);

#endif
