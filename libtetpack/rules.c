/* The container rules as pure check_* functions over a header, a directory and raw chunk bytes,
 * shared by the reader and the writer's self-check, so the rules live once. Rule numbers follow the
 * reader section of the spec; each rule returns its own result code and a message naming the chunk,
 * its tag and offset, and what was expected. Pure: no handle, and calls nothing else in libtetpack. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal_file.h"

tpk_result tpki_fail(tpki_diag *diag, tpk_result code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(diag->text, sizeof diag->text, fmt, ap);
    va_end(ap);
    return code;
}

tpk_result tpki_text_fail(char *err, size_t cap, tpk_result code, const char *fmt, ...)
{
    if (err && cap) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, cap, fmt, ap);
        va_end(ap);
    }
    return code;
}

void tpki_tag_name(uint32_t tag, char out[16])
{
    unsigned char c[4];
    for (int k = 0; k < 4; k++) {
        c[k] = (unsigned char)(tag >> (8 * k));
        if (c[k] < 0x20 || c[k] > 0x7e) {
            snprintf(out, 16, "0x%08" PRIx32, tag);
            return;
        }
    }
    snprintf(out, 16, "'%c%c%c%c'", c[0], c[1], c[2], c[3]);
}

void tpki_entry_name(uint64_t i, const tpk_dir_entry *e, char out[80])
{
    char tag[16];
    tpki_tag_name(e->tag, tag);
    snprintf(out, 80, "chunk %" PRIu64 " %s at offset %" PRIu64, i, tag, e->offset);
}

static void *default_alloc(void *user, size_t size)
{
    (void)user;
    return malloc(size);
}

static void default_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

void tpki_resolve_allocator(const tpk_allocator *in, tpk_allocator *out)
{
    *out = in ? *in : (tpk_allocator){0};
    if (!out->alloc)
        out->alloc = default_alloc;
    if (!out->free)
        out->free = default_free;
}

void tpki_resolve_limits(const tpk_limits *in, tpk_limits *out)
{
    *out = in ? *in : (tpk_limits){0};
    if (!out->max_chunks)
        out->max_chunks = TPK_DEFAULT_MAX_CHUNKS;
    if (!out->max_chunk_bytes)
        out->max_chunk_bytes = TPK_DEFAULT_MAX_CHUNK_BYTES;
    if (!out->max_total_bytes)
        out->max_total_bytes = TPK_DEFAULT_MAX_TOTAL_BYTES;
}

uint32_t tpki_elem_type_size(uint32_t elem_type)
{
    static const uint32_t sizes[TPK_ELEM_TYPE_COUNT] = {1, 4, 4, 8, 12, 16, 20, 32, 16, 128};
    return elem_type < TPK_ELEM_TYPE_COUNT ? sizes[elem_type] : 0;
}

int tpki_known_tag(uint32_t tag, uint32_t *out_elem_type, int *out_required)
{
    static const struct {
        uint32_t tag, elem_type;
        int required; /* what a writer must set (spec, writer rule 5) */
    } known[] = {
        {TPK_TAG_META, TPK_ELEM_BYTE, 0},       {TPK_TAG_POS3, TPK_ELEM_VEC3_F32, 1},
        {TPK_TAG_TT16, TPK_ELEM_TET16, 1},      {TPK_TAG_TT20, TPK_ELEM_TET20, 1},
        {TPK_TAG_TT32, TPK_ELEM_TET32, 1},      {TPK_TAG_SHEL, TPK_ELEM_SHELL_FACE, 1},
        {TPK_TAG_FDSC, TPK_ELEM_FIELD_DESC, 1}, {TPK_TAG_FDAT, TPK_ELEM_F32, 1},
        {TPK_TAG_TIME, TPK_ELEM_F64, 0},        {TPK_TAG_TMAP, TPK_ELEM_I32, 0},
        {TPK_TAG_VMAP, TPK_ELEM_I32, 0},        {TPK_TAG_PART, TPK_ELEM_BYTE, 0},
        {TPK_TAG_LINK, TPK_ELEM_I32, 0},        {TPK_TAG_LEVL, TPK_ELEM_BYTE, 0},
        {TPK_TAG_CULL, TPK_ELEM_I32, 0},
    };
    for (size_t k = 0; k < sizeof known / sizeof known[0]; k++) {
        if (known[k].tag == tag) {
            if (out_elem_type)
                *out_elem_type = known[k].elem_type;
            if (out_required)
                *out_required = known[k].required;
            return 1;
        }
    }
    return 0;
}

/* ---- header ---------------------------------------------------------------------------------- */

/* Rule 5 (format 1.1): origin and bounds finite, since every position a reader computes adds the
 * origin, and a renderer frames its camera on the bounds. */
static tpk_result check_header_frame(const tpk_header *h, tpki_diag *diag)
{
    static const char *const names[3] = {"origin", "bounds_min", "bounds_max"};
    const double *values[3] = {h->origin, h->bounds_min, h->bounds_max};
    const size_t offsets[3] = {offsetof(tpk_header, origin), offsetof(tpk_header, bounds_min),
                               offsetof(tpk_header, bounds_max)};
    for (int f = 0; f < 3; f++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(values[f][k]))
                return tpki_fail(diag, TPK_ERR_CORRUPT, "header: %s[%d] (byte offset %zu) is %g, must be finite",
                                 names[f], k, offsets[f] + 8 * (size_t)k, values[f][k]);
    return TPK_OK;
}

