/* Exporter tests: a tiny .tpk written with tpk_writer (2 tets sharing a face, TT32 or TT16 only, POS3,
 * SHEL, a point field, a 2-step tet field, TIME, TMAP, VMAP) exported to VTU and PLY. The VTU is read back
 * with meshio (an independent reader) through python3; the PLY is parsed here and by meshio. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "export/exporters.h"
#include "harness.h"
#include "tetpack.h"

/* Vertices: origin + (0,0,0), (1,0,0), (0,1,0), (0,0,1), (1,1,1). Tets A = (0,1,2,3), B = (1,2,3,4), both
 * positive, sharing face (1,2,3). */
static const double origin[3] = {1000.0, -5.0, 0.25};
static const float positions[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};

static tpk_result add(tpk_writer *w, uint32_t tag, uint8_t elem_type, uint32_t elem_size, uint64_t count,
                      uint32_t index, uint32_t step, int required, int zstd, const void *data)
{
    tpk_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.tag = tag;
    d.flags = required ? TPK_CHUNK_REQUIRED : 0;
    d.codec = zstd ? TPK_CODEC_ZSTD : TPK_CODEC_NONE;
    d.elem_type = elem_type;
    d.elem_size = elem_size;
    d.index = index;
    d.step = step;
    d.elem_count = count;
    return tpk_writer_add_chunk(w, &d, data);
}

static tpk_field_desc field(const char *name, uint32_t assoc, uint32_t steps, float lo, float hi)
{
    tpk_field_desc f;
    memset(&f, 0, sizeof f);
    snprintf(f.name, sizeof f.name, "%s", name);
    f.association = assoc;
    f.step_count = steps;
    f.components = 1;
    f.min_value = lo;
    f.max_value = hi;
    return f;
}

/* layout 32: TT32 only; 16: TT16 only. Returns 0 on success. */
static int write_tiny(const char *path, int layout, char *err, size_t cap)
{
    const tpk_tet32 tet32[2] = {{{0, 1, 2}, 0 ^ 1 ^ 2 ^ 3, {1, -1, -1, -1}}, {{1, 2, 3}, 1 ^ 2 ^ 3 ^ 4, {-1, -1, -1, 0}}};
    /* Tet16: n sorted by the rank of the opposite vertex id; nx[r] = n[r] ^ n[3]. */
    const tpk_tet16 tet16[2] = {{0 ^ 1 ^ 2 ^ 3, {1 ^ -1, -1 ^ -1, -1 ^ -1}}, {1 ^ 2 ^ 3 ^ 4, {-1 ^ 0, -1 ^ 0, -1 ^ 0}}};
    /* Outward faces of a positive tet (v0..v3): opp 0 (1,2,3), opp 1 (0,3,2), opp 2 (0,1,3), opp 3 (0,2,1). */
    const tpk_shell_face shell[6] = {{0, 3, 2, 0}, {0, 1, 3, 0}, {0, 2, 1, 0}, {2, 3, 4, 1}, {1, 4, 3, 1}, {1, 2, 4, 1}};
    const tpk_field_desc fields[2] = {field("temperature", TPK_ASSOC_POINT, 1, 0.5f, 4.5f),
                                      field("pressure", TPK_ASSOC_TET, 2, 10.0f, 21.0f)};
    const float temperature[5] = {0.5f, 1.5f, 2.5f, 3.5f, 4.5f}, p0[2] = {10, 20}, p1[2] = {11, 21};
    const double times[2] = {0.0, 0.5};
    const int32_t tmap[2] = {7, 9}, vmap[5] = {100, 101, 102, 103, 104};
    tpk_writer *w;
    tpk_result r = tpk_writer_open(&w, path, NULL, err, cap);
    if (r != TPK_OK)
        return -1;
    r = add(w, TPK_TAG_POS3, TPK_ELEM_VEC3_F32, 12, 5, 0, 0, 1, 0, positions);
    if (r == TPK_OK)
        r = layout == 32 ? add(w, TPK_TAG_TT32, TPK_ELEM_TET32, 32, 2, 0, 0, 1, 0, tet32)
                         : add(w, TPK_TAG_TT16, TPK_ELEM_TET16, 16, 2, 0, 0, 1, 1, tet16);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_SHEL, TPK_ELEM_SHELL_FACE, 16, 6, 0, 0, 1, 0, shell);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_FDSC, TPK_ELEM_FIELD_DESC, 128, 2, 0, 0, 1, 0, fields);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_FDAT, TPK_ELEM_F32, 4, 5, 0, 0, 1, 0, temperature);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_FDAT, TPK_ELEM_F32, 4, 2, 1, 0, 1, 0, p0);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_FDAT, TPK_ELEM_F32, 4, 2, 1, 1, 1, 1, p1); /* zstd: exercises decoding */
    if (r == TPK_OK)
        r = add(w, TPK_TAG_TIME, TPK_ELEM_F64, 8, 2, 0, 0, 0, 0, times);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_TMAP, TPK_ELEM_I32, 4, 2, 0, 0, 0, 0, tmap);
    if (r == TPK_OK)
        r = add(w, TPK_TAG_VMAP, TPK_ELEM_I32, 4, 5, 0, 0, 0, 0, vmap);
    if (r != TPK_OK) {
        snprintf(err, cap, "add_chunk: %s", tpk_writer_error_text(w));
        tpk_writer_abort(w);
        return -1;
    }
    tpk_header_fields h;
    memset(&h, 0, sizeof h);
    h.vertex_count = 5;
    h.tet_count = 2;
    h.shell_face_count = 6;
    for (int k = 0; k < 3; k++) {
        h.origin[k] = origin[k];
        h.bounds_min[k] = origin[k];
        h.bounds_max[k] = origin[k] + 1.0;
    }
    r = tpk_writer_finish(w, &h);
    if (r != TPK_OK)
        snprintf(err, cap, "finish: %s", tpk_result_string(r));
    return r == TPK_OK ? 0 : -1;
}

