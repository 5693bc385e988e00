/* Container tests: writer/reader round trips, alignment, the must-fail cases of every reader rule (each
 * with its exact result code), the writer's atomicity, and allocation-failure injection.
 * With TPK_WRITE_CORPUS=<dir>, the write_fuzz_corpus test writes the fuzz seeds and must-fail files. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "harness.h"
#include "tetpack.h"

/* ---- a small sample mesh: 2 tets sharing face (0,1,2) -------------------------------------------- */

#define SAMPLE_V 5
#define SAMPLE_T 2
#define SAMPLE_S 6
#define BIG_BYTES 70000

typedef struct sample {
    float positions[SAMPLE_V][3];
    tpk_tet32 tet32[SAMPLE_T];
    tpk_tet20 tet20[SAMPLE_T];
    tpk_tet16 tet16[SAMPLE_T];
    tpk_shell_face shell[SAMPLE_S];
    tpk_field_desc fields[2];
    float temperature[2][SAMPLE_V];
    float pressure[2][SAMPLE_T];
    double time[2];
    int32_t tmap[SAMPLE_T];
    char meta[40];
    uint8_t big[BIG_BYTES];
} sample;

typedef struct chunk_src {
    tpk_chunk_desc desc;
    const void *data;
} chunk_src;

typedef struct build_opts {
    int big;               /* add a 70000-byte uncompressed optional chunk (4096 alignment) */
    uint32_t extra_tag;    /* add a 16-byte unknown chunk with this tag (0: none) */
    uint16_t extra_flags;
    int bad_tet32;         /* put an out-of-range vertex id into TT32 */
    int bad_shell;         /* put an out-of-range vertex id into SHEL */
} build_opts;

static sample the_sample;

static void make_sample(sample *s)
{
    memset(s, 0, sizeof *s);
    const float p[SAMPLE_V][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}};
    memcpy(s->positions, p, sizeof p);
    s->tet32[0] = (tpk_tet32){{0, 1, 2}, 0 ^ 1 ^ 2 ^ 3, {-1, -1, -1, 1}};
    s->tet32[1] = (tpk_tet32){{0, 2, 1}, 0 ^ 2 ^ 1 ^ 4, {-1, -1, -1, 0}};
    s->tet20[0] = (tpk_tet20){0 ^ 1 ^ 2 ^ 3, {-1, -1, -1, 1}};
    s->tet20[1] = (tpk_tet20){0 ^ 1 ^ 2 ^ 4, {-1, -1, -1, 0}};
    s->tet16[0] = (tpk_tet16){0 ^ 1 ^ 2 ^ 3, {-1 ^ 1, -1 ^ 1, -1 ^ 1}};
    s->tet16[1] = (tpk_tet16){0 ^ 1 ^ 2 ^ 4, {-1 ^ 0, -1 ^ 0, -1 ^ 0}};
    const tpk_shell_face shell[SAMPLE_S] = {{0, 2, 1, 0}, {0, 1, 3, 0}, {0, 3, 2, 0}, {1, 2, 3, 0},
                                            {0, 1, 4, 1}, {1, 2, 4, 1}};
    memcpy(s->shell, shell, sizeof shell);
    s->fields[0] = (tpk_field_desc){.association = TPK_ASSOC_POINT, .step_count = 2, .components = 1,
                                    .min_value = 0, .max_value = 8.5f};
    snprintf(s->fields[0].name, sizeof s->fields[0].name, "temperature");
    snprintf(s->fields[0].units, sizeof s->fields[0].units, "K");
    snprintf(s->fields[1].name, sizeof s->fields[1].name, "pressure");
    s->fields[1].association = TPK_ASSOC_TET;
    s->fields[1].step_count = 2;
    s->fields[1].components = 1;
    for (int v = 0; v < SAMPLE_V; v++) {
        s->temperature[0][v] = (float)v;
        s->temperature[1][v] = (float)v + 4.5f;
    }
    s->pressure[0][0] = 1.0f, s->pressure[0][1] = 2.0f, s->pressure[1][0] = 3.0f, s->pressure[1][1] = 4.0f;
    s->time[0] = 0.25, s->time[1] = 0.5;
    s->tmap[0] = 7, s->tmap[1] = 8;
    snprintf(s->meta, sizeof s->meta, "{\"converter\":\"test\"}");
    for (size_t k = 0; k < BIG_BYTES; k++)
        s->big[k] = (uint8_t)(k * 31u);
}

static chunk_src chunk(uint32_t tag, uint8_t codec, uint8_t type, uint32_t size, uint64_t count, const void *data)
{
    int required = tag == TPK_TAG_POS3 || tag == TPK_TAG_TT32 || tag == TPK_TAG_TT20 || tag == TPK_TAG_TT16 ||
                   tag == TPK_TAG_SHEL || tag == TPK_TAG_FDSC || tag == TPK_TAG_FDAT;
    chunk_src c = {{.tag = tag, .flags = required ? TPK_CHUNK_REQUIRED : 0, .codec = codec, .elem_type = type,
                    .elem_size = size, .elem_count = count, .zstd_level = 3},
                   data};
    return c;
}

/* The chunk list of the sample, in file order; returns the count. */
static int sample_chunks(const sample *s, const build_opts *o, chunk_src *out)
{
    int n = 0;
    out[n++] = chunk(TPK_TAG_POS3, TPK_CODEC_NONE, TPK_ELEM_VEC3_F32, 12, SAMPLE_V, s->positions);
    out[n++] = chunk(TPK_TAG_TT32, TPK_CODEC_NONE, TPK_ELEM_TET32, 32, SAMPLE_T, s->tet32);
    out[n++] = chunk(TPK_TAG_TT20, TPK_CODEC_ZSTD, TPK_ELEM_TET20, 20, SAMPLE_T, s->tet20);
    out[n++] = chunk(TPK_TAG_TT16, TPK_CODEC_NONE, TPK_ELEM_TET16, 16, SAMPLE_T, s->tet16);
    out[n++] = chunk(TPK_TAG_SHEL, TPK_CODEC_ZSTD, TPK_ELEM_SHELL_FACE, 16, SAMPLE_S, s->shell);
    out[n++] = chunk(TPK_TAG_FDSC, TPK_CODEC_NONE, TPK_ELEM_FIELD_DESC, 128, 2, s->fields);
    for (uint32_t step = 0; step < 2; step++) {
        chunk_src t = chunk(TPK_TAG_FDAT, step ? TPK_CODEC_ZSTD : TPK_CODEC_NONE, TPK_ELEM_F32, 4, SAMPLE_V,
                            s->temperature[step]);
        t.desc.step = step;
        out[n++] = t;
        chunk_src p = chunk(TPK_TAG_FDAT, step ? TPK_CODEC_NONE : TPK_CODEC_ZSTD, TPK_ELEM_F32, 4, SAMPLE_T,
                            s->pressure[step]);
        p.desc.index = 1;
        p.desc.step = step;
        out[n++] = p;
    }
    out[n++] = chunk(TPK_TAG_TIME, TPK_CODEC_ZSTD, TPK_ELEM_F64, 8, 2, s->time);
    out[n++] = chunk(TPK_TAG_TMAP, TPK_CODEC_NONE, TPK_ELEM_I32, 4, SAMPLE_T, s->tmap);
    out[n++] = chunk(TPK_TAG_META, TPK_CODEC_ZSTD, TPK_ELEM_BYTE, 1, strlen(s->meta), s->meta);
    if (o && o->big)
        out[n++] = chunk(TPK_FOURCC('x', 'b', 'i', 'g'), TPK_CODEC_NONE, TPK_ELEM_BYTE, 1, BIG_BYTES, s->big);
    if (o && o->extra_tag) {
        out[n] = chunk(o->extra_tag, TPK_CODEC_NONE, TPK_ELEM_BYTE, 1, 16, s->big);
        out[n++].desc.flags = o->extra_flags;
    }
    return n;
}

static tpk_header_fields sample_header(void)
{
    tpk_header_fields h = {.vertex_count = SAMPLE_V, .tet_count = SAMPLE_T, .shell_face_count = SAMPLE_S,
                           .origin = {100.0, 200.0, 300.0}, .bounds_min = {100, 200, 299},
                           .bounds_max = {101, 201, 301}};
    return h;
}

static tpk_result build_file(const char *path, const build_opts *o)
{
    static sample s;
    make_sample(&s);
    if (o && o->bad_tet32)
        s.tet32[1].v[2] = SAMPLE_V; /* also changes the derived 4th vertex: fine, v[2] is reported first */
    if (o && o->bad_shell)
        s.shell[3].b = -2;
    chunk_src chunks[32];
    int n = sample_chunks(&s, o, chunks);
    tpk_writer *w;
    char err[256];
    tpk_result r = tpk_writer_open(&w, path, NULL, err, sizeof err);
    for (int k = 0; r == TPK_OK && k < n; k++) {
        r = tpk_writer_add_chunk(w, &chunks[k].desc, chunks[k].data);
        if (r != TPK_OK)
            tpk_writer_abort(w);
    }
    tpk_header_fields h = sample_header();
    return r == TPK_OK ? tpk_writer_finish(w, &h) : r;
}

