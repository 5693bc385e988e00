/* libtetpack private declarations for whole meshes built from the layouts. Not installed.
 * Owners, top to bottom (a file calls only files below it):
 *   set_mesh.c  tpk_set_mesh_* (public, tetpack.h): the parts of a set as the arrays of one mesh
 *   recover.c   tpk_recover_tets, tpk_recover_tets_threads (public), tpki_recover_tets_neighbors */
#ifndef TPK_INTERNAL_MESH_H
#define TPK_INTERNAL_MESH_H

#include <stdint.h>

#include "tetpack.h"

/* tpk_recover_tets, and each tet's neighbors by rank (nbr: 4 per tet, n[r] across the face opposite the
 * vertex of rank r, as Tet20 stores them), checked in [-1, tet_count), from any layout. */
tpk_result tpki_recover_tets_neighbors(const tpk_mesh_arrays *mesh, int32_t *dst, int32_t *nbr);

#endif
