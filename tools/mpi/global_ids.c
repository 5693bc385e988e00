/* Global vertex ids across ranks. Each point is sent to the rank that owns its key (a Morton key of its
 * coordinates, owners by key range, or the id the files give it); the owner sorts what it got, gives equal
 * coordinates one id, and sends the ids back. The points of piece boundaries, the only ones two ranks
 * share, meet at their owner whichever ranks hold them. */
#include <stdlib.h>
#include <string.h>

#include "base/spread_bits.h"
#include "exchange.h"

typedef struct point_record {
    uint64_t key;  /* Morton key, or the given global id */
    double x[3];
    int64_t slot;  /* at the owner: where the record came in (the reply goes back in that order) */
} point_record;

static uint64_t morton_key(const double p[3], const double lo[3], double scale)
{
    uint64_t key = 0;
    for (int k = 0; k < 3; k++) {
        double q = (p[k] - lo[k]) * scale;
        uint64_t c = q > 0 ? (q < 2097151.0 ? (uint64_t)q : 2097151u) : 0;
        key |= tpk_spread_bits3(c) << k;
    }
    return key; /* 63 bits */
}

static int compare_records(const void *a, const void *b)
{
    const point_record *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    for (int k = 0; k < 3; k++)
        if (x->x[k] != y->x[k])
            return x->x[k] < y->x[k] ? -1 : 1;
    return (x->slot > y->slot) - (x->slot < y->slot);
}

/* At the owner: ids for the sorted records, in their slots; -1 when one given id names two positions. */
static int number_records(MPI_Comm comm, point_record *recs, int64_t n, int given, int64_t *reply)
{
    qsort(recs, (size_t)n, sizeof *recs, compare_records);
    int64_t unique = 0;
    int bad = 0;
    for (int64_t i = 0; i < n; i++) {
        int same_key = i > 0 && recs[i].key == recs[i - 1].key;
        int same_point = same_key && !memcmp(recs[i].x, recs[i - 1].x, sizeof recs[i].x);
        if (given && same_key && !same_point)
            bad = 1;
        if (!same_point)
            unique++;
        reply[recs[i].slot] = unique - 1; /* rebased below */
    }
    int64_t offset = 0;
    MPI_Exscan(&unique, &offset, 1, MPI_INT64_T, MPI_SUM, comm);
    int rank;
    MPI_Comm_rank(comm, &rank);
    if (rank == 0)
        offset = 0; /* MPI_Exscan leaves rank 0's result undefined */
    for (int64_t i = 0; i < n; i++)
        reply[recs[i].slot] = given ? (int64_t)recs[i].key : reply[recs[i].slot] + offset;
    return bad ? -1 : 0;
}

/* Where each point goes: its record, in send order grouped by owner rank (counts[r] per rank), and
 * pos[i], the place of point i in that order. Local; -1 when out of memory. */
typedef struct send_plan {
    point_record *send;
    int64_t *counts, *recv_counts; /* size each */
    int64_t *pos;
} send_plan;

static void free_plan(send_plan *plan)
{
    free(plan->send), free(plan->counts), free(plan->pos);
}

static int plan_sends(const tpk_mesh *mesh, const int64_t *given, const double lo[3], const double hi[3], int size,
                      send_plan *plan)
{
    int64_t n = mesh->point_count;
    double extent = 0;
    for (int k = 0; k < 3; k++)
        extent = hi[k] - lo[k] > extent ? hi[k] - lo[k] : extent;
    double scale = extent > 0 ? 2097151.0 / extent : 0;
    plan->counts = calloc((size_t)size * 3, sizeof *plan->counts);
    plan->send = malloc(sizeof *plan->send * (size_t)(n ? n : 1));
    plan->pos = malloc(sizeof *plan->pos * (size_t)(n ? n : 1));
    if (!plan->counts || !plan->send || !plan->pos)
        return -1;
    plan->recv_counts = plan->counts + size;
    int64_t *start = plan->counts + 2 * size;
    for (int64_t i = 0; i < n; i++) { /* pos holds the owner first, then the place */
        uint64_t key = given ? (uint64_t)given[i] : morton_key(mesh->points + 3 * i, lo, scale);
        plan->pos[i] = given ? (int64_t)(key % (uint64_t)size) : (int64_t)(((unsigned __int128)key * (unsigned)size) >> 63);
        plan->counts[plan->pos[i]]++;
    }
    for (int r = 1; r < size; r++)
        start[r] = start[r - 1] + plan->counts[r - 1];
    for (int64_t i = 0; i < n; i++) {
        const double *p = mesh->points + 3 * i;
        plan->pos[i] = start[plan->pos[i]]++;
        plan->send[plan->pos[i]] = (point_record){given ? (uint64_t)given[i] : morton_key(p, lo, scale),
                                                  {p[0], p[1], p[2]}, 0};
    }
    return 0;
}

int tpk_global_ids(MPI_Comm comm, const tpk_mesh *mesh, const int64_t *given, const double lo[3],
                   const double hi[3], int64_t *ids, int64_t *global_count, int64_t *exchanged, tpk_diag *diag)
{
    int size;
    MPI_Comm_size(comm, &size);
    int mine = given != NULL, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, comm); /* the file's ids only when every rank has them */
    send_plan plan = {0};
    if (tpk_agree(comm, plan_sends(mesh, all ? given : NULL, lo, hi, size, &plan)) != 0) {
        free_plan(&plan);
        return tpk_diag_fail(diag, "global ids: out of memory for %lld points", (long long)mesh->point_count);
    }
    *exchanged += (int64_t)sizeof *plan.send * mesh->point_count;
    point_record *recv = NULL;
    int64_t total = 0, *reply = NULL, *back = NULL, back_total = 0;
    int rc = tpk_alltoallv(comm, plan.send, plan.counts, sizeof *plan.send, (void **)&recv, plan.recv_counts, &total,
                           diag);
    if (rc == 0 && tpk_agree(comm, !(reply = malloc(sizeof *reply * (size_t)(total ? total : 1)))) != 0)
        rc = tpk_diag_fail(diag, "global ids: out of memory");
    int bad = 0;
    if (rc == 0) {
        for (int64_t i = 0; i < total; i++)
            recv[i].slot = i;
        bad = number_records(comm, recv, total, all, reply);
        /* the ids go back the way the points came: the counts swap roles */
        rc = tpk_alltoallv(comm, reply, plan.recv_counts, sizeof *reply, (void **)&back, plan.counts, &back_total,
                           diag);
    }
    if (rc == 0 && tpk_agree(comm, bad) != 0)
        rc = tpk_diag_fail(diag, "global ids: a global point id the files give names points at different positions");
    int64_t largest = -1;
    for (int64_t i = 0; rc == 0 && i < mesh->point_count; i++) {
        ids[i] = back[plan.pos[i]];
        largest = ids[i] > largest ? ids[i] : largest;
    }
    MPI_Allreduce(&largest, global_count, 1, MPI_INT64_T, MPI_MAX, comm);
    (*global_count)++;
    free_plan(&plan);
    free(recv), free(reply), free(back);
    return rc;
}