static uint8_t *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *data = malloc((size_t)n + 1);
    if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
        free(data);
        data = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return data;
}

/* A good small file in memory (malloc'ed; free it). */
static uint8_t *good_bytes(size_t *size, const build_opts *o)
{
    const char *path = tpk_temp_path("good.tpk");
    if (build_file(path, o) != TPK_OK)
        return NULL;
    return read_all(path, size);
}

/* ---- in-memory mutation helpers -------------------------------------------------------------------- */

static tpk_header *hdr(uint8_t *bytes)
{
    return (tpk_header *)bytes; /* malloc'ed buffer: aligned */
}

static tpk_dir_entry *entry(uint8_t *bytes, uint64_t i)
{
    return (tpk_dir_entry *)(bytes + hdr(bytes)->directory_offset) + i;
}

static uint64_t entry_of(uint8_t *bytes, uint32_t tag, uint32_t index, uint32_t step)
{
    for (uint64_t i = 0; i < hdr(bytes)->chunk_count; i++) {
        if (entry(bytes, i)->tag == tag && entry(bytes, i)->index == index && entry(bytes, i)->step == step)
            return i;
    }
    return UINT64_MAX;
}

static void fix_header(uint8_t *bytes)
{
    hdr(bytes)->header_checksum = XXH64(bytes, offsetof(tpk_header, header_checksum), 0);
}

static void fix_directory(uint8_t *bytes)
{
    tpk_header *h = hdr(bytes);
    h->directory_checksum = XXH64(bytes + h->directory_offset, h->chunk_count * TPK_DIR_ENTRY_SIZE, 0);
    fix_header(bytes);
}

/* Turn chunk i into an unknown optional chunk (the reader then ignores it). */
static void hide_chunk(uint8_t *bytes, uint64_t i, uint32_t tag)
{
    entry(bytes, i)->tag = tag;
    entry(bytes, i)->flags = 0;
}

static void fix_chunk(uint8_t *bytes, uint64_t i)
{
    tpk_dir_entry *e = entry(bytes, i);
    e->checksum = XXH64(bytes + e->offset, e->raw_size, 0);
    fix_directory(bytes);
}

/* ---- must-fail cases -------------------------------------------------------------------------------- */

typedef struct fail_case {
    const char *name;
    size_t (*mutate)(uint8_t *bytes, size_t size); /* returns the new size */
    tpk_result open_result;   /* expected from tpk_open_memory */
    tpk_result verify_result; /* expected from tpk_verify when the open succeeds */
} fail_case;

static size_t cut_0(uint8_t *b, size_t n) { (void)b, (void)n; return 0; }
static size_t cut_5(uint8_t *b, size_t n) { (void)b, (void)n; return 5; }
static size_t cut_8(uint8_t *b, size_t n) { (void)b, (void)n; return 8; }
static size_t cut_100(uint8_t *b, size_t n) { (void)b, (void)n; return 100; }
static size_t cut_191(uint8_t *b, size_t n) { (void)b, (void)n; return 191; }
static size_t cut_last(uint8_t *b, size_t n) { (void)b; return n - 1; }
static size_t cut_dir(uint8_t *b, size_t n) { (void)b; return n - 64; }

static size_t wrong_magic(uint8_t *b, size_t n)
{
    b[1] = 'X';
    return n;
}

static size_t text_prefix(uint8_t *b, size_t n)
{
    (void)n;
    memcpy(b, "solid cube\n", 11);
    return 11;
}

static size_t short_not_magic(uint8_t *b, size_t n)
{
    (void)n;
    b[2] = 'Q';
    return 5;
}

static size_t crlf_magic(uint8_t *b, size_t n)
{
    /* LF -> CRLF conversion: "\r\n" becomes "\r\r\n", the final "\n" becomes "\r\n". */
    memmove(b + 6, b + 5, n - 5);
    b[5] = '\r';
    memmove(b + 9, b + 8, n + 1 - 8);
    b[8] = '\r';
    return n + 2;
}

static size_t major_2(uint8_t *b, size_t n)
{
    hdr(b)->version_major = 2; /* checksum left stale: VERSION is checked first */
    return n;
}

static size_t major_0(uint8_t *b, size_t n)
{
    hdr(b)->version_major = 0;
    fix_header(b);
    return n;
}

static size_t header_flip(uint8_t *b, size_t n)
{
    b[offsetof(tpk_header, vertex_count)] ^= 0x10;
    return n;
}

static size_t header_flags(uint8_t *b, size_t n)
{
    hdr(b)->flags = 1;
    fix_header(b);
    return n;
}

static size_t header_reserved(uint8_t *b, size_t n)
{
    hdr(b)->reserved[31] = 1;
    fix_header(b);
    return n;
}

static size_t trailing_bytes(uint8_t *b, size_t n)
{
    b[n] = 0;
    return n + 1;
}

static size_t shell_count(uint8_t *b, size_t n)
{
    hdr(b)->shell_face_count = 4 * SAMPLE_T + 1;
    fix_header(b);
    return n;
}

static size_t chunk_limit(uint8_t *b, size_t n)
{
    hdr(b)->chunk_count = 100000;
    fix_header(b);
    return n;
}

static size_t directory_misaligned(uint8_t *b, size_t n)
{
    hdr(b)->directory_offset += 8;
    fix_header(b);
    return n;
}

static size_t count_past_end(uint8_t *b, size_t n)
{
    hdr(b)->chunk_count += 1;
    fix_header(b);
    return n;
}

static size_t directory_flip(uint8_t *b, size_t n)
{
    entry(b, 2)->elem_count ^= 4;
    return n;
}

static size_t entry_reserved(uint8_t *b, size_t n)
{
    entry(b, 1)->reserved = 1;
    fix_directory(b);
    return n;
}

static size_t entry_flag_bit(uint8_t *b, size_t n)
{
    entry(b, 1)->flags |= 0x4;
    fix_directory(b);
    return n;
}

static size_t unknown_codec(uint8_t *b, size_t n)
{
    entry(b, 1)->codec = 2;
    fix_directory(b);
    return n;
}

static size_t elem_size_wrong(uint8_t *b, size_t n)
{
    entry(b, 1)->elem_size = 16;
    fix_directory(b);
    return n;
}

static size_t stored_size_wrong(uint8_t *b, size_t n)
{
    entry(b, 1)->stored_size -= 4; /* codec none */
    fix_directory(b);
    return n;
}

static size_t offset_misaligned(uint8_t *b, size_t n)
{
    entry(b, 1)->offset += 16;
    fix_directory(b);
    return n;
}

static size_t offset_past_end(uint8_t *b, size_t n)
{
    entry(b, 1)->offset = hdr(b)->file_size + 64;
    fix_directory(b);
    return n;
}

static size_t stored_past_end(uint8_t *b, size_t n)
{
    entry(b, entry_of(b, TPK_TAG_TT20, 0, 0))->stored_size = UINT64_MAX - 8; /* zstd chunk; overflow-safe */
    fix_directory(b);
    return n;
}

static size_t overlap_chunks(uint8_t *b, size_t n)
{
    entry(b, entry_of(b, TPK_TAG_FDAT, 0, 0))->offset = entry(b, entry_of(b, TPK_TAG_POS3, 0, 0))->offset;
    fix_directory(b);
    return n;
}

static size_t overlap_directory(uint8_t *b, size_t n)
{
    tpk_dir_entry *e = entry(b, entry_of(b, TPK_TAG_TMAP, 0, 0));
    e->offset = hdr(b)->directory_offset;
    e->checksum = XXH64(b + e->offset, e->raw_size, 0);
    fix_directory(b);
    return n;
}

static size_t unknown_required(uint8_t *b, size_t n)
{
    tpk_dir_entry *e = entry(b, entry_of(b, TPK_TAG_META, 0, 0));
    e->tag = TPK_FOURCC('Z', 'Z', 'Z', 1);
    e->flags = TPK_CHUNK_REQUIRED;
    fix_directory(b);
    return n;
}

static size_t wrong_elem_type(uint8_t *b, size_t n)
{
    tpk_dir_entry *e = entry(b, entry_of(b, TPK_TAG_TMAP, 0, 0));
    e->elem_type = TPK_ELEM_F32;
    fix_directory(b);
    return n;
}

static size_t index_nonzero(uint8_t *b, size_t n)
{
    entry(b, entry_of(b, TPK_TAG_TMAP, 0, 0))->step = 1;
    fix_directory(b);
    return n;
}

static size_t duplicate_chunk(uint8_t *b, size_t n)
{
    entry(b, entry_of(b, TPK_TAG_FDAT, 1, 1))->step = 0;
    fix_directory(b);
    return n;
}

static size_t count_mismatch(uint8_t *b, size_t n)
{
    tpk_dir_entry *e = entry(b, entry_of(b, TPK_TAG_TMAP, 0, 0));
    e->elem_count = 1;
    e->raw_size = e->stored_size = 4;
    fix_chunk(b, entry_of(b, TPK_TAG_TMAP, 0, 0));
    return n;
}

