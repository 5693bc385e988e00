/* Generator of the format's test vectors (samples/vectors/, spec §13). The good files are built from the
 * explicit numbers below with libtetpack's writer; Tet20, Tet16 and the shell are derived from Tet32 by
 * the spec's formulas written out here, not by the converter's code. The must-fail files are one_tet.tpk
 * or two_tets_zstd.tpk with one rule broken by patching bytes. Compiled as part of test_vectors.c (#included there). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <xxhash.h>

#include "tetpack.h"

/* ---- the meshes, as numbers ------------------------------------------------------------------ */

/* one_tet: vertex ids are listed in positive order (1, 2, 3, 0): p1 -> p2 is +x, p1 -> p3 is +y and
 * p1 -> p0 is +z, so det[p2-p1, p3-p1, p0-p1] = det(I) = 1 > 0. */
static const double one_tet_origin[3] = {10.0, 20.0, 30.0};
static const float one_tet_positions[4][3] = {{0, 0, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
static const int32_t one_tet_tets[1][4] = {{1, 2, 3, 0}};
static const int32_t one_tet_neighbors[1][4] = {{-1, -1, -1, -1}};
static const float one_tet_height[4] = {31, 30, 30, 30}; /* world z = origin z + position z */
static const char one_tet_meta[] = "{\"converter\":{\"name\":\"tetpack make_vectors\",\"version\":\"1.0\"}}";

/* two_tets_zstd: tet 0 = (3, 0, 4, 1) is the unit corner tet, tet 1 = (0, 4, 1, 2) lies across the
 * face {0, 4, 1} (the plane x + y + z = 1) with p2 = (1, 1, 1); det for tet 1 is 2 > 0. */
static const double two_tets_origin[3] = {1000000.0, -2.5, 0.0};
static const float two_tets_positions[5][3] = {{1, 0, 0}, {0, 0, 1}, {1, 1, 1}, {0, 0, 0}, {0, 1, 0}};
static const int32_t two_tets_tets[2][4] = {{3, 0, 4, 1}, {0, 4, 1, 2}};
static const int32_t two_tets_neighbors[2][4] = {{1, -1, -1, -1}, {-1, -1, -1, 0}};
static const float two_tets_temperature[2][5] = {{300, 301, 302, 303, 304}, {310, 311, 312, 313, 314}};
static const float two_tets_material[2] = {1, 2};
static const double two_tets_time[2] = {0.0, 0.5};
static const int32_t two_tets_tmap[2] = {7, 9};
static const int32_t two_tets_vmap[5] = {10, 11, 12, 13, 14};
static const char two_tets_note[] = "vendor chunks without the REQUIRED bit are skipped";

#define VECTOR_ZSTD_LEVEL 3

/* ---- layouts by the spec's formulas (§6.3 to §6.6) --------------------------------------------- */

static void spec_tet32(const int32_t v[4], const int32_t n[4], tpk_tet32 *out)
{
    memset(out, 0, sizeof *out);
    for (int k = 0; k < 3; k++)
        out->v[k] = v[k];
    out->vx = v[0] ^ v[1] ^ v[2] ^ v[3];
    for (int k = 0; k < 4; k++)
        out->n[k] = n[k];
}

static int spec_rank(const int32_t v[4], int k)
{
    int rank = 0;
    for (int j = 0; j < 4; j++)
        rank += v[j] < v[k];
    return rank;
}

static void spec_tet20(const int32_t v[4], const int32_t n[4], tpk_tet20 *out)
{
    memset(out, 0, sizeof *out);
    out->vx = v[0] ^ v[1] ^ v[2] ^ v[3];
    for (int k = 0; k < 4; k++)
        out->n[spec_rank(v, k)] = n[k];
}

static void spec_tet16(const tpk_tet20 *in, tpk_tet16 *out)
{
    memset(out, 0, sizeof *out);
    out->vx = in->vx;
    for (int r = 0; r < 3; r++)
        out->nx[r] = (int32_t)((uint32_t)in->n[r] ^ (uint32_t)in->n[3]);
}

/* Outward boundary faces of positively oriented tets, in tet order then face order. Face j is opposite
 * v_j; listed so that (a, c, b, v_j) is an even permutation of (v0, v1, v2, v3). */
static size_t spec_shell(const int32_t (*tets)[4], const int32_t (*neighbors)[4], size_t tet_count,
                         tpk_shell_face *out)
{
    const int (*faces)[3] = tpk_tet_faces; /* the spec's order (tetpack_format.h) */
    size_t count = 0;
    for (size_t t = 0; t < tet_count; t++)
        for (int j = 0; j < 4; j++)
            if (neighbors[t][j] == -1)
                out[count++] = (tpk_shell_face){tets[t][faces[j][0]], tets[t][faces[j][1]],
                                                tets[t][faces[j][2]], (int32_t)t};
    return count;
}

static void spec_field(tpk_field_desc *f, const char *name, const char *units, uint32_t association,
                       uint32_t step_count, float min_value, float max_value)
{
    memset(f, 0, sizeof *f);
    strncpy(f->name, name, sizeof f->name - 1);
    strncpy(f->units, units, sizeof f->units - 1);
    f->association = association;
    f->step_count = step_count;
    f->components = 1;
    f->min_value = min_value;
    f->max_value = max_value;
}

/* ---- writing ---------------------------------------------------------------------------------- */

typedef struct vector_writer {
    tpk_writer *writer;
    int codec;
    tpk_result result;
} vector_writer;

static void put(vector_writer *w, uint32_t tag, int required, tpk_elem_type type, uint32_t elem_size,
                uint64_t count, uint32_t index, uint32_t step, const void *data)
{
    if (w->result != TPK_OK)
        return;
    tpk_chunk_desc d = {0};
    d.tag = tag;
    d.flags = required ? TPK_CHUNK_REQUIRED : 0;
    d.codec = (uint8_t)w->codec;
    d.elem_type = (uint8_t)type;
    d.elem_size = elem_size;
    d.index = index;
    d.step = step;
    d.elem_count = count;
    d.zstd_level = VECTOR_ZSTD_LEVEL;
    w->result = tpk_writer_add_chunk(w->writer, &d, data);
    if (w->result != TPK_OK)
        fprintf(stderr, "make_vectors: add_chunk: %s\n", tpk_writer_error_text(w->writer));
}

static void bounds_of(const float (*pos)[3], size_t n, const double origin[3], tpk_header_fields *h)
{
    for (int k = 0; k < 3; k++) {
        h->origin[k] = origin[k];
        h->bounds_min[k] = h->bounds_max[k] = origin[k] + (double)pos[0][k];
    }
    for (size_t i = 1; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double x = origin[k] + (double)pos[i][k];
            h->bounds_min[k] = x < h->bounds_min[k] ? x : h->bounds_min[k];
            h->bounds_max[k] = x > h->bounds_max[k] ? x : h->bounds_max[k];
        }
}

static tpk_result finish(vector_writer *w, tpk_header_fields *h)
{
    if (w->result != TPK_OK) {
        tpk_writer_abort(w->writer);
        return w->result;
    }
    tpk_result r = tpk_writer_finish(w->writer, h);
    if (r != TPK_OK)
        fprintf(stderr, "make_vectors: finish: %s\n", tpk_result_string(r));
    return r;
}

static tpk_result open_writer(vector_writer *w, const char *path, int codec)
{
    char err[512] = "";
    w->codec = codec;
    w->result = tpk_writer_open(&w->writer, path, NULL, err, sizeof err);
    if (w->result != TPK_OK)
        fprintf(stderr, "make_vectors: %s: %s\n", path, err);
    return w->result;
}

/* one_tet.tpk; with `vendor` set, also an optional chunk 'vndr' (patched to REQUIRED later). */
static tpk_result write_one_tet(const char *path, int vendor)
{
    vector_writer w;
    if (open_writer(&w, path, TPK_CODEC_NONE) != TPK_OK)
        return w.result;
    tpk_tet32 t32;
    tpk_tet20 t20;
    tpk_tet16 t16;
    tpk_shell_face shell[4];
    tpk_field_desc field;
    spec_tet32(one_tet_tets[0], one_tet_neighbors[0], &t32);
    spec_tet20(one_tet_tets[0], one_tet_neighbors[0], &t20);
    spec_tet16(&t20, &t16);
    size_t shell_count = spec_shell(one_tet_tets, one_tet_neighbors, 1, shell);
    spec_field(&field, "height", "m", TPK_ASSOC_POINT, 1, 30.0f, 31.0f);

    put(&w, TPK_TAG_POS3, 1, TPK_ELEM_VEC3_F32, 12, 4, 0, 0, one_tet_positions);
    put(&w, TPK_TAG_TT32, 1, TPK_ELEM_TET32, 32, 1, 0, 0, &t32);
    put(&w, TPK_TAG_TT20, 1, TPK_ELEM_TET20, 20, 1, 0, 0, &t20);
    put(&w, TPK_TAG_TT16, 1, TPK_ELEM_TET16, 16, 1, 0, 0, &t16);
    put(&w, TPK_TAG_SHEL, 1, TPK_ELEM_SHELL_FACE, 16, shell_count, 0, 0, shell);
    put(&w, TPK_TAG_FDSC, 1, TPK_ELEM_FIELD_DESC, 128, 1, 0, 0, &field);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 4, 0, 0, one_tet_height);
    put(&w, TPK_TAG_META, 0, TPK_ELEM_BYTE, 1, strlen(one_tet_meta), 0, 0, one_tet_meta);
    if (vendor)
        put(&w, TPK_FOURCC('v', 'n', 'd', 'r'), 0, TPK_ELEM_BYTE, 1, 4, 0, 0, "vndr");

    tpk_header_fields h = {0};
    h.vertex_count = 4;
    h.tet_count = 1;
    h.shell_face_count = shell_count;
    bounds_of(one_tet_positions, 4, one_tet_origin, &h);
    return finish(&w, &h);
}

/* Format 1.4 (spec §17, §13.6): the culling blocks of the two-tet mesh, written out by hand. B = 16, so
 * ceil(2 / 16) = 1 block; tet 0 = (3, 0, 4, 1) reaches tet 1 across their face {0, 4, 1}, so one seed:
 * tet 0 as (0, 1, 4, 3), an even permutation (smallest first, then the smallest of the other three),
 * with n3 = -1, the face opposite 4 (its largest id) being the shell face {3, 0, 1}; one interval, ids
 * 0 to 4. */
#define TWO_TETS_CULL_N3_WORD 13
static const int32_t two_tets_cull[16] = {
    16, 1, 1, 1, /* block_tets, block_count, seed_count, interval_count */
    0,  1,       /* seed_start */
    0,  1,       /* interval_start */
    0,  0, 1, 4, 3, -1, /* seed: tet, a, b, c, d, n3 */
    0,  5,       /* interval: first, end */
};

/* The two-tet mesh, its fields, TIME, TMAP and VMAP with `codec`; then the vendor chunk `note` (with
 * `note`), a LEVL 1 of `level` bytes (level != NULL) or the CULL chunk of `cull_words` words. */
static tpk_result write_two_tets(const char *path, int codec, int note, const void *level, size_t level_size,
                                 const int32_t *cull, size_t cull_words)
{
    vector_writer w;
    if (open_writer(&w, path, codec) != TPK_OK)
        return w.result;
    tpk_tet32 t32[2];
    tpk_tet20 t20[2];
    tpk_tet16 t16[2];
    tpk_shell_face shell[8];
    tpk_field_desc fields[2];
    for (int t = 0; t < 2; t++) {
        spec_tet32(two_tets_tets[t], two_tets_neighbors[t], &t32[t]);
        spec_tet20(two_tets_tets[t], two_tets_neighbors[t], &t20[t]);
        spec_tet16(&t20[t], &t16[t]);
    }
    size_t shell_count = spec_shell(two_tets_tets, two_tets_neighbors, 2, shell);
    spec_field(&fields[0], "temperature", "K", TPK_ASSOC_POINT, 2, 300.0f, 314.0f);
    spec_field(&fields[1], "material", "", TPK_ASSOC_TET, 1, 1.0f, 2.0f);

    put(&w, TPK_TAG_POS3, 1, TPK_ELEM_VEC3_F32, 12, 5, 0, 0, two_tets_positions);
    put(&w, TPK_TAG_TT32, 1, TPK_ELEM_TET32, 32, 2, 0, 0, t32);
    put(&w, TPK_TAG_TT20, 1, TPK_ELEM_TET20, 20, 2, 0, 0, t20);
    put(&w, TPK_TAG_TT16, 1, TPK_ELEM_TET16, 16, 2, 0, 0, t16);
    put(&w, TPK_TAG_SHEL, 1, TPK_ELEM_SHELL_FACE, 16, shell_count, 0, 0, shell);
    put(&w, TPK_TAG_FDSC, 1, TPK_ELEM_FIELD_DESC, 128, 2, 0, 0, fields);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 5, 0, 0, two_tets_temperature[0]);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 5, 0, 1, two_tets_temperature[1]);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 2, 1, 0, two_tets_material);
    put(&w, TPK_TAG_TIME, 0, TPK_ELEM_F64, 8, 2, 0, 0, two_tets_time);
    put(&w, TPK_TAG_TMAP, 0, TPK_ELEM_I32, 4, 2, 0, 0, two_tets_tmap);
    put(&w, TPK_TAG_VMAP, 0, TPK_ELEM_I32, 4, 5, 0, 0, two_tets_vmap);
    if (note)
        put(&w, TPK_FOURCC('n', 'o', 't', 'e'), 0, TPK_ELEM_BYTE, 1, strlen(two_tets_note), 0, 0, two_tets_note);
    if (level)
        put(&w, TPK_TAG_LEVL, 0, TPK_ELEM_BYTE, 1, level_size, 1, 0, level);
    if (cull)
        put(&w, TPK_TAG_CULL, 0, TPK_ELEM_I32, 4, cull_words, 0, 0, cull);

    tpk_header_fields h = {0};
    h.vertex_count = 5;
    h.tet_count = 2;
    h.shell_face_count = shell_count;
    bounds_of(two_tets_positions, 5, two_tets_origin, &h);
    return finish(&w, &h);
}

