/* One frame of tetpack render (the backend, --legend, the PNG, the report) and the scene it used; for
 * cmd_render.c and render_set.c (part sets). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/strbuf.h"
#include "cli.h"
#include "render/budget.h"
#include "render/legend.h"
#include "render/render.h"
#include "render_frame.h"
#include "scene/scene.h"
#include "tetpack.h"
#ifdef TPK_WITH_VULKAN
#include "render_vk/render_vk.h"
#endif

void render_session_end(render_session *session)
{
    tpk_vertex_cache_destroy(session->cache);
#ifdef TPK_WITH_VULKAN
    tpk_vk_renderer_destroy(session->vk);
#endif
    memset(session, 0, sizeof *session);
}

#ifdef TPK_WITH_VULKAN
/* A frame on the session's Vulkan renderer: made for these arrays, or handed this frame's field. Its
 * seconds include what this frame set up, as tpk_render_vulkan's do. */
static int session_vulkan(render_session *s, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                          uint8_t *rgba, tpk_render_stats *stats, tpk_diag *diag)
{
    double t0 = tpk_now_seconds();
    if (s->vk && !tpk_render_same_mesh(&s->vk_mesh, mesh)) {
        tpk_vk_renderer_destroy(s->vk);
        s->vk = NULL;
    }
    if (!s->vk) {
        if (tpk_vk_renderer_create(&s->vk, mesh, opt->tet_scalars, diag) != 0) {
            s->vk = NULL;
            return -1;
        }
    } else if ((s->vk_mesh.scalars != mesh->scalars || s->vk_tet_scalars != opt->tet_scalars) &&
               tpk_vk_renderer_set_field(s->vk, mesh->scalars, opt->tet_scalars, diag) != 0) {
        tpk_vk_renderer_destroy(s->vk); /* what the device holds is unknown: made again next time */
        s->vk = NULL;
        return -1;
    }
    s->vk_mesh = *mesh;
    s->vk_tet_scalars = opt->tet_scalars;
    int rc = tpk_vk_renderer_frame(s->vk, opt, rgba, stats, diag);
    if (stats)
        stats->seconds = tpk_now_seconds() - t0;
    return rc;
}
#endif

int render_image(const render_args *a, const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                 render_session *session, tpk_render_stats *stats, tpk_diag *diag)
{
    (void)a; /* without Vulkan, the CPU reference whatever the arguments say */
#ifdef TPK_WITH_VULKAN
    if (!strcmp(a->backend, "vulkan"))
        return a->iso_raster ? tpk_render_iso_raster(mesh, opt, rgba, stats, diag)
               : session    ? session_vulkan(session, mesh, opt, rgba, stats, diag)
                            : tpk_render_vulkan(mesh, opt, rgba, stats, diag);
#endif
    if (!session)
        return tpk_render_cpu(mesh, opt, rgba, stats, diag);
    if (!session->cache) {
        if (!(session->cache = tpk_vertex_cache_create()))
            return tpk_diag_fail(diag, "render: out of memory for the renderer's cache");
        tpk_vertex_cache_frames_per_field(session->cache, 1); /* a session draws each step once */
    }
    return tpk_render_cpu_cached(mesh, opt, rgba, session->cache, stats, diag);
}

double render_frame_seconds(const render_args *a, const tpk_render_stats *stats)
{
    (void)a;
    return stats->gpu_seconds > 0 ? stats->gpu_seconds : stats->seconds;
}

int render_frame(const render_args *a, const frame_source *src, const tpk_render_options *opt, const char *output,
                 uint8_t *rgba)
{
    tpk_render_stats stats;
    return render_frame_stats(a, src, opt, output, rgba, &stats);
}