static size_t no_shell(uint8_t *b, size_t n)
{
    hide_chunk(b, entry_of(b, TPK_TAG_SHEL, 0, 0), TPK_FOURCC('s', 'h', 'e', 'l'));
    fix_directory(b);
    return n;
}

static size_t field_name_empty(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_FDSC, 0, 0);
    b[entry(b, i)->offset + 128] = 0; /* second field's name */
    fix_chunk(b, i);
    return n;
}

static size_t field_names_equal(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_FDSC, 0, 0);
    tpk_field_desc *f = (tpk_field_desc *)(b + entry(b, i)->offset);
    memcpy(f[1].name, f[0].name, sizeof f[1].name);
    fix_chunk(b, i);
    return n;
}

static size_t fdsc_checksum(uint8_t *b, size_t n)
{
    b[entry(b, entry_of(b, TPK_TAG_FDSC, 0, 0))->offset + 70] ^= 1; /* the units */
    return n;
}

static size_t fdat_step_outside(uint8_t *b, size_t n)
{
    entry(b, entry_of(b, TPK_TAG_FDAT, 0, 1))->step = 2;
    fix_directory(b);
    return n;
}

static size_t fdat_missing(uint8_t *b, size_t n)
{
    hide_chunk(b, entry_of(b, TPK_TAG_FDAT, 1, 1), TPK_FOURCC('x', 'd', 'a', 't'));
    fix_directory(b);
    return n;
}

static size_t time_count(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_FDSC, 0, 0);
    tpk_field_desc *f = (tpk_field_desc *)(b + entry(b, i)->offset);
    f[0].step_count = 1;
    f[1].step_count = 1;
    hide_chunk(b, entry_of(b, TPK_TAG_FDAT, 0, 1), TPK_FOURCC('x', 'd', 'a', 't'));
    hide_chunk(b, entry_of(b, TPK_TAG_FDAT, 1, 1), TPK_FOURCC('y', 'd', 'a', 't'));
    fix_chunk(b, i);
    return n;
}

static size_t chunk_data_flip(uint8_t *b, size_t n)
{
    b[entry(b, entry_of(b, TPK_TAG_TT32, 0, 0))->offset + 5] ^= 0x40;
    return n;
}

static size_t zstd_data_flip(uint8_t *b, size_t n)
{
    b[entry(b, entry_of(b, TPK_TAG_TT20, 0, 0))->offset] ^= 0xff; /* the zstd frame magic */
    return n;
}

static size_t tet32_vertex(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_TT32, 0, 0);
    tpk_tet32 *t = (tpk_tet32 *)(b + entry(b, i)->offset);
    t[1].vx ^= 8; /* the derived 4th vertex becomes 12 */
    fix_chunk(b, i);
    return n;
}

static size_t tet32_neighbor(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_TT32, 0, 0);
    tpk_tet32 *t = (tpk_tet32 *)(b + entry(b, i)->offset);
    t[0].n[0] = -2;
    fix_chunk(b, i);
    return n;
}

static size_t tmap_negative(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_TMAP, 0, 0);
    int32_t *m = (int32_t *)(b + entry(b, i)->offset);
    m[1] = -1;
    fix_chunk(b, i);
    return n;
}

/* Bytes of padding after chunk i, before the next chunk or the directory: room to grow it in place. */
static uint64_t room_after(uint8_t *b, uint64_t i)
{
    const tpk_header *h = hdr(b);
    uint64_t end = entry(b, i)->offset + entry(b, i)->stored_size, next = h->directory_offset;
    for (uint64_t j = 0; j < h->chunk_count; j++)
        if (entry(b, j)->offset >= end && entry(b, j)->offset < next)
            next = entry(b, j)->offset;
    return next - end;
}

/* Append `extra` to the first zstd chunk with room for it, making it more than the one frame spec §4.2
 * allows; zstd's own decoder accepts both tails, so only the reader's single-frame rule refuses them. */
static size_t zstd_append(uint8_t *b, size_t n, const uint8_t *extra, size_t extra_size)
{
    for (uint64_t i = 0; i < hdr(b)->chunk_count; i++) {
        tpk_dir_entry *e = entry(b, i);
        if (e->codec == TPK_CODEC_ZSTD && room_after(b, i) >= extra_size) {
            memcpy(b + e->offset + e->stored_size, extra, extra_size);
            e->stored_size += extra_size;
            fix_directory(b);
            return n;
        }
    }
    return n; /* no room: the case then opens clean and its test fails */
}

static size_t zstd_skippable_after(uint8_t *b, size_t n)
{
    static const uint8_t skippable[8] = {0x50, 0x2A, 0x4D, 0x18, 0, 0, 0, 0}; /* magic 0x184D2A50, size 0 */
    return zstd_append(b, n, skippable, sizeof skippable);
}

static size_t zstd_second_frame(uint8_t *b, size_t n)
{
    /* A frame of no content: single segment, content size 0, one empty last raw block. */
    static const uint8_t empty[9] = {0x28, 0xB5, 0x2F, 0xFD, 0x20, 0x00, 0x01, 0x00, 0x00};
    return zstd_append(b, n, empty, sizeof empty);
}

/* A zstd chunk claiming more than any frame of its stored size decodes to (format 1.1, rule 10). */
static size_t zstd_implausible_size(uint8_t *b, size_t n)
{
    tpk_dir_entry *e = entry(b, entry_of(b, TPK_TAG_META, 0, 0));
    e->elem_count = e->raw_size = e->stored_size * 32768 + 1;
    fix_directory(b);
    return n;
}

static size_t origin_nan(uint8_t *b, size_t n)
{
    hdr(b)->origin[1] = NAN;
    fix_header(b);
    return n;
}

/* An FDSC of no fields, its FDAT and TIME chunks hidden: the only rule broken is "FDSC iff fields". */
static size_t fdsc_empty(uint8_t *b, size_t n)
{
    static const uint32_t hidden[5] = {TPK_FOURCC('a', 'd', 'a', 't'), TPK_FOURCC('b', 'd', 'a', 't'),
                                       TPK_FOURCC('c', 'd', 'a', 't'), TPK_FOURCC('d', 'd', 'a', 't'),
                                       TPK_FOURCC('t', 'i', 'm', 'e')};
    int k = 0;
    for (uint64_t i = 0; i < hdr(b)->chunk_count; i++)
        if (entry(b, i)->tag == TPK_TAG_FDAT || entry(b, i)->tag == TPK_TAG_TIME)
            hide_chunk(b, i, hidden[k++ % 5]);
    tpk_dir_entry *e = entry(b, entry_of(b, TPK_TAG_FDSC, 0, 0));
    e->elem_count = e->raw_size = e->stored_size = 0;
    e->codec = TPK_CODEC_NONE;
    e->checksum = XXH64(NULL, 0, 0);
    fix_directory(b);
    return n;
}

/* A Tet16 vx of 8 with 5 vertices: no xor of ids in [0, 5) reaches 8 (format 1.1, rule 17). */
static size_t tet16_vx(uint8_t *b, size_t n)
{
    uint64_t i = entry_of(b, TPK_TAG_TT16, 0, 0);
    tpk_tet16 *t = (tpk_tet16 *)(b + entry(b, i)->offset);
    t[1].vx = 8;
    fix_chunk(b, i);
    return n;
}

