/* tetpack render: a .tpk to PNG (emission-absorption and the effects of render.h) with the CPU reference
 * or the Vulkan renderer, one image or one per time step, or a part set's image; the options are parsed
 * by render_args.c (shared with tetpack view). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "cli.h"
#include "render/render.h"
#include "render/budget.h"
#include "render/level_set.h"
#include "render/render_backend.h"
#include "scene/scene.h"
#include "tetpack.h"
#include "render/transfer_function.h"
#include "render_args.h"
#include "render_frame.h"
#include "render_input.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

static const char render_help[] =
    "usage: tetpack render FILE -o IMAGE.png [options]\n"
    "\n"
    "FILE is a .tpk, a part set's manifest (.tpkset, convert --parts: its parts drawn as the one mesh\n"
    "they were cut from), or any mesh tetpack convert reads (tetpack formats), converted in memory first.\n"
    "Ray-marches the tets (shell BVH entry, watertight tet-to-tet marching) with the Vulkan renderer on\n"
    "a GPU, else with the CPU reference on all cores (--backend), and writes a PNG. Both draw the same\n"
    "picture. Emission-absorption: within a tet the scalar is linear, so each piece is split exactly\n"
    "where the scalar crosses a TF control point; color and extinction\n"
    "are then linear in distance and are integrated in steps of optical depth <= 0.05.\n"
    "\n"; /* then the options, from the option table (render_args_help) */

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

/* The field values of one step: point scalars into mesh, or a tet field into opt->tet_scalars; and the
 * file's culling blocks (spec §17), if it has them, into *cull and opt->cull. */
