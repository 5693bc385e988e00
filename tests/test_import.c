/* Importer tests: VTK legacy (ASCII/BINARY, old and 5.1 cell forms) and TetGen on the real files of
 * ../shared/data, with expected values checked independently (meshio 5.0 / numpy one-off reads, noted
 * beside each number), a small mesh written in every VTK form by this test, and a corpus of bad inputs
 * that must fail with a message naming the file and the place. */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "import/importers.h"
#include "tetpack_format.h"

/* ---- helpers ------------------------------------------------------------------------------------ */

static int mesh_is_zero(const tpk_mesh *m)
{
    static const tpk_mesh zero;
    return memcmp(m, &zero, sizeof zero) == 0;
}

static const tpk_src_field *find_field(const tpk_mesh *m, const char *name)
{
    for (int i = 0; i < m->field_count; i++)
        if (!strcmp(m->fields[i].name, name))
            return &m->fields[i];
    return NULL;
}

static double field_sum(const tpk_src_field *f, int64_t n)
{
    double s = 0;
    for (int64_t i = 0; i < n * f->components; i++)
        s += f->values[i];
    return s;
}

static int64_t count_type(const tpk_mesh *m, int type)
{
    int64_t n = 0;
    for (int64_t c = 0; c < m->cell_count; c++)
        n += m->cell_types[c] == type;
    return n;
}

/* Sign of det[p1-p0, p2-p0, p3-p0] in double (well-shaped real meshes; exact decisions belong to the
 * pipeline). Returns the number of negative tets. */
static int64_t negative_tets(const tpk_mesh *m)
{
    int64_t neg = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        if (m->cell_types[c] != TPK_CELL_TETRA)
            continue;
        const int32_t *v = m->cell_conn + m->cell_offsets[c];
        const double *p0 = m->points + 3 * v[0], *p1 = m->points + 3 * v[1], *p2 = m->points + 3 * v[2],
                     *p3 = m->points + 3 * v[3];
        double a[3], b[3], d[3];
        for (int k = 0; k < 3; k++) {
            a[k] = p1[k] - p0[k];
            b[k] = p2[k] - p0[k];
            d[k] = p3[k] - p0[k];
        }
        double det = a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
                     a[2] * (b[0] * d[1] - b[1] * d[0]);
        neg += det < 0;
    }
    return neg;
}

static const char *write_temp(const char *name, const void *data, size_t size)
{
    const char *path = tpk_temp_path(name);
    FILE *f = fopen(path, "wb");
    if (!f)
        return NULL;
    fwrite(data, 1, size, f);
    fclose(f);
    return path;
}

static int quiet_warnings;
static void count_warning(void *user, const char *text)
{
    (void)user;
    if (!quiet_warnings)
        fprintf(stderr, "warning: %s\n", text);
}

static tpk_diag new_diag(void)
{
    tpk_diag d;
    memset(&d, 0, sizeof d);
    d.warn = count_warning;
    return d;
}

/* ---- real VTK files ----------------------------------------------------------------------------- */

TPK_TEST(vtk_cylinder_ascii)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("sfepy/cylinder.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 354);
    CHECK_EQ_INT(m.cell_count, 1348);
    CHECK_EQ_INT(count_type(&m, TPK_CELL_TETRA), 1348);
    CHECK(!strcmp(m.format, "vtk-legacy-ascii"));
    CHECK_EQ_INT(m.step_count, 1);
    CHECK_EQ_INT(d.warning_count, 0);
    /* meshio: points[0] = (0.1, 0.02, -1.2246063538e-18) (file text), cells[0] = 28 60 45 29,
     * cells[-1] = 353 295 139 140, mat_id sum 8088. */
    CHECK(m.points[0] == 0.1 && m.points[1] == 0.02 && m.points[2] == -1.2246063538e-18);
    CHECK((float)m.points[3 * 353 + 2] == 0.009604603052139282f);
    const int32_t first[4] = {28, 60, 45, 29}, last[4] = {353, 295, 139, 140};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    CHECK(!memcmp(m.cell_conn + m.cell_offsets[1347], last, sizeof last));
    CHECK_EQ_INT(m.cell_offsets[1348], 4 * 1348);
    CHECK_EQ_INT(m.field_count, 1);
    const tpk_src_field *f = find_field(&m, "mat_id");
    CHECK(f && f->association == TPK_ASSOC_TET && f->components == 1 && f->step_count == 1);
    CHECK(field_sum(f, 1348) == 8088.0);
    CHECK_EQ_INT(negative_tets(&m), 0);
    tpk_mesh_free(&m);
    CHECK(mesh_is_zero(&m));
}

TPK_TEST(vtk_acoustic_hex_point_and_cell_data)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("sfepy/acoustic_wg.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 1893);
    CHECK_EQ_INT(m.cell_count, 1392);
    CHECK_EQ_INT(count_type(&m, TPK_CELL_HEXAHEDRON), 1392);
    /* meshio: cells[0] = 143 144 152 151 183 186 213 210; node_groups sum 60; mat_id sum 2088;
     * points[-1] = float32 (0.325, 0.2, 0.14). */
    const int32_t first[8] = {143, 144, 152, 151, 183, 186, 213, 210};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    CHECK((float)m.points[3 * 1892] == 0.32499998807907104f && (float)m.points[3 * 1892 + 1] == 0.2f);
    const tpk_src_field *p = find_field(&m, "node_groups"), *c = find_field(&m, "mat_id");
    CHECK(p && p->association == TPK_ASSOC_POINT && p->components == 1);
    CHECK(c && c->association == TPK_ASSOC_TET && c->components == 1);
    CHECK(field_sum(p, 1893) == 60.0);
    CHECK(field_sum(c, 1392) == 2088.0);
    CHECK(c->values[0] == 1.0f && c->values[1391] == 2.0f);
    tpk_mesh_free(&m);
}

TPK_TEST(vtk_piezo_version_26)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("sfepy/piezo_mesh_micro.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 8918);
    CHECK_EQ_INT(m.cell_count, 42744);
    CHECK_EQ_INT(count_type(&m, TPK_CELL_TETRA), 42744);
    const int32_t first[4] = {994, 1163, 1128, 1243}, last[4] = {8177, 8155, 8583, 8912};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    CHECK(!memcmp(m.cell_conn + 4 * 42743, last, sizeof last));
    CHECK(field_sum(find_field(&m, "mat_id"), 42744) == 52596.0);
    CHECK_EQ_INT(negative_tets(&m), 0);
    tpk_mesh_free(&m);
}

