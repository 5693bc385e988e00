/* tetpack check 6xx on .tpk files: converted real meshes (every layout) report nothing; for each check a
 * file that breaks exactly that rule, crafted with libtetpack's writer so every checksum is right and the
 * reader accepts it, gives the exact count (and near misses give none); the spec's test vectors behave
 * as spec §13 says; and the file's mesh for the mesh-level groups is the file's content. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "convert/convert.h"
#include "harness.h"
#include "convert/pipeline.h"
#include "tetpack.h"
#include "tpk_assert.h"

#define ALL_LAYOUTS (TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET20 | TPK_LAYOUT_BIT_TET32)

/* ---- running the checks ------------------------------------------------------------------------- */

/* 6xx on `path` into *report (caller frees). 0 when the checks ran, 1 when the file does not open,
 * -1 when the checks could not run. */
static int run_6xx(const char *path, tpk_check_report *report)
{
    tpk_check_options o;
    tpk_check_options_default(&o);
    o.threads = 2;
    if (tpk_check_report_init(report, &o))
        return -1;
    tpk_file *file = NULL;
    if (tpk_open_path(&file, path, NULL, NULL, 0) != TPK_OK)
        return 1;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = tpk_check_tpk_file(path, file, report, &diag);
    tpk_close(file);
    if (rc)
        fprintf(stderr, "%s: %s\n", path, diag.message);
    return rc;
}

static int64_t found(tpk_check_report *r, int id)
{
    return tpk_check_finding(r, id)->count;
}

/* The same with a given thread count and example limit. */
static int run_6xx_with(const char *path, int threads, int max_examples, tpk_check_report *report)
{
    tpk_check_options o;
    tpk_check_options_default(&o);
    o.threads = threads;
    o.max_examples = max_examples;
    tpk_file *file = NULL;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_check_report_init(report, &o) || tpk_open_path(&file, path, NULL, NULL, 0) != TPK_OK)
        return -1;
    int rc = tpk_check_tpk_file(path, file, report, &diag);
    tpk_close(file);
    return rc;
}

/* Sum over 600..613 and 616; prints what was found, so a failing test shows it. */
static int64_t total_6xx(tpk_check_report *r, const char *label)
{
    int64_t sum = 0;
    for (int id = 600; id <= 616; id++) {
        if (id == 614 || id == 615)
            continue; /* the part set's and the levels' (check_set.c, check_levels.c) */
        tpk_finding *f = tpk_check_finding(r, id);
        sum += f->count;
        if (f->count)
            fprintf(stderr, "  [%s] %d %s: %lld%s%s%s%s\n", label, id, f->check->name, (long long)f->count,
                    f->summary[0] ? " | " : "", f->summary, f->example_count ? " | " : "",
                    f->example_count ? f->examples[0].note : "");
    }
    return sum;
}

/* ---- files -------------------------------------------------------------------------------------- */

static int convert_with(const char *data, const char *out, unsigned layouts, int zstd, int cull)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = tpk_data_path(data);
    o.output = out;
    o.layouts = layouts;
    o.zstd_level = zstd;
    o.cull = cull;
    o.threads = 2;
    tpk_convert_report report;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_convert_checked(&o, &report, &diag) != 0) {
        fprintf(stderr, "convert %s: %s\n", data, diag.message);
        return -1;
    }
    return 0;
}

static int convert(const char *data, const char *out, unsigned layouts, int zstd)
{
    return convert_with(data, out, layouts, zstd, 0);
}

/* A file as a list of chunks in memory, to change and write back with the library's writer (which
 * computes every checksum, so only the content is wrong). */
#define MAX_PARTS 64
typedef struct part {
    tpk_chunk_desc desc;
    void *data;
} part;

typedef struct parts {
    tpk_header_fields header;
    int count;
    part p[MAX_PARTS];
} parts;

static void parts_free(parts *ps)
{
    for (int i = 0; i < ps->count; i++)
        free(ps->p[i].data);
    ps->count = 0;
}

static int parts_read(const char *path, parts *ps)
{
    memset(ps, 0, sizeof *ps);
    tpk_file *file;
    tpk_file_info info;
    if (tpk_open_path(&file, path, NULL, NULL, 0) != TPK_OK)
        return -1;
    tpk_get_info(file, &info);
    ps->header = (tpk_header_fields){info.vertex_count, info.tet_count, info.shell_face_count,
                                     {info.origin[0], info.origin[1], info.origin[2]},
                                     {info.bounds_min[0], info.bounds_min[1], info.bounds_min[2]},
                                     {info.bounds_max[0], info.bounds_max[1], info.bounds_max[2]}};
    int rc = info.chunk_count <= MAX_PARTS ? 0 : -1;
    for (uint64_t i = 0; !rc && i < info.chunk_count; i++) {
        tpk_dir_entry e;
        tpk_get_chunk(file, i, &e);
        part *p = &ps->p[ps->count++];
        p->desc = (tpk_chunk_desc){e.tag, e.flags, TPK_CODEC_NONE, e.elem_type, e.elem_size, e.index, e.step,
                                   e.elem_count, 0};
        p->data = malloc(e.raw_size + 1);
        rc = !p->data || tpk_read_chunk(file, i, p->data, e.raw_size) != TPK_OK;
    }
    tpk_close(file);
    if (rc)
        parts_free(ps);
    return rc ? -1 : 0;
}

static part *parts_get(parts *ps, uint32_t tag, uint32_t index, uint32_t step)
{
    for (int i = 0; i < ps->count; i++)
        if (ps->p[i].desc.tag == tag && ps->p[i].desc.index == index && ps->p[i].desc.step == step)
            return &ps->p[i];
    return NULL;
}

static void *parts_data(parts *ps, uint32_t tag)
{
    part *p = parts_get(ps, tag, 0, 0);
    return p ? p->data : NULL;
}

static void parts_remove(parts *ps, uint32_t tag)
{
    for (int i = 0; i < ps->count; i++)
        if (ps->p[i].desc.tag == tag) {
            free(ps->p[i].data);
            ps->p[i--] = ps->p[--ps->count];
        }
}

static int parts_write(const parts *ps, const char *path)
{
    tpk_writer *w;
    if (tpk_writer_open(&w, path, NULL, NULL, 0) != TPK_OK)
        return -1;
    for (int i = 0; i < ps->count; i++)
        if (tpk_writer_add_chunk(w, &ps->p[i].desc, ps->p[i].data) != TPK_OK) {
            fprintf(stderr, "add chunk %d: %s\n", i, tpk_writer_error_text(w));
            tpk_writer_abort(w);
            return -1;
        }
    return tpk_writer_finish(w, &ps->header) == TPK_OK ? 0 : -1;
}

/* Base files, converted once per test process. */
static const char *cylinder_all(void)
{
    static char path[512];
    if (!path[0]) {
        snprintf(path, sizeof path, "%s", tpk_temp_path("cylinder_all.tpk"));
        if (convert("sfepy/cylinder.vtk", path, ALL_LAYOUTS, 0))
            path[0] = 0;
    }
    return path;
}

static const char *exomerge_all(void) /* point fields over 5 steps, TIME, hexahedra split */
{
    static char path[512];
    if (!path[0]) {
        snprintf(path, sizeof path, "%s", tpk_temp_path("exomerge_all.tpk"));
        if (convert("seacas/exomerge_unit_test.e", path, ALL_LAYOUTS, 0))
            path[0] = 0;
    }
    return path;
}

/* Read `base`, keep only the layouts in `keep` (TPK_LAYOUT_BIT_*), and hand the parts to the caller. */
static int parts_from(const char *base, unsigned keep, parts *ps)
{
    if (!base[0] || parts_read(base, ps))
        return -1;
    if (!(keep & TPK_LAYOUT_BIT_TET32))
        parts_remove(ps, TPK_TAG_TT32);
    if (!(keep & TPK_LAYOUT_BIT_TET20))
        parts_remove(ps, TPK_TAG_TT20);
    if (!(keep & TPK_LAYOUT_BIT_TET16))
        parts_remove(ps, TPK_TAG_TT16);
    return 0;
}

