/* Face matching (pipeline stage 4, docs/ARCHITECTURE.md §4): the face matcher (mesh/face_match.h) in its
 * neighbours mode, sort-based and multithreaded, with the converter's messages; the fold candidates it
 * finds (pairs whose outward orders agree) kept per worker and confirmed by the exact test. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/grow.h"
#include "base/parallel.h"
#include "mesh/face_match.h"
#include "pipeline.h"

/* From this many tets on, connect matches faces in two windows of vertex ids, one after the other: the
 * matcher's entries (8 bytes a tet) are what connect adds to the tets and neighbors at the converter's
 * peak, and each window holds about half of them (reorder put the vertices in Hilbert order, so either
 * half starts about as many faces). Grid 120's peak: 531 -> 485 MiB in connect (bench/README). The tets
 * are counted into their buckets once for both windows (face_match.h `windows`). */
#define CONNECT_WINDOWED (INT64_C(1) << 20)

/* Per worker: pairs of slots (4 * tet + k) whose faces' orders agree (fold candidates), when asked. */
typedef struct agree_list {
    int64_t *slots;
    int64_t count, cap;
    int failed; /* out of memory for them */
} agree_list;

typedef struct connect_job {
    const int32_t *tets;
    int64_t vertex_count;
    int threads;
    agree_list agree[TPK_MAX_THREADS];
} connect_job;

static void keep_agreeing(void *user, int worker, int64_t a, int64_t b)
{
    agree_list *s = &((connect_job *)user)->agree[worker];
    if (s->count + 2 > s->cap) {
        int64_t *grown = tpk_grow(s->slots, &s->cap, s->count + 2, sizeof *grown, 64);
        if (!grown) {
            s->failed = 1;
            return;
        }
        s->slots = grown;
    }
    s->slots[s->count++] = a;
    s->slots[s->count++] = b;
}

static int report_shared_face(const tpk_match_failure *f, tpk_diag *diag)
{
    char list[256] = "";
    size_t used = 0;
    for (int i = 0; i < f->listed_count && used < sizeof list; i++) {
        int wrote = snprintf(list + used, sizeof list - used, "%s%d", i ? ", " : "", f->listed[i]);
        if (wrote < 0)
            break;
        used += (size_t)wrote;
    }
    return tpk_diag_fail(diag, "face (%lld, %lld, %lld) is shared by %lld tets: %s%s; a face can bound "
                         "at most two tets (overlapping or non-manifold cells)",
                         (long long)f->shared_ids[0], (long long)f->shared_ids[1], (long long)f->shared_ids[2],
                         (long long)f->shared_count, list, f->shared_count > f->listed_count ? ", ..." : "");
}

static int report_bad_tet(const connect_job *job, int64_t t, tpk_diag *diag)
{
    const int32_t *v = job->tets + 4 * t;
    int out_of_range = 0;
    for (int k = 0; k < 4; k++)
        out_of_range |= v[k] < 0 || v[k] >= job->vertex_count;
    return tpk_diag_fail(diag, "connect: tet %lld has vertices (%d, %d, %d, %d): %s", (long long)t, v[0],
                         v[1], v[2], v[3],
                         out_of_range ? "an id is out of range" : "a vertex is repeated (orient drops such tets)");
}

static void free_job(connect_job *job)
{
    for (int w = 0; w < TPK_MAX_THREADS; w++)
        free(job->agree[w].slots);
    free(job);
}

static int compare_int64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* The candidates of every worker, each confirmed by the exact test from its lower tet: *slots ascending. */
static int confirm_folds(const connect_job *job, const double *points, int64_t **slots, int64_t *count,
                         tpk_diag *diag)
{
    int64_t total = 0;
    for (int w = 0; w < job->threads; w++) {
        if (job->agree[w].failed)
            return tpk_diag_fail(diag, "folds: out of memory for the folded faces");
        total += job->agree[w].count / 2;
    }
    if (total == 0)
        return 0;
    int64_t *found = malloc(sizeof *found * (size_t)total), n = 0;
    if (!found)
        return tpk_diag_fail(diag, "folds: out of memory for the folded faces");
    for (int w = 0; w < job->threads; w++)
        for (int64_t i = 0; i < job->agree[w].count; i += 2) {
            int64_t a = job->agree[w].slots[i], b = job->agree[w].slots[i + 1];
            int64_t lower = (a >> 2) < (b >> 2) ? a : b, upper = lower == a ? b : a;
            if (tpk_face_folded(job->tets, points, lower >> 2, (int)(lower & 3), upper >> 2))
                found[n++] = lower;
        }
    qsort(found, (size_t)n, sizeof *found, compare_int64);
    if (n == 0) {
        free(found);
        found = NULL;
    }
    *slots = found;
    *count = n;
    return 0;
}

