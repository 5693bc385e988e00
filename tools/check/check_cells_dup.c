/* 211 duplicate_cell: a usable volume cell (any type, lower-dimensional cells excluded) whose vertex set
 * equals that of a lower-numbered cell; the example names both. Two such cells share their smallest
 * vertex, so cells are bucketed by it (a counting sort: 8 bytes per cell, 4 per vertex and counting
 * worker) and only the cells of one bucket are compared, by a hash of the sorted ids first, then by the
 * ids themselves. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/cell_types.h"
#include "check_cells_internal.h"
#include "base/parallel.h"

#define NO_BUCKET UINT32_MAX

typedef struct dup_pair {
    int64_t cell, first; /* `cell` repeats the vertex set of `first` (< cell) */
} dup_pair;

typedef struct dup_worker {
    int64_t count;
    dup_pair *heap; /* the lowest `cap` pairs by cell: a max-heap */
    int size, cap;
} dup_worker;

typedef struct dup_key {
    uint32_t hash, cell;
} dup_key;

typedef struct dup_job {
    const tpk_mesh *mesh;
    uint32_t *cursor[TPK_MAX_THREADS]; /* per counting worker and vertex: its cells there, then its next
                                          slot (no atomics: a shuffled mesh makes every access a miss,
                                          and plain stores can overlap where locked ones cannot) */
    const uint32_t *bucket_end;        /* the last worker's cursors after the scatter: each bucket's end */
    struct dup_key *keys; /* usable cells grouped by smallest vertex, each with a hash of its sorted ids
                             (so buckets are compared without going back to the cells) */
    uint8_t volume[256];  /* cell types of dimension 3 */
    int max_examples;
    dup_worker workers[TPK_MAX_THREADS];
} dup_job;


/* Sorted vertex ids of a usable volume cell into `out` (64 at most); 0 when the cell takes no part.
 * Usable as tpk_check_cell_usable says (ids in range, none repeated), decided on the sorted ids: this
 * runs twice per cell, so it avoids that call's quadratic scan. */
static int cell_key(const dup_job *job, int64_t cell, int32_t *out)
{
    const tpk_mesh *mesh = job->mesh;
    int64_t b = mesh->cell_offsets[cell], e = mesh->cell_offsets[cell + 1];
    if (!job->volume[mesh->cell_types[cell]] || e - b < 1 || e - b > 64)
        return 0;
    int n = (int)(e - b);
    for (int i = 0; i < n; i++) { /* insertion sort: a handful of ids */
        int32_t id = mesh->cell_conn[b + i];
        int j = i;
        for (; j > 0 && out[j - 1] > id; j--)
            out[j] = out[j - 1];
        out[j] = id;
    }
    if (out[0] < 0 || out[n - 1] >= mesh->point_count)
        return 0;
    for (int i = 1; i < n; i++)
        if (out[i] == out[i - 1])
            return 0;
    return n;
}

static uint64_t key_hash(const int32_t *ids, int n)
{
    uint64_t h = 0x9e3779b97f4a7c15ull ^ (uint64_t)n;
    for (int i = 0; i < n; i++) {
        h ^= (uint64_t)(uint32_t)ids[i];
        h *= 0xff51afd7ed558ccdull;
        h ^= h >> 32;
    }
    return h;
}

static void count_buckets(void *ctx, int64_t begin, int64_t end, int worker)
{
    dup_job *job = ctx;
    int32_t key[64];
    uint32_t *count = job->cursor[worker];
    for (int64_t c = begin; c < end; c++)
        if (cell_key(job, c, key))
            count[key[0]]++;
}

static void scatter_cells(void *ctx, int64_t begin, int64_t end, int worker)
{
    dup_job *job = ctx;
    int32_t key[64];
    uint32_t *next = job->cursor[worker];
    for (int64_t c = begin; c < end; c++) {
        int n = cell_key(job, c, key);
        if (n) {
            uint32_t at = next[key[0]]++;
            job->keys[at] = (dup_key){(uint32_t)key_hash(key, n), (uint32_t)c};
        }
    }
}

static void heap_push(dup_worker *w, dup_pair pair)
{
    w->count++;
    if (w->cap == 0)
        return;
    if (w->size < w->cap) { /* sift up */
        int i = w->size++;
        while (i > 0 && w->heap[(i - 1) / 2].cell < pair.cell) {
            w->heap[i] = w->heap[(i - 1) / 2];
            i = (i - 1) / 2;
        }
        w->heap[i] = pair;
        return;
    }
    if (pair.cell >= w->heap[0].cell)
        return; /* full, and every kept pair is lower */
    int i = 0; /* replace the largest, sift down */
    for (;;) {
        int l = 2 * i + 1, r = l + 1, top = -1;
        int64_t largest = pair.cell;
        if (l < w->size && w->heap[l].cell > largest)
            top = l, largest = w->heap[l].cell;
        if (r < w->size && w->heap[r].cell > largest)
            top = r;
        if (top < 0)
            break;
        w->heap[i] = w->heap[top];
        i = top;
    }
    w->heap[i] = pair;
}

static int compare_keys(const void *a, const void *b)
{
    const dup_key *x = a, *y = b;
    if (x->hash != y->hash)
        return x->hash < y->hash ? -1 : 1;
    return x->cell < y->cell ? -1 : x->cell > y->cell;
}

/* Sorted by (hash, cell): within a run of equal hashes, a cell repeats the first earlier one whose ids
 * are equal (a hash collision only costs a comparison). */
static void report_run(dup_job *job, dup_worker *w, const dup_key *keys, int n)
{
    int32_t a[64], b[64];
    for (int i = 1; i < n; i++) {
        int na = cell_key(job, keys[i].cell, a);
        for (int j = 0; j < i; j++) {
            int nb = cell_key(job, keys[j].cell, b);
            if (na == nb && !memcmp(a, b, (size_t)na * sizeof *a)) {
                heap_push(w, (dup_pair){keys[i].cell, keys[j].cell});
                break;
            }
        }
    }
}

