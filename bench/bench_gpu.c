/* The GPU benchmark's measuring program (bench/gpu/run.sh drives it): per layout in FILE, one Vulkan
 * renderer set up once (device, upload, pipeline, first frame, timed apart), then per effect set (E+A,
 * each effect alone, all together) the median frame time, wall and GPU (timestamp queries), tet steps
 * per second, device bytes per tet and the PSNR of the picture against the CPU reference's (same
 * options, all cores; TPK_GPU_PSNR=0 skips the reference). One JSON line per layout and effect set.
 * Effect set `iso_raster` (Tet16 only: it reads positions and values, no layout): render --iso-raster of
 * the field's mid-range value, opaque, shaded, at TPK_GPU_ISO_SIZE (WxH, default 3840x2160), by the
 * device's path (task and mesh shaders where it has VK_EXT_mesh_shader), against the CPU's ray-marched
 * isosurface (a TF transparent everywhere); tet_steps counts the tets classified.
 * usage: bench_gpu FILE.tpk NAME [size=1024] [frames=10] [effects=ea,shading,shadows,ao4,all,iso_raster] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "render_vk/render_vk.h"
#include "tetpack.h"

/* An effect set by name: ea, shading, shadows, ao4 (AO with 4 rays), all. */
static int set_effects(tpk_render_options *opt, const char *name)
{
    opt->shading = !strcmp(name, "shading") || !strcmp(name, "all");
    opt->shadows = !strcmp(name, "shadows") || !strcmp(name, "all");
    opt->ao_rays = !strcmp(name, "ao4") || !strcmp(name, "all") ? 4 : 0;
    return strcmp(name, "ea") && !opt->shading && !opt->shadows && !opt->ao_rays ? -1 : 0;
}

typedef struct bench_run {
    const char *mesh, *layout;
    int frames;
    uint8_t *vk, *cpu;
} bench_run;

/* One effect set on a renderer that exists: first frame (its pipeline compiled), then `frames` more. */
static int bench_effect(tpk_vk_renderer *r, const tpk_mesh_arrays *mesh, tpk_render_options *opt, const char *effect,
                        const bench_run *b, double setup_s, const tpk_render_stats *setup)
{
    tpk_diag diag = {0};
    tpk_render_stats st;
    double t0 = now();
    if (tpk_vk_renderer_frame(r, opt, b->vk, &st, &diag) != 0) {
        fprintf(stderr, "vulkan: %s\n", diag.message);
        return -1;
    }
    double first = now() - t0, wall[256], gpu[256];
    for (int f = 0; f < b->frames; f++) {
        if (tpk_vk_renderer_frame(r, opt, b->vk, &st, &diag) != 0) {
            fprintf(stderr, "vulkan: %s\n", diag.message);
            return -1;
        }
        wall[f] = st.seconds;
        gpu[f] = st.gpu_seconds;
    }
    double wall_s = bench_median(wall, b->frames), gpu_s = bench_median(gpu, b->frames), db = -1, cpu_s = -1;
    const char *no_psnr = getenv("TPK_GPU_PSNR");
    if (!(no_psnr && !strcmp(no_psnr, "0"))) {
        tpk_render_stats cs;
        if (tpk_render_cpu(mesh, opt, b->cpu, &cs, &diag) != 0) {
            fprintf(stderr, "cpu: %s\n", diag.message);
            return -1;
        }
        db = bench_psnr(b->cpu, b->vk, (size_t)opt->width * (size_t)opt->height * 4);
        cpu_s = cs.seconds;
    }
    double per_s = (double)st.tet_steps / (gpu_s > 0 ? gpu_s : wall_s);
    printf("{\"mesh\":\"%s\",\"layout\":\"%s\",\"tets\":%llu,\"effect\":\"%s\",\"size\":%d,\"frames\":%d,"
           "\"device\":\"%s\",\"setup_s\":%.4f,\"setup\":{\"device\":%.4f,\"upload\":%.4f,\"pipeline\":%.4f,"
           "\"pipeline_cache_bytes\":%llu},\"first_frame_s\":%.4f,\"frame_wall_s\":%.5f,\"frame_gpu_s\":%.5f,"
           "\"tet_steps\":%llu,\"secondary_rays\":%llu,\"tet_steps_per_s\":%.4g,\"device_bytes\":%llu,"
           "\"device_bytes_per_tet\":%.2f,\"cpu_frame_s\":%.4f,\"psnr_db\":%.1f}\n",
           b->mesh, b->layout, (unsigned long long)mesh->tet_count, effect, opt->width, b->frames,
           tpk_vk_renderer_device(r), setup_s, setup->setup_device_seconds, setup->setup_upload_seconds,
           setup->setup_pipeline_seconds, (unsigned long long)setup->pipeline_cache_bytes, first, wall_s, gpu_s,
           (unsigned long long)st.tet_steps, (unsigned long long)st.secondary_rays, per_s,
           (unsigned long long)st.device_bytes, (double)st.device_bytes / (double)(mesh->tet_count ? mesh->tet_count : 1),
           cpu_s, db);
    fflush(stdout);
    return 0;
}

