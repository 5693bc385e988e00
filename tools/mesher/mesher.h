/* Tets from a closed surface or a point cloud, by TetGen 1.5 (optional, AGPL-3: TETPACK_WITH_TETGEN):
 * the closed-surface check, TetGen's switches, and the meshing run (mesher/tetgen_shim.h is the only
 * C++ unit). The input is a tpk_mesh of polygons (corners in order) or of points alone, as the surface
 * readers (import/surface/surface.h) produce it; the output is a tpk_mesh of positively oriented tets. */
#ifndef TPK_MESHER_H
#define TPK_MESHER_H

#include <stddef.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* A surface TetGen can fill: at least 4 faces, no face with fewer than 3 or repeated corners, every
 * edge in exactly two faces which use it in opposite directions (closed, manifold, consistently
 * oriented). Returns 0, or -1 naming the first bad edge or face with its vertex ids (0-based, in file
 * order) and coordinates. */
int tpk_surface_check_closed(const char *name, const tpk_mesh *surface, tpk_diag *diag);

/* TetGen settings; zero-initialised means the defaults. */
typedef struct tpk_tetgen_options {
    double radius_edge_ratio; /* q: largest radius-edge ratio; 0: 1.414; < 0: no quality refinement */
    double min_dihedral;      /* q's second value, smallest dihedral angle in degrees; 0: TetGen's */
    double max_volume;        /* a: largest tet volume; 0: no limit */
    const char *switches;     /* expert: TetGen switches replacing the three above (checked by
                                 tpk_tetgen_check_switches); NULL: none */
} tpk_tetgen_options;

/* Accept only switches that keep TetGen in memory and quiet: p q a Y M T O o S z Q and their numbers.
 * Returns 0, or -1 naming the refused character and why. */
int tpk_tetgen_check_switches(const char *switches, tpk_diag *diag);
/* The switches used for a surface ("p180zQ", i.e. input facets kept as they are, + quality or the
 * expert switches) into buf (cap >= 128); a point cloud always gets "zQ".
 * Returns 0, or -1 when the options are invalid (message says which). */
int tpk_tetgen_surface_switches(const tpk_tetgen_options *options, char *buf, size_t cap, tpk_diag *diag);

/* 0 when tetpack was built with TetGen; otherwise -1 with a message naming `name` that says so. */
int tpk_tetgen_available(const char *name, tpk_diag *diag);

/* The same for a surface or point cloud already read (consumed: *in is freed). `name` for messages. */
int tpk_surface_tetrahedralize(const char *name, tpk_mesh *in, const tpk_tetgen_options *options,
                               tpk_mesh *out, tpk_diag *diag);

#endif
