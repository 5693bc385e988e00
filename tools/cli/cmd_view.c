/* tetpack view: the window viewer (tools/view/) over the options of tetpack render (render_args.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "cli.h"
#include "render_args.h"
#include "render_frame.h"
#include "render_input.h"
#include "render/render_backend.h"
#include "tetpack.h"
#ifdef TPK_WITH_VIEW
#include "view/view.h"
#endif
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

static const char view_help[] =
    "usage: tetpack view FILE [--scene scene.json] [options]\n"
    "\n"
    "FILE is a .tpk, a part set's manifest (.tpkset, convert --parts: its parts shown as the one mesh\n"
    "they were cut from), or any mesh tetpack convert reads (tetpack formats), converted in memory first.\n"
    "Opens a window that renders the file with the Vulkan renderer (the CPU reference where there is\n"
    "no Vulkan device) and shows each frame; the title shows what is shown, the device, the frame rate,\n"
    "the frame time and the GPU time. Vulkan frames go straight to the window's swapchain where the\n"
    "device can present to it, else through OpenGL (--present). Needs a display: for images without\n"
    "one, use tetpack render.\n"
    "\n"
    "Mouse: left drag orbits around the look-at point, right drag or the wheel zooms, middle drag (or\n"
    "shift + left drag) pans. While dragging, frames that take longer than 1/15 s are rendered at a\n"
    "fraction of the resolution.\n"
    "Keys: T next transfer function preset, F next field, [ ] previous / next time step, L next layout\n"
    "(of those stored), I isosurface at the middle of the range on/off, S shading on/off, C clip box\n"
    "(the half of the bounds below the middle of x) on/off, P screenshot (--screenshot, else\n"
    "view_NNN.png), W write the scene (--save-scene, else view_scene.json), Q or Esc quit.\n"
    "The first CSG probe: O its shape (a cut sphere, then a plane facing the camera that keeps the far\n"
    "half, then a cut box, then none), K keep/cut, arrows or 4 6 8 2 move it left, right, up, down,\n"
    "Page Up/Down or 9 3 away and near (a twentieth of the bounds each), + - grow and shrink it.\n"
    "\n"; /* then the options view takes from render (the option table), and its own: */

static const char view_help_own[] =
    "  --frames N                   show N frames, then close (with --screenshot: tests, scripts)\n"
    "  --orbit DEG                  turn the camera by DEG degrees per frame around its up axis\n"
    "  --screenshot IMAGE.png       the window's last frame as PNG when it closes (and P's file)\n"
    "  --keys KEYS                  press these keys (of the list above) before the first frame\n"
    "  --present auto|vulkan|gl     how frames reach the window: the Vulkan swapchain, OpenGL (frames\n"
    "                               read back), or auto (default; TETPACK_VIEW_PRESENT): Vulkan where\n"
    "                               the renderer is Vulkan and the device can present, else OpenGL\n"
    "--size WxH is the window's size (default 640x480); a scene's size is used when it gives one.\n";

typedef struct view_args {
    int frames;
    double orbit;
    const char *screenshot;
    const char *keys;
    const char *present; /* NULL: TETPACK_VIEW_PRESENT, else auto */
} view_args;

/* The options only view has. 1 when argv[*i] is one (parsed, *i advanced), 0 when it is not, or
 * TPK_EXIT_USAGE + 1 on a bad value. */
static int view_option(int argc, char **argv, int *i, view_args *v)
{
    const char *arg = argv[*i], *value;
    if (!strncmp(arg, "--frames", 8) && (!arg[8] || arg[8] == '=')) {
        value = tpk_cli_value(argc, argv, i, "--frames");
        if (!value || tpk_cli_parse_int(value, 1, 1 << 30, &v->frames))
            return tpk_cli_fail("view", "--frames expects a frame count >= 1, found '%s'", value ? value : "") + 1;
    } else if (!strncmp(arg, "--orbit", 7) && (!arg[7] || arg[7] == '=')) {
        value = tpk_cli_value(argc, argv, i, "--orbit");
        if (!value || tpk_cli_parse_doubles(value, &v->orbit, 1) || !(fabs(v->orbit) <= 360))
            return tpk_cli_fail("view", "--orbit expects degrees per frame in [-360, 360], found '%s'",
                                value ? value : "") + 1;
    } else if (!strncmp(arg, "--screenshot", 12) && (!arg[12] || arg[12] == '=')) {
        if (!(v->screenshot = tpk_cli_value(argc, argv, i, "--screenshot")))
            return tpk_cli_fail("view", "--screenshot expects an output PNG path") + 1;
    } else if (!strncmp(arg, "--keys", 6) && (!arg[6] || arg[6] == '=')) {
        v->keys = tpk_cli_value(argc, argv, i, "--keys");
        if (!v->keys || strspn(v->keys, "TtFf[]LlIiSsCcPpWwQqOoKk468293+=-") != strlen(v->keys))
            return tpk_cli_fail("view", "--keys expects keys of T F [ ] L I S C P W Q O K 4 6 8 2 9 3 + -, found '%s'",
                                v->keys ? v->keys : "") + 1;
    } else if (!strncmp(arg, "--present", 9) && (!arg[9] || arg[9] == '=')) {
        if (!(v->present = tpk_cli_value(argc, argv, i, "--present")))
            return tpk_cli_fail("view", "--present expects auto, vulkan or gl") + 1;
    } else if (render_args_find_option(arg) && render_args_find_option(arg)->render_only) {
        return tpk_cli_fail("view", "%s is an option of tetpack render; view shows one step at a time ([ and ] "
                            "step) and saves with --screenshot or P", arg) + 1;
    } else {
        return 0;
    }
    return 1;
}

