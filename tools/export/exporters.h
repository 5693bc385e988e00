/* Exporters from a loaded .tpk: VTU and VTKHDF (tets + fields, for ParaView and meshio) and the shell as PLY, OBJ,
 * OFF or STL. Written atomically (temporary file, then rename). */
#ifndef TPK_EXPORTERS_H
#define TPK_EXPORTERS_H

#include <stdint.h>

#include "base/diag.h"
#include "tetpack.h"

/* All tets (vertex order positive), positions (origin added back, float64), every field (all steps
 * as NAME, or NAME_t0, NAME_t1, ... when there are several), and the tet->source cell map as cell data "source_cell" when present. */
int tpk_export_vtu(tpk_file *file, const char *path, tpk_diag *diag);

/* The same content as VTKHDF (VTK's HDF5 format; export_vtkhdf.c): Version 1.0 for one step, which every
 * vtkHDFReader (VTK 9.1 on) reads; with several steps Version 2.0 and a Steps group (VTK 9.3 on reads the
 * steps; 9.1 and 9.2 only step 0). Each field one array (float32, a column per component) with every
 * step's values one after another; source_point and source_cell as Int32. Built in memory by HDF5, then
 * written atomically. Without HDF5 (TETPACK_WITH_HDF5=OFF) it says so. */
int tpk_export_vtkhdf(tpk_file *file, const char *path, tpk_diag *diag);

/* The shell of a .tpk as a triangle mesh: only the vertices the shell uses, renumbered in ascending id
 * order, in world coordinates (origin + float32 position, as doubles); faces outward, in the file's
 * order, with each face's tet. tpk_shell_load checks every id against the counts (untrusted input). */
typedef struct tpk_shell_mesh {
    int64_t vertex_count, face_count;
    double *xyz;   /* 3 per vertex */
    int32_t *tri;  /* 3 per face, outward (counter-clockwise seen from outside) */
    int32_t *tet;  /* per face: the tet it bounds */
} tpk_shell_mesh;
int tpk_shell_load(tpk_file *file, const char *path, tpk_shell_mesh *shell, tpk_diag *diag);
void tpk_shell_free(tpk_shell_mesh *shell);

/* Shell export, the format from the extension of `path` (case-insensitive): .ply (binary PLY, ours:
 * float64 positions and a per-face 'tet' property), .obj, .off (ASCII) and .stl (binary) with OpenMesh's
 * writers, which store float32 positions (warned about when that moves vertices by more than 1e-6 of
 * the shell's diagonal). Refuses other extensions, and .obj/.off/.stl in a build without OpenMesh. */
int tpk_export_shell(tpk_file *file, const char *path, tpk_diag *diag);
/* Shell faces as a binary little-endian PLY (outward triangles, vertex positions in world space). */
int tpk_export_shell_ply(tpk_file *file, const char *path, tpk_diag *diag);

#endif