tpk_result tpki_check_header_fields(const tpk_header *h, tpki_diag *diag)
{
    if (h->header_size != TPK_HEADER_SIZE)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "header: header_size is %" PRIu32 ", must be %u",
                             h->header_size, TPK_HEADER_SIZE);
    if (h->dir_entry_size != TPK_DIR_ENTRY_SIZE)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "header: dir_entry_size is %" PRIu32 ", must be %u",
                             h->dir_entry_size, TPK_DIR_ENTRY_SIZE);
    if (h->flags != 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "header: flags is 0x%08" PRIx32 ", reserved bits must be 0", h->flags);
    for (size_t k = 0; k < sizeof h->reserved; k++) {
        if (h->reserved[k] != 0)
            return tpki_fail(diag, TPK_ERR_CORRUPT,
                                 "header: reserved byte at offset %zu is 0x%02x, must be 0",
                                 offsetof(tpk_header, reserved) + k, h->reserved[k]);
    }
    return check_header_frame(h, diag);
}

tpk_result tpki_check_header_counts(const tpk_header *h, const tpk_limits *limits, tpki_diag *diag)
{
    if (h->vertex_count > TPK_MAX_ID || h->tet_count > TPK_MAX_ID)
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "header: vertex_count %" PRIu64 " / tet_count %" PRIu64
                             " exceeds 2^31-1 (split larger meshes into parts)",
                             h->vertex_count, h->tet_count);
    if (h->shell_face_count > 4 * h->tet_count)
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "header: shell_face_count %" PRIu64 " exceeds 4 * tet_count = %" PRIu64,
                             h->shell_face_count, 4 * h->tet_count);
    if (h->chunk_count > limits->max_chunks)
        return tpki_fail(diag, TPK_ERR_LIMIT,
                             "header: chunk_count %" PRIu64 " exceeds the limit max_chunks %" PRIu64,
                             h->chunk_count, limits->max_chunks);
    if (h->directory_offset % TPK_CHUNK_ALIGN != 0)
        return tpki_fail(diag, TPK_ERR_MISALIGNED,
                             "header: directory_offset %" PRIu64 " is not a multiple of %u",
                             h->directory_offset, TPK_CHUNK_ALIGN);
    if (h->directory_offset < TPK_HEADER_SIZE || h->directory_offset > h->file_size ||
        h->chunk_count > (h->file_size - h->directory_offset) / TPK_DIR_ENTRY_SIZE)
        return tpki_fail(diag, TPK_ERR_OUT_OF_BOUNDS,
                             "header: directory at offset %" PRIu64 " with %" PRIu64
                             " entries of 64 bytes does not fit in [192, file_size %" PRIu64 "]",
                             h->directory_offset, h->chunk_count, h->file_size);
    return TPK_OK;
}

/* ---- directory entries --------------------------------------------------------------------------- */

/* Rule 10, first part: reserved bits, codec, element type and sizes. */
static tpk_result check_entry_sizes(const tpk_dir_entry *e, const char *name, tpki_diag *diag)
{
    if (e->reserved != 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: reserved field is 0x%08" PRIx32 ", must be 0",
                             name, e->reserved);
    if (e->flags & ~TPK_CHUNK_REQUIRED)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: flags 0x%04x has reserved bits set", name,
                             e->flags);
    if (e->codec > TPK_CODEC_ZSTD)
        return tpki_fail(diag, TPK_ERR_UNSUPPORTED_CHUNK,
                             "%s: unknown codec %u (this reader knows 0 = none, 1 = zstd)", name, e->codec);
    uint32_t size = tpki_elem_type_size(e->elem_type);
    if (size == 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: unknown elem_type %u", name, e->elem_type);
    if (e->elem_size != size)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: elem_size %" PRIu32 " but elem_type %u has size %" PRIu32,
                             name, e->elem_size, e->elem_type, size);
    if (e->elem_count > UINT64_MAX / size || e->elem_count * size != e->raw_size)
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "%s: raw_size %" PRIu64 " but elem_count %" PRIu64 " * elem_size %" PRIu32
                             " differs", name, e->raw_size, e->elem_count, size);
    if (e->codec == TPK_CODEC_NONE && e->stored_size != e->raw_size)
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "%s: stored_size %" PRIu64 " but codec none needs raw_size %" PRIu64, name,
                             e->stored_size, e->raw_size);
    /* Format 1.1: no Zstandard frame expands further (each block decodes to at most 128 KiB and takes
     * at least 4 bytes), so a larger claim is damage, refused before anything is allocated for it. */
    if (e->codec == TPK_CODEC_ZSTD && e->stored_size < e->raw_size / TPK_ZSTD_MAX_EXPANSION +
                                                           (e->raw_size % TPK_ZSTD_MAX_EXPANSION != 0))
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "%s: implausible raw_size %" PRIu64 " from %" PRIu64 " stored bytes: a zstd frame "
                             "expands at most %u times", name, e->raw_size, e->stored_size, TPK_ZSTD_MAX_EXPANSION);
    return TPK_OK;
}

/* Rule 10, second part: caller limits. */
static tpk_result check_entry_limits(const tpk_dir_entry *e, const char *name, const tpk_limits *limits,
                                     uint64_t *total_raw, tpki_diag *diag)
{
    if (e->raw_size > limits->max_chunk_bytes)
        return tpki_fail(diag, TPK_ERR_LIMIT,
                             "%s: raw_size %" PRIu64 " exceeds the limit max_chunk_bytes %" PRIu64, name,
                             e->raw_size, limits->max_chunk_bytes);
    if (e->raw_size > limits->max_total_bytes - *total_raw)
        return tpki_fail(diag, TPK_ERR_LIMIT,
                             "%s: raw sizes of the chunks so far exceed the limit max_total_bytes %" PRIu64,
                             name, limits->max_total_bytes);
    *total_raw += e->raw_size;
    return TPK_OK;
}

