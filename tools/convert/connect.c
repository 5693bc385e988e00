/* Face matching (pipeline stage 4), sort-based and multithreaded (docs/ARCHITECTURE.md §4).
 * A counting sort puts every tet into two buckets, by the rule of mesh/face_buckets.h: bucket s0 for its
 * three faces that contain its smallest id s0, bucket s1 for its face opposite s0. So bucket v holds
 * exactly the faces whose smallest id is v, with only 4 bytes per tet per bucket (the tet id, and one
 * bit for which of the two roles). Buckets are small (about 12 tets, 24 faces in a typical mesh): each
 * is expanded into its faces and matched with a small hash table keyed by the other two ids: a face
 * seen once is a boundary face, twice makes neighbors, more is an error. Workers take contiguous tet
 * ranges and bucket ranges, so the result does not depend on timing. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "mesh/face_buckets.h"
#include "pipeline.h"

#define MAX_LISTED_TETS 16
#define ROLE_S1 0x80000000u /* bucket entry flag: the tet's face opposite s0, not its three s0 faces */
#define ID_MASK 0x7fffffffu
/* A face's slot (4 * tet + k) carries, in bit 62, the parity of its outward vertex order (tpk_tet_faces)
 * against ascending ids: two positive tets that share a face see it in opposite orders unless it folds. */
#define SLOT_ODD ((int64_t)1 << 62)
#define SLOT_MASK (SLOT_ODD - 1)

static inline int has_repeat(const int32_t *v)
{
    return (v[0] == v[1]) | (v[0] == v[2]) | (v[0] == v[3]) | (v[1] == v[2]) | (v[1] == v[3]) | (v[2] == v[3]);
}

/* Scratch of one worker for matching a bucket. */
typedef struct bucket_scratch {
    uint64_t *faces;  /* (mid << 31 | max) per face of the bucket */
    int64_t *slots;   /* 4 * tet + k per face, and SLOT_ODD */
    int32_t *table;   /* open addressing over face indices */
    int64_t *agree;   /* pairs of slots whose faces' orders agree (fold candidates), when asked */
    int64_t agree_count, agree_cap;
    int agree_failed; /* out of memory for them */
} bucket_scratch;

typedef struct connect_job {
    const int32_t *tets;
    int64_t tet_count, vertex_count;
    int threads;
    uint32_t *starts[TPK_MAX_THREADS]; /* per worker, per vertex: count, then next slot (< 2 * tet_count < 2^32;
                                        * 32 bits: these arrays are part of the converter's peak memory) */
    const uint32_t *bucket_end;       /* after the scatter: the last worker's next slots, which are where each
                                       * bucket ends (bucket v is [v ? end[v - 1] : 0, end[v])); no array of
                                       * its own, as that would add to the peak */
    int64_t largest_bucket;
    uint32_t *entries;                /* 2 * tet_count: tet | ROLE_S1 */
    bucket_scratch scratch[TPK_MAX_THREADS];
    int32_t *neighbors;
    int64_t bucket_begin[TPK_MAX_THREADS + 1];
    int64_t bad_tet[TPK_MAX_THREADS];    /* first tet with an id out of range or repeated, or -1 */
    int64_t bad_bucket[TPK_MAX_THREADS]; /* first bucket with a face of 3+ tets, or -1 */
    uint64_t bad_face[TPK_MAX_THREADS];  /* that face (mid << 31 | max) */
    int want_folds;                      /* keep the fold candidates (scratch[w].agree) */
} connect_job;

static inline uint64_t face_key(int32_t mid, int32_t max)
{
    return (uint64_t)(uint32_t)mid << 31 | (uint32_t)max;
}

static void count_entries(void *ctx, int64_t begin, int64_t end, int worker)
{
    connect_job *job = ctx;
    uint32_t *count = job->starts[worker];
    memset(count, 0, sizeof *count * (size_t)job->vertex_count);
    job->bad_tet[worker] = -1;
    for (int64_t t = begin; t < end; t++) {
        const int32_t *v = job->tets + 4 * t;
        if (has_repeat(v)) {
            job->bad_tet[worker] = t;
            return;
        }
        tpk_sorted_tet s;
        tpk_sort_tet(v, &s);
        if (s.id[0] < 0 || s.id[3] >= job->vertex_count) {
            job->bad_tet[worker] = t;
            return;
        }
        count[s.id[0]]++;
        count[s.id[1]]++;
    }
}

