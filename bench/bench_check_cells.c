/* Time of the cells group of `tetpack check` (tpk_check_cells) on a generated grid, in memory:
 *   bench_check_cells tets N THREADS [shuffle]  -- N^3 cubes, 6 Kuhn tets each (N = 119: 10.1M tets)
 *   bench_check_cells hexes N THREADS [shuffle] -- N^3 hexahedra
 * Points are jittered (no two tets alike); `shuffle` relabels vertices and shuffles cells (no locality). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_clock.h"
#include "../tests/meshgen.h"
#include "check/check.h"

static void jitter(double *points, int64_t count, double amount, uint64_t seed)
{
    for (int64_t i = 0; i < 3 * count; i++)
        points[i] += amount * ((double)(tpk_gen_next(&seed) >> 11) / 9007199254740992.0 - 0.5);
}

static int tets_mesh(int n, int shuffle, tpk_mesh *out)
{
    tpk_gen_options opt = {.relabel = shuffle, .shuffle_tets = shuffle, .seed = 7};
    tpk_tetmesh tm;
    if (tpk_gen_kuhn_grid(n, &opt, &tm))
        return -1;
    memset(out, 0, sizeof *out);
    out->point_count = tm.vertex_count;
    out->points = tm.points;
    tm.points = NULL;
    out->cell_count = tm.tet_count;
    out->cell_conn = tm.tets;
    tm.tets = NULL;
    out->cell_types = malloc((size_t)out->cell_count);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(out->cell_count + 1));
    tpk_tetmesh_free(&tm);
    if (!out->cell_types || !out->cell_offsets)
        return -1;
    memset(out->cell_types, TPK_CELL_TETRA, (size_t)out->cell_count);
    for (int64_t c = 0; c <= out->cell_count; c++)
        out->cell_offsets[c] = 4 * c;
    return 0;
}

static int hexes_mesh(int n, int shuffle, tpk_mesh *out)
{
    int64_t side = n + 1, cells = (int64_t)n * n * n;
    memset(out, 0, sizeof *out);
    out->point_count = side * side * side;
    out->cell_count = cells;
    out->points = malloc(sizeof *out->points * 3 * (size_t)out->point_count);
    out->cell_conn = malloc(sizeof *out->cell_conn * 8 * (size_t)cells);
    out->cell_types = malloc((size_t)cells);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(cells + 1));
    if (!out->points || !out->cell_conn || !out->cell_types || !out->cell_offsets)
        return -1;
    for (int64_t v = 0; v < out->point_count; v++) {
        out->points[3 * v] = (double)(v / (side * side));
        out->points[3 * v + 1] = (double)(v / side % side);
        out->points[3 * v + 2] = (double)(v % side);
    }
    static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (int64_t c = 0; c < cells; c++) {
        int64_t i = c / ((int64_t)n * n), j = c / n % n, k = c % n;
        for (int q = 0; q < 8; q++)
            out->cell_conn[8 * c + q] =
                (int32_t)(((i + corner[q][0]) * side + j + corner[q][1]) * side + k + corner[q][2]);
        out->cell_offsets[c] = 8 * c;
    }
    out->cell_offsets[cells] = 8 * cells;
    memset(out->cell_types, TPK_CELL_HEXAHEDRON, (size_t)cells);
    (void)shuffle;
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: bench_check_cells tets|hexes N THREADS [shuffle]\n");
        return 2;
    }
    int n = atoi(argv[2]), threads = atoi(argv[3]), shuffle = argc > 4 && !strcmp(argv[4], "shuffle");
    int hexes = !strcmp(argv[1], "hexes");
    tpk_mesh mesh;
    if ((hexes ? hexes_mesh(n, shuffle, &mesh) : tets_mesh(n, shuffle, &mesh))) {
        fprintf(stderr, "bench_check_cells: out of memory\n");
        return 1;
    }
    jitter(mesh.points, mesh.point_count, hexes ? 0.05 : 0.3, 11); /* hexes: warps of a few degrees */
    tpk_check_options opt;
    tpk_check_options_default(&opt);
    opt.threads = threads;
    tpk_check_report report;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_check_report_init(&report, &opt))
        return 1;
    tpk_check_input in = {.mesh = &mesh, .path = "generated"};
    double t0 = now(), c0 = cpu_now();
    int rc = tpk_check_cells(&in, &report, &diag);
    double t1 = now(), c1 = cpu_now();
    int64_t found = 0;
    for (int i = 0; i < report.finding_count; i++)
        found += report.findings[i].check->id / 100 == 2 ? report.findings[i].count : 0;
    printf("%s: %lld cells, %lld points, %d threads%s: cells group %.3f s wall, %.3f s cpu, %lld findings (rc %d)\n",
           argv[1], (long long)mesh.cell_count, (long long)mesh.point_count, threads, shuffle ? ", shuffled" : "",
           t1 - t0, c1 - c0, (long long)found, rc);
    tpk_check_print_text(&report, stdout);
    tpk_check_report_free(&report);
    tpk_mesh_free(&mesh);
    return rc ? 1 : 0;
}
