/* Writing one .tpk from the pipeline's tet mesh: positions, layouts and shell streamed block by block,
 * fields, maps and META (and, for a part of a part set, its LINK chunk), atomically. */
#include "write_tpk.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "base/output_file.h"
#include "base/parallel.h"
#include "base/strbuf.h"
#include "pipeline.h"
#include "tetpack.h"

/* ---- the writer's own thread ------------------------------------------------------------------- */

/* The writer's calls, run in order on a thread of their own while the converter goes on: the checksums
 * and the write() calls (into tmpfs, serialized per file by the kernel) overlap the records' building and
 * the next chunks, rather than alternate with them. The calls are the same, in the same order, so the
 * bytes are those of making them one after the other. With one thread (--threads 1) each runs in the
 * caller, as it is queued. A call's data must stay as it is until the call is done (queue_wait); after a
 * failed call the rest are skipped, and the failure is reported when the queue is closed. */
typedef enum { CALL_ADD, CALL_BEGIN, CALL_APPEND, CALL_END } call_kind;

typedef struct writer_call {
    call_kind kind;
    tpk_chunk_desc desc; /* CALL_ADD, CALL_BEGIN */
    const void *data;    /* CALL_ADD, CALL_APPEND */
    uint64_t size;       /* CALL_APPEND */
} writer_call;

#define QUEUE_CALLS 16

typedef struct write_queue {
    tpk_writer *writer;
    int threaded; /* 1: the calls run on `thread` */
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t changed;
    writer_call call[QUEUE_CALLS];
    uint64_t queued, done; /* calls queued and done, since the queue was opened */
    int closing;
    tpk_result result;     /* the first failure */
} write_queue;

static tpk_result run_call(tpk_writer *w, const writer_call *c)
{
    switch (c->kind) {
    case CALL_ADD:
        return tpk_writer_add_chunk(w, &c->desc, c->data);
    case CALL_BEGIN:
        return tpk_writer_begin_chunk(w, &c->desc);
    case CALL_APPEND:
        return tpk_writer_append(w, c->data, c->size);
    default:
        return tpk_writer_end_chunk(w);
    }
}

