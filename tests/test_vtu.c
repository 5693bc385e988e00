/* VTK XML UnstructuredGrid (.vtu) importer: real meshio files (counts, values from meshio, positive
 * hexahedra in VTK order), one small mesh written by meshio in every encoding it has plus hand-built
 * appended raw files (UInt64 headers, zlib, big-endian), and bad input that must fail naming the file. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <expat.h>
#include <zlib.h>

#include "harness.h"
#include "import/importers.h"
#include "convert/pipeline.h"
#include "tetpack_format.h"

static void ignore_warning(void *user, const char *text)
{
    (void)user;
    (void)text;
}

static void quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
    d->warn = ignore_warning;
}

static const tpk_src_field *field(const tpk_mesh *m, const char *name)
{
    for (int i = 0; i < m->field_count; i++)
        if (!strcmp(m->fields[i].name, name))
            return &m->fields[i];
    return NULL;
}

static int mesh_is_empty(const tpk_mesh *m)
{
    return !m->points && !m->cell_types && !m->cell_offsets && !m->cell_conn && !m->fields && !m->point_count &&
           !m->cell_count && !m->field_count;
}

/* Values from meshio 5.0 reading the same files. */
TPK_TEST(real_ascii_hexahedra)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_vtu(tpk_data_path("hard/huge_offset_hex.vtu"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 1331);
    CHECK_EQ_INT(m.cell_count, 1000);
    CHECK(!strcmp(m.format, "vtu"));
    int ok = 1;
    for (int64_t c = 0; c < m.cell_count; c++)
        ok &= m.cell_types[c] == TPK_CELL_HEXAHEDRON && m.cell_offsets[c] == 8 * c;
    static const int32_t first[8] = {0, 2, 359, 358, 31, 112, 602, 521}, last[8] = {1330, 448, 240, 340,
                                                                                       158, 122, 121, 140};
    for (int k = 0; k < 8; k++)
        ok &= m.cell_conn[k] == first[k] && m.cell_conn[8 * 999 + k] == last[k];
    ok &= m.points[0] == 6500000.5 && m.points[1] == 4899999.5 && m.points[2] == 1200.5;
    ok &= m.points[3 * 1330] == 6499999.6 && m.points[3 * 1330 + 1] == 4900000.4 && m.points[3 * 1330 + 2] == 1199.6;
    const tpk_src_field *z = field(&m, "z_local");
    ok &= m.field_count == 1 && z && z->association == TPK_ASSOC_POINT && z->components == 1 && z->step_count == 1;
    ok &= z && z->values[0] == 0.5f && z->values[1330] == -0.4f && z->values[5] == 0.1f;
    tpk_mesh_free(&m);
    CHECK(ok);
}

/* Every corner of a VTK-ordered hexahedron (bottom 0-3, top 4-7) is right-handed in its three edges. */
TPK_TEST(real_hexahedra_are_vtk_ordered)
{
    static const int around[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                                     {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_vtu(tpk_data_path("hard/huge_offset_hex.vtu"), &m, &d) == 0, "%s", d.message);
    int64_t bad = 0;
    for (int64_t c = 0; c < m.cell_count; c++) {
        const int32_t *h = m.cell_conn + m.cell_offsets[c];
        for (int k = 0; k < 8; k++)
            bad += tpk_orient3d_exact(m.points + 3 * h[k], m.points + 3 * h[around[k][0]],
                                      m.points + 3 * h[around[k][1]], m.points + 3 * h[around[k][2]]) <= 0;
    }
    int ok = m.cell_count == 1000 && m.cell_types[0] == TPK_CELL_HEXAHEDRON;
    tpk_mesh_free(&m);
    CHECK_MSG(ok && bad == 0, "%lld corners not positive", (long long)bad);
}

TPK_TEST(real_binary_tetrahedra)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_vtu(tpk_data_path("hard/nonmanifold_vertex_edge_tets.vtu"), &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 1336);
    CHECK_EQ_INT(m.cell_count, 5346);
    int ok = !strcmp(m.format, "vtu");
    for (int64_t c = 0; c < m.cell_count; c++)
        ok &= m.cell_types[c] == TPK_CELL_TETRA && m.cell_offsets[c] == 4 * c;
    static const int32_t first[4] = {6, 18, 72, 233}, last[4] = {1243, 1288, 1333, 1208};
    for (int k = 0; k < 4; k++)
        ok &= m.cell_conn[k] == first[k] && m.cell_conn[4 * 5345 + k] == last[k];
    ok &= m.points[0] == -0.5 && m.points[1] == 0.5 && m.points[2] == 0.5;
    ok &= m.points[3 * 1335] == 1.241297781467 && m.points[3 * 1335 + 1] == -1.0781490430236 &&
          m.points[3 * 1335 + 2] == -0.221770316362;
    const tpk_src_field *f = field(&m, "component");
    ok &= m.field_count == 1 && f && f->association == TPK_ASSOC_TET && f->components == 1;
    int seen[3] = {0, 0, 0};
    for (int64_t c = 0; f && c < m.cell_count; c++) {
        float v = f->values[c];
        ok &= v == 0.0f || v == 1.0f || v == 2.0f;
        if (v == 0.0f || v == 1.0f || v == 2.0f)
            seen[(int)v] = 1;
    }
    ok &= f && f->values[0] == 0.0f && f->values[5345] == 2.0f && seen[0] && seen[1] && seen[2];
    tpk_mesh_free(&m);
    CHECK(ok);
}

