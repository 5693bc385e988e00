/* Importers: each reads one file format into a tpk_mesh. On error they return -1 with a message in
 * diag naming the file, the place (line or byte offset), what was expected and what was found, and
 * leave *out empty. Bounded memory on absurd counts: counts are checked against the file size. */
#ifndef TPK_IMPORTERS_H
#define TPK_IMPORTERS_H

#include <stddef.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* VTK legacy UNSTRUCTURED_GRID, ASCII or BINARY (big-endian). */
int tpk_import_vtk_legacy(const char *path, tpk_mesh *out, tpk_diag *diag);
/* Same from memory (for fuzzing); `name` is used in messages. */
int tpk_import_vtk_legacy_memory(const char *name, const char *data, size_t size, tpk_mesh *out,
                                 tpk_diag *diag);
/* TetGen .node/.ele: path may name either file or their common stem. */
int tpk_import_tetgen(const char *path, tpk_mesh *out, tpk_diag *diag);
/* Same from memory (for fuzzing); messages name `name`.node and `name`.ele. */
int tpk_import_tetgen_memory(const char *name, const char *node_data, size_t node_size, const char *ele_data,
                             size_t ele_size, tpk_mesh *out, tpk_diag *diag);

/* Medit .mesh (ASCII): Vertices, Tetrahedra, Hexahedra (surface and line elements dropped with a
 * warning); element references become the cell field "ref", non-zero vertex references "vertex_ref". */
int tpk_import_medit(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_medit_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
/* Binary Medit (.meshb, libMeshb versions 1-4, either byte order): the same content as the ASCII form;
 * unknown keywords are skipped by their offsets. */
int tpk_import_meshb(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_meshb_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* VTK XML UnstructuredGrid (.vtu): ascii, base64 binary and raw appended data, zlib-compressed or not,
 * UInt32 or UInt64 headers (expat parses the XML). Point and cell data arrays become fields. */
int tpk_import_vtu(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_vtu_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
/* ParaView series (.pvd): one .vtu per time step (paths relative to the .pvd), all with the same mesh;
 * their fields become fields with one step per file, in time order, with the time values. */
int tpk_import_pvd(const char *path, tpk_mesh *out, tpk_diag *diag);

/* Gmsh .msh 2.2 and 4.1, ASCII and binary: volume elements (tets, hexes, prisms, pyramids, and their
 * higher-order kinds reduced to corners) in VTK node order, $NodeData/$ElementData as fields. */
int tpk_import_gmsh(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_gmsh_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* NASA/AFLR3 UGRID: .ugrid (ASCII), .b8.ugrid (big-endian), .lb8.ugrid (little-endian); tetrahedra
 * (surface elements dropped; pyramids, prisms and hexahedra refused until their node order is checked).
 * The memory form takes the kind from `name`'s extension. */
int tpk_import_ugrid(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_ugrid_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* Exodus II (.exo, .e, .g, .ex2; netCDF classic or netCDF-4) through the Exodus library: tetra, hex,
 * wedge and pyramid blocks (higher-order reduced to corners), nodal and element variables with every
 * time step. */
int tpk_import_exodus(const char *path, tpk_mesh *out, tpk_diag *diag);

/* Pick the importer from the extension (and the file's first bytes); format may force one
 * ("vtk", "vtu", "pvd", "gmsh", "tetgen", "medit", "ugrid", "exodus", and for surfaces and point
 * clouds, tetrahedralized by TetGen (surface.h): "stl", "off", "ply", "csv", "surface", "points"). */
int tpk_import_any(const char *path, const char *format, tpk_mesh *out, tpk_diag *diag);
/* The same with TetGen's settings for surfaces (NULL: defaults). */
struct tpk_tetgen_options;
int tpk_import_any_with(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                        tpk_mesh *out, tpk_diag *diag);

#endif
