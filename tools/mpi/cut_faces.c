/* Matching the faces on cuts between ranks: every shell face goes to the owner of its key (its three
 * global vertex ids, sorted); a key that arrives twice is a face two ranks share, and each gets the
 * other's rank, shell index and tet back. Faces whose key arrives once are the outer shell. */
#include <stdlib.h>
#include <string.h>

#include "convert/pipeline.h"
#include "exchange.h"

typedef struct face_record {
    int64_t g[3];   /* sorted global ids */
    int64_t shell;  /* index in the sender's SHEL */
    int64_t tet;
    int64_t from;   /* at the owner: the sending rank */
} face_record;

typedef struct link_record {
    int64_t shell, part, other_shell, other_tet;
} link_record;

static int compare_faces(const void *a, const void *b)
{
    const face_record *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->g[k] != y->g[k])
            return x->g[k] < y->g[k] ? -1 : 1;
    return (x->from > y->from) - (x->from < y->from);
}

static int owner_of(const int64_t g[3], int size)
{
    uint64_t h = (uint64_t)g[0] * 0x9E3779B97F4A7C15ULL ^ (uint64_t)g[1] * 0xC2B2AE3D27D4EB4FULL ^
                 (uint64_t)g[2] * 0x165667B19E3779F9ULL;
    h ^= h >> 29;
    return (int)(h % (uint64_t)size);
}

static void sort3(int64_t g[3])
{
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2 - i; j++)
            if (g[j] > g[j + 1]) {
                int64_t t = g[j];
                g[j] = g[j + 1];
                g[j + 1] = t;
            }
}

/* This rank's shell faces with a key (none of their points added by the converter), grouped by owner. */
static face_record *shell_records(const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                                  const int64_t *gid, int size, int64_t *counts)
{
    int64_t n = tpk_count_shell_faces(neighbors, tet_count), s = 0, kept = 0;
    face_record *all = malloc(sizeof *all * (size_t)(n ? n : 1)), *send = malloc(sizeof *send * (size_t)(n ? n : 1));
    int *dest = malloc(sizeof *dest * (size_t)(n ? n : 1));
    if (!all || !send || !dest) {
        free(all), free(send), free(dest);
        return NULL;
    }
    for (int64_t t = 0; t < tet_count; t++)
        for (int k = 0; k < 4; k++) {
            if (neighbors[4 * t + k] >= 0)
                continue;
            face_record r = {{0, 0, 0}, s++, t, 0};
            int added = 0;
            for (int j = 0, m = 0; j < 4; j++)
                if (j != k) {
                    r.g[m++] = gid[tets[4 * t + j]];
                    added |= gid[tets[4 * t + j]] < 0;
                }
            if (added)
                continue;
            sort3(r.g);
            dest[kept] = owner_of(r.g, size);
            counts[dest[kept]]++;
            all[kept++] = r;
        }
    int64_t *start = calloc((size_t)size, sizeof *start);
    for (int r = 1; start && r < size; r++)
        start[r] = start[r - 1] + counts[r - 1];
    for (int64_t i = 0; start && i < kept; i++)
        send[start[dest[i]]++] = all[i];
    int ok = start != NULL;
    free(start), free(all), free(dest);
    if (!ok) {
        free(send);
        return NULL;
    }
    return send;
}

