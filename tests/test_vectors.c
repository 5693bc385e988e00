/* The format's test vectors (spec §13, samples/vectors/): regenerated files equal the committed ones,
 * good files decode to the numbers in samples/vectors/README.md, bad files give their exact result.
 * TPK_REGENERATE_VECTORS=1 in the environment rewrites the committed files instead of comparing. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <zstd.h>

#include "harness.h"
#include "convert/pipeline.h"
#include "make_vectors.c"
#include "tetpack.h"

#define VECTOR_DIR TPK_SOURCE_DIR "/samples/vectors"
/* zstd does not promise identical output across versions: compressed vectors are compared byte for
 * byte only with the version that made them (all other checks still run). */
#define VECTOR_ZSTD_VERSION 10504

static const char *const vector_names[] = {
    "one_tet.tpk",     "two_tets_zstd.tpk",          "bad_magic.tpk",      "truncated.tpk",
    "newer_major.tpk", "unknown_required_chunk.tpk", "chunk_checksum.tpk", "overlap.tpk",
    "nonfinite_origin.tpk", "empty_fdsc.tpk", "tet16_vx.tpk", "zstd_skippable_frame.tpk",
    "zstd_chunk_checksum.tpk", "implausible_zstd_size.tpk", "two_parts.tpkset", "two_parts-0.tpk",
    "two_parts-1.tpk", "bad_link.tpkset", "bad_link-0.tpk", "bad_link-1.tpk", "two_tets_levels.tpk",
    "level_not_coarser.tpk", "level_zstd.tpk", "two_tets_cull.tpk", "cull_bad_seed.tpk", "cull_block_count.tpk",
};

static const char *vector_path(const char *name)
{
    static char buf[4][1024];
    static int next;
    next = (next + 1) % 4;
    snprintf(buf[next], sizeof buf[next], "%s/%s", VECTOR_DIR, name);
    return buf[next];
}

static int same_bytes(const char *a, const char *b)
{
    byte_buffer x = {0}, y = {0};
    int same = load_bytes(a, &x) == 0 && load_bytes(b, &y) == 0 && x.size == y.size &&
               memcmp(x.data, y.data, x.size) == 0;
    free(x.data);
    free(y.data);
    return same;
}

TPK_TEST(vectors_match)
{
    const char *regenerate = getenv("TPK_REGENERATE_VECTORS");
    if (regenerate && strcmp(regenerate, "1") == 0) {
        CHECK_EQ_INT(tpk_make_vectors(VECTOR_DIR), 0);
        fprintf(stderr, "rewrote the vectors in %s\n", VECTOR_DIR);
        return;
    }
    CHECK_EQ_INT(tpk_make_vectors(tpk_temp_dir()), 0);
    for (size_t i = 0; i < sizeof vector_names / sizeof vector_names[0]; i++) {
        const char *name = vector_names[i];
        if (strstr(name, "zstd") && ZSTD_versionNumber() != VECTOR_ZSTD_VERSION) {
            fprintf(stderr, "note: zstd %u, vectors made with %u: not comparing %s byte for byte\n",
                    ZSTD_versionNumber(), VECTOR_ZSTD_VERSION, name);
            continue;
        }
        CHECK_MSG(same_bytes(tpk_temp_path(name), vector_path(name)),
                  "%s differs from the committed vector (a format or writer change? see spec §13; "
                  "TPK_REGENERATE_VECTORS=1 rewrites them)", name);
    }
}

/* ---- decoding the good vectors ---------------------------------------------------------------- */

/* Sign of det[b-a, c-a, d-a] on the stored positions, exact (the converter's predicate). */
static double orient_ids(const float *pos, int32_t a, int32_t b, int32_t c, int32_t d)
{
    double p[4][3];
    const int32_t id[4] = {a, b, c, d};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            p[i][k] = pos[3 * id[i] + k];
    return tpk_orient3d_exact(p[0], p[1], p[2], p[3]);
}

/* Read chunk (tag, index, step) into dst, which must be exactly its raw size. */
static tpk_result read_tagged(tpk_file *file, uint32_t tag, uint32_t index, uint32_t step, void *dst,
                              uint64_t size, tpk_dir_entry *entry)
{
    uint64_t i;
    tpk_result r = tpk_find_chunk(file, tag, index, step, &i);
    if (r == TPK_OK)
        r = tpk_get_chunk(file, i, entry);
    if (r == TPK_OK && entry->raw_size != size)
        return TPK_ERR_CORRUPT;
    return r == TPK_OK ? tpk_read_chunk(file, i, dst, size) : r;
}

typedef struct expected_mesh {
    const double *origin, *bounds_min, *bounds_max;
    uint64_t vertex_count, tet_count, shell_face_count, chunk_count;
    const float *positions;
    const int32_t *tets;  /* 4 per tet, the stored positive order */
    const tpk_tet32 *tet32;
    const tpk_tet20 *tet20;
    const tpk_tet16 *tet16;
    const tpk_shell_face *shell;
    uint8_t codec;
} expected_mesh;

static int same_set(const int32_t *a, const int32_t *b)
{
    for (int i = 0; i < 4; i++) {
        int found = 0;
        for (int j = 0; j < 4; j++)
            found |= a[i] == b[j];
        if (!found)
            return 0;
    }
    return 1;
}

