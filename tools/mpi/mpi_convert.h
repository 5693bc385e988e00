/* tetpack-mpi convert: a decomposed mesh (.pvtu pieces) into a part set, one part per rank. */
#ifndef TPK_MPI_CONVERT_H
#define TPK_MPI_CONVERT_H

#include <mpi.h>
#include <stdint.h>

#include "base/diag.h"

typedef struct tpk_mpi_options {
    const char *input;        /* .pvtu, OpenFOAM case, Exodus files per processor */
    const char *output;       /* the manifest, .tpkset; parts <stem>-<rank>.tpk beside it */
    unsigned layouts;         /* TPK_LAYOUT_BIT_*; 0: Tet16 */
    int zstd_level;
    int threads;              /* per rank; <= 0: all cores */
    const char *command_line;
} tpk_mpi_options;

/* What one rank did: its counts, seconds per phase, bytes it sent, its peak memory. */
typedef struct tpk_mpi_rank_report {
    int64_t pieces, points_read, vertices, tets, shell_faces, links, global_vertices;
    int64_t exchanged_bytes, peak_rss_bytes, file_bytes;
    double t_read, t_ids, t_tets, t_cut, t_write, t_total; /* t_tets: split, orient and connect */
    /* CPU seconds of this rank's process in each phase, without the agreement that ends it: on a loaded
     * machine the work a phase costs, where wall time also counts waiting for a core (and OpenMPI spins
     * while it waits inside an exchange, so ids and cut count some waiting too). */
    double cpu_read, cpu_ids, cpu_tets, cpu_cut, cpu_write;
} tpk_mpi_rank_report;

/* Collective over comm. Returns 0, or -1 on every rank (diag set on the ranks that know why). */
int tpk_mpi_convert(MPI_Comm comm, const tpk_mpi_options *o, tpk_mpi_rank_report *rep, tpk_diag *diag);

#endif