static tpk_result write_two_tets_zstd(const char *path)
{
    return write_two_tets(path, TPK_CODEC_ZSTD, 1, NULL, 0, NULL, 0);
}

/* ---- must-fail files: patched bytes ------------------------------------------------------------ */

typedef struct byte_buffer {
    uint8_t *data;
    size_t size;
} byte_buffer;

static int load_bytes(const char *path, byte_buffer *out)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    out->data = malloc(size > 0 ? (size_t)size : 1);
    out->size = size > 0 ? (size_t)size : 0;
    int ok = out->data && fread(out->data, 1, out->size, f) == out->size;
    fclose(f);
    return ok ? 0 : -1;
}

static int save_bytes(const char *path, const uint8_t *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = fwrite(data, 1, size, f) == size;
    return fclose(f) == 0 && ok ? 0 : -1;
}

static tpk_header *header_of(byte_buffer *b)
{
    return (tpk_header *)b->data; /* malloc'ed, so aligned; the host is little-endian (internal_file.h) */
}

static tpk_dir_entry *entry_of(byte_buffer *b, uint32_t tag)
{
    tpk_header *h = header_of(b);
    tpk_dir_entry *e = (tpk_dir_entry *)(b->data + h->directory_offset);
    for (uint64_t i = 0; i < h->chunk_count; i++)
        if (e[i].tag == tag)
            return &e[i];
    return NULL;
}