TPK_TEST(vtk_gmsh_binary)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("gmsh/t5_small_tet_bin.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK(!strcmp(m.format, "vtk-legacy-binary"));
    CHECK_EQ_INT(m.point_count, 2857);
    CHECK_EQ_INT(m.cell_count, 13391);
    CHECK_EQ_INT(count_type(&m, TPK_CELL_TETRA), 13391);
    /* numpy (big-endian >f8/>i4 read of the blocks): points[0] = (0.5, 0.5, 0.5),
     * points[-1] = (0.8300000000000001, 0.7499999999999999, 0.8299999999999998), sum 4445.255602341804;
     * cells[0] = 251 1442 1440 1560; CellEntityIds sum 130044. */
    CHECK(m.points[0] == 0.5 && m.points[1] == 0.5 && m.points[2] == 0.5);
    CHECK(m.points[3 * 2856] == 0.8300000000000001 && m.points[3 * 2856 + 1] == 0.7499999999999999 &&
          m.points[3 * 2856 + 2] == 0.8299999999999998);
    double sum = 0;
    for (int64_t i = 0; i < 3 * 2857; i++)
        sum += m.points[i];
    CHECK(fabs(sum - 4445.255602341804) < 1e-9);
    const int32_t first[4] = {251, 1442, 1440, 1560}, last[4] = {345, 1557, 39, 2856};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    CHECK(!memcmp(m.cell_conn + 4 * 13390, last, sizeof last));
    const tpk_src_field *f = find_field(&m, "CellEntityIds");
    CHECK(f && f->association == TPK_ASSOC_TET);
    CHECK(field_sum(f, 13391) == 130044.0);
    tpk_mesh_free(&m);
}

TPK_TEST(vtk_51_ascii_inverted)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("hard/inverted_tets.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 354);
    CHECK_EQ_INT(m.cell_count, 1348);
    const int32_t first[4] = {60, 28, 45, 29};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    const tpk_src_field *f = find_field(&m, "is_inverted");
    CHECK(f && f->association == TPK_ASSOC_TET && f->components == 1);
    CHECK(field_sum(f, 1348) == 135.0);
    /* The importer keeps node order: the 135 inverted tets stay negative, and exactly those. */
    CHECK_EQ_INT(negative_tets(&m), 135);
    tpk_mesh_free(&m);
}

TPK_TEST(vtk_51_binary_degenerate)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("hard/degenerate_tets.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 1843);
    CHECK_EQ_INT(m.cell_count, 8161);
    const int32_t first[4] = {67, 76, 66, 111}, last[4] = {1582, 1495, 1767, 925};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    CHECK(!memcmp(m.cell_conn + 4 * 8160, last, sizeof last));
    CHECK(m.points[0] == 0.0 && m.points[1] == 0.0 && m.points[2] == 0.03);
    CHECK(field_sum(find_field(&m, "degenerate_kind"), 8161) == 60.0);
    tpk_mesh_free(&m);
}

TPK_TEST(vtk_51_hanging_nodes_hex)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("hard/hanging_nodes_hex.vtk"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 3476);
    CHECK_EQ_INT(count_type(&m, TPK_CELL_HEXAHEDRON), 2750);
    const int32_t first[8] = {0, 2, 359, 358, 31, 112, 602, 521};
    CHECK(!memcmp(m.cell_conn, first, sizeof first));
    CHECK(field_sum(find_field(&m, "refine_level"), 2750) == 2000.0);
    tpk_mesh_free(&m);
}

/* ---- a small mesh written by this test in every VTK form ----------------------------------------- */

typedef struct small_mesh {
    int points;
    double xyz[12][3];
    int cells;
    int types[8];
    int sizes[8];
    int ids[8][20];
} small_mesh;

static small_mesh sample(void)
{
    small_mesh s;
    memset(&s, 0, sizeof s);
    s.points = 12;
    for (int i = 0; i < 8; i++) {
        s.xyz[i][0] = (i & 1) ? 1.5 : -0.25;
        s.xyz[i][1] = (i & 2) ? 2.0 / 3.0 : 1e-7;
        s.xyz[i][2] = (i & 4) ? 6.4e6 : -3.0;
    }
    for (int i = 8; i < 12; i++)
        for (int k = 0; k < 3; k++)
            s.xyz[i][k] = 0.1 * i + k;
    const int tet[4] = {0, 1, 2, 4}, hex[8] = {0, 1, 3, 2, 4, 5, 7, 6}, wedge[6] = {0, 1, 2, 4, 5, 6};
    const int qtet[10] = {0, 1, 2, 4, 8, 9, 10, 11, 8, 9};
    const int poly[17] = {4, 3, 0, 1, 2, 3, 0, 1, 4, 3, 1, 2, 4, 3, 0, 2, 4};
    struct {
        int type, n;
        const int *ids;
    } list[7] = {{10, 4, tet}, {1, 1, (const int[]){3}}, {12, 8, hex}, {5, 3, tet}, {24, 10, qtet}, {13, 6, wedge},
                 {42, 17, poly}};
    s.cells = 7;
    for (int c = 0; c < 7; c++) {
        s.types[c] = list[c].type;
        s.sizes[c] = list[c].n;
        memcpy(s.ids[c], list[c].ids, sizeof(int) * (size_t)list[c].n);
    }
    return s;
}

typedef struct buf {
    char *data;
    size_t size, cap;
} buf;

static void put(buf *b, const void *p, size_t n)
{
    if (b->size + n > b->cap) {
        b->cap = (b->size + n) * 2 + 256;
        b->data = realloc(b->data, b->cap);
    }
    memcpy(b->data + b->size, p, n);
    b->size += n;
}

