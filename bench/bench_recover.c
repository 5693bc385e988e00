/* tpk_recover_tets (the walk from the shell that recovers each tet's vertex order, issue 39) in process:
 * the file's Tet16 or Tet20 records loaded once, then N recoveries, timed by the wall clock and by the
 * process's CPU time (all threads); medians, in ns per tet. threads 1 calls tpk_recover_tets, more
 * tpk_recover_tets_threads (0: all cores). Built with -DBENCH_RECOVER_OLD it calls only tpk_recover_tets,
 * so that the same source times an older libtetpack. One JSON line.
 * Usage: bench_recover FILE.tpk [layout 16|20 (16)] [threads (1)] [runs (9)] */
#include <stdio.h>
#include <stdlib.h>

#include "bench_clock.h"
#include "tetpack.h"

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_recover FILE.tpk [layout 16|20] [threads] [runs]\n");
        return 2;
    }
    int layout = argc > 2 ? atoi(argv[2]) : 16, threads = argc > 3 ? atoi(argv[3]) : 1;
    int runs = bench_runs(argc, argv, 4, 9);
    if (layout != 16 && layout != 20) {
        fprintf(stderr, "layout: 16 or 20, not %d\n", layout);
        return 2;
    }
    tpk_file *f = bench_open_file(argv[1]);
    if (!f)
        return 2;
    tpk_mesh_arrays mesh;
    if (tpk_load_arrays(f, (tpk_layout)layout, NULL, 0, &mesh) != TPK_OK) {
        fprintf(stderr, "%s: no Tet%d layout\n", argv[1], layout);
        return 2;
    }
    int32_t *tets = malloc(16 * (size_t)(mesh.tet_count ? mesh.tet_count : 1));
    double *wall = calloc((size_t)runs, sizeof *wall), *cpu = calloc((size_t)runs, sizeof *cpu);
    if (!tets || !wall || !cpu)
        return 2;
    for (int r = 0; r < runs; r++) {
        double w0 = now(), c0 = cpu_now();
#ifdef BENCH_RECOVER_OLD
        tpk_result rc = tpk_recover_tets(&mesh, tets);
#else
        tpk_result rc = threads == 1 ? tpk_recover_tets(&mesh, tets) : tpk_recover_tets_threads(&mesh, tets, threads);
#endif
        wall[r] = now() - w0;
        cpu[r] = cpu_now() - c0;
        if (rc != TPK_OK) {
            fprintf(stderr, "%s: %s\n", argv[1], tpk_result_string(rc));
            return 2;
        }
    }
    uint64_t hash = 1469598103934665603ull; /* FNV-1a of the result: the same bytes for any thread count */
    for (uint64_t i = 0; i < 4 * mesh.tet_count; i++)
        hash = (hash ^ (uint32_t)tets[i]) * 1099511628211ull;
    double w = bench_median(wall, runs), c = bench_median(cpu, runs), n = (double)mesh.tet_count;
    printf("{\"file\":\"%s\",\"layout\":%d,\"threads\":%d,\"runs\":%d,\"tets\":%llu,\"seconds\":%.6f,"
           "\"cpu_seconds\":%.6f,\"wall_ns_per_tet\":%.1f,\"cpu_ns_per_tet\":%.1f,\"hash\":\"%016llx\"}\n",
           argv[1], layout, threads, runs, (unsigned long long)mesh.tet_count, w, c, 1e9 * w / n, 1e9 * c / n,
           (unsigned long long)hash);
    free(wall);
    free(cpu);
    free(tets);
    tpk_close(f);
    return 0;
}
