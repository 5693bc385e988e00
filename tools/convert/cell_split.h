/* Conformal split of linear volume cells into tets without new points (docs/ARCHITECTURE.md §5). */
#ifndef TPK_CELL_SPLIT_H
#define TPK_CELL_SPLIT_H

#include <stdint.h>

/* Most tets tpk_split_cell makes for a cell of this VTK type; 0 when the type is not split here. */
int tpk_split_max_tets(int type);

/* Split a voxel, hexahedron, wedge or pyramid (VTK node order, global vertex ids `nodes`, coordinates
 * `points` as 3 doubles per id) into positively oriented tets written to `out` (4 ids each). Every quad
 * face is cut along the diagonal through its smallest id, so two cells sharing a face cut it the same
 * way; a hexahedron whose six diagonals all join one alternating set of 4 corners becomes 5 tets, any
 * other cell a cone from its smallest vertex (hexahedron 6, wedge 3, pyramid 2). Orientation is decided
 * exactly: a mirrored cell (all tets negative) is turned over and *mirrored set to 1. Returns the number
 * of tets, or -1 for a cell the split would fold (a tet flat or of the opposite orientation: a warped,
 * non-convex or degenerate cell). */
int tpk_split_cell(int type, const int32_t *nodes, const double *points, int32_t *out, int *mirrored);

/* Most tets tpk_star_cell makes for a cell of this VTK type (0: not handled). */
int tpk_star_max_tets(int type);

/* For a cell tpk_split_cell refuses: tets from an added point `centre` (id centre_id, coordinates given
 * apart from `points`) to every boundary triangle, quad faces cut along the same smallest-id diagonals
 * as the neighbours use, so the mesh stays conforming. Returns the number of tets, or -1 when the
 * centre does not see every face from inside (exact orientation): the cell then needs more than one
 * point, or is degenerate. *mirrored as for tpk_split_cell. */
int tpk_star_cell(int type, const int32_t *nodes, const double *points, const double centre[3],
                  int32_t centre_id, int32_t *out, int *mirrored);

#endif
