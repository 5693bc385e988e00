/* tetpack iso's extraction alone (tpk_iso_extract, issue 21), in process: the file's first point field
 * and tets loaded once, then N extractions of one value, timed by the wall clock and by the process's CPU
 * time (all threads), whose median is the steadier figure on a shared, loaded machine: tets per
 * core-second = tets / CPU seconds. One JSON line.
 * Usage: bench_iso_extract FILE.tpk VALUE [threads (1)] [runs (9)] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"
#include "iso/iso.h"
#include "tetpack.h"

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: bench_iso_extract FILE.tpk VALUE [threads] [runs]\n");
        return 2;
    }
    double value = atof(argv[2]);
    int threads = argc > 3 ? atoi(argv[3]) : 1, runs = bench_runs(argc, argv, 4, 9);
    tpk_file *f = bench_open_file(argv[1]);
    if (!f)
        return 2;
    const char *field = NULL;
    tpk_field_desc d;
    for (uint32_t i = 0; !field && i < tpk_field_count(f); i++)
        if (tpk_get_field(f, i, &d) == TPK_OK && d.association == TPK_ASSOC_POINT)
            field = d.name;
    tpk_mesh_arrays mesh;
    int32_t *tets = NULL;
    /* the vertices straight from Tet32 where the file has it, else recovered from Tet16 (outside the timing) */
    if (!field || (tpk_load_arrays(f, TPK_LAYOUT_TET32, field, 0, &mesh) != TPK_OK &&
                   tpk_load_arrays(f, TPK_LAYOUT_TET16, field, 0, &mesh) != TPK_OK) ||
        !(tets = malloc(16 * (size_t)(mesh.tet_count ? mesh.tet_count : 1))) || tpk_recover_tets(&mesh, tets) != TPK_OK) {
        fprintf(stderr, "%s: needs a point field and a Tet32 or Tet16 layout\n", argv[1]);
        return 2;
    }
    tpk_iso_input in = {.vertex_count = (int64_t)mesh.vertex_count, .tet_count = (int64_t)mesh.tet_count,
                        .positions = mesh.positions, .tets = tets, .scalars = mesh.scalars};
    memcpy(in.origin, mesh.origin, sizeof in.origin);
    double *wall = calloc((size_t)runs, sizeof *wall), *cpu = calloc((size_t)runs, sizeof *cpu);
    int64_t triangles = 0;
    for (int r = 0; r < runs; r++) {
        tpk_iso_surface s;
        tpk_diag diag = {0};
        double w0 = now(), c0 = cpu_now();
        if (tpk_iso_extract(&in, &value, 1, threads, &s, &diag) != 0) {
            fprintf(stderr, "%s\n", diag.message);
            return 2;
        }
        wall[r] = now() - w0;
        cpu[r] = cpu_now() - c0;
        triangles = s.triangle_count;
        tpk_iso_surface_free(&s);
    }
    double w = bench_median(wall, runs), c = bench_median(cpu, runs);
    printf("{\"file\":\"%s\",\"value\":%g,\"threads\":%d,\"runs\":%d,\"tets\":%lld,\"triangles\":%lld,"
           "\"seconds\":%.6f,\"cpu_seconds\":%.6f,\"tets_per_second\":%.0f,\"tets_per_core_second\":%.0f}\n",
           argv[1], value, threads, runs, (long long)in.tet_count, (long long)triangles, w, c,
           (double)in.tet_count / w, (double)in.tet_count / c);
    free(wall);
    free(cpu);
    free(tets);
    tpk_close(f);
    return 0;
}
