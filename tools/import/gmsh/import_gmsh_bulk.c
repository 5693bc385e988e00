/* Gmsh importer: the 4.1 node and element blocks on all threads, binary straight from the mapping, ASCII
 * in pieces read by tpk_scan_numbers (cut at whitespace). What they take lands where one-by-one reading
 * (import_gmsh_mesh.c) puts it, for any thread count; what they do not take is left to that reader, with
 * the scanner where it would have it, so that any failure reads the same. Calls only import_gmsh_scan.c. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "import_gmsh_internal.h"
#include "base/parallel.h"
#include "base/text_numbers.h"
#include "base/text_scan.h"

/* Numbers in one ASCII piece at most (16 MiB of scratch): a fixed size, so the pieces, and where a piece
 * that does not read cleanly starts, do not depend on the thread count. */
#define PIECE_NUMBERS ((int64_t)1 << 21)
/* Fewer numbers than this are read one by one (tpk_scan_numbers declines them anyway). */
#define MIN_NUMBERS 65536

int32_t gmsh_lookup(const tag_index *t, int64_t n, int64_t tag, int *found)
{
    int64_t lo = 0, hi = n;
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (t[mid].tag < tag)
            lo = mid + 1;
        else
            hi = mid;
    }
    *found = lo < n && t[lo].tag == tag;
    return *found ? t[lo].index : -1;
}

int32_t gmsh_node_at(const gmsh_reader *r, int64_t tag, int *found)
{
    if (r->node_dense) {
        *found = tag >= 1 && tag <= r->point_count;
        return *found ? (int32_t)(tag - 1) : -1;
    }
    if (r->node_at) {
        int32_t i = tag >= 0 && tag <= r->node_at_max ? r->node_at[tag] : -1;
        *found = i >= 0;
        return i;
    }
    return gmsh_lookup(r->node_tags, r->point_count, tag, found);
}

int gmsh_index_nodes(gmsh_reader *r)
{
    int64_t n = r->point_count;
    if (r->node_dense || n == 0)
        return 0;
    int64_t max = r->node_tags[n - 1].tag; /* sorted */
    if (max > 4 * n + 4096 || max >= INT32_MAX)
        return 0; /* spread out: the binary search, rather than 4 bytes a possible tag */
    /* a lookup per node id instead of a binary search over 16-byte entries: the search was half of
     * reading a 4.1 file whose node tags run 1, 3, 5, ... (perf) */
    r->node_at = malloc(sizeof *r->node_at * (size_t)(max + 1));
    if (!r->node_at)
        return 0; /* the search still works */
    memset(r->node_at, 0xff, sizeof *r->node_at * (size_t)(max + 1));
    for (int64_t i = 0; i < n; i++)
        r->node_at[r->node_tags[i].tag] = r->node_tags[i].index;
    r->node_at_max = max;
    return 0;
}

static inline uint64_t load_u64(const unsigned char *p)
{
    uint64_t x;
    memcpy(&x, p, sizeof x);
    return x;
}

static int threads_for(int64_t count)
{
    return tpk_threads_for(count, tpk_thread_count(0), 65536);
}

/* After a piece of `numbers` tokens was read but only its first `taken` are wanted: the scanner put back
 * to the piece's start, then those tokens read one by one, which leaves it as the one-by-one reader. */
static void rewind_to(gmsh_reader *r, const tpk_scan *saved, int64_t taken)
{
    r->s = *saved;
    const char *tok;
    for (int64_t i = 0; i < taken; i++)
        tpk_scan_token(&r->s, &tok);
}

/* ---- Node tags ---------------------------------------------------------------------------------- */

typedef struct tags_job {
    const unsigned char *src; /* count uint64 (binary), or int64 parsed (ASCII: a negative one is huge) */
    int64_t at, count;
    gmsh_reader *r;
    int64_t bad[TPK_MAX_THREADS];   /* per worker: its first tag below 1 (or above INT64_MAX), else end */
    int broken[TPK_MAX_THREADS];    /* some tag before that is not at + i + 1 */
} tags_job;