static void check_recover(tpk_file *file, const expected_mesh *m, const float *positions)
{
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    for (int l = 0; l < 3; l++) {
        tpk_mesh_arrays arrays;
        CHECK_EQ_INT(tpk_load_arrays(file, layouts[l], NULL, 0, &arrays), TPK_OK);
        CHECK_EQ_INT(arrays.tet_count, m->tet_count);
        int32_t got[8];
        CHECK(m->tet_count <= 2);
        CHECK_EQ_INT(tpk_recover_tets(&arrays, got), TPK_OK);
        for (uint64_t t = 0; t < m->tet_count; t++) {
            const int32_t *g = &got[4 * t];
            CHECK_MSG(same_set(g, &m->tets[4 * t]), "layout %d tet %d: vertices differ", layouts[l], (int)t);
            CHECK_MSG(orient_ids(positions, g[0], g[1], g[2], g[3]) > 0, "layout %d tet %d: not positive",
                      layouts[l], (int)t);
        }
    }
}

/* Header, positions, the three layouts, the shell, the geometry rules, and recovery from each layout. */
static void check_mesh(tpk_file *file, const expected_mesh *m)
{
    tpk_file_info info;
    CHECK_EQ_INT(tpk_get_info(file, &info), TPK_OK);
    CHECK_EQ_INT(info.version_major, 1);
    CHECK_EQ_INT(info.version_minor, 1);
    CHECK_EQ_INT(info.vertex_count, m->vertex_count);
    CHECK_EQ_INT(info.tet_count, m->tet_count);
    CHECK_EQ_INT(info.shell_face_count, m->shell_face_count);
    CHECK_EQ_INT(info.chunk_count, m->chunk_count);
    for (int k = 0; k < 3; k++) {
        CHECK(info.origin[k] == m->origin[k]);
        CHECK(info.bounds_min[k] == m->bounds_min[k]);
        CHECK(info.bounds_max[k] == m->bounds_max[k]);
    }
    for (uint64_t i = 0; i < info.chunk_count; i++) {
        tpk_dir_entry e;
        CHECK_EQ_INT(tpk_get_chunk(file, i, &e), TPK_OK);
        CHECK_EQ_INT(e.codec, m->codec);
        CHECK_EQ_INT(e.offset % 64, 0);
    }
    tpk_dir_entry e;
    float pos[3 * 5];
    tpk_tet32 t32[2];
    tpk_tet20 t20[2];
    tpk_tet16 t16[2];
    tpk_shell_face shell[6];
    CHECK(m->vertex_count <= 5 && m->tet_count <= 2 && m->shell_face_count <= 6);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_POS3, 0, 0, pos, 12 * m->vertex_count, &e), TPK_OK);
    CHECK(memcmp(pos, m->positions, 12 * m->vertex_count) == 0);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_TT32, 0, 0, t32, 32 * m->tet_count, &e), TPK_OK);
    CHECK(memcmp(t32, m->tet32, 32 * m->tet_count) == 0);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_TT20, 0, 0, t20, 20 * m->tet_count, &e), TPK_OK);
    CHECK(memcmp(t20, m->tet20, 20 * m->tet_count) == 0);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_TT16, 0, 0, t16, 16 * m->tet_count, &e), TPK_OK);
    CHECK(memcmp(t16, m->tet16, 16 * m->tet_count) == 0);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_SHEL, 0, 0, shell, 16 * m->shell_face_count, &e), TPK_OK);
    CHECK(memcmp(shell, m->shell, 16 * m->shell_face_count) == 0);

    for (uint64_t t = 0; t < m->tet_count; t++) {
        const int32_t *v = &m->tets[4 * t];
        CHECK_MSG(orient_ids(pos, v[0], v[1], v[2], v[3]) > 0, "tet %d is not positive (TPK-M02)", (int)t);
        CHECK_EQ_INT(t32[t].vx ^ t32[t].v[0] ^ t32[t].v[1] ^ t32[t].v[2], v[3]);
    }
    for (uint64_t s = 0; s < m->shell_face_count; s++) {
        const tpk_shell_face *f = &shell[s];
        int32_t x = t32[f->t].vx ^ f->a ^ f->b ^ f->c;
        CHECK_MSG(orient_ids(pos, f->a, f->c, f->b, x) > 0, "shell face %d is not outward (TPK-M10)", (int)s);
    }
    tpk_result verified = tpk_verify(file);
    CHECK_MSG(verified == TPK_OK, "tpk_verify: %s", tpk_error_text(file));
    check_recover(file, m, pos);
}

static void check_field(tpk_file *file, uint32_t i, const char *name, const char *units, uint32_t association,
                        uint32_t steps, float min_value, float max_value)
{
    tpk_field_desc f;
    uint32_t found;
    CHECK_EQ_INT(tpk_get_field(file, i, &f), TPK_OK);
    CHECK(strcmp(f.name, name) == 0);
    CHECK(strcmp(f.units, units) == 0);
    CHECK_EQ_INT(f.association, association);
    CHECK_EQ_INT(f.step_count, steps);
    CHECK_EQ_INT(f.components, 1);
    CHECK(f.min_value == min_value && f.max_value == max_value);
    CHECK_EQ_INT(tpk_find_field(file, name, &found), TPK_OK);
    CHECK_EQ_INT(found, i);
}

