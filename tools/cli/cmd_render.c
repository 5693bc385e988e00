/* tetpack render: CPU reference rendering of a .tpk to PNG (emission-absorption and the effects of
 * render.h), one image or one per time step. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "cli.h"
#include "render/render.h"
#include "scene/scene.h"
#include "tetpack.h"
#include "render/transfer_function.h"
#include "render_args.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

static const char render_help[] =
    "usage: tetpack render FILE.tpk -o IMAGE.png [options]\n"
    "\n"
    "Ray-marches the tets with the reference CPU marcher (shell BVH entry, watertight tet-to-tet\n"
    "marching) on all cores and writes a PNG. Emission-absorption: within a tet the scalar is linear,\n"
    "so each piece is split exactly where the scalar crosses a TF control point; color and extinction\n"
    "are then linear in distance and are integrated in steps of optical depth <= 0.05.\n"
    "\n"
    "  -o, --output IMAGE.png       output image (written atomically)\n"
    "  --size WxH                   image size (default 512x512)\n"
    "  --camera ex,ey,ez,ax,ay,az,ux,uy,uz,fovy\n"
    "                               eye, look-at point, up vector, vertical field of view in degrees\n"
    "                               (default: a 3/4 view framing the bounds)\n"
    "  --tf PRESET|FILE             transfer function: a preset (viridis, cool-warm, inferno,\n"
    "                               grayscale) or a text file of lines 's r g b a' (default viridis)\n"
    "  --field NAME                 field to render: a point field (linear in each tet) or a tet\n"
    "                               field (constant in each tet) (default: the first point field)\n"
    "  --step N                     time step of the field (default 0)\n"
    "  --steps A:B                  render steps A..B, one PNG each: -o must hold one %d\n"
    "                               conversion for the step, e.g. -o frame_%04d.png\n"
    "  --range LO,HI                scalar range mapped onto the TF (default: the field's range)\n"
    "  --layout tet16|tet20|tet32   which stored layout to march (default: the first present)\n"
    "  --unit-distance D            TF opacity is per distance D (default: bounds diagonal / 100)\n"
    "  --integration exact|sampled|midpoint\n"
    "                               per-piece integration as above (default), point samples at\n"
    "                               most unit-distance/2 apart, or one sample per tet piece at its\n"
    "                               midpoint\n"
    "  --iso V[,V...]               up to 4 exact isosurfaces of the field (scalar units), coloured\n"
    "                               by the TF at V\n"
    "  --iso-opacity A              opacity of an isosurface, in (0,1] (default 1)\n"
    "  --clip-box x0,y0,z0,x1,y1,z1 show only the volume inside this box (world coordinates)\n"
    "  --shading                    gradient shading (two-sided Lambert, ambient 0.3)\n"
    "  --shadows                    shadows: transmittance marched toward the light\n"
    "  --light x,y,z                point light position (default: at the eye)\n"
    "  --ao N                       ambient occlusion from N hemisphere rays (1..1024)\n"
    "  --ao-radius R                length of the AO rays (default: bounds diagonal / 10)\n"
    "Effect definitions: docs/ARCHITECTURE.md, \"Render effects\".\n"
    "  --threads N                  worker threads of the CPU backend (default: all cores)\n"
    "  --backend vulkan|cpu         vulkan: compute shaders on the first Vulkan device (a GPU, else\n"
    "                               lavapipe); cpu: the reference renderer. Same options, same picture.\n"
    "                               Default: $TETPACK_RENDER_BACKEND if set, else vulkan when a\n"
    "                               Vulkan device is present, else cpu (part sets: cpu)\n"
    "  --scene FILE                 a scene file (spec/scene-json.md): its values first, then the\n"
    "                               options given here override them\n"
    "  --save-scene FILE            write the scene of this render (every value it used) as JSON\n"
    "  --json                       print render statistics as JSON\n";

void render_args_default(render_args *a)
{
    memset(a, 0, sizeof *a);
    a->width = a->height = 512;
}

static int parse_size(const char *text, int *w, int *h)
{
    char *end;
    long x = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X'))
        return -1;
    const char *rest = end + 1;
    long y = strtol(rest, &end, 10);
    if (end == rest || *end || x < 1 || y < 1 || x > 16384 || y > 16384)
        return -1;
    *w = (int)x;
    *h = (int)y;
    return 0;
}

/* 1 to `max` comma-separated numbers. */
static int parse_list(const char *text, double *out, int max, int *count)
{
    char *end;
    for (int n = 0; n < max; n++) {
        out[n] = strtod(text, &end);
        if (end == text || !isfinite(out[n]))
            return -1;
        if (!*end) {
            *count = n + 1;
            return 0;
        }
        if (*end != ',')
            return -1;
        text = end + 1;
    }
    return -1;
}

/* ---- The option table: one parser per option; each returns 0 or -1 (then the table's `expects` is
 * printed with the value found). */

