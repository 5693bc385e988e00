/* The container writer: chunks are appended (aligned, optionally zstd-compressed, checksummed) to a
 * temporary file beside the target, then the directory and header are written and the file is renamed
 * into place; or, with tpk_writer_open_fd, to a file the caller made and puts in place itself. The
 * finished layout is checked with the reader's own rules first. Output is deterministic. */
#ifdef __linux__
#define _GNU_SOURCE /* sync_file_range */
#include <fcntl.h>
#endif
#include <errno.h>
#include <pthread.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>
#include <zstd.h>

#include "internal_file.h"

struct tpk_writer {
    tpk_allocator allocator;
    tpk_message_fn message;
    void *message_user;
    int fd;
    int owns_fd;       /* 0: the caller's (tpk_writer_open_fd): never closed, renamed or removed here */
    char *temp_path;   /* "<path>.tmp.XXXXXX" */
    char *path;        /* the target, or the caller's name for its fd (messages only) */
    uint64_t end;      /* bytes written so far */
    uint64_t kicked;   /* bytes before this offset have been handed to write-back (see write_all) */
    tpk_dir_entry *entries;
    uint64_t count, capacity;
    tpk_field_desc *fields; /* copy of the FDSC chunk, for the final check */
    uint32_t field_count;
    int failed;        /* an I/O error left the temporary file in an unknown state */
    /* The chunk being streamed (tpk_writer_begin_chunk .. end_chunk); open_chunk 0 when none. */
    int open_chunk;
    tpk_dir_entry chunk;
    uint64_t chunk_appended;  /* raw bytes so far */
    int chunk_level;
    XXH64_state_t *hash;
    int threads;              /* tpk_write_options.threads */
    ZSTD_CCtx *zstd;
    void *zstd_out;           /* ZSTD_CStreamOutSize() bytes */
    char error_text[TPK_ERROR_TEXT_SIZE];
};

static tpk_result writer_fail(tpk_writer *w, tpk_result code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static tpk_result writer_fail(tpk_writer *w, tpk_result code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w->error_text, sizeof w->error_text, fmt, ap);
    va_end(ap);
    if (w->message)
        w->message(w->message_user, code, w->error_text);
    return code;
}

static tpk_result io_fail(tpk_writer *w, const char *what)
{
    char buffer[128] = "";
    int code = errno;
    /* _GNU_SOURCE (above) gives glibc's strerror_r, which returns the text and may leave the buffer
     * untouched; elsewhere the XSI one fills the buffer. */
#if defined(__GLIBC__)
    const char *reason = strerror_r(code, buffer, sizeof buffer);
#else
    const char *reason = strerror_r(code, buffer, sizeof buffer) == 0 ? buffer : "unknown error";
#endif
    w->failed = 1;
    return writer_fail(w, TPK_ERR_IO, "%s '%s': %s", what, w->temp_path ? w->temp_path : w->path, reason);
}

static void *writer_alloc(const tpk_writer *w, uint64_t size)
{
    return size > SIZE_MAX ? NULL : w->allocator.alloc(w->allocator.user, size ? (size_t)size : 1);
}

static void writer_free(const tpk_writer *w, void *ptr)
{
    if (ptr)
        w->allocator.free(w->allocator.user, ptr);
}

/* Free everything; remove the temporary file if it is still there. */
static void writer_destroy(tpk_writer *w)
{
    if (w->fd >= 0 && w->owns_fd)
        close(w->fd);
    if (w->temp_path)
        unlink(w->temp_path);
    writer_free(w, w->temp_path);
    writer_free(w, w->path);
    writer_free(w, w->entries);
    writer_free(w, w->fields);
    writer_free(w, w->zstd_out);
    ZSTD_freeCCtx(w->zstd);
    XXH64_freeState(w->hash);
    w->allocator.free(w->allocator.user, w);
}

/* ---- low-level output --------------------------------------------------------------------------- */