tpk_result tpki_check_entry(const tpk_header *h, const tpk_limits *limits, uint64_t i,
                           const tpk_dir_entry *e, uint64_t *total_raw, tpki_diag *diag)
{
    char name[80];
    tpki_entry_name(i, e, name);
    tpk_result r = check_entry_sizes(e, name, diag);
    if (r == TPK_OK)
        r = check_entry_limits(e, name, limits, total_raw, diag);
    if (r != TPK_OK)
        return r;
    if (e->offset % TPK_CHUNK_ALIGN != 0)
        return tpki_fail(diag, TPK_ERR_MISALIGNED, "%s: offset is not a multiple of %u", name,
                             TPK_CHUNK_ALIGN);
    if (e->codec == TPK_CODEC_NONE && e->raw_size >= TPK_LARGE_CHUNK_BYTES &&
        e->offset % TPK_LARGE_CHUNK_ALIGN != 0)
        return tpki_fail(diag, TPK_ERR_MISALIGNED,
                             "%s: uncompressed chunk of %" PRIu64 " bytes (>= %u) must be aligned to %u",
                             name, e->raw_size, TPK_LARGE_CHUNK_BYTES, TPK_LARGE_CHUNK_ALIGN);
    if (e->offset > h->file_size || e->stored_size > h->file_size - e->offset)
        return tpki_fail(diag, TPK_ERR_OUT_OF_BOUNDS,
                             "%s: stored_size %" PRIu64 " reaches past the end of the file (%" PRIu64 " bytes)",
                             name, e->stored_size, h->file_size);
    return TPK_OK;
}

/* ---- overlaps (rule 12) ------------------------------------------------------------------------ */

#define RANGE_HEADER UINT64_MAX
#define RANGE_DIRECTORY (UINT64_MAX - 1)

typedef struct byte_range {
    uint64_t begin, end, owner; /* owner: chunk index, RANGE_HEADER or RANGE_DIRECTORY */
} byte_range;

static int compare_ranges(const void *pa, const void *pb)
{
    const byte_range *a = pa, *b = pb;
    if (a->begin != b->begin)
        return a->begin < b->begin ? -1 : 1;
    return a->owner < b->owner ? -1 : a->owner > b->owner;
}

static void range_name(const tpk_dir_entry *entries, const byte_range *range, char out[80])
{
    if (range->owner == RANGE_HEADER)
        snprintf(out, 80, "the header");
    else if (range->owner == RANGE_DIRECTORY)
        snprintf(out, 80, "the directory");
    else
        tpki_entry_name(range->owner, &entries[range->owner], out);
}

static size_t collect_ranges(const tpk_header *h, const tpk_dir_entry *entries, byte_range *ranges)
{
    size_t n = 0;
    ranges[n++] = (byte_range){0, TPK_HEADER_SIZE, RANGE_HEADER};
    if (h->chunk_count > 0)
        ranges[n++] = (byte_range){h->directory_offset,
                                   h->directory_offset + h->chunk_count * TPK_DIR_ENTRY_SIZE, RANGE_DIRECTORY};
    for (uint64_t i = 0; i < h->chunk_count; i++) {
        if (entries[i].stored_size > 0)
            ranges[n++] = (byte_range){entries[i].offset, entries[i].offset + entries[i].stored_size, i};
    }
    return n;
}

tpk_result tpki_check_overlaps(const tpk_header *h, const tpk_dir_entry *entries,
                              const tpk_allocator *allocator, tpki_diag *diag)
{
    tpk_result r = TPK_OK;
    byte_range *ranges = allocator->alloc(allocator->user, (h->chunk_count + 2) * sizeof *ranges);
    if (!ranges)
        return tpki_fail(diag, TPK_ERR_OUT_OF_MEMORY, "out of memory checking %" PRIu64 " chunk ranges",
                             h->chunk_count);
    size_t n = collect_ranges(h, entries, ranges);
    qsort(ranges, n, sizeof *ranges, compare_ranges);
    size_t widest = 0; /* the range reaching furthest among those before k */
    for (size_t k = 1; k < n; k++) {
        if (ranges[k].begin < ranges[widest].end) {
            char a[80], b[80];
            range_name(entries, &ranges[widest], a);
            range_name(entries, &ranges[k], b);
            r = tpki_fail(diag, TPK_ERR_OVERLAP,
                              "%s (bytes %" PRIu64 "..%" PRIu64 ") overlaps %s (bytes %" PRIu64 "..%" PRIu64 ")",
                              b, ranges[k].begin, ranges[k].end, a, ranges[widest].begin, ranges[widest].end);
            goto fail;
        }
        if (ranges[k].end > ranges[widest].end)
            widest = k;
    }
fail:
    allocator->free(allocator->user, ranges);
    return r;
}

/* ---- tags (rules 13, 14) ----------------------------------------------------------------------- */

/* The elem_count a known tag must have, or UINT64_MAX when the header does not fix it. */
static uint64_t expected_count(const tpk_header *h, uint32_t tag, const char **what)
{
    switch (tag) {
    case TPK_TAG_POS3:
    case TPK_TAG_VMAP:
        *what = "vertex_count";
        return h->vertex_count;
    case TPK_TAG_TT16:
    case TPK_TAG_TT20:
    case TPK_TAG_TT32:
    case TPK_TAG_TMAP:
        *what = "tet_count";
        return h->tet_count;
    case TPK_TAG_SHEL:
        *what = "shell_face_count";
        return h->shell_face_count;
    default:
        return UINT64_MAX;
    }
}