/* Write the parts, check them, free them; the report is the caller's to free. */
static int check_parts(parts *ps, const char *name, tpk_check_report *report)
{
    const char *path = tpk_temp_path(name);
    int rc = parts_write(ps, path);
    parts_free(ps);
    return rc ? -1 : run_6xx(path, report);
}

/* An interior tet of a Tet32 file with all four neighbors: the first such tet. */
static int64_t interior_tet(const tpk_tet32 *tets, int64_t count)
{
    for (int64_t t = 0; t < count; t++)
        if (tets[t].n[0] >= 0 && tets[t].n[1] >= 0 && tets[t].n[2] >= 0 && tets[t].n[3] >= 0)
            return t;
    return -1;
}

/* A small mesh written directly: positions, positive tets and their neighbors as given (so non-manifold
 * or folded configurations can be written), all three layouts and the shell of the -1 faces. */
static int write_small(const char *path, const float (*pos)[3], int64_t V, const int32_t (*tets)[4],
                       const int32_t (*nb)[4], int64_t T)
{
    tpk_tet32 t32[8];
    tpk_tet20 t20[8];
    tpk_tet16 t16[8];
    tpk_shell_face shell[32];
    tpk_build_tet32(&tets[0][0], &nb[0][0], T, t32);
    tpk_build_tet20(&tets[0][0], &nb[0][0], T, t20);
    tpk_build_tet16(&tets[0][0], &nb[0][0], T, t16);
    int64_t S = tpk_count_shell_faces(&nb[0][0], T);
    tpk_build_shell(&tets[0][0], &nb[0][0], T, shell);
    tpk_header_fields h = {(uint64_t)V, (uint64_t)T, (uint64_t)S, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    for (int a = 0; a < 3; a++) {
        h.bounds_min[a] = h.bounds_max[a] = pos[0][a];
        for (int64_t i = 1; i < V; i++) {
            h.bounds_min[a] = fmin(h.bounds_min[a], pos[i][a]);
            h.bounds_max[a] = fmax(h.bounds_max[a], pos[i][a]);
        }
    }
    tpk_writer *w;
    if (tpk_writer_open(&w, path, NULL, NULL, 0) != TPK_OK)
        return -1;
    const tpk_chunk_desc d[5] = {
        {TPK_TAG_POS3, TPK_CHUNK_REQUIRED, 0, TPK_ELEM_VEC3_F32, 12, 0, 0, (uint64_t)V, 0},
        {TPK_TAG_TT32, TPK_CHUNK_REQUIRED, 0, TPK_ELEM_TET32, 32, 0, 0, (uint64_t)T, 0},
        {TPK_TAG_TT20, TPK_CHUNK_REQUIRED, 0, TPK_ELEM_TET20, 20, 0, 0, (uint64_t)T, 0},
        {TPK_TAG_TT16, TPK_CHUNK_REQUIRED, 0, TPK_ELEM_TET16, 16, 0, 0, (uint64_t)T, 0},
        {TPK_TAG_SHEL, TPK_CHUNK_REQUIRED, 0, TPK_ELEM_SHELL_FACE, 16, 0, 0, (uint64_t)S, 0}};
    const void *data[5] = {pos, t32, t20, t16, shell};
    for (int k = 0; k < 5; k++)
        if (tpk_writer_add_chunk(w, &d[k], data[k]) != TPK_OK) {
            tpk_writer_abort(w);
            return -1;
        }
    return tpk_writer_finish(w, &h) == TPK_OK ? 0 : -1;
}

/* Unit triangle 0, 1, 2 in z = 0; apexes 3 above it, 4 and 5 placed by the tests. */
static float small_pos[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25f, 0.25f, 1}, {0, 0, 0}, {0.2f, 0.2f, 2}};

static int check_small(const char *name, const int32_t (*tets)[4], const int32_t (*nb)[4], int64_t T,
                       tpk_check_report *report)
{
    const char *path = tpk_temp_path(name);
    if (write_small(path, (const float (*)[3])small_pos, 6, tets, nb, T))
        return -1;
    return run_6xx(path, report);
}

/* ---- clean files -------------------------------------------------------------------------------- */

/* Converted real meshes, in every layout alone and all three together (compressed), report nothing. */
TPK_TEST(clean_converted_files)
{
    static const char *const meshes[] = {"sfepy/cylinder.vtk", "seacas/exomerge_unit_test.e",
                                         "gmsh/t3_hex_prism_ascii41.msh", "hard/huge_offset_hex.vtu",
                                         "tetgen/hinge_small.node", "nasa_refine/om6_om6-curv-no-geom.meshb"};
    static const unsigned layouts[4] = {TPK_LAYOUT_BIT_TET16, TPK_LAYOUT_BIT_TET20, TPK_LAYOUT_BIT_TET32,
                                        ALL_LAYOUTS};
    for (size_t m = 0; m < sizeof meshes / sizeof meshes[0]; m++) {
        for (int l = 0; l < 4; l++) {
            const char *path = tpk_temp_path("clean.tpk");
            CHECK(convert(meshes[m], path, layouts[l], l == 3 ? 3 : 0) == 0);
            tpk_check_report report;
            int rc = run_6xx(path, &report);
            int64_t total = total_6xx(&report, meshes[m]);
            tpk_check_report_free(&report);
            CHECK_EQ_INT(rc, 0);
            CHECK_MSG(total == 0, "%s, layouts %u: %lld findings", meshes[m], layouts[l], (long long)total);
        }
    }
}

/* spec §13: the files a reader must read are clean; of those it must refuse, the one that opens (a bad
 * chunk checksum is found when the chunk is read) is check 600, the others do not open. */
