/* Scene files (spec/scene-json.md): a JSON object that says what a render shows and how (camera,
 * transfer function, field and steps, range, clip box, probes, isosurfaces, effects, layout, size, backend,
 * integration). Parsed with cJSON and validated key by key; every error names the file, the line and
 * column, and the key. `render --scene` replays one, `render --save-scene` writes one, and `extract
 * --scene` keeps only what one needs. */
#ifndef TPK_SCENE_H
#define TPK_SCENE_H

#include <stdint.h>

#include "base/diag.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "option_table.h"

#define TPK_SCENE_VERSION 1

/* Which keys a scene gives (tpk_scene.given): one bit per row of the option table, TPK_SCENE_GIVEN(id). A
 * key a scene leaves out leaves the renderer's default, or the command line's value, in place. */
#define TPK_SCENE_GIVEN(id) ((uint64_t)1 << (id))
#define TPK_SCENE_CAMERA TPK_SCENE_GIVEN(TPK_OPT_CAMERA)
#define TPK_SCENE_TF TPK_SCENE_GIVEN(TPK_OPT_TF)
#define TPK_SCENE_FIELD TPK_SCENE_GIVEN(TPK_OPT_FIELD)
#define TPK_SCENE_STEP TPK_SCENE_GIVEN(TPK_OPT_STEP) /* "step" or "steps": step_first..step_last */
#define TPK_SCENE_RANGE TPK_SCENE_GIVEN(TPK_OPT_RANGE)
#define TPK_SCENE_UNIT_DISTANCE TPK_SCENE_GIVEN(TPK_OPT_UNIT_DISTANCE)
#define TPK_SCENE_CLIP TPK_SCENE_GIVEN(TPK_OPT_CLIP_BOX)
#define TPK_SCENE_PROBES TPK_SCENE_GIVEN(TPK_OPT_PROBE)
#define TPK_SCENE_ISO TPK_SCENE_GIVEN(TPK_OPT_ISO)
#define TPK_SCENE_LIGHT TPK_SCENE_GIVEN(TPK_OPT_LIGHT)
#define TPK_SCENE_LAYOUT TPK_SCENE_GIVEN(TPK_OPT_LAYOUT)
#define TPK_SCENE_SIZE TPK_SCENE_GIVEN(TPK_OPT_SIZE)
#define TPK_SCENE_BACKEND TPK_SCENE_GIVEN(TPK_OPT_BACKEND)
#define TPK_SCENE_AO_RAYS TPK_SCENE_GIVEN(TPK_OPT_AO_RAYS)
#define TPK_SCENE_AO_RADIUS TPK_SCENE_GIVEN(TPK_OPT_AO_RADIUS)

typedef enum tpk_scene_tf_kind { TPK_SCENE_TF_PRESET = 1, TPK_SCENE_TF_FILE = 2, TPK_SCENE_TF_POINTS = 3 } tpk_scene_tf_kind;
typedef enum tpk_scene_backend { TPK_SCENE_BACKEND_CPU = 1, TPK_SCENE_BACKEND_VULKAN = 2 } tpk_scene_backend;

/* A parsed scene: plain values, nothing to free. Values whose bit is not in `given` are zero. */
typedef struct tpk_scene {
    uint64_t given;                /* TPK_SCENE_GIVEN bits */
    tpk_camera camera;
    tpk_scene_tf_kind tf_kind;
    char tf_source[1024];          /* preset name, or the file path resolved against the scene's folder */
    tpk_transfer_function tf;      /* the loaded transfer function, whatever its kind */
    char field[64];
    int step_first, step_last;     /* "step": N gives N..N; "steps": [A, B] gives A..B */
    int step_range;                /* 1 when the scene says "steps" (an animation), 0 for "step" */
    double range[2];
    double clip_min[3], clip_max[3];
    int probe_count;               /* 1..TPK_RENDER_MAX_PROBES when TPK_SCENE_PROBES is given */
    tpk_probe probes[TPK_RENDER_MAX_PROBES];
    int iso_count;
    double iso[TPK_RENDER_MAX_ISO];
    double light[3];
    tpk_layout layout;
    int width, height;
    tpk_scene_backend backend;
    /* The table's options (render/render_options.def, S = 1): the unit distance, the iso opacity, the
     * effects' switches and values, occlusion and integration. */
#define TPK_OPTION TPK_OPTION_FIELD_S
#include "render/render_options.def"
#undef TPK_OPTION
} tpk_scene;

/* Read and parse the scene file at `path`. Relative "tf": {"file": ...} paths are taken from the
 * scene's folder. Returns 0, or -1 with a message "PATH:LINE:COL: key 'K': expected ..., found ..."
 * (JSON syntax errors, a value of the wrong type or out of range, an unknown or repeated key, a
 * missing key, a transfer function file that does not load). */
int tpk_scene_load(const char *path, tpk_scene *out, tpk_diag *diag);

/* Parse scene text from memory; `name` starts every message, `base_dir` (NULL: the current folder)
 * resolves relative TF file paths. */
int tpk_scene_parse(const char *name, const char *text, const char *base_dir, tpk_scene *out, tpk_diag *diag);

/* The scene as JSON text (malloc'd, the caller frees), pretty-printed, with only the keys in `given`.
 * A transfer function that came from a file is written inline ("points"), so the scene stands alone;
 * numbers are written so that they read back exactly: tpk_scene_parse of the text gives the same
 * values. NULL when out of memory. */
char *tpk_scene_to_json(const tpk_scene *scene);

/* Write the scene to `path` atomically (base/output_file.h). 0, or -1 with a message naming `path`. */
int tpk_scene_write(const char *path, const tpk_scene *scene, tpk_diag *diag);

/* Set the render options the scene gives (camera, tf, range, unit distance, integration, size, clip, probes,
 * iso, shading, shadows, light, ambient occlusion), leaving the others as they are. `opt->tf` points
 * into `scene`, which must outlive the render. Field, step, layout and backend are for the caller:
 * they pick what to load. */
void tpk_scene_apply(const tpk_scene *scene, tpk_render_options *opt);

/* The scene of a render: every option `opt` holds (camera, tf, range, integration, size, and each
 * effect that is on; unit_distance when > 0), with the field, step and layout the caller loaded.
 * `tf` is a preset when tpk_tf_load of its name gives the same points, else it is written inline. */
void tpk_scene_from_options(const tpk_render_options *opt, const char *field, int step, tpk_layout layout,
                            tpk_scene *out);

#endif