/* Open a committed vector; the error text is printed when `expected` differs from the result. */
static tpk_file *open_vector(const char *name, uint32_t flags, tpk_result expected, tpk_result *result)
{
    tpk_open_options options = {0};
    options.size = sizeof options;
    options.flags = flags;
    tpk_file *file = NULL;
    char err[512] = "";
    *result = tpk_open_path(&file, vector_path(name), &options, err, sizeof err);
    if (*result != expected)
        fprintf(stderr, "%s: %s (%s)\n", name, tpk_result_string(*result), err);
    return file;
}

/* The numbers of samples/vectors/README.md, written out again rather than taken from the generator. */
TPK_TEST(vectors_one_tet)
{
    static const double origin[3] = {10, 20, 30}, lo[3] = {10, 20, 30}, hi[3] = {11, 21, 31};
    static const float positions[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const int32_t tets[4] = {1, 2, 3, 0};
    static const tpk_tet32 tet32 = {{1, 2, 3}, 0, {-1, -1, -1, -1}};
    static const tpk_tet20 tet20 = {0, {-1, -1, -1, -1}};
    static const tpk_tet16 tet16 = {0, {0, 0, 0}};
    static const tpk_shell_face shell[4] = {{2, 3, 0, 0}, {1, 0, 3, 0}, {1, 2, 0, 0}, {1, 3, 2, 0}};
    static const float height[4] = {31, 30, 30, 30};
    static const char meta[] = "{\"converter\":{\"name\":\"tetpack make_vectors\",\"version\":\"1.0\"}}";
    const expected_mesh m = {origin, lo, hi, 4, 1, 4, 8, positions, tets, &tet32, &tet20, &tet16, shell,
                             TPK_CODEC_NONE};

    tpk_result r;
    tpk_file *file = open_vector("one_tet.tpk", TPK_OPEN_VERIFY_ALL, TPK_OK, &r);
    CHECK_EQ_INT(r, TPK_OK);
    check_mesh(file, &m);
    CHECK_EQ_INT(tpk_field_count(file), 1);
    check_field(file, 0, "height", "m", TPK_ASSOC_POINT, 1, 30.0f, 31.0f);
    float values[4];
    char text[sizeof meta];
    tpk_dir_entry e;
    double time;
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_FDAT, 0, 0, values, sizeof values, &e), TPK_OK);
    CHECK(memcmp(values, height, sizeof values) == 0);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_META, 0, 0, text, sizeof meta - 1, &e), TPK_OK);
    CHECK(memcmp(text, meta, sizeof meta - 1) == 0);
    CHECK_EQ_INT(tpk_get_time(file, 0, &time), TPK_ERR_NOT_FOUND);
    /* Uncompressed chunks are zero-copy views. */
    const void *view;
    uint64_t size, i;
    CHECK_EQ_INT(tpk_find_chunk(file, TPK_TAG_TT16, 0, 0, &i), TPK_OK);
    CHECK_EQ_INT(tpk_view_chunk(file, i, &view, &size), TPK_OK);
    CHECK(size == 16 && memcmp(view, &tet16, 16) == 0);
    tpk_close(file);
}

