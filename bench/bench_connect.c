/* Pipeline stage timings on a generated grid: N^3 cubes, Kuhn split (6 tets each; N = 119 gives
 * 10.1M tets), with shuffled vertex ids, tet order and vertex order inside tets.
 * Usage: bench_connect [N] [runs]. Prints the median of `runs` for orient, reorder, connect (1 and 2
 * threads, before and after reorder), layouts and shell. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_clock.h"
#include "../tests/meshgen.h"
#include "convert/pipeline.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return v[n / 2];
}

/* Call after median(): the sorted array's first element. */
static double fastest(const double *v)
{
    return v[0];
}

static void copy_mesh(const tpk_tetmesh *src, tpk_tetmesh *dst)
{
    *dst = *src;
    dst->points = malloc(sizeof *dst->points * 3 * (size_t)src->vertex_count);
    dst->vertex_source = malloc(sizeof *dst->vertex_source * (size_t)src->vertex_count);
    dst->tets = malloc(sizeof *dst->tets * 4 * (size_t)src->tet_count);
    dst->tet_source = malloc(sizeof *dst->tet_source * (size_t)src->tet_count);
    memcpy(dst->points, src->points, sizeof *dst->points * 3 * (size_t)src->vertex_count);
    memcpy(dst->vertex_source, src->vertex_source, sizeof *dst->vertex_source * (size_t)src->vertex_count);
    memcpy(dst->tets, src->tets, sizeof *dst->tets * 4 * (size_t)src->tet_count);
    memcpy(dst->tet_source, src->tet_source, sizeof *dst->tet_source * (size_t)src->tet_count);
}

static double time_connect(const tpk_tetmesh *m, int32_t *nb, int threads, int runs, double *best,
                           double *cpu)
{
    double t[16], c[16];
    tpk_diag diag = {0};
    for (int r = 0; r < runs; r++) {
        double start = now(), cpu_start = cpu_now();
        if (tpk_connect(m->tets, m->tet_count, m->vertex_count, nb, threads, &diag)) {
            fprintf(stderr, "connect: %s\n", diag.message);
            exit(1);
        }
        t[r] = now() - start;
        c[r] = cpu_now() - cpu_start;
    }
    double mid = median(t, runs);
    *best = fastest(t);
    *cpu = median(c, runs);
    return mid;
}

int main(int argc, char **argv)
{
    int n = argc > 1 ? atoi(argv[1]) : 119;
    int runs = argc > 2 ? atoi(argv[2]) : 3;
    if (runs < 1 || runs > 16 || n < 1)
        return 2;
    tpk_gen_options opt = {1e-3, {6.4e6, 4.9e6, 100}, 1, 1, 1, 42};
    tpk_tetmesh base;
    if (tpk_gen_kuhn_grid(n, &opt, &base))
        return 1;
    double mt = (double)base.tet_count * 1e-6;
    printf("grid %d^3 cubes: %lld tets, %lld vertices, median of %d runs\n", n, (long long)base.tet_count,
           (long long)base.vertex_count, runs);
    double t_orient[16], t_reorder[16];
    tpk_tetmesh m;
    tpk_diag diag = {0};
    for (int r = 0; r < runs; r++) {
        copy_mesh(&base, &m);
        tpk_orient_stats stats;
        double start = now();
        if (tpk_orient(&m, 0, 0, &stats, &diag)) {
            fprintf(stderr, "orient: %s\n", diag.message);
            return 1;
        }
        t_orient[r] = now() - start;
        start = now();
        if (tpk_reorder(&m, 0, &diag)) {
            fprintf(stderr, "reorder: %s\n", diag.message);
            return 1;
        }
        t_reorder[r] = now() - start;
        if (r + 1 < runs)
            tpk_tetmesh_free(&m);
    }
    double mid = median(t_orient, runs);
    printf("orient  (all cores): median %.3f s (%.1f M tets/s), fastest %.3f s\n", mid, mt / mid, fastest(t_orient));
    mid = median(t_reorder, runs);
    printf("reorder (all cores): median %.3f s (%.1f M tets/s), fastest %.3f s\n", mid, mt / mid, fastest(t_reorder));
    int32_t *nb = malloc(sizeof *nb * 4 * (size_t)m.tet_count);
    for (int threads = 1; threads <= 2; threads++) {
        double best, cpu, t = time_connect(&base, nb, threads, runs, &best, &cpu);
        printf("connect, input order,   %d thread%s: median %.3f s (%.1f M tets/s), fastest %.3f s (%.1f M tets/s), "
               "CPU %.3f s\n", threads, threads > 1 ? "s" : "", t, mt / t, best, mt / best, cpu);
        t = time_connect(&m, nb, threads, runs, &best, &cpu);
        printf("connect, Hilbert order, %d thread%s: median %.3f s (%.1f M tets/s), fastest %.3f s (%.1f M tets/s), "
               "CPU %.3f s\n", threads, threads > 1 ? "s" : "", t, mt / t, best, mt / best, cpu);
    }
    double start = now();
    tpk_tet32 *t32 = malloc(sizeof *t32 * (size_t)m.tet_count);
    tpk_tet20 *t20 = malloc(sizeof *t20 * (size_t)m.tet_count);
    tpk_tet16 *t16 = malloc(sizeof *t16 * (size_t)m.tet_count);
    tpk_build_tet32(m.tets, nb, m.tet_count, t32);
    tpk_build_tet20(m.tets, nb, m.tet_count, t20);
    tpk_build_tet16(m.tets, nb, m.tet_count, t16);
    double t_layouts = now() - start;
    start = now();
    int64_t shell_count = tpk_count_shell_faces(nb, m.tet_count);
    tpk_shell_face *shell = malloc(sizeof *shell * (size_t)shell_count);
    tpk_build_shell(m.tets, nb, m.tet_count, shell);
    double t_shell = now() - start;
    printf("layouts (32+20+16, 1 thread): %.3f s; shell (1 thread): %.3f s, %lld faces\n", t_layouts, t_shell,
           (long long)shell_count);
    free(t32);
    free(t20);
    free(t16);
    free(shell);
    free(nb);
    tpk_tetmesh_free(&m);
    tpk_tetmesh_free(&base);
    return 0;
}