/* Start write-back of what has piled up since the last call, every 16 MiB, rather than leave it all to
 * the final fsync: the disk writes while the converter computes the next records (a 134 MB file: the
 * fsync 57 -> 9 ms, bench/RESULTS.md). Advice only; an error here changes nothing (the fsync reports real
 * ones). */
static void kick_writeback(tpk_writer *w)
{
#ifdef SYNC_FILE_RANGE_WRITE
    if (w->end - w->kicked >= ((uint64_t)16 << 20)) {
        (void)sync_file_range(w->fd, (off_t)w->kicked, (off_t)(w->end - w->kicked), SYNC_FILE_RANGE_WRITE);
        w->kicked = w->end;
    }
#else
    (void)w;
#endif
}

/* In pieces of at most 4 MiB, each followed by kick_writeback: one 23 MB write() took 2 ms/MB here,
 * 4 MiB ones 0.25 ms/MB (the page cache throttles a writer with much dirty data and none under way). */
static tpk_result write_all(tpk_writer *w, const void *data, uint64_t size)
{
    const uint8_t *p = data;
    while (size > 0) {
        size_t n = size > ((uint64_t)4 << 20) ? ((size_t)4 << 20) : (size_t)size;
        ssize_t done = write(w->fd, p, n);
        if (done < 0 && errno == EINTR)
            continue;
        if (done <= 0)
            return io_fail(w, "cannot write");
        p += done;
        size -= (uint64_t)done;
        w->end += (uint64_t)done;
        kick_writeback(w);
    }
    return TPK_OK;
}

static tpk_result pad_to(tpk_writer *w, uint64_t align)
{
    static const uint8_t zeros[TPK_LARGE_CHUNK_ALIGN];
    uint64_t pad = (align - w->end % align) % align;
    return write_all(w, zeros, pad);
}

static tpk_result pwrite_all(tpk_writer *w, const void *data, size_t size, off_t offset)
{
    const uint8_t *p = data;
    while (size > 0) {
        ssize_t done = pwrite(w->fd, p, size, offset);
        if (done < 0 && errno == EINTR)
            continue;
        if (done <= 0)
            return io_fail(w, "cannot write");
        p += done;
        size -= (size_t)done;
        offset += done;
    }
    return TPK_OK;
}

/* ---- open --------------------------------------------------------------------------------------- */

static char *copy_string(const tpk_writer *w, const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    char *copy = writer_alloc(w, a + b + 1);
    if (copy) {
        memcpy(copy, s, a);
        memcpy(copy + a, suffix, b + 1);
    }
    return copy;
}

static tpk_result create_temp(tpk_writer *w, const char *path)
{
    w->path = copy_string(w, path, "");
    w->temp_path = copy_string(w, path, ".tmp.XXXXXX");
    if (!w->path || !w->temp_path)
        return writer_fail(w, TPK_ERR_OUT_OF_MEMORY, "out of memory for the path '%s'", path);
    w->fd = mkstemp(w->temp_path);
    if (w->fd < 0) {
        writer_free(w, w->temp_path); /* nothing was created: nothing to unlink */
        w->temp_path = NULL;
        return io_fail(w, "cannot create a temporary file beside");
    }
    w->owns_fd = 1;
    fchmod(w->fd, 0644); /* mkstemp's 0600 is too strict for a data file */
    return TPK_OK;
}

/* The header is written last (it holds the directory's offset and checksum): hold its place. */
static tpk_result write_header_placeholder(tpk_writer *w)
{
    static const uint8_t header_placeholder[TPK_HEADER_SIZE];
    return write_all(w, header_placeholder, sizeof header_placeholder);
}

/* A writer with the options resolved; NULL, with the reason in err_text, when out of memory. */
static tpk_writer *writer_new(const tpk_write_options *options, char *err_text, size_t err_cap)
{
    tpk_write_options opt = {0};
    if (options)
        memcpy(&opt, options, options->size && options->size < sizeof opt ? options->size : sizeof opt);
    tpk_allocator allocator;
    tpki_resolve_allocator(&opt.allocator, &allocator);
    tpk_writer *w = allocator.alloc(allocator.user, sizeof *w);
    if (!w) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "out of memory for the writer");
        return NULL;
    }
    *w = (tpk_writer){.allocator = allocator, .message = opt.message, .message_user = opt.message_user, .fd = -1,
                        .threads = opt.threads};
    return w;
}