static int load_step(const render_args *a, tpk_file *file, int tet_field, int step, tpk_mesh_arrays *mesh,
                     tpk_render_options *opt, tpk_cull *cull)
{
    tpk_layout layout = render_args_layout(file, a->layout);
    tpk_result r = tpk_load_arrays(file, layout, tet_field ? NULL : a->field, (uint32_t)step, mesh);
    if (r == TPK_OK && tet_field) {
        mesh->scalars = NULL; /* the tet field replaces any point field */
        r = tpk_load_tet_field(file, a->field, (uint32_t)step, &opt->tet_scalars);
    }
    opt->cull = NULL;
    if (r == TPK_OK && cull)
        r = tpk_render_use_cull(file, cull, opt);
    return r == TPK_OK ? 0 : tpk_cli_fail_file("render", a->path, tpk_error_text(file));
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

/* The backend of this render (render/render_backend.h: --backend, the scene's, $TETPACK_RENDER_BACKEND,
 * else Vulkan on a hardware device and the CPU reference otherwise); a->device gets the device's name
 * ("cpu" for the reference) and a->backend_reason why. Returns 0 or -1 with a message. */
static int resolve_backend(render_args *a, tpk_diag *diag)
{
    tpk_backend_request req = {.flag = a->backend_from_scene ? NULL : a->backend,
                               .scene = a->backend_from_scene ? a->backend : NULL,
                               .env = getenv("TETPACK_RENDER_BACKEND"),
                               .vulkan_only = a->iso_raster};
#ifdef TPK_WITH_VULKAN
    req.vulkan_built = 1;
    int kind = TPK_VK_DEVICE_NONE;
    if (tpk_backend_needs_device(&req))
        tpk_vulkan_probe(a->device, sizeof a->device, &kind);
    req.device = (tpk_vk_device_kind)kind;
    req.device_name = a->device;
#endif
    tpk_backend_choice choice;
    if (tpk_backend_choose(&req, &choice, diag) != 0)
        return -1;
    if (choice.scene_fallback)
        fprintf(stderr, "tetpack render: note: %s asks for the Vulkan backend; no Vulkan device here, so the CPU "
                "reference renders it (the same picture)\n", a->scene_path);
    a->backend = choice.vulkan ? "vulkan" : "cpu";
    snprintf(a->backend_reason, sizeof a->backend_reason, "%s", choice.reason);
    if (!choice.vulkan)
        snprintf(a->device, sizeof a->device, "cpu");
    if (a->verbose)
        fprintf(stderr, "tetpack render: backend %s (%s): %s\n", a->backend, a->device, a->backend_reason);
    return 0;
}

/* ---- Levels of detail (spec §16): --level K and --max-ms T ------------------------------------------ */

static int open_levels(const render_args *a, tpk_file *file, tpk_level_set *ls)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_level_set_open(ls, file, a->path, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
    if (a->level >= ls->count)
        return tpk_cli_fail("render", "%s: no level %d: the file has %d level%s of detail (convert --levels N makes "
                            "them; tetpack info lists them)", a->path, a->level, ls->count - 1, ls->count == 2 ? "" : "s");
    return 0;
}

/* --max-ms: the cost model's first frames, the coarsest level at an eighth and a quarter of the size (at
 * least 16 pixels a side): two sizes, so the fit tells a frame's fixed cost from its cost per ray. */
static int fit_on_probe(const render_args *a, const tpk_level_set *ls, int tet_field, const tpk_render_options *opt,
                        tpk_cost_model *model)
{
    int k = ls->count - 1;
    for (int div = 8; div >= 4; div /= 2) {
        tpk_render_options small = *opt;
        small.width = a->width / div > 16 ? a->width / div : (a->width < 16 ? a->width : 16);
        small.height = a->height / div > 16 ? a->height / div : (a->height < 16 ? a->height : 16);
        tpk_mesh_arrays mesh;
        if (load_step(a, ls->files[k], tet_field, a->step, &mesh, &small, NULL))
            return TPK_EXIT_USAGE;
        uint8_t *rgba = malloc((size_t)small.width * (size_t)small.height * 4);
        tpk_render_stats stats;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        memset(&stats, 0, sizeof stats);
        int rc = rgba && render_image(a, &mesh, &small, rgba, NULL, &stats, &diag) == 0 ? 0 : -1;
        free(rgba);
        if (rc != 0)
            return tpk_cli_fail_file("render", a->path, diag.message[0] ? diag.message : "out of memory");
        tpk_cost_model_add(model, (double)small.width * small.height, (double)ls->tets[k],
                           render_frame_seconds(a, &stats));
    }
    return 0;
}

static int render_file(render_args *a, tpk_file *file)
{
    int association;
    if (render_args_check_field("render", a, file, &association))
        return TPK_EXIT_USAGE;
    char name[80];
    uint32_t steps = render_args_field_steps(file, a->field, name);
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
    tpk_field_desc field;
    int have_field = render_args_field_desc(file, a->field, &field) == 0;
    double iso_auto = NAN;
    if (a->iso_auto && render_args_iso_auto("render", a, file, &opt, &iso_auto))
        return TPK_EXIT_USAGE;
    if (a->iso_auto && a->verbose)
        fprintf(stderr, "tetpack render: --iso auto: %.9g, the median of '%s' at step %d\n", iso_auto, field.name,
                a->step);
    tpk_level_set ls;
    if (open_levels(a, file, &ls)) {
        tpk_level_set_close(&ls);
        return TPK_EXIT_USAGE;
    }
    tpk_cost_model model = {0};
    int rc = a->max_ms > 0 ? fit_on_probe(a, &ls, association == TPK_ASSOC_TET, &opt, &model) : TPK_EXIT_OK;
    uint8_t *rgba = rc == TPK_EXIT_OK ? malloc((size_t)a->width * (size_t)a->height * 4) : NULL;
    if (rc == TPK_EXIT_OK && !rgba)
        rc = tpk_cli_fail("render", "out of memory for a %dx%d image", a->width, a->height);
    /* Several steps keep the renderer's set-up from one to the next (render_session: the CPU reference's
     * marcher, whose shell BVH a frame would otherwise build again, or the Vulkan device and arrays),
     * and hand it each step's field. The pictures are those of one step at a time
     * (tests/cli/render_effects.sh, render_vk_iso_culling.sh). */
    render_session session = {0};
    tpk_cull cull; /* views into the file, which outlives the frames */
    for (int step = a->step; step <= a->step_last && rc == TPK_EXIT_OK; step++) {
        char path[4096];
        tpk_mesh_arrays mesh;
        double pixels = (double)a->width * a->height, budget = a->max_ms / 1e3;
        /* the camera, range and unit distance are the full mesh's (opt): every level shows the same view */
        int k = a->max_ms > 0 ? tpk_level_set_choose(&ls, &model, pixels, budget) : a->level;
        int d = a->max_ms > 0 ? tpk_cost_model_pixel_step(&model, pixels, (double)ls.tets[k], budget, a->max_pixel_step)
                              : 1;
        int drawn_w, drawn_h; /* the rays cast */
        tpk_pixel_step_size(a->width, a->height, d, &drawn_w, &drawn_h);
        if (frame_path(a, step, path, sizeof path))
            rc = tpk_cli_fail("render", "-o: the image path of step %d is too long", step);
        if (rc == TPK_EXIT_OK)
            rc = load_step(a, ls.files[k], association == TPK_ASSOC_TET, step, &mesh, &opt, &cull);
        frame_source src = {.mesh = &mesh, .field = have_field ? &field : NULL, .iso_auto = iso_auto, .level = k,
                            .level_tets = ls.tets[k], .error_max = ls.error_max[k], .error_rms = ls.error_rms[k],
                            .shell_distance = ls.shell_distance[k],
                            .budget = a->max_ms > 0 ? budget : 0,
                            .predicted = tpk_cost_model_predict(&model, (double)drawn_w * drawn_h,
                                                                (double)ls.tets[k]),
                            .pixel_step = d, .session = a->step_last > a->step ? &session : NULL};
        if (rc == TPK_EXIT_OK && a->verbose && (a->max_ms > 0 || k > 0))
            fprintf(stderr, "tetpack render: level %d (%lld tets)%s\n", k, (long long)ls.tets[k],
                    a->max_ms > 0 ? ", the finest the cost model fits in --max-ms" : "");
        if (rc == TPK_EXIT_OK && a->verbose && d > 1)
            fprintf(stderr, "tetpack render: pixel step %d (%dx%d rays, interpolated to %dx%d): the coarsest level "
                    "at every pixel does not fit in --max-ms\n", d, drawn_w, drawn_h, a->width, a->height);
        tpk_render_stats stats;
        if (rc == TPK_EXIT_OK)
            rc = render_frame_stats(a, &src, &opt, path, rgba, &stats);
        if (rc == TPK_EXIT_OK && a->max_ms > 0) /* the model learns from every frame drawn */
            tpk_cost_model_add(&model, (double)drawn_w * drawn_h, (double)ls.tets[k], render_frame_seconds(a, &stats));
    }
    render_session_end(&session);
    free(rgba);
    tpk_level_set_close(&ls);
    if (rc == TPK_EXIT_OK && a->save_scene && render_save_scene(a, file, &opt) != 0)
        return TPK_EXIT_USAGE;
    return rc;
}

/* Every output (each frame with --steps) against the inputs, before any work. */
static int check_outputs(const render_args *a)
{
    /* A --tf that names a file is read too (a preset name names none: stat fails, nothing matches). */
    tpk_output_input inputs[4] = {{.arg = "FILE.tpk", .given = a->path}};
    size_t count = 1;
    if (a->save_tpk && tpk_cli_check_convert_output("render", "--save-tpk", a->path, NULL, a->save_tpk))
        return TPK_EXIT_USAGE;
    if (a->save_tpk)
        inputs[count++] = (tpk_output_input){.arg = "--save-tpk", .given = a->save_tpk};
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

int tpk_cmd_render(int argc, char **argv)
{
    render_args a;
    render_args_default(&a);
    if (render_args_merge_scene("render", argc, argv, &a))
        return TPK_EXIT_USAGE;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(render_help, stdout);
            render_args_help(stdout);
            return TPK_EXIT_OK;
        }
        int rc = render_args_parse_option("render", argc, argv, &i, &a);
        if (rc)
            return rc;
    }
    if (!a.path || !a.output)
        return tpk_cli_fail("render", "expected FILE and -o IMAGE.png (see tetpack render --help)");
    if (check_outputs(&a))
        return TPK_EXIT_USAGE;
    render_input in;
    if (render_input_open("render", a.path, a.save_tpk, a.threads, &in))
        return TPK_EXIT_USAGE;
    if (in.converted && a.verbose)
        fprintf(stderr, "tetpack render: converted %s with convert's defaults: %lld tets in %.3f s, %s\n", a.path,
                in.tets, in.convert_seconds, in.tpk_path ? in.tpk_path : "in memory (--save-tpk FILE keeps it)");
    uint64_t part_chunk;
    if (tpk_find_chunk(in.file, TPK_TAG_PART, 0, 0, &part_chunk) == TPK_OK) { /* a part set's manifest */
        render_input_close(&in);
        if (a.level > 0 || a.max_ms > 0) /* convert makes levels of one file only (--levels and --parts) */
            return tpk_cli_fail("render", "%s: a part set has no levels of detail: %s draws a single file's",
                                a.path, a.level > 0 ? "--level" : "--max-ms");
        tpk_diag backend_diag;
        memset(&backend_diag, 0, sizeof backend_diag);
        if (resolve_backend(&a, &backend_diag) != 0)
            return tpk_cli_fail("render", "%s", backend_diag.message);
        return render_part_set(&a);
    }
    int rc = render_file(&a, in.file);
    render_input_close(&in);
    return rc;
}