static int opt_output(const char *v, render_args *a) { a->output = v; return 0; }
static int opt_size(const char *v, render_args *a) { return parse_size(v, &a->width, &a->height); }
static int opt_tf(const char *v, render_args *a) { a->tf = v; return 0; }
static int opt_field(const char *v, render_args *a) { a->field = v; return 0; }
static int opt_json(const char *v, render_args *a) { (void)v; a->json = 1; return 0; }
static int opt_shading(const char *v, render_args *a) { (void)v; a->shading = 1; return 0; }
static int opt_shadows(const char *v, render_args *a) { (void)v; a->shadows = 1; return 0; }

static int opt_camera(const char *v, render_args *a)
{
    a->have_camera = 1;
    return tpk_cli_parse_doubles(v, a->camera, 10) || !(a->camera[9] > 0 && a->camera[9] < 180) ? -1 : 0;
}

static int opt_step(const char *v, render_args *a)
{
    a->have_steps = 0;
    if (tpk_cli_parse_int(v, 0, 1 << 30, &a->step))
        return -1;
    a->step_last = a->step;
    return 0;
}

static int opt_steps(const char *v, render_args *a)
{
    char first[32];
    const char *colon = strchr(v, ':');
    if (!colon || (size_t)(colon - v) >= sizeof first)
        return -1;
    memcpy(first, v, (size_t)(colon - v));
    first[colon - v] = 0;
    if (tpk_cli_parse_int(first, 0, 1 << 30, &a->step) || tpk_cli_parse_int(colon + 1, 0, 1 << 30, &a->step_last) ||
        a->step_last < a->step || a->step_last - a->step >= 100000)
        return -1;
    a->have_steps = 1;
    return 0;
}

static int opt_range(const char *v, render_args *a)
{
    a->have_range = 1;
    return tpk_cli_parse_doubles(v, a->range, 2) || !(a->range[0] < a->range[1]) ? -1 : 0;
}

static int opt_layout(const char *v, render_args *a)
{
    a->layout = v;
    return strcmp(v, "tet16") && strcmp(v, "tet20") && strcmp(v, "tet32") ? -1 : 0;
}

static int opt_unit(const char *v, render_args *a)
{
    return tpk_cli_parse_doubles(v, &a->unit_distance, 1) || !(a->unit_distance > 0) ? -1 : 0;
}

static int opt_integration(const char *v, render_args *a)
{
    a->integration = !strcmp(v, "exact") ? TPK_INTEGRATION_EXACT : !strcmp(v, "sampled") ? TPK_INTEGRATION_SAMPLED
                     : !strcmp(v, "midpoint") ? TPK_INTEGRATION_MIDPOINT : -1;
    return a->integration < 0 ? -1 : 0;
}

static int opt_scene(const char *v, render_args *a) { (void)v; (void)a; return 0; } /* read by render_args_merge_scene */
static int opt_save_scene(const char *v, render_args *a) { a->save_scene = v; return 0; }
static int opt_threads(const char *v, render_args *a) { return tpk_cli_parse_int(v, 1, 1024, &a->threads); }
static int opt_backend(const char *v, render_args *a)
{
    a->backend = v;
    a->backend_from_scene = 0;
    return strcmp(v, "vulkan") && strcmp(v, "cpu");
}
static int opt_iso(const char *v, render_args *a) { return parse_list(v, a->iso, TPK_RENDER_MAX_ISO, &a->iso_count); }

static int opt_iso_opacity(const char *v, render_args *a)
{
    return tpk_cli_parse_doubles(v, &a->iso_opacity, 1) || !(a->iso_opacity > 0 && a->iso_opacity <= 1) ? -1 : 0;
}

static int opt_clip(const char *v, render_args *a)
{
    a->clip = 1;
    if (tpk_cli_parse_doubles(v, a->clip_box, 6))
        return -1;
    for (int k = 0; k < 3; k++)
        if (!(a->clip_box[k] <= a->clip_box[k + 3]))
            return -1;
    return 0;
}

static int opt_light(const char *v, render_args *a)
{
    a->have_light = 1;
    return tpk_cli_parse_doubles(v, a->light, 3);
}

static int opt_ao(const char *v, render_args *a) { return tpk_cli_parse_int(v, 1, 1024, &a->ao_rays); }

static int opt_ao_radius(const char *v, render_args *a)
{
    return tpk_cli_parse_doubles(v, &a->ao_radius, 1) || !(a->ao_radius > 0) ? -1 : 0;
}

typedef struct render_option {
    const char *name, *alias; /* alias: a short form, or NULL */
    int takes_value;
    int (*parse)(const char *value, render_args *a);
    const char *expects;
} render_option;

