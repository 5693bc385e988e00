/* tetpack render: CPU reference rendering of a .tpk to PNG (emission-absorption). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "cli.h"
#include "render/render.h"
#include "scene/scene.h"
#include "tetpack.h"
#include "render/transfer_function.h"

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
    "  --field NAME                 point field to render (default: the first point field)\n"
    "  --step N                     time step of the field (default 0)\n"
    "  --range LO,HI                scalar range mapped onto the TF (default: the field's range)\n"
    "  --layout tet16|tet20|tet32   which stored layout to march (default: the first present)\n"
    "  --unit-distance D            TF opacity is per distance D (default: bounds diagonal / 100)\n"
    "  --integration exact|sampled  per-piece integration as above (default), or point samples\n"
    "                               at most unit-distance/2 apart\n"
    "  --threads N                  worker threads (default: all cores)\n"
    "  --scene FILE                 a scene file (spec/scene-json.md): its values first, then the\n"
    "                               options given here override them\n"
    "  --save-scene FILE            write the scene of this render (every value it used) as JSON\n"
    "  --json                       print render statistics as JSON\n";

typedef struct render_args {
    const char *path, *output, *tf, *field, *layout;
    int width, height, step, threads, json, have_camera, have_range, integration;
    double camera[10], range[2], unit_distance;
    const char *scene_path, *save_scene; /* --scene, --save-scene */
    int have_step;
    tpk_scene scene;
} render_args;

static int parse_size(const char *text, int *w, int *h)
{
    char *end;
    long a = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X'))
        return -1;
    const char *rest = end + 1;
    long b = strtol(rest, &end, 10);
    if (end == rest || *end || a < 1 || b < 1 || a > 16384 || b > 16384)
        return -1;
    *w = (int)a;
    *h = (int)b;
    return 0;
}

static int parse_option(int argc, char **argv, int *i, render_args *a)
{
    const char *arg = argv[*i], *v = NULL;
#define VALUE(name) (v = tpk_cli_value(argc, argv, i, name))
    if (!strcmp(arg, "-o") || !strncmp(arg, "--output", 8)) {
        if (!VALUE(arg[1] == 'o' ? "-o" : "--output"))
            return tpk_cli_fail("render", "-o expects an output PNG path");
        a->output = v;
    } else if (!strncmp(arg, "--size", 6)) {
        if (!VALUE("--size") || parse_size(v, &a->width, &a->height))
            return tpk_cli_fail("render", "--size expects WxH (1..16384), found '%s'", v ? v : "");
    } else if (!strncmp(arg, "--camera", 8)) {
        if (!VALUE("--camera") || tpk_cli_parse_doubles(v, a->camera, 10) || !(a->camera[9] > 0 && a->camera[9] < 180))
            return tpk_cli_fail("render", "--camera expects 10 numbers ex,ey,ez,ax,ay,az,ux,uy,uz,fovy "
                                          "(fovy in (0,180)), found '%s'", v ? v : "");
        a->have_camera = 1;
    } else if (!strncmp(arg, "--tf", 4)) {
        if (!VALUE("--tf"))
            return tpk_cli_fail("render", "--tf expects a preset name or a file");
        a->tf = v;
    } else if (!strncmp(arg, "--field", 7)) {
        if (!VALUE("--field"))
            return tpk_cli_fail("render", "--field expects a field name");
        a->field = v;
    } else if (!strncmp(arg, "--step", 6)) {
        if (!VALUE("--step") || tpk_cli_parse_int(v, 0, 1 << 30, &a->step))
            return tpk_cli_fail("render", "--step expects a step number >= 0, found '%s'", v ? v : "");
        a->have_step = 1;
    } else if (!strncmp(arg, "--range", 7)) {
        if (!VALUE("--range") || tpk_cli_parse_doubles(v, a->range, 2) || !(a->range[0] < a->range[1]))
            return tpk_cli_fail("render", "--range expects LO,HI with LO < HI, found '%s'", v ? v : "");
        a->have_range = 1;
    } else if (!strncmp(arg, "--layout", 8)) {
        if (!VALUE("--layout") || (strcmp(v, "tet16") && strcmp(v, "tet20") && strcmp(v, "tet32")))
            return tpk_cli_fail("render", "--layout expects tet16, tet20 or tet32, found '%s'", v ? v : "");
        a->layout = v;
    } else if (!strncmp(arg, "--unit-distance", 15)) {
        if (!VALUE("--unit-distance") || tpk_cli_parse_doubles(v, &a->unit_distance, 1) || !(a->unit_distance > 0))
            return tpk_cli_fail("render", "--unit-distance expects a positive number, found '%s'", v ? v : "");
    } else if (!strncmp(arg, "--integration", 13)) {
        if (!VALUE("--integration") || (strcmp(v, "exact") && strcmp(v, "sampled")))
            return tpk_cli_fail("render", "--integration expects exact or sampled, found '%s'", v ? v : "");
        a->integration = !strcmp(v, "sampled");
    } else if (!strncmp(arg, "--threads", 9)) {
        if (!VALUE("--threads") || tpk_cli_parse_int(v, 1, 1024, &a->threads))
            return tpk_cli_fail("render", "--threads expects 1..1024, found '%s'", v ? v : "");
    } else if (!strncmp(arg, "--scene", 7)) {
        if (!VALUE("--scene"))
            return tpk_cli_fail("render", "--scene expects a scene file");
    } else if (!strncmp(arg, "--save-scene", 12)) {
        if (!VALUE("--save-scene"))
            return tpk_cli_fail("render", "--save-scene expects an output path");
        a->save_scene = v;
    } else if (!strcmp(arg, "--json")) {
        a->json = 1;
    } else if (arg[0] == '-' && arg[1]) {
        return tpk_cli_fail("render", "unknown option '%s' (see tetpack render --help)", arg);
    } else if (!a->path) {
        a->path = arg;
    } else {
        return tpk_cli_fail("render", "expected one FILE.tpk, found a second argument '%s'", arg);
    }
#undef VALUE
    return 0;
}