/* Finish opening: on failure pass the reason on and free the writer. */
static tpk_result writer_started(tpk_writer **out, tpk_writer *w, tpk_result r, char *err_text, size_t err_cap)
{
    if (r == TPK_OK)
        r = write_header_placeholder(w);
    if (r != TPK_OK) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "%s", w->error_text);
        writer_destroy(w);
        return r;
    }
    *out = w;
    return TPK_OK;
}

tpk_result tpk_writer_open(tpk_writer **out, const char *path, const tpk_write_options *options, char *err_text,
                           size_t err_cap)
{
    if (!out || !path) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "tpk_writer_open: NULL argument");
        return TPK_ERR_INVALID_ARGUMENT;
    }
    *out = NULL;
    tpk_writer *w = writer_new(options, err_text, err_cap);
    if (!w)
        return TPK_ERR_OUT_OF_MEMORY;
    return writer_started(out, w, create_temp(w, path), err_text, err_cap);
}

tpk_result tpk_writer_open_fd(tpk_writer **out, int fd, const char *name, const tpk_write_options *options,
                              char *err_text, size_t err_cap)
{
    if (!out || fd < 0 || !name) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "tpk_writer_open_fd: NULL argument or negative fd");
        return TPK_ERR_INVALID_ARGUMENT;
    }
    *out = NULL;
    tpk_writer *w = writer_new(options, err_text, err_cap);
    if (!w)
        return TPK_ERR_OUT_OF_MEMORY;
    w->fd = fd;
    w->path = copy_string(w, name, "");
    tpk_result r = TPK_OK;
    if (!w->path)
        r = writer_fail(w, TPK_ERR_OUT_OF_MEMORY, "out of memory for the name '%s'", name);
    return writer_started(out, w, r, err_text, err_cap);
}

/* ---- chunks ------------------------------------------------------------------------------------- */

static tpk_result check_desc(tpk_writer *w, const tpk_chunk_desc *d)
{
    char tag[16];
    tpki_tag_name(d->tag, tag);
    uint32_t size = tpki_elem_type_size(d->elem_type), want_type = 0;
    int required = 0;
    if (d->codec > TPK_CODEC_ZSTD || (d->flags & ~TPK_CHUNK_REQUIRED))
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "chunk %s: codec %u / flags 0x%x not allowed", tag,
                           d->codec, d->flags);
    if (size == 0 || d->elem_size != size)
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "chunk %s: elem_size %" PRIu32 " does not match elem_type %u",
                           tag, d->elem_size, d->elem_type);
    int known = tpki_known_tag(d->tag, &want_type, &required);
    if (known && d->elem_type != want_type)
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "chunk %s: elem_type %u, the tag needs %" PRIu32, tag,
                           d->elem_type, want_type);
    uint8_t first = (uint8_t)d->tag;
    if (!known && !(first >= 'a' && first <= 'z'))
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT,
                           "chunk %s: not a tag of format 1.0 nor a vendor tag (first byte a-z)", tag);
    if (known && !(d->flags & TPK_CHUNK_REQUIRED) != !required)
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "chunk %s: the REQUIRED flag must be %s for this tag", tag,
                           required ? "set" : "clear");
    if (d->elem_count > UINT64_MAX / size || d->elem_count * size > SIZE_MAX)
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "chunk %s: %" PRIu64 " elements: too large", tag,
                           d->elem_count);
    if (d->tag == TPK_TAG_FDSC && (w->fields || d->elem_count > TPK_MAX_FIELDS))
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "chunk %s: a second FDSC, or more than %u fields", tag,
                           TPK_MAX_FIELDS);
    return TPK_OK;
}

