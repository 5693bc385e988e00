/* Opening a tetpack file (mmap or caller memory): header and directory validation (rules 1-15), and
 * access to chunks, fields and time values. Opening reads only the header, the directory and the small
 * FDSC chunk; chunk data is checked when first used (chunks.c), or all at once with
 * TPK_OPEN_VERIFY_ALL or tpk_verify. */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "internal_file.h"

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    uint8_t first;
    memcpy(&first, &one, 1);
    return first == 1;
}

static tpk_file *file_create(const tpk_open_options *options)
{
    tpk_open_options opt = {0};
    if (options)
        memcpy(&opt, options, options->size && options->size < sizeof opt ? options->size : sizeof opt);
    tpk_allocator allocator;
    tpki_resolve_allocator(&opt.allocator, &allocator);
    tpk_file *file = allocator.alloc(allocator.user, sizeof *file);
    if (!file)
        return NULL;
    memset(file, 0, sizeof *file);
    file->allocator = allocator;
    file->flags = opt.flags;
    tpki_resolve_limits(&opt.limits, &file->limits);
    file->message = opt.message;
    file->message_user = opt.message_user;
    atomic_init(&file->poisoned, 0);
    if (pthread_mutex_init(&file->lock, NULL) != 0) {
        allocator.free(allocator.user, file);
        return NULL;
    }
    return file;
}

void tpk_close(tpk_file *file)
{
    if (!file)
        return;
    for (uint64_t i = 0; file->decoded && i < file->header.chunk_count; i++)
        tpki_file_free(file, file->decoded[i]);
    tpki_file_free(file, file->decoded);
    tpki_file_free(file, file->entries);
    tpki_file_free(file, (void *)file->chunk_state);
    tpki_file_free(file, file->fields);
    if (file->mapping)
        munmap(file->mapping, file->mapping_size);
    pthread_mutex_destroy(&file->lock);
    file->allocator.free(file->allocator.user, file);
}

/* ---- header (rules 1-9) ------------------------------------------------------------------------ */

static tpk_result check_magic(const uint8_t *data, uint64_t size, tpki_diag *diag)
{
    size_t n = size < TPK_MAGIC_SIZE ? (size_t)size : TPK_MAGIC_SIZE;
    if (n > 0 && memcmp(data, TPK_MAGIC, n) == 0)
        return n == TPK_MAGIC_SIZE ? TPK_OK
                                   : tpki_fail(diag, TPK_ERR_TRUNCATED,
                                                   "file is %zu bytes, shorter than the 8-byte magic", n);
    if (n == 0)
        return tpki_fail(diag, TPK_ERR_TRUNCATED, "file is empty");
    if (n >= 4 && memcmp(data, TPK_MAGIC, 4) == 0)
        return tpki_fail(diag, TPK_ERR_NOT_TETPACK,
                             "magic bytes 4..7 are %02x %02x %02x %02x, expected 0d 0a 1a 0a: the file was "
                             "probably transferred in text mode (line endings converted)",
                             data[4], n > 5 ? data[5] : 0, n > 6 ? data[6] : 0, n > 7 ? data[7] : 0);
    return tpki_fail(diag, TPK_ERR_NOT_TETPACK,
                         "not a tetpack file: first byte 0x%02x, expected the magic 89 54 50 4b 0d 0a 1a 0a",
                         data[0]);
}

/* Rules 2-4: size, version (before checksums: a newer major may change the header), checksum. */
static tpk_result check_header_start(const uint8_t *data, uint64_t size, tpk_header *h, tpki_diag *diag)
{
    if (size < TPK_HEADER_SIZE)
        return tpki_fail(diag, TPK_ERR_TRUNCATED, "file is %" PRIu64 " bytes, shorter than the %u-byte header",
                             size, TPK_HEADER_SIZE);
    memcpy(h, data, sizeof *h);
    if (h->version_major > TPK_VERSION_MAJOR)
        return tpki_fail(diag, TPK_ERR_VERSION, "file is format %u.x, this reader supports %u.x",
                             h->version_major, TPK_VERSION_MAJOR);
    if (h->version_major == 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "header: version_major is 0");
    uint64_t sum = XXH64(data, offsetof(tpk_header, header_checksum), 0);
    if (sum != h->header_checksum)
        return tpki_fail(diag, TPK_ERR_HEADER_CHECKSUM,
                             "header: checksum of bytes 0..184 is 0x%016" PRIx64 ", header_checksum says 0x%016" PRIx64,
                             sum, h->header_checksum);
    return TPK_OK;
}

