/* tetpack-mpi: the MPI front end. `mpirun -np P tetpack-mpi convert IN.pvtu OUT.tpkset` converts a
 * decomposed mesh (.pvtu, OpenFOAM processor folders, Exodus files per processor) into a part set, one
 * part per rank (tools/mpi/mpi_convert.h). */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/convert.h"
#include "mpi_convert.h"
#include "tetpack.h"

static const char mpi_help[] =
    "usage: mpirun -np P tetpack-mpi convert INPUT OUTPUT.tpkset [options]\n"
    "\n"
    "Converts a decomposed mesh into a part set (spec §15). INPUT is a .pvtu (its pieces), an OpenFOAM\n"
    "case folder decomposed by decomposePar (processor0, processor1, ...), or Exodus files per processor as\n"
    "SEACAS's nem_slice/decomp write them (mesh.e.4.0 .. mesh.e.4.3: name one of them, or mesh.e when they\n"
    "lie beside it). Rank r reads the r-th block of pieces; vertices are identified across ranks by the\n"
    "files' global ids (Exodus node number maps, OpenFOAM's pointProcAddressing, or a point field\n"
    "GlobalPointIds of integers below 2^24 in every piece), else by exact coordinates;\n"
    "each rank splits, orients and connects its cells on the whole mesh's float32 grid, the faces on\n"
    "cuts are matched by an exchange keyed by their sorted global vertex ids, each rank writes OUTPUT's\n"
    "stem + -<rank>.tpk with its links and rank 0 the manifest OUTPUT. Needs at least P pieces.\n"
    "\n"
    "  --layout tet16|tet20|tet32  layout to store (repeatable; default tet16)\n"
    "  --zstd LEVEL                compress chunks with zstd (1-22)\n"
    "  --threads N                 worker threads per rank (default: all cores)\n"
    "  --json                      print the per-rank report as one JSON object (rank 0)\n"
    "  --quiet                     print nothing on success\n"
    "\n"
    "Exit status: 0 on success, 2 on unusable input or a failure on any rank (each rank that knows why\n"
    "says so on stderr, prefixed with its rank).\n";

typedef struct mpi_args {
    tpk_mpi_options o;
    int json, quiet;
} mpi_args;

static int parse(int argc, char **argv, mpi_args *a, int rank)
{
    const char *pos[2];
    int n = 0;
    for (int i = 2; i < argc; i++) {
        const char *arg = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(arg, "--layout") && v) {
            a->o.layouts |= !strcmp(v, "tet32") ? TPK_LAYOUT_BIT_TET32 : !strcmp(v, "tet20") ? TPK_LAYOUT_BIT_TET20
                          : !strcmp(v, "tet16") ? TPK_LAYOUT_BIT_TET16 : 0x80000000u;
            i++;
        } else if (!strcmp(arg, "--zstd") && v) {
            a->o.zstd_level = atoi(v), i++;
            if (a->o.zstd_level < 1 || a->o.zstd_level > 22)
                a->o.layouts |= 0x80000000u;
        } else if (!strcmp(arg, "--threads") && v) {
            a->o.threads = atoi(v), i++;
        } else if (!strcmp(arg, "--json")) {
            a->json = 1;
        } else if (!strcmp(arg, "--quiet")) {
            a->quiet = 1;
        } else if (arg[0] != '-' && n < 2) {
            pos[n++] = arg;
        } else if (!strcmp(arg, "--max-error") || !strcmp(arg, "--max-error-field") || !strcmp(arg, "--subdivide")) {
            /* docs/ARCHITECTURE.md §10: the refinement's marks, edge order and midpoints would have to agree
             * across ranks, which they do not yet */
            if (rank == 0)
                fprintf(stderr, "tetpack-mpi convert: error: %s is not offered here: a shared face between two "
                                "ranks would not be refined alike from both sides; convert the whole mesh "
                                "with tetpack convert %s\n",
                        arg, arg);
            return 2;
        } else {
            if (rank == 0)
                fprintf(stderr, "tetpack-mpi convert: error: unexpected argument '%s' (see --help)\n", arg);
            return 2;
        }
    }
    if (n != 2 || (a->o.layouts & 0x80000000u) || !strcmp(pos[0], pos[1])) {
        if (rank == 0)
            fprintf(stderr, "tetpack-mpi convert: error: expected INPUT (.pvtu, decomposed OpenFOAM case or "
                            "Exodus files per processor) and "
                            "OUTPUT.tpkset (a different file), "
                            "--layout tet16|tet20|tet32, --zstd 1..22 (see --help)\n");
        return 2;
    }
    a->o.input = pos[0];
    a->o.output = pos[1];
    return 0;
}