static void reseal(byte_buffer *b)
{
    tpk_header *h = header_of(b);
    h->directory_checksum = XXH64(b->data + h->directory_offset, h->chunk_count * TPK_DIR_ENTRY_SIZE, 0);
    h->header_checksum = XXH64(b->data, offsetof(tpk_header, header_checksum), 0);
}

static int make_broken(const char *dir, const char *name, const char *one_tet_path,
                       int (*patch)(byte_buffer *b))
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    byte_buffer b = {0};
    int rc = load_bytes(one_tet_path, &b);
    if (rc == 0)
        rc = patch(&b);
    if (rc == 0)
        rc = save_bytes(path, b.data, b.size);
    if (rc != 0)
        fprintf(stderr, "make_vectors: cannot make %s\n", path);
    free(b.data);
    return rc;
}

/* A text-mode transfer turned the magic's CR LF into LF: one byte fewer. */
static int patch_bad_magic(byte_buffer *b)
{
    memmove(b->data + 4, b->data + 5, b->size - 5);
    b->size--;
    return 0;
}

static int patch_truncated(byte_buffer *b)
{
    if (b->size <= 256)
        return -1;
    b->size = 256;
    return 0;
}

static int patch_newer_major(byte_buffer *b)
{
    header_of(b)->version_major = 2;
    reseal(b);
    return 0;
}

