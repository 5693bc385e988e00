/* Open time of a .tpk (tpk_open_path: header, directory and field table, which every open checks;
 * chunk data is mapped, not read), median of N runs with a warm page cache, and the time of one full
 * tpk_verify (every chunk checksum and id range) for comparison. Usage: bench_open FILE.tpk [runs] */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_clock.h"
#include "tetpack.h"

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_open FILE.tpk [runs]\n");
        return 2;
    }
    int runs = bench_runs(argc, argv, 2, 21);
    double *open_s = calloc((size_t)runs, sizeof *open_s);
    tpk_file *f = NULL;
    char err[512];
    for (int r = 0; r < runs; r++) {
        double t0 = now();
        if (tpk_open_path(&f, argv[1], NULL, err, sizeof err) != TPK_OK) {
            fprintf(stderr, "%s\n", err);
            return 2;
        }
        open_s[r] = now() - t0;
        tpk_close(f);
    }
    qsort(open_s, (size_t)runs, sizeof *open_s, bench_compare_double);
    if (tpk_open_path(&f, argv[1], NULL, err, sizeof err) != TPK_OK)
        return 2;
    double t0 = now();
    tpk_result verified = tpk_verify(f);
    double verify = now() - t0;
    tpk_file_info info;
    tpk_get_info(f, &info);
    tpk_close(f);
    printf("{\"file\":\"%s\",\"tets\":%llu,\"bytes\":%llu,\"open_median_ms\":%.4f,\"open_min_ms\":%.4f,"
           "\"runs\":%d,\"full_verify_ms\":%.2f,\"verify_ok\":%s}\n",
           argv[1], (unsigned long long)info.tet_count, (unsigned long long)info.file_size,
           1e3 * open_s[runs / 2], 1e3 * open_s[0], runs, 1e3 * verify, verified == TPK_OK ? "true" : "false");
    free(open_s);
    return 0;
}