static void *queue_thread(void *arg)
{
    write_queue *q = arg;
    pthread_mutex_lock(&q->lock);
    for (;;) {
        while (q->done == q->queued && !q->closing)
            pthread_cond_wait(&q->changed, &q->lock);
        if (q->done == q->queued)
            break;
        writer_call c = q->call[q->done % QUEUE_CALLS];
        int skip = q->result != TPK_OK;
        pthread_mutex_unlock(&q->lock);
        tpk_result r = skip ? TPK_OK : run_call(q->writer, &c);
        pthread_mutex_lock(&q->lock);
        if (r != TPK_OK && q->result == TPK_OK)
            q->result = r;
        q->done++;
        pthread_cond_broadcast(&q->changed);
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

/* The thread where threads >= 2 and it starts; else the calls run as they are queued. */
static void queue_open(write_queue *q, tpk_writer *writer, int threads)
{
    memset(q, 0, sizeof *q);
    q->writer = writer;
    q->result = TPK_OK;
    if (threads < 2)
        return;
    if (pthread_mutex_init(&q->lock, NULL) != 0)
        return;
    if (pthread_cond_init(&q->changed, NULL) != 0) {
        pthread_mutex_destroy(&q->lock);
        return;
    }
    q->threaded = pthread_create(&q->thread, NULL, queue_thread, q) == 0;
    if (!q->threaded) {
        pthread_cond_destroy(&q->changed);
        pthread_mutex_destroy(&q->lock);
    }
}

/* Queues a call (waiting while QUEUE_CALLS are pending); returns its number, for queue_wait. */
static uint64_t queue_call(write_queue *q, writer_call c)
{
    if (!q->threaded) {
        if (q->result == TPK_OK)
            q->result = run_call(q->writer, &c);
        q->done++;
        return q->queued++;
    }
    pthread_mutex_lock(&q->lock);
    while (q->queued - q->done == QUEUE_CALLS)
        pthread_cond_wait(&q->changed, &q->lock);
    q->call[q->queued % QUEUE_CALLS] = c;
    uint64_t number = q->queued++;
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    return number;
}

/* Waits until the calls before number `until` are done; returns the first failure so far. */
static tpk_result queue_wait(write_queue *q, uint64_t until)
{
    if (!q->threaded)
        return q->result;
    pthread_mutex_lock(&q->lock);
    while (q->done < until)
        pthread_cond_wait(&q->changed, &q->lock);
    tpk_result r = q->result;
    pthread_mutex_unlock(&q->lock);
    return r;
}

/* Every call done and the thread joined: the writer is the caller's again. */
static tpk_result queue_close(write_queue *q)
{
    if (!q->threaded)
        return q->result;
    pthread_mutex_lock(&q->lock);
    q->closing = 1;
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    pthread_join(q->thread, NULL);
    pthread_cond_destroy(&q->changed);
    pthread_mutex_destroy(&q->lock);
    q->threaded = 0;
    return q->result;
}

/* ---- chunks ------------------------------------------------------------------------------------- */

/* Records made block by block (fill(user, first, count, dst)) and streamed into one chunk, so a large
 * array never exists whole next to the mesh: the converter's peak memory is the mesh plus the blocks. */
#define STREAM_BLOCK ((int64_t)1 << 18)
/* Blocks in turn: one being filled while the writer's thread takes the others (one block where the calls
 * run as they are queued). */
#define STREAM_BLOCKS 3
/* Data the queue's calls read that is freed when the queue is closed. */
#define OWNED_MOST 4

typedef struct chunk_writer {
    tpk_writer *writer;
    write_queue *queue; /* NULL: the writer is called directly (tpk_write_end) */
    int zstd_level;
    int threads; /* for building records */
    tpk_diag *diag;
    char *blocks[STREAM_BLOCKS]; /* stream_chunk's, kept for the next streamed chunk (NULL until the first) */
    uint64_t block_free[STREAM_BLOCKS]; /* the queue's calls to wait for before a block is filled again */
    void *owned[OWNED_MOST];
    int owned_count;
} chunk_writer;

static tpk_chunk_desc chunk_desc(const chunk_writer *cw, uint32_t tag, int required, tpk_elem_type type,
                                  uint32_t size, uint64_t count, uint32_t index, uint32_t step)
{
    tpk_chunk_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.tag = tag;
    desc.flags = required ? TPK_CHUNK_REQUIRED : 0;
    desc.codec = cw->zstd_level > 0 ? TPK_CODEC_ZSTD : TPK_CODEC_NONE;
    desc.zstd_level = cw->zstd_level;
    desc.elem_type = (uint8_t)type;
    desc.elem_size = size;
    desc.elem_count = count;
    desc.index = index;
    desc.step = step;
    return desc;
}

/* A whole chunk from `data`, which must stay until the queue is closed (or be given to it: keep_owned). */
static int put_chunk(chunk_writer *cw, uint32_t tag, int required, tpk_elem_type type, uint32_t size,
                     uint64_t count, uint32_t index, uint32_t step, const void *data)
{
    tpk_chunk_desc desc = chunk_desc(cw, tag, required, type, size, count, index, step);
    if (cw->queue) {
        queue_call(cw->queue, (writer_call){.kind = CALL_ADD, .desc = desc, .data = data});
        return 0; /* a failure is reported when the queue is closed */
    }
    if (tpk_writer_add_chunk(cw->writer, &desc, data) != TPK_OK)
        return tpk_diag_fail(cw->diag, "%s", tpk_writer_error_text(cw->writer));
    return 0;
}

/* `data` (malloc'd), read by queued calls, freed when the queue is closed; at once without a queue. */
static void keep_owned(chunk_writer *cw, void *data)
{
    if (cw->queue && cw->owned_count < OWNED_MOST) {
        cw->owned[cw->owned_count++] = data;
        return;
    }
    if (cw->queue) /* never: OWNED_MOST covers the callers; wait for the calls instead of failing */
        queue_wait(cw->queue, cw->queue->queued);
    free(data);
}

typedef void (*fill_fn)(const void *user, int64_t first, int64_t count, void *dst, int worker);

typedef struct fill_job {
    fill_fn fill;
    const void *user;
    int64_t first;
    char *block;
    uint32_t elem_size;
} fill_job;

static void fill_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const fill_job *job = ctx;
    job->fill(job->user, job->first + begin, end - begin, job->block + (size_t)begin * job->elem_size, worker);
}

/* block_done(user), where given, runs after each block's fill, its workers joined. Each block is appended
 * by the queue as soon as it is filled; a block is filled again once its append is done. */
static int stream_chunk(chunk_writer *cw, const tpk_chunk_desc *desc, fill_fn fill, const void *user,
                        void (*block_done)(const void *user))
{
    int64_t total = (int64_t)desc->elem_count;
    /* Room for the largest record (Tet32) made once for all the streamed chunks: each chunk touches the
     * pages its records need, and the next reuses them (POS3's blocks become TT16's; fresh blocks per
     * chunk were 1536 page faults on grid 120). */
    if (desc->elem_size > sizeof(tpk_tet32))
        return tpk_diag_fail(cw->diag, "internal: %u-byte records streamed, at most %zu", desc->elem_size,
                             sizeof(tpk_tet32));
    write_queue *q = cw->queue;
    int blocks = q->threaded ? STREAM_BLOCKS : 1;
    for (int b = 0; b < blocks; b++)
        if (!cw->blocks[b] && !(cw->blocks[b] = malloc((size_t)STREAM_BLOCK * sizeof(tpk_tet32))))
            return tpk_diag_fail(cw->diag, "out of memory for a block of %u-byte records", desc->elem_size);
    fill_job job = {fill, user, 0, NULL, desc->elem_size};
    queue_call(q, (writer_call){.kind = CALL_BEGIN, .desc = *desc});
    for (int b = 0; job.first < total; job.first += STREAM_BLOCK, b = (b + 1) % blocks) {
        if (queue_wait(q, cw->block_free[b]) != TPK_OK)
            break; /* reported when the queue is closed */
        int64_t count = total - job.first < STREAM_BLOCK ? total - job.first : STREAM_BLOCK;
        job.block = cw->blocks[b];
        tpk_parallel_for(count, tpk_threads_for(count, cw->threads, 16384), fill_range, &job);
        if (block_done)
            block_done(user);
        cw->block_free[b] = 1 + queue_call(q, (writer_call){.kind = CALL_APPEND, .data = job.block,
                                                            .size = (uint64_t)count * desc->elem_size});
    }
    queue_call(q, (writer_call){.kind = CALL_END});
    return 0;
}

/* The points' passes on all threads (tpk_thread_count(0): convert's --threads), each worker over a
 * contiguous range: per worker the first point that is not finite, the first too far from the origin,
 * and the bounds of its points in the stored frame, merged in worker order by the same strict comparisons
 * (so the bound kept among equal values, 0.0 or -0.0, is the first in point order, as one pass keeps). */
typedef struct points_job {
    double *points;
    const double *origin;
    int64_t not_finite[TPK_MAX_THREADS], too_far[TPK_MAX_THREADS];
    double lo[TPK_MAX_THREADS][3], hi[TPK_MAX_THREADS][3];
} points_job;

static void storable_range(void *ctx, int64_t begin, int64_t end, int w)
{
    points_job *job = ctx;
    job->not_finite[w] = job->too_far[w] = INT64_MAX;
    for (int64_t i = begin; i < end; i++) {
        const double *p = job->points + 3 * i;
        int bad_value = 0, bad_offset = 0;
        for (int k = 0; k < 3; k++) {
            bad_value |= !isfinite(p[k]);
            bad_offset |= !isfinite((float)(p[k] - job->origin[k]));
        }
        if (bad_value && job->not_finite[w] == INT64_MAX)
            job->not_finite[w] = i;
        if (bad_offset && job->too_far[w] == INT64_MAX)
            job->too_far[w] = i;
    }
}

static void quantize_range(void *ctx, int64_t begin, int64_t end, int w)
{
    points_job *job = ctx;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = begin; i < end; i++)
        for (int k = 0; k < 3; k++) {
            double rel = (double)(float)(job->points[3 * i + k] - job->origin[k]);
            double world = job->origin[k] + rel;
            job->points[3 * i + k] = rel;
            lo[k] = world < lo[k] ? world : lo[k];
            hi[k] = world > hi[k] ? world : hi[k];
        }
    memcpy(job->lo[w], lo, sizeof lo);
    memcpy(job->hi[w], hi, sizeof hi);
}

