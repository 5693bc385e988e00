/* Rendering speed against image error, per layout and integration method (bench/report part 1).
 * usage: bench_render_error FILE.tpk [size=384] [runs=3] [threads=0 (all cores)]
 * FILE.tpk should hold the three layouts (convert --layout tet16 --layout tet20 --layout tet32). The scene
 * is bench_scene.h's (analytic field, two-peak TF, default camera). The reference is BI_REFERENCE (Gauss-
 * Legendre, optical depth 0.1 per interval, no early termination); its own convergence is printed
 * against depth 0.02 with at least 4 intervals per part. Methods: midpoint, exact (render's scheme), fixed steps of 2, 1, 1/2, 1/4 and 1/8
 * unit distances, all stopping at transmittance 1e-3 (and exact once without stopping); then `tpk_render_cpu` itself (8-bit output, stops
 * at 98% opacity) with integration exact and sampled. One JSON line per layout and method: median wall
 * ms per frame over `runs` (wall, and CPU of all threads), tet steps, steps/s, RMSE and PSNR against the reference (premultiplied RGBA
 * in [0,1]), and whether the image equals the first layout's bit for bit. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_clock.h"
#include "bench_scene.h"

#define MAX_RUNS 31

typedef struct method_row {
    const char *name;
    bi_method method;
    double step_units; /* BI_STEP: step in unit distances */
    int render_cpu;    /* -1: ours; 0/1: tpk_render_cpu with that integration */
} method_row;

/* tpk_render_cpu's 8-bit straight-alpha image back to premultiplied floats. */
static void to_premultiplied(const uint8_t *rgba, size_t pixels, float *out)
{
    for (size_t i = 0; i < pixels; i++) {
        double a = rgba[4 * i + 3] / 255.0;
        for (int k = 0; k < 3; k++)
            out[4 * i + k] = (float)(rgba[4 * i + k] / 255.0 * a);
        out[4 * i + 3] = (float)a;
    }
}

/* One timed frame of a row; returns wall seconds, *cpu the process CPU seconds (all threads: steadier on
 * a loaded machine), the image in img. */
static double frame(const bi_scene *sc, const tpk_mesh_arrays *arrays, const bench_scene_mesh *m, const method_row *row,
                    int threads, float *img, uint8_t *bytes, uint64_t *steps, int *failed, double *cpu)
{
    size_t pixels = (size_t)sc->width * (size_t)sc->height;
    double c0 = cpu_now();
    if (row->render_cpu < 0) {
        double t0 = now();
        *failed = bi_render(sc, &row->method, threads, img, steps);
        double t = now() - t0;
        *cpu = cpu_now() - c0;
        return t;
    }
    tpk_render_options opt;
    memset(&opt, 0, sizeof opt); /* transparent background, as ours */
    opt.width = sc->width, opt.height = sc->height;
    tpk_camera_default(m->info.bounds_min, m->info.bounds_max, &opt.camera);
    opt.tf = &m->tf;
    opt.range_min = m->range_min, opt.range_max = m->range_max;
    opt.unit_distance = 1.0 / sc->inv_unit;
    opt.threads = threads;
    opt.integration = row->render_cpu;
    tpk_render_stats st;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    double t0 = now();
    *failed = tpk_render_cpu(arrays, &opt, bytes, &st, &diag) != 0;
    double t = now() - t0;
    *cpu = cpu_now() - c0;
    *steps = st.tet_steps;
    to_premultiplied(bytes, pixels, img);
    return t;
}