TPK_TEST(vectors_two_tets_zstd)
{
    static const double origin[3] = {1000000, -2.5, 0}, lo[3] = {1000000, -2.5, 0}, hi[3] = {1000001, -1.5, 1};
    static const float positions[15] = {1, 0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 0, 0, 1, 0};
    static const int32_t tets[8] = {3, 0, 4, 1, 0, 4, 1, 2};
    static const tpk_tet32 tet32[2] = {{{3, 0, 4}, 6, {1, -1, -1, -1}}, {{0, 4, 1}, 7, {-1, -1, -1, 0}}};
    static const tpk_tet20 tet20[2] = {{6, {-1, -1, 1, -1}}, {7, {-1, -1, 0, -1}}};
    static const tpk_tet16 tet16[2] = {{6, {0, 0, -2}}, {7, {0, 0, -1}}};
    static const tpk_shell_face shell[6] = {{3, 1, 4, 0}, {3, 0, 1, 0}, {3, 4, 0, 0},
                                            {4, 1, 2, 1}, {0, 2, 1, 1}, {0, 4, 2, 1}};
    static const float temperature[2][5] = {{300, 301, 302, 303, 304}, {310, 311, 312, 313, 314}};
    static const float material[2] = {1, 2};
    static const int32_t tmap[2] = {7, 9}, vmap[5] = {10, 11, 12, 13, 14};
    const expected_mesh m = {origin, lo, hi, 5, 2, 6, 13, positions, tets, tet32, tet20, tet16, shell,
                             TPK_CODEC_ZSTD};

    tpk_result r;
    tpk_file *file = open_vector("two_tets_zstd.tpk", 0, TPK_OK, &r);
    CHECK_EQ_INT(r, TPK_OK);
    check_mesh(file, &m);
    CHECK_EQ_INT(tpk_field_count(file), 2);
    check_field(file, 0, "temperature", "K", TPK_ASSOC_POINT, 2, 300.0f, 314.0f);
    check_field(file, 1, "material", "", TPK_ASSOC_TET, 1, 1.0f, 2.0f);
    float values[5];
    int32_t ids[5];
    tpk_dir_entry e;
    for (uint32_t s = 0; s < 2; s++) {
        CHECK_EQ_INT(read_tagged(file, TPK_TAG_FDAT, 0, s, values, sizeof temperature[s], &e), TPK_OK);
        CHECK(memcmp(values, temperature[s], sizeof temperature[s]) == 0);
    }
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_FDAT, 1, 0, values, sizeof material, &e), TPK_OK);
    CHECK(memcmp(values, material, sizeof material) == 0);
    double time;
    CHECK_EQ_INT(tpk_get_time(file, 0, &time), TPK_OK);
    CHECK(time == 0.0);
    CHECK_EQ_INT(tpk_get_time(file, 1, &time), TPK_OK);
    CHECK(time == 0.5);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_TMAP, 0, 0, ids, sizeof tmap, &e), TPK_OK);
    CHECK(memcmp(ids, tmap, sizeof tmap) == 0);
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_VMAP, 0, 0, ids, sizeof vmap, &e), TPK_OK);
    CHECK(memcmp(ids, vmap, sizeof vmap) == 0);
    /* The unknown optional vendor chunk is listed but did not stop the open. */
    uint64_t i;
    CHECK_EQ_INT(tpk_find_chunk(file, TPK_FOURCC('n', 'o', 't', 'e'), 0, 0, &i), TPK_OK);
    CHECK_EQ_INT(tpk_get_chunk(file, i, &e), TPK_OK);
    CHECK_EQ_INT(e.flags, 0);
    /* A compressed chunk has no zero-copy view. */
    const void *view;
    uint64_t size;
    CHECK_EQ_INT(tpk_find_chunk(file, TPK_TAG_TT16, 0, 0, &i), TPK_OK);
    CHECK_EQ_INT(tpk_view_chunk(file, i, &view, &size), TPK_ERR_UNSUPPORTED_CHUNK);
    tpk_close(file);
}

/* ---- the files that must be refused ---------------------------------------------------------- */

TPK_TEST(vectors_must_fail)
{
    static const struct {
        const char *name;
        uint32_t flags;
        tpk_result expected;
    } cases[] = {
        {"bad_magic.tpk", 0, TPK_ERR_NOT_TETPACK},
        {"truncated.tpk", 0, TPK_ERR_TRUNCATED},
        {"newer_major.tpk", 0, TPK_ERR_VERSION},
        {"unknown_required_chunk.tpk", 0, TPK_ERR_UNSUPPORTED_CHUNK},
        {"chunk_checksum.tpk", TPK_OPEN_VERIFY_ALL, TPK_ERR_CHUNK_CHECKSUM},
        {"overlap.tpk", 0, TPK_ERR_OVERLAP},
        {"nonfinite_origin.tpk", 0, TPK_ERR_CORRUPT},
        {"empty_fdsc.tpk", 0, TPK_ERR_CORRUPT},
        {"implausible_zstd_size.tpk", 0, TPK_ERR_CORRUPT},
        {"zstd_skippable_frame.tpk", TPK_OPEN_VERIFY_ALL, TPK_ERR_DECOMPRESS},
        {"zstd_chunk_checksum.tpk", TPK_OPEN_VERIFY_ALL, TPK_ERR_CHUNK_CHECKSUM},
        {"level_zstd.tpk", 0, TPK_ERR_CORRUPT},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        tpk_result r;
        tpk_file *file = open_vector(cases[k].name, cases[k].flags, cases[k].expected, &r);
        CHECK_MSG(r == cases[k].expected, "%s: got %s, expected %s", cases[k].name, tpk_result_string(r),
                  tpk_result_string(cases[k].expected));
        CHECK(file == NULL);
    }
    /* Chunk checksums are checked lazily by default: the open succeeds, the first use fails. */
    tpk_result r;
    tpk_file *file = open_vector("chunk_checksum.tpk", 0, TPK_OK, &r);
    CHECK_EQ_INT(r, TPK_OK);
    float values[4];
    tpk_dir_entry e;
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_FDAT, 0, 0, values, sizeof values, &e), TPK_ERR_CHUNK_CHECKSUM);
    tpk_close(file);
    /* The rest open, and fail where a renderer meets them: in tpk_load_arrays (the path that decodes
     * zstd chunks into handle-owned copies, whose checksum check issue 10 found untested), and in
     * tpk_verify. */
    static const struct {
        const char *name;
        tpk_layout layout;
        tpk_result expected;
        const char *where; /* the message names the chunk */
    } lazy[] = {
        {"zstd_chunk_checksum.tpk", TPK_LAYOUT_TET32, TPK_ERR_CHUNK_CHECKSUM, "chunk 0 'POS3' at offset 192"},
        {"zstd_skippable_frame.tpk", TPK_LAYOUT_TET32, TPK_ERR_DECOMPRESS, "chunk 0 'POS3' at offset 192"},
        {"tet16_vx.tpk", TPK_LAYOUT_TET16, TPK_ERR_CORRUPT, "'TT16'"},
    };
    for (size_t k = 0; k < sizeof lazy / sizeof lazy[0]; k++) {
        for (int verify = 0; verify < 2; verify++) {
            file = open_vector(lazy[k].name, 0, TPK_OK, &r);
            CHECK_MSG(r == TPK_OK, "%s: open gave %s", lazy[k].name, tpk_result_string(r));
            tpk_mesh_arrays arrays;
            r = verify ? tpk_verify(file) : tpk_load_arrays(file, lazy[k].layout, NULL, 0, &arrays);
            char text[512];
            snprintf(text, sizeof text, "%s", tpk_error_text(file));
            tpk_close(file);
            CHECK_MSG(r == lazy[k].expected && strstr(text, lazy[k].where),
                      "%s: %s gave %s (%s), expected %s", lazy[k].name, verify ? "tpk_verify" : "tpk_load_arrays",
                      tpk_result_string(r), text, tpk_result_string(lazy[k].expected));
        }
    }
}

