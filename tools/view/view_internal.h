/* Shared by the files of tools/view/ only. view.c (the loop) calls the others; none calls back:
 * view_state.c: what is shown (file arrays, field, step, layout, TF, effects) and the scene of it;
 * view_frame.c: the renderer kept across frames (Vulkan, presenting to the window or not, else the CPU
 *               reference); calls view_window.c for the window's Vulkan surface;
 * view_window.c: the GLFW window, its input as actions and drags, OpenGL presentation;
 * view_nav.c: camera navigation (declared in view.h). */
#ifndef TPK_VIEW_INTERNAL_H
#define TPK_VIEW_INTERNAL_H

#include <stdint.h>

#include "view.h"
#ifdef TPK_WITH_VULKAN
#include "render/level_set.h"
#include "render_vk/render_vk_present.h"
#endif

/* ---- view_state.c ---- */
typedef struct view_state {
    tpk_file *file;
    tpk_set_mesh *set_mesh;        /* tpk_view_options.set_mesh: the arrays come from it, layout fixed */
    tpk_partset *set;              /* tpk_view_options.set: a field's range spans every part's */
    const char *path;
    tpk_render_options opt;        /* opt.tf points at tf */
    tpk_transfer_function tf;
    int tf_preset;                 /* index in the preset list, -1: not a preset (a file or a scene's) */
    char field[64];                /* "" without a field */
    int tet_field;                 /* the field is per tet (opt.tet_scalars) */
    uint32_t step_count;           /* of the field (1 without one) */
    int step;
    tpk_layout layout;
    tpk_mesh_arrays mesh;
    tpk_cull cull;                 /* the file's culling blocks (spec §17), opt.cull = &cull when it has them */
    double bounds_min[3], bounds_max[3];
    int iso_raster;                /* tpk_view_options.iso_raster */
    /* Levels of detail (spec §16): levels.files[0] is the file itself, the others opened over it; `file`
     * is levels.files[level]. The camera, range and bounds stay the full mesh's whatever the level. */
    tpk_level_set levels;
    int level;
} view_state;

/* What a key asks for. */
typedef enum view_action {
    VIEW_NONE, VIEW_NEXT_TF, VIEW_NEXT_FIELD, VIEW_STEP_BACK, VIEW_STEP_FORWARD, VIEW_NEXT_LAYOUT, VIEW_ISO,
    VIEW_SHADING, VIEW_CLIP, VIEW_SCREENSHOT, VIEW_WRITE_SCENE, VIEW_QUIT,
    /* the first probe: its shape (none, sphere, plane, box, none ...), keep or cut, moved along the
     * camera's right, up and forward axes, grown and shrunk */
    VIEW_PROBE, VIEW_PROBE_MODE, VIEW_PROBE_LEFT, VIEW_PROBE_RIGHT, VIEW_PROBE_UP, VIEW_PROBE_DOWN, VIEW_PROBE_AWAY,
    VIEW_PROBE_NEAR, VIEW_PROBE_GROW, VIEW_PROBE_SHRINK
} view_action;

/* From the options: the field (resolved), step, layout and arrays loaded. 0, or -1 with a message. */
int view_state_init(view_state *s, const tpk_view_options *o, tpk_diag *diag);
/* Show level `level` (0: the full mesh). 1 when the arrays changed, 0 when it was shown already, -1 with
 * a message (the state is then unchanged). */
int view_state_set_level(view_state *s, int level, tpk_diag *diag);
/* Close the levels view_state_init opened. */
void view_state_close(view_state *s);
/* Apply a key's action. Returns 1 when the arrays changed (the renderer must be made again), 0 when only
 * the options did, -1 with a message when the new arrays do not load (the state is then unchanged). */
int view_state_apply(view_state *s, view_action action, tpk_diag *diag);
/* Write the scene of the current state to `path` (tpk_scene_write). 0, or -1 with a message. */
int view_state_write_scene(const view_state *s, const char *path, int vulkan, tpk_diag *diag);
/* One line for the title: file, field and step, layout, effects. */
void view_state_describe(const view_state *s, char *out, size_t n);