/* ---- One small mesh in every encoding ----------------------------------------------------------- */

/* Two tets, a hexahedron, a quadratic tet (kept whole), a triangle (dropped); point scalar + vector, cell
 * scalar (float64) and cell int field. */
static const char meshio_script[] =
    "import sys, numpy as np, meshio\n"
    "pts = np.array([[0,0,0],[1,0,0],[0,1,0],[0,0,1],[1,1,0],[1,0,1],[0,1,1],[1,1,1],"
    "[0.5,0,0],[0.5,0.5,0],[0,0.5,0],[0,0,0.5],[0.5,0,0.5],[0,0.5,0.5]], dtype=float) + [0.25, -3.5, 1e3]\n"
    "cells = [('tetra', np.array([[0,1,2,3],[1,4,2,7]])),\n"
    "         ('hexahedron', np.array([[0,1,4,2,3,5,7,6]])),\n"
    "         ('tetra10', np.array([[0,1,2,3,8,9,10,11,12,13]])),\n"
    "         ('triangle', np.array([[0,1,2]]))]\n"
    "n = len(pts)\n"
    "pd = {'temp': np.arange(n, dtype=float) * 0.5, 'vel': np.stack([np.arange(n), -np.arange(n), 2*np.arange(n)], 1).astype(np.float32)}\n"
    "cd = {'mat': [np.array([1.5, 2.5]), np.array([3.5]), np.array([4.5]), np.array([9.0])],\n"
    "      'id': [np.array([10, 11], dtype=np.int32), np.array([12], dtype=np.int32), np.array([13], dtype=np.int32), np.array([14], dtype=np.int32)]}\n"
    "m = meshio.Mesh(pts, cells, point_data=pd, cell_data=cd)\n"
    "d = sys.argv[1]\n"
    "meshio.write(d + '/ascii.vtu', m, binary=False)\n"
    "meshio.write(d + '/raw.vtu', m, binary=True, compression=None)\n"
    "meshio.write(d + '/zlib.vtu', m, binary=True, compression='zlib')\n"
    "meshio.write(d + '/zlib64.vtu', m, binary=True, compression='zlib', header_type='UInt64')\n";

static int write_meshio_files(void)
{
    FILE *f = fopen(tpk_temp_path("make.py"), "w");
    if (!f)
        return -1;
    fputs(meshio_script, f);
    fclose(f);
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s", tpk_temp_path("make.py"), tpk_temp_dir());
    return system(cmd) == 0 ? 0 : -1;
}

static int same_mesh(const tpk_mesh *a, const tpk_mesh *b, char *why, size_t cap)
{
    if (a->point_count != b->point_count || a->cell_count != b->cell_count || a->field_count != b->field_count) {
        snprintf(why, cap, "counts differ");
        return 0;
    }
    if (memcmp(a->points, b->points, sizeof(double) * 3 * (size_t)a->point_count) ||
        memcmp(a->cell_types, b->cell_types, (size_t)a->cell_count) ||
        memcmp(a->cell_offsets, b->cell_offsets, sizeof(int64_t) * (size_t)(a->cell_count + 1)) ||
        memcmp(a->cell_conn, b->cell_conn, sizeof(int32_t) * (size_t)a->cell_offsets[a->cell_count])) {
        snprintf(why, cap, "points or cells differ");
        return 0;
    }
    for (int i = 0; i < a->field_count; i++) {
        const tpk_src_field *fa = &a->fields[i], *fb = field(b, fa->name);
        int64_t n = fa->association == TPK_ASSOC_POINT ? a->point_count : a->cell_count;
        if (!fb || fb->association != fa->association || fb->components != fa->components ||
            memcmp(fa->values, fb->values, sizeof(float) * (size_t)n * (size_t)fa->components)) {
            snprintf(why, cap, "field '%s' differs", fa->name);
            return 0;
        }
    }
    return 1;
}

/* The file `name` in the test directory imports as `ref`; else why not (its message, or the difference). */
static int imports_as(const tpk_mesh *ref, const char *name, char *why, size_t cap)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    if (tpk_import_vtu(tpk_temp_path(name), &m, &d) != 0) {
        size_t n = strlen(d.message) < cap ? strlen(d.message) : cap - 1;
        memcpy(why, d.message, n);
        why[n] = 0;
        return 0;
    }
    int ok = same_mesh(ref, &m, why, cap);
    tpk_mesh_free(&m);
    return ok;
}