/* Rules 13 and 14 for one entry; *known is set when the tag is a TPK_TAG_*. */
static tpk_result check_entry_tag(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, int *known,
                                  int allow_unknown_required, tpki_diag *diag)
{
    char name[80], tag[16];
    tpki_entry_name(i, e, name);
    tpki_tag_name(e->tag, tag);
    uint32_t elem_type;
    *known = tpki_known_tag(e->tag, &elem_type, NULL);
    if (!*known && (e->flags & TPK_CHUNK_REQUIRED) && !allow_unknown_required)
        return tpki_fail(diag, TPK_ERR_UNSUPPORTED_CHUNK,
                             "%s: unknown chunk tag %s is marked required; this reader cannot use the file",
                             name, tag);
    if (!*known)
        return TPK_OK;
    if (e->elem_type != elem_type)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: elem_type %u, but tag %s needs elem_type %" PRIu32,
                             name, e->elem_type, tag, elem_type);
    if (e->tag != TPK_TAG_FDAT && e->tag != TPK_TAG_LEVL && (e->index != 0 || e->step != 0))
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: index %" PRIu32 " and step %" PRIu32 " must be 0",
                             name, e->index, e->step);
    const char *what = NULL;
    uint64_t count = expected_count(h, e->tag, &what);
    if (count != UINT64_MAX && e->elem_count != count)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: elem_count %" PRIu64 " but header %s is %" PRIu64,
                             name, e->elem_count, what, count);
    if (e->tag == TPK_TAG_FDSC && e->elem_count > TPK_MAX_FIELDS)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %" PRIu64 " field descriptors, at most %u allowed",
                             name, e->elem_count, TPK_MAX_FIELDS);
    /* Format 1.2: PART and LINK hold whole records (spec §15). */
    if (e->tag == TPK_TAG_PART && e->elem_count % sizeof(tpk_part_record) != 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %" PRIu64 " bytes, not a whole number of %zu-byte part records",
                         name, e->elem_count, sizeof(tpk_part_record));
    if (e->tag == TPK_TAG_LINK && e->elem_count % 4 != 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %" PRIu64 " values, not a whole number of 4-value links", name,
                         e->elem_count);
    /* Format 1.3: a level is a whole file, stored as it is, so a reader opens it over the mapping. */
    if (e->tag == TPK_TAG_LEVL && (e->codec != TPK_CODEC_NONE || e->index == 0 || e->step != 0))
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: a level is stored uncompressed, with index 1 or more and step 0 "
                         "(codec %u, index %u, step %u)", name, (unsigned)e->codec, e->index, e->step);
    if (e->tag == TPK_TAG_FDSC && e->elem_count == 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: no field descriptors; a file without fields has no 'FDSC' "
                             "chunk (format 1.1)", name);
    return TPK_OK;
}

typedef struct chunk_key {
    uint32_t tag, index, step;
    uint64_t chunk;
} chunk_key;

static int compare_keys(const void *pa, const void *pb)
{
    const chunk_key *a = pa, *b = pb;
    if (a->tag != b->tag)
        return a->tag < b->tag ? -1 : 1;
    if (a->index != b->index)
        return a->index < b->index ? -1 : 1;
    if (a->step != b->step)
        return a->step < b->step ? -1 : 1;
    return a->chunk < b->chunk ? -1 : a->chunk > b->chunk;
}

static tpk_result check_duplicates(chunk_key *keys, size_t n, tpki_diag *diag)
{
    qsort(keys, n, sizeof *keys, compare_keys);
    for (size_t k = 1; k < n; k++) {
        if (keys[k].tag == keys[k - 1].tag && keys[k].index == keys[k - 1].index &&
            keys[k].step == keys[k - 1].step) {
            char tag[16];
            tpki_tag_name(keys[k].tag, tag);
            return tpki_fail(diag, TPK_ERR_CORRUPT,
                                 "chunks %" PRIu64 " and %" PRIu64 " both have tag %s index %" PRIu32
                                 " step %" PRIu32, keys[k - 1].chunk, keys[k].chunk, tag, keys[k].index,
                                 keys[k].step);
        }
    }
    return TPK_OK;
}

static tpk_result check_required_present(const tpk_header *h, const tpk_dir_entry *entries, tpki_diag *diag)
{
    int pos3 = 0, shel = 0, tets = 0;
    for (uint64_t i = 0; i < h->chunk_count; i++) {
        pos3 |= entries[i].tag == TPK_TAG_POS3;
        shel |= entries[i].tag == TPK_TAG_SHEL;
        tets |= entries[i].tag == TPK_TAG_TT16 || entries[i].tag == TPK_TAG_TT20 ||
                entries[i].tag == TPK_TAG_TT32;
    }
    if (!pos3)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "no 'POS3' (positions) chunk");
    if (!shel)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "no 'SHEL' (shell faces) chunk");
    if (!tets)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "no tet layout chunk ('TT16', 'TT20' or 'TT32')");
    return TPK_OK;
}

tpk_result tpki_check_tags(const tpk_header *h, const tpk_dir_entry *entries, int allow_unknown_required,
                          const tpk_allocator *allocator, tpki_diag *diag)
{
    tpk_result r = TPK_OK;
    chunk_key *keys = allocator->alloc(allocator->user, (h->chunk_count + 1) * sizeof *keys);
    if (!keys)
        return tpki_fail(diag, TPK_ERR_OUT_OF_MEMORY, "out of memory checking %" PRIu64 " chunk tags",
                             h->chunk_count);
    size_t n = 0;
    for (uint64_t i = 0; i < h->chunk_count; i++) {
        int known = 0;
        r = check_entry_tag(h, i, &entries[i], &known, allow_unknown_required, diag);
        if (r != TPK_OK)
            goto fail;
        if (known)
            keys[n++] = (chunk_key){entries[i].tag, entries[i].index, entries[i].step, i};
    }
    r = check_duplicates(keys, n, diag);
    if (r == TPK_OK)
        r = check_required_present(h, entries, diag);
fail:
    allocator->free(allocator->user, keys);
    return r;
}