int main(int argc, char **argv)
{
    if (argc < 2)
        return fprintf(stderr, "usage: bench_render_error FILE.tpk [size] [runs] [threads]\n"), 2;
    int size = argc > 2 ? atoi(argv[2]) : 384, runs = argc > 3 ? atoi(argv[3]) : 3;
    int threads = argc > 4 ? atoi(argv[4]) : 0;
    if (size < 8 || runs < 1 || runs > MAX_RUNS)
        return fprintf(stderr, "bench_render_error: size >= 8, 1 <= runs <= %d\n", MAX_RUNS), 2;
    if (threads <= 0)
        threads = (int)sysconf(_SC_NPROCESSORS_ONLN);
    bench_scene_mesh m;
    if (bench_scene_open(&m, argv[1]) != 0)
        return 1;
    size_t pixels = (size_t)size * (size_t)size;
    float *ref = malloc(4 * pixels * sizeof(float)), *img = malloc(4 * pixels * sizeof(float));
    float *first = malloc(4 * pixels * sizeof(float) * 16);
    uint8_t *bytes = malloc(4 * pixels);
    if (!ref || !img || !first || !bytes)
        return fprintf(stderr, "bench_render_error: out of memory\n"), 1;
    double unit = bench_diagonal(&m.info) / 100.0;
    method_row rows[16];
    int nrows = 0;
    rows[nrows++] = (method_row){"midpoint", {BI_MIDPOINT, 0, 0, 1e-3, 0}, 0, -1};
    rows[nrows++] = (method_row){"exact", {BI_EXACT, 0, 0.05, 1e-3, 0}, 0, -1};
    /* the same without early termination: what the stop costs in error and saves in tet steps */
    rows[nrows++] = (method_row){"exact, no stop", {BI_EXACT, 0, 0.05, 0, 0}, 0, -1};
    const double steps_units[5] = {2, 1, 0.5, 0.25, 0.125};
    for (int i = 0; i < 5; i++)
        rows[nrows++] = (method_row){"step", {BI_STEP, steps_units[i] * unit, 0, 1e-3, 0}, steps_units[i], -1};
    rows[nrows++] = (method_row){"render exact", {0, 0, 0, 0, 0}, 0, 0};
    rows[nrows++] = (method_row){"render sampled", {0, 0, 0, 0, 0}, 0.5, 1};

    const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    int have_first = 0;
    for (int l = 0; l < 3; l++) {
        tpk_mesh_arrays arrays;
        if (tpk_load_arrays(m.file, layouts[l], NULL, 0, &arrays) != TPK_OK)
            continue; /* layout not stored */
        arrays.scalars = m.scalars;
        tpk_marcher *marcher;
        if (tpk_marcher_create(&marcher, &arrays) != TPK_OK)
            return fprintf(stderr, "bench_render_error: marcher\n"), 1;
        bi_scene sc;
        bench_scene_setup(&sc, &m, marcher, size, size);
        if (!have_first) { /* the reference, and how far it is from a finer one */
            bi_method refm = {BI_REFERENCE, 0, 0.1, 0, 1}, finer = {BI_REFERENCE, 0, 0.02, 0, 4};
            uint64_t steps;
            double t0 = now();
            int failed = bi_render(&sc, &refm, threads, ref, &steps);
            double t_ref = now() - t0;
            bi_render(&sc, &finer, threads, img, NULL);
            double mx, rmse = bi_rmse(ref, img, pixels, &mx);
            printf("{\"bench\":\"render_reference\",\"file\":\"%s\",\"tets\":%llu,\"width\":%d,\"height\":%d,"
                   "\"unit_distance\":%.6g,\"threads\":%d,\"ms\":%.1f,\"failed_rays\":%d,"
                   "\"rmse_vs_finer\":%.3e,\"max_abs_vs_finer\":%.3e}\n",
                   argv[1], (unsigned long long)m.info.tet_count, size, size, unit, threads, t_ref * 1e3, failed,
                   rmse, mx);
            fflush(stdout);
        }
        for (int r = 0; r < nrows; r++) {
            double times[MAX_RUNS], cpus[MAX_RUNS];
            uint64_t steps = 0;
            int failed = 0;
            for (int k = 0; k < runs; k++)
                times[k] = frame(&sc, &arrays, &m, &rows[r], threads, img, bytes, &steps, &failed, &cpus[k]);
            qsort(times, (size_t)runs, sizeof times[0], bench_compare_double);
            qsort(cpus, (size_t)runs, sizeof cpus[0], bench_compare_double);
            double t = times[runs / 2], cpu = cpus[runs / 2], mx, rmse = bi_rmse(ref, img, pixels, &mx);
            float *mine = first + 4 * pixels * (size_t)r;
            int same = 1;
            if (!have_first)
                memcpy(mine, img, 4 * pixels * sizeof(float));
            else
                same = memcmp(mine, img, 4 * pixels * sizeof(float)) == 0;
            printf("{\"bench\":\"render_error\",\"layout\":\"tet%d\",\"method\":\"%s\",\"step_units\":%g,"
                   "\"ms_per_frame\":%.2f,\"cpu_ms_per_frame\":%.2f,\"tet_steps\":%llu,\"msteps_per_s\":%.3f,\"rmse\":%.4e,\"psnr\":%.2f,"
                   "\"max_abs\":%.3e,\"failed\":%d,\"same_as_first_layout\":%s}\n",
                   (int)layouts[l], rows[r].name, rows[r].step_units, t * 1e3, cpu * 1e3, (unsigned long long)steps,
                   (double)steps / t * 1e-6, rmse, fmin(bi_psnr(rmse), 999.0), mx, failed, same ? "true" : "false");
            fflush(stdout);
        }
        have_first = 1;
        tpk_marcher_destroy(marcher);
    }
    free(ref), free(img), free(first), free(bytes);
    bench_scene_close(&m);
    return have_first ? 0 : 1;
}
