/* The MPI exchanges of tetpack-mpi: all-to-all of fixed-size records, and the two exchanges built on it
 * (global vertex ids, matching the faces on cuts). */
#ifndef TPK_EXCHANGE_H
#define TPK_EXCHANGE_H

#include <mpi.h>
#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"
#include "tetpack.h"

/* MPI_Alltoallv of records of `record` bytes: send holds send_counts[d] records for each rank d in rank
 * order; *recv (malloc'd, the caller frees) gets recv_counts[s] records from each rank s in rank order.
 * Counts per pair must stay below 2^31 records. Returns 0, or -1 (diag set) on allocation failure. */
int tpk_alltoallv(MPI_Comm comm, const void *send, const int64_t *send_counts, size_t record, void **recv,
                  int64_t *recv_counts, int64_t *recv_total, tpk_diag *diag);

/* One global id per point of `mesh` (ids[point_count]): given[i] (the files' ids, checked: one id, one
 * position) when every rank has them (given non-NULL), else exact coordinate matching: points with the
 * same coordinates on any rank get the same id, numbered along a Morton curve of the box [lo, hi], so
 * that ids follow space. *global_count: 1 + the largest id. `exchanged` adds the bytes this rank sent.
 * Collective. Returns 0, or -1 (diag set) on every rank when one failed. */
int tpk_global_ids(MPI_Comm comm, const tpk_mesh *mesh, const int64_t *given, const double lo[3],
                   const double hi[3], int64_t *ids, int64_t *global_count, int64_t *exchanged, tpk_diag *diag);

/* The faces on cuts: every shell face of this rank (tet order then face order, as SHEL numbers them) is
 * sent, keyed by its sorted global vertex ids (vertex_gid per vertex, -1 for a point the converter added,
 * whose faces stay outer shell), to an owner rank; a key two ranks sent is a cut face, and each side gets
 * a link to the other (part = rank). *links (malloc'd) sorted by face. Collective; -1 on every rank when
 * a face is on more than two ranks. */
int tpk_cut_faces(MPI_Comm comm, const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                  const int64_t *vertex_gid, tpk_link **links, int64_t *link_count, int64_t *exchanged,
                  tpk_diag *diag);

/* 0 on every rank when rc is 0 on every rank, else -1 on every rank. */
int tpk_agree(MPI_Comm comm, int rc);

#endif
