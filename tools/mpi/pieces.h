/* The pieces one rank of tetpack-mpi reads, merged into one source mesh (no MPI here). */
#ifndef TPK_PIECES_H
#define TPK_PIECES_H

#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"
#include "pvtu.h"

typedef struct tpk_rank_pieces {
    tpk_mesh mesh;          /* pieces [first, last) one after another: points, cells (polyhedra with their
                               face streams) and fields */
    int64_t *given_ids;     /* per point: its global id as the files give it (the importer's exact
                               global_point_ids, e.g. Exodus node number maps; OpenFOAM's
                               pointProcAddressing; or an exact integer point field GlobalPointIds), or NULL
                               when a piece gives none */
    int64_t *given_cell_ids; /* per cell: its global id from the files (the importer's global_cell_ids,
                                Exodus element number maps), or NULL when a piece gives none */
    int32_t *cell_piece;    /* per cell: the piece (index in the .pvtu) it came from */
    int64_t *cell_volume;   /* per cell: its index among its piece's volume cells, or -1 (lower dimension) */
    int64_t points_read;    /* before any merging: the pieces' points, each boundary point once per piece */
} tpk_rank_pieces;

/* Read pieces [first, last) of `list` with the importers and append them. Every piece must carry the same
 * fields (name, association, components, steps) as the first. Returns 0, or -1 with a message naming the
 * piece. */
int tpk_read_pieces(const tpk_piece_list *list, int first, int last, tpk_rank_pieces *out, tpk_diag *diag);
void tpk_rank_pieces_free(tpk_rank_pieces *pieces);

/* Point ids in the face streams of cells [first_cell, cell_count): each id becomes map[id] (map non-NULL)
 * or id + offset. */
void tpk_face_stream_ids(tpk_mesh *mesh, int64_t first_cell, const int32_t *map, int32_t offset);

/* VTK cell types of dimension 3 that the converter splits (tetra, voxel, hexahedron, wedge, pyramid,
 * polyhedron). */
int tpk_is_volume_cell(uint8_t type);

#endif