static tpk_result reserve_entry(tpk_writer *w)
{
    if (w->count < w->capacity)
        return TPK_OK;
    uint64_t capacity = w->capacity ? 2 * w->capacity : 16;
    tpk_dir_entry *grown = writer_alloc(w, capacity * sizeof *grown);
    if (!grown)
        return writer_fail(w, TPK_ERR_OUT_OF_MEMORY, "out of memory for %" PRIu64 " directory entries", capacity);
    if (w->count > 0)
        memcpy(grown, w->entries, w->count * sizeof *grown);
    writer_free(w, w->entries);
    w->entries = grown;
    w->capacity = capacity;
    return TPK_OK;
}

static tpk_result keep_fields(tpk_writer *w, const tpk_chunk_desc *d, const void *data)
{
    if (d->tag != TPK_TAG_FDSC)
        return TPK_OK;
    w->fields = writer_alloc(w, d->elem_count * sizeof *w->fields);
    if (!w->fields)
        return writer_fail(w, TPK_ERR_OUT_OF_MEMORY, "out of memory for %" PRIu64 " field descriptors", d->elem_count);
    if (d->elem_count > 0)
        memcpy(w->fields, data, d->elem_count * sizeof *w->fields);
    w->field_count = (uint32_t)d->elem_count;
    return TPK_OK;
}

/* zstd's multi-threaded mode cuts the input into jobs of this size, compresses them on its workers and
 * joins them into ONE frame (each job after the first primed with the end of the one before), so a
 * chunk stays one frame, as spec §4.2 requires. Its bytes depend on the job size and never on the
 * number of workers, for any count from 1 up (zstd's streaming guarantee; a first call with
 * ZSTD_e_end would take a one-pass path that lacks it, and tpk_writer_append never makes one). So every
 * zstd chunk goes through that mode, with threads workers at most: the same file for any threads. A
 * fixed job size keeps the bytes independent of zstd's default for the level; 8 MiB is that default at
 * level 3, where smaller jobs cost CPU (4 MiB: +7%, 2 MiB: +25% on grid 120's TT16) for no gain in
 * size. Chunks of 512 KiB or less zstd compresses on the calling thread, in the single-threaded
 * format, whatever the setting (again the same for any count). */
#define ZSTD_JOB_BYTES ((uint64_t)8 << 20)

/* Workers for a chunk of raw_size bytes: one per job, at most threads, at least one (not 0, whose bytes
 * differ). More than there are jobs would only hold buffers: each worker holds about two jobs' worth. */
static int zstd_workers(int threads, uint64_t raw_size)
{
    uint64_t jobs = (raw_size + ZSTD_JOB_BYTES - 1) / ZSTD_JOB_BYTES;
    int workers = threads > 1 ? threads : 1;
    return jobs < (uint64_t)workers ? (jobs > 0 ? (int)jobs : 1) : workers;
}

/* A compression context (made once; zstd allocates it itself: custom allocators are in zstd's
 * experimental API only) set up for one frame of raw_size bytes: the pledged size makes zstd record the
 * content size in the frame header. A libzstd built without threads refuses the workers: it then
 * compresses on the calling thread, in the single-threaded format, still the same for any threads. */
static tpk_result start_zstd(tpk_writer *w, int level, uint64_t raw_size)
{
    if (!w->zstd) {
        w->zstd = ZSTD_createCCtx();
        w->zstd_out = writer_alloc(w, ZSTD_CStreamOutSize());
        if (!w->zstd || !w->zstd_out)
            return writer_fail(w, TPK_ERR_OUT_OF_MEMORY, "out of memory for a zstd compression context");
    }
    size_t rc = ZSTD_CCtx_reset(w->zstd, ZSTD_reset_session_and_parameters);
    if (!ZSTD_isError(rc))
        rc = ZSTD_CCtx_setParameter(w->zstd, ZSTD_c_compressionLevel, level ? level : ZSTD_CLEVEL_DEFAULT);
    if (!ZSTD_isError(rc))
        rc = ZSTD_CCtx_setPledgedSrcSize(w->zstd, raw_size);
    if (ZSTD_isError(rc))
        return writer_fail(w, TPK_ERR_INVALID_ARGUMENT, "zstd level %d: %s", level, ZSTD_getErrorName(rc));
    if (!ZSTD_isError(ZSTD_CCtx_setParameter(w->zstd, ZSTD_c_nbWorkers, zstd_workers(w->threads, raw_size))))
        (void)ZSTD_CCtx_setParameter(w->zstd, ZSTD_c_jobSize, (int)ZSTD_JOB_BYTES);
    return TPK_OK;
}