/* ---- fields (rule 15) -------------------------------------------------------------------------- */

static tpk_result check_field_desc(uint32_t i, const tpk_field_desc *f, tpki_diag *diag)
{
    if (!memchr(f->name, 0, sizeof f->name))
        return tpki_fail(diag, TPK_ERR_CORRUPT, "field %" PRIu32 ": name is not NUL-terminated within 64 bytes", i);
    if (f->name[0] == 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "field %" PRIu32 ": name is empty", i);
    if (!memchr(f->units, 0, sizeof f->units))
        return tpki_fail(diag, TPK_ERR_CORRUPT,
                             "field %" PRIu32 " '%s': units are not NUL-terminated within 32 bytes", i, f->name);
    if (f->association > TPK_ASSOC_TET)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "field %" PRIu32 " '%s': association %" PRIu32
                             ", must be 0 (point) or 1 (tet)", i, f->name, f->association);
    if (f->components != 1)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "field %" PRIu32 " '%s': components %" PRIu32
                             ", must be 1 in format 1.x", i, f->name, f->components);
    if (f->step_count < 1)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "field %" PRIu32 " '%s': step_count is 0", i, f->name);
    if (f->reserved0 != 0 || f->reserved1 != 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "field %" PRIu32 " '%s': reserved fields must be 0", i,
                             f->name);
    return TPK_OK;
}

static int compare_names(const void *pa, const void *pb)
{
    const tpk_field_desc *a = *(const tpk_field_desc *const *)pa, *b = *(const tpk_field_desc *const *)pb;
    int c = strcmp(a->name, b->name);
    return c != 0 ? c : (a < b ? -1 : a > b);
}

static tpk_result check_unique_names(const tpk_field_desc *fields, uint32_t count,
                                     const tpk_allocator *allocator, tpki_diag *diag)
{
    tpk_result r = TPK_OK;
    const tpk_field_desc **sorted = allocator->alloc(allocator->user, ((size_t)count + 1) * sizeof *sorted);
    if (!sorted)
        return tpki_fail(diag, TPK_ERR_OUT_OF_MEMORY, "out of memory checking %" PRIu32 " field names", count);
    for (uint32_t i = 0; i < count; i++)
        sorted[i] = &fields[i];
    qsort(sorted, count, sizeof *sorted, compare_names);
    for (uint32_t k = 1; k < count; k++) {
        if (strcmp(sorted[k]->name, sorted[k - 1]->name) == 0) {
            r = tpki_fail(diag, TPK_ERR_CORRUPT, "fields %td and %td are both named '%s'",
                              sorted[k - 1] - fields, sorted[k] - fields, sorted[k]->name);
            break;
        }
    }
    allocator->free(allocator->user, sorted);
    return r;
}

static tpk_result check_fdat(const tpk_header *h, uint64_t i, const tpk_dir_entry *e,
                             const tpk_field_desc *fields, uint32_t field_count, tpki_diag *diag)
{
    char name[80];
    tpki_entry_name(i, e, name);
    if (field_count == 0)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: field data without a 'FDSC' chunk", name);
    if (e->index >= field_count)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: field index %" PRIu32 " but the file has %" PRIu32
                             " fields", name, e->index, field_count);
    const tpk_field_desc *f = &fields[e->index];
    if (e->step >= f->step_count)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: step %" PRIu32 " but field '%s' has %" PRIu32 " steps",
                             name, e->step, f->name, f->step_count);
    uint64_t count = f->association == TPK_ASSOC_POINT ? h->vertex_count : h->tet_count;
    if (e->elem_count != count)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: elem_count %" PRIu64 " but %s field '%s' needs %" PRIu64,
                             name, e->elem_count, f->association == TPK_ASSOC_POINT ? "point" : "tet", f->name,
                             count);
    return TPK_OK;
}

/* Called when the number of FDAT chunks falls short: name the first field missing some. Duplicates
 * and out-of-range FDATs were rejected already, so some field has fewer chunks than steps. */
static tpk_result report_missing_fdat(const tpk_header *h, const tpk_dir_entry *entries,
                                      const tpk_field_desc *fields, uint32_t field_count, tpki_diag *diag)
{
    for (uint32_t f = 0; f < field_count; f++) {
        uint64_t have = 0;
        for (uint64_t i = 0; i < h->chunk_count; i++)
            have += entries[i].tag == TPK_TAG_FDAT && entries[i].index == f;
        if (have != fields[f].step_count)
            return tpki_fail(diag, TPK_ERR_CORRUPT,
                                 "field %" PRIu32 " '%s' has %" PRIu32 " steps but %" PRIu64 " 'FDAT' chunks", f,
                                 fields[f].name, fields[f].step_count, have);
    }
    return tpki_fail(diag, TPK_ERR_CORRUPT, "'FDAT' chunks do not match the field descriptors");
}

static tpk_result check_fdat_chunks(const tpk_header *h, const tpk_dir_entry *entries,
                                    const tpk_field_desc *fields, uint32_t field_count, tpki_diag *diag)
{
    uint64_t needed = 0, found = 0;
    for (uint32_t f = 0; f < field_count; f++)
        needed += fields[f].step_count;
    for (uint64_t i = 0; i < h->chunk_count; i++) {
        if (entries[i].tag != TPK_TAG_FDAT)
            continue;
        tpk_result r = check_fdat(h, i, &entries[i], fields, field_count, diag);
        if (r != TPK_OK)
            return r;
        found++;
    }
    return found == needed ? TPK_OK : report_missing_fdat(h, entries, fields, field_count, diag);
}