static void search_buckets(void *ctx, int64_t begin, int64_t end, int worker)
{
    dup_job *job = ctx;
    dup_worker *w = &job->workers[worker];
    for (int64_t v = begin; v < end; v++) {
        uint32_t first = v == 0 ? 0 : job->bucket_end[v - 1], last = job->bucket_end[v];
        size_t n = last - first;
        if (n < 2)
            continue;
        dup_key *keys = job->keys + first;
        if (n > 16) {
            qsort(keys, n, sizeof *keys, compare_keys);
        } else { /* most buckets: a few cells */
            for (size_t i = 1; i < n; i++) {
                dup_key k = keys[i];
                size_t j = i;
                for (; j > 0 && compare_keys(&keys[j - 1], &k) > 0; j--)
                    keys[j] = keys[j - 1];
                keys[j] = k;
            }
        }
        for (size_t i = 0; i < n;) {
            size_t j = i + 1;
            while (j < n && keys[j].hash == keys[i].hash)
                j++;
            if (j - i > 1)
                report_run(job, w, keys + i, (int)(j - i));
            i = j;
        }
    }
}

static int compare_pairs(const void *a, const void *b)
{
    const dup_pair *x = a, *y = b;
    return x->cell < y->cell ? -1 : x->cell > y->cell;
}

static void report_pairs(dup_job *job, int threads, tpk_check_report *report)
{
    int total = 0;
    int64_t count = 0;
    for (int t = 0; t < threads; t++) {
        count += job->workers[t].count;
        total += job->workers[t].size;
    }
    dup_pair *all = malloc((size_t)(total ? total : 1) * sizeof *all);
    int n = 0;
    for (int t = 0; t < threads && all; t++)
        for (int i = 0; i < job->workers[t].size; i++)
            all[n++] = job->workers[t].heap[i];
    if (all)
        qsort(all, (size_t)n, sizeof *all, compare_pairs);
    int shown = all && n < job->max_examples ? n : all ? job->max_examples : 0;
    for (int i = 0; i < shown; i++) {
        tpk_example *ex = tpk_check_hit(report, 211, "cell");
        int64_t ids[2] = {all[i].cell, all[i].first};
        tpk_example_ids(ex, 2, ids);
        double centre[3];
        tpk_cell_centre(job->mesh, all[i].cell, centre);
        tpk_example_point(ex, centre);
        tpk_example_note(ex, "same vertices as cell %lld", (long long)all[i].first);
    }
    tpk_check_count(report, 211, count - shown);
    free(all);
}

int tpk_check_duplicate_cells(const tpk_mesh *mesh, int threads, tpk_check_report *report, tpk_diag *diag)
{
    if (mesh->cell_count == 0 || mesh->point_count == 0)
        return 0;
    if (mesh->cell_count >= (int64_t)NO_BUCKET) {
        snprintf(tpk_check_finding(report, 211)->summary, sizeof tpk_check_finding(report, 211)->summary,
                 "not checked: more than 2^32 cells");
        return 0;
    }
    dup_job *job = calloc(1, sizeof *job);
    int rc = -1;
    if (!job)
        goto done;
    job->mesh = mesh;
    for (int t = 0; t < 256; t++) {
        const tpk_cell_type_info *info = t == 41 ? NULL : tpk_cell_type(t);
        job->volume[t] = info && info->dim == 3;
    }
    job->max_examples = report->options.max_examples;
    /* Workers' cells land in cell order inside each bucket. Private counts cost 4 bytes per vertex and
     * worker, so there are at most cells / vertices of them (about 6 for tets). */
    int64_t most = mesh->cell_count / mesh->point_count;
    int cell_threads = tpk_threads_for(mesh->cell_count, threads < most ? threads : (int)(most ? most : 1), 65536);
    for (int t = 0; t < cell_threads; t++)
        if (!(job->cursor[t] = calloc((size_t)mesh->point_count, sizeof *job->cursor[t])))
            goto done;
    tpk_parallel_for(mesh->cell_count, cell_threads, count_buckets, job);
    uint32_t usable = 0;
    for (int64_t v = 0; v < mesh->point_count; v++) /* exclusive prefix sum over (vertex, worker) */
        for (int t = 0; t < cell_threads; t++) {
            uint32_t n = job->cursor[t][v];
            job->cursor[t][v] = usable;
            usable += n;
        }
    if (!(job->keys = malloc((size_t)(usable ? usable : 1) * sizeof *job->keys)))
        goto done;
    tpk_parallel_for(mesh->cell_count, cell_threads, scatter_cells, job);
    job->bucket_end = job->cursor[cell_threads - 1];
    int point_threads = tpk_threads_for(mesh->point_count, threads, 65536);
    for (int t = 0; t < point_threads; t++) {
        job->workers[t].cap = job->max_examples;
        if (job->max_examples && !(job->workers[t].heap = malloc((size_t)job->max_examples * sizeof(dup_pair))))
            goto done;
    }
    tpk_parallel_for(mesh->point_count, point_threads, search_buckets, job);
    report_pairs(job, point_threads, report);
    rc = 0;
done:
    if (job) {
        for (int t = 0; t < TPK_MAX_THREADS; t++)
            free(job->workers[t].heap);
        for (int t = 0; t < TPK_MAX_THREADS; t++)
            free(job->cursor[t]);
        free(job->keys);
    }
    free(job);
    if (rc)
        return tpk_diag_fail(diag, "check cells: out of memory looking for duplicate cells (%lld cells)",
                             (long long)mesh->cell_count);
    return rc;
}
