/* Closed surfaces (STL, OFF, PLY) and point clouds with values (CSV, PLY) as converter input: readers,
 * and tpk_import_surface, which reads one and fills it with tets (mesher/mesher.h: TetGen).
 *
 * A surface is held in a tpk_mesh whose cells are polygons (TPK_CELL_SURF_TRIANGLE or
 * TPK_CELL_SURF_POLYGON, corners in file order); a point cloud is a tpk_mesh with points, point fields
 * and no cells. tpk_import_surface turns either into a tpk_mesh of tets (type 10) for the pipeline. */
#ifndef TPK_SURFACE_H
#define TPK_SURFACE_H

#include <stddef.h>

#include "base/diag.h"
#include "mesh/mesh.h"
#include "mesher/mesher.h"

/* VTK codes of the surface cells the readers produce (never seen by the tet pipeline). */
enum { TPK_CELL_SURF_TRIANGLE = 5, TPK_CELL_SURF_POLYGON = 7 };

typedef enum tpk_surface_kind {
    TPK_SURFACE_UNKNOWN = 0,
    TPK_SURFACE_STL,   /* ASCII or binary */
    TPK_SURFACE_OFF,   /* OFF / COFF */
    TPK_SURFACE_PLY,   /* ascii, binary_little_endian, binary_big_endian */
    TPK_SURFACE_CSV    /* point cloud: header x,y,z[,name...] then one point per line */
} tpk_surface_kind;

/* The kind from the extension (.stl, .off, .ply, .csv), or TPK_SURFACE_UNKNOWN. */
tpk_surface_kind tpk_surface_kind_from_name(const char *path);
/* The kind from the first bytes ("ply", "OFF"/"COFF", "solid", a binary STL whose size matches its
 * triangle count, a CSV header naming x, y and z), or TPK_SURFACE_UNKNOWN. */
tpk_surface_kind tpk_surface_kind_sniff(const char *data, size_t size);

/* Parse a whole file held in memory. Messages name `name` and a line (text) or byte offset (binary).
 * STL vertices with the same coordinates are merged (in order of first use); PLY vertex properties
 * other than x, y, z and CSV columns other than x, y, z become point fields (float). A PLY with no
 * faces (or none listed) is a point cloud. Returns 0, or -1 with *out empty. Safe on untrusted input:
 * counts are checked against the bytes left before anything is allocated. */
int tpk_read_surface_memory(const char *name, const char *data, size_t size, tpk_surface_kind kind,
                            tpk_mesh *out, tpk_diag *diag);
/* The same from a file; kind TPK_SURFACE_UNKNOWN: from the extension, else the first bytes. */
int tpk_read_surface(const char *path, tpk_surface_kind kind, tpk_mesh *out, tpk_diag *diag);

/* The readers, one per format (the same contract as tpk_read_surface_memory). */
int tpk_read_stl(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
int tpk_read_off(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
int tpk_read_ply(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
int tpk_read_csv_points(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* Read a surface or point cloud and tetrahedralize it: a surface after tpk_surface_check_closed and a
 * self-intersection check (TetGen -d, refused naming the faces), with the quality switches; a point
 * cloud by Delaunay tetrahedralization of its distinct points (exact duplicates merged, the first
 * one's values kept, a warning counts them). Vertex fields of a surface are kept on its vertices; the
 * Steiner points TetGen adds get NaN. Output: tets (type 10), positively oriented, point fields.
 * TetGen runs in a child process with time and memory limits (mesher/tetgen_guard.h): its crashes are
 * errors naming the file. Built without TetGen: refused with a message saying so. */
typedef enum tpk_surface_mode {
    TPK_SURFACE_AUTO = 0,  /* faces: a surface; none: a point cloud */
    TPK_SURFACE_FACES,     /* must be a surface (a file without faces is refused) */
    TPK_SURFACE_POINTS     /* a point cloud: faces are ignored */
} tpk_surface_mode;
int tpk_import_surface(const char *path, tpk_surface_kind kind, tpk_surface_mode mode,
                       const tpk_tetgen_options *options, tpk_mesh *out, tpk_diag *diag);
#endif