static const render_option render_options[] = {
    {"--output", "-o", 1, opt_output, "an output PNG path"},
    {"--size", NULL, 1, opt_size, "WxH (1..16384)"},
    {"--camera", NULL, 1, opt_camera, "10 numbers ex,ey,ez,ax,ay,az,ux,uy,uz,fovy (fovy in (0,180))"},
    {"--tf", NULL, 1, opt_tf, "a preset name or a file"},
    {"--field", NULL, 1, opt_field, "a field name"},
    {"--step", NULL, 1, opt_step, "a step number >= 0"},
    {"--steps", NULL, 1, opt_steps, "A:B with 0 <= A <= B, at most 100000 steps"},
    {"--range", NULL, 1, opt_range, "LO,HI with LO < HI"},
    {"--layout", NULL, 1, opt_layout, "tet16, tet20 or tet32"},
    {"--unit-distance", NULL, 1, opt_unit, "a positive number"},
    {"--integration", NULL, 1, opt_integration, "exact, sampled or midpoint"},
    {"--threads", NULL, 1, opt_threads, "1..1024"},
    {"--backend", NULL, 1, opt_backend, "vulkan or cpu"},
    {"--json", NULL, 0, opt_json, NULL},
    {"--iso", NULL, 1, opt_iso, "1 to 4 comma-separated finite numbers"},
    {"--iso-opacity", NULL, 1, opt_iso_opacity, "a number in (0,1]"},
    {"--clip-box", NULL, 1, opt_clip, "6 numbers x0,y0,z0,x1,y1,z1 with x0 <= x1, y0 <= y1, z0 <= z1"},
    {"--shading", NULL, 0, opt_shading, NULL},
    {"--shadows", NULL, 0, opt_shadows, NULL},
    {"--light", NULL, 1, opt_light, "3 numbers x,y,z"},
    {"--ao", NULL, 1, opt_ao, "a ray count 1..1024"},
    {"--ao-radius", NULL, 1, opt_ao_radius, "a positive length"},
    {"--scene", NULL, 1, opt_scene, "a scene file"},
    {"--save-scene", NULL, 1, opt_save_scene, "an output path"},
};

/* The table entry `arg` names ("--name", "--name=value" or the alias), or NULL. */
static const render_option *find_option(const char *arg)
{
    for (size_t k = 0; k < sizeof render_options / sizeof render_options[0]; k++) {
        const render_option *o = &render_options[k];
        size_t n = strlen(o->name);
        if ((o->alias && !strcmp(arg, o->alias)) || !strcmp(arg, o->name) ||
            (o->takes_value && !strncmp(arg, o->name, n) && arg[n] == '='))
            return o;
    }
    return NULL;
}

int render_args_parse_option(const char *cmd, int argc, char **argv, int *i, render_args *a)
{
    const char *arg = argv[*i];
    const render_option *o = find_option(arg);
    if (o) {
        const char *v = o->takes_value ? tpk_cli_value(argc, argv, i, o->alias && !strcmp(arg, o->alias) ? o->alias : o->name)
                                       : NULL;
        if (o->takes_value && !v)
            return tpk_cli_fail(cmd, "%s expects %s", o->name, o->expects);
        if (o->parse(v, a))
            return tpk_cli_fail(cmd, "%s expects %s, found '%s'", o->name, o->expects, v ? v : "");
    } else if (arg[0] == '-' && arg[1]) {
        return tpk_cli_fail(cmd, "unknown option '%s' (see tetpack %s --help)", arg, cmd);
    } else if (!a->path) {
        a->path = arg;
    } else {
        return tpk_cli_fail(cmd, "expected one FILE.tpk, found a second argument '%s'", arg);
    }
    return 0;
}

tpk_layout render_args_layout(tpk_file *file, const char *name)
{
    if (name)
        return !strcmp(name, "tet16") ? TPK_LAYOUT_TET16 : !strcmp(name, "tet20") ? TPK_LAYOUT_TET20 : TPK_LAYOUT_TET32;
    uint64_t i;
    if (tpk_find_chunk(file, TPK_TAG_TT16, 0, 0, &i) == TPK_OK)
        return TPK_LAYOUT_TET16;
    if (tpk_find_chunk(file, TPK_TAG_TT20, 0, 0, &i) == TPK_OK)
        return TPK_LAYOUT_TET20;
    return TPK_LAYOUT_TET32;
}

/* The range of the field being rendered, from its descriptor (min and max over all steps, so frames
 * of a step range share one colour scale): the named field, or the first point field. */
static void field_range(tpk_file *file, const char *name, double range[2])
{
    range[0] = 0.0;
    range[1] = 1.0;
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) != TPK_OK)
            continue;
        if (name ? strcmp(name, d.name) != 0 : d.association != TPK_ASSOC_POINT)
            continue;
        if (d.min_value < d.max_value) {
            range[0] = d.min_value;
            range[1] = d.max_value;
        }
        return;
    }
}