static int check_small_mesh(const tpk_mesh *m, char *why, size_t cap)
{
    static const uint8_t types[5] = {10, 10, 12, 24};
    static const int32_t conn[] = {0, 1, 2, 3, 1, 4, 2, 7, 0, 1, 4, 2, 3, 5, 7, 6, 0, 1, 2, 3, 8, 9, 10, 11, 12, 13};
    if (m->point_count != 14 || m->cell_count != 4 || m->cell_offsets[4] != 26) {
        snprintf(why, cap, "counts: %lld points, %lld cells", (long long)m->point_count, (long long)m->cell_count);
        return 0;
    }
    if (memcmp(m->cell_types, types, 4) || memcmp(m->cell_conn, conn, sizeof conn)) {
        snprintf(why, cap, "cells differ");
        return 0;
    }
    if (m->points[0] != 0.25 || m->points[1] != -3.5 || m->points[2] != 1000 || m->points[3 * 7] != 1.25) {
        snprintf(why, cap, "points differ");
        return 0;
    }
    const tpk_src_field *temp = field(m, "temp"), *vel = field(m, "vel"), *mat = field(m, "mat"), *id = field(m, "id");
    if (m->field_count != 4 || !temp || !vel || !mat || !id || temp->components != 1 || vel->components != 3 ||
        mat->association != TPK_ASSOC_TET || temp->association != TPK_ASSOC_POINT || temp->values[13] != 6.5f ||
        vel->values[3 * 13 + 1] != -13.0f || vel->values[3 * 13 + 2] != 26.0f || mat->values[0] != 1.5f ||
        mat->values[3] != 4.5f || id->values[2] != 12.0f || id->values[3] != 13.0f) {
        snprintf(why, cap, "fields differ");
        return 0;
    }
    return 1;
}