/* python3 with meshio: the system one first (the PATH one may lack it). Returns NULL if none. */
static const char *python_with_meshio(void)
{
    static const char *candidates[] = {"/usr/bin/python3", "python3"};
    for (int i = 0; i < 2; i++) {
        char cmd[256];
        snprintf(cmd, sizeof cmd, "%s -c 'import meshio' >/dev/null 2>&1", candidates[i]);
        if (system(cmd) == 0)
            return candidates[i];
    }
    return NULL;
}

static int run_python(const char *script, const char *arg)
{
    const char *py = python_with_meshio();
    if (!py)
        return -2;
    const char *script_path = tpk_temp_path("check.py");
    FILE *f = fopen(script_path, "w");
    if (!f)
        return -1;
    fputs(script, f);
    fclose(f);
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s -W ignore %s '%s'", py, script_path, arg);
    return system(cmd) == 0 ? 0 : -1;
}

static const char vtu_check[] =
    "import sys, meshio, numpy as np\n"
    "m = meshio.read(sys.argv[1])\n"
    "layout = int(sys.argv[1].split('_')[-1].split('.')[0])\n"
    "pts = np.array([[1000,-5,0.25],[1001,-5,0.25],[1000,-4,0.25],[1000,-5,1.25],[1001,-4,1.25]], dtype=float)\n"
    "assert m.points.dtype == np.float64, m.points.dtype\n"
    "assert np.array_equal(m.points, pts), m.points\n"
    "assert len(m.cells) == 1 and m.cells[0].type == 'tetra', m.cells\n"
    "c = m.cells[0].data\n"
    "if layout == 32: assert c.tolist() == [[0,1,2,3],[1,2,3,4]], c\n"
    "assert [sorted(t) for t in c.tolist()] == [[0,1,2,3],[1,2,3,4]], c\n"
    "for t in c:\n"
    "    p = m.points[t]\n"
    "    assert np.linalg.det(np.array([p[1]-p[0], p[2]-p[0], p[3]-p[0]])) > 0, t\n"
    "pd, cd = m.point_data, m.cell_data\n"
    "assert sorted(pd) == ['source_point', 'temperature'], sorted(pd)\n"
    "assert sorted(cd) == ['pressure_t0', 'pressure_t1', 'source_cell'], sorted(cd)\n"
    "assert pd['temperature'].dtype == np.float32 and pd['temperature'].tolist() == [0.5,1.5,2.5,3.5,4.5]\n"
    "assert pd['source_point'].dtype == np.int32 and pd['source_point'].tolist() == [100,101,102,103,104]\n"
    "assert cd['pressure_t0'][0].tolist() == [10,20] and cd['pressure_t1'][0].tolist() == [11,21]\n"
    "assert cd['source_cell'][0].tolist() == [7, 9]\n";

