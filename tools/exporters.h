/* Exporters from a loaded .tpk: VTU (tets + fields, for ParaView and meshio) and the shell as PLY.
 * Written atomically (temporary file, then rename). */
#ifndef TPK_EXPORTERS_H
#define TPK_EXPORTERS_H

#include "diag.h"
#include "tetpack.h"

/* All tets (vertex order positive), positions (origin added back, float64), every field (all steps
 * as NAME, or NAME_t0, NAME_t1, ... when there are several), and the tet->source cell map as cell data "source_cell" when present. */
int tpk_export_vtu(tpk_file *file, const char *path, tpk_diag *diag);
/* Shell faces as a binary little-endian PLY (outward triangles, vertex positions in world space). */
int tpk_export_shell_ply(tpk_file *file, const char *path, tpk_diag *diag);

#endif