/* The spec's worked Tet16 example (§6.5), decoded from each possible entry. */
TPK_TEST(vectors_tet16_example)
{
    const int32_t v[4] = {7, 2, 9, 4}, n[4] = {12, -1, 5, 30};
    tpk_tet20 t20;
    tpk_tet16 t16;
    spec_tet20(v, n, &t20);
    spec_tet16(&t20, &t16);
    CHECK(t20.vx == 8 && t20.n[0] == -1 && t20.n[1] == 30 && t20.n[2] == 12 && t20.n[3] == 5);
    CHECK(t16.vx == 8 && t16.nx[0] == -6 && t16.nx[1] == 27 && t16.nx[2] == 9);
    static const uint8_t bytes[16] = {8, 0, 0, 0, 0xFA, 0xFF, 0xFF, 0xFF, 0x1B, 0, 0, 0, 9, 0, 0, 0};
    CHECK(memcmp(&t16, bytes, 16) == 0);
    for (int k = 0; k < 4; k++) { /* enter through the face opposite v[k], coming from n[k] */
        int32_t x = v[k], p = n[k];
        int rank = spec_rank(v, k);
        CHECK_EQ_INT(x, t16.vx ^ v[(k + 1) % 4] ^ v[(k + 2) % 4] ^ v[(k + 3) % 4]);
        int32_t n3 = rank == 3 ? p : (int32_t)((uint32_t)t16.nx[rank] ^ (uint32_t)p);
        CHECK_EQ_INT(n3, 5);
        for (int r = 0; r < 3; r++)
            CHECK_EQ_INT((int32_t)((uint32_t)t16.nx[r] ^ (uint32_t)n3), t20.n[r]);
    }
}

/* ---- culling blocks (spec §13.6) ------------------------------------------------------------- */

/* two_tets_cull.tpk: format 1.4, its CULL the 16 words of samples/vectors/README.md; a walk of its block
 * from the seed gives the walk from the shell's tets, in every layout. cull_bad_seed.tpk is within rule
 * 17, and the block walk refuses it (spec §9): Tet20 stores n[3], which differs from n3 (MESH); Tet16
 * decodes from n3 a neighbor across a face whose derived fourth id is one of the face's (CORRUPT, as
 * the walk from the shell gives for a derived id). cull_block_count.tpk is not within rule 17: refused
 * when the chunk is used (tpk_load_cull, tpk_verify) and not before. */
