/* Between scenes and render options: what a scene sets on a render, and the scene of a render. */
#include <string.h>

#include "scene.h"

/* The options of the table (render/render_options.def) that are both render options and scene keys:
 * applied where the scene gives them; saved always, or where they matter (the row's `when`) and are > 0. */
static void apply_table(const tpk_scene *s, tpk_render_options *opt)
{
#define TPK_OPTION(ID, name, kind, R, A, S, ...)                                                               \
    TPK_IF(R, TPK_IF(S, if (s->given & TPK_SCENE_GIVEN(TPK_OPT_##ID)) opt->name = s->name;))
#include "render/render_options.def"
#undef TPK_OPTION
}

static void table_from(const tpk_render_options *opt, tpk_scene *out)
{
#define TPK_USE(init, when, always, ...) always, when
#define SAVED(name, ...) SAVED_(name, __VA_ARGS__)
#define SAVED_(name, always, when) ((always) || ((when) && opt->name > 0))
#define TPK_OPTION(ID, name, kind, R, A, S, rule, cli, key, use, vk) \
    TPK_IF(R, TPK_IF(S, if (SAVED(name, use)) {                                                               \
        out->given |= TPK_SCENE_GIVEN(TPK_OPT_##ID);                                                          \
        out->name = opt->name;                                                                                \
    }))
#include "render/render_options.def"
#undef TPK_OPTION
#undef TPK_USE
#undef SAVED
#undef SAVED_
}

static void apply_effects(const tpk_scene *s, tpk_render_options *opt)
{
    if (s->given & TPK_SCENE_CLIP) {
        opt->clip = 1;
        memcpy(opt->clip_min, s->clip_min, sizeof opt->clip_min);
        memcpy(opt->clip_max, s->clip_max, sizeof opt->clip_max);
    }
    if (s->given & TPK_SCENE_PROBES) {
        opt->probe_count = s->probe_count;
        memcpy(opt->probes, s->probes, sizeof opt->probes);
    }
    if (s->given & TPK_SCENE_ISO) {
        opt->iso_count = s->iso_count;
        memcpy(opt->iso, s->iso, sizeof opt->iso);
    }
    if (s->given & TPK_SCENE_LIGHT) {
        opt->have_light = 1;
        memcpy(opt->light, s->light, sizeof opt->light);
    }
}

void tpk_scene_apply(const tpk_scene *s, tpk_render_options *opt)
{
    if (s->given & TPK_SCENE_CAMERA)
        opt->camera = s->camera;
    if (s->given & TPK_SCENE_TF)
        opt->tf = &s->tf;
    if (s->given & TPK_SCENE_RANGE) {
        opt->range_min = s->range[0];
        opt->range_max = s->range[1];
    }
    if (s->given & TPK_SCENE_SIZE) {
        opt->width = s->width;
        opt->height = s->height;
    }
    apply_effects(s, opt);
    apply_table(s, opt);
}

/* A preset whose points are exactly these is written by name. */
static void set_tf(const tpk_transfer_function *tf, tpk_scene *out)
{
    tpk_transfer_function preset;
    tpk_diag quiet;
    memset(&quiet, 0, sizeof quiet);
    out->tf = *tf;
    out->tf_kind = TPK_SCENE_TF_POINTS;
    if (tpk_tf_load(tf->name, &preset, &quiet) == 0 && !strcmp(preset.name, tf->name) && preset.count == tf->count &&
        !memcmp(preset.points, tf->points, sizeof preset.points[0] * (size_t)tf->count)) {
        out->tf_kind = TPK_SCENE_TF_PRESET;
        strncpy(out->tf_source, tf->name, sizeof out->tf_source - 1);
    }
}

static void effects_from(const tpk_render_options *opt, tpk_scene *out)
{
    if (opt->clip) {
        out->given |= TPK_SCENE_CLIP;
        memcpy(out->clip_min, opt->clip_min, sizeof out->clip_min);
        memcpy(out->clip_max, opt->clip_max, sizeof out->clip_max);
    }
    if (opt->probe_count > 0) {
        out->given |= TPK_SCENE_PROBES;
        out->probe_count = opt->probe_count;
        memcpy(out->probes, opt->probes, sizeof out->probes);
    }
    if (opt->iso_count > 0) {
        out->given |= TPK_SCENE_ISO;
        out->iso_count = opt->iso_count;
        memcpy(out->iso, opt->iso, sizeof out->iso);
    }
    if (opt->have_light) {
        out->given |= TPK_SCENE_LIGHT;
        memcpy(out->light, opt->light, sizeof out->light);
    }
}

void tpk_scene_from_options(const tpk_render_options *opt, const char *field, int step, tpk_layout layout,
                            tpk_scene *out)
{
    memset(out, 0, sizeof *out);
    out->given = TPK_SCENE_CAMERA | TPK_SCENE_SIZE | TPK_SCENE_STEP | TPK_SCENE_LAYOUT | TPK_SCENE_BACKEND;
    out->camera = opt->camera;
    if (opt->tf) {
        out->given |= TPK_SCENE_TF;
        set_tf(opt->tf, out);
    }
    if (field && field[0]) {
        out->given |= TPK_SCENE_FIELD;
        strncpy(out->field, field, sizeof out->field - 1);
    }
    out->step_first = out->step_last = step;
    if (opt->range_min < opt->range_max) { /* equal: no range (a scene's range has low < high) */
        out->given |= TPK_SCENE_RANGE;
        out->range[0] = opt->range_min;
        out->range[1] = opt->range_max;
    }
    out->width = opt->width;
    out->height = opt->height;
    out->layout = layout;
    out->backend = TPK_SCENE_BACKEND_CPU; /* the only renderer this build has */
    effects_from(opt, out);
    table_from(opt, out);
}
