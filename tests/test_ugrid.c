/* UGRID importer: refine's acceptance meshes (ASCII), the same mesh re-encoded big- and little-endian
 * binary here, refused element kinds, bad input with byte or line positions, every truncation. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "meshgen.h"
#include "import/importers.h"
#include "convert/pipeline.h"

static void quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
}

TPK_TEST(real_ascii_files)
{
    static const struct {
        const char *path;
        int64_t points, tets;
    } files[] = {{"nasa_refine/cube_polar1.ugrid", 111, 314}, {"nasa_refine/cube_cylinder_ega.ugrid", -1, 1937}};
    for (int f = 0; f < 2; f++) {
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_any(tpk_data_path(files[f].path), NULL, &m, &d) == 0, "%s", d.message);
        int ok = m.cell_count == files[f].tets && (files[f].points < 0 || m.point_count == files[f].points) &&
                 !strcmp(m.format, "ugrid");
        int64_t negative = 0;
        for (int64_t c = 0; ok && c < m.cell_count; c++) {
            const int32_t *t = m.cell_conn + 4 * c;
            negative += tpk_orient3d_exact(m.points + 3 * t[0], m.points + 3 * t[1], m.points + 3 * t[2],
                                           m.points + 3 * t[3]) < 0;
        }
        tpk_mesh_free(&m);
        CHECK_MSG(ok && negative == 0, "%s: counts differ or %lld tets negative", files[f].path, (long long)negative);
    }
    /* cube_polar1: first tet (1-based in the file) is 81 1 57 17, the second node at (0, 0.25, 0). */
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK(tpk_import_ugrid(tpk_data_path("nasa_refine/cube_polar1.ugrid"), &m, &d) == 0);
    int ok = m.cell_conn[0] == 80 && m.cell_conn[1] == 0 && m.cell_conn[2] == 56 && m.cell_conn[3] == 16 &&
             m.points[3] == 0 && m.points[4] == 0.25 && m.points[5] == 0;
    tpk_mesh_free(&m);
    CHECK(ok);
}

static void put32(FILE *f, uint32_t v, int big)
{
    unsigned char b[4];
    for (int i = 0; i < 4; i++)
        b[big ? 3 - i : i] = (unsigned char)(v >> (8 * i));
    fwrite(b, 1, 4, f);
}

static void put64(FILE *f, double x, int big)
{
    uint64_t v;
    memcpy(&v, &x, sizeof v);
    unsigned char b[8];
    for (int i = 0; i < 8; i++)
        b[big ? 7 - i : i] = (unsigned char)(v >> (8 * i));
    fwrite(b, 1, 8, f);
}

/* Re-encode the ASCII file as binary: every number of the ASCII file in order (ints as 4 bytes, the
 * coordinates as 8). */
static int write_binary(const char *ascii, const char *out, int big)
{
    FILE *in = fopen(ascii, "r"), *f = fopen(out, "wb");
    if (!in || !f)
        return -1;
    long long c[7];
    for (int i = 0; i < 7; i++)
        if (fscanf(in, "%lld", &c[i]) != 1)
            return -1;
    for (int i = 0; i < 7; i++)
        put32(f, (uint32_t)c[i], big);
    for (long long i = 0; i < 3 * c[0]; i++) {
        double x;
        if (fscanf(in, "%lf", &x) != 1)
            return -1;
        put64(f, x, big);
    }
    long long v;
    while (fscanf(in, "%lld", &v) == 1)
        put32(f, (uint32_t)v, big);
    fclose(in);
    fclose(f);
    return 0;
}