void render_args_to_options(const render_args *a, tpk_file *file, const tpk_transfer_function *tf,
                            tpk_render_options *opt)
{
    tpk_file_info info;
    tpk_get_info(file, &info);
    opt->width = a->width;
    opt->height = a->height;
    if (a->have_camera) {
        memcpy(opt->camera.eye, a->camera, sizeof opt->camera.eye);
        memcpy(opt->camera.at, a->camera + 3, sizeof opt->camera.at);
        memcpy(opt->camera.up, a->camera + 6, sizeof opt->camera.up);
        opt->camera.fovy_deg = a->camera[9];
    } else {
        tpk_camera_default(info.bounds_min, info.bounds_max, &opt->camera);
    }
    opt->tf = tf;
    double range[2] = {a->range[0], a->range[1]};
    if (!a->have_range)
        field_range(file, a->field, range);
    opt->range_min = range[0];
    opt->range_max = range[1];
    opt->unit_distance = a->unit_distance;
    opt->threads = a->threads;
    opt->integration = a->integration;
    opt->iso_count = a->iso_count;
    memcpy(opt->iso, a->iso, sizeof opt->iso);
    opt->iso_opacity = a->iso_opacity;
    opt->clip = a->clip;
    memcpy(opt->clip_min, a->clip_box, sizeof opt->clip_min);
    memcpy(opt->clip_max, a->clip_box + 3, sizeof opt->clip_max);
    opt->shading = a->shading;
    opt->shadows = a->shadows;
    opt->have_light = a->have_light;
    memcpy(opt->light, a->light, sizeof opt->light);
    opt->ao_rays = a->ao_rays;
    opt->ao_radius = a->ao_radius;
}

/* The association of the named field (-1 when there is none), or a usage error naming the fields the
 * file has. */
static int check_field(const render_args *a, tpk_file *file, int *association)
{
    *association = TPK_ASSOC_POINT;
    if (!a->field)
        return 0;
    char names[512] = "";
    size_t used = 0;
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) != TPK_OK)
            continue;
        if (!strcmp(d.name, a->field)) {
            *association = (int)d.association;
            return 0;
        }
        if (used + strlen(d.name) + 3 < sizeof names)
            used += (size_t)snprintf(names + used, sizeof names - used, "%s%s", used ? ", " : "", d.name);
    }
    return tpk_cli_fail("render", "%s: no field named '%s' (this file has %s%s)", a->path, a->field,
                        used ? "fields: " : "no fields", names);
}

/* The steps of the field rendered (the named one, or the first point field; 1 without a field), so a
 * step range past them is refused before any frame is written. */
static uint32_t field_steps(tpk_file *file, const char *name, char found[80])
{
    snprintf(found, 80, "(no field)");
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) == TPK_OK && (name ? !strcmp(name, d.name) : d.association == TPK_ASSOC_POINT)) {
            snprintf(found, 80, "field '%s'", d.name);
            return d.step_count;
        }
    }
    return 1;
}

/* -o with --steps: exactly one %d conversion (flags 0-9 only, e.g. %04d) and no other '%' but "%%". */
static int frame_pattern_ok(const char *pattern)
{
    int conversions = 0;
    for (const char *p = pattern; *p; p++) {
        if (*p != '%')
            continue;
        if (p[1] == '%') {
            p++;
            continue;
        }
        p++;
        while (*p >= '0' && *p <= '9')
            p++;
        if (*p != 'd')
            return 0;
        conversions++;
    }
    return conversions == 1;
}

/* The field values of one step: point scalars into mesh, or a tet field into opt->tet_scalars. */
static int load_step(const render_args *a, tpk_file *file, int tet_field, int step, tpk_mesh_arrays *mesh,
                     tpk_render_options *opt)
{
    tpk_layout layout = render_args_layout(file, a->layout);
    tpk_result r = tpk_load_arrays(file, layout, tet_field ? NULL : a->field, (uint32_t)step, mesh);
    if (r == TPK_OK && tet_field) {
        mesh->scalars = NULL; /* the tet field replaces any point field */
        r = tpk_load_tet_field(file, a->field, (uint32_t)step, &opt->tet_scalars);
    }
    return r == TPK_OK ? 0 : tpk_cli_fail_file("render", a->path, tpk_error_text(file));
}

/* What a frame marches: one file's arrays, or a part set's link-following marcher. */
typedef struct frame_source {
    const tpk_mesh_arrays *mesh;
    const tpk_set_marcher *set;
    int has_scalars;  /* the set's parts carry a point field */
    double diagonal;  /* of the box of all the set's positions */
} frame_source;

static int render_frame(const render_args *a, const frame_source *src, const tpk_render_options *opt,
                        const char *output, uint8_t *rgba)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_render_stats stats;
    memset(&stats, 0, sizeof stats);
    int vulkan = 0;
#ifdef TPK_WITH_VULKAN
    vulkan = !src->set && !strcmp(a->backend, "vulkan");