TPK_TEST(vectors_cull)
{
    static const int32_t words[16] = {16, 1, 1, 1, 0, 1, 0, 1, 0, 0, 1, 4, 3, -1, 0, 5};
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    tpk_result r;
    tpk_file *file = open_vector("two_tets_cull.tpk", TPK_OPEN_VERIFY_ALL, TPK_OK, &r);
    CHECK_EQ_INT(r, TPK_OK);
    if (!file)
        return;
    tpk_file_info info;
    CHECK(tpk_get_info(file, &info) == TPK_OK && info.version_major == 1 && info.version_minor == 4);
    int32_t raw[16];
    tpk_dir_entry e;
    CHECK_EQ_INT(read_tagged(file, TPK_TAG_CULL, 0, 0, raw, sizeof raw, &e), TPK_OK);
    CHECK(memcmp(raw, words, sizeof words) == 0 && e.flags == 0 && e.elem_type == TPK_ELEM_I32 && e.elem_count == 16);
    tpk_cull cull;
    CHECK_EQ_INT(tpk_load_cull(file, &cull), TPK_OK);
    CHECK(cull.block_tets == 16 && cull.block_count == 1 && cull.seed_count == 1 && cull.interval_count == 1 &&
          cull.seed_start[1] == 1 && cull.interval_start[1] == 1 && cull.seeds[0] == 0 && cull.seeds[5] == -1 &&
          cull.intervals[0] == 0 && cull.intervals[1] == 5);
    for (int l = 0; l < 3; l++) {
        tpk_mesh_arrays m;
        int32_t walked[8], block[8];
        CHECK_EQ_INT(tpk_load_arrays(file, layouts[l], NULL, 0, &m), TPK_OK);
        CHECK_EQ_INT(tpk_recover_tets(&m, walked), TPK_OK);
        CHECK_EQ_INT(tpk_recover_block(&m, &cull, 0, block), TPK_OK);
        CHECK_MSG(memcmp(walked, block, sizeof block) == 0, "layout %d", l);
    }
    tpk_close(file);
    /* the file without CULL has none */
    file = open_vector("two_tets_levels.tpk", 0, TPK_OK, &r);
    CHECK(file && tpk_load_cull(file, &cull) == TPK_ERR_NOT_FOUND);
    tpk_close(file);

    file = open_vector("cull_bad_seed.tpk", TPK_OPEN_VERIFY_ALL, TPK_OK, &r);
    CHECK_EQ_INT(r, TPK_OK);
    if (file) {
        tpk_mesh_arrays m;
        int32_t block[8];
        CHECK_EQ_INT(tpk_load_cull(file, &cull), TPK_OK);
        CHECK(cull.seeds[5] == 1);
        static const tpk_layout walked[2] = {TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
        static const tpk_result refused[2] = {TPK_ERR_MESH, TPK_ERR_CORRUPT};
        for (int l = 0; l < 2; l++) {
            CHECK_EQ_INT(tpk_load_arrays(file, walked[l], NULL, 0, &m), TPK_OK);
            r = tpk_recover_block(&m, &cull, 0, block);
            CHECK_MSG(r == refused[l], "a Tet%d walk from a wrong n3: %s", l ? 16 : 20, tpk_result_string(r));
        }
        tpk_close(file);
    }

    for (int verify = 0; verify < 2; verify++) {
        file = open_vector("cull_block_count.tpk", 0, TPK_OK, &r);
        CHECK_EQ_INT(r, TPK_OK);
        if (!file)
            continue;
        tpk_mesh_arrays m;
        CHECK_EQ_INT(tpk_load_arrays(file, TPK_LAYOUT_TET16, NULL, 0, &m), TPK_OK); /* CULL not used */
        r = verify ? tpk_verify(file) : tpk_load_cull(file, &cull);
        char text[512];
        snprintf(text, sizeof text, "%s", tpk_error_text(file));
        tpk_close(file);
        CHECK_MSG(r == TPK_ERR_CORRUPT && strstr(text, "'CULL'") && strstr(text, "block_count 2"), "%s: %s (%s)",
                  verify ? "tpk_verify" : "tpk_load_cull", tpk_result_string(r), text);
    }
    file = open_vector("cull_block_count.tpk", TPK_OPEN_VERIFY_ALL, TPK_OK, &r); /* its checksums are right */
    CHECK(file != NULL && r == TPK_OK);
    tpk_close(file);
}

/* ---- part sets (spec §13.4) ------------------------------------------------------------------- */

typedef struct piece_list {
    int count;
    uint32_t part[8];
    tpk_segment seg[8];
    uint32_t current_part;
} piece_list;

static int collect_piece(void *user, const tpk_segment *segment)
{
    piece_list *l = user;
    if (l->count < 8) {
        l->part[l->count] = l->current_part;
        l->seg[l->count++] = *segment;
    }
    return 0;
}

TPK_TEST(vectors_two_parts)
{
    tpk_partset *set = NULL;
    char err[512] = "";
    CHECK_EQ_INT(tpk_partset_open(&set, vector_path("two_parts.tpkset"), NULL, NULL, NULL, err, sizeof err), TPK_OK);
    if (!set) {
        fprintf(stderr, "%s\n", err);
        return;
    }
    CHECK_EQ_INT(tpk_partset_part_count(set), 2);
    tpk_mesh_arrays parts[2];
    const tpk_link *links[2];
    uint64_t counts[2];
    for (uint32_t p = 0; p < 2; p++) {
        tpk_file_info info;
        CHECK_EQ_INT(tpk_get_info(tpk_partset_file(set, p), &info), TPK_OK);
        CHECK_EQ_INT(info.version_minor, 2);
        CHECK_EQ_INT(tpk_load_arrays(tpk_partset_file(set, p), TPK_LAYOUT_TET32, NULL, 0, &parts[p]), TPK_OK);
        CHECK_EQ_INT(tpk_partset_links(set, p, &links[p], &counts[p]), TPK_OK);
        CHECK_EQ_INT((int)counts[p], 1);
    }
    CHECK_EQ_INT(links[0][0].face, 0);
    CHECK_EQ_INT(links[0][0].other_face, 3);
    CHECK_EQ_INT(links[1][0].face, 3);
    CHECK_EQ_INT(links[1][0].other_face, 0);
    /* Both parts span the unit box: a box beyond x = 1 opens neither, one touching x = 1 both. */
    tpk_partset *some = NULL;
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = two_tets_origin[k] + (k == 0 ? 1.5 : 0.2);
        hi[k] = two_tets_origin[k] + (k == 0 ? 2.0 : 0.4);
    }
    CHECK_EQ_INT(tpk_partset_open(&some, vector_path("two_parts.tpkset"), NULL, lo, hi, err, sizeof err), TPK_OK);
    CHECK(some && !tpk_partset_file(some, 0) && !tpk_partset_file(some, 1));
    tpk_partset_close(some);
    lo[0] = two_tets_origin[0] + 1.0;
    CHECK_EQ_INT(tpk_partset_open(&some, vector_path("two_parts.tpkset"), NULL, lo, hi, err, sizeof err), TPK_OK);
    CHECK(some && tpk_partset_file(some, 0) && tpk_partset_file(some, 1));
    tpk_partset_close(some);

    /* A ray through both tets: the set gives the pieces of the single file, in order. */
    tpk_set_marcher *sm = NULL;
    CHECK_EQ_INT(tpk_set_marcher_create(&sm, 2, parts, links, counts), TPK_OK);
    tpk_result opened;
    tpk_file *whole = open_vector("two_tets_zstd.tpk", 0, TPK_OK, &opened);
    tpk_mesh_arrays whole_arrays;
    CHECK_EQ_INT(tpk_load_arrays(whole, TPK_LAYOUT_TET32, NULL, 0, &whole_arrays), TPK_OK);
    tpk_marcher *m = NULL;
    CHECK_EQ_INT(tpk_marcher_create(&m, &whole_arrays), TPK_OK);
    const double org[3] = {two_tets_origin[0] + 0.1, two_tets_origin[1] + 0.2, two_tets_origin[2] - 1.0};
    const double dir[3] = {0.3, 0.25, 1.0};
    piece_list a = {0}, b = {0};
    CHECK_EQ_INT(tpk_march_ray(m, org, dir, 0, INFINITY, collect_piece, &a, NULL), TPK_OK);
    CHECK_EQ_INT(tpk_set_march_ray(sm, org, dir, 0, INFINITY, collect_piece, &b, &b.current_part, NULL), TPK_OK);
    CHECK_EQ_INT(a.count, 2);
    CHECK_EQ_INT(b.count, 2);
    for (int i = 0; i < a.count && i < b.count; i++) {
        CHECK_EQ_INT((int)b.part[i], a.seg[i].tet); /* part i holds whole tet i */
        CHECK(fabs(a.seg[i].t_in - b.seg[i].t_in) < 1e-12 && fabs(a.seg[i].t_out - b.seg[i].t_out) < 1e-12);
    }
    tpk_marcher_destroy(m);
    tpk_close(whole);
    tpk_set_marcher_destroy(sm);
    tpk_partset_close(set);
}