static void putf(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void putf(buf *b, const char *fmt, ...)
{
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    put(b, text, (size_t)n);
}

static void put_be(buf *b, uint64_t v, int bytes)
{
    unsigned char out[8];
    for (int i = 0; i < bytes; i++)
        out[i] = (unsigned char)(v >> (8 * (bytes - 1 - i)));
    put(b, out, (size_t)bytes);
}

static void put_double(buf *b, int binary, double v)
{
    if (binary) {
        uint64_t u;
        memcpy(&u, &v, 8);
        put_be(b, u, 8);
    } else {
        putf(b, "%.17g ", v);
    }
}

static void put_float(buf *b, int binary, float v)
{
    if (binary) {
        uint32_t u;
        memcpy(&u, &v, 4);
        put_be(b, u, 4);
    } else {
        putf(b, "%.9g\n", v);
    }
}

static void put_int(buf *b, int binary, int64_t v, int bytes)
{
    if (binary)
        put_be(b, (uint64_t)v, bytes);
    else
        putf(b, "%lld ", (long long)v);
}

/* The sample in VTK legacy form: binary or ASCII, old CELLS lists or the 5.1 OFFSETS/CONNECTIVITY. */
static buf write_sample(const small_mesh *s, int binary, int v51)
{
    buf b = {0};
    putf(&b, "# vtk DataFile Version %s\nsample mesh\n%s\nDATASET UNSTRUCTURED_GRID\n", v51 ? "5.1" : "3.0",
         binary ? "BINARY" : "ASCII");
    if (v51) { /* a dataset-level FIELD and a METADATA block: skipped */
        putf(&b, "FIELD FieldData 1\nTIME 1 1 double\n");
        put_double(&b, binary, 0.5);
        putf(&b, "\nMETADATA\nINFORMATION 0\n\n");
    }
    putf(&b, "POINTS %d double\n", s->points);
    for (int i = 0; i < s->points; i++)
        for (int k = 0; k < 3; k++)
            put_double(&b, binary, s->xyz[i][k]);
    putf(&b, "\n");
    int total = 0;
    for (int c = 0; c < s->cells; c++)
        total += s->sizes[c];
    if (v51) {
        putf(&b, "CELLS %d %d\nOFFSETS vtktypeint64\n", s->cells + 1, total);
        int64_t o = 0;
        put_int(&b, binary, 0, 8);
        for (int c = 0; c < s->cells; c++)
            put_int(&b, binary, o += s->sizes[c], 8);
        putf(&b, "\nCONNECTIVITY vtktypeint64\n");
        for (int c = 0; c < s->cells; c++)
            for (int j = 0; j < s->sizes[c]; j++)
                put_int(&b, binary, s->ids[c][j], 8);
    } else {
        putf(&b, "CELLS %d %d\n", s->cells, total + s->cells);
        for (int c = 0; c < s->cells; c++) {
            put_int(&b, binary, s->sizes[c], 4);
            for (int j = 0; j < s->sizes[c]; j++)
                put_int(&b, binary, s->ids[c][j], 4);
            if (!binary)
                putf(&b, "\n");
        }
    }
    putf(&b, "\nCELL_TYPES %d\n", s->cells);
    for (int c = 0; c < s->cells; c++)
        put_int(&b, binary, s->types[c], 4);
    putf(&b, "\nPOINT_DATA %d\nSCALARS temperature float 1\nLOOKUP_TABLE default\n", s->points);
    for (int i = 0; i < s->points; i++)
        put_float(&b, binary, 0.5f * (float)i - 1.0f / 3.0f);
    putf(&b, "\nVECTORS velocity double\n");
    for (int i = 0; i < s->points; i++)
        for (int k = 0; k < 3; k++)
            put_double(&b, binary, i + 0.25 * k);
    putf(&b, "\nCELL_DATA %d\nSCALARS pressure int\nLOOKUP_TABLE default\n", s->cells);
    for (int c = 0; c < s->cells; c++)
        put_int(&b, binary, 10 + c, 4);
    putf(&b, "\nFIELD FieldData 1\nmaterial%%20id 2 %d float\n", s->cells);
    for (int c = 0; c < s->cells; c++) {
        put_float(&b, binary, (float)c);
        put_float(&b, binary, -(float)c);
    }
    putf(&b, "\n");
    return b;
}

static int import_buf(const char *name, const buf *b, tpk_mesh *m, tpk_diag *d)
{
    /* Exact-size copy so an overread hits the sanitizer's redzone. */
    char *copy = malloc(b->size ? b->size : 1);
    memcpy(copy, b->data, b->size);
    int rc = tpk_import_vtk_legacy_memory(name, copy, b->size, m, d);
    free(copy);
    return rc;
}

static int same_mesh(const tpk_mesh *a, const tpk_mesh *b)
{
    if (a->point_count != b->point_count || a->cell_count != b->cell_count || a->field_count != b->field_count)
        return 0;
    if (memcmp(a->points, b->points, sizeof(double) * 3 * (size_t)a->point_count) ||
        memcmp(a->cell_types, b->cell_types, (size_t)a->cell_count) ||
        memcmp(a->cell_offsets, b->cell_offsets, sizeof(int64_t) * (size_t)(a->cell_count + 1)) ||
        memcmp(a->cell_conn, b->cell_conn, sizeof(int32_t) * (size_t)a->cell_offsets[a->cell_count]))
        return 0;
    for (int i = 0; i < a->field_count; i++) {
        const tpk_src_field *f = &a->fields[i], *g = &b->fields[i];
        int64_t n = (f->association == TPK_ASSOC_POINT ? a->point_count : a->cell_count) * f->components;
        if (strcmp(f->name, g->name) || f->association != g->association || f->components != g->components ||
            memcmp(f->values, g->values, sizeof(float) * (size_t)n))
            return 0;
    }
    return 1;
}

TPK_TEST(vtk_ascii_binary_forms_agree)
{
    small_mesh s = sample();
    tpk_mesh meshes[4];
    for (int form = 0; form < 4; form++) {
        buf b = write_sample(&s, form & 1, form >> 1);
        tpk_diag d = new_diag();
        quiet_warnings = 1;
        int rc = import_buf("sample.vtk", &b, &meshes[form], &d);
        quiet_warnings = 0;
        free(b.data);
        CHECK_MSG(rc == 0, "form %d: %s", form, d.message);
        CHECK_EQ_INT(d.warning_count, 1); /* dropped 2 lower-dimensional cells; the quadratic tet kept */
        CHECK(!strcmp(meshes[form].format, (form & 1) ? "vtk-legacy-binary" : "vtk-legacy-ascii"));
    }
    tpk_mesh *m = &meshes[0];
    /* vertex (1) and triangle (5) dropped; the quadratic tetra (24) kept whole, its 10 nodes as written. */
    CHECK_EQ_INT(m->cell_count, 5);
    const uint8_t types[5] = {10, 12, 24, 13, 42};
    CHECK(!memcmp(m->cell_types, types, 5));
    const int64_t offsets[6] = {0, 4, 12, 22, 28, 32};
    CHECK(!memcmp(m->cell_offsets, offsets, sizeof offsets));
    CHECK(!memcmp(m->cell_conn + 12, (const int32_t[]){0, 1, 2, 4, 8, 9, 10, 11, 8, 9}, 40));
    /* The polyhedron: its distinct points in cell_conn, its face stream in faces. */
    CHECK(!memcmp(m->cell_conn + 28, (const int32_t[]){0, 1, 2, 4}, 16));
    CHECK(m->face_offsets && m->face_offsets[4] == 0 && m->face_offsets[5] == 17 && m->faces[0] == 4);
    CHECK(m->points[3 * 7 + 2] == 6.4e6 && m->points[3 * 0 + 1] == 1e-7 && m->points[3 * 3 + 1] == 2.0 / 3.0);
    CHECK_EQ_INT(m->field_count, 4);
    const tpk_src_field *t = find_field(m, "temperature"), *v = find_field(m, "velocity"),
                        *p = find_field(m, "pressure"), *mat = find_field(m, "material id");
    CHECK(t && v && p && mat);
    CHECK(t->association == TPK_ASSOC_POINT && t->components == 1 && t->values[3] == 1.5f - 1.0f / 3.0f);
    CHECK(v->association == TPK_ASSOC_POINT && v->components == 3 && v->values[3 * 11 + 2] == 11.5f);
    /* Cell data follows the kept cells 0, 2, 4, 5, 6. */
    CHECK(p->association == TPK_ASSOC_TET && p->components == 1);
    const float kept[5] = {10, 12, 14, 15, 16};
    CHECK(!memcmp(p->values, kept, sizeof kept));
    CHECK(mat->components == 2 && mat->values[2] == 2.0f && mat->values[3] == -2.0f && mat->values[9] == -6.0f);
    for (int form = 1; form < 4; form++)
        CHECK_MSG(same_mesh(&meshes[0], &meshes[form]), "form %d differs from ASCII old form", form);
    for (int form = 0; form < 4; form++)
        tpk_mesh_free(&meshes[form]);
}

/* ---- bad VTK input --------------------------------------------------------------------------------- */

/* Import `text` under the name bad.vtk; it must fail, name the file, leave the mesh zeroed, and the
 * message must contain every one of the given pieces. */
static int expect_failure(const char *text, size_t size, const char *const *pieces, int n, char *message)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    quiet_warnings = 1;
    buf b = {(char *)text, size, size};
    int rc = import_buf("bad.vtk", &b, &m, &d);
    quiet_warnings = 0;
    snprintf(message, 1024, "%s", d.message);
    if (rc == 0) {
        tpk_mesh_free(&m);
        snprintf(message, 1024, "(import succeeded)");
        return 0;
    }
    if (!mesh_is_zero(&m) || strncmp(d.message, "bad.vtk", 7) != 0)
        return 0;
    for (int i = 0; i < n; i++)
        if (!strstr(d.message, pieces[i]))
            return 0;
    return 1;
}