static const fail_case fail_cases[] = {
    {"truncated_0", cut_0, TPK_ERR_TRUNCATED, TPK_OK},
    {"truncated_5", cut_5, TPK_ERR_TRUNCATED, TPK_OK},
    {"truncated_8", cut_8, TPK_ERR_TRUNCATED, TPK_OK},
    {"truncated_100", cut_100, TPK_ERR_TRUNCATED, TPK_OK},
    {"truncated_191", cut_191, TPK_ERR_TRUNCATED, TPK_OK},
    {"truncated_last_byte", cut_last, TPK_ERR_TRUNCATED, TPK_OK},
    {"truncated_directory", cut_dir, TPK_ERR_TRUNCATED, TPK_OK},
    {"wrong_magic", wrong_magic, TPK_ERR_NOT_TETPACK, TPK_OK},
    {"text_file", text_prefix, TPK_ERR_NOT_TETPACK, TPK_OK},
    {"short_not_magic", short_not_magic, TPK_ERR_NOT_TETPACK, TPK_OK},
    {"crlf_magic", crlf_magic, TPK_ERR_NOT_TETPACK, TPK_OK},
    {"major_2", major_2, TPK_ERR_VERSION, TPK_OK},
    {"major_0", major_0, TPK_ERR_CORRUPT, TPK_OK},
    {"header_bit_flip", header_flip, TPK_ERR_HEADER_CHECKSUM, TPK_OK},
    {"header_flags", header_flags, TPK_ERR_CORRUPT, TPK_OK},
    {"header_reserved", header_reserved, TPK_ERR_CORRUPT, TPK_OK},
    {"trailing_bytes", trailing_bytes, TPK_ERR_CORRUPT, TPK_OK},
    {"shell_count", shell_count, TPK_ERR_CORRUPT, TPK_OK},
    {"chunk_limit", chunk_limit, TPK_ERR_LIMIT, TPK_OK},
    {"directory_misaligned", directory_misaligned, TPK_ERR_MISALIGNED, TPK_OK},
    {"count_past_end", count_past_end, TPK_ERR_OUT_OF_BOUNDS, TPK_OK},
    {"directory_bit_flip", directory_flip, TPK_ERR_DIRECTORY_CHECKSUM, TPK_OK},
    {"entry_reserved", entry_reserved, TPK_ERR_CORRUPT, TPK_OK},
    {"entry_flag_bit", entry_flag_bit, TPK_ERR_CORRUPT, TPK_OK},
    {"unknown_codec", unknown_codec, TPK_ERR_UNSUPPORTED_CHUNK, TPK_OK},
    {"elem_size_wrong", elem_size_wrong, TPK_ERR_CORRUPT, TPK_OK},
    {"stored_size_wrong", stored_size_wrong, TPK_ERR_CORRUPT, TPK_OK},
    {"offset_misaligned", offset_misaligned, TPK_ERR_MISALIGNED, TPK_OK},
    {"offset_past_end", offset_past_end, TPK_ERR_OUT_OF_BOUNDS, TPK_OK},
    {"stored_past_end", stored_past_end, TPK_ERR_OUT_OF_BOUNDS, TPK_OK},
    {"overlap_chunks", overlap_chunks, TPK_ERR_OVERLAP, TPK_OK},
    {"overlap_directory", overlap_directory, TPK_ERR_OVERLAP, TPK_OK},
    {"unknown_required", unknown_required, TPK_ERR_UNSUPPORTED_CHUNK, TPK_OK},
    {"wrong_elem_type", wrong_elem_type, TPK_ERR_CORRUPT, TPK_OK},
    {"index_nonzero", index_nonzero, TPK_ERR_CORRUPT, TPK_OK},
    {"duplicate_chunk", duplicate_chunk, TPK_ERR_CORRUPT, TPK_OK},
    {"count_mismatch", count_mismatch, TPK_ERR_CORRUPT, TPK_OK},
    {"no_shell", no_shell, TPK_ERR_CORRUPT, TPK_OK},
    {"field_name_empty", field_name_empty, TPK_ERR_CORRUPT, TPK_OK},
    {"field_names_equal", field_names_equal, TPK_ERR_CORRUPT, TPK_OK},
    {"fdsc_checksum", fdsc_checksum, TPK_ERR_CHUNK_CHECKSUM, TPK_OK},
    {"fdat_step_outside", fdat_step_outside, TPK_ERR_CORRUPT, TPK_OK},
    {"fdat_missing", fdat_missing, TPK_ERR_CORRUPT, TPK_OK},
    {"time_count", time_count, TPK_ERR_CORRUPT, TPK_OK},
    {"chunk_data_flip", chunk_data_flip, TPK_OK, TPK_ERR_CHUNK_CHECKSUM},
    {"zstd_data_flip", zstd_data_flip, TPK_OK, TPK_ERR_DECOMPRESS},
    {"tet32_vertex", tet32_vertex, TPK_OK, TPK_ERR_CORRUPT},
    {"tet32_neighbor", tet32_neighbor, TPK_OK, TPK_ERR_CORRUPT},
    {"tmap_negative", tmap_negative, TPK_OK, TPK_ERR_CORRUPT},
    {"zstd_skippable_after", zstd_skippable_after, TPK_OK, TPK_ERR_DECOMPRESS},
    {"zstd_second_frame", zstd_second_frame, TPK_OK, TPK_ERR_DECOMPRESS},
    {"zstd_implausible_size", zstd_implausible_size, TPK_ERR_CORRUPT, TPK_OK},
    {"origin_nan", origin_nan, TPK_ERR_CORRUPT, TPK_OK},
    {"fdsc_empty", fdsc_empty, TPK_ERR_CORRUPT, TPK_OK},
    {"tet16_vx", tet16_vx, TPK_OK, TPK_ERR_CORRUPT},
};
#define FAIL_CASE_COUNT (sizeof fail_cases / sizeof fail_cases[0])

/* Apply a case to a copy of good (with room to grow); returns the malloc'ed bytes and their size. */
static uint8_t *mutated(const uint8_t *good, size_t size, const fail_case *c, size_t *out_size)
{
    uint8_t *bytes = calloc(size + 16, 1);
    memcpy(bytes, good, size);
    *out_size = c->mutate(bytes, size);
    return bytes;
}

/* Exact-size copy so an overread hits ASan's redzone. */
static tpk_result open_exact(const uint8_t *bytes, size_t size, const tpk_open_options *options, tpk_file **out,
                             uint8_t **copy, char *err, size_t cap)
{
    *copy = malloc(size ? size : 1);
    memcpy(*copy, bytes, size);
    return tpk_open_memory(out, *copy, size, options, err, cap);
}

TPK_TEST(must_fail_cases)
{
    size_t size;
    uint8_t *good = good_bytes(&size, NULL);
    CHECK(good != NULL);
    for (size_t k = 0; k < FAIL_CASE_COUNT; k++) {
        const fail_case *c = &fail_cases[k];
        size_t n;
        uint8_t *bytes = mutated(good, size, c, &n), *copy;
        tpk_file *file = NULL;
        char err[512] = "";
        tpk_result r = open_exact(bytes, n, NULL, &file, &copy, err, sizeof err);
        free(bytes);
        tpk_result v = file ? tpk_verify(file) : TPK_OK;
        if (v != c->verify_result)
            fprintf(stderr, "%s: %s\n", c->name, tpk_error_text(file));
        tpk_close(file);
        free(copy);
        CHECK_MSG(r == c->open_result, "%s: open gave %d (%s), expected %d", c->name, r, err, c->open_result);
        CHECK_MSG(r == TPK_OK || (err[0] && !file), "%s: no message", c->name);
        CHECK_MSG(v == c->verify_result, "%s: verify gave %d, expected %d", c->name, v, c->verify_result);
    }
    free(good);
}

/* ---- round trip and reads ---------------------------------------------------------------------------- */

TPK_TEST(round_trip)
{
    const char *path = tpk_temp_path("round_trip.tpk");
    build_opts o = {.big = 1};
    CHECK_EQ_INT(build_file(path, &o), TPK_OK);
    make_sample(&the_sample);
    chunk_src chunks[32];
    int n = sample_chunks(&the_sample, &o, chunks);
    tpk_file *file;
    char err[512];
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, err, sizeof err), TPK_OK);
    tpk_file_info info;
    CHECK_EQ_INT(tpk_get_info(file, &info), TPK_OK);
    CHECK_EQ_INT(info.chunk_count, n);
    CHECK_EQ_INT(info.vertex_count, SAMPLE_V);
    CHECK(info.origin[1] == 200.0 && info.bounds_max[2] == 301.0);
    static uint8_t buffer[BIG_BYTES];
    for (int k = 0; k < n; k++) {
        tpk_dir_entry e;
        CHECK_EQ_INT(tpk_get_chunk(file, (uint64_t)k, &e), TPK_OK);
        CHECK_EQ_INT(e.tag, chunks[k].desc.tag);
        CHECK_EQ_INT(e.codec, chunks[k].desc.codec);
        uint64_t size = e.raw_size;
        CHECK_EQ_INT(tpk_read_chunk(file, (uint64_t)k, buffer, sizeof buffer), TPK_OK);
        CHECK_MSG(memcmp(buffer, chunks[k].data, size) == 0, "chunk %d differs", k);
        uint64_t found;
        CHECK_EQ_INT(tpk_find_chunk(file, e.tag, e.index, e.step, &found), TPK_OK);
        CHECK_EQ_INT(found, k);
    }
    CHECK_EQ_INT(tpk_read_chunk(file, 0, buffer, 8), TPK_ERR_INVALID_ARGUMENT); /* dst too small */
    CHECK_EQ_INT(tpk_verify(file), TPK_OK);                                   /* not poisoned */
    tpk_close(file);
}

TPK_TEST(fields_and_time)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, NULL, NULL, 0), TPK_OK);
    CHECK_EQ_INT(tpk_field_count(file), 2);
    tpk_field_desc f;
    uint32_t i;
    CHECK_EQ_INT(tpk_get_field(file, 1, &f), TPK_OK);
    CHECK(strcmp(f.name, "pressure") == 0 && f.association == TPK_ASSOC_TET && f.step_count == 2);
    CHECK_EQ_INT(tpk_find_field(file, "temperature", &i), TPK_OK);
    CHECK_EQ_INT(i, 0);
    CHECK_EQ_INT(tpk_find_field(file, "nope", &i), TPK_ERR_NOT_FOUND);
    CHECK_EQ_INT(tpk_get_field(file, 2, &f), TPK_ERR_INVALID_ARGUMENT);
    double t;
    CHECK_EQ_INT(tpk_get_time(file, 1, &t), TPK_OK);
    CHECK(t == 0.5);
    CHECK_EQ_INT(tpk_get_time(file, 2, &t), TPK_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(tpk_find_chunk(file, TPK_TAG_VMAP, 0, 0, &(uint64_t){0}), TPK_ERR_NOT_FOUND);
    /* the tet field's values per step; a point field, a missing one or a step too far are refused */
    const float *cells = NULL;
    CHECK_EQ_INT(tpk_load_tet_field(file, "pressure", 1, &cells), TPK_OK);
    CHECK(cells && cells[0] == 3.0f && cells[1] == 4.0f);
    CHECK_EQ_INT(tpk_load_tet_field(file, "pressure", 2, &cells), TPK_ERR_NOT_FOUND);
    CHECK(cells == NULL && strstr(tpk_error_text(file), "2 steps, step 2 asked"));
    CHECK_EQ_INT(tpk_load_tet_field(file, "temperature", 0, &cells), TPK_ERR_NOT_FOUND);
    CHECK(strstr(tpk_error_text(file), "per-point"));
    CHECK_EQ_INT(tpk_load_tet_field(file, "nope", 0, &cells), TPK_ERR_NOT_FOUND);
    CHECK_EQ_INT(tpk_load_tet_field(file, NULL, 0, &cells), TPK_ERR_INVALID_ARGUMENT);
    tpk_close(file);
    free(bytes);
}