static void check_tags(void *ctx, int64_t begin, int64_t end, int w)
{
    tags_job *job = ctx;
    int64_t i = begin;
    int broken = 0;
    for (; i < end; i++) {
        uint64_t tag = load_u64(job->src + sizeof tag * (size_t)i);
        if (tag < 1 || tag > (uint64_t)INT64_MAX)
            break;
        broken |= tag != (uint64_t)(job->at + i + 1);
    }
    job->bad[w] = i;
    job->broken[w] = broken;
}

static void list_tags(void *ctx, int64_t begin, int64_t end, int w)
{
    tags_job *job = ctx;
    (void)w;
    for (int64_t i = begin; i < end; i++) {
        job->r->node_tags[job->at + i].tag = (int64_t)load_u64(job->src + sizeof(uint64_t) * (size_t)i);
        job->r->node_tags[job->at + i].index = (int32_t)(job->at + i);
    }
}

/* The tags at src noted for nodes at.. (of n): how many before the first bad one, or -1. */
static int64_t note_tags(gmsh_reader *r, const unsigned char *src, int64_t at, int64_t count, int64_t n)
{
    tags_job job = {.src = src, .at = at, .count = count, .r = r};
    int threads = threads_for(count);
    tpk_parallel_for(count, threads, check_tags, &job);
    int64_t taken = count;
    int broken = 0;
    for (int w = 0; w < threads; w++) {
        int64_t begin, end;
        tpk_parallel_range(count, threads, w, &begin, &end);
        broken |= job.broken[w];
        if (job.bad[w] < end) {
            taken = job.bad[w];
            break;
        }
    }
    if (!r->node_tags && broken && gmsh_list_node_run(r, at, n)) /* the run so far written out, the rest listed */
        return -1;
    if (r->node_tags)
        tpk_parallel_for(taken, threads_for(taken), list_tags, &job);
    return taken;
}

int gmsh_list_node_run(gmsh_reader *r, int64_t at, int64_t n)
{
    r->node_tags = malloc(sizeof *r->node_tags * (size_t)(n ? n : 1));
    if (!r->node_tags)
        return tpk_scan_fail(&r->s, "%lld nodes: out of memory", (long long)n);
    for (int64_t i = 0; i < at; i++) {
        r->node_tags[i].tag = i + 1;
        r->node_tags[i].index = (int32_t)i;
    }
    return 0;
}

int64_t gmsh_bulk_node_tags(gmsh_reader *r, int64_t at, int64_t count, int64_t n)
{
    if (r->binary) {
        if (gmsh_bytes_left(r) / sizeof(uint64_t) < (uint64_t)count)
            return 0;
        int64_t taken = note_tags(r, (const unsigned char *)r->s.data + r->s.pos, at, count, n);
        if (taken > 0) {
            r->s.pos += sizeof(uint64_t) * (size_t)taken;
            r->s.tok_pos = r->s.pos - sizeof(uint64_t); /* as gmsh_bin_bytes leaves it */
            r->s.tok_line = r->s.line;
        }
        return taken;
    }
    if (tpk_thread_count(0) < 2 || count < MIN_NUMBERS)
        return 0;
    int64_t piece = count < PIECE_NUMBERS ? count : PIECE_NUMBERS;
    int64_t *scratch = malloc(sizeof *scratch * (size_t)piece);
    if (!scratch)
        return 0;
    int64_t done = 0;
    while (count - done >= MIN_NUMBERS) {
        int64_t k = count - done < piece ? count - done : piece;
        tpk_scan saved = r->s;
        if (tpk_scan_numbers(&r->s, (uint64_t)k, TPK_NUMBER_I64, scratch, 0))
            break;
        int64_t taken = note_tags(r, (const unsigned char *)scratch, at + done, k, n);
        if (taken < 0) {
            done = -1;
            break;
        }
        done += taken;
        if (taken < k) {
            rewind_to(r, &saved, taken);
            break;
        }
        tpk_scan_release_consumed(&r->s);
    }
    free(scratch);
    return done;
}

/* ---- Coordinates -------------------------------------------------------------------------------- */