/* Feed `size` bytes (or, with mode ZSTD_e_end, finish the frame) and write what zstd produces. */
static tpk_result pump_zstd(tpk_writer *w, const void *data, size_t size, ZSTD_EndDirective mode)
{
    ZSTD_inBuffer in = {data, size, 0};
    for (;;) {
        ZSTD_outBuffer out = {w->zstd_out, ZSTD_CStreamOutSize(), 0};
        size_t left = ZSTD_compressStream2(w->zstd, &out, &in, mode);
        if (ZSTD_isError(left))
            return writer_fail(w, TPK_ERR_OUT_OF_MEMORY, "zstd compression failed: %s", ZSTD_getErrorName(left));
        tpk_result r = write_all(w, w->zstd_out, out.pos);
        if (r != TPK_OK)
            return r;
        if (mode == ZSTD_e_end ? left == 0 : in.pos == in.size)
            return TPK_OK;
    }
}

tpk_result tpk_writer_begin_chunk(tpk_writer *writer, const tpk_chunk_desc *desc)
{
    if (!writer || !desc)
        return TPK_ERR_INVALID_ARGUMENT;
    if (writer->failed)
        return writer_fail(writer, TPK_ERR_BAD_STATE, "an earlier write failed: %s", "abort this writer");
    if (writer->open_chunk)
        return writer_fail(writer, TPK_ERR_BAD_STATE, "a streamed chunk is still open: end it first");
    tpk_result r = check_desc(writer, desc);
    if (r == TPK_OK)
        r = reserve_entry(writer);
    if (r == TPK_OK && !writer->hash && !(writer->hash = XXH64_createState()))
        r = writer_fail(writer, TPK_ERR_OUT_OF_MEMORY, "out of memory for a checksum state");
    uint64_t raw_size = desc->elem_count * desc->elem_size;
    int large = desc->codec == TPK_CODEC_NONE && raw_size >= TPK_LARGE_CHUNK_BYTES;
    if (r == TPK_OK && desc->codec == TPK_CODEC_ZSTD)
        r = start_zstd(writer, desc->zstd_level, raw_size);
    if (r == TPK_OK)
        r = pad_to(writer, large ? TPK_LARGE_CHUNK_ALIGN : TPK_CHUNK_ALIGN);
    if (r != TPK_OK)
        return r;
    tpk_dir_entry e = {.tag = desc->tag, .flags = desc->flags, .codec = desc->codec, .elem_type = desc->elem_type,
                       .elem_size = desc->elem_size, .index = desc->index, .step = desc->step,
                       .elem_count = desc->elem_count, .offset = writer->end, .raw_size = raw_size};
    writer->chunk = e;
    writer->chunk_appended = 0;
    writer->open_chunk = 1;
    XXH64_reset(writer->hash, 0);
    return TPK_OK;
}

/* Appends of this many bytes or more, uncompressed, are hashed beside the write (tpk_write_options.threads):
 * on tmpfs the write is a copy into the page cache, and the hash a second pass over the same bytes (the
 * maps and fields, written whole at the end of a conversion, each paid both on one core). */
#define HASH_ASIDE_MIN ((uint64_t)1 << 20)

typedef struct hash_job {
    XXH64_state_t *hash;
    const void *data;
    size_t size;
} hash_job;

static void *hash_run(void *arg)
{
    hash_job *job = arg;
    XXH64_update(job->hash, job->data, job->size);
    return NULL;
}