/* The set as one mesh (libtetpack/set_mesh.c): the single file's tets, positions and pieces, in Tet16
 * (re-encoded from the parts' Tet32) and Tet32; a link that is not answered is
 * refused by name. */
TPK_TEST(vectors_set_mesh)
{
    tpk_partset *set = NULL;
    char err[512] = "";
    CHECK_EQ_INT(tpk_partset_open(&set, vector_path("two_parts.tpkset"), NULL, NULL, NULL, err, sizeof err), TPK_OK);
    if (!set)
        return;
    tpk_result opened;
    tpk_file *whole = open_vector("two_tets_zstd.tpk", 0, TPK_OK, &opened);
    tpk_mesh_arrays w;
    CHECK_EQ_INT(tpk_load_arrays(whole, TPK_LAYOUT_TET32, NULL, 0, &w), TPK_OK);
    int32_t wq[8], mq[8];
    CHECK_EQ_INT(tpk_recover_tets(&w, wq), TPK_OK);
    tpk_marcher *wm = NULL;
    CHECK_EQ_INT(tpk_marcher_create(&wm, &w), TPK_OK);
    const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    for (int l = 0; l < 3; l++) {
        tpk_set_mesh *sm = NULL;
        tpk_mesh_arrays m;
        CHECK_EQ_INT(tpk_set_mesh_create(&sm, set, layouts[l], err, sizeof err), TPK_OK);
        CHECK_EQ_INT(tpk_set_mesh_arrays(sm, NULL, 0, &m, err, sizeof err), TPK_OK);
        CHECK_EQ_INT((int)m.vertex_count, (int)w.vertex_count); /* the 3 vertices of the cut once */
        CHECK_EQ_INT((int)m.tet_count, 2);
        CHECK_EQ_INT((int)m.shell_face_count, (int)w.shell_face_count); /* the linked faces are not shell */
        CHECK_EQ_INT((int)tpk_set_mesh_tet_base(sm, 1), 1);
        CHECK_EQ_INT(tpk_recover_tets(&m, mq), TPK_OK);
        for (int i = 0; i < 8; i++) { /* the same tets at the same places (Tet16/20 walks may rotate them) */
            int found = 0;
            for (int j = 4 * (i / 4); j < 4 * (i / 4) + 4; j++)
                found += !memcmp(&m.positions[3 * mq[i]], &w.positions[3 * wq[j]], 3 * sizeof(float));
            CHECK_EQ_INT(found, 1);
        }
        tpk_marcher *mm = NULL;
        CHECK_EQ_INT(tpk_marcher_create(&mm, &m), TPK_OK);
        const double org[3] = {two_tets_origin[0] + 0.1, two_tets_origin[1] + 0.2, two_tets_origin[2] - 1.0};
        const double dir[3] = {0.3, 0.25, 1.0};
        piece_list a = {0}, b = {0};
        CHECK_EQ_INT(tpk_march_ray(wm, org, dir, 0, INFINITY, collect_piece, &a, NULL), TPK_OK);
        CHECK_EQ_INT(tpk_march_ray(mm, org, dir, 0, INFINITY, collect_piece, &b, NULL), TPK_OK);
        CHECK_EQ_INT(b.count, 2);
        for (int i = 0; i < a.count && i < b.count; i++)
            CHECK(a.seg[i].tet == b.seg[i].tet && a.seg[i].t_in == b.seg[i].t_in && a.seg[i].t_out == b.seg[i].t_out);
        tpk_marcher_destroy(mm);
        tpk_set_mesh_destroy(sm);
    }
    tpk_marcher_destroy(wm);
    tpk_close(whole);
    tpk_partset_close(set);

    CHECK_EQ_INT(tpk_partset_open(&set, vector_path("bad_link.tpkset"), NULL, NULL, NULL, err, sizeof err), TPK_OK);
    tpk_set_mesh *bad = NULL;
    CHECK_EQ_INT(tpk_set_mesh_create(&bad, set, TPK_LAYOUT_TET16, err, sizeof err), TPK_ERR_MESH);
    CHECK(bad == NULL && strstr(err, "link"));
    tpk_partset_close(set);
}