/* Stored positions MUST be finite (TPK-M11): a point that is not, or whose offset from the origin
 * overflows float32, is an error naming it (also when no cell uses it: the file stores every point).
 * Non-finite points are reported first: they would make every offset overflow. */
static int check_storable(const tpk_tetmesh *mesh, points_job *job, int threads, tpk_diag *diag)
{
    tpk_parallel_for(mesh->vertex_count, threads, storable_range, job);
    int64_t first[2] = {INT64_MAX, INT64_MAX};
    for (int w = 0; w < threads; w++) {
        first[0] = job->not_finite[w] < first[0] ? job->not_finite[w] : first[0];
        first[1] = job->too_far[w] < first[1] ? job->too_far[w] : first[1];
    }
    for (int pass = 0; pass < 2; pass++) {
        int64_t i = first[pass];
        if (i == INT64_MAX)
            continue;
        const double *p = mesh->points + 3 * i;
        return tpk_diag_fail(diag, "point %d is at (%.17g, %.17g, %.17g): %s",
                             mesh->vertex_source ? mesh->vertex_source[i] : (int32_t)i, p[0], p[1], p[2],
                             pass == 0 ? "a coordinate is not a finite number"
                                       : "too far from the origin for float32 positions (the "
                                         "format stores them relative to it)");
    }
    return 0;
}

/* Move the points into the frame the file stores: relative to the origin of tpk_points_origin (so
 * meshes far from 0 keep float32 precision) and rounded to float32. Everything after this (exact orientation
 * included) then decides on exactly the coordinates a reader of the file sees. */