tpk_result tpk_writer_append(tpk_writer *writer, const void *data, uint64_t size)
{
    if (!writer || (!data && size > 0))
        return TPK_ERR_INVALID_ARGUMENT;
    if (!writer->open_chunk)
        return writer_fail(writer, TPK_ERR_BAD_STATE, "tpk_writer_append: no chunk begun");
    if (size > writer->chunk.raw_size - writer->chunk_appended)
        return writer_fail(writer, TPK_ERR_INVALID_ARGUMENT, "chunk data past the %" PRIu64 " bytes announced",
                           writer->chunk.raw_size);
    if (size == 0)
        return TPK_OK;
    if (writer->chunk.codec != TPK_CODEC_ZSTD && writer->threads >= 2 && size >= HASH_ASIDE_MIN) {
        hash_job job = {writer->hash, data, (size_t)size};
        pthread_t thread;
        if (pthread_create(&thread, NULL, hash_run, &job) == 0) {
            writer->chunk_appended += size;
            tpk_result r = write_all(writer, data, size);
            pthread_join(thread, NULL);
            return r;
        }
    }
    XXH64_update(writer->hash, data, (size_t)size);
    writer->chunk_appended += size;
    if (writer->chunk.codec == TPK_CODEC_ZSTD)
        return pump_zstd(writer, data, (size_t)size, ZSTD_e_continue);
    return write_all(writer, data, size);
}

tpk_result tpk_writer_end_chunk(tpk_writer *writer)
{
    if (!writer)
        return TPK_ERR_INVALID_ARGUMENT;
    if (!writer->open_chunk)
        return writer_fail(writer, TPK_ERR_BAD_STATE, "tpk_writer_end_chunk: no chunk begun");
    writer->open_chunk = 0; /* on failure the bytes stay as unreferenced padding */
    if (writer->chunk_appended != writer->chunk.raw_size)
        return writer_fail(writer, TPK_ERR_INVALID_ARGUMENT, "chunk got %" PRIu64 " of the %" PRIu64 " bytes announced",
                           writer->chunk_appended, writer->chunk.raw_size);
    tpk_result r = TPK_OK;
    if (writer->chunk.codec == TPK_CODEC_ZSTD)
        r = pump_zstd(writer, NULL, 0, ZSTD_e_end);
    if (r != TPK_OK)
        return r;
    writer->chunk.stored_size = writer->end - writer->chunk.offset;
    writer->chunk.checksum = XXH64_digest(writer->hash);
    writer->entries[writer->count++] = writer->chunk;
    return TPK_OK;
}

tpk_result tpk_writer_add_chunk(tpk_writer *writer, const tpk_chunk_desc *desc, const void *data)
{
    if (!writer || !desc || (!data && desc->elem_count > 0))
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_result r = tpk_writer_begin_chunk(writer, desc);
    if (r != TPK_OK)
        return r;
    r = tpk_writer_append(writer, data, desc->elem_count * desc->elem_size);
    if (r == TPK_OK)
        r = keep_fields(writer, desc, data);
    if (r == TPK_OK)
        r = tpk_writer_end_chunk(writer);
    else
        writer->open_chunk = 0; /* abandon the chunk begun here; its bytes stay as padding */
    return r;
}

/* ---- finish ------------------------------------------------------------------------------------- */

