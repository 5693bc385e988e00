/* XDMF from memory (the fuzz targets' form): inline XML parses to the same mesh and fields as from a
 * file; HDF data is refused with a message naming the DataItem; a wrong-length Attribute fails, or is
 * recorded and dropped when read leniently (tetpack check); a failure leaves the mesh empty. */
#include <string.h>

#include "harness.h"
#include "import/importers.h"
#include "tetpack_format.h"

/* Two tets sharing a face, a point field and a 3-component cell field. */
static const char two_tets[] =
    "<Xdmf Version=\"3.0\"><Domain><Grid Name=\"g\">\n"
    "<Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"2\">\n"
    "  <DataItem DataType=\"Int\" Dimensions=\"2 4\">0 1 2 3  0 2 1 4</DataItem></Topology>\n"
    "<Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"5 3\">0 0 0 1 0 0 0 1 0 0 0 1 0 0 -1</DataItem></Geometry>\n"
    "<Attribute Name=\"p\" Center=\"Node\"><DataItem Dimensions=\"5\">0 1 2 3 4</DataItem></Attribute>\n"
    "<Attribute Name=\"v\" AttributeType=\"Vector\" Center=\"Cell\"><DataItem Dimensions=\"2 3\">1 2 3 4 5 6</DataItem>"
    "</Attribute>\n"
    "</Grid></Domain></Xdmf>\n";

static int empty(const tpk_mesh *m)
{
    return !m->points && !m->cell_conn && !m->fields && m->cell_count == 0;
}

TPK_TEST(memory_inline_xml)
{
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_xdmf_memory("two.xdmf", two_tets, sizeof two_tets - 1, &m, &d) == 0);
    CHECK_EQ_INT(m.point_count, 5);
    CHECK_EQ_INT(m.cell_count, 2);
    CHECK_EQ_INT(m.cell_conn[5], 2); /* the second tet as written: 0 2 1 4 */
    CHECK_EQ_INT(m.field_count, 2);
    CHECK(!strcmp(m.fields[1].name, "v") && m.fields[1].association == TPK_ASSOC_TET);
    CHECK_EQ_INT(m.fields[1].components, 3);
    CHECK(m.fields[1].values[4] == 5.0f);
    CHECK_EQ_INT(m.step_count, 1);
    tpk_mesh_free(&m);
}

TPK_TEST(memory_refuses_hdf)
{
    static const char hdf[] = "<Xdmf><Domain><Grid><Topology TopologyType=\"Tetrahedron\">"
                              "<DataItem Dimensions=\"1 4\">0 1 2 3</DataItem></Topology><Geometry>\n"
                              "<DataItem Dimensions=\"4 3\" Format=\"HDF\">mesh.h5:/geometry</DataItem>"
                              "</Geometry></Grid></Domain></Xdmf>";
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_xdmf_memory("h.xdmf", hdf, sizeof hdf - 1, &m, &d) != 0);
    CHECK(empty(&m));
    CHECK(strstr(d.message, "h.xdmf: line 2: <DataItem>: Format HDF (\"mesh.h5:/geometry\"): HDF data is not "
                            "read from memory") != NULL);
}

TPK_TEST(wrong_length_attribute)
{
    char text[sizeof two_tets];
    memcpy(text, two_tets, sizeof text);
    char *five = strstr(text, "0 1 2 3 4</DataItem>");
    CHECK(five != NULL);
    memcpy(five, "0 1 2 3  ", 9); /* 4 values where 5 points need 5 */
    char *dims = strstr(text, "Dimensions=\"5\"");
    dims[12] = '4';
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_xdmf_memory("short.xdmf", text, strlen(text), &m, &d) != 0);
    CHECK(empty(&m));
    CHECK(strstr(d.message, "Attribute 'p' (Scalar, Center Node): expected 5 values (one value per point), "
                            "found 4") != NULL);
    memset(&d, 0, sizeof d);
    d.lenient_fields = 1;
    CHECK(tpk_import_xdmf_memory("short.xdmf", text, strlen(text), &m, &d) == 0);
    CHECK_EQ_INT(m.field_count, 1); /* p dropped, v kept */
    CHECK_EQ_INT(d.field_problem_count, 1);
    CHECK(!strcmp(d.field_problems[0].name, "p"));
    tpk_mesh_free(&m);
}