static int connect_run(const int32_t *tets, int64_t tet_count, int64_t vertex_count, const double *points,
                       int32_t *neighbors, int windows, int threads, int64_t **fold_slots, int64_t *fold_count,
                       tpk_diag *diag)
{
    if (fold_slots) {
        *fold_slots = NULL;
        *fold_count = 0;
    }

    if (tet_count < 0 || vertex_count < 0 || (tet_count > 0 && (!tets || !neighbors)))
        return tpk_diag_fail(diag, "connect: invalid arguments");
    if (tet_count > INT32_MAX || vertex_count > INT32_MAX)
        return tpk_diag_fail(diag, "connect: %lld tets and %lld vertices exceed the limit of 2^31-1",
                             (long long)tet_count, (long long)vertex_count);
    if (tet_count == 0)
        return 0;
    connect_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "connect: out of memory");
    job->tets = tets;
    job->vertex_count = vertex_count;
    job->threads = tpk_threads_for(tet_count, tpk_thread_count(threads), 32768);
    /* Windows of vertex ids, one after the other: a face lies in one window with both its tets, so the
     * neighbors are those of one pass, and the first bad face is still the one with the smallest ids. */
    if (windows < 1)
        windows = tet_count >= CONNECT_WINDOWED ? 2 : 1;
    tpk_match_failure failure;
    tpk_face_matcher m = {.item_count = tet_count, .vertex_count = vertex_count, .windows = windows,
                          .threads = job->threads, .user = job, .tets = tets, .check_ids = 1,
                          .neighbors = neighbors, .agreeing = fold_slots ? keep_agreeing : NULL};
    int rc = tpk_face_match(&m, &failure);
    if (rc == TPK_MATCH_BAD_ITEM)
        rc = report_bad_tet(job, failure.bad_item, diag);
    else if (rc == TPK_MATCH_SHARED)
        rc = report_shared_face(&failure, diag);
    else if (rc == TPK_MATCH_NOMEM && failure.largest > 0)
        rc = tpk_diag_fail(diag, "connect: out of memory (a vertex is the smallest id of %lld tets)",
                           (long long)failure.largest);
    else if (rc != TPK_MATCH_OK)
        rc = tpk_diag_fail(diag, "connect: out of memory (%lld tets)", (long long)tet_count);
    if (rc == 0 && fold_slots)
        rc = confirm_folds(job, points, fold_slots, fold_count, diag);
    free_job(job);
    return rc;
}

int tpk_connect(const int32_t *tets, int64_t tet_count, int64_t vertex_count, int32_t *neighbors,
                int threads, tpk_diag *diag)
{
    return connect_run(tets, tet_count, vertex_count, NULL, neighbors, 0, threads, NULL, NULL, diag);
}

int tpk_connect_windows(const int32_t *tets, int64_t tet_count, int64_t vertex_count, int32_t *neighbors,
                        int windows, int threads, tpk_diag *diag)
{
    return connect_run(tets, tet_count, vertex_count, NULL, neighbors, windows > 0 ? windows : 1, threads, NULL,
                       NULL, diag);
}

int tpk_connect_folds(const int32_t *tets, int64_t tet_count, int64_t vertex_count, const double *points,
                      int32_t *neighbors, int threads, int64_t **slots, int64_t *count, tpk_diag *diag)
{
    return connect_run(tets, tet_count, vertex_count, points, neighbors, 0, threads, slots, count, diag);
}