#define EXPECT_FAIL(text, ...)                                                                  \
    do {                                                                                        \
        const char *pieces_[] = {__VA_ARGS__};                                                   \
        char msg_[1024];                                                                        \
        CHECK_MSG(expect_failure(text, strlen(text), pieces_, (int)(sizeof pieces_ / sizeof *pieces_), msg_), \
                  "message: %s", msg_);                                                          \
    } while (0)

#define HDR "# vtk DataFile Version 3.0\nbad\nASCII\nDATASET UNSTRUCTURED_GRID\n"
#define PTS4 "POINTS 4 float\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
#define BINHDR "# vtk DataFile Version 3.0\nbad\nBINARY\nDATASET UNSTRUCTURED_GRID\n"

TPK_TEST(vtk_bad_header_and_dataset)
{
    EXPECT_FAIL("", "bad.vtk:1:", "expected '# vtk DataFile Version x.y'", "an empty file");
    EXPECT_FAIL("# vtk DataFile Version 3.0\n", "bad.vtk:2:", "title");
    EXPECT_FAIL("<?xml version=\"1.0\"?>\n", "bad.vtk:1:", "found '<?xml version=");
    EXPECT_FAIL("# vtk DataFile Version 3.0\nt\nTEXT\n", "bad.vtk:3:", "expected 'ASCII' or 'BINARY', found 'TEXT'");
    EXPECT_FAIL("# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n", "bad.vtk:4:",
                "unsupported dataset type 'POLYDATA'", "UNSTRUCTURED_GRID");
    EXPECT_FAIL(HDR PTS4 "CELL 1 5\n4 0 1 2 3\n", "bad.vtk:10:", "found 'CELL'");
    EXPECT_FAIL(HDR PTS4, "expected a CELLS section, found end of file");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPE 1\n10\n", "bad.vtk:12:", "found 'CELL_TYPE'");
}

TPK_TEST(vtk_bad_numbers_and_counts)
{
    EXPECT_FAIL(HDR "POINTS 2 float\n0 0 0\n1 0 x1\n", "bad.vtk:7:", "POINTS: expected a number (value 6 of 6)",
                "found 'x1'");
    EXPECT_FAIL(HDR "POINTS 2 float\n0 0 0\n1 0 1.2.3\n", "bad.vtk:7:", "found '1.2.3'");
    EXPECT_FAIL(HDR "POINTS 2 float\n0 0 0\n1 0\n", "bad.vtk:8:", "POINTS block truncated: expected 6 values, found 5");
    EXPECT_FAIL(HDR "POINTS -4 float\n", "bad.vtk:5:", "expected a point count (>= 0), found -4");
    EXPECT_FAIL(HDR "POINTS many float\n", "bad.vtk:5:", "expected a point count, found 'many'");
    EXPECT_FAIL(HDR "POINTS 4 quad_float\n", "bad.vtk:5:", "expected a data type", "found 'quad_float'");
    EXPECT_FAIL(HDR "POINTS 999999999999 double\n0 0 0\n", "bad.vtk:5:", "POINTS: 2999999999997 values cannot fit",
                "bytes left in the file");
    EXPECT_FAIL(HDR "POINTS 99999999999999999999 double\n", "bad.vtk:5:", "found '99999999999999999999'");
    /* Found by fuzzing: a count whose value count overflows 64 bits failed without a message. */
    EXPECT_FAIL(HDR "POINTS 8888888888888888892 double\n", "bad.vtk:5:", "POINTS 8888888888888888892: too many points");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10 10\n", "bad.vtk:12:",
                "CELL_TYPES 2: expected one type per cell (CELLS has 1 cells)");
    EXPECT_FAIL(HDR PTS4 "CELLS 2 9\n4 0 1 2 3\n4 0 1 2 3\n", "bad.vtk:12:", "cell 1 has point count 4",
                "the CELLS size 9 leaves room for at most 3");
    EXPECT_FAIL(HDR PTS4 "CELLS 2 11\n4 0 1 2 3\n4 0 1 2 3\n3\n", "bad.vtk:10:", "CELLS 2 11",
                "the 2 cells hold 10 numbers, expected 11");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n7 0 1 2 3\n", "bad.vtk:11:", "cell 0 has point count 7");
    EXPECT_FAIL(HDR PTS4 "CELLS 100000000 500000000\n4 0 1 2 3\n", "bad.vtk:10:", "cannot fit");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 2\n", "bad.vtk:14:",
                "CELL_DATA 2: expected 1 (one per cell)");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS t float\n1 2 3\n",
                "bad.vtk:17:", "SCALARS block truncated: expected 4 values, found 3");
}