static char *read_whole(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc(n > 0 ? (size_t)n : 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return buf;
}

TPK_TEST(meshio_encodings_agree)
{
    CHECK(write_meshio_files() == 0);
    tpk_mesh ref;
    tpk_diag d;
    quiet(&d);
    char why[200];
    CHECK_MSG(tpk_import_vtu(tpk_temp_path("ascii.vtu"), &ref, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(d.warning_count, 1); /* one dropped triangle (the tet10 kept whole) */
    int ok = check_small_mesh(&ref, why, sizeof why);
    if (!ok)
        tpk_mesh_free(&ref);
    CHECK_MSG(ok, "ascii: %s", why);
    const char *names[] = {"raw.vtu", "zlib.vtu", "zlib64.vtu"};
    for (int i = 0; i < 3; i++) {
        ok = imports_as(&ref, names[i], why, sizeof why);
        if (!ok)
            tpk_mesh_free(&ref);
        CHECK_MSG(ok, "%s: %s", names[i], why);
    }
    tpk_mesh_free(&ref);
}

/* ---- Hand-built appended raw files -------------------------------------------------------------- */

typedef struct buf {
    char *p;
    size_t n, cap;
} buf;

static void put(buf *b, const void *data, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2 + 256;
        b->p = realloc(b->p, b->cap);
    }
    memcpy(b->p + b->n, data, n);
    b->n += n;
}

static void puts_(buf *b, const char *s)
{
    put(b, s, strlen(s));
}

static void put_word(buf *b, uint64_t v, unsigned size, int big)
{
    unsigned char w[8];
    for (unsigned i = 0; i < size; i++)
        w[big ? size - 1 - i : i] = (unsigned char)(v >> (8 * i));
    put(b, w, size);
}

/* Values of `size` bytes each (integers or IEEE bits), swapped for big-endian. */
static void put_values(buf *b, const uint64_t *v, size_t n, unsigned size, int big)
{
    for (size_t i = 0; i < n; i++)
        put_word(b, v[i], size, big);
}

static uint64_t f32_bits(float x)
{
    uint32_t u;
    memcpy(&u, &x, 4);
    return u;
}

static void put_base64(buf *b, const unsigned char *p, size_t n)
{
    static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
        char q[4] = {digits[v >> 18], digits[(v >> 12) & 63], i + 1 < n ? digits[(v >> 6) & 63] : '=',
                     i + 2 < n ? digits[v & 63] : '='};
        put(b, q, 4);
    }
}

/* One array's appended block: UInt64 header (+ zlib blocks of 16 bytes when compressing); with b64 the
 * header and the data are base64-encoded separately, as VTK does. */
static void put_block(buf *app, const buf *raw, int zlib, int big, int b64)
{
    buf head = {0}, data = {0};
    if (!zlib) {
        put_word(&head, raw->n, 8, big);
        put(&data, raw->p, raw->n);
    } else {
        const size_t bs = 16;
        size_t blocks = (raw->n + bs - 1) / bs;
        uint64_t csize[64];
        for (size_t i = 0; i < blocks; i++) {
            size_t len = i + 1 == blocks ? raw->n - i * bs : bs;
            unsigned char out[128];
            uLongf olen = sizeof out;
            compress2(out, &olen, (const Bytef *)raw->p + i * bs, len, 9);
            csize[i] = olen;
            put(&data, out, olen);
        }
        put_word(&head, blocks, 8, big);
        put_word(&head, bs, 8, big);
        put_word(&head, raw->n % bs, 8, big);
        for (size_t i = 0; i < blocks; i++)
            put_word(&head, csize[i], 8, big);
    }
    if (b64) {
        put_base64(app, (const unsigned char *)head.p, head.n);
        put_base64(app, (const unsigned char *)data.p, data.n);
    } else {
        put(app, head.p, head.n);
        put(app, data.p, data.n);
    }
    free(head.p);
    free(data.p);
}

/* A pyramid and a wedge over 6 points, Float32 points, UInt8 types, Int16 offsets, a UInt64 cell field. */
static char *appended_file(int zlib, int big, int b64, size_t *size)
{
    static const float xyz[18] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5f, 0.5f, 1, 0.5f, 0.5f, -1};
    uint64_t pts[18], offs[2] = {5, 11}, types[2] = {14, 13}, ids[2] = {7, 0xffffffffull};
    uint64_t conn11[11] = {0, 1, 2, 3, 4, 0, 3, 5, 1, 2, 5};
    for (int i = 0; i < 18; i++)
        pts[i] = f32_bits(xyz[i]);
    buf app = {0}, raw = {0}, xml = {0};
    char line[256];
    size_t off[5];
    off[0] = app.n;
    put_values(&raw, pts, 18, 4, big);
    put_block(&app, &raw, zlib, big, b64);
    raw.n = 0;
    off[1] = app.n;
    put_values(&raw, conn11, 11, 8, big);
    put_block(&app, &raw, zlib, big, b64);
    raw.n = 0;
    off[2] = app.n;
    put_values(&raw, offs, 2, 2, big);
    put_block(&app, &raw, zlib, big, b64);
    raw.n = 0;
    off[3] = app.n;
    put_values(&raw, types, 2, 1, big);
    put_block(&app, &raw, zlib, big, b64);
    raw.n = 0;
    off[4] = app.n;
    put_values(&raw, ids, 2, 8, big);
    put_block(&app, &raw, zlib, big, b64);
    free(raw.p);
    snprintf(line, sizeof line,
             "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" "
             "header_type=\"UInt64\"%s>\n",
             big ? "BigEndian" : "LittleEndian", zlib ? " compressor=\"vtkZLibDataCompressor\"" : "");
    puts_(&xml, line);
    puts_(&xml, "  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"6\" NumberOfCells=\"2\">\n");
    snprintf(line, sizeof line,
             "      <Points>\n        <DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
             "offset=\"%zu\"/>\n      </Points>\n      <Cells>\n", off[0]);
    puts_(&xml, line);
    snprintf(line, sizeof line, "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" "
             "offset=\"%zu\"/>\n", off[1]);
    puts_(&xml, line);
    snprintf(line, sizeof line, "        <DataArray type=\"Int16\" Name=\"offsets\" format=\"appended\" "
             "offset=\"%zu\"/>\n", off[2]);
    puts_(&xml, line);
    snprintf(line, sizeof line, "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" "
             "offset=\"%zu\"></DataArray>\n      </Cells>\n", off[3]);
    puts_(&xml, line);
    snprintf(line, sizeof line, "      <CellData>\n        <DataArray type=\"UInt64\" Name=\"ids\" "
             "format=\"appended\" offset=\"%zu\"/>\n      </CellData>\n", off[4]);
    puts_(&xml, line);
    puts_(&xml, "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"");
    puts_(&xml, b64 ? "base64" : "raw");
    puts_(&xml, "\">\n   _");
    put(&xml, app.p, app.n);
    puts_(&xml, "\n  </AppendedData>\n</VTKFile>\n");
    free(app.p);
    *size = xml.n;
    return xml.p;
}

static int check_appended_mesh(const tpk_mesh *m)
{
    static const int32_t conn[11] = {0, 1, 2, 3, 4, 0, 3, 5, 1, 2, 5};
    const tpk_src_field *ids = field(m, "ids");
    return m->point_count == 6 && m->cell_count == 2 && m->cell_types[0] == TPK_CELL_PYRAMID &&
           m->cell_types[1] == TPK_CELL_WEDGE && m->cell_offsets[1] == 5 && m->cell_offsets[2] == 11 &&
           !memcmp(m->cell_conn, conn, sizeof conn) && m->points[3 * 4 + 2] == 1.0 && m->points[3 * 5 + 2] == -1.0 &&
           m->points[3 * 4] == 0.5 && ids && ids->association == TPK_ASSOC_TET && ids->values[0] == 7.0f &&
           ids->values[1] == 4294967295.0f && !strcmp(m->format, "vtu");
}

TPK_TEST(appended_raw)
{
    for (int variant = 0; variant < 8; variant++) {
        size_t size;
        char *text = appended_file(variant & 1, (variant >> 1) & 1, variant >> 2, &size);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        int rc = tpk_import_vtu_memory("app.vtu", text, size, &m, &d);
        free(text);
        CHECK_MSG(rc == 0, "variant %d: %s", variant, d.message);
        int ok = check_appended_mesh(&m);
        tpk_mesh_free(&m);
        CHECK_MSG(ok, "variant %d (zlib %d, big-endian %d, base64 %d): mesh differs", variant, variant & 1,
                  (variant >> 1) & 1, variant >> 2);
    }
}

/* ---- Bad input ----------------------------------------------------------------------------------- */

static void expect_failure_n(const char *text, size_t size, const char *where, const char *what, int line)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    char *copy = malloc(size ? size : 1); /* exact size: an overread is caught by ASan */
    memcpy(copy, text, size);
    int rc = tpk_import_vtu_memory("bad.vtu", copy, size, &m, &d);
    free(copy);
    if (rc == 0)
        tpk_mesh_free(&m);
    if (rc == 0 || !strstr(d.message, "bad.vtu") || (where && !strstr(d.message, where)) ||
        (what && !strstr(d.message, what)) || !mesh_is_empty(&m)) {
        fprintf(stderr, "test_vtu.c:%d: expected a failure with '%s' and '%s', got rc %d: '%s'\n", line,
                where ? where : "", what ? what : "", rc, d.message);
        tpk_test_failures++;
    }
}

