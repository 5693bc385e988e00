/* One render-option contract (tpk_render_check_options): a list of bad option sets goes through both
 * backends, the CPU reference and the Vulkan renderer (lavapipe, no GPU needed); each must be refused by
 * both, with the same message, the one tpk_render_check_options gives. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "render_vk/render_vk.h"
#include "vk_device.h"
#include "tetpack.h"
#include "tpk_assert.h"

#define SIZE 16

/* One bad option set: what it breaks, and a piece of the message that says so. */
typedef struct bad_case {
    const char *what, *expect;
} bad_case;

static const bad_case bad_cases[] = {
    {"width 0", "width and height in 1..32768"},
    {"height above the limit", "width and height in 1..32768"},
    {"no transfer function", "transfer function"},
    {"empty transfer function", "transfer function"},
    {"integration 3", "integration"},
    {"range not finite", "scalar range must be finite"},
    {"5 iso values", "0..4 iso values"},
    {"iso value NaN", "iso value 1 is not finite"},
    {"iso opacity above 1", "iso opacity <= 1"},
    {"iso opacity NaN", "iso opacity <= 1"},
    {"clip box not finite", "clip box must be finite"},
    {"clip box min above max", "clip box min 2 above max 1 on axis y"},
    {"light not finite", "light position must be finite"},
    {"light NaN", "light position must be finite"},
    {"AO rays -1", "0..1024 AO rays"},
    {"AO rays 1025", "0..1024 AO rays"},
    {"AO radius not finite", "AO radius must be finite"},
    {"camera eye == at", "the same point"},
    {"camera eye not finite", "must be finite"},
    {"field of view 180", "field of view"},
    {"occlusion 3", "occlusion ray (0), vertex (1) or surface (2)"},
};
#define BAD_CASES (sizeof bad_cases / sizeof bad_cases[0])

/* Break `opt` as case c says. */
static void break_options(size_t c, tpk_render_options *opt, tpk_transfer_function *empty_tf)
{
    switch (c) {
    case 0: opt->width = 0; break;
    case 1: opt->height = 40000; break;
    case 2: opt->tf = NULL; break;
    case 3: empty_tf->count = 0; opt->tf = empty_tf; break;
    case 4: opt->integration = 3; break;
    case 5: opt->range_max = INFINITY; break;
    case 6: opt->iso_count = 5; break;
    case 7: opt->iso_count = 1; opt->iso[0] = NAN; break;
    case 8: opt->iso_count = 1; opt->iso_opacity = 1.5; break; /* the Vulkan renderer accepted it once */
    case 9: opt->iso_opacity = NAN; break;
    case 10: opt->clip = 1; opt->clip_max[0] = INFINITY; break;
    case 11: opt->clip = 1; opt->clip_min[1] = 2; opt->clip_max[1] = 1; break;
    case 12: opt->have_light = 1; opt->light[2] = INFINITY; break; /* and this one */
    case 13: opt->have_light = 1; opt->light[0] = NAN; break;
    case 14: opt->ao_rays = -1; break;
    case 15: opt->ao_rays = 1025; break;
    case 16: opt->ao_rays = 1; opt->ao_radius = INFINITY; break;
    case 17: memcpy(opt->camera.at, opt->camera.eye, sizeof opt->camera.at); break;
    case 18: opt->camera.eye[1] = NAN; break;
    case 19: opt->camera.fovy_deg = 180; break;
    default: opt->occlusion = 3; break;
    }
}

TPK_TEST(both_backends_reject_alike)
{
    if (!have_device())
        return;
    char msg[512];
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = TPK_SOURCE_DIR "/samples/cylinder.vtk";
    o.output = tpk_temp_path("bad_options.tpk");
    o.layouts = TPK_LAYOUT_BIT_TET16;
    tpk_convert_report report;
    tpk_diag diag = {0};
    CHECK(tpk_convert_checked(&o, &report, &diag) == 0);
    tpk_file *file = NULL;
    tpk_file_info info;
    CHECK(tpk_open_path(&file, o.output, NULL, msg, sizeof msg) == TPK_OK && tpk_get_info(file, &info) == TPK_OK);
    tpk_mesh_arrays mesh;
    CHECK(tpk_load_arrays(file, TPK_LAYOUT_TET16, NULL, 0, &mesh) == TPK_OK);
    tpk_transfer_function tf, empty_tf;
    CHECK(tpk_tf_load("viridis", &tf, &diag) == 0);
    empty_tf = tf;
    uint8_t *img = malloc((size_t)SIZE * SIZE * 4);
    CHECK(img);

    tpk_render_options good;
    tpk_render_options_default(&good);
    good.width = good.height = SIZE;
    tpk_camera_default(info.bounds_min, info.bounds_max, &good.camera);
    good.tf = &tf;
    CHECK(tpk_render_check_options(&good, &diag) == 0);
    for (size_t c = 0; c < BAD_CASES; c++) {
        tpk_render_options opt = good;
        break_options(c, &opt, &empty_tf);
        tpk_diag check = {0}, cpu = {0}, vk = {0};
        int rc_check = tpk_render_check_options(&opt, &check);
        int rc_cpu = tpk_render_cpu(&mesh, &opt, img, NULL, &cpu);
        int rc_vk = tpk_render_vulkan(&mesh, &opt, img, NULL, &vk);
        printf("%-26s %s\n", bad_cases[c].what, check.message);
        CHECK_MSG(rc_check == -1 && rc_cpu == -1 && rc_vk == -1, "%s: check %d, cpu %d, vulkan %d (%s)",
                  bad_cases[c].what, rc_check, rc_cpu, rc_vk, vk.message);
        CHECK_MSG(strstr(check.message, bad_cases[c].expect) != NULL, "%s: '%s' lacks '%s'", bad_cases[c].what,
                  check.message, bad_cases[c].expect);
        CHECK_MSG(!strcmp(cpu.message, check.message) && !strcmp(vk.message, check.message),
                  "%s: check '%s', cpu '%s', vulkan '%s'", bad_cases[c].what, check.message, cpu.message, vk.message);
    }
    free(img);
    tpk_close(file);
}

/* What only the Vulkan renderer limits is refused by it alone, and says so. */
TPK_TEST(vulkan_limits_named)
{
    if (!have_device())
        return;
    tpk_mesh_arrays mesh;
    memset(&mesh, 0, sizeof mesh);
    mesh.vertex_count = 0x80000000u; /* refused before any array is read */
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    CHECK(tpk_tf_load("viridis", &tf, &diag) == 0);
    tpk_render_options opt;
    tpk_render_options_default(&opt);
    opt.width = opt.height = SIZE;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    tpk_camera_default(lo, hi, &opt.camera);
    opt.tf = &tf;
    uint8_t img[SIZE * SIZE * 4];
    CHECK(tpk_render_check_options(&opt, &diag) == 0);
    CHECK(tpk_render_vulkan(&mesh, &opt, img, NULL, &diag) == -1);
    CHECK_MSG(strstr(diag.message, "2^31 - 1") != NULL, "%s", diag.message);
    /* (--occlusion vertex is no longer a Vulkan limit: render_vk_effects.point_field_effects draws it) */
}