static void scatter_entries(void *ctx, int64_t begin, int64_t end, int worker)
{
    connect_job *job = ctx;
    uint32_t *next = job->starts[worker];
    uint32_t *entries = job->entries;
    for (int64_t t = begin; t < end; t++) {
        tpk_sorted_tet s;
        tpk_sort_tet(job->tets + 4 * t, &s);
        entries[next[s.id[0]]++] = (uint32_t)t;
        entries[next[s.id[1]]++] = (uint32_t)t | ROLE_S1;
    }
}

static inline int64_t bucket_first(const connect_job *job, int64_t b)
{
    return b ? (int64_t)job->bucket_end[b - 1] : 0;
}

static inline int64_t face_parity(const int32_t *v, int k)
{
    return tpk_face_parity(v, k) ? SLOT_ODD : 0;
}

static inline void put_face(uint64_t *faces, int64_t *slots, int64_t at, int64_t t, const int32_t *v,
                            const tpk_bucket_face *f)
{
    faces[at] = face_key(f->mid, f->max);
    slots[at] = (4 * t + f->opposite) | face_parity(v, f->opposite);
}

/* Expands a bucket's entries into faces; returns the face count. */
static int64_t bucket_faces(const connect_job *job, int64_t b, uint64_t *faces, int64_t *slots)
{
    int64_t n = 0, end = job->bucket_end[b];
    for (int64_t i = bucket_first(job, b); i < end; i++) {
        if (i + 8 < 2 * job->tet_count) /* tets of a bucket are scattered in memory */
            __builtin_prefetch(job->tets + 4 * (int64_t)(job->entries[i + 8] & ID_MASK));
        uint32_t entry = job->entries[i];
        int64_t t = entry & ID_MASK;
        const int32_t *v = job->tets + 4 * t;
        tpk_sorted_tet s;
        tpk_sort_tet(v, &s);
        tpk_bucket_face f[3];
        if (entry & ROLE_S1) { /* each branch with its own count, so both are unrolled */
            tpk_tet_bucket_faces(&s, 0, f);
            put_face(faces, slots, n++, t, v, &f[0]);
        } else {
            tpk_tet_bucket_faces(&s, 1, f);
            for (int i = 0; i < 3; i++)
                put_face(faces, slots, n++, t, v, &f[i]);
        }
    }
    return n;
}

static void keep_agreeing(bucket_scratch *s, int64_t a, int64_t b)
{
    if (s->agree_count + 2 > s->agree_cap) {
        int64_t cap = s->agree_cap ? 2 * s->agree_cap : 64;
        int64_t *grown = realloc(s->agree, sizeof *grown * (size_t)cap);
        if (!grown) {
            s->agree_failed = 1;
            return;
        }
        s->agree = grown;
        s->agree_cap = cap;
    }
    s->agree[s->agree_count++] = a;
    s->agree[s->agree_count++] = b;
}

/* Table values: -1 empty; i >= 0 the first face i of a face key seen once; -2 - i seen twice.
 * Returns nonzero (and the face) if a face key occurs three times or more. With `agree`, the pairs whose
 * faces' orders agree go there. */