/* A copy of two_parts.tpkset in the temp folder (beside copies of its parts) with `patch` applied to its
 * part records and the checksums recomputed: what tpk_partset_open says. */
static tpk_result open_patched_set(void (*patch)(tpk_part_record *records), char *err, size_t cap)
{
    byte_buffer b = {0};
    if (load_bytes(vector_path("two_parts.tpkset"), &b) != 0)
        return TPK_ERR_IO;
    for (int p = 0; p < 2; p++) {
        byte_buffer part = {0};
        char name[64];
        snprintf(name, sizeof name, "two_parts-%d.tpk", p);
        if (load_bytes(vector_path(name), &part) == 0)
            save_bytes(tpk_temp_path(name), part.data, part.size);
        free(part.data);
    }
    tpk_dir_entry *e = entry_of(&b, TPK_TAG_PART);
    tpk_part_record *records = (tpk_part_record *)(b.data + e->offset);
    patch(records);
    e->checksum = XXH64(records, e->raw_size, 0);
    reseal(&b);
    save_bytes(tpk_temp_path("patched.tpkset"), b.data, b.size);
    free(b.data);
    tpk_partset *set = NULL;
    tpk_result r = tpk_partset_open(&set, tpk_temp_path("patched.tpkset"), NULL, NULL, NULL, err, cap);
    tpk_partset_close(set);
    return r;
}

static void patch_nothing(tpk_part_record *r) { (void)r; }
static void rename_part(tpk_part_record *r, const char *name)
{
    memset(r->file, 0, sizeof r->file); /* NUL-padded: bytes after the name must be 0 */
    snprintf(r->file, sizeof r->file, "%s", name);
}
static void patch_parent_dir(tpk_part_record *r) { rename_part(&r[1], "../two_parts-1.tpk"); }
static void patch_missing(tpk_part_record *r) { rename_part(&r[0], "gone.tpk"); }
static void patch_padding(tpk_part_record *r) { r[0].file[100] = 'x'; }
static void patch_count(tpk_part_record *r) { r[1].tet_count = 2; }
static void patch_checksum(tpk_part_record *r) { r[0].header_checksum ^= 1; }
static void patch_reserved(tpk_part_record *r) { r[0].reserved[31] = 1; }

TPK_TEST(part_set_refused)
{
    char err[512] = "";
    CHECK_EQ_INT(open_patched_set(patch_nothing, err, sizeof err), TPK_OK);
    CHECK_EQ_INT(open_patched_set(patch_parent_dir, err, sizeof err), TPK_ERR_CORRUPT);
    CHECK_MSG(strstr(err, "part 1: the file name") != NULL, "message: %s", err);
    CHECK_EQ_INT(open_patched_set(patch_missing, err, sizeof err), TPK_ERR_IO);
    CHECK_MSG(strstr(err, "gone.tpk") != NULL, "message: %s", err);
    CHECK_EQ_INT(open_patched_set(patch_count, err, sizeof err), TPK_ERR_CORRUPT);
    CHECK_MSG(strstr(err, "counts differ") != NULL, "message: %s", err);
    CHECK_EQ_INT(open_patched_set(patch_checksum, err, sizeof err), TPK_ERR_CORRUPT);
    CHECK_MSG(strstr(err, "header_checksum") != NULL, "message: %s", err);
    CHECK_EQ_INT(open_patched_set(patch_reserved, err, sizeof err), TPK_ERR_CORRUPT);
    CHECK_EQ_INT(open_patched_set(patch_padding, err, sizeof err), TPK_ERR_CORRUPT);
    /* A plain .tpk is not a set. */
    tpk_partset *set = NULL;
    CHECK_EQ_INT(tpk_partset_open(&set, vector_path("one_tet.tpk"), NULL, NULL, NULL, err, sizeof err),
                 TPK_ERR_NOT_FOUND);
    CHECK(set == NULL);
}
