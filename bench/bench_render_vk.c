/* Benchmark of the Vulkan renderer against the CPU reference on the same mesh, in one run: per layout,
 * the median frame time and tet steps per second of each (E+A, exact integration, default camera),
 * the Vulkan setup time (device, upload, pipeline) apart, and whether the pictures agree. Besides wall
 * time, the process CPU time of each frame (lavapipe's worker threads are in this process): on a shared,
 * loaded machine the ratio of steps per CPU second is the steadier comparison.
 * usage: bench_render_vk FILE.tpk [size=512] [frames=5] [cpu threads=2]
 * Set LP_NUM_THREADS to the same thread count for lavapipe (bench/bench_render_vk.sh does). One JSON line
 * per layout. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"
#include "render/render.h"
#include "render/transfer_function.h"
#include "render_vk/render_vk.h"
#include "tetpack.h"

/* Median CPU frame seconds over `frames` renders; steps of the last. */
static int bench_cpu(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, int frames, uint8_t *img,
                     double *seconds, double *cpu_seconds, uint64_t *steps)
{
    double t[64], c[64];
    for (int f = 0; f < frames; f++) {
        tpk_render_stats st;
        tpk_diag diag = {0};
        double c0 = cpu_now();
        if (tpk_render_cpu(mesh, opt, img, &st, &diag) != 0) {
            fprintf(stderr, "cpu: %s\n", diag.message);
            return -1;
        }
        c[f] = cpu_now() - c0;
        t[f] = st.seconds;
        *steps = st.tet_steps;
    }
    *seconds = bench_median(t, frames);
    *cpu_seconds = bench_median(c, frames);
    return 0;
}

static int bench_vulkan(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, int frames, uint8_t *img,
                        double *setup, double *seconds, double *cpu_seconds, uint64_t *steps, char *device,
                        size_t device_size)
{
    tpk_diag diag = {0};
    tpk_vk_renderer *r = NULL;
    double t0 = now();
    if (tpk_vk_renderer_create(&r, mesh, NULL, &diag) != 0) {
        fprintf(stderr, "vulkan: %s\n", diag.message);
        return -1;
    }
    tpk_render_stats st;
    int rc = tpk_vk_renderer_frame(r, opt, img, &st, &diag); /* the first frame compiles nothing more, but warms */
    *setup = now() - t0;
    double t[64], c[64];
    for (int f = 0; f < frames && rc == 0; f++) {
        double c0 = cpu_now();
        rc = tpk_vk_renderer_frame(r, opt, img, &st, &diag);
        c[f] = cpu_now() - c0; /* lavapipe's threads are ours: their CPU time counts */
        t[f] = st.seconds;
        *steps = st.tet_steps;
    }
    if (rc != 0)
        fprintf(stderr, "vulkan: %s\n", diag.message);
    else {
        *seconds = bench_median(t, frames);
        *cpu_seconds = bench_median(c, frames);
    }
    snprintf(device, device_size, "%s", tpk_vk_renderer_device(r));
    tpk_vk_renderer_destroy(r);
    return rc;
}

static int bench_layout(tpk_file *file, tpk_layout layout, const char *name, tpk_render_options *opt, int frames)
{
    tpk_mesh_arrays mesh;
    if (tpk_load_arrays(file, layout, NULL, 0, &mesh) != TPK_OK)
        return 0; /* layout not in the file */
    size_t n = (size_t)opt->width * (size_t)opt->height * 4;
    uint8_t *a = malloc(n), *b = malloc(n);
    double cpu_s = 0, vk_s = 0, vk_setup = 0, cpu_c = 0, vk_c = 0;
    uint64_t cpu_steps = 0, vk_steps = 0;
    char device[256] = "";
    int rc = -1;
    if (a && b && bench_cpu(&mesh, opt, frames, a, &cpu_s, &cpu_c, &cpu_steps) == 0 &&
        bench_vulkan(&mesh, opt, frames, b, &vk_setup, &vk_s, &vk_c, &vk_steps, device, sizeof device) == 0) {
        printf("{\"layout\":\"%s\",\"tets\":%llu,\"size\":%d,\"frames\":%d,\"cpu_threads\":%d,"
               "\"cpu_frame_s\":%.4f,\"cpu_steps_per_s\":%.4g,\"vulkan_device\":\"%s\",\"vulkan_setup_s\":%.3f,"
               "\"vulkan_frame_s\":%.4f,\"vulkan_steps_per_s\":%.4g,\"speedup\":%.2f,\"tet_steps\":[%llu,%llu],"
               "\"cpu_cpu_s\":%.4f,\"vulkan_cpu_s\":%.4f,\"speedup_per_cpu_s\":%.2f,\"psnr_db\":%.1f}\n",
               name, (unsigned long long)mesh.tet_count, opt->width, frames, opt->threads, cpu_s,
               (double)cpu_steps / cpu_s, device, vk_setup, vk_s, (double)vk_steps / vk_s,
               ((double)vk_steps / vk_s) / ((double)cpu_steps / cpu_s), (unsigned long long)cpu_steps,
               (unsigned long long)vk_steps, cpu_c, vk_c, ((double)vk_steps / vk_c) / ((double)cpu_steps / cpu_c),
               bench_psnr(a, b, n));
        fflush(stdout);
        rc = 0;
    }
    free(a);
    free(b);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_render_vk FILE.tpk [size=512] [frames=5] [cpu threads=2]\n");
        return 2;
    }
    int size = argc > 2 ? atoi(argv[2]) : 512, frames = argc > 3 ? atoi(argv[3]) : 5;
    int threads = argc > 4 ? atoi(argv[4]) : 2;
    frames = frames < 1 ? 1 : frames > 64 ? 64 : frames;
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
    opt.threads = threads;
    opt.tf = &tf;
    opt.range_min = 0;
    opt.range_max = 1;
    tpk_camera_default(info.bounds_min, info.bounds_max, &opt.camera);
    /* no early termination in a thin volume: every ray walks through the mesh */
    opt.unit_distance = 1e3 * sqrt(pow(info.bounds_max[0] - info.bounds_min[0], 2) +
                                   pow(info.bounds_max[1] - info.bounds_min[1], 2) +
                                   pow(info.bounds_max[2] - info.bounds_min[2], 2));
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    static const char *const names[3] = {"tet16", "tet20", "tet32"};
    int rc = 0;
    for (int l = 0; l < 3 && rc == 0; l++)
        rc = bench_layout(file, layouts[l], names[l], &opt, frames);
    tpk_close(file);
    return rc == 0 ? 0 : 1;
}