int tpk_quantize_points(tpk_tetmesh *mesh, tpk_header_fields *hdr, tpk_diag *diag)
{
    /* On the grid tetrahedralize decided on (TPK_TETRA_FILE_GRID), the same origin keeps it exact. */
    if (mesh->on_grid)
        memcpy(hdr->origin, mesh->grid_origin, sizeof hdr->origin);
    else
        tpk_points_origin(mesh->points, mesh->vertex_count, hdr->origin);
    for (int k = 0; k < 3; k++) {
        hdr->bounds_min[k] = mesh->vertex_count ? INFINITY : 0.0;
        hdr->bounds_max[k] = mesh->vertex_count ? -INFINITY : 0.0;
    }
    points_job *job = malloc(sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "out of memory");
    job->points = mesh->points;
    job->origin = hdr->origin;
    int threads = tpk_threads_for(mesh->vertex_count, tpk_thread_count(0), (int64_t)1 << 16);
    if (check_storable(mesh, job, threads, diag) != 0) {
        free(job);
        return -1;
    }
    memcpy(mesh->origin, hdr->origin, sizeof mesh->origin);
    tpk_parallel_for(mesh->vertex_count, threads, quantize_range, job);
    for (int w = 0; w < threads && mesh->vertex_count; w++)
        for (int k = 0; k < 3; k++) {
            hdr->bounds_min[k] = job->lo[w][k] < hdr->bounds_min[k] ? job->lo[w][k] : hdr->bounds_min[k];
            hdr->bounds_max[k] = job->hi[w][k] > hdr->bounds_max[k] ? job->hi[w][k] : hdr->bounds_max[k];
        }
    free(job);
    return 0;
}

static void fill_positions(const void *user, int64_t first, int64_t count, void *dst, int worker)
{
    const double *points = user;
    (void)worker;
    float *pos = dst;
    for (int64_t i = 0; i < 3 * count; i++)
        pos[i] = (float)points[3 * first + i]; /* exact: quantize_points rounded them already */
}

static int write_positions(chunk_writer *cw, const tpk_tetmesh *mesh)
{
    tpk_chunk_desc desc = chunk_desc(cw, TPK_TAG_POS3, 1, TPK_ELEM_VEC3_F32, 12, (uint64_t)mesh->vertex_count, 0, 0);
    return stream_chunk(cw, &desc, fill_positions, mesh->points, NULL);
}

/* The layouts' records, and beside the first layout's the shell faces (tpk_shell_gather: the tets and
 * neighbours read once for both; its own pass cost a scan of both arrays that did not scale). */
typedef struct layout_source {
    const int32_t *tets, *neighbors;
    tpk_shell_gather *shell; /* NULL: gathered already */
} layout_source;

static void gather_shell(const layout_source *src, int64_t first, int64_t count, int worker)
{
    if (src->shell)
        tpk_shell_gather_range(src->shell, src->tets, src->neighbors, first, count, worker);
}

/* The records and the shell faces of a worker's range in pieces of this many tets (128 KiB of tets and
 * neighbours): the gather reads what the records just read, from the cache rather than from memory. */
#define LAYOUT_PIECE ((int64_t)4096)

static void build_tet16(const int32_t *tets, const int32_t *neighbors, int64_t count, void *dst)
{
    tpk_build_tet16(tets, neighbors, count, dst);
}

static void build_tet20(const int32_t *tets, const int32_t *neighbors, int64_t count, void *dst)
{
    tpk_build_tet20(tets, neighbors, count, dst);
}

static void build_tet32(const int32_t *tets, const int32_t *neighbors, int64_t count, void *dst)
{
    tpk_build_tet32(tets, neighbors, count, dst);
}

static void fill_layout(const layout_source *src, int64_t first, int64_t count, char *dst, int worker,
                        void (*build)(const int32_t *, const int32_t *, int64_t, void *), size_t record)
{
    for (int64_t at = 0; at < count; at += LAYOUT_PIECE) {
        int64_t n = count - at < LAYOUT_PIECE ? count - at : LAYOUT_PIECE;
        build(src->tets + 4 * (first + at), src->neighbors + 4 * (first + at), n, dst + (size_t)at * record);
        gather_shell(src, first + at, n, worker);
    }
}

static void fill_tet16(const void *user, int64_t first, int64_t count, void *dst, int worker)
{
    fill_layout(user, first, count, dst, worker, build_tet16, sizeof(tpk_tet16));
}

static void fill_tet20(const void *user, int64_t first, int64_t count, void *dst, int worker)
{
    fill_layout(user, first, count, dst, worker, build_tet20, sizeof(tpk_tet20));
}

static void fill_tet32(const void *user, int64_t first, int64_t count, void *dst, int worker)
{
    fill_layout(user, first, count, dst, worker, build_tet32, sizeof(tpk_tet32));
}

static void shell_block_done(const void *user)
{
    const layout_source *src = user;
    if (src->shell)
        tpk_shell_gather_block(src->shell);
}

