/* Cells the plain split cannot take (warped or non-convex hexahedra, wedges and pyramids; polyhedra),
 * tetrahedralized with added points where the exact predicates say the result is valid (docs/ARCHITECTURE.md §5). */
#ifndef TPK_STEINER_H
#define TPK_STEINER_H

#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* The points tpk_steiner_stage adds, in the order of their vertex ids (source points first): added point
 * i is vertex point_count + i, the mean of corners[corner_start[i] .. [i+1]) (a cell's corners for a cell
 * centre, a face's for a face centre), serving cells[2i], cells[2i+1] (the cell of a centre; the one or
 * two cells on a face; -1 for none). */
typedef struct tpk_added_points {
    int64_t count;
    int64_t *corner_start; /* count + 1 */
    int32_t *corners;
    int32_t *cells;
    int64_t cap, corner_cap;
} tpk_added_points;

void tpk_added_points_free(tpk_added_points *added);

/* Tetrahedralize the `hard` cells (ascending ids: cells tpk_split_cell refused, and every polyhedron),
 * appending tets (tet_source = the cell), points (vertex_source -1) and their description to `out` and
 * `added`; out->tets and out->tet_source hold *tet_capacity tets and grow. Faces are cut the same way from
 * both sides: fanned from their smallest id, or split at a face point, or (a recut quad) along the
 * diagonal a face table entry names. A face whose fan diagonal joins two corners that another face of the
 * cell also holds (an edge carrying points, as on OpenFOAM's split faces) always gets a face point, so no
 * point of the cell is left out. A face point sits at the face's mean, or at the midpoint of a diagonal
 * when the fan from the mean folds. In order of preference, per cell:
 *  - a polyhedron with no face point: a cone from its smallest vertex over its face triangles when that
 *    vertex sees every one not touching it from inside, no point added;
 *  - a star from a point at the cell's centre (its corners' mean) to its face triangles, with a point at
 *    the centre of each face of 4 or more corners that the centre does not see whole. Such a face point
 *    is shared: every cell on the face, also one whose plain split was valid, is then decided again with
 *    it, until no cell asks for another, so the mesh stays conforming;
 *  - with TetGen (tools/convert/fixed_boundary.h): a tetrahedralization inside its boundary triangles,
 *    which must not cross (when they do, its quad faces are cut otherwise, fewest changes first, each face
 *    at most once; or points go on the faces whose fan folds, then on all; cells on a changed face are
 *    decided again in the next round).
 * Every tet is checked with the exact predicate (on the file's float32 grid with TPK_TETRA_FILE_GRID); a
 * cell none of this makes valid is an error naming it (returns -2), or with TPK_TETRA_SKIP_BAD_CELLS is
 * left out and counted. Counts go to out (steiner_cells, face_steiner_points, fixed_boundary_cells,
 * polyhedra, mirrored_cells, cells_into, bad_cells_skipped). Returns 0, -1 when out of memory, -2 with a
 * message. Deterministic: points are numbered in cell order. Not thread-safe with TetGen. */
int tpk_steiner_stage(const tpk_mesh *src, const int64_t *hard, int64_t hard_count, int flags,
                      int64_t *tet_capacity, tpk_tetmesh *out, tpk_added_points *added, tpk_diag *diag);

#endif