static int match_bucket(const uint64_t *faces, const int64_t *slots, int64_t n, int32_t *table,
                        int32_t *neighbors, uint64_t *bad_face, bucket_scratch *agree)
{
    if (n == 1) {
        neighbors[slots[0] & SLOT_MASK] = -1;
        return 0;
    }
    int bits = 2;
    while (((int64_t)1 << bits) < 2 * n)
        bits++;
    uint32_t mask = (1u << bits) - 1;
    memset(table, 0xff, sizeof *table << bits);
    int failed = 0;
    for (int64_t i = 0; i < n; i++) {
        uint32_t h = (uint32_t)((faces[i] * 0x9e3779b97f4a7c15ull) >> (64 - bits));
        for (;; h = (h + 1) & mask) {
            int32_t at = table[h];
            if (at == -1) {
                table[h] = (int32_t)i;
                neighbors[slots[i] & SLOT_MASK] = -1;
                break;
            }
            int32_t first = at >= 0 ? at : -2 - at;
            if (faces[first] != faces[i])
                continue;
            if (at >= 0) {
                int64_t si = slots[i] & SLOT_MASK, sa = slots[at] & SLOT_MASK;
                table[h] = -2 - at;
                neighbors[si] = (int32_t)(sa >> 2);
                neighbors[sa] = (int32_t)(si >> 2);
                if (agree && !((slots[i] ^ slots[at]) & SLOT_ODD))
                    keep_agreeing(agree, si, sa);
            } else {
                neighbors[slots[i] & SLOT_MASK] = -1;
                if (!failed)
                    *bad_face = faces[i];
                failed = 1;
            }
            break;
        }
    }
    return failed;
}

static void match_faces(void *ctx, int64_t begin, int64_t end, int worker)
{
    connect_job *job = ctx;
    bucket_scratch *scratch = &job->scratch[worker];
    (void)begin;
    (void)end;
    job->bad_bucket[worker] = -1;
    for (int64_t b = job->bucket_begin[worker]; b < job->bucket_begin[worker + 1]; b++) {
        int64_t n = bucket_faces(job, b, scratch->faces, scratch->slots);
        uint64_t face = 0;
        if (n > 0 &&
            match_bucket(scratch->faces, scratch->slots, n, scratch->table, job->neighbors, &face,
                         job->want_folds ? scratch : NULL) &&
            job->bad_bucket[worker] < 0) {
            job->bad_bucket[worker] = b;
            job->bad_face[worker] = face;
        }
    }
}

static int report_shared_face(const connect_job *job, int w, tpk_diag *diag)
{
    const bucket_scratch *scratch = &job->scratch[w];
    int64_t b = job->bad_bucket[w], run = 0;
    uint64_t face = job->bad_face[w];
    int32_t listed[MAX_LISTED_TETS];
    int64_t n = bucket_faces(job, b, scratch->faces, scratch->slots);
    for (int64_t i = 0; i < n; i++)
        if (scratch->faces[i] == face && run++ < MAX_LISTED_TETS)
            listed[run - 1] = (int32_t)((scratch->slots[i] & SLOT_MASK) >> 2);
    int shown = run < MAX_LISTED_TETS ? (int)run : MAX_LISTED_TETS;
    qsort(listed, (size_t)shown, sizeof *listed, tpk_compare_int32);
    char list[256] = "";
    size_t used = 0;
    for (int i = 0; i < shown && used < sizeof list; i++) {
        int wrote = snprintf(list + used, sizeof list - used, "%s%d", i ? ", " : "", listed[i]);
        if (wrote < 0)
            break;
        used += (size_t)wrote;
    }
    return tpk_diag_fail(diag, "face (%lld, %lld, %lld) is shared by %lld tets: %s%s; a face can bound "
                         "at most two tets (overlapping or non-manifold cells)",
                         (long long)b, (long long)(face >> 31), (long long)(face & ID_MASK), (long long)run,
                         list, run > shown ? ", ..." : "");
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
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        tpk_free_large(job->starts[w], sizeof *job->starts[w] * (size_t)(job->vertex_count ? job->vertex_count : 1));
        free(job->scratch[w].faces);
        free(job->scratch[w].slots);
        free(job->scratch[w].table);
        free(job->scratch[w].agree);
    }
    tpk_free_large(job->entries, sizeof *job->entries * 2 * (size_t)job->tet_count);
    free(job);
}

/* Each worker's count becomes its first slot: the workers' parts of a bucket follow each other in
 * worker order, and the buckets in vertex order. */
static void prefix_counts(connect_job *job)
{
    int64_t running = 0, largest = 0;
    for (int64_t v = 0; v < job->vertex_count; v++) {
        int64_t begin = running;
        for (int w = 0; w < job->threads; w++) {
            int64_t c = job->starts[w][v];
            job->starts[w][v] = (uint32_t)running;
            running += c;
        }
        if (running - begin > largest)
            largest = running - begin;
    }
    job->largest_bucket = largest;
}

