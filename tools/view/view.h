/* tetpack view: a window (GLFW) that renders a .tpk with the Vulkan renderer (the CPU reference where
 * there is no Vulkan device) and lets the user orbit, zoom and pan, and change the transfer function,
 * field, step, layout and effects; the frame rate (and the GPU time) is in the window title. Vulkan
 * frames go to the window's swapchain on the device; OpenGL shows the others, and Vulkan's where the
 * device cannot present. */
#ifndef TPK_VIEW_H
#define TPK_VIEW_H

#include "base/diag.h"
#include "render/render.h"
#include "tetpack.h"

/* How frames reach the window. */
typedef enum tpk_view_present {
    TPK_VIEW_PRESENT_AUTO,   /* Vulkan's swapchain where the renderer is Vulkan and can present, else OpenGL */
    TPK_VIEW_PRESENT_VULKAN, /* the swapchain or an error */
    TPK_VIEW_PRESENT_GL,     /* OpenGL glDrawPixels of each frame read back */
} tpk_view_present;

typedef struct tpk_view_options {
    tpk_file *file;               /* open, owned by the caller; must outlive tpk_view_run */
    tpk_set_mesh *set_mesh;       /* a part set (spec §15): its parts as one mesh, shown in its own layout
                                     (file is then part 0, for the field list; bounds the set's), or NULL */
    tpk_partset *set;             /* with set_mesh: the set, whose parts' ranges a field's colour range spans */
    double set_bounds_min[3], set_bounds_max[3];
    const char *path;             /* for the title and messages */
    tpk_render_options render;    /* the first frame's options (size: the window's) */
    tpk_transfer_function tf;     /* render.tf is ignored: the view points it at its own copy */
    const char *field;            /* NULL: the first point field (as tpk_load_arrays) */
    int step;
    tpk_layout layout;
    int cpu;                      /* 1: the CPU reference even where Vulkan is present */
    tpk_view_present present;
    int frames;                   /* > 0: render this many frames, then close (headless tests) */
    double orbit_deg;             /* turn the camera by this much per frame around its up axis */
    const char *screenshot;       /* write the last frame's window contents here (PNG) on exit */
    const char *save_scene;       /* where W writes the scene (and, with `frames`, the last frame's) */
    const char *keys;             /* keys pressed before the first frame, in order ("LI]"), as typed */
    int iso_raster;               /* the isosurfaces drawn as triangles (render --iso-raster; Vulkan, shown
                                     through OpenGL), each value extracted once, drawn for every camera */
    double max_ms;                /* > 0: a time budget per frame: while the view moves, the finest level of
                                     detail (spec §16) the cost model fitted on the frames drawn predicts to
                                     fit; once it rests, the full mesh */
    int max_pixel_step;           /* past the coarsest level, rays at every d-th pixel at most (budget.h);
                                     <= 1: every pixel */
} tpk_view_options;

/* Open the window and run until it is closed (or `frames` frames were shown). Returns 0; -1 with a
 * message (a file that does not load, a renderer error, a PNG or scene that cannot be written); -2 with
 * a message when no window can be opened (no display). */
int tpk_view_run(const tpk_view_options *options, tpk_diag *diag);

/* ---- Camera navigation (view_nav.c): pure functions on tpk_camera, the look-at point fixed unless
 * panned. Angles in degrees; the up vector stays as given. */
/* Turn the eye around the up axis through the look-at point by `deg` (counter-clockwise seen from up). */
void tpk_view_orbit(tpk_camera *camera, double deg);
/* Tilt the eye toward (+) or away from (-) the up axis, stopping 1 degree short of it. */
void tpk_view_tilt(tpk_camera *camera, double deg);
/* Move the eye toward the look-at point: distance times `factor` (> 0; < 1 comes closer). */
void tpk_view_zoom(tpk_camera *camera, double factor);
/* Shift eye and look-at point by (dx, dy) pixels of an image `height` pixels high, so that the point
 * under the cursor at the look-at depth follows it (dx right, dy down). */
void tpk_view_pan(tpk_camera *camera, double dx, double dy, int height);

#endif
