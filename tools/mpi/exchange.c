/* All-to-all of fixed-size records over MPI, and the agreement every phase ends with. */
#include "exchange.h"

#include <stdlib.h>

int tpk_agree(MPI_Comm comm, int rc)
{
    int failed = rc != 0, any = 0;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
    return any ? -1 : 0;
}

int tpk_alltoallv(MPI_Comm comm, const void *send, const int64_t *send_counts, size_t record, void **recv,
                  int64_t *recv_counts, int64_t *recv_total, tpk_diag *diag)
{
    int size;
    MPI_Comm_size(comm, &size);
    MPI_Alltoall(send_counts, 1, MPI_INT64_T, recv_counts, 1, MPI_INT64_T, comm);
    int *sc = malloc(sizeof *sc * (size_t)size * 4), *sd = sc + size, *rc = sc + 2 * size, *rd = sc + 3 * size;
    int64_t total = 0, sent = 0;
    for (int r = 0; sc && r < size; r++) {
        sc[r] = (int)send_counts[r];
        rc[r] = (int)recv_counts[r];
        sd[r] = (int)sent; /* displacements in records: a rank's buffers stay below 2^31 records */
        rd[r] = (int)total;
        sent += send_counts[r];
        total += recv_counts[r];
    }
    *recv = malloc(record * (size_t)(total ? total : 1));
    int ok = sc && *recv && sent < INT32_MAX && total < INT32_MAX;
    if (tpk_agree(comm, !ok) != 0) { /* every rank leaves the exchange together */
        free(sc);
        free(*recv);
        *recv = NULL;
        return tpk_diag_fail(diag, "exchange: out of memory, or more than 2^31 records on one rank (%lld sent, "
                             "%lld received here)", (long long)sent, (long long)total);
    }
    MPI_Datatype type;
    MPI_Type_contiguous((int)record, MPI_BYTE, &type);
    MPI_Type_commit(&type);
    MPI_Alltoallv(send, sc, sd, type, *recv, rc, rd, type, comm);
    MPI_Type_free(&type);
    free(sc);
    *recv_total = total;
    return 0;
}