/* The layouts chosen, then SHEL from the faces gathered beside the first. */
static int write_layouts_and_shell(chunk_writer *cw, const tpk_tetmesh *mesh, const int32_t *neighbors,
                                   unsigned layouts, uint64_t *shell_count)
{
    static const struct {
        unsigned bit;
        uint32_t tag;
        tpk_elem_type type;
        uint32_t size;
        fill_fn fill;
    } kinds[] = {{TPK_LAYOUT_BIT_TET16, TPK_TAG_TT16, TPK_ELEM_TET16, 16, fill_tet16},
                 {TPK_LAYOUT_BIT_TET20, TPK_TAG_TT20, TPK_ELEM_TET20, 20, fill_tet20},
                 {TPK_LAYOUT_BIT_TET32, TPK_TAG_TT32, TPK_ELEM_TET32, 32, fill_tet32}};
    tpk_shell_gather *shell = calloc(1, sizeof *shell);
    if (!shell)
        return tpk_diag_fail(cw->diag, "out of memory");
    layout_source src = {mesh->tets, neighbors, shell};
    int rc = 0;
    for (size_t k = 0; rc == 0 && k < sizeof kinds / sizeof kinds[0]; k++) {
        if (!(layouts & kinds[k].bit))
            continue;
        tpk_chunk_desc desc = chunk_desc(cw, kinds[k].tag, 1, kinds[k].type, kinds[k].size,
                                         (uint64_t)mesh->tet_count, 0, 0);
        rc = stream_chunk(cw, &desc, kinds[k].fill, &src, shell_block_done);
        src.shell = NULL;
    }
    tpk_shell_gather_done(shell);
    if (rc == 0 && src.shell) { /* no layout streamed (none known asked for): a pass of its own */
        shell->faces = tpk_make_shell(mesh->tets, neighbors, mesh->tet_count, cw->threads, &shell->count);
        shell->failed = !shell->faces;
    }
    if (rc == 0 && shell->failed)
        rc = tpk_diag_fail(cw->diag, "out of memory for %lld shell faces", (long long)shell->count);
    if (rc == 0) {
        *shell_count = (uint64_t)shell->count;
        rc = put_chunk(cw, TPK_TAG_SHEL, 1, TPK_ELEM_SHELL_FACE, 16, (uint64_t)shell->count, 0, 0, shell->faces);
    }
    keep_owned(cw, shell->faces); /* the SHEL call reads them */
    free(shell);
    return rc;
}

/* A field's range, NaN left out, on all threads: per worker over a contiguous range, merged in worker
 * order by the same strict comparisons (so of -0.0 and 0.0 the first in value order is kept, as one pass
 * keeps). */
typedef struct range_job {
    const float *values;
    float lo[TPK_MAX_THREADS], hi[TPK_MAX_THREADS];
} range_job;

static void range_range(void *ctx, int64_t begin, int64_t end, int w)
{
    range_job *job = ctx;
    float mn = INFINITY, mx = -INFINITY;
    for (int64_t i = begin; i < end; i++) {
        float v = job->values[i];
        if (v == v) {
            mn = v < mn ? v : mn;
            mx = v > mx ? v : mx;
        }
    }
    job->lo[w] = mn;
    job->hi[w] = mx;
}

static void field_range(const tpk_src_field *f, size_t values, int threads, float *lo, float *hi)
{
    range_job job = {.values = f->values};
    threads = tpk_threads_for((int64_t)values, threads, (int64_t)1 << 16);
    tpk_parallel_for((int64_t)values, threads, range_range, &job);
    float mn = INFINITY, mx = -INFINITY;
    for (int w = 0; w < threads; w++) {
        mn = job.lo[w] < mn ? job.lo[w] : mn;
        mx = job.hi[w] > mx ? job.hi[w] : mx;
    }
    if (mn > mx)
        mn = mx = NAN;
    *lo = mn;
    *hi = mx;
}

static int write_fields(chunk_writer *cw, const tpk_tetmesh *mesh)
{
    if (mesh->field_count == 0)
        return 0;
    tpk_field_desc *desc = calloc((size_t)mesh->field_count, sizeof *desc);
    if (!desc)
        return tpk_diag_fail(cw->diag, "out of memory for field descriptors");
    int max_steps = 1;
    for (int i = 0; i < mesh->field_count; i++) {
        const tpk_src_field *f = &mesh->fields[i];
        size_t length = strnlen(f->name, sizeof desc[i].name - 1);
        if (!tpk_utf8_valid(f->name, length)) { /* spec §7.1: names are UTF-8 */
            free(desc);
            return tpk_diag_fail(cw->diag, "field '%.*s' (kept field %d): its name is not valid UTF-8 (a name in "
                                 "another encoding, or cut inside a character at %d bytes); the format stores "
                                 "UTF-8 names: rename it in the source, or leave it out with --field",
                                 (int)length, f->name, i + 1, TPK_NAME_MAX - 1);
        }
        size_t per_step = (size_t)(f->association == TPK_ASSOC_POINT ? mesh->vertex_count : mesh->tet_count);
        memcpy(desc[i].name, f->name, length); /* NUL-padded by calloc */
        desc[i].association = (uint32_t)f->association;
        desc[i].step_count = (uint32_t)f->step_count;
        desc[i].components = 1;
        field_range(f, per_step * (size_t)f->step_count, cw->threads, &desc[i].min_value, &desc[i].max_value);
        max_steps = f->step_count > max_steps ? f->step_count : max_steps;
    }
    int rc = put_chunk(cw, TPK_TAG_FDSC, 1, TPK_ELEM_FIELD_DESC, 128, (uint64_t)mesh->field_count, 0, 0, desc);
    keep_owned(cw, desc);
    for (int i = 0; rc == 0 && i < mesh->field_count; i++) {
        const tpk_src_field *f = &mesh->fields[i];
        size_t per_step = (size_t)(f->association == TPK_ASSOC_POINT ? mesh->vertex_count : mesh->tet_count);
        for (int s = 0; rc == 0 && s < f->step_count; s++)
            rc = put_chunk(cw, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, per_step, (uint32_t)i, (uint32_t)s,
                           f->values + per_step * (size_t)s);
    }
    for (int s = 0; rc == 0 && mesh->times && s < mesh->step_count; s++)
        if (!isfinite(mesh->times[s])) /* TPK-M13 */
            rc = tpk_diag_fail(cw->diag, "time step %d has the time %g; the format stores only finite times", s,
                               mesh->times[s]);
    if (rc == 0 && mesh->times && mesh->step_count == max_steps && max_steps > 0)
        rc = put_chunk(cw, TPK_TAG_TIME, 0, TPK_ELEM_F64, 8, (uint64_t)max_steps, 0, 0, mesh->times);
    return rc;
}