static int no_temp_files_left(void)
{
    DIR *d = opendir(tpk_temp_dir());
    struct dirent *e;
    int clean = 1;
    while (d && (e = readdir(d)) != NULL)
        clean &= strstr(e->d_name, ".tmp-") == NULL;
    if (d)
        closedir(d);
    return clean;
}

static void export_and_check_vtu(int layout)
{
    char err[512] = "", name[64];
    snprintf(name, sizeof name, "tiny_%d.tpk", layout);
    const char *tpk = tpk_temp_path(name);
    CHECK_MSG(write_tiny(tpk, layout, err, sizeof err) == 0, "%s", err);
    tpk_file *file;
    CHECK_MSG(tpk_open_path(&file, tpk, NULL, err, sizeof err) == TPK_OK, "%s", err);
    snprintf(name, sizeof name, "tiny_%d.vtu", layout);
    const char *vtu = tpk_temp_path(name);
    tpk_diag d;
    memset(&d, 0, sizeof d);
    int rc = tpk_export_vtu(file, vtu, &d);
    tpk_close(file);
    CHECK_MSG(rc == 0, "%s", d.message);
    CHECK(no_temp_files_left());
    FILE *f = fopen(vtu, "rb");
    CHECK(f);
    char head[2048] = {0};
    size_t n = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    CHECK(n > 200);
    CHECK(strstr(head, "version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\""));
    CHECK(strstr(head, "<AppendedData encoding=\"raw\">"));
    int py = run_python(vtu_check, vtu);
    if (py == -2) /* meshio is the independent reader; without it this test proves too little to pass */
        TPK_SKIP("python3 with meshio not found; VTU contents not checked independently");
    CHECK_MSG(py == 0, "meshio check of %s failed (see the python traceback above)", vtu);
}

TPK_TEST(vtu_from_tet32)
{
    export_and_check_vtu(32);
}

TPK_TEST(vtu_from_tet16_zstd)
{
    export_and_check_vtu(16);
}

/* meshio 5.0 cannot read a binary PLY whose faces carry a scalar after the index list (it reads the
 * lists of all faces, then one scalar), so the independent check parses the records with numpy. */
static const char ply_check[] =
    "import sys, numpy as np\n"
    "data = open(sys.argv[1], 'rb').read()\n"
    "head, body = data.split(b'end_header\\n', 1)\n"
    "lines = head.decode().splitlines()\n"
    "assert lines[0] == 'ply' and lines[1] == 'format binary_little_endian 1.0', lines\n"
    "nv = int([l for l in lines if l.startswith('element vertex')][0].split()[2])\n"
    "nf = int([l for l in lines if l.startswith('element face')][0].split()[2])\n"
    "assert (nv, nf) == (5, 6), (nv, nf)\n"
    "v = np.frombuffer(body, dtype='<f8', count=3 * nv).reshape(-1, 3)\n"
    "f = np.frombuffer(body, dtype=[('n', 'u1'), ('i', '<i4', 3), ('t', '<i4')], offset=24 * nv)\n"
    "assert len(f) == nf and (f['n'] == 3).all() and f['t'].tolist() == [0, 0, 0, 1, 1, 1], f\n"
    "assert v[:, 0].min() == 1000 and v[:, 2].max() == 1.25, v\n"
    "tets = [[0, 1, 2, 3], [1, 2, 3, 4]]\n"
    "for (n, i, t) in f:\n"
    "    a, b, c = v[i]\n"
    "    assert np.dot(np.cross(b - a, c - a), a - v[tets[t]].mean(axis=0)) > 0, (i, t)\n";