TPK_TEST(views_aligned)
{
    const char *path = tpk_temp_path("aligned.tpk");
    build_opts o = {.big = 1};
    CHECK_EQ_INT(build_file(path, &o), TPK_OK);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
    tpk_file_info info;
    tpk_get_info(file, &info);
    int large_seen = 0;
    for (uint64_t i = 0; i < info.chunk_count; i++) {
        tpk_dir_entry e;
        tpk_get_chunk(file, i, &e);
        const void *data;
        uint64_t size;
        tpk_result r = tpk_view_chunk(file, i, &data, &size);
        if (e.codec != TPK_CODEC_NONE) {
            CHECK_EQ_INT(r, TPK_ERR_UNSUPPORTED_CHUNK);
            continue;
        }
        CHECK_EQ_INT(r, TPK_OK);
        CHECK_EQ_INT(size, e.raw_size);
        CHECK_EQ_INT((uintptr_t)data % 64, 0);
        if (e.raw_size >= TPK_LARGE_CHUNK_BYTES) {
            CHECK_EQ_INT((uintptr_t)data % 4096, 0);
            large_seen = 1;
        }
    }
    CHECK(large_seen);
    CHECK_EQ_INT(tpk_verify(file), TPK_OK); /* UNSUPPORTED from a view of a zstd chunk does not poison */
    tpk_close(file);
}

TPK_TEST(open_options)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    tpk_file *file;
    tpk_open_options o = {.size = sizeof o, .flags = TPK_OPEN_VERIFY_ALL};
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_OK);
    tpk_close(file);
    /* VERIFY_ALL catches a chunk checksum at open; TRUSTED never looks. */
    bytes[entry(bytes, entry_of(bytes, TPK_TAG_TT16, 0, 0))->offset] ^= 1;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_ERR_CHUNK_CHECKSUM);
    CHECK(file == NULL);
    o.flags = TPK_OPEN_TRUSTED;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_OK);
    tpk_mesh_arrays m;
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET16, NULL, 0, &m), TPK_OK);
    tpk_close(file);
    /* Limits. */
    o = (tpk_open_options){.limits = {.max_chunks = 3}};
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_ERR_LIMIT);
    o = (tpk_open_options){.limits = {.max_chunk_bytes = 100}};
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_ERR_LIMIT);
    o = (tpk_open_options){.limits = {.max_total_bytes = 500}};
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_ERR_LIMIT);
    free(bytes);
}

static int messages_seen;
static tpk_result last_message_code;

static void count_message(void *user, tpk_result code, const char *text)
{
    (void)user;
    CHECK(text && text[0]);
    messages_seen++;
    last_message_code = code;
}

TPK_TEST(messages_are_specific)
{
    size_t size;
    uint8_t *good = good_bytes(&size, NULL);
    struct {
        const char *name, *expect;
    } cases[] = {
        {"major_2", "file is format 2.x, this reader supports 1.x"},
        {"stored_size_wrong", "chunk 1 'TT32' at offset 256: stored_size 60 but codec none needs raw_size 64"},
        {"unknown_required", "tag 0x015a5a5a is marked required"},
        {"tet32_vertex", "4th vertex"},
        {"crlf_magic", "text mode"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const fail_case *fc = NULL;
        for (size_t k = 0; k < FAIL_CASE_COUNT; k++)
            fc = strcmp(fail_cases[k].name, cases[c].name) == 0 ? &fail_cases[k] : fc;
        CHECK(fc != NULL);
        size_t n;
        uint8_t *bytes = mutated(good, size, fc, &n);
        tpk_file *file = NULL;
        char err[512] = "";
        tpk_open_options o = {.message = count_message};
        messages_seen = 0;
        tpk_result r = tpk_open_memory(&file, bytes, n, &o, err, sizeof err);
        if (r == TPK_OK) {
            r = tpk_verify(file);
            snprintf(err, sizeof err, "%s", tpk_error_text(file));
            tpk_close(file);
        }
        free(bytes);
        const char *expect = cases[c].expect;
        CHECK_MSG(strstr(err, expect) != NULL, "%s: message '%s' lacks '%s'", cases[c].name, err, expect);
        CHECK_EQ_INT(messages_seen, 1);
        CHECK_EQ_INT(last_message_code, r);
    }
    free(good);
}

TPK_TEST(poisoned_handle)
{
    size_t size, n;
    uint8_t *good = good_bytes(&size, NULL);
    const fail_case flip = {"flip", chunk_data_flip, TPK_OK, TPK_OK};
    uint8_t *bytes = mutated(good, size, &flip, &n);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, n, NULL, NULL, 0), TPK_OK);
    tpk_mesh_arrays m;
    /* Caller errors do not poison. */
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET20, "pressure", 0, &m), TPK_ERR_NOT_FOUND);
    CHECK(strstr(tpk_error_text(file), "per-tet") != NULL);
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET20, "temperature", 2, &m), TPK_ERR_NOT_FOUND);
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET20, "temperature", 1, &m), TPK_OK);
    uint64_t tt32;
    CHECK_EQ_INT(tpk_find_chunk(file, TPK_TAG_TT32, 0, 0, &tt32), TPK_OK);
    const void *view;
    uint64_t view_size;
    CHECK_EQ_INT(tpk_view_chunk(file, tt32, &view, &view_size), TPK_ERR_CHUNK_CHECKSUM);
    CHECK(strstr(tpk_error_text(file), "'TT32'") != NULL);
    CHECK_EQ_INT(tpk_view_chunk(file, tt32, &view, &view_size), TPK_ERR_BAD_STATE);
    CHECK_EQ_INT(tpk_read_chunk(file, 0, &(float[15]){0}, 60), TPK_ERR_BAD_STATE);
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET20, NULL, 0, &m), TPK_ERR_BAD_STATE);
    CHECK_EQ_INT(tpk_verify(file), TPK_ERR_BAD_STATE);
    CHECK_EQ_INT(tpk_get_time(file, 0, &(double){0}), TPK_ERR_BAD_STATE);
    tpk_close(file);
    free(bytes);
    free(good);
}

/* ---- arrays ------------------------------------------------------------------------------------------ */

TPK_TEST(load_arrays_layouts)
{
    const char *path = tpk_temp_path("arrays.tpk");
    CHECK_EQ_INT(build_file(path, NULL), TPK_OK);
    make_sample(&the_sample);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
    tpk_mesh_arrays m;
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET32, NULL, 1, &m), TPK_OK);
    CHECK(m.tet32 && !m.tet20 && !m.tet16 && m.layout == TPK_LAYOUT_TET32);
    CHECK_EQ_INT(m.tet_count, SAMPLE_T);
    CHECK(memcmp(m.tet32, the_sample.tet32, sizeof the_sample.tet32) == 0);
    CHECK(memcmp(m.positions, the_sample.positions, sizeof the_sample.positions) == 0);
    CHECK(memcmp(m.shell, the_sample.shell, sizeof the_sample.shell) == 0);
    CHECK(memcmp(m.scalars, the_sample.temperature[1], sizeof the_sample.temperature[1]) == 0);
    CHECK(m.origin[0] == 100.0);
    const void *view;
    uint64_t view_size, tt32;
    tpk_find_chunk(file, TPK_TAG_TT32, 0, 0, &tt32);
    CHECK_EQ_INT(tpk_view_chunk(file, tt32, &view, &view_size), TPK_OK);
    CHECK(view == (const void *)m.tet32); /* zero-copy */
    tpk_mesh_arrays m20;
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET20, "temperature", 0, &m20), TPK_OK);
    CHECK(memcmp(m20.tet20, the_sample.tet20, sizeof the_sample.tet20) == 0);
    CHECK(m20.shell == m.shell); /* decoded once, owned by the handle */
    CHECK(memcmp(m20.scalars, the_sample.temperature[0], sizeof the_sample.temperature[0]) == 0);
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET16, NULL, 0, &m), TPK_OK);
    CHECK(memcmp(m.tet16, the_sample.tet16, sizeof the_sample.tet16) == 0);
    CHECK_EQ_INT(tpk_load_arrays(file, (tpk_layout)17, NULL, 0, &m), TPK_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET16, "nope", 0, &m), TPK_ERR_NOT_FOUND);
    tpk_close(file);
}

