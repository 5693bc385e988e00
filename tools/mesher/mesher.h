/* Tets from a closed surface or a point cloud, by TetGen 1.5 (optional, AGPL-3: TETPACK_WITH_TETGEN):
 * the closed-surface check, TetGen's switches, the limits on its input (tetgen_limits.c), and the
 * meshing run in a child process (tetgen_guard.h; mesher/tetgen_shim.h is the only C++ unit). The input is a tpk_mesh of polygons (corners in order) or of points alone, as the surface
 * readers (import/surface/surface.h) produce it; the output is a tpk_mesh of positively oriented tets. */
#ifndef TPK_MESHER_H
#define TPK_MESHER_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* A surface TetGen can fill: at least 4 faces, no face with fewer than 3 or repeated corners, every
 * edge in exactly two faces which use it in opposite directions (closed, manifold, consistently
 * oriented). Returns 0, or -1 naming the first bad edge or face with its vertex ids (0-based, in file
 * order) and coordinates. */
int tpk_surface_check_closed(const char *name, const tpk_mesh *surface, tpk_diag *diag);

/* Limits of a TetGen run (tetgen_limits.c, tetgen_child.c). Coordinates: TetGen's exact predicates
 * multiply up to five coordinate differences (insphere, orient4d), so |x| <= 1e50 keeps (2e50)^5 = 3e251
 * and the expansions' error terms inside double range (measured: a cube at 1e70 makes TetGen assert, at
 * 1e61 it still works), and a point set at least 1e-50 across keeps them clear of underflow (a cube of
 * side 1e-70 asserts, 1e-100 crashes). Tets: TetGen's refinement leaves tets of about half the volume
 * bound (2.06 tets per bound on a unit cube at 1e-5), about 300 bytes and a few microseconds each in
 * TetGen and the pipeline: 10 million is a few GiB and minutes. Time: a generous guard against a run
 * that never ends; memory: the machine's RAM (RLIMIT_AS), so TetGen fails before the system swaps. */
#define TPK_TETGEN_MAX_COORDINATE 1e50
#define TPK_TETGEN_TETS_PER_VOLUME_BOUND 2.0
#define TPK_TETGEN_DEFAULT_MAX_TETS INT64_C(10000000)
#define TPK_TETGEN_DEFAULT_TIME_LIMIT 3600.0

/* TetGen settings; zero-initialised means the defaults. */
typedef struct tpk_tetgen_options {
    double radius_edge_ratio; /* q: largest radius-edge ratio; 0: 1.414; < 0: no quality refinement */
    double min_dihedral;      /* q's second value, smallest dihedral angle in degrees; 0: TetGen's */
    double max_volume;        /* a: largest tet volume; 0: no limit */
    const char *switches;     /* expert: TetGen switches replacing the three above (checked by
                                 tpk_tetgen_check_switches); NULL: none */
    int64_t max_tets;         /* refuse a volume bound estimated to make more tets; 0: the default */
    double time_limit;        /* seconds before TetGen is stopped; 0: the default; < 0: none */
    int64_t memory_limit;     /* bytes of address space for TetGen's process; 0: the machine's memory;
                                 < 0: none */
    int progress;             /* a progress line per TetGen stage on stderr */
} tpk_tetgen_options;

/* Accept only switches that keep TetGen in memory and quiet: p q a Y M T O o S z Q and their numbers.
 * Returns 0, or -1 naming the refused character and why. */
int tpk_tetgen_check_switches(const char *switches, tpk_diag *diag);
/* The switches used for a surface ("p180zQ", i.e. input facets kept as they are, + quality or the
 * expert switches) into buf (cap >= 128); a point cloud always gets "zQ".
 * Returns 0, or -1 when the options are invalid (message says which). */
int tpk_tetgen_surface_switches(const tpk_tetgen_options *options, char *buf, size_t cap, tpk_diag *diag);

/* Points TetGen can tetrahedralize: every |coordinate| <= TPK_TETGEN_MAX_COORDINATE, spanning at least
 * its inverse, and 4 of them not on one plane (decided exactly, tpk_orient3d_exact). Returns 0, or -1
 * naming the point or saying which degenerate shape (one point, a line, a plane) the points have. */
int tpk_tetgen_check_points(const char *name, const double *points, int64_t count, tpk_diag *diag);
/* The volume a closed surface encloses (faces fanned from their first corner; absolute value). */
double tpk_surface_enclosed_volume(const tpk_mesh *surface);
/* With a volume bound ('a' in the switch string): refuse when enclosed volume / bound times
 * TPK_TETGEN_TETS_PER_VOLUME_BOUND exceeds max_tets (0: the default), naming --max-tets. */
int tpk_tetgen_check_tet_estimate(const char *name, const tpk_mesh *surface, const char *switches,
                                  int64_t max_tets, tpk_diag *diag);

/* 0 when tetpack was built with TetGen; otherwise -1 with a message naming `name` that says so. */
int tpk_tetgen_available(const char *name, tpk_diag *diag);

/* The same for a surface or point cloud already read (consumed: *in is freed). `name` for messages. */
int tpk_surface_tetrahedralize(const char *name, tpk_mesh *in, const tpk_tetgen_options *options,
                               tpk_mesh *out, tpk_diag *diag);

#endif