static tpk_result check_time_chunk(const tpk_header *h, const tpk_dir_entry *entries,
                                   const tpk_field_desc *fields, uint32_t field_count, tpki_diag *diag)
{
    uint64_t steps = field_count == 0 ? 1 : 0; /* a file without fields has one state */
    for (uint32_t f = 0; f < field_count; f++)
        steps = fields[f].step_count > steps ? fields[f].step_count : steps;
    for (uint64_t i = 0; i < h->chunk_count; i++) {
        if (entries[i].tag == TPK_TAG_TIME && entries[i].elem_count != steps) {
            char name[80];
            tpki_entry_name(i, &entries[i], name);
            return tpki_fail(diag, TPK_ERR_CORRUPT,
                                 "%s: %" PRIu64 " time values but the fields have %" PRIu64 " steps", name,
                                 entries[i].elem_count, steps);
        }
    }
    return TPK_OK;
}

tpk_result tpki_check_fields(const tpk_header *h, const tpk_dir_entry *entries, const tpk_field_desc *fields,
                            uint32_t field_count, const tpk_allocator *allocator, tpki_diag *diag)
{
    for (uint32_t i = 0; i < field_count; i++) {
        tpk_result r = check_field_desc(i, &fields[i], diag);
        if (r != TPK_OK)
            return r;
    }
    tpk_result r = check_unique_names(fields, field_count, allocator, diag);
    if (r == TPK_OK)
        r = check_fdat_chunks(h, entries, fields, field_count, diag);
    if (r == TPK_OK)
        r = check_time_chunk(h, entries, fields, field_count, diag);
    return r;
}

/* ---- chunk contents (rule 17) ------------------------------------------------------------------ */

static tpk_result id_error(tpki_diag *diag, uint64_t i, const tpk_dir_entry *e, uint64_t record,
                           const char *what, int32_t value, int64_t lo, uint64_t hi)
{
    char name[80];
    tpki_entry_name(i, e, name);
    return tpki_fail(diag, TPK_ERR_CORRUPT,
                         "%s: record %" PRIu64 " (raw byte %" PRIu64 "): %s = %" PRId32
                         " is outside [%" PRId64 ", %" PRIu64 ")",
                         name, record, record * e->elem_size, what, value, lo, hi);
}

static int in_range(int32_t value, int64_t lo, uint64_t hi)
{
    return value >= lo && (value < 0 || (uint64_t)value < hi);
}

static tpk_result check_tet32(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const uint8_t *raw,
                              tpki_diag *diag)
{
    static const char *const vname[4] = {"v[0]", "v[1]", "v[2]", "4th vertex (vx^v0^v1^v2)"};
    static const char *const nname[4] = {"n[0]", "n[1]", "n[2]", "n[3]"};
    for (uint64_t t = 0; t < e->elem_count; t++) {
        tpk_tet32 tet;
        memcpy(&tet, raw + t * sizeof tet, sizeof tet);
        int32_t v[4] = {tet.v[0], tet.v[1], tet.v[2], tet.vx ^ tet.v[0] ^ tet.v[1] ^ tet.v[2]};
        for (int k = 0; k < 4; k++) {
            if (!in_range(v[k], 0, h->vertex_count))
                return id_error(diag, i, e, t, vname[k], v[k], 0, h->vertex_count);
            if (!in_range(tet.n[k], -1, h->tet_count))
                return id_error(diag, i, e, t, nname[k], tet.n[k], -1, h->tet_count);
        }
    }
    return TPK_OK;
}

/* The bound on vx in a layout that stores no vertex ids (format 1.1): the xor of ids in [0, V) is below
 * the smallest power of two >= V, and no id exists when V = 0. The ids derived from vx still need
 * their own check against [0, V) where a reader derives them (spec §6.6). */
static uint64_t vx_limit(uint64_t vertex_count)
{
    uint64_t limit = vertex_count ? 1 : 0;
    while (limit < vertex_count)
        limit <<= 1;
    return limit;
}

/* limit: vx_limit(vertex_count), computed once per chunk (its loop per record cost 12 ns a tet). */
static tpk_result check_vx(uint64_t limit, uint64_t i, const tpk_dir_entry *e, uint64_t t, int32_t vx,
                           tpki_diag *diag)
{
    return in_range(vx, 0, limit) ? TPK_OK : id_error(diag, i, e, t, "vx", vx, 0, limit);
}

static tpk_result check_tet16(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const uint8_t *raw,
                              tpki_diag *diag)
{
    const uint64_t limit = vx_limit(h->vertex_count);
    for (uint64_t t = 0; t < e->elem_count; t++) {
        tpk_tet16 tet;
        memcpy(&tet, raw + t * sizeof tet, sizeof tet);
        tpk_result r = check_vx(limit, i, e, t, tet.vx, diag);
        if (r != TPK_OK)
            return r;
    }
    return TPK_OK;
}

static tpk_result check_tet20(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const uint8_t *raw,
                              tpki_diag *diag)
{
    static const char *const nname[4] = {"n[0]", "n[1]", "n[2]", "n[3]"};
    const uint64_t limit = vx_limit(h->vertex_count);
    for (uint64_t t = 0; t < e->elem_count; t++) {
        tpk_tet20 tet;
        memcpy(&tet, raw + t * sizeof tet, sizeof tet);
        tpk_result r = check_vx(limit, i, e, t, tet.vx, diag);
        if (r != TPK_OK)
            return r;
        for (int k = 0; k < 4; k++) {
            if (!in_range(tet.n[k], -1, h->tet_count))
                return id_error(diag, i, e, t, nname[k], tet.n[k], -1, h->tet_count);
        }
    }
    return TPK_OK;
}