/* The isosurface rasterizer (render --iso-raster) on its own device: set up once (device, upload,
 * pipeline, the value's extraction or count), then `frames` frames of one value. */
static int bench_iso_raster(const tpk_mesh_arrays *mesh, const tpk_render_options *base, const bench_run *b)
{
    if (!mesh->scalars) {
        fprintf(stderr, "bench_gpu: iso_raster: %s has no point field\n", b->mesh);
        return 0;
    }
    tpk_render_options opt = *base;
    const char *size = getenv("TPK_GPU_ISO_SIZE");
    int w = 3840, h = 2160;
    if (size && sscanf(size, "%dx%d", &w, &h) != 2)
        w = 3840, h = 2160;
    w = w < 1 ? 1 : w > 8192 ? 8192 : w, h = h < 1 ? 1 : h > 8192 ? 8192 : h;
    opt.width = w, opt.height = h;
    double lo = INFINITY, hi = -INFINITY;
    for (uint64_t i = 0; i < mesh->vertex_count; i++)
        if (!isnan(mesh->scalars[i])) {
            lo = mesh->scalars[i] < lo ? mesh->scalars[i] : lo;
            hi = mesh->scalars[i] > hi ? mesh->scalars[i] : hi;
        }
    if (!(lo <= hi))
        return 0;
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    if (tpk_tf_parse("iso only", "0 0.2 0.4 0.9 0\n1 0.9 0.2 0.1 0\n", &tf, &diag) != 0) { /* opacity 0 */
        fprintf(stderr, "bench_gpu: %s\n", diag.message);
        return -1;
    }
    opt.tf = &tf;
    opt.range_min = lo, opt.range_max = hi;
    opt.iso_count = 1, opt.iso[0] = 0.5 * (lo + hi);
    opt.shading = 1, opt.shadows = 0, opt.ao_rays = 0;
    size_t n = 4 * (size_t)w * (size_t)h;
    uint8_t *vk = malloc(n), *cpu = malloc(n);
    tpk_iso_raster *ra = NULL;
    tpk_render_stats st;
    double t0 = now(), first = 0, wall[256], gpu[256];
    int rc = vk && cpu && tpk_iso_raster_create(&ra, mesh, &diag) == 0 && tpk_iso_raster_frame(ra, &opt, vk, &st, &diag) == 0
                 ? 0
                 : -1;
    double setup_s = now() - t0;
    for (int f = 0; f < b->frames && rc == 0; f++) {
        t0 = now();
        rc = tpk_iso_raster_frame(ra, &opt, vk, &st, &diag);
        wall[f] = now() - t0, gpu[f] = st.gpu_seconds;
        first = f == 0 ? wall[0] : first;
    }
    double db = -1, cpu_s = -1;
    const char *no_psnr = getenv("TPK_GPU_PSNR");
    if (rc == 0 && !(no_psnr && !strcmp(no_psnr, "0"))) {
        tpk_render_stats cs;
        rc = tpk_render_cpu(mesh, &opt, cpu, &cs, &diag);
        db = bench_psnr(cpu, vk, n);
        cpu_s = cs.seconds;
    }
    if (rc == 0) {
        double wall_s = bench_median(wall, b->frames), gpu_s = bench_median(gpu, b->frames);
        printf("{\"mesh\":\"%s\",\"layout\":\"%s\",\"tets\":%llu,\"effect\":\"iso_raster %dx%d, %s\",\"size\":%d,"
               "\"frames\":%d,\"device\":\"%s\",\"setup_s\":%.4f,\"setup\":{\"device\":0,\"upload\":0,\"pipeline\":0,"
               "\"pipeline_cache_bytes\":0},\"first_frame_s\":%.4f,\"frame_wall_s\":%.5f,\"frame_gpu_s\":%.5f,"
               "\"tet_steps\":%llu,\"secondary_rays\":0,\"tet_steps_per_s\":%.4g,\"device_bytes\":0,"
               "\"device_bytes_per_tet\":0,\"cpu_frame_s\":%.4f,\"psnr_db\":%.1f,\"iso_triangles\":%llu,"
               "\"iso_path\":\"%s\"}\n",
               b->mesh, b->layout, (unsigned long long)mesh->tet_count, w, h,
               st.iso_mesh_shader == 1 ? "task and mesh shaders" : "compute + indirect draw", opt.width, b->frames,
               tpk_iso_raster_device(ra), setup_s, first, wall_s, gpu_s, (unsigned long long)mesh->tet_count,
               (double)mesh->tet_count / (gpu_s > 0 ? gpu_s : wall_s), cpu_s, db,
               (unsigned long long)st.iso_triangles, st.iso_mesh_shader == 1 ? "mesh" : "compute");
        fflush(stdout);
    } else
        fprintf(stderr, "bench_gpu: iso_raster: %s\n", diag.message);
    tpk_iso_raster_destroy(ra);
    free(vk);
    free(cpu);
    return rc;
}

