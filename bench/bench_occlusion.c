/* Effects speed against error (bench/report part 1b): shading + shadows + AO with the secondary rays at
 * every pixel's shade points (--occlusion ray, the reference), at the mesh vertices, interpolated
 * (--occlusion vertex; render.h OCCLUSION AT VERTICES), and once per pixel at its first shade point
 * (--occlusion surface; render.h OCCLUSION AT THE SURFACE: the scene has no iso values).
 * usage: bench_occlusion FILE.tpk [size=128] [runs=3] [ao_rays=4] [threads=0 (all cores)]
 * Scene: bench_scene.h's field, TF and default camera (a headlight, so the cache is rebuilt every frame,
 * as it would be while the camera moves). One JSON line per mode: median wall ms per frame over `runs`
 * (the cache included), the cache alone (ms, one run), tet steps, secondary rays, and PSNR of the 8-bit
 * image against the ray mode's. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"
#include "bench_scene.h"
#include "render/render.h"

#define MAX_RUNS 31

int main(int argc, char **argv)
{
    if (argc < 2)
        return fprintf(stderr, "usage: bench_occlusion FILE.tpk [size] [runs] [ao_rays] [threads]\n"), 2;
    int size = argc > 2 ? atoi(argv[2]) : 128, runs = argc > 3 ? atoi(argv[3]) : 3;
    int ao = argc > 4 ? atoi(argv[4]) : 4, threads = argc > 5 ? atoi(argv[5]) : 0;
    if (size < 1 || size > 4096 || runs < 1 || runs > MAX_RUNS || ao < 0 || ao > TPK_RENDER_MAX_AO_RAYS)
        return fprintf(stderr, "bench_occlusion: bad size, runs or AO rays\n"), 2;
    bench_scene_mesh m;
    if (bench_scene_open(&m, argv[1]) != 0)
        return 1;
    tpk_mesh_arrays a;
    if (tpk_load_arrays(m.file, TPK_LAYOUT_TET16, NULL, 0, &a) != TPK_OK &&
        tpk_load_arrays(m.file, TPK_LAYOUT_TET20, NULL, 0, &a) != TPK_OK &&
        tpk_load_arrays(m.file, TPK_LAYOUT_TET32, NULL, 0, &a) != TPK_OK)
        return fprintf(stderr, "%s: no layout loads\n", argv[1]), 1;
    a.scalars = m.scalars;
    tpk_render_options opt;
    memset(&opt, 0, sizeof opt);
    opt.width = opt.height = size;
    tpk_camera_default(m.info.bounds_min, m.info.bounds_max, &opt.camera);
    opt.tf = &m.tf;
    opt.range_min = m.range_min, opt.range_max = m.range_max;
    opt.threads = threads;
    opt.shading = opt.shadows = 1;
    opt.ao_rays = ao;
    size_t bytes = (size_t)size * (size_t)size * 4;
    uint8_t *ref = malloc(bytes), *img = malloc(bytes);
    float *cache = malloc(2 * sizeof *cache * (size_t)(a.vertex_count ? a.vertex_count : 1));
    if (!ref || !img || !cache)
        return fprintf(stderr, "bench_occlusion: out of memory\n"), 1;
    const char *names[3] = {"ray", "vertex", "surface"};
    for (int mode = 0; mode < 3; mode++) {
        opt.occlusion = mode == 0 ? TPK_OCCLUSION_RAY : mode == 1 ? TPK_OCCLUSION_VERTEX : TPK_OCCLUSION_SURFACE;
        double wall[MAX_RUNS];
        tpk_render_stats st;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        for (int r = 0; r < runs; r++) {
            double t0 = now();
            if (tpk_render_cpu(&a, &opt, mode == 0 ? ref : img, &st, &diag) != 0)
                return fprintf(stderr, "bench_occlusion: %s\n", diag.message), 1;
            wall[r] = (now() - t0) * 1e3;
        }
        double cache_ms = 0; /* the cache alone, once */
        tpk_render_stats cs;
        if (mode == 1 && tpk_render_vertex_cache(&a, &opt, cache, cache + a.vertex_count, &cs, &diag) == 0)
            cache_ms = cs.seconds * 1e3;
        printf("{\"mesh\":\"%s\",\"tets\":%llu,\"vertices\":%llu,\"size\":%d,\"ao_rays\":%d,\"runs\":%d,"
               "\"occlusion\":\"%s\",\"frame_ms\":%.2f,\"cache_ms\":%.2f,\"tet_steps\":%llu,\"secondary_rays\":%llu,"
               "\"psnr_vs_ray\":%.2f}\n",
               argv[1], (unsigned long long)a.tet_count, (unsigned long long)a.vertex_count, size, ao, runs, names[mode],
               bench_median(wall, runs), cache_ms, (unsigned long long)st.tet_steps,
               (unsigned long long)st.secondary_rays, mode == 0 ? 99.0 : bench_psnr(ref, img, bytes));
        fflush(stdout);
    }
    free(ref);
    free(img);
    free(cache);
    bench_scene_close(&m);
    return 0;
}