static void build_header(const tpk_writer *w, const tpk_header_fields *fields, uint64_t directory_offset,
                         tpk_header *h)
{
    memset(h, 0, sizeof *h);
    memcpy(h->magic, TPK_MAGIC, TPK_MAGIC_SIZE);
    h->version_major = TPK_VERSION_MAJOR;
    h->version_minor = TPK_VERSION_MINOR_PLAIN;
    for (uint64_t i = 0; i < w->count; i++) /* writer rule 1: 1.2, 1.3 or 1.4 only where their chunks are used */
        if ((w->entries[i].tag == TPK_TAG_PART || w->entries[i].tag == TPK_TAG_LINK) &&
            h->version_minor < TPK_VERSION_MINOR_PARTS)
            h->version_minor = TPK_VERSION_MINOR_PARTS;
        else if (w->entries[i].tag == TPK_TAG_LEVL && h->version_minor < TPK_VERSION_MINOR_LEVELS)
            h->version_minor = TPK_VERSION_MINOR_LEVELS;
        else if (w->entries[i].tag == TPK_TAG_CULL)
            h->version_minor = TPK_VERSION_MINOR_CULL;
    h->header_size = TPK_HEADER_SIZE;
    h->dir_entry_size = TPK_DIR_ENTRY_SIZE;
    h->directory_offset = directory_offset;
    h->chunk_count = w->count;
    h->file_size = directory_offset + w->count * TPK_DIR_ENTRY_SIZE;
    h->vertex_count = fields->vertex_count;
    h->tet_count = fields->tet_count;
    h->shell_face_count = fields->shell_face_count;
    memcpy(h->origin, fields->origin, sizeof h->origin);
    memcpy(h->bounds_min, fields->bounds_min, sizeof h->bounds_min);
    memcpy(h->bounds_max, fields->bounds_max, sizeof h->bounds_max);
    h->directory_checksum = XXH64(w->entries, w->count * TPK_DIR_ENTRY_SIZE, 0);
    h->header_checksum = XXH64(h, offsetof(tpk_header, header_checksum), 0);
}

static tpk_result write_tail(tpk_writer *w, const tpk_header_fields *fields)
{
    tpk_header h;
    tpki_diag diag;
    uint64_t directory_offset = (w->end + TPK_CHUNK_ALIGN - 1) / TPK_CHUNK_ALIGN * TPK_CHUNK_ALIGN;
    build_header(w, fields, directory_offset, &h);
    tpk_result r = tpki_check_layout(&h, w->entries, w->fields, w->field_count, &w->allocator, &diag);
    if (r != TPK_OK)
        return writer_fail(w, r == TPK_ERR_OUT_OF_MEMORY ? r : TPK_ERR_INVALID_ARGUMENT,
                           "refusing to write an invalid file '%s': %s", w->path, diag.text);
    r = pad_to(w, TPK_CHUNK_ALIGN);
    if (r == TPK_OK)
        r = write_all(w, w->entries, w->count * TPK_DIR_ENTRY_SIZE);
    if (r == TPK_OK)
        r = pwrite_all(w, &h, sizeof h, 0);
    if (r == TPK_OK && fsync(w->fd) != 0)
        r = io_fail(w, "cannot flush");
    return r;
}

tpk_result tpk_writer_finish(tpk_writer *writer, const tpk_header_fields *header)
{
    if (!writer)
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_result r = TPK_OK;
    if (!header)
        r = writer_fail(writer, TPK_ERR_INVALID_ARGUMENT, "tpk_writer_finish: NULL header fields");
    else if (writer->failed)
        r = writer_fail(writer, TPK_ERR_BAD_STATE, "an earlier write to '%s' failed",
                       writer->temp_path ? writer->temp_path : writer->path);
    else if (writer->open_chunk)
        r = writer_fail(writer, TPK_ERR_BAD_STATE, "a streamed chunk is still open at finish");
    if (r == TPK_OK)
        r = write_tail(writer, header);
    if (r == TPK_OK && writer->owns_fd) { /* else flushed (write_tail): the caller puts its file in place */
        int closed = close(writer->fd);
        writer->fd = -1;
        if (closed != 0)
            r = io_fail(writer, "cannot close");
        else if (rename(writer->temp_path, writer->path) != 0)
            r = io_fail(writer, "cannot rename into place");
        else
            writer_free(writer, writer->temp_path);
        if (r == TPK_OK)
            writer->temp_path = NULL; /* renamed: nothing left to unlink */
    }
    writer_destroy(writer);
    return r;
}

void tpk_writer_abort(tpk_writer *writer)
{
    if (writer)
        writer_destroy(writer);
}

const char *tpk_writer_error_text(const tpk_writer *writer)
{
    return writer ? writer->error_text : "";
}
