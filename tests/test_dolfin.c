/* Legacy DOLFIN XML importer: files DOLFIN 2019 wrote (tests/cli/dolfin/, how in its README), detection
 * next to VTU (both may start "<?xml"), and bad input that must fail with the file, line, what was
 * expected and what was found. meshio's files are converted in tests/cli/dolfin.sh. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"
#include "base/predicates.h"
#include "import/importers.h"

static void silent(void *user, const char *text)
{
    (void)user;
    (void)text;
}

static void quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
    d->warn = silent;
}

static const char *fixture(const char *name)
{
    static char path[512];
    snprintf(path, sizeof path, "%s/tests/cli/dolfin/%s", TPK_SOURCE_DIR, name);
    return path;
}

TPK_TEST(dolfin_written_tets_with_domains)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_any(fixture("unit_cube_tets.xml"), NULL, &m, &d) == 0, "%s", d.message);
    CHECK(m.point_count == 27 && m.cell_count == 48 && !strcmp(m.format, "dolfin-xml"));
    CHECK(m.field_count == 1 && !strcmp(m.fields[0].name, "m"));
    /* the value collection marks cells left of x = 0.5 with 1, the others 2 */
    int64_t wrong = 0;
    for (int64_t c = 0; c < m.cell_count; c++) {
        double x = 0;
        for (int k = 0; k < 4; k++)
            x += m.points[3 * m.cell_conn[4 * c + k]] / 4;
        wrong += m.fields[0].values[c] != (x < 0.5 ? 1.0f : 2.0f);
    }
    CHECK_EQ_INT(wrong, 0);
    /* DOLFIN's first tet, as written: v0=0 v1=1 v2=4 v3=13 */
    CHECK(m.cell_conn[0] == 0 && m.cell_conn[1] == 1 && m.cell_conn[2] == 4 && m.cell_conn[3] == 13);
    tpk_mesh_free(&m);
}

/* Every corner of a VTK-ordered hexahedron is right-handed in its three edges: DOLFIN's lexicographic
 * order read as it is would give twisted cells. */
TPK_TEST(dolfin_hexahedra_in_vtk_order)
{
    static const int around[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                                     {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_dolfin(fixture("unit_cube_hexes.xml"), &m, &d) == 0, "%s", d.message);
    CHECK(m.cell_count == 8 && m.cell_types[0] == 12 && m.cell_offsets[8] == 64);
    int64_t bad = 0;
    for (int64_t c = 0; c < m.cell_count; c++) {
        const int32_t *h = m.cell_conn + 8 * c;
        for (int k = 0; k < 8; k++)
            bad += tpk_orient3d_exact(m.points + 3 * h[k], m.points + 3 * h[around[k][0]],
                                      m.points + 3 * h[around[k][1]], m.points + 3 * h[around[k][2]]) <= 0;
    }
    CHECK_EQ_INT(bad, 0);
    tpk_mesh_free(&m);
}

/* The DOLFIN row comes before VTU and both may start "<?xml": its sniff keeps VTU files VTU, by
 * extension or by content (even named .xml), and DOLFIN files DOLFIN whatever their name. */
TPK_TEST(detection_beside_vtu)
{
    const tpk_import_format *dolfin = tpk_import_format_named("dolfin", NULL), *vtu = tpk_import_format_named("vtu", NULL);
    CHECK(tpk_import_format_detect(fixture("unit_cube_tets.xml")) == dolfin);
    CHECK(tpk_import_format_detect(tpk_data_path("hard/huge_offset_hex.vtu")) == vtu);
    char dir[] = "/tmp/tpk_dolfin_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[128];
    static const char *const names[] = {"vtk_xml.xml", "dolfin.dat", "other.xml"};
    static const char *const texts[] = {"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\">",
                                        "<?xml version=\"1.0\"?>\n<!-- mesh -->\n<dolfin>", "<?xml version=\"1.0\"?>\n<svg>"};
    /* other XML goes to VTU by its "<?xml" magic, as before DOLFIN came; its reader then says what it found */
    const tpk_import_format *want[] = {vtu, dolfin, vtu};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        FILE *f = fopen(path, "w");
        if (f) {
            fputs(texts[i], f);
            fclose(f);
        }
        CHECK_MSG(tpk_import_format_detect(path) == want[i], "%s", names[i]);
        remove(path);
    }
    rmdir(dir);
}

static void expect_failure(const char *text, const char *where, const char *what)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    int rc = tpk_import_dolfin_memory("bad.xml", text, strlen(text), &m, &d);
    CHECK_MSG(rc != 0 && strstr(d.message, where) && strstr(d.message, what), "for input %.50s...: '%s'", text,
              d.message);
    CHECK(m.cell_count == 0 && m.points == NULL && m.fields == NULL);
}

