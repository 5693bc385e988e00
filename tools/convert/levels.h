/* Levels of detail (spec §16, convert --levels N): coarser complete meshes of the same domain, each a
 * whole .tpk that the file carries in a LEVL chunk. Owner: levels.c. */
#ifndef TPK_CONVERT_LEVELS_H
#define TPK_CONVERT_LEVELS_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "convert.h"
#include "mesh/mesh.h"
#include "write_tpk.h" /* tpk_level, tpk_levels: what the writer stores of a level */

/* Make up to `count` levels of `mesh` (in the stored frame, tets positive, `neighbors` as connect gave
 * them), each with about a sixth of the tets of the one before, by half-edge collapses that keep every
 * tet positive (exact orientation) and of fair shape; shell vertices move only within flat pieces of the
 * shell, or inward within o->level_shell_error times the bounding box diagonal of every shell vertex
 * removed. Stops early (fewer levels, out->count) when a level would keep more than 85% of the tets of
 * the one before. Each level is written as a complete file with `o`'s layouts and compression, every
 * field (point fields at the kept vertices, tet fields of the tet each level tet descends from), TIME,
 * TMAP and VMAP, and META with `source` (its source_cells and source_points: the levels' maps number the
 * same source). The mesh's tets and the neighbors are its scratch: on return they hold no mesh (the
 * file's own chunks are written before: tpk_write_begin). 0, or -1 with a message. */
int tpk_make_levels(const tpk_convert_options *o, tpk_tetmesh *mesh, int32_t *neighbors, int count,
                    const char *source_format, const tpk_convert_report *source, tpk_levels *out, tpk_diag *diag);
void tpk_levels_free(tpk_levels *levels);

#endif