int render_frame_stats(const render_args *a, const frame_source *src, const tpk_render_options *opt,
                       const char *output, uint8_t *rgba, tpk_render_stats *out)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_render_stats stats;
    memset(&stats, 0, sizeof stats);
    memset(out, 0, sizeof *out);
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
    /* a pixel step d > 1 (--max-ms): the frame drawn at about 1/d of the size, then brought to it */
    tpk_render_options small = *opt;
    uint8_t *drawn = rgba;
    if (!src->set && src->pixel_step > 1) {
        tpk_pixel_step_size(opt->width, opt->height, src->pixel_step, &small.width, &small.height);
        drawn = malloc((size_t)small.width * (size_t)small.height * 4);
        if (!drawn)
            return tpk_cli_fail("render", "out of memory for a %dx%d image", small.width, small.height);
    }
    int failed = src->set ? tpk_render_cpu_set(src->set, src->has_scalars, src->diagonal, opt, rgba, &stats, &diag)
                          : render_image(a, src->mesh, &small, drawn, src->session, &stats, &diag);
    if (!failed && drawn != rgba) {
        double t0 = tpk_now_seconds();
        if (tpk_image_upscale(drawn, small.width, small.height, rgba, opt->width, opt->height) != 0) {
            free(drawn);
            return tpk_cli_fail("render", "out of memory for a %dx%d image", opt->width, opt->height);
        }
        double upscale = tpk_now_seconds() - t0; /* part of the frame */
        stats.seconds += upscale;
        stats.gpu_seconds += stats.gpu_seconds > 0 ? upscale : 0;
    }
    if (drawn != rgba)
        free(drawn);
    if (failed)
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
        if (stats.vertex_cache_seconds > 0) /* --occlusion vertex: the casts of this frame */
            printf(",\"vertex_cache_seconds\":%.6f", stats.vertex_cache_seconds);
        if (!vulkan)
            printf(",\"seconds_rays\":%.6f,\"cpu_seconds_rays\":%.6f", stats.seconds_rays, stats.cpu_seconds_rays);
        if (src->level > 0 || src->budget > 0) {
            printf(",\"level\":%d,\"level_tets\":%lld", src->level, (long long)src->level_tets);
            char rms[32] = "null"; /* META's null: the field has NaNs */
            if (!isnan(src->error_rms))
                snprintf(rms, sizeof rms, "%.9g", src->error_rms);
            if (src->level > 0 && !isnan(src->error_max))
                printf(",\"level_error\":{\"max\":%.9g,\"rms\":%s,\"shell_distance\":%.9g}", src->error_max, rms,
                       isnan(src->shell_distance) ? 0 : src->shell_distance);
            else
                printf(",\"level_error\":%s",
                       src->level == 0 ? "{\"max\":0,\"rms\":0,\"shell_distance\":0}" : "null");
        }
        if (src->budget > 0)
            printf(",\"max_ms\":%.6g,\"predicted_ms\":%.6g,\"frame_ms\":%.6g,\"pixel_step\":%d", src->budget * 1e3,
                   src->predicted * 1e3, render_frame_seconds(a, &stats) * 1e3,
                   src->pixel_step > 1 ? src->pixel_step : 1);
        if (a->iso_raster) {
            char why[160];
            snprintf(why, sizeof why, "VK_EXT_mesh_shader present, not used%s%s",
                     stats.iso_mesh_reason ? ": " : "", stats.iso_mesh_reason ? stats.iso_mesh_reason : "");
            printf(",\"iso_raster\":{\"triangles\":%llu,\"draw_gpu_seconds\":",
                   (unsigned long long)stats.iso_triangles);
            if (stats.iso_draw_gpu_seconds >= 0)
                printf("%.6f", stats.iso_draw_gpu_seconds);
            else
                printf("null");
            const char *path = stats.iso_raster_compute ? (stats.iso_raster_atomics == 64
                                                                ? "compute rasterizer, 64-bit atomics"
                                                                : "compute rasterizer, 32-bit atomics")
                               : stats.iso_mesh_shader == 1 ? "task and mesh shaders"
                                                            : "compute extraction + indirect draw";
            printf(",\"path\":\"%s\",\"mesh_shader\":\"%s\"", path,
                   stats.iso_mesh_shader == 1 ? "VK_EXT_mesh_shader used" : stats.iso_mesh_shader == 2 ? why
                                                                                  : "VK_EXT_mesh_shader absent");
            /* --iso-raster-path auto: both draws' device times, as measured on this frame or an earlier one */
            printf(",\"choice\":\"%s\"", a->iso_raster_path != TPK_ISO_RASTER_AUTO ? "--iso-raster-path"
                                           : stats.iso_raster_note                  ? stats.iso_raster_note
                                           : stats.iso_raster_measured             ? "measured on this frame"
                                                                                   : "measured on an earlier frame");
            if (stats.iso_raster_seconds[0] >= 0 && stats.iso_raster_seconds[1] >= 0)
                printf(",\"measured_seconds\":{\"graphics\":%.6f,\"compute\":%.6f}", stats.iso_raster_seconds[0],
                       stats.iso_raster_seconds[1]);
            printf("}");
        }
        tpk_strbuf reason = {0};
        tpk_strbuf_json_string(&reason, src->set ? "a part set renders with the CPU reference" : a->backend_reason);
        printf(",\"backend_reason\":%s}\n", reason.data ? reason.data : "\"\"");
        tpk_strbuf_free(&reason);
    } else
        printf("%s: %dx%d, %llu rays, %llu secondary rays, %llu tet steps, %.3f s\n", output, a->width, a->height,
               (unsigned long long)stats.rays, (unsigned long long)stats.secondary_rays,
               (unsigned long long)stats.tet_steps, stats.seconds);
    *out = stats;
    return TPK_EXIT_OK;
}

int render_save_scene(const render_args *a, tpk_file *file, const tpk_render_options *opt)
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
