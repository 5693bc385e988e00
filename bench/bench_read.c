/* One import, timed alone: the importer the registry picks for FILE (as tetpack convert would), its
 * wall and CPU seconds as one JSON line. bench/bench_import.py runs it, a fresh process each time, beside
 * meshio.read of the same file. Usage: bench_read FILE */
#include <stdio.h>

#include "bench_clock.h"
#include "import/importers.h"

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: bench_read FILE\n");
        return 2;
    }
    tpk_mesh mesh;
    tpk_diag diag = {0};
    double t0 = now(), c0 = cpu_now();
    int rc = tpk_import_any(argv[1], NULL, &mesh, &diag);
    double wall = now() - t0, cpu = cpu_now() - c0;
    if (rc != 0) {
        fprintf(stderr, "bench_read: %s\n", diag.message);
        return 1;
    }
    printf("{\"seconds\":%.6f,\"cpu_seconds\":%.6f,\"points\":%lld,\"cells\":%lld}\n", wall, cpu,
           (long long)mesh.point_count, (long long)mesh.cell_count);
    tpk_mesh_free(&mesh);
    return 0;
}