static tpk_result check_shell(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const uint8_t *raw,
                              tpki_diag *diag)
{
    for (uint64_t s = 0; s < e->elem_count; s++) {
        tpk_shell_face face;
        memcpy(&face, raw + s * sizeof face, sizeof face);
        if (!in_range(face.a, 0, h->vertex_count))
            return id_error(diag, i, e, s, "a", face.a, 0, h->vertex_count);
        if (!in_range(face.b, 0, h->vertex_count))
            return id_error(diag, i, e, s, "b", face.b, 0, h->vertex_count);
        if (!in_range(face.c, 0, h->vertex_count))
            return id_error(diag, i, e, s, "c", face.c, 0, h->vertex_count);
        if (!in_range(face.t, 0, h->tet_count))
            return id_error(diag, i, e, s, "t", face.t, 0, h->tet_count);
    }
    return TPK_OK;
}

static tpk_result check_tmap(uint64_t i, const tpk_dir_entry *e, const uint8_t *raw, tpki_diag *diag)
{
    for (uint64_t t = 0; t < e->elem_count; t++) {
        int32_t cell;
        memcpy(&cell, raw + t * sizeof cell, sizeof cell);
        if (cell < 0)
            return id_error(diag, i, e, t, "source cell", cell, 0, (uint64_t)INT32_MAX + 1);
    }
    return TPK_OK;
}

/* Rule 17 for LINK (1.2): the face in [0, S), ids on the other side non-negative (their upper bounds
 * are the other part's, checked when a set is opened), faces strictly ascending so each appears once. */
static tpk_result check_links(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const uint8_t *raw,
                              tpki_diag *diag)
{
    int64_t previous = -1;
    for (uint64_t l = 0; l < e->elem_count / 4; l++) {
        tpk_link link;
        memcpy(&link, raw + l * sizeof link, sizeof link);
        if (!in_range(link.face, 0, h->shell_face_count))
            return id_error(diag, i, e, l, "face", link.face, 0, h->shell_face_count);
        if (link.face <= previous)
            return tpki_fail(diag, TPK_ERR_CORRUPT, "chunk %" PRIu64 " 'LINK': link %" PRIu64 " names shell face %d "
                             "after face %lld: links are sorted by face, one per face", i, l, link.face,
                             (long long)previous);
        previous = link.face;
        if (link.part < 0 || link.other_face < 0 || link.other_tet < 0)
            return tpki_fail(diag, TPK_ERR_CORRUPT, "chunk %" PRIu64 " 'LINK': link %" PRIu64 " has a negative id "
                             "(part %d, other face %d, other tet %d)", i, l, link.part, link.other_face,
                             link.other_tet);
    }
    return TPK_OK;
}

/* Format 1.4 (spec §17): the words of CULL, read one at a time (the chunk need not be 4-byte aligned in
 * a caller's buffer). */
static int32_t cull_word(const uint8_t *raw, uint64_t w)
{
    int32_t v;
    memcpy(&v, raw + 4 * w, sizeof v);
    return v;
}

/* A run of K + 1 starts: 0 first, strictly increasing, `total` last. */
static tpk_result check_cull_starts(tpki_diag *diag, const char *name, const char *what, const uint8_t *raw,
                                    uint64_t at, uint64_t K, uint64_t total)
{
    int64_t previous = -1;
    for (uint64_t k = 0; k <= K; k++) {
        int64_t s = cull_word(raw, at + k);
        int ok = k == 0 ? s == 0 : s > previous;
        if (ok && k == K)
            ok = (uint64_t)s == total;
        if (!ok)
            return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %s[%" PRIu64 "] (word %" PRIu64 ") is %" PRId64 ", but the "
                             "starts run from 0 up to %" PRIu64 ", each block holding at least one", name, what, k,
                             at + k, s, total);
        previous = s;
    }
    return TPK_OK;
}