/* At the owner: a reply for each side of every shared key, grouped by the rank it goes to. */
static link_record *pair_faces(face_record *recs, int64_t n, int size, int64_t *counts, int *bad)
{
    qsort(recs, (size_t)n, sizeof *recs, compare_faces);
    link_record *out = malloc(sizeof *out * (size_t)(n ? n : 1));
    int64_t *dest = malloc(sizeof *dest * (size_t)(n ? n : 1)), made = 0;
    if (!out || !dest) {
        free(out), free(dest);
        return NULL;
    }
    for (int64_t i = 0; i < n;) {
        int64_t j = i + 1;
        while (j < n && !memcmp(recs[j].g, recs[i].g, sizeof recs[i].g))
            j++;
        if (j - i > 2 || (j - i == 2 && recs[i].from == recs[i + 1].from))
            *bad = 1; /* a face of three tets, or twice on one rank: not a conforming mesh */
        else if (j - i == 2)
            for (int side = 0; side < 2; side++) {
                const face_record *me = &recs[i + side], *other = &recs[i + 1 - side];
                dest[made] = me->from;
                out[made++] = (link_record){me->shell, other->from, other->shell, other->tet};
                counts[me->from]++;
            }
        i = j;
    }
    link_record *grouped = malloc(sizeof *grouped * (size_t)(made ? made : 1));
    int64_t *start = calloc((size_t)size, sizeof *start);
    for (int r = 1; start && r < size; r++)
        start[r] = start[r - 1] + counts[r - 1];
    for (int64_t i = 0; grouped && start && i < made; i++)
        grouped[start[dest[i]]++] = out[i];
    int ok = grouped && start;
    free(out), free(dest), free(start);
    if (!ok) {
        free(grouped);
        return NULL;
    }
    return grouped;
}

static int compare_links(const void *a, const void *b)
{
    const tpk_link *x = a, *y = b;
    return (x->face > y->face) - (x->face < y->face);
}

int tpk_cut_faces(MPI_Comm comm, const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                  const int64_t *vertex_gid, tpk_link **links, int64_t *link_count, int64_t *exchanged,
                  tpk_diag *diag)
{
    int size;
    MPI_Comm_size(comm, &size);
    *links = NULL;
    *link_count = 0;
    int64_t *counts = calloc((size_t)size * 4, sizeof *counts);
    face_record *send = counts ? shell_records(tets, neighbors, tet_count, vertex_gid, size, counts) : NULL;
    if (tpk_agree(comm, !send) != 0) {
        free(counts), free(send);
        return tpk_diag_fail(diag, "cut faces: out of memory for the shell faces");
    }
    int64_t *recv_counts = counts + size, *reply_counts = counts + 2 * size, *back_counts = counts + 3 * size;
    int64_t sent = 0, total = 0, back_total = 0;
    for (int r = 0; r < size; r++)
        sent += counts[r];
    *exchanged += (int64_t)sizeof *send * sent;
    face_record *recv = NULL;
    link_record *replies = NULL, *back = NULL;
    int rc = tpk_alltoallv(comm, send, counts, sizeof *send, (void **)&recv, recv_counts, &total, diag);
    int bad = 0;
    if (rc == 0) {
        int64_t at = 0;
        for (int r = 0; r < size; r++)
            for (int64_t i = 0; i < recv_counts[r]; i++)
                recv[at++].from = r;
        replies = pair_faces(recv, total, size, reply_counts, &bad);
        if (tpk_agree(comm, !replies) != 0)
            rc = tpk_diag_fail(diag, "cut faces: out of memory");
    }
    if (rc == 0)
        rc = tpk_alltoallv(comm, replies, reply_counts, sizeof *replies, (void **)&back, back_counts, &back_total,
                           diag);
    if (rc == 0 && tpk_agree(comm, bad) != 0)
        rc = tpk_diag_fail(diag, "cut faces: a face is shared by more than two tets across the pieces (the "
                           "pieces do not form one conforming mesh)");
    if (rc == 0 && !(*links = malloc(sizeof **links * (size_t)(back_total ? back_total : 1))))
        rc = tpk_diag_fail(diag, "cut faces: out of memory");
    for (int64_t i = 0; rc == 0 && i < back_total; i++)
        (*links)[i] = (tpk_link){(int32_t)back[i].shell, (int32_t)back[i].part, (int32_t)back[i].other_shell,
                                 (int32_t)back[i].other_tet};
    if (rc == 0) {
        qsort(*links, (size_t)back_total, sizeof **links, compare_links);
        *link_count = back_total;
    }
    free(counts), free(send), free(recv), free(replies), free(back);
    return rc;
}
