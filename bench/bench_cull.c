/* The set-up of a culled iso render (issue 39) in process: range trees made from all tets
 * (tpk_range_bvh_create_threads: the walk from the shell) against trees made from the file's culling
 * blocks (tpk_range_bvh_create_cull, spec §17), each then selected for the iso value; medians of N runs,
 * wall seconds, plus the share of blocks whose range over their intervals holds the value and the share
 * of blocks whose tets' own vertices hold it (what the intervals' spare ids cost). Both select the same active tets (checked). One JSON line.
 * Usage: bench_cull FILE.tpk ISO [threads (1)] [runs (5)] */
#include <stdio.h>
#include <stdlib.h>

#include "bench_clock.h"
#include "tetpack.h"

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: bench_cull FILE.tpk ISO [threads] [runs]\n");
        return 2;
    }
    double iso = atof(argv[2]);
    int threads = argc > 3 ? atoi(argv[3]) : 1, runs = bench_runs(argc, argv, 4, 5);
    tpk_file *f = bench_open_file(argv[1]);
    if (!f)
        return 2;
    tpk_mesh_arrays mesh;
    tpk_cull cull;
    if (tpk_load_arrays(f, TPK_LAYOUT_TET16, NULL, 0, &mesh) != TPK_OK || tpk_load_cull(f, &cull) != TPK_OK) {
        fprintf(stderr, "%s: needs a Tet16 layout, a point field and culling blocks (convert --cull)\n", argv[1]);
        return 2;
    }
    tpk_marcher *m = NULL;
    if (tpk_marcher_create(&m, &mesh) != TPK_OK)
        return 2;
    double *full = calloc((size_t)runs, sizeof *full), *blocks = calloc((size_t)runs, sizeof *blocks);
    double share = 0, exact = 0;
    {   /* the share of blocks whose tets' own vertices hold the value: what the intervals add to it */
        int32_t *tets = malloc(16 * (size_t)(mesh.tet_count ? mesh.tet_count : 1));
        if (!tets || tpk_recover_tets(&mesh, tets) != TPK_OK)
            return 2;
        for (uint64_t k = 0; k < cull.block_count; k++) {
            float lo = 1e30f, hi = -1e30f;
            for (uint64_t t = k * cull.block_tets; t < (k + 1) * cull.block_tets && t < mesh.tet_count; t++)
                for (int c = 0; c < 4; c++) {
                    float x = mesh.scalars[tets[4 * t + c]];
                    lo = x < lo ? x : lo, hi = x > hi ? x : hi;
                }
            exact += lo <= iso && iso <= hi;
        }
        exact /= (double)(cull.block_count ? cull.block_count : 1);
        free(tets);
    }
    for (int r = 0; r < runs; r++) {
        tpk_range_bvh *a = NULL, *b = NULL;
        double t0 = now();
        tpk_result ra = tpk_range_bvh_create_threads(&a, m, threads);
        if (ra == TPK_OK)
            ra = tpk_range_bvh_select(a, &iso, 1);
        double t1 = now();
        tpk_result rb = tpk_range_bvh_create_cull(&b, m, &cull, threads);
        if (rb == TPK_OK) {
            share = tpk_range_bvh_active(b, &iso, 1);
            rb = tpk_range_bvh_select(b, &iso, 1);
        }
        double t2 = now();
        if (ra != TPK_OK || rb != TPK_OK) {
            fprintf(stderr, "%s: %s / %s\n", argv[1], tpk_result_string(ra), tpk_result_string(rb));
            return 2;
        }
        full[r] = t1 - t0, blocks[r] = t2 - t1;
        tpk_range_bvh_destroy(a);
        tpk_range_bvh_destroy(b);
    }
    printf("{\"file\":\"%s\",\"iso\":%g,\"threads\":%d,\"runs\":%d,\"tets\":%llu,\"blocks\":%llu,"
           "\"block_share\":%.4f,\"exact_block_share\":%.4f,\"all_tets_s\":%.6f,\"cull_s\":%.6f,\"ratio\":%.3f}\n",
           argv[1], iso, threads, runs, (unsigned long long)mesh.tet_count, (unsigned long long)cull.block_count,
           share, exact, bench_median(full, runs), bench_median(blocks, runs),
           bench_median(blocks, runs) / bench_median(full, runs));
    free(full);
    free(blocks);
    tpk_marcher_destroy(m);
    tpk_close(f);
    return 0;
}