TPK_TEST(vtk_bad_ids_and_types)
{
    EXPECT_FAIL(HDR PTS4 "CELLS 2 10\n4 0 1 2 3\n4 0 1 2 99\nCELL_TYPES 2\n10 10\n", "bad.vtk:10:",
                "cell 1 uses point id 99", "only 4 points");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 -1 2 3\nCELL_TYPES 1\n10\n", "bad.vtk:11:", "cell 0 uses point id -1");
    EXPECT_FAIL(HDR PTS4 "CELLS 2 10\n4 0 1 2 3\n4 0 1 2 3\nCELL_TYPES 2\n10 200\n", "bad.vtk:13:",
                "cell 1 has unsupported cell type 200 (unknown)");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n41\n", "cell 0 has unsupported cell type 41 (convex point set)");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n10\n", "bad.vtk:10:", "cell 0 (tetra, type 10) has 3 points, expected 4");
    EXPECT_FAIL(HDR PTS4 "CELLS 2 8\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2 3 0 1 2 9\n"
                "CELL_TYPES 1\n10\n", "bad.vtk:12:", "OFFSETS", "expected the last offset to equal the CELLS size 8, found 4");
    EXPECT_FAIL(HDR PTS4 "CELLS 3 8\nOFFSETS vtktypeint64\n0 5 4\nCONNECTIVITY vtktypeint64\n0 1 2 3 0 1 2 3\n",
                "cell 1 ends at 4");
    EXPECT_FAIL(HDR PTS4 "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 8\nCONNECTIVITY vtktypeint64\n0 1 2 3 0 1 2 -3\n",
                "bad.vtk:14:", "cell 1 uses point id -3");
    EXPECT_FAIL(HDR PTS4 "CELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECT vtktypeint64\n",
                "bad.vtk:13:", "expected 'CONNECTIVITY type'", "found 'CONNECT'");
}

TPK_TEST(vtk_bad_fields)
{
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 1\nFIELD f 1\nmat 1 3 float\n1 2 3\n",
                "bad.vtk:16:", "array 'mat' has 3 tuples, expected 1 (one per cell)");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nSCALARS s float\n1\n", "bad.vtk:14:",
                "expected POINT_DATA or CELL_DATA before SCALARS");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nVECTORS v float\n1.5 2.5 3.5 4.5 5.5 6.5\n",
                "bad.vtk:17:", "VECTORS block truncated: expected 12 values, found 6");
    EXPECT_FAIL(HDR PTS4 "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS s float 0\n",
                "bad.vtk:15:", "expected a component count, found '0'");
}

static void put_text(buf *b, const char *t)
{
    put(b, t, strlen(t));
}

TPK_TEST(vtk_bad_binary)
{
    /* POINTS block shorter than announced: the message gives the byte offset of the block. */
    buf b = {0};
    put_text(&b, BINHDR "POINTS 128 double\n");
    size_t block = b.size;
    for (int i = 0; i < 150; i++)
        put_double(&b, 1, i);
    char expect[128], msg[1024];
    snprintf(expect, sizeof expect, "bad.vtk: byte %zu: POINTS block truncated: expected 3072 bytes, found 1200", block);
    const char *pieces[] = {expect};
    CHECK_MSG(expect_failure(b.data, b.size, pieces, 1, msg), "message: %s", msg);
    free(b.data);

    /* Absurd count in a tiny binary file. */
    const char *absurd = BINHDR "POINTS 999999999999 double\nabc";
    const char *p2[] = {"bad.vtk: byte ", "POINTS block truncated: expected 23999999999976 bytes, found 3"};
    CHECK_MSG(expect_failure(absurd, strlen(absurd), p2, 2, msg), "message: %s", msg);

    /* Out-of-range id in a binary cell list. */
    b = (buf){0};
    put_text(&b, BINHDR "POINTS 4 float\n");
    for (int i = 0; i < 12; i++)
        put_float(&b, 1, (float)(i % 4 == 0));
    put_text(&b, "\nCELLS 1 5\n");
    const int ids[5] = {4, 0, 1, 2, 70000};
    for (int i = 0; i < 5; i++)
        put_int(&b, 1, ids[i], 4);
    put_text(&b, "\nCELL_TYPES 1\n");
    put_int(&b, 1, 10, 4);
    const char *p3[] = {"bad.vtk: byte ", "cell 0 uses point id 70000, but there are only 4 points"};
    CHECK_MSG(expect_failure(b.data, b.size, p3, 2, msg), "message: %s", msg);
    free(b.data);
}

/* A BINARY file of `cells` cells of `each` ids (ids[c * each + j]) and one type per cell, on 4 points, in the
 * old CELLS form or the 5.1 one (64-bit offsets and ids). */
static buf binary_cells(int v51, int cells, int each, const int *ids, const int *types)
{
    buf b = {0};
    put_text(&b, BINHDR "POINTS 4 float\n");
    for (int i = 0; i < 12; i++)
        put_float(&b, 1, (float)(i % 4 == i / 3));
    char line[96];
    if (v51) {
        snprintf(line, sizeof line, "\nCELLS %d %d\nOFFSETS vtktypeint64\n", cells + 1, cells * each);
        put_text(&b, line);
        for (int c = 0; c <= cells; c++)
            put_int(&b, 1, (int64_t)c * each, 8);
        put_text(&b, "\nCONNECTIVITY vtktypeint64\n");
        for (int k = 0; k < cells * each; k++)
            put_int(&b, 1, ids[k], 8);
    } else {
        snprintf(line, sizeof line, "\nCELLS %d %d\n", cells, cells * (each + 1));
        put_text(&b, line);
        for (int c = 0; c < cells; c++) {
            put_int(&b, 1, each, 4);
            for (int j = 0; j < each; j++)
                put_int(&b, 1, ids[c * each + j], 4);
        }
    }
    snprintf(line, sizeof line, "\nCELL_TYPES %d\n", cells);
    put_text(&b, line);
    for (int c = 0; c < cells; c++)
        put_int(&b, 1, types[c], 4);
    put_text(&b, "\n");
    return b;
}