static int patch_required(byte_buffer *b)
{
    tpk_dir_entry *e = entry_of(b, TPK_FOURCC('v', 'n', 'd', 'r'));
    if (!e)
        return -1;
    e->flags |= TPK_CHUNK_REQUIRED;
    reseal(b);
    return 0;
}

/* 31.0f (00 00 F8 41) of vertex 0 becomes 31.000002f (01 00 F8 41); the stored checksum stays. */
static int patch_chunk_checksum(byte_buffer *b)
{
    tpk_dir_entry *e = entry_of(b, TPK_TAG_FDAT);
    if (!e)
        return -1;
    b->data[e->offset] ^= 0x01;
    return 0;
}

static int patch_overlap(byte_buffer *b)
{
    tpk_dir_entry *fdat = entry_of(b, TPK_TAG_FDAT), *pos3 = entry_of(b, TPK_TAG_POS3);
    if (!fdat || !pos3)
        return -1;
    fdat->offset = pos3->offset;
    reseal(b);
    return 0;
}

/* Rule 16 (spec §4.2): POS3's one zstd frame followed by an empty skippable frame (magic 0x184D2A50,
 * size 0) in the padding after it. zstd's decoder skips it; a compliant reader refuses the chunk. */
static int patch_zstd_skippable(byte_buffer *b)
{
    static const uint8_t skippable[8] = {0x50, 0x2A, 0x4D, 0x18, 0, 0, 0, 0};
    tpk_header *h = header_of(b);
    tpk_dir_entry *e = (tpk_dir_entry *)(b->data + h->directory_offset);
    /* The writer stores chunks in entry order, so entry 1 starts where entry 0's padding ends. */
    if (e[0].tag != TPK_TAG_POS3 || e[1].offset < e[0].offset + e[0].stored_size + sizeof skippable)
        return -1;
    memcpy(b->data + e[0].offset + e[0].stored_size, skippable, sizeof skippable);
    e[0].stored_size += sizeof skippable;
    reseal(b);
    return 0;
}