#define expect_failure(text, where, what) expect_failure_n(text, strlen(text), where, what, __LINE__)

#define HEAD "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n<UnstructuredGrid>\n"
#define PIECE(np, nc) "<Piece NumberOfPoints=\"" np "\" NumberOfCells=\"" nc "\">\n"
#define POINTS4                                                                                               \
    "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1"  \
    "</DataArray></Points>\n"
#define CELLS(conn, offs, types)                                                                           \
    "<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">" conn "</DataArray>\n"      \
    "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">" offs "</DataArray>\n"                      \
    "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" types "</DataArray>\n</Cells>\n"
#define TAIL "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"

TPK_TEST(small_ascii_file)
{
    static const char text[] = HEAD PIECE("4", "2") POINTS4 CELLS("0 1 2 3 0 1 2", "4 7", "10 5") TAIL;
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_vtu_memory("ok.vtu", text, sizeof text - 1, &m, &d) == 0, "%s", d.message);
    int ok = m.point_count == 4 && m.cell_count == 1 && m.cell_types[0] == TPK_CELL_TETRA && d.warning_count == 1;
    tpk_mesh_free(&m);
    CHECK(ok);
}

/* A cube given as a polyhedron (its distinct points in cell_conn, its face stream in faces) next to a
 * tetrahedron; arrays outside the Piece's sections are ignored. */
TPK_TEST(polyhedron_faces)
{
    static const char text[] =
        HEAD "<FieldData><DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\">0.5</DataArray></FieldData>\n"
        PIECE("8", "2")
        "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0 "
        "0 0 1 1 0 1 1 1 1 0 1 1</DataArray></Points>\n"
        "<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\">0 1 2 3 4 5 6 7 0 1 3 4</DataArray>\n"
        "<DataArray type=\"Int64\" Name=\"offsets\">8 12</DataArray>\n"
        "<DataArray type=\"Int64\" Name=\"types\">42 10</DataArray>\n"
        "<DataArray type=\"Int64\" Name=\"faces\">6 4 0 3 2 1 4 4 5 6 7 4 0 1 5 4 4 1 2 6 5 4 2 3 7 6 4 3 0 4 7"
        "</DataArray>\n<DataArray type=\"Int64\" Name=\"faceoffsets\">31 -1</DataArray>\n</Cells>\n"
        "<CellData><DataArray type=\"Int8\" Name=\"flag\">-1 1</DataArray></CellData>\n" TAIL;
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_vtu_memory("poly.vtu", text, sizeof text - 1, &m, &d) == 0, "%s", d.message);
    const tpk_src_field *flag = field(&m, "flag");
    int ok = m.point_count == 8 && m.cell_count == 2 && m.cell_types[0] == TPK_CELL_POLYHEDRON &&
             m.cell_types[1] == TPK_CELL_TETRA && m.cell_offsets[1] == 8 && m.cell_offsets[2] == 12 &&
             m.cell_conn[0] == 0 && m.cell_conn[7] == 7 && m.cell_conn[8] == 0 && m.cell_conn[9] == 1 &&
             m.face_offsets[1] == 31 && m.face_offsets[2] == 31 && m.faces[0] == 6 && m.faces[30] == 7 &&
             m.field_count == 1 && flag && flag->values[0] == -1.0f && flag->values[1] == 1.0f;
    tpk_mesh_free(&m);
    CHECK(ok);
    char bad[sizeof text];
    memcpy(bad, text, sizeof text);
    char *f = strstr(bad, ">6 4 0 3 2 1");
    f[1] = '3';
    expect_failure_n(bad, sizeof bad - 1, "DataArray 'faces'", "cell 0 (polyhedron): expected a face count >= 4",
                     __LINE__);
    memcpy(bad, text, sizeof text);
    f = strstr(bad, " 4 3 0 4 7<");
    f[9] = '9';
    expect_failure_n(bad, sizeof bad - 1, "DataArray 'faces'", "point id 9", __LINE__);
}

