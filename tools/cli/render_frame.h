/* One frame of tetpack render and the scene it used: cmd_render.c owns them, render_set.c (part sets)
 * uses them too. */
#ifndef TPK_CLI_RENDER_FRAME_H
#define TPK_CLI_RENDER_FRAME_H

#include <stdint.h>

#include "render/render.h"
#include "render_args.h"
#include "tetpack.h"

/* What a frame marches: one file's arrays, or a part set's link-following marcher. */
typedef struct frame_source {
    const tpk_mesh_arrays *mesh;
    const tpk_set_marcher *set;
    int has_scalars;  /* the set's parts carry a point field */
    double diagonal;  /* of the box of all the set's positions */
    const tpk_field_desc *field; /* the field shown (its name and units for --legend) */
    double iso_auto;  /* --iso auto's value (NAN: not asked) */
    /* Levels of detail (spec §16): the level drawn (0: the full mesh), its tets, field error and shell
     * distance (from the
     * file's META; NAN when not given), and with --max-ms the budget and the prediction (seconds). */
    int level;
    int64_t level_tets;
    double error_max, error_rms, shell_distance, budget, predicted;
    int pixel_step; /* rays at every pixel_step-th pixel, the rest interpolated (budget.h; <= 1: every pixel) */
    struct render_session *session; /* what is kept from frame to frame (--steps), or NULL */
} frame_source;

/* What render keeps from one frame to the next (--steps), each made by the first frame that needs it:
 * the CPU reference's marcher, range trees and vertex cache (tpk_render_cpu_cached), or the Vulkan
 * renderer (its device and uploaded arrays; a step hands it its field: tpk_vk_renderer_set_field). Made
 * again for other arrays (another level). Start zeroed; render_session_end frees it. */
typedef struct render_session {
    tpk_vertex_cache *cache;
    struct tpk_vk_renderer *vk;
    tpk_mesh_arrays vk_mesh;    /* the arrays vk was made for, with the field it holds */
    const float *vk_tet_scalars; /* the tet field it holds */
} render_session;
void render_session_end(render_session *session);

/* The picture of `mesh` by the backend of the arguments (the CPU reference, Vulkan, --iso-raster), no
 * file written. 0, or -1 with diag's message. */
int render_image(const render_args *a, const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                 render_session *session, tpk_render_stats *stats, tpk_diag *diag);
/* A frame's seconds for the cost model (tools/render/budget.h): the GPU's time where the device gives it,
 * else the wall time of the render. */
double render_frame_seconds(const render_args *a, const tpk_render_stats *stats);

/* Render one frame of `src` with `opt` into rgba (width x height of the arguments) and write it to
 * `output` as PNG (with --legend, --json, -v as the arguments say). A TPK_EXIT_* code. */
int render_frame(const render_args *a, const frame_source *src, const tpk_render_options *opt, const char *output,
                 uint8_t *rgba);
/* render_frame, giving the frame's statistics (the cost model of --max-ms learns from them). */
int render_frame_stats(const render_args *a, const frame_source *src, const tpk_render_options *opt,
                       const char *output, uint8_t *rgba, tpk_render_stats *stats);
/* The scene of this render, every value it used, so that render --scene gives the same images
 * (--save-scene). 0, or TPK_EXIT_USAGE with a message printed. */
int render_save_scene(const render_args *a, tpk_file *file, const tpk_render_options *opt);
/* tetpack render of a part set's manifest (render_set.c). A TPK_EXIT_* code. */
int render_part_set(const render_args *a);
/* An open set's box (of its parts' headers) and the range of the field of the arguments over its open
 * parts (render_set.c; for view). */
void render_set_extent(const render_args *a, tpk_partset *set, double bounds_min[3], double bounds_max[3],
                       double range[2]);

#endif