/* Rule 16 through the decoded bytes of a zstd chunk: POS3's checksum no longer matches them. */
static int patch_zstd_checksum(byte_buffer *b)
{
    tpk_dir_entry *e = entry_of(b, TPK_TAG_POS3);
    if (!e)
        return -1;
    e->checksum ^= 1;
    reseal(b);
    return 0;
}

/* Rule 10 (format 1.1): the vendor chunk 'note' claims more bytes than any zstd frame of its stored
 * size can decode to (32768 per stored byte). */
static int patch_implausible_size(byte_buffer *b)
{
    tpk_dir_entry *e = entry_of(b, TPK_FOURCC('n', 'o', 't', 'e'));
    if (!e)
        return -1;
    e->elem_count = e->raw_size = e->stored_size * 32768 + 1;
    reseal(b);
    return 0;
}

/* Format 1.3 (spec §16): two_tets_levels.tpk is two_tets_zstd.tpk's mesh, uncompressed, with one level of
 * detail: tet 0 of the two alone ({3, 0, 4, 1}: old vertices 0, 1, 3, 4 renumbered 0..3 in their order),
 * its fields gathered (temperature at those vertices, material of tet 0), TIME, TMAP and VMAP mapped.
 * With `same` the level is the parent's own mesh (level_not_coarser.tpk: check 615). */
static const float level_positions[4][3] = {{1, 0, 0}, {0, 0, 1}, {0, 0, 0}, {0, 1, 0}};
static const int32_t level_tets[1][4] = {{2, 0, 3, 1}};
static const int32_t level_neighbors[1][4] = {{-1, -1, -1, -1}};
static const float level_temperature[2][4] = {{300, 301, 303, 304}, {310, 311, 313, 314}};
static const float level_material[1] = {1};
static const int32_t level_tmap[1] = {7};
static const int32_t level_vmap[4] = {10, 11, 13, 14};

static tpk_result write_level_one(const char *path)
{
    vector_writer w;
    if (open_writer(&w, path, TPK_CODEC_NONE) != TPK_OK)
        return w.result;
    tpk_tet32 t32;
    tpk_tet20 t20;
    tpk_tet16 t16;
    tpk_shell_face shell[4];
    tpk_field_desc fields[2];
    spec_tet32(level_tets[0], level_neighbors[0], &t32);
    spec_tet20(level_tets[0], level_neighbors[0], &t20);
    spec_tet16(&t20, &t16);
    size_t shell_count = spec_shell(level_tets, level_neighbors, 1, shell);
    spec_field(&fields[0], "temperature", "K", TPK_ASSOC_POINT, 2, 300.0f, 314.0f);
    spec_field(&fields[1], "material", "", TPK_ASSOC_TET, 1, 1.0f, 1.0f);
    put(&w, TPK_TAG_POS3, 1, TPK_ELEM_VEC3_F32, 12, 4, 0, 0, level_positions);
    put(&w, TPK_TAG_TT32, 1, TPK_ELEM_TET32, 32, 1, 0, 0, &t32);
    put(&w, TPK_TAG_TT20, 1, TPK_ELEM_TET20, 20, 1, 0, 0, &t20);
    put(&w, TPK_TAG_TT16, 1, TPK_ELEM_TET16, 16, 1, 0, 0, &t16);
    put(&w, TPK_TAG_SHEL, 1, TPK_ELEM_SHELL_FACE, 16, shell_count, 0, 0, shell);
    put(&w, TPK_TAG_FDSC, 1, TPK_ELEM_FIELD_DESC, 128, 2, 0, 0, fields);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 4, 0, 0, level_temperature[0]);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 4, 0, 1, level_temperature[1]);
    put(&w, TPK_TAG_FDAT, 1, TPK_ELEM_F32, 4, 1, 1, 0, level_material);
    put(&w, TPK_TAG_TIME, 0, TPK_ELEM_F64, 8, 2, 0, 0, two_tets_time);
    put(&w, TPK_TAG_TMAP, 0, TPK_ELEM_I32, 4, 1, 0, 0, level_tmap);
    put(&w, TPK_TAG_VMAP, 0, TPK_ELEM_I32, 4, 4, 0, 0, level_vmap);
    tpk_header_fields h = {0};
    h.vertex_count = 4;
    h.tet_count = 1;
    h.shell_face_count = shell_count;
    bounds_of(level_positions, 4, two_tets_origin, &h);
    return finish(&w, &h);
}