TPK_TEST(bad_input)
{
    expect_failure("", "line 1", "expected well-formed XML");
    expect_failure("<VTKFile type=\"PolyData\">", "line 1", "expected type=\"UnstructuredGrid\", found \"PolyData\"");
    expect_failure("<foo/>", "line 1", "expected <VTKFile>");
    expect_failure(HEAD PIECE("4", "1") POINTS4 CELLS("0 1 2 9", "4", "10") TAIL, "DataArray 'connectivity' (line 7)",
                   "uses point id 9, but there are only 4 points");
    expect_failure(HEAD PIECE("4", "1") POINTS4 CELLS("0 1 2 -1", "4", "10") TAIL, "'connectivity'", "point id -1");
    expect_failure(HEAD PIECE("4", "2") POINTS4 CELLS("0 1 2 3 0 1 2 3", "8 4", "10 10") TAIL, "'offsets'",
                   "not decreasing");
    expect_failure(HEAD PIECE("4", "2") POINTS4 CELLS("0 1 2 3 0 1 2 3", "4 9", "10 10") TAIL, "'offsets'",
                   "from 4 to 8");
    expect_failure(HEAD PIECE("4", "2") POINTS4 CELLS("0 1 2 3 0 1 2 3", "4 7", "10 10") TAIL, "'offsets'",
                   "last offset");
    expect_failure(HEAD PIECE("4", "1") POINTS4 CELLS("0 1 2 3", "4", "12") TAIL, "'connectivity'",
                   "has 4 points, expected 8");
    expect_failure(HEAD PIECE("4", "1") POINTS4 CELLS("0 1 2 3", "4", "99") TAIL, "'types'", "unsupported cell type 99");
    expect_failure(HEAD PIECE("99999999999", "1") POINTS4 TAIL, "line 4", "NumberOfPoints 99999999999");
    expect_failure(HEAD PIECE("2000000000", "1") POINTS4 TAIL, "line 4", "cannot be held");
    expect_failure(HEAD PIECE("5", "1") POINTS4 TAIL, "DataArray 'unnamed' (line 5)", "expected 15 values, found 12");
    expect_failure(HEAD PIECE("x", "1") TAIL, "line 4", "expected NumberOfPoints >= 0, found x");
    expect_failure(HEAD PIECE("4", "1") "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\">0 0 0 1 0 0 0 1 "
                   "0 0 0 z</DataArray></Points>" TAIL, "line 5", "expected a number (value 12 of 12), found 'z'");
    expect_failure(HEAD PIECE("4", "1") "<Points><DataArray type=\"Float16\" NumberOfComponents=\"3\"/></Points>" TAIL,
                   "line 5", "found Float16");
    expect_failure(HEAD PIECE("4", "1") POINTS4 TAIL, NULL, "expected DataArrays connectivity, offsets and types");
    expect_failure(HEAD PIECE("1", "0") "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
                   "format=\"binary\">DAAAAAAAAAAAAAAAAAAAA!AA</DataArray></Points>" TAIL, "line 5", "not base64");
    expect_failure(HEAD PIECE("1", "0") "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
                   "format=\"binary\">DAAAAAAAAAAAAAAAAAAAAA</DataArray></Points>" TAIL, "line 5", "base64");
    expect_failure(HEAD PIECE("1", "0") "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
                   "format=\"binary\">/wAAAAAAAAAAAAAAAAAAAA==</DataArray></Points>" TAIL, "line 5",
                   "found a header saying 255");
    expect_failure(HEAD PIECE("1", "0") "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
                   "format=\"appended\" offset=\"0\"/></Points>" TAIL, "line 5", "expected an AppendedData section");
    expect_failure("<!DOCTYPE x [<!ENTITY a \"aaaa\">]><VTKFile/>", "line 1", "DOCTYPE");
    expect_failure(HEAD PIECE("0", "0") "</Piece>\n" PIECE("0", "0") TAIL, "line 6", "found a second");
    expect_failure("<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkLZ4DataCompressor\"/>", "line 1",
                   "vtkLZ4DataCompressor");
}

/* A zlib block that does not decompress, and a compressed size that cannot hold its block. */
TPK_TEST(bad_zlib_blocks)
{
    size_t size;
    char *text = appended_file(1, 0, 0, &size);
    char *app = strstr(text, "   _") + 4;
    /* Spoil the zlib stream header of the first block of the first array (points: 72 bytes in 5 blocks
     * of 16, after a header of 3 + 5 UInt64 words). */
    size_t first = 8 * (3 + 5);
    char *copy = malloc(size);
    memcpy(copy, text, size);
    copy[app - text + first] ^= 0x55;
    copy[app - text + first + 1] ^= 0x55;
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    int rc = tpk_import_vtu_memory("bad.vtu", copy, size, &m, &d);
    if (rc == 0)
        tpk_mesh_free(&m);
    int ok = rc != 0 && strstr(d.message, "bad.vtu: DataArray 'unnamed' (line 6): zlib block 1 of 5 does not "
                                          "decompress") != NULL && mesh_is_empty(&m);
    /* A block claiming 16 GiB uncompressed. */
    memcpy(copy, text, size);
    uint64_t huge = (uint64_t)1 << 34;
    memcpy(copy + (app - text) + 8, &huge, 8);
    quiet(&d);
    int rc2 = tpk_import_vtu_memory("bad.vtu", copy, size, &m, &d);
    if (rc2 == 0)
        tpk_mesh_free(&m);
    free(copy);
    free(text);
    CHECK_MSG(ok, "'%s'", d.message);
    CHECK_MSG(rc2 != 0 && strstr(d.message, "bad.vtu: DataArray 'unnamed' (line 6):"), "'%s'", d.message);
}

/* Cut valid files at every byte (hand-built appended ones) or at many offsets (meshio ones): every
 * prefix fails naming the file, with the mesh left empty, except a cut in the whitespace after
 * '</VTKFile>', which leaves a whole file. */
