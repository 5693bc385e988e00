/* Binary Medit (.meshb): refine's meshes, one small mesh written here in every version (1-4) and both
 * byte orders importing identically, skipped unknown keywords, bad input, every truncation. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "import/importers.h"
#include "convert/pipeline.h"

TPK_TEST(real_files)
{
    static const struct {
        const char *path;
        int64_t points, tets;
    } files[] = {{"nasa_refine/om6_om6-curv-no-geom.meshb", 1544, 6495},
                 {"nasa_refine/cube-sphere_cube-sphere.meshb", 5062, 26260}};
    for (int f = 0; f < 2; f++) {
        tpk_mesh m;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        CHECK_MSG(tpk_import_any(tpk_data_path(files[f].path), NULL, &m, &d) == 0, "%s", d.message);
        int64_t negative = 0;
        for (int64_t c = 0; c < m.cell_count; c++) {
            const int32_t *t = m.cell_conn + 4 * c;
            negative += tpk_orient3d_exact(m.points + 3 * t[0], m.points + 3 * t[1], m.points + 3 * t[2],
                                           m.points + 3 * t[3]) <= 0;
        }
        int ok = m.point_count == files[f].points && m.cell_count == files[f].tets && m.cell_types[0] == 10 &&
                 !strcmp(m.format, "medit-binary-v2") && m.field_count == 1;
        tpk_mesh_free(&m);
        CHECK_MSG(ok && negative == 0, "%s: counts differ or %lld tets not positive", files[f].path,
                  (long long)negative);
    }
}

/* A small file: 5 vertices, an unknown keyword (skipped), 2 tets, End. */
typedef struct writer {
    unsigned char bytes[2048];
    size_t n;
    int big, version;
    size_t keyword_at[8]; /* where each keyword starts, End included */
    int keywords;
} writer;

static void put(writer *w, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++)
        w->bytes[w->n + (size_t)(w->big ? bytes - 1 - i : i)] = (unsigned char)(v >> (8 * i));
    w->n += (size_t)bytes;
}

static void put_int(writer *w, int64_t v) { put(w, (uint64_t)v, w->version >= 4 ? 8 : 4); }

static void put_real(writer *w, double x)
{
    if (w->version == 1) {
        float f = (float)x;
        uint32_t b;
        memcpy(&b, &f, 4);
        put(w, b, 4);
    } else {
        uint64_t b;
        memcpy(&b, &x, 8);
        put(w, b, 8);
    }
}

/* Keyword header; returns where the next-offset goes, patched by end_keyword. */
static size_t begin_keyword(writer *w, int code)
{
    w->keyword_at[w->keywords++] = w->n;
    put(w, (uint64_t)code, 4);
    size_t at = w->n;
    put(w, 0, w->version >= 3 ? 8 : 4);
    return at;
}

static void end_keyword(writer *w, size_t at)
{
    size_t here = w->n;
    w->n = at;
    put(w, here, w->version >= 3 ? 8 : 4);
    w->n = here;
}

static size_t small_file(writer *w, int version, int big)
{
    static const double pts[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}};
    memset(w, 0, sizeof *w);
    w->big = big;
    w->version = version;
    put(w, 1, 4);
    put(w, (uint64_t)version, 4);
    size_t k = begin_keyword(w, 3);
    put_int(w, 3);
    end_keyword(w, k);
    k = begin_keyword(w, 4);
    put_int(w, 5);
    for (int v = 0; v < 5; v++) {
        for (int a = 0; a < 3; a++)
            put_real(w, pts[v][a]);
        put_int(w, 0);
    }
    end_keyword(w, k);
    k = begin_keyword(w, 99); /* unknown: skipped by its offset */
    put_int(w, 3);
    put(w, 0xdeadbeef, 4);
    end_keyword(w, k);
    k = begin_keyword(w, 8);
    put_int(w, 2);
    const int tets[2][5] = {{1, 2, 3, 4, 7}, {1, 3, 2, 5, 8}};
    for (int t = 0; t < 2; t++)
        for (int i = 0; i < 5; i++)
            put_int(w, tets[t][i]);
    end_keyword(w, k);
    w->keyword_at[w->keywords++] = w->n;
    put(w, 54, 4); /* End */
    return w->n;
}