/* The two-tet mesh, uncompressed, with `level`'s bytes as LEVL 1. */
static tpk_result write_two_tets_levels(const char *path, const char *level)
{
    byte_buffer lb = {0};
    if (load_bytes(level, &lb) != 0)
        return TPK_ERR_IO;
    tpk_result r = write_two_tets(path, TPK_CODEC_NONE, 0, lb.data, lb.size, NULL, 0);
    free(lb.data);
    return r;
}

/* Rule 14 (format 1.3): the LEVL chunk's codec byte says zstd (its bytes are the plain file). */
static int patch_level_zstd(byte_buffer *b)
{
    tpk_dir_entry *e = entry_of(b, TPK_TAG_LEVL);
    if (!e)
        return -1;
    e->codec = TPK_CODEC_ZSTD;
    reseal(b);
    return 0;
}

/* Format 1.4: word `word` of the (uncompressed) CULL chunk set to `value`, its checksum recomputed. */
static int patch_cull_word(byte_buffer *b, uint64_t word, int32_t value)
{
    tpk_dir_entry *e = entry_of(b, TPK_TAG_CULL);
    if (!e || e->codec != TPK_CODEC_NONE || word >= e->elem_count)
        return -1;
    memcpy(b->data + e->offset + 4 * word, &value, sizeof value);
    e->checksum = XXH64(b->data + e->offset, e->raw_size, 0);
    reseal(b);
    return 0;
}

/* TPK-B01 (check 616): the seed's n3 = 1, within rule 17 ([-1, T)), but tet 0's neighbor opposite 4 is -1. */
static int patch_cull_bad_seed(byte_buffer *b)
{
    return patch_cull_word(b, TWO_TETS_CULL_N3_WORD, 1);
}

/* Rule 17 (format 1.4): block_count = 2, not ceil(2 / 16) = 1. */
static int patch_cull_block_count(byte_buffer *b)
{
    return patch_cull_word(b, 1, 2);
}

/* Rule 5 (format 1.1): origin[0] = +infinity. */
static int patch_nonfinite_origin(byte_buffer *b)
{
    header_of(b)->origin[0] = INFINITY;
    reseal(b);
    return 0;
}

/* Rule 14 (format 1.1): an FDSC of no fields. The FDAT chunk becomes an unknown optional chunk 'xdat',
 * so no other rule is broken. */
static int patch_empty_fdsc(byte_buffer *b)
{
    tpk_dir_entry *fdsc = entry_of(b, TPK_TAG_FDSC), *fdat = entry_of(b, TPK_TAG_FDAT);
    if (!fdsc || !fdat)
        return -1;
    memset(b->data + fdsc->offset, 0, fdsc->stored_size); /* now padding */
    fdsc->elem_count = fdsc->raw_size = fdsc->stored_size = 0;
    fdsc->checksum = XXH64(NULL, 0, 0);
    fdat->tag = TPK_FOURCC('x', 'd', 'a', 't');
    fdat->flags = 0;
    reseal(b);
    return 0;
}

/* Rule 17 (format 1.1): Tet16's vx = 4 with 4 vertices; ids in [0, 4) xor to at most 3. The chunk's
 * checksum is recomputed, so only the id rule catches it. */
