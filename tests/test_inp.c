/* Abaqus / CalculiX .inp importer on small files that hold each feature (the real files written by gmsh
 * and meshio are converted in tests/cli/inp.sh): arbitrary ids, continuation lines, element sets,
 * higher-order reduction, dropped shells, includes (relative, cyclic, too deep), and bad input that
 * must fail with file:line, what was expected and what was found. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "import/importers.h"

static void quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
}

static void silent(void *user, const char *text)
{
    (void)user;
    (void)text;
}

static const float *field(const tpk_mesh *m, const char *name)
{
    for (int i = 0; i < m->field_count; i++)
        if (!strcmp(m->fields[i].name, name))
            return m->fields[i].values;
    return NULL;
}

/* Nodes 101..108: the unit cube, written out of order. */
#define CUBE_NODES                                                                                            \
    "*Node, nset=all\n"                                                                                       \
    "108, 0, 1, 1\n101, 0., 0., 0.\n102, 1, 0, 0\n103, 1, 1, 0\n104, 0, 1, 0\n"                              \
    "105, 0, 0, 1\n106, 1.0e0, 0, 1\n107, 1, 1, 1\n"

TPK_TEST(features)
{
    static const char text[] =
        "*HEADING\n a cube, three ways\n"
        "** comment lines start with two stars\n" CUBE_NODES
        "*ELEMENT, TYPE=C3D8R, ELSET=Hexes\n"
        "7, 101, 102, 103, 104, 105, 106, 107, 108\n"
        "*element,type=c3d20\n" /* keywords in any case; node lists run over lines */
        "9, 101, 102, 103, 104, 105, 106, 107, 108, 101, 102, 103, 104, 105, 106, 107,\n"
        "   108, 101, 102, 103, 104\n"
        "*ELEMENT, TYPE=DC3D10, ELSET=Tets\n"
        "3, 101, 102, 104, 105, 101, 101, 101, 101, 101, 101\n"
        "*ELEMENT, TYPE=C3D6\n"
        "4, 101, 102, 104,\n105, 106, 108\n"
        "*ELEMENT, TYPE=S4R, ELSET=Skin\n" /* shells are dropped */
        "5, 101, 102, 103, 104\n"
        "*ELSET, ELSET=Odd, GENERATE\n 3, 9, 2\n"
        "*ELSET, ELSET=Skin\n5\n"
        "*MATERIAL, NAME=steel\n*ELASTIC\n 210e9, 0.3\n"
        "*STEP\n*STATIC\n*END STEP\n";
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    d.warn = silent;
    CHECK_MSG(tpk_import_inp_memory("f.inp", text, sizeof text - 1, &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, 8);
    CHECK_EQ_INT(m.cell_count, 4);
    CHECK(!strcmp(m.format, "abaqus-inp"));
    CHECK(m.cell_types[0] == 12 && m.cell_types[1] == 25 && m.cell_types[2] == 24 && m.cell_types[3] == 13);
    CHECK(m.cell_offsets[1] == 8 && m.cell_offsets[2] == 28 && m.cell_offsets[3] == 38 && m.cell_offsets[4] == 44);
    /* ids to file order: 101 is the second node written, 108 the first */
    CHECK(m.cell_conn[0] == 1 && m.cell_conn[7] == 0 && m.cell_conn[15] == 0);
    CHECK(m.points[3 * 0 + 1] == 1.0 && m.points[3 * 6 + 0] == 1.0);
    /* element 3 (a C3D10, whole: its corners, then its mid-edge nodes), and the wedge across its
     * continuation line */
    CHECK(m.cell_conn[28] == 1 && m.cell_conn[30] == 4 && m.cell_conn[32] == 1 && m.cell_conn[43] == 0);
    const float *set = field(&m, "elset");
    /* sets in order of appearance: Hexes 1, Tets 2, Skin 3, Odd 4; the later *ELSET wins */
    CHECK(set && set[0] == 4.0f && set[1] == 4.0f && set[2] == 4.0f && set[3] == 0.0f);
    CHECK_EQ_INT(d.warning_count, 2); /* the dropped shell, and *ELSET Skin naming it */
    tpk_mesh_free(&m);
}

/* A GENERATE line of a few bytes may span any number of ids: kept as a range, not expanded. */
TPK_TEST(generate_spans_any_range)
{
    /* 7 - (-8999999999999999998) is a multiple of 7, 7 - (-8999999999999999997) is not: element 7 is in All,
     * not in Miss (which would win, coming later) */
    static const char text[] = CUBE_NODES "*ELEMENT, TYPE=C3D8\n7, 101, 102, 103, 104, 105, 106, 107, 108\n"
                                          "*ELSET, ELSET=All, GENERATE\n-8999999999999999998, 9000000000000000000, 7\n"
                                          "*ELSET, ELSET=Miss, GENERATE\n-8999999999999999997, 9000000000000000000, 7\n";
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_inp_memory("g.inp", text, sizeof text - 1, &m, &d) == 0, "%s", d.message);
    const float *set = field(&m, "elset");
    CHECK(m.cell_count == 1 && set && set[0] == 1.0f);
    tpk_mesh_free(&m);
}