TPK_TEST(test_vectors)
{
    static const char *const good[] = {"one_tet.tpk", "two_tets_zstd.tpk", "two_tets_cull.tpk"};
    static const char *const refused[] = {"bad_magic.tpk",        "truncated.tpk",  "newer_major.tpk",
                                          "unknown_required_chunk.tpk", "overlap.tpk",  "nonfinite_origin.tpk",
                                          "empty_fdsc.tpk",       "implausible_zstd_size.tpk"};
    /* Those that open and break rule 16 or 17 in one chunk: check 600 names the rule and the chunk. */
    static const struct {
        const char *name, *rule, *tag;
        int64_t chunk;
    } opened[] = {
        {"chunk_checksum.tpk", "TPK-R16", "'FDAT'", 6},
        {"zstd_skippable_frame.tpk", "TPK-R16", "'POS3'", 0},
        {"zstd_chunk_checksum.tpk", "TPK-R16", "'POS3'", 0},
        {"tet16_vx.tpk", "TPK-R17", "'TT16'", 3},
        {"cull_block_count.tpk", "TPK-R17", "'CULL'", 12},
    };
    char path[1024];
    tpk_check_report report;
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        snprintf(path, sizeof path, "%s/samples/vectors/%s", TPK_SOURCE_DIR, good[i]);
        CHECK_EQ_INT(run_6xx(path, &report), 0);
        int64_t total = total_6xx(&report, good[i]);
        tpk_check_report_free(&report);
        CHECK_EQ_INT(total, 0);
    }
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; i++) {
        snprintf(path, sizeof path, "%s/samples/vectors/%s", TPK_SOURCE_DIR, refused[i]);
        CHECK_EQ_INT(run_6xx(path, &report), 1);
        tpk_check_report_free(&report);
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        CHECK(tpk_check_report_init(&report, &(tpk_check_options){.max_examples = 5}) == 0);
        CHECK_EQ_INT(tpk_check_path(path, NULL, &report, &diag), -1); /* `tetpack check` exits 2 */
        tpk_check_report_free(&report);
        CHECK_MSG(strstr(diag.message, refused[i]) != NULL, "%s", diag.message);
    }
    for (size_t i = 0; i < sizeof opened / sizeof opened[0]; i++) {
        snprintf(path, sizeof path, "%s/samples/vectors/%s", TPK_SOURCE_DIR, opened[i].name);
        CHECK_EQ_INT(run_6xx(path, &report), 0);
        tpk_finding *f = tpk_check_finding(&report, 600);
        int ok = f->count == 1 && total_6xx(&report, opened[i].name) == 1 && f->example_count == 1 &&
                 strstr(f->examples[0].note, opened[i].rule) && strstr(f->examples[0].note, opened[i].tag) &&
                 f->examples[0].ids[0] == opened[i].chunk && strstr(f->summary, "not run");
        tpk_check_report_free(&report);
        CHECK_MSG(ok, "%s", opened[i].name);
    }
    /* §13.6: every word within rule 17, but the seed's n3 is not tet 0's neighbor opposite 4: 616 alone. */
    snprintf(path, sizeof path, "%s/samples/vectors/cull_bad_seed.tpk", TPK_SOURCE_DIR);
    CHECK_EQ_INT(run_6xx(path, &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 616);
    int ok = f->count == 1 && total_6xx(&report, "cull_bad_seed") == 1 && f->example_count == 1 &&
             !strcmp(f->examples[0].kind, "block") && f->examples[0].id_count == 3 && f->examples[0].ids[0] == 0 &&
             f->examples[0].ids[1] == 0 && f->examples[0].ids[2] == 0 &&
             strstr(f->examples[0].note, "n3 is 1, but the tet across the face opposite its largest id 4 is -1");
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* ---- 600: reader rules -------------------------------------------------------------------------- */

TPK_TEST(file_rule_checksum_and_ids)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    t32[7].n[2] = (int32_t)ps.header.tet_count; /* one past the last tet: rule 17 */
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "ids.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 600);
    int ok = f->count == 1 && total_6xx(&report, "ids") == 1 && strstr(f->examples[0].note, "TPK-R17") &&
             strstr(f->examples[0].note, "record 7");
    tpk_check_report_free(&report);
    CHECK(ok);

    /* One byte of a chunk changed after writing: the checksum (rule 16). */
    const char *path = tpk_temp_path("flip.tpk");
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0 && parts_write(&ps, path) == 0);
    parts_free(&ps);
    tpk_file *tf;
    uint64_t i;
    tpk_dir_entry e;
    CHECK(tpk_open_path(&tf, path, NULL, NULL, 0) == TPK_OK);
    CHECK(tpk_find_chunk(tf, TPK_TAG_TT16, 0, 0, &i) == TPK_OK && tpk_get_chunk(tf, i, &e) == TPK_OK);
    tpk_close(tf);
    FILE *file = fopen(path, "r+b");
    CHECK(file != NULL);
    fseek(file, (long)e.offset + 100, SEEK_SET);
    int byte = fgetc(file);
    fseek(file, (long)e.offset + 100, SEEK_SET);
    fputc(byte ^ 0x10, file);
    fclose(file);
    CHECK_EQ_INT(run_6xx(path, &report), 0);
    ok = found(&report, 600) == 1 && total_6xx(&report, "flip") == 1 &&
         strstr(tpk_check_finding(&report, 600)->examples[0].note, "TPK-R16");
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* Rule 17 (format 1.1): in a layout without vertex ids, vx is below the smallest power of two >= V,
 * since it is the xor of ids in [0, V). One vx beyond it in Tet16 (which rule 17 did not read before)
 * and one in Tet20 are check 600, naming the rule, the chunk and the record. */
TPK_TEST(file_rule_vx_bound)
{
    static const uint32_t tags[2] = {TPK_TAG_TT16, TPK_TAG_TT20};
    for (int l = 0; l < 2; l++) {
        parts ps;
        CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
        parts_remove(&ps, TPK_TAG_TT32);
        parts_remove(&ps, tags[1 - l]);
        int32_t *vx = parts_data(&ps, tags[l]); /* vx is the first i32 of both records */
        size_t stride = tags[l] == TPK_TAG_TT16 ? 4 : 5;
        vx[stride * 9] ^= 0x40000000;
        tpk_check_report report;
        CHECK_EQ_INT(check_parts(&ps, "vx.tpk", &report), 0);
        tpk_finding *f = tpk_check_finding(&report, 600);
        int ok = f->count == 1 && total_6xx(&report, "vx") == 1 && strstr(f->examples[0].note, "TPK-R17") &&
                 strstr(f->examples[0].note, "record 9") && strstr(f->examples[0].note, "vx =");
        tpk_check_report_free(&report);
        CHECK_MSG(ok, "layout %s", l ? "TT20" : "TT16");
    }
}

/* The writer half of rule 15 (spec §7.1): a field name must be NUL-padded and valid UTF-8. */
TPK_TEST(file_rule_field_text)
{
    parts ps;
    CHECK(parts_from(exomerge_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_field_desc *d = parts_data(&ps, TPK_TAG_FDSC);
    CHECK(d != NULL);
    d[1].name[62] = 'x'; /* after the terminating NUL */
    d[2].units[0] = (char)0xC3; /* a lead byte without its continuation */
    d[2].units[1] = 0;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "text.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 600);
    int ok = f->count == 2 && total_6xx(&report, "text") == 2 && f->examples[0].ids[0] == 1 &&
             strstr(f->examples[0].note, "after its terminating NUL") && strstr(f->examples[1].note, "UTF-8");
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* ---- 601..610: tets, adjacency, shell ----------------------------------------------------------- */

TPK_TEST(m01_repeated_id)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    int64_t t = interior_tet(t32, (int64_t)ps.header.tet_count);
    int32_t v3 = t32[t].vx ^ t32[t].v[0] ^ t32[t].v[1] ^ t32[t].v[2];
    t32[t].v[1] = t32[t].v[0]; /* keep the fourth id: vx follows */
    t32[t].vx = t32[t].v[0] ^ t32[t].v[1] ^ t32[t].v[2] ^ v3;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m01.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 601);
    int ok = f->count == 1 && f->examples[0].ids[0] == t && total_6xx(&report, "m01") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* The xor that moves all four ids of a tet into [V, 2^k), 2^k the smallest power of two >= V: ids no
 * vertex has, from a vx that rule 17's bound still admits. 0 when there is none. */
static int32_t delta_out_of_range(const tpk_tet32 *tet, uint64_t vertex_count)
{
    uint64_t limit = 1;
    while (limit < vertex_count)
        limit <<= 1;
    int32_t v[4] = {tet->v[0], tet->v[1], tet->v[2], tet->vx ^ tet->v[0] ^ tet->v[1] ^ tet->v[2]};
    for (int32_t delta = 1; (uint64_t)delta < limit; delta++) {
        int all = 1;
        for (int k = 0; k < 4; k++)
            all &= (uint64_t)(v[k] ^ delta) >= vertex_count && (uint64_t)(v[k] ^ delta) < limit;
        if (all)
            return delta;
    }
    return 0;
}

/* Tet20 alone: a vx that gives no valid fourth id from any face leaves the tet without ids. */
TPK_TEST(m01_walk_bad_apex)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    const tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    int64_t t = interior_tet(t32, (int64_t)ps.header.tet_count);
    int32_t delta = delta_out_of_range(&t32[t], ps.header.vertex_count);
    CHECK(delta != 0);
    parts_remove(&ps, TPK_TAG_TT32);
    parts_remove(&ps, TPK_TAG_TT16);
    tpk_tet20 *t20 = parts_data(&ps, TPK_TAG_TT20);
    t20[t].vx ^= delta;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m01w.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 601);
    int ok = f->count == 1 && f->examples[0].ids[0] == t && strstr(f->summary, "not recoverable") &&
             total_6xx(&report, "m01w") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* A tet turned over (two ids and their neighbors swapped) is negative on the stored positions; its
 * neighbors still lie across its faces (no 606), and the other layouts still agree (no 608). */
TPK_TEST(m02_flipped_tet)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    int64_t t = interior_tet(t32, (int64_t)ps.header.tet_count);
    int32_t v = t32[t].v[0], n = t32[t].n[0];
    t32[t].v[0] = t32[t].v[1];
    t32[t].v[1] = v;
    t32[t].n[0] = t32[t].n[1];
    t32[t].n[1] = n;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m02.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 602);
    int ok = f->count == 1 && f->examples[0].ids[0] == t && f->examples[0].has_point &&
             strstr(f->examples[0].note, "negative") && total_6xx(&report, "m02") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* Exact decisions: an apex 2^-30 below the unit triangle is a valid tet (no float epsilon calls it
 * flat) on the far side of its neighbor; in the plane it is flat (602). */
