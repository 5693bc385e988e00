/* tetpack render: CPU reference rendering of a .tpk to PNG (emission-absorption). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "cli.h"
#include "render/render.h"
#include "tetpack.h"
#include "render/transfer_function.h"
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
    "  --field NAME                 point field to render (default: the first point field)\n"
    "  --step N                     time step of the field (default 0)\n"
    "  --range LO,HI                scalar range mapped onto the TF (default: the field's range)\n"
    "  --layout tet16|tet20|tet32   which stored layout to march (default: the first present)\n"
    "  --unit-distance D            TF opacity is per distance D (default: bounds diagonal / 100)\n"
    "  --integration exact|sampled  per-piece integration as above (default), or point samples\n"
    "                               at most unit-distance/2 apart\n"
    "  --threads N                  worker threads of the CPU backend (default: all cores)\n"
    "  --backend vulkan|cpu         vulkan: compute shaders on the first Vulkan device (a GPU, else\n"
    "                               lavapipe); cpu: the reference renderer. Same options, same picture.\n"
    "                               Default: $TETPACK_RENDER_BACKEND if set, else vulkan when a\n"
    "                               Vulkan device is present, else cpu\n"
    "  --json                       print render statistics as JSON\n";

typedef struct render_args {
    const char *path, *output, *tf, *field, *layout, *backend;
    int width, height, step, threads, json, have_camera, have_range, integration;
    double camera[10], range[2], unit_distance;
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
    } else if (!strncmp(arg, "--backend", 9)) {
        if (!VALUE("--backend") || (strcmp(v, "vulkan") && strcmp(v, "cpu")))
            return tpk_cli_fail("render", "--backend expects vulkan or cpu, found '%s'", v ? v : "");
        a->backend = v;
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

/* Render with the chosen backend; without --backend, Vulkan when a device is present. `device` gets
 * the device name ("cpu" for the reference). */
static int run_backend(render_args *a, const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                       tpk_render_stats *stats, char *device, size_t device_size, tpk_diag *diag)
{
    const char *env = getenv("TETPACK_RENDER_BACKEND");
    if (!a->backend && env && *env) {
        if (strcmp(env, "vulkan") && strcmp(env, "cpu"))
            return tpk_diag_fail(diag, "TETPACK_RENDER_BACKEND expects vulkan or cpu, found '%s'", env);
        a->backend = env;
    }
#ifdef TPK_WITH_VULKAN
    if (!a->backend)
        a->backend = tpk_vulkan_available(device, device_size) ? "vulkan" : "cpu";
    else if (!strcmp(a->backend, "vulkan") && !tpk_vulkan_available(device, device_size))
        return tpk_diag_fail(diag, "--backend vulkan: %s", device);
    if (!strcmp(a->backend, "vulkan"))
        return tpk_render_vulkan(mesh, opt, rgba, stats, diag);
#else
    if (a->backend && !strcmp(a->backend, "vulkan"))
        return tpk_diag_fail(diag, "--backend vulkan: this tetpack was built without Vulkan (TETPACK_WITH_VULKAN=OFF)");
#endif
    a->backend = "cpu";
    snprintf(device, device_size, "cpu");
    return tpk_render_cpu(mesh, opt, rgba, stats, diag);
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
    if (tpk_tf_load(a->tf ? a->tf : "viridis", &tf, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    tpk_file_info info;
    tpk_get_info(file, &info);
    tpk_render_options opt;
    tpk_render_options_default(&opt); /* opaque dark-gray background */
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
    char device[256] = "cpu";
    int rc = run_backend(a, &mesh, &opt, rgba, &stats, device, sizeof device, &diag);
    if (rc != 0) {
        free(rgba);
        return tpk_cli_fail_file("render", a->path, diag.message); /* e.g. bounds that are not finite */
    }
    rc = tpk_write_png(a->output, a->width, a->height, rgba, &diag);
    free(rgba);
    if (rc != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    if (a->json)
        printf("{\"image\":\"%s\",\"backend\":\"%s\",\"device\":\"%s\",\"width\":%d,\"height\":%d,"
               "\"rays\":%llu,\"tet_steps\":%llu,\"seconds\":%.6f}\n",
               a->output, a->backend, device, a->width, a->height, (unsigned long long)stats.rays,
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
    /* A --tf that names a file is read too (a preset name names none: stat fails, nothing matches). */
    tpk_output_input inputs[2] = {{.arg = "FILE.tpk", .given = a.path}, {.arg = "--tf", .given = a.tf}};
    if (tpk_cli_check_output("render", "-o", a.output, inputs, a.tf ? 2 : 1))
        return TPK_EXIT_USAGE;
    tpk_file *file = NULL;
    if (tpk_cli_open("render", a.path, &file))
        return TPK_EXIT_USAGE;
    int rc = render_file(&a, file);
    tpk_close(file);
    return rc;
}