/* META "levels": what each level is (spec §16). */
static void levels_json(tpk_strbuf *sb, const tpk_levels *levels)
{
    tpk_strbuf_printf(sb, ",\"levels\":[");
    for (int i = 0; i < levels->count; i++) {
        const tpk_level *l = &levels->level[i];
        tpk_strbuf_printf(sb, "%s{\"level\":%d,\"vertices\":%lld,\"tets\":%lld,\"method\":\"half-edge "
                          "collapse\",\"field\":", i ? "," : "", i + 1, (long long)l->vertices, (long long)l->tets);
        tpk_strbuf_json_string(sb, l->field);
        tpk_strbuf_printf(sb, ",\"step\":%d,\"error_samples\":%lld,\"error_max\":", l->field_step,
                          (long long)l->error_samples);
        tpk_strbuf_json_number(sb, l->error_max);
        tpk_strbuf_printf(sb, ",\"error_rms\":");
        tpk_strbuf_json_number(sb, l->error_rms);
        tpk_strbuf_printf(sb, ",\"shell_distance\":");
        tpk_strbuf_json_number(sb, l->shell_distance);
        tpk_strbuf_printf(sb, ",\"shell_tolerance\":");
        tpk_strbuf_json_number(sb, l->shell_tolerance);
        tpk_strbuf_printf(sb, "}");
    }
    tpk_strbuf_printf(sb, "]");
}

static int write_meta(chunk_writer *cw, const tpk_convert_options *o, const tpk_convert_report *rep,
                      const char *source_format, const tpk_part_extras *part, const tpk_levels *levels)
{
    tpk_strbuf sb = {0};
    tpk_strbuf_printf(&sb, "{\"converter\":{\"name\":\"tetpack\",\"version\":\"%s\"},\"command_line\":",
                      TPK_LIBRARY_VERSION);
    tpk_strbuf_json_string(&sb, o->command_line ? o->command_line : "");
    tpk_strbuf_printf(&sb, ",\"source\":{\"path\":");
    tpk_strbuf_json_string(&sb, o->input);
    tpk_strbuf_printf(&sb, ",\"format\":");
    tpk_strbuf_json_string(&sb, source_format);
    tpk_strbuf_printf(&sb, ",\"cells\":%lld,\"points\":%lld}", (long long)rep->source_cells,
                      (long long)rep->source_points);
    tpk_strbuf_printf(&sb, ",\"pipeline\":{\"reordered\":%s,\"steiner_cells\":%lld,\"face_steiner_points\":%lld,"
                      "\"polyhedra\":%lld,\"bad_cells_skipped\":%lld}",
                      o->no_reorder ? "false" : "true", (long long)rep->steiner_cells,
                      (long long)rep->face_steiner_points, (long long)rep->polyhedra,
                      (long long)rep->bad_cells_skipped);
    if (rep->higher_order_cells > 0) /* only then: the META of a linear mesh stays as it was */
        tpk_strbuf_printf(&sb, ",\"higher_order\":\"%s\",\"higher_order_cells\":%lld,\"higher_order_points\":%lld",
                          rep->higher_order_split ? "split" : "corners", (long long)rep->higher_order_cells,
                          (long long)rep->higher_order_points);
    if (o->max_error > 0 || o->subdivide > 0) { /* the bound promised (check --against holds the file to it,
                                                   not with --subdivide: none promised) and the one proved */
        if (o->subdivide > 0)
            tpk_strbuf_printf(&sb, ",\"subdivide\":%d", o->subdivide);
        else
            tpk_strbuf_printf(&sb, ",\"max_error\":%.9g", o->max_error);
        tpk_strbuf_printf(&sb, ",\"max_error_measured\":%.9g,\"max_error_geometry\":%.9g", rep->max_error.field_error,
                          rep->max_error.geometry_error);
        if (o->max_error_field_count > 0) {
            tpk_strbuf_printf(&sb, ",\"max_error_fields\":[");
            for (int i = 0; i < o->max_error_field_count; i++) {
                tpk_strbuf_printf(&sb, i ? "," : "");
                tpk_strbuf_json_string(&sb, o->max_error_fields[i]);
            }
            tpk_strbuf_printf(&sb, "]");
        }
    }
    tpk_strbuf_printf(&sb, ",\"repairs\":");
    tpk_convert_repairs_json(&sb, o, rep);
    if (part)
        tpk_strbuf_printf(&sb, ",\"part_set\":{\"index\":%d,\"parts\":%d}", part->index, part->count);
    if (levels && levels->count > 0)
        levels_json(&sb, levels);
    tpk_strbuf_printf(&sb, "}");
    int rc;
    if (sb.failed)
        rc = tpk_diag_fail(cw->diag, "out of memory for metadata");
    else
        rc = put_chunk(cw, TPK_TAG_META, 0, TPK_ELEM_BYTE, 1, sb.length, 0, 0, sb.data);
    tpk_strbuf_free(&sb);
    return rc;
}

