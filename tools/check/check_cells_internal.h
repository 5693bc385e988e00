/* Internal to the cells group (2xx): what one worker found over its range of cells, and the per-shape
 * checks that feed it. Not installed; only check_cells*.c and check_quality.c include it.
 *
 * Who defines what. check_cells.c, the entry (tpk_check_cells, check.h), sits on top and calls down:
 * check_cells_hits.c (tpk_cell_hit, tpk_cell_hits_append, tpk_cell_hits_report, tpk_cell_hits_free,
 * tpk_cell_example_vertices, tpk_cell_centre), check_cells_shape.c (tpk_check_split_cell, with the
 * exact triangle tests of base/exact_triangles.h), check_quality.c (tpk_tet_quality_of),
 * check_cells_dup.c (tpk_check_duplicate_cells). None of these calls back into check_cells.c. */
#ifndef TPK_CHECK_CELLS_INTERNAL_H
#define TPK_CHECK_CELLS_INTERNAL_H

#include <stdint.h>

#include "check.h"

#define TPK_CELLS_FIRST_ID 201
#define TPK_CELLS_ID_COUNT 15 /* 201..215 */

/* Counts and the first examples per check, for one worker's contiguous range of cells. Workers report
 * in increasing cell order, so merging them in worker order keeps the lowest ids first whatever the
 * thread count. */
typedef struct tpk_cell_hits {
    int max_examples;
    int64_t count[TPK_CELLS_ID_COUNT];
    int example_count[TPK_CELLS_ID_COUNT];
    int example_cap[TPK_CELLS_ID_COUNT];
    tpk_example *examples[TPK_CELLS_ID_COUNT];
} tpk_cell_hits;

/* Count one item of check `id` (201..213) for `cell`; returns the example to fill (kind "cell", ids[0]
 * already the cell) while fewer than max_examples are kept, else NULL (the tpk_example_* helpers accept
 * NULL). */
tpk_example *tpk_cell_hit(tpk_cell_hits *hits, int id, int64_t cell);
/* Add `from`'s counts and examples (after those already in `into`, up to max_examples); frees `from`. */
void tpk_cell_hits_append(tpk_cell_hits *into, tpk_cell_hits *from);
/* Counts and examples into the report's findings; frees `hits`. */
void tpk_cell_hits_report(tpk_cell_hits *hits, tpk_check_report *report);
void tpk_cell_hits_free(tpk_cell_hits *hits);

/* Example ids: the cell, then (up to 7 of) its vertex ids. */
void tpk_cell_example_vertices(tpk_example *ex, const tpk_mesh *mesh, int64_t cell);
/* Mean of the cell's corners (every id must be in range). */
void tpk_cell_centre(const tpk_mesh *mesh, int64_t cell, double centre[3]);

/* Geometry checks of one usable voxel, hexahedron, wedge or pyramid: 203 and 204 (by the tets of its
 * conformal split), 205 (warped quad faces), 206 (non-convex), 207 (faces that cross), 208 (the split
 * folds). check_cells_shape.c. */
void tpk_check_split_cell(const tpk_mesh *mesh, int64_t cell, double warp_deg, tpk_cell_hits *hits);


/* Quality of one tet with non-zero volume (check_quality.c). */
typedef struct tpk_tet_quality {
    double min_dihedral_deg, max_dihedral_deg;
    double radius_ratio; /* 3 r_in / r_circ: 1 for the regular tet, 0 when flat */
    double aspect_ratio; /* see check_quality.c: 1 for the regular tet, grows without bound */
} tpk_tet_quality;

void tpk_tet_quality_of(const double *a, const double *b, const double *c, const double *d,
                        tpk_tet_quality *q);

/* 211: cells with the same vertex set as a lower-numbered cell (check_cells_dup.c). Returns -1 (diag
 * set) when out of memory. */
int tpk_check_duplicate_cells(const tpk_mesh *mesh, int threads, tpk_check_report *report, tpk_diag *diag);

#endif