#endif
    if ((src->set     ? tpk_render_cpu_set(src->set, src->has_scalars, src->diagonal, opt, rgba, &stats, &diag)
#ifdef TPK_WITH_VULKAN
         : vulkan     ? tpk_render_vulkan(src->mesh, opt, rgba, &stats, &diag)
#endif
                      : tpk_render_cpu(src->mesh, opt, rgba, &stats, &diag)) != 0)
        return tpk_cli_fail_file("render", a->path, diag.message); /* e.g. bounds that are not finite */
    if (tpk_write_png(output, a->width, a->height, rgba, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    if (a->json) {
        printf("{\"image\":\"%s\",\"backend\":\"%s\",\"device\":\"%s\",\"width\":%d,\"height\":%d,"
               "\"rays\":%llu,\"secondary_rays\":%llu,\"tet_steps\":%llu,\"seconds\":%.6f,\"device_bytes\":%llu",
               output, vulkan ? "vulkan" : "cpu", vulkan ? a->device : "cpu", a->width, a->height,
               (unsigned long long)stats.rays,
               (unsigned long long)stats.secondary_rays, (unsigned long long)stats.tet_steps, stats.seconds,
               (unsigned long long)stats.device_bytes);
        if (vulkan && stats.gpu_seconds >= 0)
            printf(",\"gpu_seconds\":%.6f", stats.gpu_seconds);
        else
            printf(",\"gpu_seconds\":null"); /* the CPU reference, or a device without timestamps */
        if (vulkan)
            printf(",\"setup\":{\"device\":%.6f,\"upload\":%.6f,\"pipeline\":%.6f,\"first_frame\":%.6f},"
                   "\"pipeline_cache\":{\"loaded_bytes\":%llu,\"hits\":%d}",
                   stats.setup_device_seconds, stats.setup_upload_seconds, stats.setup_pipeline_seconds,
                   stats.first_frame_seconds, (unsigned long long)stats.pipeline_cache_bytes, stats.pipeline_cache_hits);
        printf("}\n");
    } else
        printf("%s: %dx%d, %llu rays, %llu secondary rays, %llu tet steps, %.3f s\n", output, a->width, a->height,
               (unsigned long long)stats.rays, (unsigned long long)stats.secondary_rays,
               (unsigned long long)stats.tet_steps, stats.seconds);
    return TPK_EXIT_OK;
}

/* The output path of `step`: -o itself, or its pattern filled in with --steps. */
static int frame_path(const render_args *a, int step, char *path, size_t cap)
{
    if (!a->have_steps)
        return snprintf(path, cap, "%s", a->output) < (int)cap ? 0 : -1;
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral" /* checked by frame_pattern_ok */
    int n = snprintf(path, cap, a->output, step);
#pragma GCC diagnostic pop
    return n >= 0 && n < (int)cap ? 0 : -1;
}

/* The scene of this render, every value it used, so that render --scene gives the same images. */
static int save_scene(const render_args *a, tpk_file *file, const tpk_render_options *opt)
{
    char first[sizeof ((tpk_field_desc *)0)->name] = "";
    for (uint32_t i = 0; !a->field && !first[0] && i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) == TPK_OK && d.association == TPK_ASSOC_POINT)
            memcpy(first, d.name, sizeof first); /* the first point field: the one tpk_load_arrays took */
    }
    tpk_scene scene;
    tpk_scene_from_options(opt, a->field ? a->field : first, a->step, render_args_layout(file, a->layout), &scene);
    if (a->backend && !strcmp(a->backend, "vulkan")) /* the backend that drew it (same picture either way) */
        scene.backend = TPK_SCENE_BACKEND_VULKAN;
    scene.step_last = a->step_last;
    scene.step_range = a->have_steps;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_scene_write(a->save_scene, &scene, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    return 0;
}

/* Scene values first (--scene): they fill the arguments, and the options parsed after this override
 * them; render_args_to_options then turns both into render options in one place. */
