/* The plain split of every cell of a mesh (tools/convert/cell_split.h) on all cores, for tetrahedralize.c. */
#ifndef TPK_SPLIT_PLAIN_H
#define TPK_SPLIT_PLAIN_H

#include <stdint.h>

#include "mesh/mesh.h"
#include "pipeline.h"

/* What the plain split found; merged over the workers as one pass in cell order would have found it. */
typedef struct tpk_plain_split {
    int64_t tet_count;           /* tets written */
    int64_t cells_into[7];       /* cells that gave k tets */
    int64_t mirrored_cells;      /* cells turned over (their split was all negative) */
    int64_t flat_tets;           /* tets of split cells that are flat (tpk_tet_is_flat) */
    int64_t first_mirrored_cell; /* the lowest of them (when mirrored_cells > 0) */
    int64_t *hard;               /* cells the plain split refuses, and polyhedra, ascending (malloc'ed) */
    int64_t hard_count;
} tpk_plain_split;

/* Tetra copied, voxels, hexahedra, wedges and pyramids split by tpk_split_cell (on `points`), cells of
 * lower dimension skipped, every other cell listed in res->hard. tets (4 ids each) and tet_source get
 * the tets in cell order, exactly as one pass would write them, whatever `threads` (<= 0: all cores);
 * they must hold the sum of tpk_split_max_tets (1 for a tetra) over the cells. `progress` (may be NULL)
 * hears from the calling thread. 0, or -1 when out of memory. */
int tpk_split_plain(const tpk_mesh *src, const double *points, int threads, const tpk_tetra_progress *progress,
                    int32_t *tets, int32_t *tet_source, tpk_plain_split *res);

#endif