TPK_TEST(load_arrays_missing_layout)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    hide_chunk(bytes, entry_of(bytes, TPK_TAG_TT16, 0, 0), TPK_FOURCC('x', 't', '1', '6'));
    fix_directory(bytes);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, NULL, NULL, 0), TPK_OK);
    tpk_mesh_arrays m;
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET16, NULL, 0, &m), TPK_ERR_NOT_FOUND);
    CHECK_MSG(strstr(tpk_error_text(file), "Tet32, Tet20") != NULL, "%s", tpk_error_text(file));
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET32, NULL, 0, &m), TPK_OK);
    tpk_close(file);
    free(bytes);
}

TPK_TEST(bad_ids_from_writer)
{
    const char *path = tpk_temp_path("bad_ids.tpk");
    build_opts o = {.bad_tet32 = 1};
    CHECK_EQ_INT(build_file(path, &o), TPK_OK);
    tpk_file *file;
    tpk_mesh_arrays m;
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
    CHECK_EQ_INT(tpk_verify(file), TPK_ERR_CORRUPT);
    CHECK(strstr(tpk_error_text(file), "record 1") != NULL);
    tpk_close(file);
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
    CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET32, NULL, 0, &m), TPK_ERR_CORRUPT);
    tpk_close(file);
    o = (build_opts){.bad_shell = 1};
    CHECK_EQ_INT(build_file(path, &o), TPK_OK);
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
    CHECK_EQ_INT(tpk_verify(file), TPK_ERR_CORRUPT);
    CHECK(strstr(tpk_error_text(file), "'SHEL'") != NULL);
    tpk_close(file);
}

typedef struct thread_job {
    tpk_file *file;
    tpk_result result;
    const void *shell;
} thread_job;

static void *load_in_thread(void *arg)
{
    thread_job *job = arg;
    tpk_mesh_arrays m;
    for (int k = 0; k < 50 && job->result == TPK_OK; k++) {
        job->result = tpk_load_arrays(job->file, TPK_LAYOUT_TET20, NULL, (uint32_t)(k % 2), &m);
        job->shell = m.shell;
    }
    return NULL;
}

TPK_TEST(threads_share_a_handle)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, NULL, NULL, 0), TPK_OK);
    pthread_t threads[4];
    thread_job jobs[4];
    for (int k = 0; k < 4; k++) {
        jobs[k] = (thread_job){file, TPK_OK, NULL};
        pthread_create(&threads[k], NULL, load_in_thread, &jobs[k]);
    }
    for (int k = 0; k < 4; k++)
        pthread_join(threads[k], NULL);
    for (int k = 0; k < 4; k++) {
        CHECK_EQ_INT(jobs[k].result, TPK_OK);
        CHECK(jobs[k].shell == jobs[0].shell);
    }
    tpk_close(file);
    free(bytes);
}

/* Issue 10: tpk_error_text read the handle's message without the lock its writer holds. One thread keeps
 * failing with two messages of different lengths (a missing field is NOT_FOUND, which does not poison
 * the handle) while another reads the text: every text read must be one whole message, never the start
 * of one and the rest of the other. */
#define TORN_ROUNDS 300000
static const char *const torn_fields[2] = {"a", "a_much_longer_field_name_that_fills_the_message_buffer_further"};

typedef struct torn_job {
    tpk_file *file;
    atomic_int done;
    char expected[2][512];
    long torn;
    char example[512];
} torn_job;

static void *fail_in_thread(void *arg)
{
    torn_job *job = arg;
    tpk_mesh_arrays m;
    for (int k = 0; k < TORN_ROUNDS; k++)
        tpk_load_arrays(job->file, TPK_LAYOUT_TET32, torn_fields[k % 2], 0, &m);
    atomic_store(&job->done, 1);
    return NULL;
}

static void *read_in_thread(void *arg)
{
    torn_job *job = arg;
    while (!atomic_load(&job->done)) {
        const char *text = tpk_error_text(job->file);
        if (strcmp(text, job->expected[0]) != 0 && strcmp(text, job->expected[1]) != 0 && job->torn++ == 0)
            snprintf(job->example, sizeof job->example, "%s", text);
    }
    return NULL;
}

TPK_TEST(error_text_is_never_torn)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    torn_job job = {.torn = 0};
    atomic_init(&job.done, 0);
    CHECK_EQ_INT(tpk_open_memory(&job.file, bytes, size, NULL, NULL, 0), TPK_OK);
    tpk_mesh_arrays m;
    for (int k = 0; k < 2; k++) { /* the two messages, as one thread sees them */
        CHECK_EQ_INT(tpk_load_arrays(job.file, TPK_LAYOUT_TET32, torn_fields[k], 0, &m), TPK_ERR_NOT_FOUND);
        snprintf(job.expected[k], sizeof job.expected[k], "%s", tpk_error_text(job.file));
        CHECK(strstr(job.expected[k], torn_fields[k]) != NULL);
    }
    pthread_t failer, reader;
    pthread_create(&failer, NULL, fail_in_thread, &job);
    pthread_create(&reader, NULL, read_in_thread, &job);
    pthread_join(failer, NULL);
    pthread_join(reader, NULL);
    tpk_close(job.file);
    free(bytes);
    CHECK_MSG(job.torn == 0, "%ld torn texts, e.g. '%s'", job.torn, job.example);
}

/* ---- unknown chunks ----------------------------------------------------------------------------------- */

TPK_TEST(unknown_chunks)
{
    const char *path = tpk_temp_path("unknown.tpk");
    build_opts o = {.extra_tag = TPK_FOURCC('x', 't', 'r', 'a'), .extra_flags = 0};
    CHECK_EQ_INT(build_file(path, &o), TPK_OK);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
    CHECK_EQ_INT(tpk_verify(file), TPK_OK);
    tpk_close(file);
    o.extra_flags = TPK_CHUNK_REQUIRED;
    CHECK_EQ_INT(build_file(path, &o), TPK_OK);
    char err[256];
    CHECK_EQ_INT(tpk_open_path(&file, path, NULL, err, sizeof err), TPK_ERR_UNSUPPORTED_CHUNK);
    CHECK_MSG(strstr(err, "'xtra'") != NULL, "%s", err);
}

TPK_TEST(minor_version_accepted)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    hdr(bytes)->version_minor = 7;
    fix_header(bytes);
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, NULL, NULL, 0), TPK_OK);
    tpk_close(file);
    free(bytes);
}

/* ---- writer ----------------------------------------------------------------------------------------- */

static int leftovers(const char *dir)
{
    int found = 0;
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        found += strstr(e->d_name, ".tmp.") != NULL;
    if (d)
        closedir(d);
    return found;
}

TPK_TEST(writer_deterministic)
{
    size_t a_size, b_size;
    CHECK_EQ_INT(build_file(tpk_temp_path("det_a.tpk"), NULL), TPK_OK);
    CHECK_EQ_INT(build_file(tpk_temp_path("det_b.tpk"), NULL), TPK_OK);
    uint8_t *a = read_all(tpk_temp_path("det_a.tpk"), &a_size), *b = read_all(tpk_temp_path("det_b.tpk"), &b_size);
    CHECK(a && b && a_size == b_size && memcmp(a, b, a_size) == 0);
    free(a);
    free(b);
    CHECK_EQ_INT(leftovers(tpk_temp_dir()), 0);
}

TPK_TEST(writer_abort_leaves_nothing)
{
    const char *path = tpk_temp_path("aborted.tpk");
    tpk_writer *w;
    CHECK_EQ_INT(tpk_writer_open(&w, path, NULL, NULL, 0), TPK_OK);
    CHECK_EQ_INT(leftovers(tpk_temp_dir()), 1);
    make_sample(&the_sample);
    chunk_src c = chunk(TPK_TAG_POS3, TPK_CODEC_NONE, TPK_ELEM_VEC3_F32, 12, SAMPLE_V, the_sample.positions);
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, c.data), TPK_OK);
    tpk_writer_abort(w);
    CHECK(access(path, F_OK) != 0);
    CHECK_EQ_INT(leftovers(tpk_temp_dir()), 0);
}