int render_args_merge_scene(const char *cmd, int argc, char **argv, render_args *a)
{
    for (int i = 1; i < argc; i++)
        if (!strncmp(argv[i], "--scene", 7) && (!argv[i][7] || argv[i][7] == '='))
            a->scene_path = tpk_cli_value(argc, argv, &i, "--scene");
    if (!a->scene_path)
        return 0;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    const tpk_scene *s = &a->scene;
    if (tpk_scene_load(a->scene_path, &a->scene, &diag) != 0)
        return tpk_cli_fail(cmd, "%s", diag.message);
    if (s->given & TPK_SCENE_BACKEND) { /* --backend, parsed after this, still overrides it */
        a->backend = s->backend == TPK_SCENE_BACKEND_VULKAN ? "vulkan" : "cpu";
        a->backend_from_scene = 1;
    }
    if (s->given & TPK_SCENE_SIZE)
        a->width = s->width, a->height = s->height;
    if (s->given & TPK_SCENE_CAMERA) {
        const tpk_camera *c = &s->camera;
        double v[10] = {c->eye[0], c->eye[1], c->eye[2], c->at[0], c->at[1], c->at[2], c->up[0], c->up[1], c->up[2],
                        c->fovy_deg};
        memcpy(a->camera, v, sizeof v);
        a->have_camera = 1;
    }
    if (s->given & TPK_SCENE_RANGE)
        a->range[0] = s->range[0], a->range[1] = s->range[1], a->have_range = 1;
    a->field = s->given & TPK_SCENE_FIELD ? s->field : NULL;
    a->step = s->step_first;
    a->step_last = s->step_last;
    a->have_steps = s->step_range;
    a->layout = !(s->given & TPK_SCENE_LAYOUT) ? NULL : s->layout == TPK_LAYOUT_TET16 ? "tet16"
                                               : s->layout == TPK_LAYOUT_TET20 ? "tet20" : "tet32";
    a->unit_distance = s->unit_distance;
    a->integration = s->integration;
    a->clip = (s->given & TPK_SCENE_CLIP) != 0;
    memcpy(a->clip_box, s->clip_min, sizeof s->clip_min);
    memcpy(a->clip_box + 3, s->clip_max, sizeof s->clip_max);
    a->iso_count = s->iso_count;
    memcpy(a->iso, s->iso, sizeof a->iso);
    a->iso_opacity = s->iso_opacity;
    a->shading = s->shading;
    a->shadows = s->shadows;
    a->have_light = (s->given & TPK_SCENE_LIGHT) != 0;
    memcpy(a->light, s->light, sizeof a->light);
    a->ao_rays = s->ao_rays;
    a->ao_radius = s->ao_radius;
    return 0;
}

/* The transfer function: --tf, else the scene's, else viridis. */
int render_args_load_tf(const char *cmd, const render_args *a, tpk_transfer_function *tf)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (!a->tf && (a->scene.given & TPK_SCENE_TF))
        *tf = a->scene.tf;
    else if (tpk_tf_load(a->tf ? a->tf : "viridis", tf, &diag) != 0)
        return tpk_cli_fail(cmd, "%s", diag.message);
    return 0;
}

/* The backend of this render: --backend, else $TETPACK_RENDER_BACKEND, else Vulkan when a device is
 * present; a->device gets the device's name ("cpu" for the reference). Returns 0 or -1 with a message. */
static int resolve_backend(render_args *a, tpk_diag *diag)
{
    const char *env = getenv("TETPACK_RENDER_BACKEND");
    if (a->backend_from_scene && !strcmp(a->backend, "vulkan")) {
        int have = 0;
#ifdef TPK_WITH_VULKAN
        have = tpk_vulkan_available(a->device, sizeof a->device);
#endif
        if (!have) {
            fprintf(stderr, "tetpack render: note: %s asks for the Vulkan backend; no Vulkan device here, so the CPU "
                    "reference renders it (the same picture)\n", a->scene_path);
            a->backend = "cpu";
        }
    }
    if (!a->backend && env && *env) {
        if (strcmp(env, "vulkan") && strcmp(env, "cpu"))
            return tpk_diag_fail(diag, "TETPACK_RENDER_BACKEND expects vulkan or cpu, found '%s'", env);
        a->backend = env;
    }
#ifdef TPK_WITH_VULKAN
    if (!a->backend)
        a->backend = tpk_vulkan_available(a->device, sizeof a->device) ? "vulkan" : "cpu";
    else if (!strcmp(a->backend, "vulkan") && !tpk_vulkan_available(a->device, sizeof a->device))
        return tpk_diag_fail(diag, "--backend vulkan: %s", a->device);
#else
    if (a->backend && !strcmp(a->backend, "vulkan"))
        return tpk_diag_fail(diag, "--backend vulkan: this tetpack was built without Vulkan (TETPACK_WITH_VULKAN=OFF)");
    a->backend = "cpu";
#endif
    if (!strcmp(a->backend, "cpu"))
        snprintf(a->device, sizeof a->device, "cpu");
    return 0;
}