static int parse_args(int argc, char **argv, render_args *a, view_args *v)
{
    for (int i = 1; i < argc; i++) {
        int rc = view_option(argc, argv, &i, v);
        if (rc > 1)
            return TPK_EXIT_USAGE;
        if (rc == 0 && (rc = render_args_parse_option("view", argc, argv, &i, a)) != 0)
            return rc;
    }
    if (!a->path)
        return tpk_cli_fail("view", "expected FILE (see tetpack view --help)");
    tpk_output_input inputs[3] = {{.arg = "FILE.tpk", .given = a->path}};
    size_t count = 1;
    if (a->save_tpk && tpk_cli_check_convert_output("view", "--save-tpk", a->path, NULL, a->save_tpk))
        return TPK_EXIT_USAGE;
    if (a->save_tpk)
        inputs[count++] = (tpk_output_input){.arg = "--save-tpk", .given = a->save_tpk};
    if (a->scene_path)
        inputs[count++] = (tpk_output_input){.arg = "--scene", .given = a->scene_path};
    if (v->screenshot && tpk_cli_check_output("view", "--screenshot", v->screenshot, inputs, count))
        return TPK_EXIT_USAGE;
    if (a->save_scene && tpk_cli_check_output("view", "--save-scene", a->save_scene, inputs, count))
        return TPK_EXIT_USAGE;
    return 0;
}

#ifdef TPK_WITH_VIEW
/* 1: the CPU reference, 0: Vulkan, by render's rule (render/render_backend.h: --backend, the scene's,
 * $TETPACK_RENDER_BACKEND, else Vulkan on a hardware device and the CPU reference with only a software
 * rasterizer); -1: an error printed. Where Vulkan is chosen and fails later, the view falls back with a
 * note. */
static int want_cpu(const render_args *a)
{
    tpk_backend_request req = {.flag = a->backend_from_scene ? NULL : a->backend,
                               .scene = a->backend_from_scene ? a->backend : NULL,
                               .env = getenv("TETPACK_RENDER_BACKEND"), .vulkan_only = a->iso_raster};
    char name[256] = "";
#ifdef TPK_WITH_VULKAN
    req.vulkan_built = 1;
    int kind = TPK_VK_DEVICE_NONE;
    if (tpk_backend_needs_device(&req))
        tpk_vulkan_probe(name, sizeof name, &kind);
    req.device = (tpk_vk_device_kind)kind;
    req.device_name = name;
#endif
    tpk_backend_choice choice;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_backend_choose(&req, &choice, &diag) != 0)
        return tpk_cli_fail("view", "%s", diag.message), -1;
    if (!choice.vulkan && !req.flag && !req.scene && !(req.env && *req.env))
        fprintf(stderr, "tetpack view: note: the CPU reference renders (%s)\n", choice.reason);
    return !choice.vulkan;
}

/* --present, else TETPACK_VIEW_PRESENT, else auto; -1: an error printed. */
static int want_present(const view_args *v, tpk_view_present *out)
{
    const char *present = v->present ? v->present : getenv("TETPACK_VIEW_PRESENT");
    const char *what = v->present ? "--present" : "TETPACK_VIEW_PRESENT";
    if (!present || !*present || !strcmp(present, "auto"))
        *out = TPK_VIEW_PRESENT_AUTO;
    else if (!strcmp(present, "vulkan"))
        *out = TPK_VIEW_PRESENT_VULKAN;
    else if (!strcmp(present, "gl"))
        *out = TPK_VIEW_PRESENT_GL;
    else
        return tpk_cli_fail("view", "%s expects auto, vulkan or gl, found '%s'", what, present), -1;
    return 0;
}

/* view_file with `set`'s parts as one mesh (spec §15; libtetpack/set_mesh.c): part 0 gives the field
 * list, the set its box, the field's range and the default camera. */
static int view_file_of(render_args *a, const view_args *v, tpk_file *file, tpk_set_mesh *set_mesh,
                        tpk_partset *set);