typedef struct copy_job {
    unsigned char *dst;
    const unsigned char *src;
} copy_job;

static void copy_range(void *ctx, int64_t begin, int64_t end, int w)
{
    const copy_job *job = ctx;
    (void)w;
    memcpy(job->dst + begin, job->src + begin, (size_t)(end - begin));
}

int gmsh_bulk_coords(gmsh_reader *r, int64_t at, int64_t count)
{
    double *dst = &r->points[3 * at];
    if (count == 0)
        return 0;
    if (r->binary) {
        size_t bytes = sizeof *dst * 3 * (size_t)count;
        if (gmsh_bytes_left(r) < bytes)
            return 0;
        /* on all threads: the first touch of the fresh points array is most of the cost */
        copy_job job = {(unsigned char *)dst, (const unsigned char *)r->s.data + r->s.pos};
        tpk_parallel_for((int64_t)bytes, tpk_threads_for((int64_t)bytes, tpk_thread_count(0), (int64_t)1 << 20),
                         copy_range, &job);
        r->s.pos += bytes;
        r->s.tok_pos = r->s.pos - sizeof *dst;
        r->s.tok_line = r->s.line;
        return 1;
    }
    return tpk_scan_numbers(&r->s, 3 * (uint64_t)count, TPK_NUMBER_F64, dst, 0) == 0;
}

/* ---- Elements ----------------------------------------------------------------------------------- */

typedef struct elem_job {
    const unsigned char *src; /* records of 1 + nodes uint64: tag, node tags */
    size_t record;
    const gmsh_type *t;
    gmsh_reader *r;
    int run;             /* the implicit tag run goes on: element e must have tag first_tag + e */
    uint64_t first_tag;
    int64_t cell0, conn0, elem0;
    float physical, entity;
    int64_t stop[TPK_MAX_THREADS]; /* per worker: its first element not taken, else end */
} elem_job;

static void elem_range(void *ctx, int64_t begin, int64_t end, int w)
{
    elem_job *job = ctx;
    gmsh_reader *r = job->r;
    const gmsh_type *t = job->t;
    const unsigned char *p = job->src + job->record * (size_t)begin;
    const uint64_t points = (uint64_t)r->point_count;
    int64_t e = begin;
    for (; e < end; e++, p += job->record) {
        uint64_t tag = load_u64(p);
        if (tag < 1 || tag > (uint64_t)INT64_MAX || (job->run && tag != job->first_tag + (uint64_t)e))
            break;
        int32_t ids[27];
        int ok = 1;
        if (r->node_dense) {
            for (int k = 0; k < t->nodes; k++) {
                uint64_t node = load_u64(p + sizeof(uint64_t) * (size_t)(1 + k));
                ok &= node >= 1 && node <= points;
                ids[k] = (int32_t)(node - 1);
            }
        } else {
            for (int k = 0; k < t->nodes && ok; k++) {
                uint64_t node = load_u64(p + sizeof(uint64_t) * (size_t)(1 + k));
                ids[k] = node <= (uint64_t)INT64_MAX ? gmsh_node_at(r, (int64_t)node, &ok) : (ok = 0, -1);
            }
        }
        if (!ok)
            break;
        int64_t c = job->cell0 + e, at = job->conn0 + e * t->kept;
        for (int k = 0; k < t->kept; k++)
            r->conn[at + k] = ids[gmsh_node_of(t, k)];
        r->types[c] = (uint8_t)t->vtk;
        r->offsets[c] = at;
        r->physical[c] = job->physical;
        r->entity[c] = job->entity;
        if (!job->run) {
            r->elem_tags[job->elem0 + e].tag = (int64_t)tag;
            r->elem_tags[job->elem0 + e].index = (int32_t)c;
        }
    }
    job->stop[w] = e;
}

/* The elements in `count` records at src that need nothing but copying, up to the first that needs more:
 * written and counted as finish_cell would. Returns how many, or -1 (out of memory). */
