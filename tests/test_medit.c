/* Medit .mesh (ASCII) importer: real sfepy files (counts, references, positive hexahedra in VTK node
 * order), every section kind on a small file, and bad input that must fail with file:line. */
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "import/importers.h"
#include "convert/pipeline.h"

static int quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
    d->warn = NULL;
    return 0;
}

static const float *field(const tpk_mesh *m, const char *name)
{
    for (int i = 0; i < m->field_count; i++)
        if (!strcmp(m->fields[i].name, name))
            return m->fields[i].values;
    return NULL;
}

TPK_TEST(real_tetra_files)
{
    static const struct {
        const char *path;
        int64_t points, cells;
    } files[] = {{"sfepy/cube_big_tetra.mesh", 36878, 202596},
                 {"sfepy/elbow.mesh", 1823, 8161},
                 {"sfepy/cube_cylinder.mesh", 10490, 54517},
                 {"sfepy/cube_medium_tetra.mesh", 448, 1782}};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_any(tpk_data_path(files[i].path), NULL, &m, &d) == 0, "%s", d.message);
        int ok = m.point_count == files[i].points && m.cell_count == files[i].cells &&
                 !strcmp(m.format, "medit-ascii") && field(&m, "ref") != NULL;
        for (int64_t c = 0; ok && c < m.cell_count; c++)
            ok = m.cell_types[c] == 10 && m.cell_offsets[c] == 4 * c;
        tpk_mesh_free(&m);
        CHECK_MSG(ok, "%s: counts, types or fields differ", files[i].path);
    }
}