#define MESH "<dolfin>\n<mesh celltype=\"tetrahedron\" dim=\"3\">\n"
#define VERTS                                                                                                 \
    MESH "<vertices size=\"4\">\n<vertex index=\"0\" x=\"0\" y=\"0\" z=\"0\"/>\n"                             \
         "<vertex index=\"1\" x=\"1\" y=\"0\" z=\"0\"/>\n<vertex index=\"2\" x=\"0\" y=\"1\" z=\"0\"/>\n"     \
         "<vertex index=\"3\" x=\"0\" y=\"0\" z=\"1\"/>\n</vertices>\n"

TPK_TEST(bad_input)
{
    expect_failure("", "bad.xml: line 1, column 0:", "expected well-formed XML, found an error: no element found");
    expect_failure("<VTKFile/>", "bad.xml: line 1:", "expected a <dolfin> root element (a DOLFIN XML mesh), found <VTKFile>");
    expect_failure("<!DOCTYPE d [<!ENTITY a \"aaaa\">]><dolfin/>", "bad.xml: line 1:", "found a DOCTYPE declaration");
    expect_failure("<dolfin><mesh celltype=\"triangle\" dim=\"2\"/></dolfin>", "line 1:",
                   "expected celltype \"tetrahedron\" or \"hexahedron\" (a volume mesh), found 'triangle'");
    expect_failure("<dolfin><mesh celltype=\"tetrahedron\"/></dolfin>", "line 1:", "expected dim=\"3\", found none");
    expect_failure(MESH "<vertices size=\"99999\">", "bad.xml: line 3:", "that many items cannot fit in the");
    expect_failure(MESH "<vertices size=\"-1\">", "bad.xml: line 3:", "expected size to be an integer from 0 to");
    expect_failure(MESH "<vertices size=\"1\">\n<vertex index=\"1\" x=\"0\" y=\"0\" z=\"0\"/>", "line 4:",
                   "<vertex>: expected index to be an integer from 0 to 0, found '1'");
    expect_failure(MESH "<vertices size=\"1\">\n<vertex index=\"0\" x=\"0\" y=\"zero\" z=\"0\"/>", "line 4:",
                   "<vertex index=\"0\">: expected a number y, found 'zero'");
    expect_failure(VERTS "<cells size=\"1\">\n<tetrahedron index=\"0\" v0=\"0\" v1=\"1\" v2=\"2\" v3=\"4\"/>",
                   "bad.xml: line 10:", "<tetrahedron>: expected v3 to be an integer from 0 to 3, found '4'");
    expect_failure(VERTS "<cells size=\"1\">\n<hexahedron index=\"0\"/>", "line 10:",
                   "<cells>: expected <tetrahedron> (the mesh's celltype), found <hexahedron>");
    expect_failure(VERTS "<cells size=\"2\">\n<tetrahedron index=\"0\" v0=\"0\" v1=\"1\" v2=\"2\" v3=\"3\"/>\n"
                         "</cells></mesh></dolfin>",
                   "bad.xml:", "expected 4 vertices and 2 cells (the size attributes), found 4 and 1");
    expect_failure(VERTS "<cells size=\"1\">\n<tetrahedron index=\"0\" v0=\"0\" v1=\"1\" v2=\"2\" v3=\"3\"/>\n"
                         "</cells>\n<domains><mesh_value_collection dim=\"3\">\n<value cell_index=\"0\" value=\"x\"/>",
                   "line 13:", "<value cell_index=\"0\">: expected a number value, found 'x'");
    expect_failure(VERTS "<cells size=\"1\">\n<tetrahedron index=\"0\" v0=\"0\" v1=\"1\" v2=\"2\" v3=\"3\"/>\n</cells>",
                   "bad.xml: line 11, column", "(truncated file?)");
}

/* Cut a real file at every byte: each prefix fails with a placed message; the copy has the exact size,
 * so ASan catches an overread. */
TPK_TEST(every_truncation)
{
    static const char text[] = VERTS "<cells size=\"1\">\n<tetrahedron index=\"0\" v0=\"0\" v1=\"1\" v2=\"2\" v3=\"3\"/>\n"
                                     "</cells>\n</mesh>\n</dolfin>\n";
    for (size_t n = 0; n + 1 < sizeof text - 1; n++) {
        char *copy = malloc(n ? n : 1);
        memcpy(copy, text, n);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        int rc = tpk_import_dolfin_memory("cut.xml", copy, n, &m, &d);
        free(copy);
        if (rc == 0)
            tpk_mesh_free(&m);
        CHECK_MSG(rc != 0 && strstr(d.message, "cut.xml: line"), "prefix %zu: '%s'", n, d.message);
    }
}