static int64_t take_elements(gmsh_reader *r, const gmsh_type *t, const unsigned char *src, int64_t count,
                             int64_t physical, int64_t entity)
{
    if (count == 0)
        return 0;
    elem_job job = {.src = src, .record = sizeof(uint64_t) * (size_t)(1 + t->nodes), .t = t, .r = r,
                    .run = !r->elem_listed, .cell0 = r->cell_count, .conn0 = r->conn_count,
                    .elem0 = r->elem_count, .physical = (float)physical, .entity = (float)entity};
    if (job.run) {
        if (r->cell_count != r->elem_count)
            return 0;
        job.first_tag = r->elem_count ? (uint64_t)r->elem_first_tag + (uint64_t)r->elem_count : load_u64(src);
        if (job.first_tag < 1 || job.first_tag > (uint64_t)INT64_MAX)
            return 0;
    } else if (r->elem_count + count > r->elem_cap) { /* as add_elem_tag grows the table */
        int64_t cap = r->elem_cap ? r->elem_cap : 1024;
        while (cap < r->elem_count + count)
            cap *= 2;
        tag_index *tags = realloc(r->elem_tags, sizeof *tags * (size_t)cap);
        if (!tags)
            return tpk_scan_fail(&r->s, "out of memory");
        r->elem_tags = tags;
        r->elem_cap = cap;
    }
    if (r->cell_count + count > r->cell_cap || r->conn_count + count * t->kept > r->conn_cap)
        return 0;
    int threads = threads_for(count);
    tpk_parallel_for(count, threads, elem_range, &job);
    int64_t taken = count;
    for (int w = 0; w < threads; w++) {
        int64_t begin, end;
        tpk_parallel_range(count, threads, w, &begin, &end);
        if (job.stop[w] < end) {
            taken = job.stop[w];
            break;
        }
    }
    if (taken == 0)
        return 0;
    if (job.run && r->elem_count == 0)
        r->elem_first_tag = (int64_t)job.first_tag;
    r->elem_count += taken;
    r->cell_count += taken;
    r->conn_count += taken * t->kept;
    r->offsets[r->cell_count] = r->conn_count;
    return taken;
}

int64_t gmsh_bulk_elements(gmsh_reader *r, const gmsh_type *t, int64_t count, int64_t physical, int64_t entity,
                           int *again)
{
    *again = 0;
    if (!t->vtk || count == 0)
        return 0;
    int64_t values = 1 + t->nodes;
    if (r->binary) {
        size_t record = sizeof(uint64_t) * (size_t)values;
        int64_t fit = (int64_t)(gmsh_bytes_left(r) / record);
        if (fit > count)
            fit = count;
        int run = !r->elem_listed;
        int64_t taken = take_elements(r, t, (const unsigned char *)r->s.data + r->s.pos, fit, physical, entity);
        if (taken > 0) {
            r->s.pos += record * (size_t)taken;
            r->s.tok_pos = r->s.pos - sizeof(uint64_t); /* as gmsh_bin_bytes leaves it */
            r->s.tok_line = r->s.line;
        }
        *again = run && taken >= 0 && taken < fit; /* a break of the run: listed from the next element on */
        return taken;
    }
    if (tpk_thread_count(0) < 2 || count * values < MIN_NUMBERS)
        return 0;
    int64_t piece = PIECE_NUMBERS / values;
    if (piece > count)
        piece = count;
    int64_t *scratch = malloc(sizeof *scratch * (size_t)(piece * values));
    if (!scratch)
        return 0;
    int64_t done = 0;
    while ((count - done) * values >= MIN_NUMBERS) {
        int64_t k = count - done < piece ? count - done : piece;
        tpk_scan saved = r->s;
        if (tpk_scan_numbers(&r->s, (uint64_t)(k * values), TPK_NUMBER_I64, scratch, 0))
            break;
        int run = !r->elem_listed;
        int64_t taken = take_elements(r, t, (const unsigned char *)scratch, k, physical, entity);
        if (taken < 0) {
            done = -1;
            break;
        }
        done += taken;
        if (taken < k) {
            rewind_to(r, &saved, taken * values);
            *again = run;
            break;
        }
        tpk_scan_release_consumed(&r->s);
    }
    free(scratch);
    return done;
}