/* Binary cells of one type and one size are checked without a pass over each cell (the reading passes
 * proved the ids and types); whatever that proof does not cover must still fail with the message of the
 * cell-by-cell check, in both CELLS forms. */
TPK_TEST(vtk_binary_one_type_checked)
{
    static const int good[8] = {0, 1, 2, 3, 3, 2, 1, 0}, past[8] = {0, 1, 2, 3, 0, 1, 2, 4};
    static const int tets[2] = {10, 10}, convex[2] = {41, 41}, mixed[2] = {10, 41}, tris[2] = {5, 5};
    static const int tri_ids[6] = {0, 1, 2, 1, 2, 3};
    for (int v51 = 0; v51 < 2; v51++) {
        char msg[1024];
        buf b = binary_cells(v51, 2, 4, good, tets);
        tpk_mesh m;
        tpk_diag d = new_diag();
        CHECK(import_buf("good.vtk", &b, &m, &d) == 0);
        CHECK(m.cell_count == 2 && m.cell_offsets[2] == 8 && m.cell_conn[7] == 0 && m.cell_types[1] == 10);
        tpk_mesh_free(&m);
        free(b.data);

        b = binary_cells(v51, 2, 4, past, tets); /* the largest id is the point count */
        const char *p1[] = {"bad.vtk: ", "cell 1 uses point id 4, but there are only 4 points (0 to 3)"};
        CHECK_MSG(expect_failure(b.data, b.size, p1, 2, msg), "message: %s", msg);
        free(b.data);

        b = binary_cells(v51, 2, 4, good, convex);
        const char *p2[] = {"bad.vtk: ", "CELL_TYPES: cell 0 has unsupported cell type 41 (convex point set)"};
        CHECK_MSG(expect_failure(b.data, b.size, p2, 2, msg), "message: %s", msg);
        free(b.data);

        b = binary_cells(v51, 2, 4, good, mixed);
        const char *p3[] = {"bad.vtk: ", "cell 1 has unsupported cell type 41"};
        CHECK_MSG(expect_failure(b.data, b.size, p3, 2, msg), "message: %s", msg);
        free(b.data);

        b = binary_cells(v51, 2, 3, tri_ids, tets); /* tetra with 3 points */
        const char *p4[] = {"bad.vtk: ", "cell 0 (tetra, type 10) has 3 points, expected 4"};
        CHECK_MSG(expect_failure(b.data, b.size, p4, 2, msg), "message: %s", msg);
        free(b.data);

        b = binary_cells(v51, 2, 3, tri_ids, tris); /* no volume: both dropped, none kept */
        d = new_diag();
        quiet_warnings = 1;
        CHECK(import_buf("tris.vtk", &b, &m, &d) == 0);
        quiet_warnings = 0;
        CHECK(m.cell_count == 0 && m.cell_offsets[0] == 0);
        tpk_mesh_free(&m);
        free(b.data);
    }
}

/* COLOR_SCALARS in BINARY are unsigned chars scaled to [0, 1]. Read leniently (tetpack check), a block of
 * the wrong length is recorded and dropped; the scaling must not touch a field that is not there (a
 * fuzzer's SIGSEGV: ../shared/crashers/check_vtk_color_scalars.vtk). */
static void color_scalars_file(buf *b, int announced)
{
    put_text(b, BINHDR "POINTS 4 float\n");
    for (int i = 0; i < 12; i++)
        put_float(b, 1, (float)(i % 4 == 0));
    put_text(b, "\nCELLS 1 5\n");
    for (int i = 0; i < 5; i++)
        put_int(b, 1, i ? i - 1 : 4, 4);
    put_text(b, "\nCELL_TYPES 1\n");
    put_int(b, 1, 10, 4);
    char line[64];
    snprintf(line, sizeof line, "\nPOINT_DATA %d\nCOLOR_SCALARS rgb 3\n", announced);
    put_text(b, line);
    for (int i = 0; i < 3 * announced; i++)
        put(b, (const char[]){(char)(unsigned char)(i * 51 % 256)}, 1);
    put_text(b, "\n");
}

TPK_TEST(vtk_color_scalars_strict_and_lenient)
{
    buf b = {0};
    color_scalars_file(&b, 4);
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_vtk_legacy_memory("rgb.vtk", b.data, b.size, &m, &d) == 0);
    const tpk_src_field *f = find_field(&m, "rgb");
    CHECK(f && f->components == 3);
    for (int i = 0; f && i < 12; i++)
        CHECK_MSG(f->values[i] == (float)(i * 51 % 256) / 255.0f, "value %d: %g", i, (double)f->values[i]);
    tpk_mesh_free(&m);
    free(b.data);

    /* 2 colors for 4 points: refused strictly, dropped leniently (the crasher's shape: no other field). */
    b = (buf){0};
    color_scalars_file(&b, 2);
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_vtk_legacy_memory("rgb.vtk", b.data, b.size, &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "POINT_DATA 2: expected 4 (one per point)") != NULL, "got %s", d.message);
    memset(&d, 0, sizeof d);
    d.lenient_fields = 1;
    CHECK(tpk_import_vtk_legacy_memory("rgb.vtk", b.data, b.size, &m, &d) == 0);
    CHECK_EQ_INT(m.field_count, 0);
    CHECK_EQ_INT(d.field_problem_count, 1);
    CHECK(!strcmp(d.field_problems[0].name, "rgb"));
    tpk_mesh_free(&m);
    free(b.data);
}

/* Truncate valid files at every offset: each import must fail with the file name and a place, or
 * (at a section boundary) succeed; never crash or leak (run under ASan). */
TPK_TEST(vtk_truncated_everywhere)
{
    small_mesh s = sample();
    for (int form = 0; form < 4; form++) {
        buf b = write_sample(&s, form & 1, form >> 1);
        int failed = 0;
        for (size_t cut = 0; cut < b.size; cut++) {
            tpk_mesh m;
            tpk_diag d = new_diag();
            buf part = {b.data, cut, cut};
            quiet_warnings = 1;
            int rc = import_buf("cut.vtk", &part, &m, &d);
            quiet_warnings = 0;
            if (rc == 0) {
                tpk_mesh_free(&m);
                continue;
            }
            failed++;
            CHECK_MSG(mesh_is_zero(&m), "cut %zu", cut);
            int placed = !strncmp(d.message, "cut.vtk:", 8) || !strncmp(d.message, "cut.vtk: byte ", 14);
            CHECK_MSG(placed, "form %d cut %zu: %s", form, cut, d.message);
        }
        CHECK_MSG(failed > (int)b.size * 9 / 10, "form %d: only %d of %zu cuts failed", form, failed, b.size);
        free(b.data);
    }
}