static int bench_layout(tpk_file *file, tpk_layout layout, const char *layout_name, tpk_render_options *opt,
                        const char *effects, bench_run *b)
{
    tpk_mesh_arrays mesh;
    if (tpk_load_arrays(file, layout, NULL, 0, &mesh) != TPK_OK)
        return 0; /* layout not in the file */
    b->layout = layout_name;
    tpk_diag diag = {0};
    tpk_vk_renderer *r = NULL;
    double t0 = now();
    tpk_render_stats setup;
    set_effects(opt, "ea");
    if (tpk_vk_renderer_create(&r, &mesh, NULL, &diag) != 0 || tpk_vk_renderer_frame(r, opt, b->vk, &setup, &diag) != 0) {
        fprintf(stderr, "vulkan: %s\n", diag.message);
        tpk_vk_renderer_destroy(r);
        return -1;
    }
    double setup_s = now() - t0; /* device, upload, pipeline and the first frame */
    char list[256];
    snprintf(list, sizeof list, "%s", effects);
    int rc = 0;
    for (char *save = NULL, *e = strtok_r(list, ",", &save); e && rc == 0; e = strtok_r(NULL, ",", &save)) {
        if (!strcmp(e, "iso_raster")) {
            if (layout == TPK_LAYOUT_TET16)
                rc = bench_iso_raster(&mesh, opt, b);
        } else if (set_effects(opt, e) != 0) {
            fprintf(stderr, "bench_gpu: unknown effect set '%s' (ea, shading, shadows, ao4, all, iso_raster)\n", e);
            rc = -1;
        } else
            rc = bench_effect(r, &mesh, opt, e, b, setup_s, &setup);
    }
    tpk_vk_renderer_destroy(r);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: bench_gpu FILE.tpk NAME [size=1024] [frames=10] "
                        "[effects=ea,shading,shadows,ao4,all,iso_raster]\n");
        return 2;
    }
    int size = argc > 3 ? atoi(argv[3]) : 1024, frames = argc > 4 ? atoi(argv[4]) : 10;
    const char *effects = argc > 5 ? argv[5] : "ea,shading,shadows,ao4,all";
    frames = frames < 1 ? 1 : frames > 256 ? 256 : frames;
    size = size < 1 ? 1 : size > 8192 ? 8192 : size;
    char msg[512];
    tpk_file *file = NULL;
    if (tpk_open_path(&file, argv[1], NULL, msg, sizeof msg) != TPK_OK) {
        fprintf(stderr, "%s: %s\n", argv[1], msg);
        return 2;
    }
    tpk_file_info info;
    tpk_get_info(file, &info);
    tpk_transfer_function tf;
    tpk_diag diag = {0};
    tpk_tf_load("viridis", &tf, &diag);
    tpk_render_options opt;
    tpk_render_options_default(&opt);
    opt.width = opt.height = size;
    opt.threads = 0; /* the CPU reference on every core */
    opt.tf = &tf;
    opt.range_min = 0;
    opt.range_max = 1;
    tpk_camera_default(info.bounds_min, info.bounds_max, &opt.camera);
    size_t n = (size_t)size * (size_t)size * 4;
    bench_run b = {argv[2], NULL, frames, malloc(n), malloc(n)};
    int rc = b.vk && b.cpu ? 0 : -1;
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    static const char *const names[3] = {"tet16", "tet20", "tet32"};
    for (int l = 0; l < 3 && rc == 0; l++)
        rc = bench_layout(file, layouts[l], names[l], &opt, effects, &b);
    free(b.vk);
    free(b.cpu);
    tpk_close(file);
    return rc == 0 ? 0 : 1;
}
