/* The CPU volume renderer (emission-absorption over the reference marcher, all cores) and PNG output.
 * The image origin is the top-left pixel; pixels are RGBA 8-bit, straight (not premultiplied) alpha. */
#ifndef TPK_RENDER_H
#define TPK_RENDER_H

#include <stdint.h>

#include "base/diag.h"
#include "tetpack.h"
#include "transfer_function.h"

typedef struct tpk_camera {
    double eye[3], at[3], up[3]; /* world coordinates */
    double fovy_deg;             /* vertical field of view */
} tpk_camera;

/* A camera that frames the box from a 3/4 view: eye along (1, 0.6, 0.8) from the box center, far
 * enough that the bounding sphere fits the view with a margin, up = +z, fovy 35. */
void tpk_camera_default(const double bounds_min[3], const double bounds_max[3], tpk_camera *out);

/* Render options. tpk_render_options_default fills friendly defaults; a zero-initialised struct
 * (plus width, height, camera and tf) also works: then the background is transparent black. */
typedef struct tpk_render_options {
    int width, height;             /* pixels, 1 .. 32768 each */
    tpk_camera camera;
    const tpk_transfer_function *tf;
    double range_min, range_max;   /* scalar range mapped to TF s in [0,1]; equal: every scalar -> 0.5 */
    double unit_distance;          /* TF alpha is opacity per this distance; <= 0: bbox diagonal / 100 */
    int threads;                   /* <= 0: all cores */
    int integration;               /* 0: exact per segment (default), 1: sampling with steps of
                                      unit_distance / 2 at most (and at least 1 sample per segment) */
    float background[4];           /* RGBA, straight alpha, composited behind the volume */
    /* ---- Effects (zero: off). Both backends (CPU reference, Vulkan) implement each one with the
     * same definition, so their pictures agree; the definitions live in render.h's comments and in
     * docs/ARCHITECTURE.md "Render effects". */
    const float *tet_scalars;      /* per tet (a tet field): constant in each tet, replaces the
                                      point scalars of the mesh for colour, opacity and iso */
    int iso_count;                 /* 0..TPK_RENDER_MAX_ISO exact isosurfaces of the linear scalar */
    double iso[4];                 /* iso values (in scalar units, not TF units) */
    double iso_opacity;            /* opacity of an isosurface hit; <= 0: 1 (opaque) */
    int clip;                      /* nonzero: only the volume inside [clip_min, clip_max] shows */
    double clip_min[3], clip_max[3];
    int shading;                   /* gradient (Lambert, two-sided) shading of volume and isosurfaces */
    int shadows;                   /* transmittance toward the point light, marched through the volume */
    int have_light;                /* zero: a headlight at the camera eye */
    double light[3];               /* point light position, world coordinates */
    int ao_rays;                   /* ambient occlusion with this many hemisphere rays; 0: off */
    double ao_radius;              /* AO ray length; <= 0: bounds diagonal / 10 */
} tpk_render_options;

#define TPK_RENDER_MAX_ISO 4

/* width 800, height 600, integration 0, threads all, background opaque dark gray (0.1, 0.1, 0.1, 1);
 * the camera, tf and range are left zero for the caller. */
void tpk_render_options_default(tpk_render_options *opt);

typedef struct tpk_render_stats {
    uint64_t rays;      /* primary rays (one per pixel) */
    uint64_t tet_steps; /* tets the marcher stepped through, all rays */
    double seconds;     /* wall time of the render (marcher creation included) */
} tpk_render_stats;

/* Render `mesh` into rgba (width * height * 4 bytes, caller-owned). Emission-absorption front to back
 * in world units (ray parameter = distance from the eye); the scalar is linear along each tet piece and
 * the TF piecewise linear, so `integration` 0 integrates each piece between the TF's control points
 * with an optical-depth-limited quadrature (converges to the exact integral); rays stop at 98% opacity.
 * With mesh->scalars NULL the volume has constant density: every point takes the TF at s = 0.5.
 * Deterministic: the image does not depend on the thread count. Returns 0, or -1 with a message
 * (invalid options, out of memory, TPK_ERR_MESH from the marcher with the pixel it happened at). */
int tpk_render_cpu(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                   tpk_render_stats *stats, tpk_diag *diag);

/* The same over a part set (spec §15) through its link-following marcher: the picture of the one file
 * the parts were cut from. has_scalars: the parts' arrays carry a point field; diagonal: of the box of
 * all parts' positions (tpk_positions_diagonal), for the default unit distance. */
int tpk_render_cpu_set(const tpk_set_marcher *marcher, int has_scalars, double diagonal,
                       const tpk_render_options *opt, uint8_t *rgba, tpk_render_stats *stats, tpk_diag *diag);
/* The diagonal of the box of mesh->positions (0 for fewer than two distinct points). */
double tpk_positions_diagonal(const tpk_mesh_arrays *mesh);

/* Write an 8-bit RGBA PNG, rows top to bottom, atomically: a temporary file in the same directory,
 * renamed over `path` only when complete. Returns 0, or -1 with a message naming the path. */
int tpk_write_png(const char *path, int width, int height, const uint8_t *rgba, tpk_diag *diag);

#endif
