/* The connectivity and shell checks (3xx + 4xx) on an in-memory N^3 grid: Kuhn tets (6 per cube, turned
 * positive) or hexahedra, jittered, optionally shuffled (points and cells in random order).
 * Usage: bench_check_topo N THREADS [tets|hex] [shuffle] [runs]. Prints wall and CPU seconds per run
 * and the peak RSS; the mesh arrays' size is printed for comparison. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "bench_clock.h"
#include "check/check.h"
#include "convert/pipeline.h"
#include "base/predicates.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static uint64_t next_random(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

static void shuffle_ids(int64_t *perm, int64_t n)
{
    for (int64_t i = 0; i < n; i++)
        perm[i] = i;
    for (int64_t i = n - 1; i > 0; i--) {
        int64_t j = (int64_t)(next_random() % (uint64_t)(i + 1)), t = perm[i];
        perm[i] = perm[j];
        perm[j] = t;
    }
}

static void make_points(tpk_mesh *m, int n, const int64_t *perm)
{
    int64_t s = n + 1;
    m->point_count = s * s * s;
    m->points = malloc(sizeof *m->points * 3 * (size_t)m->point_count);
    for (int64_t i = 0; i < m->point_count; i++) {
        int64_t g[3] = {i / (s * s), i / s % s, i % s};
        for (int k = 0; k < 3; k++)
            m->points[3 * perm[i] + k] = (double)g[k] + ((double)(next_random() >> 11) * 0x1p-53 - 0.5) * 0.3;
    }
}

static void make_cells(tpk_mesh *m, int n, int hex, const int64_t *pperm, const int64_t *cperm)
{
    static const int kuhn[6][4] = {{0, 4, 6, 7}, {0, 4, 5, 7}, {0, 2, 6, 7}, {0, 2, 3, 7}, {0, 1, 5, 7}, {0, 1, 3, 7}};
    static const int hex_corner[8] = {0, 4, 6, 2, 1, 5, 7, 3}; /* VTK order from corner bits x,y,z */
    int64_t s = n + 1, cubes = (int64_t)n * n * n, per = hex ? 1 : 6, nodes = hex ? 8 : 4;
    m->cell_count = cubes * per;
    m->cell_types = malloc((size_t)m->cell_count);
    m->cell_offsets = malloc(sizeof *m->cell_offsets * (size_t)(m->cell_count + 1));
    m->cell_conn = malloc(sizeof *m->cell_conn * (size_t)(m->cell_count * nodes));
    for (int64_t q = 0; q < cubes; q++) {
        int64_t i = q / ((int64_t)n * n), j = q / n % n, k = q % n, corner[8];
        for (int b = 0; b < 8; b++)
            corner[b] = pperm[((i + (b >> 2 & 1)) * s + j + (b >> 1 & 1)) * s + k + (b & 1)];
        for (int t = 0; t < per; t++) {
            int64_t c = cperm[q * per + t];
            int32_t *v = m->cell_conn + nodes * c;
            for (int a = 0; a < nodes; a++)
                v[a] = (int32_t)corner[hex ? hex_corner[a] : kuhn[t][a]];
            const double *p0 = m->points + 3 * v[0], *p1 = m->points + 3 * v[1];
            const double *p2 = m->points + 3 * v[2], *p3 = m->points + 3 * v[3];
            int sign = hex ? 1 : tpk_orient3d_filter(p0, p1, p2, p3);
            if (sign == 0)
                sign = tpk_orient3d_exact(p0, p1, p2, p3);
            if (sign < 0) {
                int32_t x = v[2];
                v[2] = v[3];
                v[3] = x;
            }
            m->cell_types[c] = hex ? TPK_CELL_HEXAHEDRON : TPK_CELL_TETRA;
        }
    }
    for (int64_t c = 0; c <= m->cell_count; c++)
        m->cell_offsets[c] = nodes * c;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: bench_check_topo N THREADS [tets|hex] [shuffle] [runs]\n");
        return 2;
    }
    int n = atoi(argv[1]), threads = atoi(argv[2]);
    int hex = argc > 3 && !strcmp(argv[3], "hex"), shuffle = argc > 4 && !strcmp(argv[4], "shuffle");
    int runs = argc > 5 ? atoi(argv[5]) : 3;
    tpk_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    int64_t points = (int64_t)(n + 1) * (n + 1) * (n + 1), cells = (int64_t)n * n * n * (hex ? 1 : 6);
    int64_t *pperm = malloc(sizeof *pperm * (size_t)points), *cperm = malloc(sizeof *cperm * (size_t)cells);
    for (int64_t i = 0; i < points; i++)
        pperm[i] = i;
    for (int64_t i = 0; i < cells; i++)
        cperm[i] = i;
    if (shuffle) {
        shuffle_ids(pperm, points);
        shuffle_ids(cperm, cells);
    }
    make_points(&mesh, n, pperm);
    make_cells(&mesh, n, hex, pperm, cperm);
    free(pperm);
    free(cperm);
    double mb = (double)(24 * mesh.point_count + 9 * mesh.cell_count + 8 + 4 * mesh.cell_offsets[mesh.cell_count]) / 1e6;
    printf("%lld %s%s, %lld points, mesh arrays %.0f MB, %d threads\n", (long long)mesh.cell_count,
           hex ? "hexahedra" : "tets", shuffle ? " (shuffled)" : "", (long long)mesh.point_count, mb, threads);
    for (int r = 0; r < runs; r++) {
        tpk_check_options options;
        tpk_check_options_default(&options);
        options.threads = threads;
        tpk_check_report report;
        tpk_check_report_init(&report, &options);
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        tpk_check_input in = {&mesh, "grid", NULL};
        double t0 = now(), c0 = cpu_now();
        int rc = tpk_check_topology(&in, &report, &diag);
        double wall = now() - t0, used = cpu_now() - c0;
        int64_t problems = 0;
        for (int i = 0; i < report.finding_count; i++)
            problems += report.findings[i].check->severity == TPK_SEV_ERROR ? report.findings[i].count : 0;
        struct rusage u;
        getrusage(RUSAGE_SELF, &u);
        printf("run %d: rc %d, %.3f s wall, %.3f s cpu, %lld components, %lld error items, peak RSS %ld MB\n", r,
               rc, wall, used, (long long)report.component_count, (long long)problems, u.ru_maxrss / 1024);
        tpk_check_report_free(&report);
    }
    tpk_mesh_free(&mesh);
    return 0;
}