static int cut_everywhere(const char *text, size_t size, size_t step)
{
    for (size_t n = 0; n < size; n += step) {
        char *copy = malloc(n ? n : 1);
        memcpy(copy, text, n);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        int rc = tpk_import_vtu_memory("cut.vtu", copy, n, &m, &d);
        free(copy);
        size_t rest = n;
        while (rest < size && strchr(" \t\r\n", text[rest]))
            rest++;
        int whole = rest == size && n >= strlen("</VTKFile>") && !memcmp(text + n - 10, "</VTKFile>", 10);
        if (rc == 0)
            tpk_mesh_free(&m);
        if (whole != (rc == 0)) {
            fprintf(stderr, "prefix %zu of %zu (%s): '%s'\n", n, size, whole ? "a whole file" : "cut", d.message);
            return -1;
        }
        if (rc == 0)
            continue;
        if (!strstr(d.message, "cut.vtu") || !mesh_is_empty(&m)) {
            fprintf(stderr, "prefix %zu of %zu: '%s'\n", n, size, d.message);
            return -1;
        }
    }
    return 0;
}

TPK_TEST(every_truncation)
{
    for (int variant = 0; variant < 8; variant++) {
        size_t size;
        char *text = appended_file(variant & 1, (variant >> 1) & 1, variant >> 2, &size);
        int rc = cut_everywhere(text, size, 1);
        free(text);
        CHECK_MSG(rc == 0, "variant %d", variant);
    }
    CHECK(write_meshio_files() == 0);
    const char *names[] = {"ascii.vtu", "raw.vtu", "zlib.vtu", "zlib64.vtu"};
    for (int i = 0; i < 4; i++) {
        size_t size;
        char *text = read_whole(tpk_temp_path(names[i]), &size);
        CHECK(text);
        int rc = cut_everywhere(text, size, 7);
        /* A cut just before the closing tags fails too. */
        size_t end = size;
        while (end && text[end - 1] != '<')
            end--;
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        int rc2 = end ? tpk_import_vtu_memory("cut.vtu", text, end - 1, &m, &d) : -1;
        if (rc2 == 0)
            tpk_mesh_free(&m);
        free(text);
        CHECK_MSG(rc == 0, "%s", names[i]);
        CHECK_MSG(rc2 != 0 && strstr(d.message, "cut.vtu"), "%s: '%s'", names[i], d.message);
    }
}

/* expat's own verdict on a whole buffer, as "line L, column C" (NULL when it takes the document). */
static const char *expat_place(const char *text, size_t size, char *place, size_t cap)
{
    XML_Parser p = XML_ParserCreate(NULL);
    int ok = XML_Parse(p, text, (int)size, 1) != XML_STATUS_ERROR;
    snprintf(place, cap, "line %ld, column %ld", (long)XML_GetCurrentLineNumber(p), (long)XML_GetCurrentColumnNumber(p));
    XML_ParserFree(p);
    return ok ? NULL : place;
}

/* A real meshio file (binary, base64) and where the text of its first binary DataArray starts (after
 * the tag's line break); NULL if it cannot be read. */
static char *read_run_file(size_t *size, size_t *at)
{
    char *text = read_whole(TPK_DATA_DIR "/hard/nonmanifold_vertex_edge_tets.vtu", size);
    const char *run = text ? strstr(text, "format=\"binary\">\n") : NULL;
    if (!run) {
        free(text);
        return NULL;
    }
    *at = (size_t)(run - text) + strlen("format=\"binary\">\n");
    return text;
}

/* Long base64 runs are read past expat (tools/import/xml_input.c): a file broken in or after one still
 * gets the line and column expat itself finds in the whole file. A real meshio file, broken inside its
 * longest run, with the run's closing tag on its line and misspelt, and cut inside the run. */
TPK_TEST(long_base64_runs_keep_error_places)
{
    size_t size, at = 0;
    char *text = read_run_file(&size, &at);
    CHECK(text);
    if (!text)
        return;
    size_t len = strcspn(text + at, "<\n");
    CHECK_MSG(len > 20000, "a run of %zu characters", len); /* long enough to be taken */
    char *bad = malloc(size);
    const struct {
        size_t offset;
        const char *put;
        size_t cut; /* 0: the whole file */
    } cases[] = {{at + 9000, "&", 0}, {at + 15000, "<", 0}, {at + len, "</DataArrax>", 0}, {at, "", at + 12000}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memcpy(bad, text, size);
        size_t n = cases[i].cut ? cases[i].cut : size;
        memcpy(bad + cases[i].offset, cases[i].put, strlen(cases[i].put)); /* the tag overwrites "\n</DataArray" */
        char place[64];
        const char *expected = expat_place(bad, n, place, sizeof place);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        int rc = tpk_import_vtu_memory("bad.vtu", bad, n, &m, &d);
        CHECK_MSG(expected && rc != 0 && strstr(d.message, expected) && strstr(d.message, "expected well-formed XML"),
                  "case %zu: expat says '%s', the reader '%s'", i, expected ? expected : "(fine)", d.message);
        if (rc == 0)
            tpk_mesh_free(&m);
    }
    free(bad);
    free(text);
}

/* ---- Large arrays on all cores ------------------------------------------------------------------ */