/* Every corner of a VTK-ordered hexahedron (bottom 0-3, top 4-7) is right-handed in its three edges. */
TPK_TEST(real_hexahedra_are_vtk_ordered)
{
    static const int around[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                                     {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
    const char *paths[] = {"sfepy/cube_medium_hexa.mesh", "sfepy/acoustics_mesh3d.mesh", "sfepy/cross3d.mesh"};
    const int64_t counts[] = {1000, 4380, 7};
    for (int f = 0; f < 3; f++) {
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_medit(tpk_data_path(paths[f]), &m, &d) == 0, "%s", d.message);
        int64_t bad = 0;
        for (int64_t c = 0; c < m.cell_count; c++) {
            const int32_t *h = m.cell_conn + m.cell_offsets[c];
            for (int k = 0; k < 8; k++)
                bad += tpk_orient3d_exact(m.points + 3 * h[k], m.points + 3 * h[around[k][0]],
                                          m.points + 3 * h[around[k][1]], m.points + 3 * h[around[k][2]]) <= 0;
        }
        int ok = m.cell_count == counts[f] && m.cell_types[0] == 12;
        tpk_mesh_free(&m);
        CHECK_MSG(ok && bad == 0, "%s: %lld cells? %lld corners not positive", paths[f], (long long)counts[f],
                  (long long)bad);
    }
}

TPK_TEST(all_section_kinds)
{
    static const char text[] =
        "# a comment before the header\n"
        "MeshVersionFormatted 2\n"
        "Dimension\n3\n"
        "Vertices\n5\n"
        "0 0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0   0 0 -1 7\n"
        "Corners 2\n1 2\n"
        "Edges\n1\n1 2 9\n"
        "Triangles\n2\n1 2 3 4\n1 2 5 4\n"
        "Quadrilaterals 0\n"
        "Normals 1 0 0 1\n"
        "NormalAtVertices 1 1 1\n"
        "Tetrahedra\n2\n1 2 3 4 11\n1 3 2 5 12\n"
        "# trailing comment\n"
        "End\n"
        "anything after End is ignored\n";
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    d.warn = NULL;
    CHECK_MSG(tpk_import_medit_memory("small", text, sizeof text - 1, &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 5);
    CHECK_EQ_INT(m.cell_count, 2);
    CHECK_EQ_INT(d.warning_count, 1); /* 3 surface and line elements dropped */
    CHECK(m.cell_conn[0] == 0 && m.cell_conn[3] == 3 && m.cell_conn[4] == 0 && m.cell_conn[7] == 4);
    CHECK(m.points[3 * 4 + 2] == -1.0);
    const float *ref = field(&m, "ref"), *vref = field(&m, "vertex_ref");
    CHECK(ref && ref[0] == 11.0f && ref[1] == 12.0f);
    CHECK(vref && vref[0] == 1.0f && vref[4] == 7.0f && vref[1] == 0.0f);
    tpk_mesh_free(&m);
}

static void expect_failure(const char *text, const char *where, const char *what)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    int rc = tpk_import_medit_memory("bad.mesh", text, strlen(text), &m, &d);
    CHECK_MSG(rc != 0 && strstr(d.message, where) && strstr(d.message, what), "for input %.40s...: '%s'", text,
              d.message);
    CHECK(m.cell_count == 0 && m.points == NULL && m.fields == NULL);
}

#define HDR "MeshVersionFormatted 2\nDimension 3\n"
#define VERTS HDR "Vertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"

TPK_TEST(bad_input)
{
    expect_failure("", "bad.mesh:1:", "expected 'MeshVersionFormatted' (a Medit .mesh file), found 'end of file'");
    expect_failure("# vtk DataFile Version 2.0\n", "bad.mesh:2:", "expected 'MeshVersionFormatted'");
    expect_failure("MeshVersionFormatted 9\n", "bad.mesh:1:", "expected format version 1 to 4, found 9");
    expect_failure("MeshVersionFormatted 2\nDimension 2\n", "bad.mesh:2:", "expected dimension 3");
    expect_failure(HDR "Vertices\n2\n0 0 0 0\n1 0 x 0\n", "bad.mesh:6:", "expected a vertex coordinate, found 'x'");
    expect_failure(HDR "Vertices\n999999999999\n0 0 0 0\n", "bad.mesh:4:", "cannot fit in the");
    expect_failure(HDR "Vertices\n-3\n", "bad.mesh:4:", "expected a count of 0 or more, found -3");
    expect_failure(VERTS "Tetrahedra\n1\n1 2 3 0 0\n", "bad.mesh:11:", "vertex id 0, expected 1 or more");
    expect_failure(VERTS "Tetrahedra\n1\n1 2 3 9 0\n", "bad.mesh:", "uses vertex 9, but there are only 4 vertices");
    expect_failure(VERTS "Tetrahedra\n2\n1 2 3 4 0\n1 2 3\n", "bad.mesh:", "found end of file");
    expect_failure(VERTS "Prisms\n1\n1 2 3 4 1 2 0\n", "bad.mesh:9:", "Prisms are not read yet");
    expect_failure(VERTS "Tetrahedrons\n1\n", "bad.mesh:9:", "unknown Medit keyword 'Tetrahedrons'");
    expect_failure(HDR "Tetrahedra 0\n", "bad.mesh:", "expected a Vertices section, found end of file");
    expect_failure(VERTS "Vertices 0\n", "bad.mesh:9:", "expected one Vertices section, found a second");
}

/* A prefix of `text` that is a whole Medit file: one cut where a section after Vertices ends (before or
 * after that line's newline), or in the last newline. End is optional (the reader stops at the end of the
 * file, as libMeshb does) and so are the sections after Vertices. Every number in the text is one digit,
 * so no cut shortens a number into another valid one. */
static int whole_medit_prefix(const char *text, size_t n)
{
    static const char *const next_sections[] = {"\nTriangles", "\nTetrahedra", "\nEnd"};
    for (size_t k = 0; k < sizeof next_sections / sizeof *next_sections; k++) {
        size_t at = (size_t)(strstr(text, next_sections[k]) - text);
        if (n == at || n == at + 1)
            return 1;
    }
    return n == strlen(text) - 1;
}

/* Cut a valid file at every byte: every prefix is refused with a placed message, except the whole files
 * above, which import with the cells they hold. */
TPK_TEST(every_truncation)
{
    static const char text[] = VERTS "Triangles 1\n1 2 3 0\nTetrahedra\n1\n1 2 3 4 5\nEnd\n";
    int whole_count = 0;
    for (size_t n = 0; n < sizeof text - 1; n++) {
        char *copy = malloc(n ? n : 1); /* exact size: an overread is caught by ASan */
        memcpy(copy, text, n);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        int rc = tpk_import_medit_memory("cut.mesh", copy, n, &m, &d);
        free(copy);
        int64_t cells = rc == 0 ? m.cell_count : -1;
        if (rc == 0)
            tpk_mesh_free(&m);
        int whole = whole_medit_prefix(text, n);
        whole_count += whole;
        CHECK_MSG(whole ? rc == 0 : rc != 0 && strstr(d.message, "cut.mesh:"), "prefix %zu (%s): '%s'", n,
                  whole ? "a whole file" : "cut", d.message);
        int64_t tets = n >= (size_t)(strstr(text, "\nEnd") - text); /* the triangle is dropped */
        CHECK_MSG(!whole || cells == tets, "prefix %zu: %lld cells", n, (long long)cells);
    }
    CHECK_EQ_INT(whole_count, 7);
}