static tpk_layout pick_layout(tpk_file *file, const char *name)
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

/* The range of the field being rendered, from its descriptor. */
static void field_range(tpk_file *file, const char *name, double range[2])
{
    range[0] = 0.0;
    range[1] = 1.0;
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) != TPK_OK || d.association != TPK_ASSOC_POINT)
            continue;
        if (name && strcmp(name, d.name))
            continue;
        if (d.min_value < d.max_value) {
            range[0] = d.min_value;
            range[1] = d.max_value;
        }
        return;
    }
}

/* The renderer interpolates per-point values linearly inside each tet; say so, and which fields fit,
 * when the named field is per-tet or missing. */
static int check_field(const render_args *a, tpk_file *file)
{
    if (!a->field)
        return 0;
    char points[512] = "";
    size_t used = 0;
    int found = -1;
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) != TPK_OK)
            continue;
        if (!strcmp(d.name, a->field))
            found = (int)d.association;
        if (d.association == TPK_ASSOC_POINT && used + strlen(d.name) + 3 < sizeof points)
            used += (size_t)snprintf(points + used, sizeof points - used, "%s%s", used ? ", " : "", d.name);
    }
    if (found == TPK_ASSOC_POINT)
        return 0;
    return tpk_cli_fail("render", "%s: %s '%s'; render needs a per-point field (this file has %s%s)", a->path,
                        found < 0 ? "no field named" : "per-tet field", a->field,
                        used ? "point fields: " : "no point field", points);
}

/* The scene of this render, every value it used, so that render --scene gives the same image. */
static int save_scene(const render_args *a, tpk_file *file, const tpk_mesh_arrays *mesh, const tpk_render_options *opt)
{
    char first[sizeof ((tpk_field_desc *)0)->name] = "";
    for (uint32_t i = 0; !a->field && mesh->scalars && !first[0] && i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) == TPK_OK && d.association == TPK_ASSOC_POINT)
            memcpy(first, d.name, sizeof first); /* the first point field: the one tpk_load_arrays took */
    }
    const char *field = a->field ? a->field : first;
    tpk_scene scene;
    tpk_scene_from_options(opt, field, a->step, mesh->layout, &scene);
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_scene_write(a->save_scene, &scene, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    return 0;
}

/* Scene values first (--scene): they fill what the command line leaves unset; the options parsed after
 * this override them. */