void tpk_convert_repairs_json(tpk_strbuf *sb, const tpk_convert_options *o, const tpk_convert_report *r)
{
    tpk_strbuf_printf(sb, "{\"reorient\":{\"requested\":%s,\"inverted_tets\":%lld,\"mirrored_cells\":%lld},",
                      o->strict_orientation ? "false" : "true", (long long)r->inverted_fixed,
                      (long long)r->mirrored_cells);
    tpk_strbuf_printf(sb, "\"drop_degenerate\":{\"requested\":%s,\"degenerate_tets\":%lld,\"collapsed_cells\":%lld},",
                      o->drop_degenerate ? "true" : "false", (long long)r->degenerate_dropped,
                      (long long)r->collapsed_cells_dropped);
    tpk_strbuf_printf(sb, "\"merge_duplicates\":{\"requested\":%s,\"tolerance\":",
                      o->merge_duplicates ? "true" : "false");
    tpk_strbuf_json_number(sb, o->merge_duplicates ? o->merge_tolerance : 0.0);
    tpk_strbuf_printf(sb, ",\"merged_vertices\":%lld},", (long long)r->merged_vertices);
    tpk_strbuf_printf(sb, "\"cut_folds\":{\"requested\":%s,\"folded_faces\":%lld}}", o->cut_folds ? "true" : "false",
                      (long long)r->folds_cut);
}

static int write_maps(chunk_writer *cw, const tpk_tetmesh *mesh)
{
    int rc = put_chunk(cw, TPK_TAG_TMAP, 0, TPK_ELEM_I32, 4, (uint64_t)mesh->tet_count, 0, 0, mesh->tet_source);
    if (rc == 0)
        rc = put_chunk(cw, TPK_TAG_VMAP, 0, TPK_ELEM_I32, 4, (uint64_t)mesh->vertex_count, 0, 0,
                       mesh->vertex_source);
    return rc;
}

/* convert --cull: the CULL chunk (spec §17), built here while the tets and neighbors are intact. */
static int write_cull(chunk_writer *cw, const tpk_tetmesh *mesh, const int32_t *neighbors)
{
    if (mesh->tet_count == 0)
        return 0; /* no blocks: a file of no tets has nothing to cull */
    uint64_t count = 0;
    int32_t *words = tpk_build_cull(mesh->tets, neighbors, mesh->tet_count, mesh->vertex_count, cw->threads, &count);
    if (!words)
        return tpk_diag_fail(cw->diag, "convert: out of memory building the culling blocks (--cull)");
    int rc = put_chunk(cw, TPK_TAG_CULL, 0, TPK_ELEM_I32, 4, count, 0, 0, words);
    keep_owned(cw, words);
    return rc;
}

/* The writer's failures go to the diagnostics, except while its calls run on the queue's thread: the
 * caller reports them itself once the queue is closed (so only one thread writes the diagnostics). */
static void writer_message(void *user, tpk_result code, const char *text)
{
    const tpk_write_session *ws = user;
    (void)code;
    if (!ws->queued)
        tpk_diag_fail(ws->diag, "%s", text);
}

static int write_chunks(chunk_writer *cw, const tpk_convert_options *o, const tpk_tetmesh *mesh,
                        const int32_t *neighbors, tpk_header_fields *hdr)
{
    unsigned layouts = o->layouts ? o->layouts : TPK_LAYOUT_BIT_TET16;
    int rc = write_positions(cw, mesh);
    if (rc == 0)
        rc = write_layouts_and_shell(cw, mesh, neighbors, layouts, &hdr->shell_face_count);
    if (rc == 0)
        rc = write_fields(cw, mesh);
    if (rc == 0)
        rc = write_maps(cw, mesh);
    if (rc == 0 && o->cull)
        rc = write_cull(cw, mesh, neighbors);
    return rc;
}