static tpk_result check_header(const uint8_t *data, uint64_t size, const tpk_limits *limits, tpk_header *h,
                               tpki_diag *diag)
{
    tpk_result r = check_magic(data, size, diag);
    if (r == TPK_OK)
        r = check_header_start(data, size, h, diag);
    if (r == TPK_OK)
        r = tpki_check_header_fields(h, diag);
    if (r != TPK_OK)
        return r;
    if (h->file_size > size)
        return tpki_fail(diag, TPK_ERR_TRUNCATED, "header: file_size is %" PRIu64 " but the file has %" PRIu64
                             " bytes", h->file_size, size);
    if (h->file_size < size)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "header: file_size is %" PRIu64 " but the file has %" PRIu64
                             " bytes (trailing data)", h->file_size, size);
    r = tpki_check_header_counts(h, limits, diag);
    if (r != TPK_OK)
        return r;
    uint64_t sum = XXH64(data + h->directory_offset, h->chunk_count * TPK_DIR_ENTRY_SIZE, 0);
    if (sum != h->directory_checksum)
        return tpki_fail(diag, TPK_ERR_DIRECTORY_CHECKSUM,
                             "directory at offset %" PRIu64 ": checksum is 0x%016" PRIx64
                             ", header says 0x%016" PRIx64, h->directory_offset, sum, h->directory_checksum);
    return TPK_OK;
}

/* ---- directory (rules 10-14) ------------------------------------------------------------------- */

static tpk_result load_directory(tpk_file *file, tpki_diag *diag)
{
    uint64_t count = file->header.chunk_count;
    file->entries = tpki_file_alloc(file, count * sizeof *file->entries);
    file->chunk_state = tpki_file_alloc(file, count * sizeof *file->chunk_state);
    file->decoded = tpki_file_alloc(file, count * sizeof *file->decoded);
    if (file->decoded)
        memset(file->decoded, 0, count * sizeof *file->decoded);
    if (!file->entries || !file->chunk_state || !file->decoded)
        return tpki_fail(diag, TPK_ERR_OUT_OF_MEMORY, "out of memory for a directory of %" PRIu64 " chunks",
                             count);
    memcpy(file->entries, file->data + file->header.directory_offset, count * sizeof *file->entries);
    for (uint64_t i = 0; i < count; i++)
        atomic_init(&file->chunk_state[i], 0);
    uint64_t total = 0;
    for (uint64_t i = 0; i < count; i++) {
        tpk_result r = tpki_check_entry(&file->header, &file->limits, i, &file->entries[i], &total, diag);
        if (r != TPK_OK)
            return r;
    }
    tpk_result r = tpki_check_overlaps(&file->header, file->entries, &file->allocator, diag);
    if (r == TPK_OK)
        r = tpki_check_tags(&file->header, file->entries, 0, &file->allocator, diag);
    return r;
}

/* ---- fields (rule 15) ---------------------------------------------------------------------------- */

static tpk_result load_fields(tpk_file *file)
{
    uint64_t i;
    if (tpk_find_chunk(file, TPK_TAG_FDSC, 0, 0, &i) != TPK_OK)
        return TPK_OK;
    const tpk_dir_entry *e = &file->entries[i];
    file->fields = tpki_file_alloc(file, e->raw_size);
    if (!file->fields)
        return tpki_file_fail(file, TPK_ERR_OUT_OF_MEMORY, "out of memory for %" PRIu64 " field descriptors",
                             e->elem_count);
    tpk_result r = tpki_file_decode(file, i, file->fields);
    if (r == TPK_OK && !(file->flags & TPK_OPEN_TRUSTED))
        r = tpki_file_check_sum(file, i, file->fields);
    if (r != TPK_OK)
        return r;
    file->field_count = (uint32_t)e->elem_count;
    tpki_diag diag;
    r = tpki_check_fields(&file->header, file->entries, file->fields, file->field_count, &file->allocator, &diag);
    return r == TPK_OK ? r : tpki_file_report(file, r, diag.text);
}

/* ---- open ------------------------------------------------------------------------------------------- */

static tpk_result validate(tpk_file *file)
{
    tpki_diag diag;
    if (!host_is_little_endian())
        return tpki_file_fail(file, TPK_ERR_INVALID_ARGUMENT, "libtetpack supports little-endian hosts only");
    tpk_result r = check_header(file->data, file->size, &file->limits, &file->header, &diag);
    if (r == TPK_OK)
        r = load_directory(file, &diag);
    if (r != TPK_OK)
        return tpki_file_report(file, r, diag.text);
    r = load_fields(file);
    for (uint64_t i = 0; r == TPK_OK && (file->flags & TPK_OPEN_VERIFY_ALL) && i < file->header.chunk_count; i++)
        r = tpki_file_verify_chunk(file, i, 0);
    return r;
}