static int render_file(render_args *a, tpk_file *file)
{
    int association;
    if (check_field(a, file, &association))
        return TPK_EXIT_USAGE;
    char name[80];
    uint32_t steps = field_steps(file, a->field, name);
    if ((uint32_t)a->step_last >= steps)
        return tpk_cli_fail("render", "%s: %s has %u step(s) (0..%u), step %d asked", a->path, name, steps,
                            steps - 1, a->step_last);
    tpk_diag backend_diag;
    memset(&backend_diag, 0, sizeof backend_diag);
    if (resolve_backend(a, &backend_diag) != 0)
        return tpk_cli_fail("render", "%s", backend_diag.message);
    tpk_transfer_function tf;
    if (render_args_load_tf("render", a, &tf))
        return TPK_EXIT_USAGE;
    tpk_render_options opt;
    tpk_render_options_default(&opt); /* opaque dark-gray background */
    render_args_to_options(a, file, &tf, &opt);
    uint8_t *rgba = malloc((size_t)a->width * (size_t)a->height * 4);
    if (!rgba)
        return tpk_cli_fail("render", "out of memory for a %dx%d image", a->width, a->height);
    int rc = TPK_EXIT_OK;
    for (int step = a->step; step <= a->step_last && rc == TPK_EXIT_OK; step++) {
        char path[4096];
        tpk_mesh_arrays mesh;
        if (frame_path(a, step, path, sizeof path))
            rc = tpk_cli_fail("render", "-o: the image path of step %d is too long", step);
        if (rc == TPK_EXIT_OK)
            rc = load_step(a, file, association == TPK_ASSOC_TET, step, &mesh, &opt);
        if (rc == TPK_EXIT_OK)
            rc = render_frame(a, &(frame_source){.mesh = &mesh}, &opt, path, rgba);
    }
    free(rgba);
    if (rc == TPK_EXIT_OK && a->save_scene && save_scene(a, file, &opt) != 0)
        return TPK_EXIT_USAGE;
    return rc;
}

/* Every output (each frame with --steps) against the inputs, before any work. */
static int check_outputs(const render_args *a)
{
    /* A --tf that names a file is read too (a preset name names none: stat fails, nothing matches). */
    tpk_output_input inputs[3] = {{.arg = "FILE.tpk", .given = a->path}};
    size_t count = 1;
    if (a->scene_path)
        inputs[count++] = (tpk_output_input){.arg = "--scene", .given = a->scene_path};
    if (a->tf)
        inputs[count++] = (tpk_output_input){.arg = "--tf", .given = a->tf};
    if (a->have_steps && !frame_pattern_ok(a->output)) {
        if (a->scene.step_range && a->step == a->scene.step_first && a->step_last == a->scene.step_last)
            return tpk_cli_fail("render", "%s: the scene gives steps %d..%d: -o needs one %%d conversion for the "
                                "step (e.g. frame_%%04d.png), or choose one step with --step N, found '%s'",
                                a->scene_path, a->step, a->step_last, a->output);
        return tpk_cli_fail("render", "--steps expects -o with one %%d conversion for the step (e.g. "
                                      "frame_%%04d.png), found '%s'", a->output);
    }
    if (a->save_scene && tpk_cli_check_output("render", "--save-scene", a->save_scene, inputs, count))
        return TPK_EXIT_USAGE;
    for (int step = a->step; step <= a->step_last; step++) {
        char path[4096];
        if (frame_path(a, step, path, sizeof path))
            return tpk_cli_fail("render", "-o: the image path of step %d is too long", step);
        if (tpk_cli_check_output("render", "-o", path, inputs, count))
            return TPK_EXIT_USAGE;
    }
    return 0;
}

/* ---- Part sets (spec §15): every part loaded, marched across the cuts by its links ---------------- */

typedef struct set_view {
    double bounds_min[3], bounds_max[3]; /* of the parts' headers */
    double range[2];                     /* the field's, over all parts */
    double lo[3], hi[3];                 /* of the stored positions, as one file's */
    int has_scalars;
} set_view;

/* Part p's arrays and links, merged into the view's boxes and range. */
static int load_part(const render_args *a, tpk_partset *set, uint32_t p, tpk_mesh_arrays *mesh,
                     const tpk_link **links, uint64_t *link_count, set_view *v)
{
    tpk_file *file = tpk_partset_file(set, p);
    int association;
    if (check_field(a, file, &association))
        return TPK_EXIT_USAGE;
    if (association == TPK_ASSOC_TET)
        return tpk_cli_fail("render", "%s: '%s' is a tet field; a part set renders point fields (render a part, "
                            "or the single file)", a->path, a->field);
    tpk_result r = tpk_load_arrays(file, render_args_layout(file, a->layout), a->field, (uint32_t)a->step, mesh);
    if (r == TPK_OK)
        r = tpk_partset_links(set, p, links, link_count);
    if (r != TPK_OK)
        return tpk_cli_fail("render", "%s: part %u: %s", a->path, p, tpk_error_text(file));
    tpk_file_info info;
    tpk_get_info(file, &info);
    double range[2];
    field_range(file, a->field, range);
    v->has_scalars = mesh->scalars != NULL;
    for (int k = 0; k < 3; k++) {
        v->bounds_min[k] = p == 0 || info.bounds_min[k] < v->bounds_min[k] ? info.bounds_min[k] : v->bounds_min[k];
        v->bounds_max[k] = p == 0 || info.bounds_max[k] > v->bounds_max[k] ? info.bounds_max[k] : v->bounds_max[k];
    }
    v->range[0] = p == 0 || range[0] < v->range[0] ? range[0] : v->range[0];
    v->range[1] = p == 0 || range[1] > v->range[1] ? range[1] : v->range[1];
    for (uint64_t i = 0; i < mesh->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->positions[3 * i + k];
            v->lo[k] = x < v->lo[k] ? x : v->lo[k];
            v->hi[k] = x > v->hi[k] ? x : v->hi[k];
        }
    return 0;
}

