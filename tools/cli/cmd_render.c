/* tetpack render: a .tpk to PNG (emission-absorption and the effects of render.h) with the CPU reference
 * or the Vulkan renderer, one image or one per time step, or a part set's image; the options are parsed
 * by render_args.c (shared with tetpack view). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "base/strbuf.h"
#include "cli.h"
#include "render/render.h"
#include "render/legend.h"
#include "render/render_backend.h"
#include "scene/scene.h"
#include "tetpack.h"
#include "render/transfer_function.h"
#include "render_args.h"
#include "render_input.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

static const char render_help[] =
    "usage: tetpack render FILE -o IMAGE.png [options]\n"
    "\n"
    "FILE is a .tpk, or any mesh tetpack convert reads (tetpack formats), converted in memory first.\n"
    "Ray-marches the tets with the reference CPU marcher (shell BVH entry, watertight tet-to-tet\n"
    "marching) on all cores and writes a PNG. Emission-absorption: within a tet the scalar is linear,\n"
    "so each piece is split exactly where the scalar crosses a TF control point; color and extinction\n"
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
    const tpk_field_desc *field; /* the field shown (its name and units for --legend) */
    double iso_auto;  /* --iso auto's value (NAN: not asked) */
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
    if (a->iso_raster && (src->set || !vulkan))
        return tpk_cli_fail("render", "--iso-raster draws with Vulkan (a single file, --backend vulkan)%s",
#ifdef TPK_WITH_VULKAN
                            ""
#else
                            ": this tetpack was built without Vulkan (TETPACK_WITH_VULKAN=OFF)"
#endif
        );
    if ((src->set     ? tpk_render_cpu_set(src->set, src->has_scalars, src->diagonal, opt, rgba, &stats, &diag)
#ifdef TPK_WITH_VULKAN
         : a->iso_raster ? tpk_render_iso_raster(src->mesh, opt, rgba, &stats, &diag)
         : vulkan     ? tpk_render_vulkan(src->mesh, opt, rgba, &stats, &diag)
#endif
                      : tpk_render_cpu(src->mesh, opt, rgba, &stats, &diag)) != 0)
        return tpk_cli_fail_file("render", a->path, diag.message); /* e.g. bounds that are not finite */
    tpk_legend legend = {opt->tf, opt->range_min, opt->range_max, src->field ? src->field->name : NULL,
                         src->field ? src->field->units : NULL};
    if (a->legend && tpk_legend_draw(rgba, a->width, a->height, &legend, &diag) != 0)
        return tpk_cli_fail("render", "%s", diag.message);
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
        if (!isnan(src->iso_auto))
            printf(",\"iso_auto\":%.9g", src->iso_auto);
        printf(",\"iso_culling\":%s", stats.iso_culling ? "true" : "false");
        if (a->iso_raster)
            printf(",\"iso_raster\":{\"triangles\":%llu,\"path\":\"compute extraction + indirect draw\","
                   "\"mesh_shader\":\"%s\"}", (unsigned long long)stats.iso_triangles,
                   stats.iso_mesh_shader ? "VK_EXT_mesh_shader present, its path not written yet" : "VK_EXT_mesh_shader absent");
        tpk_strbuf reason = {0};
        tpk_strbuf_json_string(&reason, src->set ? "a part set renders with the CPU reference" : a->backend_reason);
        printf(",\"backend_reason\":%s}\n", reason.data ? reason.data : "\"\"");
        tpk_strbuf_free(&reason);
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
            rc = render_frame(a, &(frame_source){.mesh = &mesh, .field = have_field ? &field : NULL,
                                                 .iso_auto = iso_auto}, &opt, path, rgba);
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
    if (render_args_check_field("render", a, file, &association))
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
    render_args_field_range(file, a->field, range);
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
    if (!(a->unit_distance > 0)) /* the default scale of the whole set, not of part 0 */
        opt.unit_distance = render_args_default_unit(v->bounds_min, v->bounds_max);
    tpk_field_desc field;
    int have_field = render_args_field_desc(tpk_partset_file(set, 0), a->field, &field) == 0;
    if (have_field && !a->have_range)
        field.min_value = (float)v->range[0], field.max_value = (float)v->range[1];
    frame_source src = {.set = marcher, .has_scalars = v->has_scalars, .diagonal = sqrt(d2),
                        .field = have_field ? &field : NULL, .iso_auto = NAN};
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
    if (a->iso_auto)
        return tpk_cli_fail("render", "%s: --iso auto takes one file's median; for a part set give --iso V", a->path);
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
        return render_set(&a);
    }
    int rc = render_file(&a, in.file);
    render_input_close(&in);
    return rc;
}
