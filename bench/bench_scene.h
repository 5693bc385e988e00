/* The scene the rendering benchmarks share (bench_render_error.c, bench_storage.c): a .tpk opened with
 * libtetpack, an analytic scalar over its positions (so every mesh, real or generated, gets the same
 * smooth field with structure at several scales), a transfer function with two narrow opacity peaks
 * (where integration methods differ most), the render's default camera and unit distance. */
#ifndef TPK_BENCH_SCENE_H
#define TPK_BENCH_SCENE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_integrate.h"

/* s r g b a: a blue haze, a yellow peak at 0.3 and a red one at 0.7, white at the top. */
static const char bench_tf_text[] = "0.00 0.10 0.20 0.80 0.00\n"
                                    "0.20 0.10 0.50 0.90 0.04\n"
                                    "0.30 0.95 0.90 0.20 0.60\n"
                                    "0.36 0.20 0.80 0.30 0.02\n"
                                    "0.60 0.90 0.40 0.10 0.08\n"
                                    "0.70 1.00 0.10 0.10 0.80\n"
                                    "0.76 0.80 0.80 0.80 0.04\n"
                                    "1.00 1.00 1.00 1.00 0.20\n";

typedef struct bench_scene_mesh {
    tpk_file *file;
    tpk_file_info info;
    float *scalars;          /* the analytic field, per vertex */
    double range_min, range_max;
    tpk_transfer_function tf;
} bench_scene_mesh;

/* s = sin(3 pi x) cos(2 pi y) + z + 0.3 sin(9 pi (x + y)), with x, y, z the position in the bounds
 * scaled to [0, 1], computed in double from the stored float32 positions plus the origin. */
static inline double bench_field(const double u[3])
{
    return sin(3 * M_PI * u[0]) * cos(2 * M_PI * u[1]) + u[2] + 0.3 * sin(9 * M_PI * (u[0] + u[1]));
}

static inline int bench_scene_open(bench_scene_mesh *m, const char *path)
{
    memset(m, 0, sizeof *m);
    char err[512];
    if (tpk_open_path(&m->file, path, NULL, err, sizeof err) != TPK_OK)
        return fprintf(stderr, "%s: %s\n", path, err), -1;
    tpk_get_info(m->file, &m->info);
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_tf_parse("bench peaks", bench_tf_text, &m->tf, &diag) != 0)
        return fprintf(stderr, "%s\n", diag.message), -1;
    tpk_mesh_arrays a;
    tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    int found = 0;
    for (int l = 0; l < 3 && !found; l++)
        found = tpk_load_arrays(m->file, layouts[l], NULL, 0, &a) == TPK_OK;
    if (!found)
        return fprintf(stderr, "%s: no layout loads: %s\n", path, tpk_error_text(m->file)), -1;
    m->scalars = malloc(sizeof(float) * (size_t)(a.vertex_count ? a.vertex_count : 1));
    if (!m->scalars)
        return -1;
    m->range_min = INFINITY, m->range_max = -INFINITY;
    for (uint64_t v = 0; v < a.vertex_count; v++) {
        double u[3];
        for (int k = 0; k < 3; k++) {
            double ext = m->info.bounds_max[k] - m->info.bounds_min[k];
            u[k] = ext > 0 ? (a.origin[k] + a.positions[3 * v + k] - m->info.bounds_min[k]) / ext : 0.5;
        }
        m->scalars[v] = (float)bench_field(u);
        m->range_min = fmin(m->range_min, m->scalars[v]);
        m->range_max = fmax(m->range_max, m->scalars[v]);
    }
    return 0;
}

static inline void bench_scene_close(bench_scene_mesh *m)
{
    free(m->scalars);
    tpk_close(m->file);
    memset(m, 0, sizeof *m);
}

static inline double bench_diagonal(const tpk_file_info *info)
{
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (info->bounds_max[k] - info->bounds_min[k]) * (info->bounds_max[k] - info->bounds_min[k]);
    return sqrt(d2);
}

/* A scene over `marcher` with the render's defaults: camera framing the bounds, unit = diagonal / 100. */
static inline void bench_scene_setup(bi_scene *sc, const bench_scene_mesh *m, const tpk_marcher *marcher, int width,
                                     int height)
{
    memset(sc, 0, sizeof *sc);
    sc->marcher = marcher;
    sc->tf = &m->tf;
    sc->range_min = m->range_min;
    sc->inv_range = m->range_max > m->range_min ? 1.0 / (m->range_max - m->range_min) : 0;
    sc->inv_unit = 100.0 / bench_diagonal(&m->info);
    sc->width = width;
    sc->height = height;
    tpk_camera cam;
    tpk_camera_default(m->info.bounds_min, m->info.bounds_max, &cam);
    bi_scene_camera(sc, &cam);
}

#endif