TPK_TEST(writer_failures_leave_nothing)
{
    char err[512] = "";
    tpk_writer *w;
    /* The directory does not exist. */
    const char *missing = tpk_temp_path("no_such_dir/x.tpk");
    CHECK_EQ_INT(tpk_writer_open(&w, missing, NULL, err, sizeof err), TPK_ERR_IO);
    CHECK(w == NULL && strstr(err, "no_such_dir") != NULL);
    /* The device is full (/dev/full refuses every write with ENOSPC): the message gives the reason. */
    int full = open("/dev/full", O_WRONLY);
    if (full >= 0) {
        err[0] = '\0';
        CHECK_EQ_INT(tpk_writer_open_fd(&w, full, "full.tpk", NULL, err, sizeof err), TPK_ERR_IO);
        CHECK(w == NULL && strstr(err, "cannot write") != NULL && strstr(err, strerror(ENOSPC)) != NULL);
        close(full);
    }
    /* Rename fails: the target is a directory. */
    const char *target = tpk_temp_path("target_is_dir.tpk");
    CHECK_EQ_INT(mkdir(target, 0755), 0);
    tpk_write_options wo = {.size = sizeof wo, .message = count_message};
    messages_seen = 0;
    CHECK_EQ_INT(tpk_writer_open(&w, target, &wo, NULL, 0), TPK_OK);
    make_sample(&the_sample);
    chunk_src chunks[32];
    int n = sample_chunks(&the_sample, NULL, chunks);
    for (int k = 0; k < n; k++)
        CHECK_EQ_INT(tpk_writer_add_chunk(w, &chunks[k].desc, chunks[k].data), TPK_OK);
    tpk_header_fields h = sample_header();
    CHECK_EQ_INT(tpk_writer_finish(w, &h), TPK_ERR_IO);
    CHECK_EQ_INT(messages_seen, 1);
    CHECK_EQ_INT(leftovers(tpk_temp_dir()), 0);
    rmdir(target);
    /* The layout is invalid (no SHEL): refused before anything is renamed. */
    const char *path = tpk_temp_path("invalid_layout.tpk");
    CHECK_EQ_INT(tpk_writer_open(&w, path, NULL, NULL, 0), TPK_OK);
    for (int k = 0; k < n; k++) {
        if (chunks[k].desc.tag != TPK_TAG_SHEL)
            CHECK_EQ_INT(tpk_writer_add_chunk(w, &chunks[k].desc, chunks[k].data), TPK_OK);
    }
    h.shell_face_count = 0;
    CHECK_EQ_INT(tpk_writer_finish(w, &h), TPK_ERR_INVALID_ARGUMENT);
    CHECK(access(path, F_OK) != 0);
    CHECK_EQ_INT(leftovers(tpk_temp_dir()), 0);
}

TPK_TEST(writer_rejects_bad_descs)
{
    tpk_writer *w;
    const char *path = tpk_temp_path("descs.tpk");
    CHECK_EQ_INT(tpk_writer_open(&w, path, NULL, NULL, 0), TPK_OK);
    make_sample(&the_sample);
    chunk_src c = chunk(TPK_TAG_POS3, TPK_CODEC_NONE, TPK_ELEM_VEC3_F32, 12, SAMPLE_V, the_sample.positions);
    c.desc.elem_size = 16;
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, c.data), TPK_ERR_INVALID_ARGUMENT);
    c.desc.elem_size = 12;
    c.desc.elem_type = TPK_ELEM_F32;
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, c.data), TPK_ERR_INVALID_ARGUMENT);
    c.desc.elem_type = TPK_ELEM_VEC3_F32;
    c.desc.codec = 2;
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, c.data), TPK_ERR_INVALID_ARGUMENT);
    c.desc.codec = 0;
    c.desc.flags = 0; /* POS3 must be REQUIRED */
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, c.data), TPK_ERR_INVALID_ARGUMENT);
    CHECK(strstr(tpk_writer_error_text(w), "REQUIRED") != NULL);
    c.desc.flags = TPK_CHUNK_REQUIRED;
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, c.data), TPK_OK);
    chunk_src undefined = chunk(TPK_FOURCC('X', 'T', 'R', 'A'), TPK_CODEC_NONE, TPK_ELEM_BYTE, 1, 4, "abc");
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &undefined.desc, undefined.data), TPK_ERR_INVALID_ARGUMENT);
    tpk_writer_abort(w);
}

/* ---- allocation failure injection --------------------------------------------------------------------- */

typedef struct failing_allocator {
    long allocations, fail_at, live;
} failing_allocator;

static void *failing_alloc(void *user, size_t size)
{
    failing_allocator *a = user;
    if (a->allocations++ == a->fail_at)
        return NULL;
    a->live++;
    return malloc(size);
}

static void failing_free(void *user, void *ptr)
{
    failing_allocator *a = user;
    a->live--;
    free(ptr);
}

/* Open + load every layout with the fail_at'th allocation failing; returns the first error. */
static tpk_result open_and_load(const uint8_t *bytes, size_t size, failing_allocator *a)
{
    tpk_open_options o = {.size = sizeof o, .allocator = {failing_alloc, failing_free, a}};
    tpk_file *file;
    tpk_result r = tpk_open_memory(&file, bytes, size, &o, NULL, 0);
    if (r != TPK_OK)
        return r;
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET20, TPK_LAYOUT_TET32, TPK_LAYOUT_TET16};
    tpk_mesh_arrays m;
    for (int k = 0; k < 3 && r == TPK_OK; k++)
        r = tpk_load_arrays(file, layouts[k], k == 1 ? "temperature" : NULL, 1, &m);
    if (r == TPK_OK)
        r = tpk_verify(file);
    if (r == TPK_OK)
        r = tpk_get_time(file, 1, &(double){0});
    tpk_close(file);
    return r;
}

/* An allocator that refuses every request of `refuse_from` bytes or more, and remembers the largest. */
typedef struct capped_allocator {
    size_t refuse_from, largest;
} capped_allocator;

static void *capped_alloc(void *user, size_t size)
{
    capped_allocator *a = user;
    a->largest = size > a->largest ? size : a->largest;
    return size >= a->refuse_from ? NULL : malloc(size);
}

static void capped_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

/* Issue 10: a header claiming 2^31-1 vertices made `info` try to allocate 25769803764 bytes and report
 * "out of memory". A zstd chunk whose claim the frame contradicts (its Frame_Content_Size says the real
 * size) is refused as DECOMPRESS before anything of the claimed size is requested, and the message says
 * what the frame declares; a claim beyond what zstd can expand to is refused at open (rule 10). */
TPK_TEST(implausible_sizes_refused_before_allocating)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    CHECK(bytes != NULL);
    uint64_t i = entry_of(bytes, TPK_TAG_META, 0, 0);
    tpk_dir_entry *e = entry(bytes, i);
    CHECK(e->codec == TPK_CODEC_ZSTD);
    uint64_t real = e->raw_size;
    e->elem_count = e->raw_size = e->stored_size * 32768; /* the most a frame of this size can decode to */
    fix_directory(bytes);
    capped_allocator a = {(size_t)e->raw_size, 0};
    tpk_open_options o = {.size = sizeof o, .allocator = {capped_alloc, capped_free, &a}};
    tpk_file *file;
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, &o, NULL, 0), TPK_OK);
    tpk_result r = tpk_verify(file);
    char text[512], declared[64];
    snprintf(text, sizeof text, "%s", tpk_error_text(file));
    snprintf(declared, sizeof declared, "declares %llu bytes", (unsigned long long)real);
    tpk_close(file);
    CHECK_MSG(r == TPK_ERR_DECOMPRESS && strstr(text, "'META'") && strstr(text, declared), "%s: %s",
              tpk_result_string(r), text);
    CHECK_MSG(a.largest < e->raw_size, "asked for %zu bytes of a claimed %llu", a.largest,
              (unsigned long long)e->raw_size);
    e->elem_count = e->raw_size = e->raw_size + 1; /* one byte more than zstd can produce */
    fix_directory(bytes);
    char err[512] = "";
    CHECK_EQ_INT(tpk_open_memory(&file, bytes, size, NULL, err, sizeof err), TPK_ERR_CORRUPT);
    CHECK_MSG(strstr(err, "implausible raw_size") && strstr(err, "'META'"), "%s", err);
    free(bytes);
}

TPK_TEST(allocation_failures)
{
    size_t size;
    uint8_t *bytes = good_bytes(&size, NULL);
    CHECK(bytes != NULL);
    int completed = 0;
    for (long n = 0; n < 1000 && !completed; n++) {
        failing_allocator a = {0, n, 0};
        tpk_result r = open_and_load(bytes, size, &a);
        CHECK_EQ_INT(a.live, 0);
        if (a.allocations <= n) {
            CHECK_EQ_INT(r, TPK_OK);
            completed = 1;
        } else {
            CHECK_MSG(r == TPK_ERR_OUT_OF_MEMORY, "failing allocation %ld gave %d", n, r);
        }
    }
    CHECK(completed);
    free(bytes);
}

TPK_TEST(writer_allocation_failures)
{
    make_sample(&the_sample);
    chunk_src chunks[32];
    int n = sample_chunks(&the_sample, NULL, chunks);
    const char *path = tpk_temp_path("alloc_writer.tpk");
    int completed = 0;
    for (long fail_at = 0; fail_at < 1000 && !completed; fail_at++) {
        failing_allocator a = {0, fail_at, 0};
        tpk_write_options o = {.size = sizeof o, .allocator = {failing_alloc, failing_free, &a}};
        tpk_writer *w;
        tpk_result r = tpk_writer_open(&w, path, &o, NULL, 0);
        for (int k = 0; r == TPK_OK && k < n; k++) {
            r = tpk_writer_add_chunk(w, &chunks[k].desc, chunks[k].data);
            if (r != TPK_OK)
                tpk_writer_abort(w);
        }
        tpk_header_fields h = sample_header();
        if (r == TPK_OK)
            r = tpk_writer_finish(w, &h);
        CHECK_EQ_INT(a.live, 0);
        CHECK_EQ_INT(leftovers(tpk_temp_dir()), 0);
        if (a.allocations <= fail_at) {
            CHECK_EQ_INT(r, TPK_OK);
            completed = 1;
        } else {
            CHECK_MSG(r == TPK_ERR_OUT_OF_MEMORY, "failing allocation %ld gave %d", fail_at, r);
        }
    }
    CHECK(completed);
}