TPK_TEST(m02_m06_near_misses)
{
    static const int32_t tets[2][4] = {{0, 1, 2, 3}, {0, 2, 1, 4}};
    static const int32_t nb[2][4] = {{-1, -1, -1, 1}, {-1, -1, -1, 0}};
    tpk_check_report report;
    small_pos[4][0] = small_pos[4][1] = 0.25f;
    small_pos[4][2] = -ldexpf(1, -30);
    CHECK_EQ_INT(check_small("thin.tpk", tets, nb, 2, &report), 0);
    int64_t total = total_6xx(&report, "thin");
    tpk_check_report_free(&report);
    CHECK_EQ_INT(total, 0);
    small_pos[4][2] = 0;
    CHECK_EQ_INT(check_small("flat.tpk", tets, nb, 2, &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 602);
    int ok = f->count == 1 && f->examples[0].ids[0] == 1 && strstr(f->examples[0].note, "zero");
    total_6xx(&report, "flat");
    tpk_check_report_free(&report);
    CHECK(ok);
}

TPK_TEST(m03_vx)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_tet20 *t20 = parts_data(&ps, TPK_TAG_TT20);
    tpk_tet16 *t16 = parts_data(&ps, TPK_TAG_TT16);
    t20[5].vx ^= 1;
    t16[9].vx ^= 2;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m03.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 603);
    int ok = f->count == 2 && f->examples[0].ids[0] == 5 && strstr(f->examples[0].note, "Tet20") &&
             f->examples[1].ids[0] == 9 && strstr(f->examples[1].note, "Tet16") && total_6xx(&report, "m03") == 2;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* t names u, u names -1 across the same face: one asymmetric slot (604); the face then is a boundary
 * face of u while t has it (605) and has no SHEL record (609). */
TPK_TEST(m04_one_sided_neighbor)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), TPK_LAYOUT_BIT_TET32, &ps) == 0);
    tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    int64_t t = interior_tet(t32, (int64_t)ps.header.tet_count);
    int32_t u = t32[t].n[2];
    t32[t].n[2] = -1;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m04.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 604);
    int ok = f->count == 1 && f->examples[0].ids[0] == u && f->examples[0].ids[1] == t &&
             found(&report, 605) == 1 && found(&report, 609) == 1 && total_6xx(&report, "m04") == 3;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* Three tets on one face (a pair and a third with -1 there); two tets with the same face, both -1. */
TPK_TEST(m05_face_use)
{
    static const int32_t three[3][4] = {{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}};
    static const int32_t three_nb[3][4] = {{-1, -1, -1, 1}, {-1, -1, -1, 0}, {-1, -1, -1, -1}};
    static const int32_t two_nb[2][4] = {{-1, -1, -1, -1}, {-1, -1, -1, -1}};
    small_pos[4][0] = small_pos[4][1] = 0.25f;
    small_pos[4][2] = -1;
    tpk_check_report report;
    CHECK_EQ_INT(check_small("m05a.tpk", three, three_nb, 3, &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 605);
    int ok = f->count == 1 && f->examples[0].id_count == 6 && f->examples[0].ids[0] == 0 &&
             f->examples[0].ids[1] == 1 && f->examples[0].ids[2] == 2 && f->examples[0].ids[5] == 2 &&
             total_6xx(&report, "m05a") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
    CHECK_EQ_INT(check_small("m05b.tpk", three, two_nb, 2, &report), 0);
    f = tpk_check_finding(&report, 605);
    ok = f->count == 1 && strstr(f->examples[0].note, "-1") && total_6xx(&report, "m05b") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
    /* Near miss: the same two tets as neighbors. */
    CHECK_EQ_INT(check_small("m05c.tpk", three, three_nb, 2, &report), 0);
    int64_t total = total_6xx(&report, "m05c");
    tpk_check_report_free(&report);
    CHECK_EQ_INT(total, 0);
}

/* Two positive tets on the same side of their shared face, linked as neighbors (606), and cut (valid). */
TPK_TEST(m06_fold)
{
    static const int32_t tets[2][4] = {{0, 1, 2, 3}, {0, 1, 2, 5}};
    static const int32_t nb[2][4] = {{-1, -1, -1, 1}, {-1, -1, -1, 0}};
    small_pos[4][0] = small_pos[4][1] = 0.25f;
    small_pos[4][2] = -1;
    tpk_check_report report;
    CHECK_EQ_INT(check_small("m06.tpk", tets, nb, 2, &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 606);
    int ok = f->count == 1 && f->examples[0].ids[0] == 0 && f->examples[0].ids[1] == 1 &&
             total_6xx(&report, "m06") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
    /* The same fold with its adjacency cut (spec §6.7): both faces are shell faces, and the file is valid;
     * m05_face_use has the same cut between tets on opposite sides, which stays 605. */
    static const int32_t cut[2][4] = {{-1, -1, -1, -1}, {-1, -1, -1, -1}};
    CHECK_EQ_INT(check_small("m06cut.tpk", tets, cut, 2, &report), 0);
    int64_t total = total_6xx(&report, "m06cut");
    tpk_check_report_free(&report);
    CHECK_EQ_INT(total, 0);
}

/* Two neighbors swapped between their slots, in Tet32 alone and in Tet20 alone. */
TPK_TEST(m07_neighbor_order)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), TPK_LAYOUT_BIT_TET32, &ps) == 0);
    tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    int64_t t = interior_tet(t32, (int64_t)ps.header.tet_count);
    int32_t n = t32[t].n[1];
    t32[t].n[1] = t32[t].n[3];
    t32[t].n[3] = n;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m07a.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 607);
    int ok = f->count == 1 && f->examples[0].ids[0] == t && total_6xx(&report, "m07a") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);

    CHECK(parts_from(cylinder_all(), TPK_LAYOUT_BIT_TET20, &ps) == 0);
    tpk_tet20 *t20 = parts_data(&ps, TPK_TAG_TT20);
    n = t20[t].n[0];
    t20[t].n[0] = t20[t].n[2];
    t20[t].n[2] = n;
    CHECK_EQ_INT(check_parts(&ps, "m07b.tpk", &report), 0);
    f = tpk_check_finding(&report, 607);
    ok = f->count == 1 && f->examples[0].ids[0] == t && strstr(f->examples[0].note, "Tet20") &&
         total_6xx(&report, "m07b") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* Tet16 that does not decode to the other layouts' neighbors; Tet20 naming another neighbor than
 * Tet32; and a Tet16-only file whose record cannot be decoded from any entry. */