static int view_part_set(render_args *a, const view_args *v)
{
    if (a->level > 0 || a->max_ms > 0)
        return tpk_cli_fail("view", "%s: a part set has no levels of detail: %s shows a single file's", a->path,
                            a->level > 0 ? "--level" : "--max-ms");
    if (a->iso_auto)
        return tpk_cli_fail("view", "%s: --iso auto takes one file's median; for a part set give --iso V", a->path);
    tpk_partset *set = NULL;
    tpk_set_mesh *mesh = NULL;
    char err[1024] = "";
    tpk_result r = tpk_partset_open(&set, a->path, NULL, NULL, NULL, err, sizeof err);
    if (r == TPK_OK)
        r = tpk_set_mesh_create(&mesh, set, render_args_layout(tpk_partset_file(set, 0), a->layout), err, sizeof err);
    int rc = r == TPK_OK ? view_file_of(a, v, tpk_partset_file(set, 0), mesh, set)
                         : tpk_cli_fail("view", "%s: %s", a->path, err[0] ? err : tpk_result_string(r));
    tpk_set_mesh_destroy(mesh);
    tpk_partset_close(set);
    return rc;
}

static int view_file(render_args *a, const view_args *v, tpk_file *file)
{
    uint64_t part_chunk;
    if (tpk_find_chunk(file, TPK_TAG_PART, 0, 0, &part_chunk) == TPK_OK)
        return view_part_set(a, v);
    return view_file_of(a, v, file, NULL, NULL);
}

static int view_file_of(render_args *a, const view_args *v, tpk_file *file, tpk_set_mesh *set_mesh,
                        tpk_partset *set)
{
    tpk_view_options o;
    memset(&o, 0, sizeof o);
    int cpu = want_cpu(a);
    if (cpu < 0 || want_present(v, &o.present) != 0 || render_args_load_tf("view", a, &o.tf))
        return TPK_EXIT_USAGE;
    tpk_render_options_default(&o.render);
    render_args_to_options(a, file, &o.tf, &o.render);
    if (set) { /* the whole set's box and range, not part 0's (as render_set.c) */
        o.set = set;
        double range[2];
        render_set_extent(a, set, o.set_bounds_min, o.set_bounds_max, range);
        if (!a->have_camera)
            tpk_camera_default(o.set_bounds_min, o.set_bounds_max, &o.render.camera);
        if (!a->have_range)
            o.render.range_min = range[0], o.render.range_max = range[1];
        if (!(a->unit_distance > 0))
            o.render.unit_distance = render_args_default_unit(o.set_bounds_min, o.set_bounds_max);
        o.set_mesh = set_mesh;
    }
    double iso_auto;
    if (a->iso_auto && render_args_iso_auto("view", a, file, &o.render, &iso_auto))
        return TPK_EXIT_USAGE;
    o.file = file;
    o.path = a->path;
    o.field = a->field;
    o.step = a->step;
    o.layout = render_args_layout(file, a->layout);
    o.cpu = cpu;
    o.frames = v->frames;
    o.orbit_deg = v->orbit;
    o.screenshot = v->screenshot;
    o.save_scene = a->save_scene;
    o.keys = v->keys;
    o.iso_raster = a->iso_raster;
    o.max_ms = a->max_ms;
    o.max_pixel_step = a->max_pixel_step;
    if (a->iso_raster && cpu)
        return tpk_cli_fail("view", "--iso-raster draws with Vulkan: not with --backend cpu");
    if (a->iso_raster && o.present == TPK_VIEW_PRESENT_VULKAN)
        return tpk_cli_fail("view", "--iso-raster shows its frames through OpenGL: not with --present vulkan");
    if (a->iso_raster)
        o.present = TPK_VIEW_PRESENT_GL;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_view_run(&o, &diag) != 0)
        return tpk_cli_fail("view", "%s", diag.message);
    return TPK_EXIT_OK;
}
#endif

int tpk_cmd_view(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(view_help, stdout);
            render_args_view_list(stdout);
            fputs(view_help_own, stdout);
            return TPK_EXIT_OK;
        }
    render_args a;
    render_args_default(&a);
    a.width = 640, a.height = 480;
    view_args v = {0, 0.0, NULL, NULL, NULL};
    if (render_args_merge_scene("view", argc, argv, &a) || parse_args(argc, argv, &a, &v))
        return TPK_EXIT_USAGE;
#ifdef TPK_WITH_VIEW
    render_input in;
    if (render_input_open("view", a.path, a.save_tpk, a.threads, &in))
        return TPK_EXIT_USAGE;
    int rc = view_file(&a, &v, in.file);
    render_input_close(&in);
    return rc;
#else
    (void)v;
    return tpk_cli_fail("view", "this tetpack was built without the window viewer (TETPACK_WITH_VIEW=OFF or GLFW "
                        "not found); tetpack render writes images");
#endif
}