/* One frame of the set: the options from the arguments, with the set's box and range as defaults. */
static int render_set_frame(const render_args *a, tpk_partset *set, const tpk_set_marcher *marcher,
                            const set_view *v)
{
    tpk_transfer_function tf;
    if (render_args_load_tf("render", a, &tf))
        return TPK_EXIT_USAGE;
    tpk_render_options opt;
    tpk_render_options_default(&opt);
    render_args_to_options(a, tpk_partset_file(set, 0), &tf, &opt);
    if (!a->have_camera)
        tpk_camera_default(v->bounds_min, v->bounds_max, &opt.camera);
    if (!a->have_range)
        opt.range_min = v->range[0], opt.range_max = v->range[1];
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += v->hi[k] > v->lo[k] ? (v->hi[k] - v->lo[k]) * (v->hi[k] - v->lo[k]) : 0;
    frame_source src = {.set = marcher, .has_scalars = v->has_scalars, .diagonal = sqrt(d2)};
    uint8_t *rgba = malloc((size_t)a->width * (size_t)a->height * 4);
    if (!rgba)
        return tpk_cli_fail("render", "out of memory for a %dx%d image", a->width, a->height);
    int rc = render_frame(a, &src, &opt, a->output, rgba);
    free(rgba);
    if (rc == TPK_EXIT_OK && a->save_scene && save_scene(a, tpk_partset_file(set, 0), &opt) != 0)
        return TPK_EXIT_USAGE;
    return rc;
}

static int render_set(const render_args *a)
{
    if (a->have_steps)
        return tpk_cli_fail("render", "%s: a part set renders one step (--step N), not a range", a->path);
    if (a->backend && !strcmp(a->backend, "vulkan") && !a->backend_from_scene)
        return tpk_cli_fail("render", "%s: a part set renders with the CPU reference only (--backend cpu)", a->path);
    tpk_partset *set = NULL;
    char err[1024] = "";
    tpk_result r = tpk_partset_open(&set, a->path, NULL, NULL, NULL, err, sizeof err);
    if (r != TPK_OK)
        return tpk_cli_fail("render", "%s", err[0] ? err : tpk_result_string(r));
    uint32_t n = tpk_partset_part_count(set);
    tpk_mesh_arrays *meshes = calloc(n, sizeof *meshes);
    const tpk_link **links = calloc(n, sizeof *links);
    uint64_t *link_counts = calloc(n, sizeof *link_counts);
    set_view v = {.lo = {INFINITY, INFINITY, INFINITY}, .hi = {-INFINITY, -INFINITY, -INFINITY}};
    int rc = meshes && links && link_counts ? 0 : tpk_cli_fail("render", "out of memory for %u parts", n);
    for (uint32_t p = 0; rc == 0 && p < n; p++)
        rc = load_part(a, set, p, &meshes[p], &links[p], &link_counts[p], &v);
    tpk_set_marcher *marcher = NULL;
    if (rc == 0 && (r = tpk_set_marcher_create(&marcher, n, meshes, links, link_counts)) != TPK_OK)
        rc = tpk_cli_fail("render", "%s: cannot march across its parts: %s", a->path, tpk_result_string(r));
    if (rc == 0)
        rc = render_set_frame(a, set, marcher, &v);
    tpk_set_marcher_destroy(marcher);
    free(meshes);
    free(links);
    free(link_counts);
    tpk_partset_close(set);
    return rc;
}

int tpk_cmd_render(int argc, char **argv)
{
    render_args a;
    render_args_default(&a);
    if (render_args_merge_scene("render", argc, argv, &a))
        return TPK_EXIT_USAGE;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(render_help, stdout);
            return TPK_EXIT_OK;
        }
        int rc = render_args_parse_option("render", argc, argv, &i, &a);
        if (rc)
            return rc;
    }
    if (!a.path || !a.output)
        return tpk_cli_fail("render", "expected FILE.tpk and -o IMAGE.png (see tetpack render --help)");
    if (check_outputs(&a))
        return TPK_EXIT_USAGE;
    tpk_file *file = NULL;
    if (tpk_cli_open("render", a.path, &file))
        return TPK_EXIT_USAGE;
    uint64_t part_chunk;
    if (tpk_find_chunk(file, TPK_TAG_PART, 0, 0, &part_chunk) == TPK_OK) { /* a part set's manifest */
        tpk_close(file);
        return render_set(&a);
    }
    int rc = render_file(&a, file);
    tpk_close(file);
    return rc;
}