static tpk_result check_cull(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const uint8_t *raw,
                             tpki_diag *diag)
{
    char name[80];
    tpki_entry_name(i, e, name);
    uint64_t n = e->elem_count, T = h->tet_count, V = h->vertex_count;
    if (n < TPK_CULL_HEADER_WORDS)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %" PRIu64 " words, fewer than its %d header words", name, n,
                         TPK_CULL_HEADER_WORDS);
    int64_t B = cull_word(raw, 0), K = cull_word(raw, 1), S = cull_word(raw, 2), I = cull_word(raw, 3);
    if (B < TPK_CULL_MIN_BLOCK || B > TPK_CULL_MAX_BLOCK)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: block_tets %" PRId64 " is outside [%d, %d]", name, B,
                         TPK_CULL_MIN_BLOCK, TPK_CULL_MAX_BLOCK);
    if ((uint64_t)K != (T + (uint64_t)B - 1) / (uint64_t)B)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: block_count %" PRId64 ", but %" PRIu64 " tets in blocks of %"
                         PRId64 " make %" PRIu64, name, K, T, B, (T + (uint64_t)B - 1) / (uint64_t)B);
    if (S < K || I < K)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %" PRId64 " seeds and %" PRId64 " intervals for %" PRId64
                         " blocks (each block needs at least one of each)", name, S, I, K);
    uint64_t want = TPK_CULL_HEADER_WORDS + 2 * ((uint64_t)K + 1) + TPK_CULL_SEED_WORDS * (uint64_t)S + 2 * (uint64_t)I;
    if (n != want)
        return tpki_fail(diag, TPK_ERR_CORRUPT, "%s: %" PRIu64 " words, but its counts (%" PRId64 " blocks, %" PRId64
                         " seeds, %" PRId64 " intervals) make %" PRIu64, name, n, K, S, I, want);
    uint64_t seed_starts = TPK_CULL_HEADER_WORDS, interval_starts = seed_starts + (uint64_t)K + 1;
    uint64_t seeds = interval_starts + (uint64_t)K + 1, intervals = seeds + TPK_CULL_SEED_WORDS * (uint64_t)S;
    tpk_result r = check_cull_starts(diag, name, "seed_start", raw, seed_starts, (uint64_t)K, (uint64_t)S);
    if (r == TPK_OK)
        r = check_cull_starts(diag, name, "interval_start", raw, interval_starts, (uint64_t)K, (uint64_t)I);
    for (int64_t k = 0; r == TPK_OK && k < K; k++) {
        int64_t t0 = k * B, t1 = (k + 1) * B < (int64_t)T ? (k + 1) * B : (int64_t)T, previous = -1;
        for (int64_t s = cull_word(raw, seed_starts + (uint64_t)k); r == TPK_OK && s < cull_word(raw, seed_starts + (uint64_t)k + 1); s++) {
            const uint64_t at = seeds + TPK_CULL_SEED_WORDS * (uint64_t)s;
            int32_t w[TPK_CULL_SEED_WORDS];
            for (int j = 0; j < TPK_CULL_SEED_WORDS; j++)
                w[j] = cull_word(raw, at + (uint64_t)j);
            if (w[0] < t0 || w[0] >= t1 || w[0] <= previous)
                r = tpki_fail(diag, TPK_ERR_CORRUPT, "%s: seed %" PRId64 " (word %" PRIu64 ") names tet %" PRId32
                              ", but block %" PRId64 " holds tets [%" PRId64 ", %" PRId64 ") and its seeds ascend",
                              name, s, at, w[0], k, t0, t1);
            for (int j = 1; r == TPK_OK && j <= 4; j++)
                if (!in_range(w[j], 0, V))
                    r = id_error(diag, i, e, at + (uint64_t)j, "seed vertex", w[j], 0, V);
            if (r == TPK_OK && (w[1] == w[2] || w[1] == w[3] || w[1] == w[4] || w[2] == w[3] || w[2] == w[4] ||
                                w[3] == w[4]))
                r = tpki_fail(diag, TPK_ERR_CORRUPT, "%s: seed %" PRId64 " (word %" PRIu64 ") repeats a vertex (%"
                              PRId32 ", %" PRId32 ", %" PRId32 ", %" PRId32 ")", name, s, at, w[1], w[2], w[3], w[4]);
            if (r == TPK_OK && !in_range(w[5], -1, T))
                r = id_error(diag, i, e, at + 5, "seed n3", w[5], -1, T);
            previous = w[0];
        }
        previous = -1;
        for (int64_t v = cull_word(raw, interval_starts + (uint64_t)k); r == TPK_OK && v < cull_word(raw, interval_starts + (uint64_t)k + 1); v++) {
            const uint64_t at = intervals + 2 * (uint64_t)v;
            int64_t first = cull_word(raw, at), end = cull_word(raw, at + 1);
            if (first < 0 || first >= end || (uint64_t)end > V || first <= previous)
                r = tpki_fail(diag, TPK_ERR_CORRUPT, "%s: interval %" PRId64 " (word %" PRIu64 ") of block %" PRId64
                              " is [%" PRId64 ", %" PRId64 "); intervals are non-empty, within [0, %" PRIu64 "), "
                              "ascending and apart", name, v, at, k, first, end, V);
            previous = end;
        }
    }
    return r;
}

tpk_result tpki_check_records(const tpk_header *h, uint64_t i, const tpk_dir_entry *e, const void *raw,
                             tpki_diag *diag)
{
    switch (e->tag) {
    case TPK_TAG_TT32: return check_tet32(h, i, e, raw, diag);
    case TPK_TAG_TT20: return check_tet20(h, i, e, raw, diag);
    case TPK_TAG_TT16: return check_tet16(h, i, e, raw, diag);
    case TPK_TAG_SHEL: return check_shell(h, i, e, raw, diag);
    case TPK_TAG_TMAP: return check_tmap(i, e, raw, diag);
    case TPK_TAG_LINK: return check_links(h, i, e, raw, diag);
    case TPK_TAG_CULL: return check_cull(h, i, e, raw, diag);
    default: return TPK_OK;
    }
}

/* ---- whole layouts and files ------------------------------------------------------------------- */

tpk_result tpki_check_layout(const tpk_header *h, const tpk_dir_entry *entries, const tpk_field_desc *fields,
                            uint32_t field_count, const tpk_allocator *allocator, tpki_diag *diag)
{
    /* A writer's own output is not untrusted input: no limits. */
    const tpk_limits limits = {UINT64_MAX, UINT64_MAX, UINT64_MAX};
    tpk_result r = tpki_check_header_fields(h, diag);
    if (r == TPK_OK)
        r = tpki_check_header_counts(h, &limits, diag);
    uint64_t total = 0;
    for (uint64_t i = 0; r == TPK_OK && i < h->chunk_count; i++)
        r = tpki_check_entry(h, &limits, i, &entries[i], &total, diag);
    if (r == TPK_OK)
        r = tpki_check_overlaps(h, entries, allocator, diag);
    if (r == TPK_OK)
        r = tpki_check_tags(h, entries, 1, allocator, diag); /* a vendor may require its chunk */
    if (r == TPK_OK)
        r = tpki_check_fields(h, entries, fields, field_count, allocator, diag);
    return r;
}