/* ---- fuzz corpus generator ---------------------------------------------------------------------------- */

static int write_bytes(const char *dir, const char *name, const uint8_t *bytes, size_t size)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = fwrite(bytes, 1, size, f) == size;
    return fclose(f) == 0 && ok ? 0 : -1;
}

/* Writes good seeds and every must-fail case into `dir`; returns the number of files written. */
static int write_corpus(const char *dir)
{
    size_t size, extra_size;
    uint8_t *good = good_bytes(&size, NULL);
    build_opts o = {.extra_tag = TPK_FOURCC('x', 't', 'r', 'a')};
    uint8_t *extra = good_bytes(&extra_size, &o);
    int failed = !good || !extra || write_bytes(dir, "good_sample.tpk", good, size) ||
                 write_bytes(dir, "good_unknown_optional.tpk", extra, extra_size);
    free(extra);
    for (size_t k = 0; k < FAIL_CASE_COUNT && !failed; k++) {
        size_t n;
        uint8_t *bytes = mutated(good, size, &fail_cases[k], &n);
        char name[128];
        snprintf(name, sizeof name, "fail_%s.tpk", fail_cases[k].name);
        failed = !bytes || write_bytes(dir, name, bytes, n);
        free(bytes);
    }
    free(good);
    return failed ? -1 : 2 + (int)FAIL_CASE_COUNT;
}

/* With TPK_WRITE_CORPUS=<dir>, writes the fuzz seeds and must-fail files there. Without it, writes them to
 * a temporary folder and checks that the committed corpus (tests/fuzz/corpus/fuzz_reader/) holds exactly
 * these bytes: a change to the writer or to a fail case that is not regenerated fails here. */
TPK_TEST(write_fuzz_corpus)
{
    const char *target = getenv("TPK_WRITE_CORPUS");
    const char *dir = target ? target : tpk_temp_path("corpus");
    if (!target)
        CHECK(mkdir(dir, 0755) == 0);
    int written = write_corpus(dir);
    CHECK_MSG(written > 2, "cannot write the corpus into %s", dir);
    if (target)
        return;
    DIR *d = opendir(dir);
    CHECK(d);
    struct dirent *e;
    int compared = 0, stale = 0;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.')
            continue;
        char made[1024], committed[1024];
        snprintf(made, sizeof made, "%s/%s", dir, e->d_name);
        snprintf(committed, sizeof committed, "%s/tests/fuzz/corpus/fuzz_reader/%s", TPK_SOURCE_DIR, e->d_name);
        size_t a_size, b_size;
        uint8_t *a = read_all(made, &a_size), *b = read_all(committed, &b_size);
        if (!a || !b || a_size != b_size || memcmp(a, b, a_size)) {
            fprintf(stderr, "%s differs from what the test writes\n", committed);
            stale++;
        }
        compared++;
        free(a);
        free(b);
    }
    closedir(d);
    CHECK_EQ_INT(compared, written);
    CHECK_MSG(stale == 0, "%d stale corpus files: regenerate with TPK_WRITE_CORPUS=tests/fuzz/corpus/fuzz_reader", stale);
}

/* The committed must-fail files (tests/fuzz/corpus/fuzz_reader/fail_*.tpk) still fail as their case says. */
TPK_TEST(golden_corpus)
{
    for (size_t k = 0; k < FAIL_CASE_COUNT; k++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/tests/fuzz/corpus/fuzz_reader/fail_%s.tpk", TPK_SOURCE_DIR,
                 fail_cases[k].name);
        size_t size;
        uint8_t *bytes = read_all(path, &size), *copy;
        CHECK_MSG(bytes != NULL, "missing %s", path);
        tpk_file *file = NULL;
        tpk_result r = open_exact(bytes, size, NULL, &file, &copy, NULL, 0);
        tpk_result v = file ? tpk_verify(file) : TPK_OK;
        tpk_close(file);
        free(copy);
        free(bytes);
        CHECK_MSG(r == fail_cases[k].open_result && v == fail_cases[k].verify_result, "%s: %d/%d",
                  fail_cases[k].name, r, v);
    }
    const char *good[2] = {"good_sample.tpk", "good_unknown_optional.tpk"};
    for (int k = 0; k < 2; k++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/tests/fuzz/corpus/fuzz_reader/%s", TPK_SOURCE_DIR, good[k]);
        tpk_file *file;
        CHECK_EQ_INT(tpk_open_path(&file, path, NULL, NULL, 0), TPK_OK);
        CHECK_EQ_INT(tpk_verify(file), TPK_OK);
        tpk_close(file);
    }
}

/* The sample written with every chunk streamed in pieces of `piece` bytes (pieces need not be whole
 * elements) must be byte-identical to the one written with tpk_writer_add_chunk. */
static tpk_result build_streamed(const char *path, size_t piece)
{
    static sample s;
    make_sample(&s);
    build_opts o = {.big = 1};
    chunk_src chunks[32];
    int n = sample_chunks(&s, &o, chunks);
    tpk_writer *w;
    char err[256];
    tpk_result r = tpk_writer_open(&w, path, NULL, err, sizeof err);
    for (int k = 0; r == TPK_OK && k < n; k++) {
        const uint8_t *bytes = chunks[k].data;
        uint64_t total = chunks[k].desc.elem_count * chunks[k].desc.elem_size;
        r = chunks[k].desc.tag == TPK_TAG_FDSC ? tpk_writer_add_chunk(w, &chunks[k].desc, bytes)
                                                : tpk_writer_begin_chunk(w, &chunks[k].desc);
        for (uint64_t at = 0; r == TPK_OK && chunks[k].desc.tag != TPK_TAG_FDSC && at < total; at += piece)
            r = tpk_writer_append(w, bytes + at, total - at < piece ? total - at : piece);
        if (r == TPK_OK && chunks[k].desc.tag != TPK_TAG_FDSC)
            r = tpk_writer_end_chunk(w);
    }
    if (r != TPK_OK) {
        tpk_writer_abort(w);
        return r;
    }
    tpk_header_fields h = sample_header();
    return tpk_writer_finish(w, &h);
}

TPK_TEST(streamed_chunks_match_whole_chunks)
{
    build_opts o = {.big = 1};
    CHECK_EQ_INT(build_file(tpk_temp_path("whole.tpk"), &o), TPK_OK);
    size_t whole_size, streamed_size;
    uint8_t *whole = read_all(tpk_temp_path("whole.tpk"), &whole_size);
    CHECK(whole != NULL);
    const size_t pieces[] = {1, 7, 4096, 1u << 20};
    for (size_t i = 0; i < sizeof pieces / sizeof pieces[0]; i++) {
        CHECK_EQ_INT(build_streamed(tpk_temp_path("streamed.tpk"), pieces[i]), TPK_OK);
        uint8_t *streamed = read_all(tpk_temp_path("streamed.tpk"), &streamed_size);
        int same = streamed && streamed_size == whole_size && !memcmp(streamed, whole, whole_size);
        free(streamed);
        CHECK_MSG(same, "pieces of %zu bytes give a different file", pieces[i]);
    }
    free(whole);
}

TPK_TEST(streamed_chunk_misuse)
{
    static sample s;
    make_sample(&s);
    chunk_src c = chunk(TPK_TAG_POS3, TPK_CODEC_ZSTD, TPK_ELEM_VEC3_F32, 12, SAMPLE_V, s.positions);
    tpk_writer *w;
    char err[256];
    const char *path = tpk_temp_path("misuse.tpk");
    CHECK_EQ_INT(tpk_writer_open(&w, path, NULL, err, sizeof err), TPK_OK);
    CHECK_EQ_INT(tpk_writer_append(w, s.positions, 12), TPK_ERR_BAD_STATE);   /* nothing begun */
    CHECK_EQ_INT(tpk_writer_end_chunk(w), TPK_ERR_BAD_STATE);
    CHECK_EQ_INT(tpk_writer_begin_chunk(w, &c.desc), TPK_OK);
    CHECK_EQ_INT(tpk_writer_begin_chunk(w, &c.desc), TPK_ERR_BAD_STATE);      /* one at a time */
    CHECK_EQ_INT(tpk_writer_add_chunk(w, &c.desc, s.positions), TPK_ERR_BAD_STATE);
    CHECK_EQ_INT(tpk_writer_append(w, s.positions, sizeof s.positions + 1), TPK_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(tpk_writer_append(w, s.positions, 12), TPK_OK);
    CHECK_EQ_INT(tpk_writer_end_chunk(w), TPK_ERR_INVALID_ARGUMENT);          /* 12 of 60 bytes */
    CHECK_EQ_INT(tpk_writer_begin_chunk(w, &c.desc), TPK_OK);
    tpk_header_fields h = sample_header();
    CHECK_EQ_INT(tpk_writer_finish(w, &h), TPK_ERR_BAD_STATE);                /* chunk still open */
    CHECK(access(path, F_OK) != 0);
}