static int patch_tet16_vx(byte_buffer *b)
{
    tpk_dir_entry *e = entry_of(b, TPK_TAG_TT16);
    if (!e || e->codec != TPK_CODEC_NONE)
        return -1;
    tpk_tet16 tet;
    memcpy(&tet, b->data + e->offset, sizeof tet);
    tet.vx = 4;
    memcpy(b->data + e->offset, &tet, sizeof tet);
    e->checksum = XXH64(b->data + e->offset, e->raw_size, 0);
    reseal(b);
    return 0;
}

/* ---- part sets (spec §13.4, §15) --------------------------------------------------------------- */

/* two_tets cut between its tets: part p keeps whole vertices part_vertices[p] (in the whole's order,
 * renumbered 0..3) and its tet; the face {0, 4, 1} of the whole is on the cut. */
static const int part_vertices[2][4] = {{0, 1, 3, 4}, {0, 1, 2, 4}};
static const int32_t part_tets[2][1][4] = {{{2, 0, 3, 1}}, {{0, 3, 1, 2}}};
static const int32_t part_neighbors[1][4] = {{-1, -1, -1, -1}};

static tpk_result write_part(const char *path, int p, const tpk_link *link, tpk_part_record *record)
{
    vector_writer w;
    if (open_writer(&w, path, TPK_CODEC_NONE) != TPK_OK)
        return w.result;
    float pos[4][3];
    for (int i = 0; i < 4; i++)
        memcpy(pos[i], two_tets_positions[part_vertices[p][i]], sizeof pos[i]);
    tpk_tet32 t32;
    tpk_shell_face shell[4];
    spec_tet32(part_tets[p][0], part_neighbors[0], &t32);
    size_t shell_count = spec_shell(part_tets[p], part_neighbors, 1, shell);
    put(&w, TPK_TAG_POS3, 1, TPK_ELEM_VEC3_F32, 12, 4, 0, 0, pos);
    put(&w, TPK_TAG_TT32, 1, TPK_ELEM_TET32, 32, 1, 0, 0, &t32);
    put(&w, TPK_TAG_SHEL, 1, TPK_ELEM_SHELL_FACE, 16, shell_count, 0, 0, shell);
    put(&w, TPK_TAG_LINK, 0, TPK_ELEM_I32, 4, 4, 0, 0, link);
    tpk_header_fields h = {0};
    h.vertex_count = 4;
    h.tet_count = 1;
    h.shell_face_count = shell_count;
    bounds_of((const float(*)[3])pos, 4, two_tets_origin, &h);
    tpk_result r = finish(&w, &h);
    byte_buffer b = {0};
    if (r == TPK_OK && load_bytes(path, &b) != 0)
        r = TPK_ERR_IO;
    if (r == TPK_OK) {
        const tpk_header *written = (const tpk_header *)b.data;
        record->file_size = written->file_size;
        record->header_checksum = written->header_checksum;
        record->vertex_count = 4;
        record->tet_count = 1;
        record->shell_face_count = shell_count;
        record->link_count = 1;
        memcpy(record->bounds_min, h.bounds_min, sizeof h.bounds_min);
        memcpy(record->bounds_max, h.bounds_max, sizeof h.bounds_max);
    }
    free(b.data);
    return r;
}

/* NAME.tpkset and NAME-0.tpk, NAME-1.tpk; `other_face_of_1` is what part 1's link names (0 is right). */
static tpk_result write_part_set(const char *dir, const char *name, int32_t other_face_of_1)
{
    const tpk_link links[2] = {{0, 1, 3, 0}, {3, 0, other_face_of_1, 0}};
    tpk_part_record records[2];
    memset(records, 0, sizeof records);
    char path[1024];
    for (int p = 0; p < 2; p++) {
        snprintf(records[p].file, sizeof records[p].file, "%s-%d.tpk", name, p);
        snprintf(path, sizeof path, "%s/%s", dir, records[p].file);
        if (write_part(path, p, &links[p], &records[p]) != TPK_OK)
            return TPK_ERR_IO;
    }
    snprintf(path, sizeof path, "%s/%s.tpkset", dir, name);
    vector_writer w;
    if (open_writer(&w, path, TPK_CODEC_NONE) != TPK_OK)
        return w.result;
    static const char meta[] = "{\"converter\":{\"name\":\"tetpack make_vectors\",\"version\":\"1.2\"}}";
    put(&w, TPK_TAG_POS3, 1, TPK_ELEM_VEC3_F32, 12, 0, 0, 0, NULL);
    put(&w, TPK_TAG_TT32, 1, TPK_ELEM_TET32, 32, 0, 0, 0, NULL);
    put(&w, TPK_TAG_SHEL, 1, TPK_ELEM_SHELL_FACE, 16, 0, 0, 0, NULL);
    put(&w, TPK_TAG_PART, 0, TPK_ELEM_BYTE, 1, sizeof records, 0, 0, records);
    put(&w, TPK_TAG_META, 0, TPK_ELEM_BYTE, 1, strlen(meta), 0, 0, meta);
    tpk_header_fields h = {0};
    memcpy(h.origin, two_tets_origin, sizeof h.origin);
    return finish(&w, &h);
}