TPK_TEST(binary_matches_ascii)
{
    const char *ascii = tpk_data_path("nasa_refine/cube_cylinder_ega.ugrid");
    tpk_mesh a;
    tpk_diag d;
    quiet(&d);
    CHECK(tpk_import_ugrid(ascii, &a, &d) == 0);
    const char *names[2] = {"cyl.b8.ugrid", "cyl.lb8.ugrid"};
    for (int big = 1; big >= 0; big--) {
        const char *path = tpk_temp_path(names[!big]);
        CHECK(write_binary(ascii, path, big) == 0);
        tpk_mesh b;
        CHECK_MSG(tpk_import_any(path, NULL, &b, &d) == 0, "%s", d.message);
        int same = b.point_count == a.point_count && b.cell_count == a.cell_count &&
                   !memcmp(b.points, a.points, sizeof *a.points * 3 * (size_t)a.point_count) &&
                   !memcmp(b.cell_conn, a.cell_conn, sizeof *a.cell_conn * 4 * (size_t)a.cell_count) &&
                   !strcmp(b.format, big ? "ugrid-b8" : "ugrid-lb8");
        tpk_mesh_free(&b);
        CHECK_MSG(same, "%s differs from the ASCII file", names[!big]);
    }
    tpk_mesh_free(&a);
}

static void expect_failure(const char *name, const char *text, const char *what)
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    int rc = tpk_import_ugrid_memory(name, text, strlen(text), &m, &d);
    CHECK_MSG(rc != 0 && strstr(d.message, name) && strstr(d.message, what), "'%s'", d.message);
    CHECK(m.points == NULL && m.cell_count == 0);
}

TPK_TEST(bad_input)
{
    expect_failure("a.ugrid", "", "expected the number of nodes, found end of file");
    expect_failure("a.ugrid", "4 0 0 1 0 0", "expected the number of hexahedra, found end of file");
    expect_failure("a.ugrid", "4 0 0 -1 0 0 0\n", "expected 0 to 2^31-1 tetrahedra, found -1");
    expect_failure("a.ugrid", "99999999 0 0 1 0 0 0\n0 0 0\n", "wrong counts or truncated file");
    expect_failure("a.ugrid", "5 0 0 0 1 0 0\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n1 2 3 4 6\n",
                   "pyramid 1: node id 6, expected 1 to 5");
    expect_failure("a.ugrid", "4 0 0 0 0 0 0\n0 0 0 1 0 0 0 1 0 0 0 1\n", "no volume cells");
    expect_failure("a.ugrid", "4 0 0 1 0 0 0\n0 0 0 1 0 0 0 1 0 0 0 1\n1 2 3 5\n",
                   "tetrahedron 1: node id 5, expected 1 to 4");
    expect_failure("a.ugrid", "4 0 0 1 0 0 0\n0 0 0 1 0 x 0 1 0 0 0 1\n1 2 3 4\n", "a.ugrid:2:");
    expect_failure("b.b8.ugrid", "abcd", "b.b8.ugrid: byte");
}

/* Every prefix is refused naming the file, except the one that only lacks the last newline: a whole file
 * (every number in the text is one digit, so no cut shortens a number into another valid one). */
TPK_TEST(every_truncation)
{
    static const char text[] = "4 1 0 1 0 0 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 2 3\n7\n1 2 3 4\n";
    for (size_t n = 0; n < sizeof text - 1; n++) {
        char *copy = malloc(n ? n : 1); /* exact size: an overread is caught by ASan */
        memcpy(copy, text, n);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        d.warn = NULL;
        int rc = tpk_import_ugrid_memory("cut.ugrid", copy, n, &m, &d);
        free(copy);
        int64_t cells = rc == 0 ? m.cell_count : -1;
        if (rc == 0)
            tpk_mesh_free(&m);
        if (n == sizeof text - 2)
            CHECK_MSG(rc == 0 && cells == 1, "the file without its last newline: '%s'", d.message);
        else
            CHECK_MSG(rc != 0 && strstr(d.message, "cut.ugrid"), "prefix %zu: '%s'", n, d.message);
    }
}

/* Writes `m` (VTK node order; tets, pyramids, wedges, hexahedra) as ASCII UGRID in refine's node order
 * (UGRID node map[k] = VTK node k, the inverse of the importer's map). */