int tpk_write_begin(tpk_write_session *ws, const tpk_convert_options *o, const tpk_tetmesh *mesh,
                    const int32_t *neighbors, tpk_header_fields *hdr, tpk_diag *diag)
{
    chunk_writer cw = {.zstd_level = o->zstd_level, .threads = tpk_thread_count(o->threads), .diag = diag};
    char err[512] = "";
    tpk_write_options wopt;
    memset(&wopt, 0, sizeof wopt);
    wopt.size = sizeof wopt;
    wopt.message = writer_message;
    wopt.message_user = ws;
    wopt.threads = cw.threads;
    /* The file has no name until it is complete (base/output_file.h): a killed conversion leaves nothing. */
    memset(ws, 0, sizeof *ws);
    ws->diag = diag;
    ws->out.fd = o->output_fd;
    ws->named = o->output_fd <= 0; /* else the caller's file (render's in-memory conversion) */
    if (ws->named && tpk_output_open(&ws->out, o->output, diag) != 0)
        return -1;
    if (tpk_writer_open_fd(&cw.writer, ws->out.fd, o->output, &wopt, err, sizeof err) != TPK_OK) {
        if (ws->named)
            tpk_output_abort(&ws->out);
        return tpk_diag_fail(diag, "%s", err);
    }
    ws->writer = cw.writer;
    hdr->vertex_count = (uint64_t)mesh->vertex_count;
    hdr->tet_count = (uint64_t)mesh->tet_count;
    write_queue queue;
    queue_open(&queue, cw.writer, cw.threads);
    cw.queue = &queue;
    ws->queued = queue.threaded;
    int rc = write_chunks(&cw, o, mesh, neighbors, hdr);
    tpk_result r = queue_close(&queue);
    ws->queued = 0;
    if (rc == 0 && r != TPK_OK)
        rc = tpk_diag_fail(diag, "%s", tpk_writer_error_text(cw.writer));
    for (int b = 0; b < STREAM_BLOCKS; b++)
        free(cw.blocks[b]);
    for (int i = 0; i < cw.owned_count; i++)
        free(cw.owned[i]);
    if (rc != 0)
        tpk_write_abort(ws);
    return rc;
}

void tpk_write_abort(tpk_write_session *ws)
{
    tpk_writer_abort(ws->writer);
    if (ws->named)
        tpk_output_abort(&ws->out);
    ws->writer = NULL;
}

int tpk_write_end(tpk_write_session *ws, const tpk_convert_options *o, tpk_header_fields *hdr,
                  tpk_convert_report *rep, const char *source_format, const tpk_part_extras *part,
                  const tpk_levels *levels, tpk_diag *diag)
{
    chunk_writer cw = {.writer = ws->writer, .zstd_level = o->zstd_level, .threads = tpk_thread_count(o->threads),
                       .diag = diag};
    int rc = write_meta(&cw, o, rep, source_format, part, levels);
    for (int i = 0; rc == 0 && levels && i < levels->count; i++) { /* spec §16: whole files, uncompressed */
        tpk_chunk_desc d = {.tag = TPK_TAG_LEVL, .codec = TPK_CODEC_NONE, .elem_type = TPK_ELEM_BYTE, .elem_size = 1,
                            .index = (uint32_t)i + 1, .elem_count = levels->level[i].size};
        if (tpk_writer_add_chunk(cw.writer, &d, levels->level[i].data) != TPK_OK)
            rc = tpk_diag_fail(diag, "%s", tpk_writer_error_text(cw.writer));
    }
    if (rc == 0 && part && part->link_count > 0) /* spec §15.3: LINK, optional, 4 I32 per link */
        rc = put_chunk(&cw, TPK_TAG_LINK, 0, TPK_ELEM_I32, 4, 4 * (uint64_t)part->link_count, 0, 0, part->links);
    if (rc != 0) {
        tpk_write_abort(ws);
        return rc;
    }
    rep->shell_faces = (int64_t)hdr->shell_face_count;
    ws->writer = NULL;
    if (tpk_writer_finish(cw.writer, hdr) != TPK_OK) {
        if (ws->named)
            tpk_output_abort(&ws->out);
        return diag->message[0] ? -1 : tpk_diag_fail(diag, "%s: could not finish the file", o->output);
    }
    if (ws->named && tpk_output_commit(&ws->out, diag) != 0)
        return -1;
    struct stat st;
    if (ws->named ? stat(o->output, &st) == 0 : fstat(o->output_fd, &st) == 0)
        rep->output_bytes = (uint64_t)st.st_size;
    return 0;
}

int tpk_write_tpk(const tpk_convert_options *o, const tpk_tetmesh *mesh, const int32_t *neighbors,
                  tpk_header_fields *hdr, tpk_convert_report *rep, const char *source_format,
                  const tpk_part_extras *part, tpk_diag *diag)
{
    tpk_write_session ws;
    if (tpk_write_begin(&ws, o, mesh, neighbors, hdr, diag) != 0)
        return -1;
    return tpk_write_end(&ws, o, hdr, rep, source_format, part, NULL, diag);
}
