/* UGRID importer: refine's acceptance meshes (ASCII), the same mesh re-encoded big- and little-endian
 * binary here, refused element kinds, bad input with byte or line positions, every truncation. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "importers.h"
#include "pipeline.h"

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
    expect_failure("a.ugrid", "5 0 0 0 1 0 0\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n1 2 3 4 5\n",
                   "1 pyramids: not read yet");
    expect_failure("a.ugrid", "4 0 0 1 0 0 0\n0 0 0 1 0 0 0 1 0 0 0 1\n1 2 3 5\n",
                   "tetrahedron 1: node id 5, expected 1 to 4");
    expect_failure("a.ugrid", "4 0 0 1 0 0 0\n0 0 0 1 0 x 0 1 0 0 0 1\n1 2 3 4\n", "a.ugrid:2:");
    expect_failure("b.b8.ugrid", "abcd", "b.b8.ugrid: byte");
}

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
        if (rc == 0)
            tpk_mesh_free(&m);
        CHECK_MSG(rc == 0 || strstr(d.message, "cut.ugrid"), "prefix %zu: '%s'", n, d.message);
    }
}