TPK_TEST(every_version_and_byte_order)
{
    for (int version = 1; version <= 4; version++)
        for (int big = 0; big <= 1; big++) {
            static writer w;
            size_t n = small_file(&w, version, big);
            tpk_mesh m;
            tpk_diag d;
            memset(&d, 0, sizeof d);
            CHECK_MSG(tpk_import_meshb_memory("small.meshb", (const char *)w.bytes, n, &m, &d) == 0,
                      "version %d %s: %s", version, big ? "big" : "little", d.message);
            int ok = m.point_count == 5 && m.cell_count == 2 && m.points[3 * 4 + 2] == -1.0 &&
                     m.cell_conn[0] == 0 && m.cell_conn[7] == 4 && m.fields[0].values[1] == 8.0f;
            tpk_mesh_free(&m);
            CHECK_MSG(ok, "version %d %s: wrong contents", version, big ? "big" : "little");
        }
}

static void expect_failure(const unsigned char *bytes, size_t n, const char *what)
{
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    int rc = tpk_import_meshb_memory("bad.meshb", (const char *)bytes, n, &m, &d);
    CHECK_MSG(rc != 0 && strstr(d.message, "bad.meshb: byte ") && strstr(d.message, what), "expected '%s', got '%s'", what, d.message);
    CHECK(m.points == NULL && m.cell_count == 0);
}

TPK_TEST(bad_input)
{
    static writer w;
    size_t n = small_file(&w, 2, 0);
    expect_failure(w.bytes, 0, "expected the endianness word 1");
    unsigned char copy[2048];
    memcpy(copy, w.bytes, n);
    copy[0] = 7;
    expect_failure(copy, n, "expected the endianness word 1 of a binary Medit file, found 0x00000007");
    memcpy(copy, w.bytes, n);
    copy[4] = 5;
    expect_failure(copy, n, "expected version 1 to 4, found 5");
    memcpy(copy, w.bytes, n);
    copy[12] = 4; /* the Dimension keyword's next offset points backwards */
    copy[13] = copy[14] = copy[15] = 0;
    expect_failure(copy, n, "is not after it and inside the file");
    memcpy(copy, w.bytes, n);
    copy[28] = 0xff, copy[29] = 0xff, copy[30] = 0xff, copy[31] = 0x0f; /* Vertices count (byte 28) absurd */
    expect_failure(copy, n, "wrong count or truncated file");
    memcpy(copy, w.bytes, n);
    size_t tet0 = n - 4 - 2 * 5 * 4; /* the first tet's first id */
    copy[tet0] = 9;
    expect_failure(copy, n, "uses vertex 9, but there are only 5 vertices");
    copy[tet0] = 0;
    expect_failure(copy, n, "vertex id 0, expected 1 or more");
    memcpy(copy, w.bytes, n);
    copy[tet0 - 12] = 9; /* the Tetrahedra keyword becomes Prisms */
    expect_failure(copy, n, "Prisms are not read yet");
}

/* Every prefix is refused naming the file, except a cut where a keyword after Vertices starts: that is a
 * whole file, since the reader (like libMeshb) takes the end of the file as End. */
TPK_TEST(every_truncation)
{
    static writer w;
    size_t n = small_file(&w, 3, 1);
    int whole_count = 0;
    for (size_t cut = 0; cut < n; cut++) {
        int whole = 0;
        for (int k = 2; k < w.keywords; k++) /* keyword 0 is Dimension, 1 Vertices */
            whole |= cut == w.keyword_at[k];
        whole_count += whole;
        unsigned char *copy = malloc(cut ? cut : 1); /* exact size: an overread is caught by ASan */
        memcpy(copy, w.bytes, cut);
        tpk_mesh m;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        int rc = tpk_import_meshb_memory("cut.meshb", (const char *)copy, cut, &m, &d);
        free(copy);
        if (rc == 0)
            tpk_mesh_free(&m);
        CHECK_MSG(whole ? rc == 0 : rc != 0 && strstr(d.message, "cut.meshb: byte "), "prefix %zu (%s): '%s'", cut,
                  whole ? "a whole file" : "cut", d.message);
    }
    CHECK_EQ_INT(whole_count, 3);
}
