/* The parsed options of `tetpack render` (and `tetpack view`), shared by the pieces of the command line
 * that fill them (the option table, a scene file) and turned into tpk_render_options in one place.
 * Owner: render_args.c. */
#ifndef TPK_CLI_RENDER_ARGS_H
#define TPK_CLI_RENDER_ARGS_H

#include <stdio.h>

#include "render/render.h"
#include "scene/option_table.h"
#include "scene/scene.h"
#include "tetpack.h"

typedef struct render_args {
    const char *path, *output, *tf, *field, *layout;
    int width, height;
    int step, step_last, have_steps; /* --step N (step_last = step) or --steps A:B */
    int have_camera, have_range;
    double camera[10], range[2];
    int iso_count;
    double iso[TPK_RENDER_MAX_ISO];
    int clip;
    double clip_box[6]; /* x0,y0,z0,x1,y1,z1 */
    int probe_count, probes_from_cli; /* the first --probe replaces the scene's probes, later ones add */
    tpk_probe probes[TPK_RENDER_MAX_PROBES];
    int have_light;
    double light[3];
    const char *scene_path, *save_scene; /* --scene, --save-scene */
    const char *save_tpk;                /* --save-tpk: keep the conversion of a mesh that is not a .tpk */
    int iso_auto;                        /* --iso auto: one isosurface at the field's median (render_args_iso_auto) */
    const char *backend;                 /* --backend vulkan|cpu; NULL: decided per render */
    int backend_from_scene;              /* backend is the scene's: without a device, the CPU (same picture) */
    char device[256];                    /* the Vulkan device's name, or "cpu" */
    char backend_reason[256];            /* why that backend (render/render_backend.h) */
    tpk_scene scene;                     /* what --scene gave (scene.given = 0 without one) */
    /* The table's options (render/render_options.def, A = 1), parsed by their kind and rule: the render
     * options (0: the renderer's default), --json, --legend, -v, --iso-raster, --level, --max-ms (0: no
     * budget), --max-pixel-step (default 8). */
#define TPK_OPTION TPK_OPTION_FIELD_A
#include "render/render_options.def"
#undef TPK_OPTION
} render_args;

/* Defaults: 512x512, step 0, the table's options their `init`, everything else off. */
void render_args_default(render_args *a);

/* Fill `opt` (after tpk_render_options_default) from the arguments: size, camera (the default 3/4 view of
 * the file's bounds unless given), tf, range (the field's from its descriptor unless given), integration,
 * threads and every effect. The field values themselves (point scalars or tet_scalars) are the caller's. */
void render_args_to_options(const render_args *a, tpk_file *file, const tpk_transfer_function *tf,
                            tpk_render_options *opt);

/* One option of the table (argv[*i], advancing *i past its value) or the FILE.tpk argument; `cmd` names
 * the command in messages. 0, or a message and TPK_EXIT_USAGE. */
int render_args_parse_option(const char *cmd, int argc, char **argv, int *i, render_args *a);

/* The row of the option table (scene/option_table.h) that `arg` names ("--name", "--name=value" or the
 * alias), or NULL. */
const tpk_option_row *render_args_find_option(const char *arg);

/* The options part of `tetpack render --help`, from the option table: each flag, its value and its help
 * in --help order, and after the effects the line that points at their definitions. */
void render_args_help(FILE *out);

/* The paragraph of `tetpack view --help` that lists the options view takes from render (the table's
 * rows that are not render_only), wrapped at 100 columns. */
void render_args_view_list(FILE *out);

/* --scene FILE, if given anywhere in argv: its values fill `a` first, so that the options parsed after
 * override them. 0, or a message and TPK_EXIT_USAGE. */
int render_args_merge_scene(const char *cmd, int argc, char **argv, render_args *a);

/* The transfer function: --tf, else the scene's, else viridis. 0, or a message and TPK_EXIT_USAGE. */
int render_args_load_tf(const char *cmd, const render_args *a, tpk_transfer_function *tf);

/* The range of the field rendered, from its descriptor (min and max over all steps, so frames of a step
 * range share one colour scale): the named field, or the first point field; [0, 1] without one. */
void render_args_field_range(tpk_file *file, const char *name, double range[2]);

/* The association of the field --field names (TPK_ASSOC_POINT without one) into *association, or a usage
 * error naming the fields the file has. */
int render_args_check_field(const char *cmd, const render_args *a, tpk_file *file, int *association);

/* The steps of the field rendered (the named one, or the first point field; 1 without a field), so that
 * a step range past them is refused before any frame is written; `found` names it for messages. */
uint32_t render_args_field_steps(tpk_file *file, const char *name, char found[80]);

/* The descriptor of the field rendered (the named one, or the first point field): 0, or -1 when the
 * file has none (out zeroed). */
int render_args_field_desc(tpk_file *file, const char *name, tpk_field_desc *out);

/* --iso auto: one isosurface at the median of the field's values (point values, or per tet for a tet
 * field; NaN ignored) at the first step rendered, into opt (iso_count 1) and *value. 0, or a message and
 * TPK_EXIT_USAGE (no field, no finite value). */
int render_args_iso_auto(const char *cmd, const render_args *a, tpk_file *file, tpk_render_options *opt,
                         double *value);

/* The default opacity scale: the TF's opacity is per this distance, diagonal / TPK_CLI_UNIT_DIVISOR of
 * the bounds (render.h's own default, for callers of the library, is diagonal / 100). */
#define TPK_CLI_UNIT_DIVISOR 30.0
double render_args_default_unit(const double bounds_min[3], const double bounds_max[3]);

/* The layout `name` says (tet16, tet20, tet32), or with NULL the first the file stores. */
tpk_layout render_args_layout(tpk_file *file, const char *name);

#endif