static void report(const mpi_args *a, const tpk_mpi_rank_report *all, int size)
{
    if (a->quiet)
        return;
    if (!a->json) {
        printf("%s: %d parts\n  rank pieces   tets      vertices  links   exchanged_B  peak_rss_MiB  read_s  ids_s  "
               "tets_s  cut_s  write_s total_s\n", a->o.output, size);
        for (int r = 0; r < size; r++) {
            const tpk_mpi_rank_report *p = &all[r];
            printf("  %-4d %-7lld %-9lld %-9lld %-7lld %-12lld %-13.1f %-7.3f %-6.3f %-7.3f %-6.3f %-7.3f %.3f\n", r,
                   (long long)p->pieces, (long long)p->tets, (long long)p->vertices, (long long)p->links,
                   (long long)p->exchanged_bytes, (double)p->peak_rss_bytes / 1048576.0, p->t_read, p->t_ids,
                   p->t_tets, p->t_cut, p->t_write, p->t_total);
        }
        return;
    }
    printf("{\"output\":\"%s\",\"ranks\":[", a->o.output);
    for (int r = 0; r < size; r++) {
        const tpk_mpi_rank_report *p = &all[r];
        printf("%s{\"rank\":%d,\"pieces\":%lld,\"points_read\":%lld,\"vertices\":%lld,\"tets\":%lld,\"shell_faces\":%lld,"
               "\"links\":%lld,\"global_vertices\":%lld,\"exchanged_bytes\":%lld,\"peak_rss_bytes\":%lld,"
               "\"file_bytes\":%lld,\"seconds\":{\"read\":%.6f,\"ids\":%.6f,\"tets\":%.6f,\"cut\":%.6f,"
               "\"write\":%.6f,\"total\":%.6f},\"cpu_seconds\":{\"read\":%.6f,\"ids\":%.6f,\"tets\":%.6f,"
               "\"cut\":%.6f,\"write\":%.6f}}", r ? "," : "", r, (long long)p->pieces, (long long)p->points_read,
               (long long)p->vertices, (long long)p->tets, (long long)p->shell_faces, (long long)p->links,
               (long long)p->global_vertices, (long long)p->exchanged_bytes, (long long)p->peak_rss_bytes,
               (long long)p->file_bytes, p->t_read, p->t_ids, p->t_tets, p->t_cut, p->t_write, p->t_total,
               p->cpu_read, p->cpu_ids, p->cpu_tets, p->cpu_cut, p->cpu_write);
    }
    printf("]}\n");
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, size, rc = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    mpi_args a;
    memset(&a, 0, sizeof a);
    if (argc >= 2 && !strcmp(argv[1], "--version")) { /* as tetpack's (help2man reads it for the man page) */
        if (rank == 0)
            printf("tetpack-mpi %s (format %d.%d)\n", TPK_LIBRARY_VERSION, TPK_VERSION_MAJOR, TPK_VERSION_MINOR);
        MPI_Finalize();
        return 0;
    }
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") ||
        (argc > 2 && !strcmp(argv[1], "convert") && (!strcmp(argv[2], "--help") || !strcmp(argv[2], "-h")))) {
        if (rank == 0)
            fputs(mpi_help, argc < 2 ? stderr : stdout);
        MPI_Finalize();
        return argc < 2 ? 2 : 0;
    }
    if (strcmp(argv[1], "convert")) {
        if (rank == 0)
            fprintf(stderr, "tetpack-mpi: error: unknown command '%s': expected convert (see --help)\n", argv[1]);
        MPI_Finalize();
        return 2;
    }
    rc = parse(argc, argv, &a, rank);
    if (rc == 0) {
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        tpk_mpi_rank_report mine, *all = rank == 0 ? calloc((size_t)size, sizeof *all) : NULL;
        rc = tpk_mpi_convert(MPI_COMM_WORLD, &a.o, &mine, &diag) != 0 ? 2 : 0;
        if (rc != 0 && diag.message[0])
            fprintf(stderr, "tetpack-mpi convert: error: rank %d: %s\n", rank, diag.message);
        MPI_Gather(&mine, (int)sizeof mine, MPI_BYTE, all, (int)sizeof mine, MPI_BYTE, 0, MPI_COMM_WORLD);
        if (rc == 0 && rank == 0 && all)
            report(&a, all, size);
        free(all);
    }
    MPI_Finalize();
    return rc;
}