TPK_TEST(shell_ply)
{
    char err[512] = "";
    const char *tpk = tpk_temp_path("tiny_ply.tpk");
    CHECK_MSG(write_tiny(tpk, 32, err, sizeof err) == 0, "%s", err);
    tpk_file *file;
    CHECK_MSG(tpk_open_path(&file, tpk, NULL, err, sizeof err) == TPK_OK, "%s", err);
    const char *ply = tpk_temp_path("shell.ply");
    tpk_diag d;
    memset(&d, 0, sizeof d);
    int rc = tpk_export_shell_ply(file, ply, &d);
    tpk_close(file);
    CHECK_MSG(rc == 0, "%s", d.message);
    CHECK(no_temp_files_left());

    FILE *f = fopen(ply, "rb");
    CHECK(f);
    static unsigned char data[4096];
    size_t n = fread(data, 1, sizeof data, f);
    fclose(f);
    const char *end = strstr((const char *)data, "end_header\n");
    CHECK(end);
    CHECK(strstr((const char *)data, "format binary_little_endian 1.0\n"));
    CHECK(strstr((const char *)data, "element vertex 5\n"));
    CHECK(strstr((const char *)data, "element face 6\n"));
    CHECK(strstr((const char *)data, "property list uchar int vertex_indices\nproperty int tet\n"));
    size_t at = (size_t)(end - (const char *)data) + strlen("end_header\n");
    CHECK_EQ_INT(n, at + 5 * 24 + 6 * 17);
    double xyz[5][3];
    memcpy(xyz, data + at, sizeof xyz);
    CHECK(xyz[4][0] == 1001.0 && xyz[4][1] == -4.0 && xyz[4][2] == 1.25 && xyz[0][2] == 0.25);
    /* Every face points away from its tet's centroid. */
    const int tets[2][4] = {{0, 1, 2, 3}, {1, 2, 3, 4}};
    for (int k = 0; k < 6; k++) {
        const unsigned char *rec = data + at + 5 * 24 + (size_t)k * 17;
        CHECK_EQ_INT(rec[0], 3);
        int32_t v[4];
        memcpy(v, rec + 1, 16);
        CHECK(v[3] == (k < 3 ? 0 : 1));
        double c[3] = {0, 0, 0}, e1[3], e2[3], nrm[3], dot = 0;
        for (int j = 0; j < 4; j++)
            for (int q = 0; q < 3; q++)
                c[q] += xyz[tets[v[3]][j]][q] / 4;
        for (int q = 0; q < 3; q++) {
            e1[q] = xyz[v[1]][q] - xyz[v[0]][q];
            e2[q] = xyz[v[2]][q] - xyz[v[0]][q];
        }
        nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
        nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
        nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
        for (int q = 0; q < 3; q++)
            dot += nrm[q] * (xyz[v[0]][q] - c[q]);
        CHECK_MSG(dot > 0, "face %d points inward", k);
    }
    int py = run_python(ply_check, ply);
    if (py == -2)
        TPK_SKIP("python3 with meshio and numpy not found; PLY not checked independently");
    CHECK_MSG(py == 0, "numpy check of %s failed", ply);
}

TPK_TEST(export_errors_leave_nothing)
{
    char err[512] = "";
    const char *tpk = tpk_temp_path("tiny_err.tpk");
    CHECK_MSG(write_tiny(tpk, 32, err, sizeof err) == 0, "%s", err);
    tpk_file *file;
    CHECK_MSG(tpk_open_path(&file, tpk, NULL, err, sizeof err) == TPK_OK, "%s", err);
    const char *bad = tpk_temp_path("no_such_dir/out.vtu");
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_export_vtu(file, bad, &d) != 0);
    CHECK_MSG(strstr(d.message, "no_such_dir/out.vtu"), "%s", d.message);
    memset(&d, 0, sizeof d);
    CHECK(tpk_export_shell_ply(file, tpk_temp_path("no_such_dir/out.ply"), &d) != 0);
    CHECK_MSG(strstr(d.message, "no_such_dir/out.ply"), "%s", d.message);
    tpk_close(file);
    CHECK(no_temp_files_left());
}