/* 140,000 tets and 12 dropped triangles over 20,000 points, with a cell field, by meshio: ASCII, base64
 * uncompressed (its connectivity 6 MB of base64, decoded on all cores), the same with the base64 broken
 * into 76-character lines, zlib; and with point ids out of range at cells 100,000 and 120,000 (both in
 * the second worker's half of the cells, with two workers). */
static const char big_script[] =
    "import sys, re, numpy as np, meshio\n"
    "rng = np.random.default_rng(7)\n"
    "pts = rng.integers(0, 1000, (20000, 3)) / 8.0  # short decimals: ASCII holds them exactly\n"
    "tets = rng.integers(0, 20000, (140000, 4))\n"
    "tris = rng.integers(0, 20000, (12, 3))\n"
    "cd = {'mat': [np.arange(140000, dtype=float), np.zeros(12)]}\n"
    "d = sys.argv[1]\n"
    "m = meshio.Mesh(pts, [('tetra', tets), ('triangle', tris)], cell_data=cd)\n"
    "meshio.write(d + '/big_ascii.vtu', m, binary=False)\n"
    "meshio.write(d + '/big_raw.vtu', m, binary=True, compression=None)\n"
    "meshio.write(d + '/big_zlib.vtu', m, binary=True, compression='zlib')\n"
    "text = open(d + '/big_raw.vtu').read()\n"
    "wrap = lambda t: '\\n'.join(t[i:i + 76] for i in range(0, len(t), 76))\n"
    "text = re.sub(r'(format=\"binary\"[^>]*>)\\s*([A-Za-z0-9+/=]{4096,})', lambda g: g.group(1) + '\\n' + wrap(g.group(2)), text)\n"
    "open(d + '/big_wrapped.vtu', 'w').write(text)\n"
    "bad = tets.copy(); bad[100000, 2] = 20000; bad[120000, 0] = 25000\n"
    "b = meshio.Mesh(pts, [('tetra', bad), ('triangle', tris)], cell_data=cd)\n"
    "meshio.write(d + '/big_bad_ascii.vtu', b, binary=False)\n"
    "meshio.write(d + '/big_bad_raw.vtu', b, binary=True, compression=None)\n";

TPK_TEST(large_arrays_on_all_cores_agree)
{
    FILE *f = fopen(tpk_temp_path("make_big.py"), "w");
    CHECK(f != NULL);
    fputs(big_script, f);
    fclose(f);
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s", tpk_temp_path("make_big.py"), tpk_temp_dir());
    CHECK(system(cmd) == 0);
    tpk_mesh ref;
    tpk_diag d;
    quiet(&d);
    char why[200];
    CHECK_MSG(tpk_import_vtu(tpk_temp_path("big_ascii.vtu"), &ref, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(ref.cell_count, 140000);
    const char *names[] = {"big_raw.vtu", "big_wrapped.vtu", "big_zlib.vtu"};
    for (int i = 0; i < 3; i++) {
        int ok = imports_as(&ref, names[i], why, sizeof why);
        if (!ok)
            tpk_mesh_free(&ref);
        CHECK_MSG(ok, "%s: %s", names[i], why);
    }
    tpk_mesh_free(&ref);
    const char *bad[] = {"big_bad_ascii.vtu", "big_bad_raw.vtu"};
    for (int i = 0; i < 2; i++) {
        tpk_mesh m;
        quiet(&d);
        CHECK(tpk_import_vtu(tpk_temp_path(bad[i]), &m, &d) != 0);
        CHECK_MSG(strstr(d.message, "cell 100000 uses point id 20000, but there are only 20000 points"), "%s: %s",
                  bad[i], d.message);
    }
}

/* A long base64 run is decoded where it lies in the file (not copied): a comment inside it makes expat
 * give the rest as more text, and the array reads as without the comment; a bad character inside it is
 * placed by its character in the array's text, as when the text was copied. */
TPK_TEST(long_base64_run_read_in_place)
{
    size_t size, at = 0;
    char *text = read_run_file(&size, &at);
    CHECK(text);
    if (!text)
        return;
    const char comment[] = "<!-- c -->";
    char *with = malloc(size + sizeof comment);
    CHECK(with != NULL);
    memcpy(with, text, at + 9000);
    memcpy(with + at + 9000, comment, strlen(comment));
    memcpy(with + at + 9000 + strlen(comment), text + at + 9000, size - at - 9000);
    tpk_mesh ref, m;
    tpk_diag d;
    char why[200];
    quiet(&d);
    CHECK_MSG(tpk_import_vtu_memory("ref.vtu", text, size, &ref, &d) == 0, "%s", d.message);
    quiet(&d);
    int rc = tpk_import_vtu_memory("comment.vtu", with, size + strlen(comment), &m, &d);
    int ok = rc == 0 && same_mesh(&ref, &m, why, sizeof why);
    if (rc == 0)
        tpk_mesh_free(&m);
    tpk_mesh_free(&ref);
    CHECK_MSG(ok, "%s", rc ? d.message : why);
    text[at + 9000] = '!';
    quiet(&d);
    CHECK(tpk_import_vtu_memory("bad.vtu", text, size, &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "found a character that is not base64 at character 9001 of the array's text"), "%s",
              d.message);
    free(with);
    free(text);
}