TPK_TEST(m08_layouts)
{
    parts ps;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_tet16 *t16 = parts_data(&ps, TPK_TAG_TT16);
    tpk_tet20 *t20 = parts_data(&ps, TPK_TAG_TT20);
    t16[11].nx[0] ^= 4;
    t20[12].n[0] = t20[12].n[0] == 0 ? 1 : 0;
    tpk_check_report report;
    CHECK_EQ_INT(check_parts(&ps, "m08a.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 608);
    int ok = f->count == 2 && f->examples[0].ids[0] == 11 && strstr(f->examples[0].note, "Tet16") &&
             f->examples[1].ids[0] == 12 && strstr(f->examples[1].note, "Tet20") && total_6xx(&report, "m08a") == 2;
    tpk_check_report_free(&report);
    CHECK(ok);

    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    int64_t t = interior_tet(parts_data(&ps, TPK_TAG_TT32), (int64_t)ps.header.tet_count);
    parts_remove(&ps, TPK_TAG_TT32);
    parts_remove(&ps, TPK_TAG_TT20);
    t16 = parts_data(&ps, TPK_TAG_TT16);
    t16[t].nx[1] ^= 0x40000000; /* every decoding of it gives an id far out of range */
    CHECK_EQ_INT(check_parts(&ps, "m08b.tpk", &report), 0);
    f = tpk_check_finding(&report, 608);
    ok = f->count == 1 && f->examples[0].ids[0] == t && strstr(f->summary, "not recoverable from Tet16") &&
         total_6xx(&report, "m08b") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

static void drop_last_shell_face(parts *ps)
{
    ps->header.shell_face_count--;
    parts_get(ps, TPK_TAG_SHEL, 0, 0)->desc.elem_count--;
}

/* A boundary face missing from SHEL (in Tet32 and in a Tet16-only file), and a record listed twice. */
TPK_TEST(m09_shell_complete)
{
    parts ps;
    tpk_check_report report;
    for (int layout = 0; layout < 2; layout++) {
        CHECK(parts_from(cylinder_all(), layout ? TPK_LAYOUT_BIT_TET16 : TPK_LAYOUT_BIT_TET32, &ps) == 0);
        tpk_shell_face last = ((tpk_shell_face *)parts_data(&ps, TPK_TAG_SHEL))[ps.header.shell_face_count - 1];
        drop_last_shell_face(&ps);
        CHECK_EQ_INT(check_parts(&ps, "m09a.tpk", &report), 0);
        tpk_finding *f = tpk_check_finding(&report, 609);
        int ok = f->count == 1 && f->examples[0].ids[0] == last.t && total_6xx(&report, "m09a") == 1;
        tpk_check_report_free(&report);
        CHECK_MSG(ok, "layout %d", layout);
    }
    CHECK(parts_from(cylinder_all(), TPK_LAYOUT_BIT_TET32, &ps) == 0);
    tpk_shell_face *shell = parts_data(&ps, TPK_TAG_SHEL);
    shell[1] = shell[0]; /* record 0 twice, record 1's face missing */
    CHECK_EQ_INT(check_parts(&ps, "m09b.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 609);
    int ok = f->count == 2 && f->examples[0].ids[0] == 1 && strstr(f->examples[0].note, "twice") &&
             total_6xx(&report, "m09b") == 2;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* A SHEL record turned over faces inward; rotated it is the same face (near miss). */
TPK_TEST(m10_shell_outward)
{
    parts ps;
    tpk_check_report report;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_shell_face *shell = parts_data(&ps, TPK_TAG_SHEL);
    int32_t b = shell[3].b;
    shell[3].b = shell[3].c;
    shell[3].c = b;
    shell[4] = (tpk_shell_face){shell[4].b, shell[4].c, shell[4].a, shell[4].t};
    CHECK_EQ_INT(check_parts(&ps, "m10.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 610);
    int ok = f->count == 1 && f->examples[0].ids[0] == 3 && strstr(f->examples[0].note, "inward") &&
             total_6xx(&report, "m10") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* ---- 611..613: values --------------------------------------------------------------------------- */

/* Bounds one ulp off; a non-finite position inside the box (bounds unchanged). */
TPK_TEST(m11_positions)
{
    parts ps;
    tpk_check_report report;
    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    ps.header.bounds_max[1] = nextafter(ps.header.bounds_max[1], INFINITY);
    CHECK_EQ_INT(check_parts(&ps, "m11a.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 611);
    int ok = f->count == 1 && strstr(f->examples[0].note, "bounds_max y") && total_6xx(&report, "m11a") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);

    CHECK(parts_from(cylinder_all(), ALL_LAYOUTS, &ps) == 0);
    float *pos = parts_data(&ps, TPK_TAG_POS3);
    int64_t inside = -1;
    for (int64_t i = 0; i < (int64_t)ps.header.vertex_count && inside < 0; i++) {
        int in = 1;
        for (int a = 0; a < 3; a++)
            in &= ps.header.origin[a] + pos[3 * i + a] > ps.header.bounds_min[a] &&
                  ps.header.origin[a] + pos[3 * i + a] < ps.header.bounds_max[a];
        inside = in ? i : -1;
    }
    CHECK(inside >= 0);
    pos[3 * inside + 2] = NAN;
    CHECK_EQ_INT(check_parts(&ps, "m11b.tpk", &report), 0);
    f = tpk_check_finding(&report, 611);
    ok = f->count == 1 && f->examples[0].ids[0] == inside && total_6xx(&report, "m11b") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* A field's min_value one ulp low; a NaN among the values, which the range ignores (near miss). */
TPK_TEST(m12_field_range)
{
    parts ps;
    tpk_check_report report;
    CHECK(parts_from(exomerge_all(), ALL_LAYOUTS, &ps) == 0);
    tpk_field_desc *d = parts_data(&ps, TPK_TAG_FDSC);
    CHECK(d != NULL && d[0].step_count == 5);
    d[0].min_value = nextafterf(d[0].min_value, -INFINITY);
    float *values = parts_get(&ps, TPK_TAG_FDAT, 1, 2)->data; /* field 1, step 2 */
    int64_t pick = -1;
    for (int64_t i = 0; i < (int64_t)ps.header.vertex_count && pick < 0; i++)
        pick = values[i] > d[1].min_value && values[i] < d[1].max_value ? i : -1;
    CHECK(pick >= 0);
    values[pick] = NAN;
    CHECK_EQ_INT(check_parts(&ps, "m12.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 612);
    int ok = f->count == 1 && f->examples[0].ids[0] == 0 && total_6xx(&report, "m12") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* An infinite time value; VMAP -2 (out of range) and -1 (an added point: near miss). */
TPK_TEST(m13_values)
{
    parts ps;
    tpk_check_report report;
    CHECK(parts_from(exomerge_all(), ALL_LAYOUTS, &ps) == 0);
    double *time = parts_data(&ps, TPK_TAG_TIME);
    int32_t *vmap = parts_data(&ps, TPK_TAG_VMAP);
    CHECK(time != NULL && vmap != NULL);
    time[3] = INFINITY;
    vmap[10] = -2;
    vmap[11] = -1;
    CHECK_EQ_INT(check_parts(&ps, "m13.tpk", &report), 0);
    tpk_finding *f = tpk_check_finding(&report, 613);
    int ok = f->count == 2 && strstr(f->examples[0].note, "TIME[3]") && f->examples[1].ids[0] == 10 &&
             total_6xx(&report, "m13") == 2;
    tpk_check_report_free(&report);
    CHECK(ok);
    /* A negative TMAP value breaks rule 17 already: 600. */
    CHECK(parts_from(exomerge_all(), ALL_LAYOUTS, &ps) == 0);
    ((int32_t *)parts_data(&ps, TPK_TAG_TMAP))[5] = -1;
    CHECK_EQ_INT(check_parts(&ps, "tmap.tpk", &report), 0);
    ok = found(&report, 600) == 1 && total_6xx(&report, "tmap") == 1;
    tpk_check_report_free(&report);
    CHECK(ok);
}

/* ---- the file's mesh ---------------------------------------------------------------------------- */

TPK_TEST(mesh_of_file)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/samples/vectors/two_tets_zstd.tpk", TPK_SOURCE_DIR);
    tpk_file *file;
    CHECK(tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK);
    tpk_mesh mesh;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = tpk_check_tpk_mesh(file, &mesh, &diag);
    tpk_close(file);
    CHECK_MSG(rc == 0, "%s", diag.message);
    static const int32_t conn[8] = {3, 0, 4, 1, 0, 4, 1, 2};
    int ok = mesh.point_count == 5 && mesh.cell_count == 2 && mesh.cell_types[1] == TPK_CELL_TETRA &&
             mesh.cell_offsets[2] == 8 && !memcmp(mesh.cell_conn, conn, sizeof conn) &&
             mesh.points[0] == 1000001.0 && mesh.points[1] == -2.5 && mesh.points[3 * 2 + 2] == 1.0 &&
             !strcmp(mesh.format, "tpk") && mesh.field_count == 2 && mesh.step_count == 2 && mesh.times &&
             mesh.times[1] == 0.5 && mesh.fields[0].step_count == 2 && mesh.fields[0].values[5] == 310 &&
             mesh.fields[1].association == TPK_ASSOC_TET && mesh.fields[1].values[1] == 2;
    tpk_mesh_free(&mesh);
    CHECK(ok);
}

/* Tet16 alone gives the same tets (as vertex sets) as Tet32. */
TPK_TEST(mesh_of_tet16_file)
{
    parts ps;
    tpk_mesh m32, m16;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    const char *p16 = tpk_temp_path("mesh16.tpk");
    CHECK(parts_from(cylinder_all(), TPK_LAYOUT_BIT_TET16, &ps) == 0 && parts_write(&ps, p16) == 0);
    parts_free(&ps);
    tpk_file *f32, *f16;
    CHECK(tpk_open_path(&f32, cylinder_all(), NULL, NULL, 0) == TPK_OK);
    CHECK(tpk_open_path(&f16, p16, NULL, NULL, 0) == TPK_OK);
    int rc = tpk_check_tpk_mesh(f32, &m32, &diag) | tpk_check_tpk_mesh(f16, &m16, &diag);
    tpk_close(f32);
    tpk_close(f16);
    CHECK_MSG(rc == 0, "%s", diag.message);
    int same = m32.cell_count == m16.cell_count && m32.cell_count == 1348;
    for (int64_t c = 0; same && c < m32.cell_count; c++) {
        int64_t s32 = 0, s16 = 0;
        for (int k = 0; k < 4; k++) {
            s32 += (int64_t)1 << (m32.cell_conn[4 * c + k] % 60);
            s16 += (int64_t)1 << (m16.cell_conn[4 * c + k] % 60);
            same &= m16.cell_conn[4 * c + k] == m32.cell_conn[4 * c + 0] ||
                    m16.cell_conn[4 * c + k] == m32.cell_conn[4 * c + 1] ||
                    m16.cell_conn[4 * c + k] == m32.cell_conn[4 * c + 2] ||
                    m16.cell_conn[4 * c + k] == m32.cell_conn[4 * c + 3];
        }
        same &= s32 == s16;
    }
    tpk_mesh_free(&m32);
    tpk_mesh_free(&m16);
    CHECK(same);
}

/* Many broken tets spread over the file: the counts and the examples (lowest ids first) are the same
 * whatever the number of threads, and with no examples kept the counts still are. */
TPK_TEST(examples_do_not_depend_on_threads)
{
    parts ps;
    const char *base = tpk_temp_path("cube_all.tpk"); /* 202596 tets: several workers' ranges */
    CHECK(convert("sfepy/cube_big_tetra.mesh", base, ALL_LAYOUTS, 0) == 0);
    CHECK(parts_from(base, ALL_LAYOUTS, &ps) == 0);
    int64_t tets = (int64_t)ps.header.tet_count;
    tpk_tet32 *t32 = parts_data(&ps, TPK_TAG_TT32);
    tpk_tet20 *t20 = parts_data(&ps, TPK_TAG_TT20);
    for (int64_t t = 3; t + 1 < tets; t += 97) {
        int32_t v = t32[t].v[0], n = t32[t].n[0];
        t32[t].v[0] = t32[t].v[1];
        t32[t].v[1] = v;
        t32[t].n[0] = t32[t].n[1];
        t32[t].n[1] = n;
        t20[t + 1].vx ^= 8;
    }
    const char *path = tpk_temp_path("threads.tpk");
    CHECK(parts_write(&ps, path) == 0);
    parts_free(&ps);
    tpk_check_report one, many, none;
    CHECK_EQ_INT(run_6xx_with(path, 1, 5, &one), 0);
    int same = 1;
    for (int threads = 2; threads <= 7 && same; threads += 5) {
        CHECK_EQ_INT(run_6xx_with(path, threads, 5, &many), 0);
        for (int id = 600; id <= 613; id++) {
            tpk_finding *a = tpk_check_finding(&one, id), *b = tpk_check_finding(&many, id);
            same &= a->count == b->count && a->example_count == b->example_count;
            for (int e = 0; same && e < a->example_count; e++)
                same &= !memcmp(a->examples[e].ids, b->examples[e].ids, sizeof a->examples[e].ids) &&
                        !strcmp(a->examples[e].note, b->examples[e].note);
        }
        tpk_check_report_free(&many);
    }
    CHECK_EQ_INT(run_6xx_with(path, 2, 0, &none), 0);
    int64_t flipped = (tets - 1 - 3 + 96) / 97;
    int ok = same && found(&one, 602) == flipped && found(&one, 603) == flipped &&
             tpk_check_finding(&one, 602)->examples[0].ids[0] == 3 &&
             tpk_check_finding(&one, 602)->examples[4].ids[0] == 3 + 4 * 97 && found(&none, 602) == flipped &&
             tpk_check_finding(&none, 602)->example_count == 0;
    total_6xx(&one, "threads");
    tpk_check_report_free(&one);
    tpk_check_report_free(&none);
    CHECK(ok);
}

/* Findings of two runs: the same counts, examples and summaries. */
static int same_findings(tpk_check_report *a, tpk_check_report *b)
{
    for (int id = 600; id <= 616; id++) {
        tpk_finding *x = tpk_check_finding(a, id), *y = tpk_check_finding(b, id);
        if (x->count != y->count || x->example_count != y->example_count || strcmp(x->summary, y->summary))
            return 0;
        for (int e = 0; e < x->example_count; e++)
            if (memcmp(x->examples[e].ids, y->examples[e].ids, sizeof x->examples[e].ids) ||
                strcmp(x->examples[e].note, y->examples[e].note))
                return 0;
    }
    return 1;
}

/* A Tet16-only file large enough for the walk to run in parallel: clean, it reports nothing; broken,
 * the findings are those of the serial walk (one thread), whatever the thread count. */
TPK_TEST(parallel_walk)
{
    parts ps;
    const char *base = tpk_temp_path("cube16.tpk"); /* 202596 tets, 12168 shell faces */
    CHECK(convert("sfepy/cube_big_tetra.mesh", base, ALL_LAYOUTS, 0) == 0);
    CHECK(parts_from(base, ALL_LAYOUTS, &ps) == 0);
    parts_remove(&ps, TPK_TAG_TT32);
    parts_remove(&ps, TPK_TAG_TT20);
    const char *clean = tpk_temp_path("cube16_clean.tpk");
    CHECK(parts_write(&ps, clean) == 0);
    /* b: no entry is refused, so the parallel walk is kept, and the checks on it find problems */
    tpk_shell_face *shell = parts_data(&ps, TPK_TAG_SHEL);
    shell[5000] = (tpk_shell_face){shell[5000].a, shell[5000].c, shell[5000].b, shell[5000].t};
    drop_last_shell_face(&ps);
    const char *broken_b = tpk_temp_path("cube16_broken_b.tpk");
    CHECK(parts_write(&ps, broken_b) == 0);
    /* a: records no entry can decode, so the parallel attempt gives way to the serial walk at once */
    tpk_tet16 *t16 = parts_data(&ps, TPK_TAG_TT16);
    for (int64_t t = 1000; t < 200000; t += 20011)
        t16[t].nx[2] ^= 0x20000000;
    const char *broken = tpk_temp_path("cube16_broken.tpk");
    CHECK(parts_write(&ps, broken) == 0);
    parts_free(&ps);
    tpk_check_report serial, parallel;
    for (int threads = 2; threads <= 4; threads += 2) {
        CHECK_EQ_INT(run_6xx_with(clean, threads, 5, &parallel), 0);
        int64_t total = total_6xx(&parallel, "cube16 clean");
        tpk_check_report_free(&parallel);
        CHECK_EQ_INT(total, 0);
    }
    const char *files[2] = {broken, broken_b};
    for (int f = 0; f < 2; f++) {
        CHECK_EQ_INT(run_6xx_with(files[f], 1, 5, &serial), 0);
        int ok = f == 0 ? found(&serial, 608) == 10 : found(&serial, 610) >= 1 && found(&serial, 609) >= 1;
        for (int threads = 2; threads <= 4 && ok; threads += 2) {
            CHECK_EQ_INT(run_6xx_with(files[f], threads, 5, &parallel), 0);
            ok = same_findings(&serial, &parallel);
            tpk_check_report_free(&parallel);
        }
        total_6xx(&serial, files[f]);
        tpk_check_report_free(&serial);
        CHECK_MSG(ok, "%s", files[f]);
    }
}

/* ---- 616: culling blocks (TPK-B01) ------------------------------------------------------------- */

/* CULL words as spec §17.4 describes them, built here from the library's recovered tets (each in its
 * canonical positive order) and Tet20's neighbors by rank: blocks of B tets; seeds in tet order, each
 * the first tet of the block the seeds before it do not reach, with n3 = Tet20's n[3]; intervals of the
 * block's vertex ids, one across runs of at most `gap` missing ids. piece[s] receives the tets seed s
 * reaches first. */
typedef struct cull_words {
    int32_t *w;
    size_t count;
    int64_t K, S, I;
    int64_t *piece;
} cull_words;

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

static int build_cull(const int32_t *tets, const tpk_tet20 *t20, int64_t T, int64_t B, int32_t gap, cull_words *out)
{
    memset(out, 0, sizeof *out);
    int64_t K = (T + B - 1) / B;
    int32_t *seeds = malloc(sizeof *seeds * (size_t)(6 * T + 1)), *intervals = malloc(sizeof *intervals * (size_t)(8 * T + 1));
    int64_t *seed_start = calloc((size_t)K + 1, sizeof *seed_start), *interval_start = calloc((size_t)K + 1, sizeof *interval_start);
    int32_t *ids = malloc(sizeof *ids * (size_t)(4 * B)), *queue = malloc(sizeof *queue * (size_t)B);
    uint8_t *reached = malloc((size_t)B);
    out->piece = malloc(sizeof *out->piece * (size_t)(T + 1));
    int64_t S = 0, I = 0;
    int ok = seeds && intervals && seed_start && interval_start && ids && queue && reached && out->piece;
    for (int64_t k = 0; ok && k < K; k++) {
        int64_t t0 = k * B, t1 = t0 + B < T ? t0 + B : T;
        memset(reached, 0, (size_t)B);
        for (int64_t t = t0; t < t1; t++) {
            if (reached[t - t0])
                continue;
            int32_t *seed = seeds + 6 * S;
            seed[0] = (int32_t)t;
            memcpy(seed + 1, tets + 4 * t, 4 * sizeof *seed);
            seed[5] = t20[t].n[3];
            int64_t head = 0, tail = 0;
            queue[tail++] = (int32_t)t;
            reached[t - t0] = 1;
            while (head < tail) {
                const int32_t *n = t20[queue[head++]].n;
                for (int f = 0; f < 4; f++)
                    if (n[f] >= t0 && n[f] < t1 && !reached[n[f] - t0]) {
                        reached[n[f] - t0] = 1;
                        queue[tail++] = n[f];
                    }
            }
            out->piece[S++] = tail;
        }
        seed_start[k + 1] = S;
        int64_t n = 4 * (t1 - t0);
        memcpy(ids, tets + 4 * t0, sizeof *ids * (size_t)n);
        qsort(ids, (size_t)n, sizeof *ids, cmp_i32);
        for (int64_t i = 0; i < n;) {
            int32_t first = ids[i], last = ids[i];
            while (i < n && ids[i] - last - 1 <= gap)
                last = ids[i++];
            intervals[2 * I] = first;
            intervals[2 * I++ + 1] = last + 1;
        }
        interval_start[k + 1] = I;
    }
    if (ok) {
        out->count = 4 + 2 * ((size_t)K + 1) + 6 * (size_t)S + 2 * (size_t)I;
        out->w = malloc(sizeof *out->w * out->count);
        ok = out->w != NULL;
    }
    if (ok) {
        int32_t *w = out->w;
        *w++ = (int32_t)B, *w++ = (int32_t)K, *w++ = (int32_t)S, *w++ = (int32_t)I;
        for (int64_t k = 0; k <= K; k++)
            *w++ = (int32_t)seed_start[k];
        for (int64_t k = 0; k <= K; k++)
            *w++ = (int32_t)interval_start[k];
        memcpy(w, seeds, sizeof *w * (size_t)(6 * S));
        memcpy(w + 6 * S, intervals, sizeof *w * (size_t)(2 * I));
        out->K = K, out->S = S, out->I = I;
    }
    free(seeds), free(intervals), free(seed_start), free(interval_start), free(ids), free(queue), free(reached);
    return ok ? 0 : -1;
}

static void cull_words_free(cull_words *c)
{
    free(c->w);
    free(c->piece);
    memset(c, 0, sizeof *c);
}

/* The words' parts: the starts, seed s, interval i. */
static int32_t *cull_seed_start(cull_words *c) { return c->w + 4; }
static int32_t *cull_interval_start(cull_words *c) { return c->w + 4 + c->K + 1; }
static int32_t *cull_seed(cull_words *c, int64_t s) { return c->w + 4 + 2 * (c->K + 1) + 6 * s; }
static int32_t *cull_interval(cull_words *c, int64_t i) { return c->w + 4 + 2 * (c->K + 1) + 6 * c->S + 2 * i; }

/* The recovered tets and Tet20 of the cylinder, and its CULL words of blocks of B. */
typedef struct cull_base {
    parts ps;
    int32_t *tets;
    int64_t T;
} cull_base;

static int cull_base_read(cull_base *b)
{
    memset(b, 0, sizeof *b);
    tpk_file *file;
    tpk_mesh_arrays m;
    if (parts_from(cylinder_all(), ALL_LAYOUTS, &b->ps) || tpk_open_path(&file, cylinder_all(), NULL, NULL, 0) != TPK_OK)
        return -1;
    b->T = (int64_t)b->ps.header.tet_count;
    b->tets = malloc(sizeof *b->tets * (size_t)(4 * b->T));
    int rc = !b->tets || tpk_load_arrays(file, TPK_LAYOUT_TET20, NULL, 0, &m) != TPK_OK ||
             tpk_recover_tets(&m, b->tets) != TPK_OK;
    tpk_close(file);
    return rc ? -1 : 0;
}

/* The cylinder with `keep` layouts and the CULL words, written and checked. */
static int check_with_cull(unsigned keep, const cull_words *c, const char *name, tpk_check_report *report)
{
    parts ps;
    if (parts_from(cylinder_all(), keep, &ps) || ps.count >= MAX_PARTS)
        return -1;
    part *p = &ps.p[ps.count++];
    p->desc = (tpk_chunk_desc){TPK_TAG_CULL, 0, TPK_CODEC_NONE, TPK_ELEM_I32, 4, 0, 0, c->count, 0};
    p->data = malloc(sizeof *c->w * c->count);
    if (!p->data) {
        parts_free(&ps);
        return -1;
    }
    memcpy(p->data, c->w, sizeof *c->w * c->count);
    return check_parts(&ps, name, report);
}

/* Blocks built by §17.4 check clean in every layout alone and all three, for blocks of 16 (the least:
 * many blocks, some in pieces) and 256 (the converter's), with intervals across gaps of 32 unused ids
 * (more ids than the tets use) and of none (the converter's). */
TPK_TEST(b01_clean_blocks)
{
    cull_base b;
    CHECK(cull_base_read(&b) == 0);
    static const unsigned layouts[4] = {TPK_LAYOUT_BIT_TET16, TPK_LAYOUT_BIT_TET20, TPK_LAYOUT_BIT_TET32,
                                        ALL_LAYOUTS};
    static const int64_t blocks[2] = {16, 256};
    const tpk_tet20 *t20 = parts_data(&b.ps, TPK_TAG_TT20);
    for (int k = 0; k < 2; k++) {
        cull_words c;
        CHECK(build_cull(b.tets, t20, b.T, blocks[k], k ? 0 : 32, &c) == 0);
        CHECK_MSG(c.K == (b.T + blocks[k] - 1) / blocks[k] && c.S >= c.K, "%lld blocks, %lld seeds", (long long)c.K,
                  (long long)c.S);
        for (int l = 0; l < 4; l++) {
            tpk_check_report report;
            CHECK_EQ_INT(check_with_cull(layouts[l], &c, "cull_clean.tpk", &report), 0);
            int64_t total = total_6xx(&report, "cull clean");
            tpk_check_report_free(&report);
            CHECK_MSG(total == 0, "B %lld, layouts %u: %lld findings", (long long)blocks[k], layouts[l], (long long)total);
        }
        cull_words_free(&c);
    }
    free(b.tets);
    parts_free(&b.ps);
}

/* One content rule broken at a time, in a Tet16-only file (ids from the walk) and in Tet32 alone: the
 * exact count under 616, nothing else. */
TPK_TEST(b01_broken_blocks)
{
    cull_base b;
    CHECK(cull_base_read(&b) == 0);
    const tpk_tet20 *t20 = parts_data(&b.ps, TPK_TAG_TT20);
    cull_words c;
    CHECK(build_cull(b.tets, t20, b.T, 16, 32, &c) == 0);
    /* a block in pieces: its second seed, and what that seed alone reaches */
    int64_t split = -1;
    for (int64_t k = 0; k < c.K && split < 0; k++)
        if (cull_seed_start(&c)[k + 1] - cull_seed_start(&c)[k] >= 2)
            split = k;
    CHECK_MSG(split >= 0, "no block of 16 tets in pieces among %lld: the removed-seed case cannot run", (long long)c.K);
    enum { ODD, N3, NOT_ITS_IDS, SEED_REMOVED, INTERVAL_SHORT, CASES };
    static const char *const want[CASES] = {"odd permutation", "n3 is", "are not the tet's", "is not reached",
                                            "lies in none of block 0's"};
    for (int layout = 0; layout < 2; layout++) {
        unsigned keep = layout ? TPK_LAYOUT_BIT_TET32 : TPK_LAYOUT_BIT_TET16;
        for (int kase = 0; kase < CASES; kase++) {
            cull_words d = c;
            d.w = malloc(sizeof *d.w * c.count);
            CHECK(d.w != NULL);
            if (!d.w)
                return;
            memcpy(d.w, c.w, sizeof *d.w * c.count);
            int64_t expected = 1;
            int32_t *seed = cull_seed(&d, 3);
            if (kase == ODD) {
                int32_t a = seed[1];
                seed[1] = seed[2], seed[2] = a;
            } else if (kase == N3) {
                seed[5] = seed[5] == -1 ? seed[0] : -1;
            } else if (kase == NOT_ITS_IDS) {
                int32_t v = 0;
                while (v == seed[1] || v == seed[2] || v == seed[3] || v == seed[4])
                    v++;
                seed[4] = v;
            } else if (kase == SEED_REMOVED) {
                /* drop the split block's last seed: the tets only it reached are not reached */
                int64_t s = cull_seed_start(&d)[split + 1] - 1;
                expected = c.piece[s];
                int32_t *at = cull_seed(&d, s);
                memmove(at, at + 6, sizeof *at * (size_t)(d.w + d.count - (at + 6)));
                d.count -= 6;
                d.w[2]--;
                for (int64_t k = split + 1; k <= d.K; k++)
                    cull_seed_start(&d)[k]--;
                d.S--;
            } else {
                /* block 0's last interval one id shorter: the tets of block 0 that use that id */
                int32_t *iv = cull_interval(&d, cull_interval_start(&d)[1] - 1);
                int32_t cut = --iv[1];
                expected = 0;
                for (int64_t t = 0; t < 16; t++)
                    expected += b.tets[4 * t] == cut || b.tets[4 * t + 1] == cut || b.tets[4 * t + 2] == cut ||
                                b.tets[4 * t + 3] == cut;
                if (iv[1] == iv[0]) /* an empty interval would break rule 17 instead */
                    expected = -1;
            }
            tpk_check_report report;
            CHECK_EQ_INT(check_with_cull(keep, &d, "cull_broken.tpk", &report), 0);
            tpk_finding *f = tpk_check_finding(&report, 616);
            int ok = expected > 0 && f->count == expected && total_6xx(&report, want[kase]) == expected &&
                     f->example_count >= 1 && strstr(f->examples[0].note, want[kase]) &&
                     strstr(f->summary, "at fault");
            if (!ok)
                fprintf(stderr, "layout %d, case %d: 616 count %lld, expected %lld: %s | %s\n", layout, kase,
                        (long long)f->count, (long long)expected, f->example_count ? f->examples[0].note : "",
                        f->summary);
            tpk_check_report_free(&report);
            free(d.w);
            CHECK(ok);
        }
    }
    cull_words_free(&c);
    free(b.tets);
    parts_free(&b.ps);
}

/* convert --cull: its CULL is the words spec §17.4 gives (blocks of 256, intervals the maximal runs of
 * consecutive ids; built here from the file's own tets), and the file checks clean, in Tet16 alone
 * (compressed) and all layouts, on real meshes of 1348 and 202596 tets. */
TPK_TEST(b01_converted_blocks)
{
    static const char *const meshes[2] = {"sfepy/cylinder.vtk", "sfepy/cube_big_tetra.mesh"};
    static const unsigned layouts[2] = {TPK_LAYOUT_BIT_TET16, ALL_LAYOUTS};
    for (int m = 0; m < 2; m++)
        for (int l = 0; l < 2; l++) {
            const char *path = tpk_temp_path("converted_cull.tpk");
            CHECK(convert_with(meshes[m], path, layouts[l] | TPK_LAYOUT_BIT_TET20, l == 0 ? 3 : 0, 1) == 0);
            tpk_check_report report;
            CHECK_EQ_INT(run_6xx(path, &report), 0);
            int64_t total = total_6xx(&report, meshes[m]);
            tpk_check_report_free(&report);
            CHECK_MSG(total == 0, "%s, layouts %u: %lld findings", meshes[m], layouts[l], (long long)total);
            parts ps;
            tpk_file *file = NULL;
            tpk_mesh_arrays arrays;
            CHECK(parts_read(path, &ps) == 0 && tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK);
            if (!file)
                return;
            int64_t T = (int64_t)ps.header.tet_count;
            int32_t *tets = malloc(sizeof *tets * (size_t)(4 * T));
            CHECK(tets && tpk_load_arrays(file, TPK_LAYOUT_TET20, NULL, 0, &arrays) == TPK_OK &&
                  tpk_recover_tets(&arrays, tets) == TPK_OK);
            tpk_file_info info;
            tpk_get_info(file, &info);
            tpk_close(file);
            part *written = parts_get(&ps, TPK_TAG_CULL, 0, 0);
            int32_t B = written && written->desc.elem_count ? *(const int32_t *)written->data : 0;
            cull_words c = {0};
            CHECK(B == 256 && build_cull(tets, parts_data(&ps, TPK_TAG_TT20), T, B, 0, &c) == 0);
            CHECK_MSG(info.version_minor == 4 && written && written->desc.elem_count == c.count &&
                          written->desc.flags == 0 && !memcmp(written->data, c.w, sizeof *c.w * c.count),
                      "%s: CULL of %llu words, %zu by spec §17.4 (%lld blocks, %lld seeds, %lld intervals)", meshes[m],
                      written ? (unsigned long long)written->desc.elem_count : 0ULL, c.count, (long long)c.K,
                      (long long)c.S, (long long)c.I);
            cull_words_free(&c);
            free(tets);
            parts_free(&ps);
        }
}