/* Validate, then hand the file out or close it with its message copied to err_text. */
static tpk_result finish_open(tpk_file *file, tpk_result r, tpk_file **out, char *err_text, size_t err_cap)
{
    if (r == TPK_OK)
        r = validate(file);
    if (r != TPK_OK) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "%s", file->error_text);
        tpk_close(file);
        return r;
    }
    *out = file;
    return TPK_OK;
}

static tpk_result open_failed(tpk_result r, const char *text, char *err_text, size_t err_cap)
{
    if (err_text && err_cap)
        snprintf(err_text, err_cap, "%s", text);
    return r;
}

tpk_result tpk_open_memory(tpk_file **out, const void *data, size_t size, const tpk_open_options *options,
                           char *err_text, size_t err_cap)
{
    if (!out || (!data && size > 0))
        return open_failed(TPK_ERR_INVALID_ARGUMENT, "tpk_open_memory: NULL argument", err_text, err_cap);
    *out = NULL;
    tpk_file *file = file_create(options);
    if (!file)
        return open_failed(TPK_ERR_OUT_OF_MEMORY, "out of memory for the file handle", err_text, err_cap);
    file->data = data;
    file->size = size;
    return finish_open(file, TPK_OK, out, err_text, err_cap);
}

/* Map the file at path into file->data (an empty file maps nothing). */
static tpk_result map_path(tpk_file *file, const char *path)
{
    char reason[128] = "";
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0)
        goto fail;
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return tpki_file_fail(file, TPK_ERR_IO, "'%s': not a regular file", path);
    }
    if (st.st_size > 0) {
        void *map = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (map == MAP_FAILED)
            goto fail;
        file->mapping = map;
        file->mapping_size = (size_t)st.st_size;
        file->data = map;
        file->size = (uint64_t)st.st_size;
    }
    close(fd);
    return TPK_OK;
fail:
    strerror_r(errno, reason, sizeof reason);
    if (fd >= 0)
        close(fd);
    return tpki_file_fail(file, TPK_ERR_IO, "cannot open '%s': %s", path, reason);
}

tpk_result tpk_open_path(tpk_file **out, const char *path, const tpk_open_options *options, char *err_text,
                         size_t err_cap)
{
    if (!out || !path)
        return open_failed(TPK_ERR_INVALID_ARGUMENT, "tpk_open_path: NULL argument", err_text, err_cap);
    *out = NULL;
    tpk_file *file = file_create(options);
    if (!file)
        return open_failed(TPK_ERR_OUT_OF_MEMORY, "out of memory for the file handle", err_text, err_cap);
    return finish_open(file, map_path(file, path), out, err_text, err_cap);
}

/* ---- directory queries ------------------------------------------------------------------------------ */

tpk_result tpk_get_info(const tpk_file *file, tpk_file_info *out)
{
    if (!file || !out)
        return TPK_ERR_INVALID_ARGUMENT;
    const tpk_header *h = &file->header;
    *out = (tpk_file_info){
        .version_major = h->version_major, .version_minor = h->version_minor, .file_size = h->file_size,
        .vertex_count = h->vertex_count, .tet_count = h->tet_count, .shell_face_count = h->shell_face_count,
        .chunk_count = h->chunk_count,
    };
    memcpy(out->origin, h->origin, sizeof out->origin);
    memcpy(out->bounds_min, h->bounds_min, sizeof out->bounds_min);
    memcpy(out->bounds_max, h->bounds_max, sizeof out->bounds_max);
    return TPK_OK;
}

tpk_result tpk_get_chunk(const tpk_file *file, uint64_t i, tpk_dir_entry *out)
{
    if (!file || !out || i >= file->header.chunk_count)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = file->entries[i];
    return TPK_OK;
}

tpk_result tpk_find_chunk(const tpk_file *file, uint32_t tag, uint32_t index, uint32_t step, uint64_t *out_i)
{
    if (!file || !out_i)
        return TPK_ERR_INVALID_ARGUMENT;
    for (uint64_t i = 0; i < file->header.chunk_count; i++) {
        const tpk_dir_entry *e = &file->entries[i];
        if (e->tag == tag && e->index == index && e->step == step) {
            *out_i = i;
            return TPK_OK;
        }
    }
    return TPK_ERR_NOT_FOUND;
}

/* ---- chunk access ----------------------------------------------------------------------------------- */

static tpk_result check_chunk_arg(tpk_file *file, uint64_t i, const char *function)
{
    if (i >= file->header.chunk_count)
        return tpki_file_fail(file, TPK_ERR_INVALID_ARGUMENT, "%s: chunk %" PRIu64 " of %" PRIu64, function, i,
                             file->header.chunk_count);
    return tpki_file_usable(file);
}