/* Deterministic byte mutations of the sample: no crash, no leak, a placed message on failure. */
TPK_TEST(vtk_mutations)
{
    small_mesh s = sample();
    uint64_t rng = 0x9e3779b97f4a7c15u;
    for (int form = 0; form < 4; form++) {
        buf b = write_sample(&s, form & 1, form >> 1);
        for (int round = 0; round < 1500; round++) {
            buf copy = {malloc(b.size), b.size, b.size};
            memcpy(copy.data, b.data, b.size);
            for (int k = 0; k < 1 + round % 4; k++) {
                rng = rng * 6364136223846793005u + 1442695040888963407u;
                size_t at = (size_t)(rng >> 33) % b.size;
                static const char bytes[] = "0123456789 -.e\n\xff\x00" "9";
                copy.data[at] = (rng >> 20) & 1 ? bytes[(rng >> 8) % (sizeof bytes - 1)] : (char)(rng >> 40);
            }
            tpk_mesh m;
            tpk_diag d = new_diag();
            quiet_warnings = 1;
            int rc = import_buf("mut.vtk", &copy, &m, &d);
            quiet_warnings = 0;
            free(copy.data);
            if (rc == 0) {
                tpk_mesh_free(&m);
                continue;
            }
            CHECK(mesh_is_zero(&m));
            CHECK_MSG(!strncmp(d.message, "mut.vtk:", 8), "%s", d.message);
        }
        free(b.data);
    }
}

/* ---- TetGen -------------------------------------------------------------------------------------- */

TPK_TEST(tetgen_hinge_one_based)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_tetgen(tpk_data_path("tetgen/hinge_small.node"), &m, &d) == 0, "%s", d.message);
    CHECK(!strcmp(m.format, "tetgen"));
    CHECK_EQ_INT(m.point_count, 4146);
    CHECK_EQ_INT(m.cell_count, 14487);
    CHECK_EQ_INT(count_type(&m, TPK_CELL_TETRA), 14487);
    /* File text: point 1 = 38.3202 17.061399999999999 5; point 4146 = 10.228216574614681 ...;
     * tet 1 = 982 972 974 1046; tet 14487 = 3535 232 3537 4146 (1-based). */
    CHECK(m.points[0] == 38.3202 && m.points[1] == 17.061399999999999 && m.points[2] == 5.0);
    CHECK(m.points[3 * 4145] == 10.228216574614681 && m.points[3 * 4145 + 2] == 0.93201317621490365);
    CHECK(!memcmp(m.cell_conn, (const int32_t[]){981, 971, 973, 1045}, 16));
    CHECK(!memcmp(m.cell_conn + 4 * 14486, (const int32_t[]){3534, 231, 3536, 4145}, 16));
    CHECK_EQ_INT(m.field_count, 0);
    CHECK_EQ_INT(negative_tets(&m), 0);
    tpk_mesh_free(&m);

    /* The same through the .ele path, the stem and tpk_import_any. */
    tpk_mesh a, b, c;
    CHECK(tpk_import_tetgen(tpk_data_path("tetgen/hinge_small.ele"), &a, &d) == 0);
    CHECK(tpk_import_tetgen(tpk_data_path("tetgen/hinge_small"), &b, &d) == 0);
    CHECK(tpk_import_any(tpk_data_path("tetgen/hinge_small.ele"), NULL, &c, &d) == 0);
    CHECK(same_mesh(&a, &b) && same_mesh(&a, &c) && a.cell_count == 14487);
    tpk_mesh_free(&a);
    tpk_mesh_free(&b);
    tpk_mesh_free(&c);
}