static void write_ugrid(const char *path, const tpk_mesh *m)
{
    static const struct {
        int vtk_type, nodes, map[8];
    } kinds[4] = {{10, 4, {0, 1, 2, 3}}, {14, 5, {1, 0, 3, 4, 2}}, {13, 6, {1, 0, 2, 4, 3, 5}},
                  {12, 8, {0, 1, 2, 3, 4, 5, 6, 7}}};
    int64_t counts[4] = {0, 0, 0, 0};
    for (int64_t c = 0; c < m->cell_count; c++)
        for (int k = 0; k < 4; k++)
            counts[k] += m->cell_types[c] == kinds[k].vtk_type;
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    fprintf(f, "%lld 0 0 %lld %lld %lld %lld\n", (long long)m->point_count, (long long)counts[0],
            (long long)counts[1], (long long)counts[2], (long long)counts[3]);
    for (int64_t p = 0; p < m->point_count; p++)
        fprintf(f, "%.17g %.17g %.17g\n", m->points[3 * p], m->points[3 * p + 1], m->points[3 * p + 2]);
    for (int k = 0; k < 4; k++)
        for (int64_t c = 0; c < m->cell_count; c++) {
            if (m->cell_types[c] != kinds[k].vtk_type)
                continue;
            int32_t ugrid[8];
            for (int j = 0; j < kinds[k].nodes; j++)
                ugrid[kinds[k].map[j]] = m->cell_conn[m->cell_offsets[c] + j];
            for (int j = 0; j < kinds[k].nodes; j++)
                fprintf(f, "%d%c", ugrid[j] + 1, j + 1 < kinds[k].nodes ? ' ' : '\n');
        }
    fclose(f);
}

/* Reads `path` back: the cells of `src` grouped by type in file order (tets, pyramids, prisms,
 * hexahedra), and a split in which no cell is mirrored or needs a centre point. */
static void check_ugrid_read_back(const char *path, const tpk_mesh *src, int64_t pyramids, int64_t wedges,
                                  int64_t hexes)
{
    static const int order[4] = {10, 14, 13, 12};
    tpk_mesh back;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_any(path, NULL, &back, &d) == 0, "%s", d.message);
    CHECK(back.point_count == src->point_count && back.cell_count == src->cell_count);
    int64_t c = 0;
    for (int k = 0; k < 4; k++)
        for (int64_t s = 0; s < src->cell_count; s++) {
            if (src->cell_types[s] != order[k])
                continue;
            int64_t n = src->cell_offsets[s + 1] - src->cell_offsets[s];
            CHECK(back.cell_types[c] == order[k] && back.cell_offsets[c + 1] - back.cell_offsets[c] == n);
            CHECK(!memcmp(back.cell_conn + back.cell_offsets[c], src->cell_conn + src->cell_offsets[s],
                          sizeof *src->cell_conn * (size_t)n));
            c++;
        }
    tpk_tetmesh tets;
    CHECK_MSG(tpk_tetrahedralize(&back, NULL, 0, TPK_TETRA_REFUSE_MIRRORED, &tets, &d) == 0, "%s", d.message);
    CHECK(tets.mirrored_cells == 0 && tets.steiner_cells == 0);
    CHECK(tets.cells_into[2] == pyramids && tets.cells_into[3] == wedges &&
          tets.cells_into[5] + tets.cells_into[6] == hexes);
    tpk_tetmesh_free(&tets);
    tpk_mesh_free(&back);
}

/* Pyramids, prisms and hexahedra: gmsh tutorial t3's 12,308 prisms and 21,720 tets (real data; prisms in
 * VTK order, checked in test_gmsh), sfepy's 1,000 hexahedra, and six pyramids filling a cube, written as
 * UGRID in refine's node order, read back in VTK order with no cell mirrored. */
TPK_TEST(pyramids_prisms_hexahedra)
{
    static const char *sources[2] = {"gmsh/t3_hex_prism_ascii41.msh", "sfepy/cube_medium_hexa.mesh"};
    for (int i = 0; i < 2; i++) {
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_any(tpk_data_path(sources[i]), NULL, &m, &d) == 0, "%s", d.message);
        const char *path = tpk_temp_path(i ? "hexa.ugrid" : "t3.ugrid");
        write_ugrid(path, &m);
        check_ugrid_read_back(path, &m, 0, i ? 0 : 12308, i ? 1000 : 0);
        tpk_mesh_free(&m);
    }
    tpk_mesh cube = tpk_gen_cube_pyramids();
    const char *path = tpk_temp_path("pyramids.ugrid");
    write_ugrid(path, &cube);
    check_ugrid_read_back(path, &cube, 6, 0, 0);
}