static int merge_scene(int argc, char **argv, render_args *a)
{
    for (int i = 1; i < argc; i++) {
        if (strncmp(argv[i], "--scene", 7) || (argv[i][7] && argv[i][7] != '='))
            continue;
        a->scene_path = tpk_cli_value(argc, argv, &i, "--scene");
    }
    if (!a->scene_path)
        return 0;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_scene *s = &a->scene;
    if (tpk_scene_load(a->scene_path, s, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    if (s->given & TPK_SCENE_BACKEND && s->backend == TPK_SCENE_BACKEND_VULKAN)
        fprintf(stderr, "tetpack render: note: %s asks for the Vulkan backend; this build renders on the CPU "
                "(the reference, same picture)\n", a->scene_path);
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
    a->layout = !(s->given & TPK_SCENE_LAYOUT) ? NULL : s->layout == TPK_LAYOUT_TET16 ? "tet16"
                                               : s->layout == TPK_LAYOUT_TET20 ? "tet20" : "tet32";
    a->unit_distance = s->unit_distance;
    a->integration = s->integration;
    return 0;
}

static int render_file(render_args *a, tpk_file *file)
{
    if (check_field(a, file))
        return TPK_EXIT_USAGE;
    tpk_mesh_arrays mesh;
    tpk_result r = tpk_load_arrays(file, pick_layout(file, a->layout), a->field, (uint32_t)a->step, &mesh);
    if (r != TPK_OK)
        return tpk_cli_fail_file("render", a->path, tpk_error_text(file));
    tpk_transfer_function tf;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (!a->tf && (a->scene.given & TPK_SCENE_TF))
        tf = a->scene.tf;
    else if (tpk_tf_load(a->tf ? a->tf : "viridis", &tf, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    tpk_file_info info;
    tpk_get_info(file, &info);
    tpk_render_options opt;
    tpk_render_options_default(&opt); /* opaque dark-gray background */
    tpk_scene_apply(&a->scene, &opt);   /* then the values below: the command line's, merged over the scene */
    opt.width = a->width;
    opt.height = a->height;
    if (a->have_camera) {
        memcpy(opt.camera.eye, a->camera, sizeof opt.camera.eye);
        memcpy(opt.camera.at, a->camera + 3, sizeof opt.camera.at);
        memcpy(opt.camera.up, a->camera + 6, sizeof opt.camera.up);
        opt.camera.fovy_deg = a->camera[9];
    } else {
        tpk_camera_default(info.bounds_min, info.bounds_max, &opt.camera);
    }
    opt.tf = &tf;
    if (a->have_range) {
        opt.range_min = a->range[0];
        opt.range_max = a->range[1];
    } else {
        double range[2];
        field_range(file, a->field, range);
        opt.range_min = range[0];
        opt.range_max = range[1];
    }
    opt.unit_distance = a->unit_distance;
    opt.threads = a->threads;
    opt.integration = a->integration;
    uint8_t *rgba = malloc((size_t)a->width * (size_t)a->height * 4);
    if (!rgba)
        return tpk_cli_fail("render", "out of memory for a %dx%d image", a->width, a->height);
    tpk_render_stats stats;
    memset(&stats, 0, sizeof stats);
    int rc = tpk_render_cpu(&mesh, &opt, rgba, &stats, &diag);
    if (rc != 0) {
        free(rgba);
        return tpk_cli_fail_file("render", a->path, diag.message); /* e.g. bounds that are not finite */
    }
    rc = tpk_write_png(a->output, a->width, a->height, rgba, &diag);
    free(rgba);
    if (rc != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    if (a->save_scene && save_scene(a, file, &mesh, &opt) != 0)
        return TPK_EXIT_USAGE;
    if (a->json)
        printf("{\"image\":\"%s\",\"width\":%d,\"height\":%d,\"rays\":%llu,\"tet_steps\":%llu,\"seconds\":%.6f}\n",
               a->output, a->width, a->height, (unsigned long long)stats.rays,
               (unsigned long long)stats.tet_steps, stats.seconds);
    else
        printf("%s: %dx%d, %llu rays, %llu tet steps, %.3f s\n", a->output, a->width, a->height,
               (unsigned long long)stats.rays, (unsigned long long)stats.tet_steps, stats.seconds);
    return TPK_EXIT_OK;
}

int tpk_cmd_render(int argc, char **argv)
{
    render_args a;
    memset(&a, 0, sizeof a);
    a.width = a.height = 512;
    if (merge_scene(argc, argv, &a))
        return TPK_EXIT_USAGE;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(render_help, stdout);
            return TPK_EXIT_OK;
        }
        int rc = parse_option(argc, argv, &i, &a);
        if (rc)
            return rc;
    }
    if (!a.path || !a.output)
        return tpk_cli_fail("render", "expected FILE.tpk and -o IMAGE.png (see tetpack render --help)");
    if (a.scene.step_first != a.scene.step_last && !a.have_step)
        return tpk_cli_fail("render", "%s: the scene gives steps %d..%d; this command renders one image: choose a "
                            "step with --step N", a.scene_path, a.scene.step_first, a.scene.step_last);
    /* A --tf that names a file is read too (a preset name names none: stat fails, nothing matches). */
    tpk_output_input inputs[3] = {{.arg = "FILE.tpk", .given = a.path}};
    size_t input_count = 1;
    if (a.scene_path)
        inputs[input_count++] = (tpk_output_input){.arg = "--scene", .given = a.scene_path};
    if (a.tf)
        inputs[input_count++] = (tpk_output_input){.arg = "--tf", .given = a.tf};
    if (tpk_cli_check_output("render", "-o", a.output, inputs, input_count) ||
        (a.save_scene && tpk_cli_check_output("render", "--save-scene", a.save_scene, inputs, input_count)))
        return TPK_EXIT_USAGE;
    tpk_file *file = NULL;
    if (tpk_cli_open("render", a.path, &file))
        return TPK_EXIT_USAGE;
    int rc = render_file(&a, file);
    tpk_close(file);
    return rc;
}