static char dir[64];

static void write_file(const char *name, const char *text)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

static int read_path(const char *name, tpk_mesh *m, tpk_diag *d)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    quiet(d);
    return tpk_import_inp(path, m, d);
}

TPK_TEST(includes)
{
    snprintf(dir, sizeof dir, "/tmp/tpk_inp_XXXXXX");
    CHECK(mkdtemp(dir) != NULL);
    char sub[128];
    snprintf(sub, sizeof sub, "%s/parts", dir);
    mkdir(sub, 0700);
    /* parts/mesh.inp includes its neighbour by a path relative to itself, not to the main file */
    write_file("parts/nodes.inp", CUBE_NODES);
    write_file("parts/mesh.inp", "*INCLUDE, INPUT=nodes.inp\n*ELEMENT, TYPE=C3D8\n1, 101, 102, 103, 104, 105, 106, "
                                 "107, 108\n");
    write_file("main.inp", "*Include, input=\"parts/mesh.inp\"\n");
    write_file("self.inp", "*NODE\n1, 0, 0, 0\n*INCLUDE, INPUT=self.inp\n");
    write_file("missing.inp", "*NODE\n1, 0, 0, 0\n\n*INCLUDE, INPUT=nothing.inp\n");
    tpk_mesh m;
    tpk_diag d;
    CHECK_MSG(read_path("main.inp", &m, &d) == 0, "%s", d.message);
    CHECK(m.point_count == 8 && m.cell_count == 1 && m.cell_conn[0] == 1);
    tpk_mesh_free(&m);
    CHECK(read_path("self.inp", &m, &d) != 0 && strstr(d.message, "self.inp:3: *INCLUDE:") &&
          strstr(d.message, "includes itself"));
    CHECK_MSG(read_path("missing.inp", &m, &d) != 0 && strstr(d.message, "missing.inp:4: *INCLUDE:") &&
                  strstr(d.message, "nothing.inp: cannot open"),
              "%s", d.message);
    CHECK(m.cell_count == 0 && m.points == NULL);
    /* a chain a0 -> a1 -> ... -> a11 without a cycle is stopped by its depth */
    for (int i = 0; i < 12; i++) {
        char name[32], text[64];
        snprintf(name, sizeof name, "a%d.inp", i);
        snprintf(text, sizeof text, "*INCLUDE, INPUT=a%d.inp\n", i + 1);
        write_file(name, text);
    }
    CHECK_MSG(read_path("a0.inp", &m, &d) != 0 && strstr(d.message, "more than 10 nested includes"), "%s", d.message);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    CHECK(system(cmd) == 0);
}

static void expect_failure(const char *text, const char *where, const char *what)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    d.warn = silent;
    int rc = tpk_import_inp_memory("bad.inp", text, strlen(text), &m, &d);
    CHECK_MSG(rc != 0 && strstr(d.message, where) && strstr(d.message, what), "for input %.40s...: '%s'", text,
              d.message);
    CHECK(m.cell_count == 0 && m.points == NULL && m.fields == NULL);
}

#define TET_NODES "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n"