tpk_result tpk_view_chunk(tpk_file *file, uint64_t i, const void **out_data, uint64_t *out_size)
{
    if (!file || !out_data || !out_size)
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_result r = check_chunk_arg(file, i, "tpk_view_chunk");
    if (r != TPK_OK)
        return r;
    const tpk_dir_entry *e = &file->entries[i];
    if (e->codec != TPK_CODEC_NONE) {
        char name[80], text[160];
        tpki_entry_name(i, &file->entries[i], name);
        snprintf(text, sizeof text, "%s is zstd-compressed: use tpk_read_chunk", name);
        return tpki_file_refuse(file, TPK_ERR_UNSUPPORTED_CHUNK, text); /* a caller mistake, not corruption */
    }
    const void *raw = file->data + e->offset;
    tpki_file_mark_read(file, i);
    if (tpki_file_needs_sum(file, i) && (r = tpki_file_check_sum(file, i, raw)) != TPK_OK)
        return r;
    *out_data = raw;
    *out_size = e->raw_size;
    return TPK_OK;
}

tpk_result tpk_read_chunk(tpk_file *file, uint64_t i, void *dst, uint64_t dst_size)
{
    if (!file)
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_result r = check_chunk_arg(file, i, "tpk_read_chunk");
    if (r != TPK_OK)
        return r;
    const tpk_dir_entry *e = &file->entries[i];
    if (dst_size < e->raw_size || (!dst && e->raw_size > 0))
        return tpki_file_fail(file, TPK_ERR_INVALID_ARGUMENT,
                             "tpk_read_chunk: chunk %" PRIu64 " needs %" PRIu64 " bytes, dst has %" PRIu64, i,
                             e->raw_size, dst ? dst_size : 0);
    r = tpki_file_decode(file, i, dst);
    if (r == TPK_OK && tpki_file_needs_sum(file, i))
        r = tpki_file_check_sum(file, i, dst);
    return r;
}

tpk_result tpk_get_chunk_use(const tpk_file *file, uint64_t i, uint32_t *out_bits)
{
    if (!file || !out_bits || i >= file->header.chunk_count)
        return TPK_ERR_INVALID_ARGUMENT;
    uint32_t state = atomic_load(&file->chunk_state[i]);
    *out_bits = ((state & TPK_CHUNK_READ) ? TPK_CHUNK_USE_READ : 0u) | ((state & TPK_CHUNK_SUM_OK) ? TPK_CHUNK_USE_VERIFIED : 0u);
    return TPK_OK;
}

/* ---- fields and time ---------------------------------------------------------------------------------- */

uint32_t tpk_field_count(const tpk_file *file)
{
    return file ? file->field_count : 0;
}

tpk_result tpk_get_field(const tpk_file *file, uint32_t i, tpk_field_desc *out)
{
    if (!file || !out || i >= file->field_count)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = file->fields[i];
    return TPK_OK;
}

tpk_result tpk_find_field(const tpk_file *file, const char *name, uint32_t *out_i)
{
    if (!file || !name || !out_i)
        return TPK_ERR_INVALID_ARGUMENT;
    for (uint32_t i = 0; i < file->field_count; i++) {
        if (strcmp(file->fields[i].name, name) == 0) {
            *out_i = i;
            return TPK_OK;
        }
    }
    return TPK_ERR_NOT_FOUND;
}

tpk_result tpk_get_time(tpk_file *file, uint32_t step, double *out_time)
{
    if (!file || !out_time)
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_result r = tpki_file_usable(file);
    uint64_t i;
    if (r != TPK_OK)
        return r;
    if (tpk_find_chunk(file, TPK_TAG_TIME, 0, 0, &i) != TPK_OK)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "the file stores no 'TIME' chunk");
    if (step >= file->entries[i].elem_count)
        return tpki_file_fail(file, TPK_ERR_INVALID_ARGUMENT, "step %" PRIu32 " but the file has %" PRIu64 " time steps",
                             step, file->entries[i].elem_count);
    const void *raw;
    r = tpki_file_chunk_bytes(file, i, &raw);
    if (r == TPK_OK)
        memcpy(out_time, (const uint8_t *)raw + (size_t)step * sizeof(double), sizeof(double));
    return r;
}

/* ---- whole-file check ------------------------------------------------------------------------------ */

tpk_result tpk_verify(tpk_file *file)
{
    if (!file)
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_result r = tpki_file_usable(file);
    for (uint64_t i = 0; r == TPK_OK && i < file->header.chunk_count; i++)
        r = tpki_file_verify_chunk(file, i, 1);
    return r;
}