/* ---- view_frame.c ---- */
typedef struct tpk_vk_renderer tpk_vk_renderer;
typedef struct tpk_vk_presenter tpk_vk_presenter;
typedef struct tpk_iso_raster tpk_iso_raster;
typedef struct view_window view_window;
typedef struct view_renderer {
    tpk_vk_renderer *vk;   /* NULL: the CPU reference */
    tpk_iso_raster *raster; /* --iso-raster: the isosurfaces drawn as triangles instead (Vulkan, read back) */
    tpk_vk_presenter *present; /* Vulkan frames go to the window's swapchain; NULL: into rgba */
    view_window *window;   /* the window presented to */
    int cpu_only;          /* Vulkan was not found (or not wanted): do not try again */
    struct tpk_vertex_cache *cache; /* the CPU reference's frame cache (vertex cache, marcher, range trees) */
    char device[256];      /* the device's name and how frames are shown, or "cpu" */
} view_renderer;

/* Set up the renderer for the state's arrays: Vulkan where a device is present (and not `cpu`), else the
 * CPU reference with a note on stderr saying why. With `window` (a view_window_open'ed with `vulkan`),
 * Vulkan presents to it: a device that cannot is an error (a Vulkan renderer is then not made), the CPU
 * reference is not (r->present stays NULL). 0, or -1 with a message. */
int view_renderer_open(view_renderer *r, const view_state *s, int cpu, view_window *window, tpk_diag *diag);
/* One frame of the state at width x height (the state's options otherwise) into rgba, or, presenting,
 * shown in the window over its whole drawable (rgba unused). */
int view_renderer_frame(view_renderer *r, const view_state *s, int width, int height, uint8_t *rgba,
                        tpk_render_stats *stats, tpk_diag *diag);
/* Presenting: the last frame shown, its top-left width x height pixels (alpha 255) into rgba. */
int view_renderer_read(view_renderer *r, uint8_t *rgba, int width, int height, tpk_diag *diag);
void view_renderer_close(view_renderer *r);

/* ---- view_window.c ---- */
#define VIEW_MAX_ACTIONS 32
typedef struct view_input {
    double orbit[2], pan[2], zoom;   /* accumulated since the last take: pixels (orbit, pan), steps (zoom) */
    int dragging;                    /* a mouse button is held */
    int released;                    /* a drag ended */
    int resized;
    view_action actions[VIEW_MAX_ACTIONS];
    int action_count;
} view_input;

/* The action of a key: T F [ ] L I S C P W Q O K (letters either case), 4 6 8 2 9 3 + = -, VIEW_NONE for
 * others. */
view_action view_key_action(int key);
/* Open a window of width x height pixels: with an OpenGL context, or (`vulkan`) with none, for a Vulkan
 * surface. 0; -2 with a message when there is no display (or GLFW cannot start); -1 with a message for
 * another failure (no OpenGL context, or GLFW finds no Vulkan loader with its surface extensions). */
int view_window_open(view_window **out, int width, int height, const char *title, int vulkan, tpk_diag *diag);
#ifdef TPK_WITH_VULKAN
/* The window's Vulkan surface, for the renderer to make on its instance (a `vulkan` window). */
void view_window_surface_source(view_window *w, tpk_vk_surface_source *out);
#endif
/* Process events (waiting for one when `wait`) and take the input gathered since the last call. */
void view_window_poll(view_window *w, int wait, view_input *in);
int view_window_closing(const view_window *w);
/* The drawable size in pixels (the frame's full resolution). */
void view_window_size(const view_window *w, int *width, int *height);
/* OpenGL windows only (draw, read, swap; swap is a no-op on a Vulkan window): */
/* Draw an image (top row first) scaled up by `zoom` into the back buffer, from the top-left corner. */
void view_window_draw(view_window *w, const uint8_t *rgba, int width, int height, int zoom);
/* Read the back buffer's width x height pixels (top row first, alpha 255) after a draw. */
void view_window_read(view_window *w, uint8_t *rgba, int width, int height);
void view_window_swap(view_window *w);
void view_window_title(view_window *w, const char *title);
/* Destroy the window; keep_display leaves GLFW and its X connection open for the next window (view's
 * fallback from Vulkan to OpenGL: closing the server's only connection makes Xvfb reset, and a connection
 * opened at once can be refused while it does). */
void view_window_close(view_window *w, int keep_display);

#endif