static int64_t first_entry(const void *ctx, int64_t b)
{
    return bucket_first(ctx, b);
}

/* Bucket ranges for the workers, about the same number of entries each (2 per tet). */
static void split_buckets(connect_job *job)
{
    tpk_split_by(first_entry, job, job->vertex_count, 2 * job->tet_count, job->threads, job->bucket_begin);
}

static int alloc_scratch(connect_job *job)
{
    size_t faces = 3 * (size_t)job->largest_bucket, table = 4;
    while (table < 2 * faces)
        table *= 2;
    for (int w = 0; w < job->threads; w++) {
        bucket_scratch *s = &job->scratch[w];
        s->faces = malloc(sizeof *s->faces * faces);
        s->slots = malloc(sizeof *s->slots * faces);
        s->table = malloc(sizeof *s->table * table);
        if (!s->faces || !s->slots || !s->table)
            return -1;
    }
    return 0;
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
        if (job->scratch[w].agree_failed)
            return tpk_diag_fail(diag, "folds: out of memory for the folded faces");
        total += job->scratch[w].agree_count / 2;
    }
    if (total == 0)
        return 0;
    int64_t *found = malloc(sizeof *found * (size_t)total), n = 0;
    if (!found)
        return tpk_diag_fail(diag, "folds: out of memory for the folded faces");
    for (int w = 0; w < job->threads; w++)
        for (int64_t i = 0; i < job->scratch[w].agree_count; i += 2) {
            int64_t a = job->scratch[w].agree[i], b = job->scratch[w].agree[i + 1];
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
                       int32_t *neighbors, int threads, int64_t **fold_slots, int64_t *fold_count, tpk_diag *diag)
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
    job->tet_count = tet_count;
    job->vertex_count = vertex_count;
    job->neighbors = neighbors;
    job->threads = tpk_threads_for(tet_count, tpk_thread_count(threads), 32768);
    job->want_folds = fold_slots != NULL;
    job->entries = tpk_alloc_large(sizeof *job->entries * 2 * (size_t)tet_count);
    int ok = job->entries != NULL;
    for (int w = 0; w < job->threads && ok; w++)
        ok = (job->starts[w] = tpk_alloc_large(sizeof *job->starts[w] * (size_t)(vertex_count ? vertex_count : 1))) != NULL;
    if (!ok) {
        free_job(job);
        return tpk_diag_fail(diag, "connect: out of memory (%lld tets)", (long long)tet_count);
    }

    tpk_parallel_for(tet_count, job->threads, count_entries, job);
    for (int w = 0; w < job->threads; w++) {
        if (job->bad_tet[w] >= 0) {
            int rc = report_bad_tet(job, job->bad_tet[w], diag);
            free_job(job);
            return rc;
        }
    }
    prefix_counts(job);
    if (alloc_scratch(job)) {
        long long largest = (long long)job->largest_bucket;
        free_job(job);
        return tpk_diag_fail(diag, "connect: out of memory (a vertex is the smallest id of %lld tets)", largest);
    }
    tpk_parallel_for(tet_count, job->threads, scatter_entries, job);
    job->bucket_end = job->starts[job->threads - 1];
    split_buckets(job);
    tpk_parallel_for(job->threads, job->threads, match_faces, job);
    int rc = 0;
    for (int w = 0; w < job->threads && !rc; w++)
        if (job->bad_bucket[w] >= 0)
            rc = report_shared_face(job, w, diag);
    if (rc == 0 && fold_slots)
        rc = confirm_folds(job, points, fold_slots, fold_count, diag);
    free_job(job);
    return rc;
}

int tpk_connect(const int32_t *tets, int64_t tet_count, int64_t vertex_count, int32_t *neighbors,
                int threads, tpk_diag *diag)
{
    return connect_run(tets, tet_count, vertex_count, NULL, neighbors, threads, NULL, NULL, diag);
}

int tpk_connect_folds(const int32_t *tets, int64_t tet_count, int64_t vertex_count, const double *points,
                      int32_t *neighbors, int threads, int64_t **slots, int64_t *count, tpk_diag *diag)
{
    return connect_run(tets, tet_count, vertex_count, points, neighbors, threads, slots, count, diag);
}