TPK_TEST(bad_input)
{
    expect_failure("", "bad.inp:", "expected *NODE and *ELEMENT keywords");
    expect_failure("# vtk DataFile Version 2.0\n", "bad.inp:", "expected *NODE and *ELEMENT keywords");
    expect_failure("*NODE\n1, 0, x, 0\n", "bad.inp:2:", "*NODE 1: expected a coordinate, found 'x'");
    expect_failure("*NODE\n1, 0\n", "bad.inp:2:", "expected an id and 2 or 3 coordinates, found 2 values");
    expect_failure("*NODE\nn1, 0, 0, 0\n", "bad.inp:2:", "expected a node id (an integer), found 'n1'");
    expect_failure(TET_NODES "*ELEMENT\n", "bad.inp:6:", "expected TYPE=<element type>, found none");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D5\n", "bad.inp:6:", "type C3D5 is a solid this reader does not read");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3\n*END\n", "bad.inp:7:",
                   "element 1 (C3D4): expected 4 node ids, found 3 before the next keyword");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n\n1, 1, 2,\n", "bad.inp:8:",
                   "expected 4 node ids, found 2 before the end of the file");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 9\n", "bad.inp:",
                   "element 1 uses node 9, which no *NODE line defines");
    /* one element per data line: values after a complete one (gmsh writes its 18-node prisms as C3D6) */
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4, 2, 3\n", "bad.inp:7:",
                   "element 1 (C3D4): expected 4 node ids, found 6 or more (each element starts a data line");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n1, 1, 2,\n3, 4, 2\n", "bad.inp:8:",
                   "element 1 (C3D4): expected 4 node ids, found 5 or more");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, four\n", "bad.inp:7:",
                   "expected a node id (an integer), found 'four'");
    expect_failure("*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n", "bad.inp:", "element 1 uses node 1, which no *NODE line defines");
    expect_failure("*NODE, INPUT=nodes.txt\n", "bad.inp:1:", "*NODE, INPUT=: data read from another file is not supported");
    expect_failure("*PART, NAME=a\n" TET_NODES "*END PART\n*PART, NAME=b\n" TET_NODES, "bad.inp:",
                   "node id 1 is defined twice (the file has several *PART blocks");
    expect_failure(TET_NODES "4, 1, 1, 1\n", "bad.inp:", "node id 4 is defined twice");
    expect_failure(TET_NODES "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n1, 1, 2, 3, 4\n", "bad.inp:", "element id 1 is defined twice");
    expect_failure(TET_NODES "*ELSET\n1\n", "bad.inp:6:", "*ELSET: expected ELSET=<name>, found none");
    expect_failure(TET_NODES "*ELSET, ELSET=x, GENERATE\n5, 1\n", "bad.inp:7:", "expected first <= last");
    expect_failure(TET_NODES "*ELSET, ELSET=x, GENERATE\n1, 5, 0\n", "bad.inp:7:", "a step of 1 or more");
    expect_failure(TET_NODES "*INCLUDE\n", "bad.inp:6:", "*INCLUDE: expected INPUT=<file>, found none");
    expect_failure(TET_NODES "*\n", "bad.inp:6:", "expected a keyword after '*'");
}

/* Cut a valid file at every byte: every prefix either parses or fails with a placed message, and reads
 * nothing past its end (the copy has the exact size: ASan catches an overread). */
TPK_TEST(every_truncation)
{
    static const char text[] = TET_NODES "*ELEMENT, TYPE=C3D10, ELSET=e\n1, 1, 2, 3, 4,\n1, 1, 1, 1, 1, 1\n"
                                         "*ELSET, ELSET=f\n1,\n";
    for (size_t n = 0; n < sizeof text - 1; n++) {
        char *copy = malloc(n ? n : 1);
        memcpy(copy, text, n);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        d.warn = silent;
        int rc = tpk_import_inp_memory("cut.inp", copy, n, &m, &d);
        free(copy);
        if (rc == 0)
            tpk_mesh_free(&m);
        CHECK_MSG(rc == 0 || strstr(d.message, "cut.inp"), "prefix %zu: '%s'", n, d.message);
    }
}