/* Write every vector into `dir`. Returns 0 on success. */
static int tpk_make_vectors(const char *dir)
{
    char one_tet[1024], path[1024], vendor[1024];
    snprintf(one_tet, sizeof one_tet, "%s/one_tet.tpk", dir);
    if (write_one_tet(one_tet, 0) != TPK_OK)
        return -1;
    snprintf(path, sizeof path, "%s/two_tets_zstd.tpk", dir);
    if (write_two_tets_zstd(path) != TPK_OK)
        return -1;
    char two_tets[1024];
    snprintf(two_tets, sizeof two_tets, "%s", path);
    int rc = make_broken(dir, "bad_magic.tpk", one_tet, patch_bad_magic);
    rc |= make_broken(dir, "truncated.tpk", one_tet, patch_truncated);
    rc |= make_broken(dir, "newer_major.tpk", one_tet, patch_newer_major);
    rc |= make_broken(dir, "chunk_checksum.tpk", one_tet, patch_chunk_checksum);
    rc |= make_broken(dir, "overlap.tpk", one_tet, patch_overlap);
    rc |= make_broken(dir, "nonfinite_origin.tpk", one_tet, patch_nonfinite_origin);
    rc |= make_broken(dir, "empty_fdsc.tpk", one_tet, patch_empty_fdsc);
    rc |= make_broken(dir, "tet16_vx.tpk", one_tet, patch_tet16_vx);
    rc |= make_broken(dir, "zstd_skippable_frame.tpk", two_tets, patch_zstd_skippable);
    rc |= make_broken(dir, "zstd_chunk_checksum.tpk", two_tets, patch_zstd_checksum);
    rc |= make_broken(dir, "implausible_zstd_size.tpk", two_tets, patch_implausible_size);
    snprintf(vendor, sizeof vendor, "%s/one_tet_vendor.tmp", dir);
    if (write_one_tet(vendor, 1) != TPK_OK)
        return -1;
    rc |= make_broken(dir, "unknown_required_chunk.tpk", vendor, patch_required);
    remove(vendor);
    rc |= write_part_set(dir, "two_parts", 0) != TPK_OK;
    rc |= write_part_set(dir, "bad_link", 1) != TPK_OK;
    /* format 1.3: a file with a level; its level not coarser (615); its level compressed (rule 14) */
    char level[1024], levels[1024], same[1024];
    snprintf(level, sizeof level, "%s/level_one.tmp", dir);
    snprintf(levels, sizeof levels, "%s/two_tets_levels.tpk", dir);
    snprintf(same, sizeof same, "%s/two_tets_plain.tmp", dir);
    rc |= write_level_one(level) != TPK_OK;
    rc |= write_two_tets_levels(levels, level) != TPK_OK;
    rc |= write_two_tets_levels(same, levels) != TPK_OK; /* LEVL 1: a file of two tets, as many as its parent */
    if (rc == 0) {
        char dst[1024];
        snprintf(dst, sizeof dst, "%s/level_not_coarser.tpk", dir);
        rc |= rename(same, dst) != 0;
    }
    rc |= make_broken(dir, "level_zstd.tpk", levels, patch_level_zstd);
    remove(level);
    /* format 1.4: a file with culling blocks; a seed's n3 wrong (616); a block count wrong (rule 17) */
    char cull[1024];
    snprintf(cull, sizeof cull, "%s/two_tets_cull.tpk", dir);
    rc |= write_two_tets(cull, TPK_CODEC_NONE, 0, NULL, 0, two_tets_cull,
                         sizeof two_tets_cull / sizeof two_tets_cull[0]) != TPK_OK;
    rc |= make_broken(dir, "cull_bad_seed.tpk", cull, patch_cull_bad_seed);
    rc |= make_broken(dir, "cull_block_count.tpk", cull, patch_cull_block_count);
    return rc;
}
