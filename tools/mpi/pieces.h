/* The pieces one rank of tetpack-mpi reads, merged into one source mesh (no MPI here). */
#ifndef TPK_PIECES_H
#define TPK_PIECES_H

#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"
#include "pvtu.h"

typedef struct tpk_rank_pieces {
    tpk_mesh mesh;          /* pieces [first, last) one after another: points, cells and fields */
    int32_t *cell_piece;    /* per cell: the piece (index in the .pvtu) it came from */
    int64_t *cell_volume;   /* per cell: its index among its piece's volume cells, or -1 (lower dimension) */
    int64_t points_read;    /* before any merging: the pieces' points, each boundary point once per piece */
} tpk_rank_pieces;

/* Read pieces [first, last) of `list` with the importers and append them. Every piece must carry the same
 * fields (name, association, components, steps) as the first; polyhedra are refused (their face streams
 * are not merged yet). Returns 0, or -1 with a message naming the piece. */
int tpk_read_pieces(const tpk_piece_list *list, int first, int last, tpk_rank_pieces *out, tpk_diag *diag);
void tpk_rank_pieces_free(tpk_rank_pieces *pieces);

/* VTK cell types of dimension 3 that the converter splits (tetra, voxel, hexahedron, wedge, pyramid). */
int tpk_is_volume_cell(uint8_t type);

#endif