TPK_TEST(tetgen_part1_and_orphans)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK_MSG(tpk_import_tetgen(tpk_data_path("tetgen/part1_small"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 1445);
    CHECK_EQ_INT(m.cell_count, 5436);
    CHECK(!memcmp(m.cell_conn, (const int32_t[]){1109, 959, 1107, 1116}, 16));
    tpk_mesh_free(&m);
    CHECK_MSG(tpk_import_tetgen(tpk_data_path("hard/two_components_orphans.node"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 8297);
    CHECK_EQ_INT(m.cell_count, 28974);
    tpk_mesh_free(&m);
}

/* hinge_small rewritten 0-based (and with comments, attributes and markers) must give the same mesh. */
TPK_TEST(tetgen_zero_based_attributes_comments)
{
    tpk_mesh ref;
    tpk_diag d = new_diag();
    CHECK(tpk_import_tetgen(tpk_data_path("tetgen/hinge_small"), &ref, &d) == 0);
    buf node = {0}, ele = {0};
    putf(&node, "# converted to 0-based\n\n%lld 3 2 1 # points dim attrs markers\n", (long long)ref.point_count);
    for (int64_t i = 0; i < ref.point_count; i++)
        putf(&node, "%lld %.17g\t%.17g %.17g  %g %g %d\n", (long long)i, ref.points[3 * i], ref.points[3 * i + 1],
             ref.points[3 * i + 2], (double)i, -0.5 * (double)i, (int)(i & 1));
    putf(&ele, "%lld 4 1\n", (long long)ref.cell_count);
    for (int64_t t = 0; t < ref.cell_count; t++) {
        const int32_t *v = ref.cell_conn + 4 * t;
        putf(&ele, "%lld %d %d %d %d %d%s\n", (long long)t, v[0], v[1], v[2], v[3], (int)(t % 3),
             t == 5 ? " # a comment" : "");
        if (t == 7)
            putf(&ele, "# a comment line\n");
    }
    write_temp("zero.node", node.data, node.size);
    write_temp("zero.ele", ele.data, ele.size);
    free(node.data);
    free(ele.data);
    tpk_mesh m;
    CHECK_MSG(tpk_import_tetgen(tpk_temp_path("zero"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.cell_count, ref.cell_count);
    CHECK(!memcmp(m.points, ref.points, sizeof(double) * 3 * (size_t)ref.point_count));
    CHECK(!memcmp(m.cell_conn, ref.cell_conn, sizeof(int32_t) * 4 * (size_t)ref.cell_count));
    CHECK_EQ_INT(m.field_count, 3);
    const tpk_src_field *a0 = find_field(&m, "attribute_0"), *a1 = find_field(&m, "attribute_1"),
                        *r0 = find_field(&m, "region_attribute_0");
    CHECK(a0 && a1 && r0);
    CHECK(a0->association == TPK_ASSOC_POINT && a0->values[4145] == 4145.0f && a1->values[3] == -1.5f);
    CHECK(r0->association == TPK_ASSOC_TET && r0->values[5] == 2.0f && r0->values[14486] == 14486 % 3);
    tpk_mesh_free(&m);
    tpk_mesh_free(&ref);
}

TPK_TEST(tetgen_ten_node_tets)
{
    const char *node = "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n";
    const char *ele = "2 10 0\n1 1 2 3 4 5 5 5 5 5 5\n2 2 3 4 5 1 1 1 1 1 1\n";
    write_temp("quad.node", node, strlen(node));
    write_temp("quad.ele", ele, strlen(ele));
    tpk_mesh m;
    tpk_diag d = new_diag();
    quiet_warnings = 1;
    int rc = tpk_import_tetgen(tpk_temp_path("quad.ele"), &m, &d);
    quiet_warnings = 0;
    CHECK_MSG(rc == 0, "%s", d.message);
    CHECK_EQ_INT(d.warning_count, 1);
    CHECK_EQ_INT(m.cell_count, 2);
    CHECK(!memcmp(m.cell_conn, (const int32_t[]){0, 1, 2, 3, 1, 2, 3, 4}, 32));
    tpk_mesh_free(&m);
}

static int tetgen_fails(const char *node, const char *ele, const char *piece1, const char *piece2, char *msg)
{
    write_temp("bad.node", node, strlen(node));
    write_temp("bad.ele", ele, strlen(ele));
    tpk_mesh m;
    tpk_diag d = new_diag();
    int rc = tpk_import_tetgen(tpk_temp_path("bad"), &m, &d);
    snprintf(msg, 1024, "%s", rc ? d.message : "(import succeeded)");
    if (rc == 0)
        tpk_mesh_free(&m);
    return rc != 0 && mesh_is_zero(&m) && strstr(d.message, piece1) && strstr(d.message, piece2);
}

TPK_TEST(tetgen_bad_input)
{
    char msg[1024];
    const char *node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    CHECK_MSG(tetgen_fails(node, "1 4 0\n1 1 2 3 5\n", "bad.ele:2:", "tet 1 uses point id 5, expected 1 to 4", msg),
              "%s", msg);
    CHECK_MSG(tetgen_fails(node, "2 4 0\n1 1 2 3 4\n", "bad.ele:3:", "expected the index of tet 2, found end of file",
                           msg), "%s", msg);
    CHECK_MSG(tetgen_fails(node, "1 4 0\n1 1 2 3\n", "bad.ele:2:", "expected a point id of tet 1, found end of line",
                           msg), "%s", msg);
    CHECK_MSG(tetgen_fails(node, "1 6 0\n", "bad.ele:1:", "expected 4 or 10 nodes per tet", msg), "%s", msg);
    CHECK_MSG(tetgen_fails(node, "999999999999 4 0\n1 1 2 3 4\n", "bad.ele:1:", "cannot fit", msg), "%s", msg);
    CHECK_MSG(tetgen_fails("1 3 0 0\n7 0 0 0\n", "", "bad.node:2:", "first point index to be 0 or 1, found 7", msg),
              "%s", msg);
    CHECK_MSG(tetgen_fails("2 3 0 0\n1 0 0 0\n2 1 zero 0\n", "", "bad.node:3:",
                           "expected the y coordinate of point 2, found 'zero'", msg), "%s", msg);
    CHECK_MSG(tetgen_fails("2 2 0 0\n", "", "bad.node:1:", "expected dimension 3", msg), "%s", msg);
    CHECK_MSG(tetgen_fails("99999999999 3 0 0\n1 0 0 0\n", "", "bad.node:1:", "cannot fit", msg), "%s", msg);
    CHECK_MSG(tetgen_fails("4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n", "", "bad.node:5:",
                           "expected the index of point 4, found end of file", msg), "%s", msg);
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK(tpk_import_tetgen(tpk_temp_path("missing"), &m, &d) != 0 && mesh_is_zero(&m));
    CHECK_MSG(strstr(d.message, "missing.node: cannot open"), "%s", d.message);
}

/* ---- tpk_import_any ------------------------------------------------------------------------------ */

TPK_TEST(import_any_dispatch)
{
    tpk_mesh m;
    tpk_diag d = new_diag();
    CHECK(tpk_import_any(tpk_data_path("sfepy/cylinder.vtk"), NULL, &m, &d) == 0 && m.cell_count == 1348);
    tpk_mesh_free(&m);
    CHECK(tpk_import_any(tpk_data_path("sfepy/cylinder.vtk"), "vtk", &m, &d) == 0 && m.cell_count == 1348);
    tpk_mesh_free(&m);
    /* No known extension: the first bytes decide. */
    FILE *in = fopen(tpk_data_path("sfepy/cylinder.vtk"), "rb");
    CHECK(in);
    static char data[60000];
    size_t n = fread(data, 1, sizeof data, in);
    fclose(in);
    const char *renamed = write_temp("cylinder.dat", data, n);
    CHECK(tpk_import_any(renamed, "auto", &m, &d) == 0 && m.cell_count == 1348);
    tpk_mesh_free(&m);
    /* TetGen by stem. */
    CHECK(tpk_import_any(tpk_data_path("tetgen/part1_small"), NULL, &m, &d) == 0 && m.cell_count == 5436);
    tpk_mesh_free(&m);
    /* Forced formats, unknown ones and unknown contents. */
    CHECK(tpk_import_any(renamed, "tetgen", &m, &d) != 0 && mesh_is_zero(&m));
    CHECK(tpk_import_any(renamed, "obj", &m, &d) != 0 && mesh_is_zero(&m));
    CHECK_MSG(strstr(d.message, "cylinder.dat") && strstr(d.message, "unknown input format 'obj'") &&
              strstr(d.message, "vtk") && strstr(d.message, "tetgen"), "%s", d.message);
    const char *other = write_temp("mesh.xyz", "hello\n", 6);
    CHECK(tpk_import_any(other, NULL, &m, &d) != 0 && mesh_is_zero(&m));
    CHECK_MSG(strstr(d.message, "mesh.xyz") && strstr(d.message, "supported: vtk"), "%s", d.message);
}
