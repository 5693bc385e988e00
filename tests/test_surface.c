/* Surfaces and point clouds through TetGen (tools/import/surface/surface.h): closed surfaces of real parts (the
 * boundary triangles of tetgen/hinge_small and part1_small, written here as STL, OFF and PLY) become
 * positive tets that fill exactly the enclosed volume and keep every surface vertex; open and
 * self-intersecting surfaces are refused by name; a point cloud gives its Delaunay tetrahedralization
 * (convex hull) with its values; bad files fail with file and place. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "import/importers.h"
#include "invariants.h"
#include "convert/pipeline.h"
#include "import/surface/surface.h"

/* A triangle surface as the tests build it: points and 0-based triangles. */
typedef struct test_surface {
    int64_t point_count, triangle_count;
    double *points;
    int32_t *triangles;
} test_surface;

static void surface_free(test_surface *s)
{
    free(s->points);
    free(s->triangles);
    memset(s, 0, sizeof *s);
}

/* Lines of a TetGen file without comments. */
static int next_record(FILE *f, char *line, size_t cap)
{
    while (fgets(line, (int)cap, f))
        if (line[strspn(line, " \t")] != '#' && line[strspn(line, " \t\r\n")])
            return 1;
    return 0;
}

/* The boundary of a TetGen mesh: .face triangles over the .node points they use (renumbered). */
static int load_boundary(const char *stem, test_surface *s)
{
    char path[512], line[512];
    snprintf(path, sizeof path, "%s.node", tpk_data_path(stem));
    FILE *f = fopen(path, "r");
    long n = 0, nf = 0;
    if (!f || !next_record(f, line, sizeof line) || sscanf(line, "%ld", &n) != 1)
        return -1;
    double *all = malloc(sizeof(double) * 3 * (size_t)n);
    for (long i = 0; i < n; i++) {
        long id;
        next_record(f, line, sizeof line);
        sscanf(line, "%ld %lf %lf %lf", &id, &all[3 * i], &all[3 * i + 1], &all[3 * i + 2]);
    }
    fclose(f);
    snprintf(path, sizeof path, "%s.face", tpk_data_path(stem));
    f = fopen(path, "r");
    if (!f || !next_record(f, line, sizeof line) || sscanf(line, "%ld", &nf) != 1)
        return -1;
    int32_t *map = malloc(sizeof(int32_t) * (size_t)n);
    for (long i = 0; i < n; i++)
        map[i] = -1;
    s->triangles = malloc(sizeof(int32_t) * 3 * (size_t)nf);
    s->points = malloc(sizeof(double) * 3 * (size_t)n);
    s->point_count = 0;
    for (long t = 0; t < nf; t++) {
        long id, v[3];
        next_record(f, line, sizeof line);
        sscanf(line, "%ld %ld %ld %ld", &id, &v[0], &v[1], &v[2]);
        for (int k = 0; k < 3; k++) {
            long old = v[k] - 1; /* 1-based files */
            if (map[old] < 0) {
                map[old] = (int32_t)s->point_count;
                memcpy(s->points + 3 * s->point_count++, all + 3 * old, 3 * sizeof(double));
            }
            s->triangles[3 * t + k] = map[old];
        }
    }
    fclose(f);
    s->triangle_count = nf;
    free(all);
    free(map);
    return 0;
}

static void cross(const double *a, const double *b, const double *c, double *n)
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

/* Area and enclosed volume (divergence theorem) of triangles, relative to a reference point so the
 * sum does not lose digits far from the origin. */
static void area_volume(const double *p, const int32_t *tri, int64_t n, const double *ref, double *area,
                        double *volume)
{
    *area = *volume = 0;
    for (int64_t t = 0; t < n; t++) {
        const double *a = p + 3 * tri[3 * t], *b = p + 3 * tri[3 * t + 1], *c = p + 3 * tri[3 * t + 2];
        double nrm[3], ra[3] = {a[0] - ref[0], a[1] - ref[1], a[2] - ref[2]};
        cross(a, b, c, nrm);
        *area += 0.5 * sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        *volume += (ra[0] * nrm[0] + ra[1] * nrm[1] + ra[2] * nrm[2]) / 6.0;
    }
}

static void write_stl_ascii(const char *path, const test_surface *s)
{
    FILE *f = fopen(path, "w");
    fprintf(f, "solid part\n");
    for (int64_t t = 0; t < s->triangle_count; t++) {
        fprintf(f, "  facet normal 0 0 0\n    outer loop\n");
        for (int k = 0; k < 3; k++) {
            const double *p = s->points + 3 * s->triangles[3 * t + k];
            fprintf(f, "      vertex %.17g %.17g %.17g\n", p[0], p[1], p[2]);
        }
        fprintf(f, "    endloop\n  endfacet\n");
    }
    fprintf(f, "endsolid part\n");
    fclose(f);
}

static void put_u32(FILE *f, uint32_t v, int big)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    if (big)
        for (int i = 0; i < 2; i++) {
            unsigned char t = b[i];
            b[i] = b[3 - i];
            b[3 - i] = t;
        }
    fwrite(b, 1, 4, f);
}

static void put_f32(FILE *f, float x, int big)
{
    uint32_t v;
    memcpy(&v, &x, 4);
    put_u32(f, v, big);
}

static void write_stl_binary(const char *path, const test_surface *s)
{
    FILE *f = fopen(path, "wb");
    char header[80] = "solid written by test_surface (binary: the size decides)";
    fwrite(header, 1, 80, f);
    put_u32(f, (uint32_t)s->triangle_count, 0);
    for (int64_t t = 0; t < s->triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            put_f32(f, 0.0f, 0);
        for (int k = 0; k < 9; k++)
            put_f32(f, (float)s->points[3 * s->triangles[3 * t + k / 3] + k % 3], 0);
        fwrite("\0\0", 1, 2, f);
    }
    fclose(f);
}

static void write_off(const char *path, const test_surface *s)
{
    FILE *f = fopen(path, "w");
    fprintf(f, "OFF\n# written by test_surface\n%lld %lld 0\n", (long long)s->point_count, (long long)s->triangle_count);
    for (int64_t i = 0; i < s->point_count; i++)
        fprintf(f, "%.17g %.17g %.17g\n", s->points[3 * i], s->points[3 * i + 1], s->points[3 * i + 2]);
    for (int64_t t = 0; t < s->triangle_count; t++)
        fprintf(f, "3 %d %d %d\n", s->triangles[3 * t], s->triangles[3 * t + 1], s->triangles[3 * t + 2]);
    fclose(f);
}

/* Binary PLY with float32 coordinates and a "scalar" = x + 2y (float32) per vertex. */
static void write_ply(const char *path, const test_surface *s, int big)
{
    FILE *f = fopen(path, "wb");
    fprintf(f, "ply\nformat binary_%s_endian 1.0\ncomment test_surface\nelement vertex %lld\nproperty float x\n"
               "property float y\nproperty float z\nproperty float scalar\nelement face %lld\n"
               "property list uchar int vertex_indices\nend_header\n",
            big ? "big" : "little", (long long)s->point_count, (long long)s->triangle_count);
    for (int64_t i = 0; i < s->point_count; i++) {
        const double *p = s->points + 3 * i;
        for (int k = 0; k < 3; k++)
            put_f32(f, (float)p[k], big);
        put_f32(f, (float)p[0] + 2.0f * (float)p[1], big);
    }
    for (int64_t t = 0; t < s->triangle_count; t++) {
        fputc(3, f);
        for (int k = 0; k < 3; k++)
            put_u32(f, (uint32_t)s->triangles[3 * t + k], big);
    }
    fclose(f);
}

/* The pipeline after the importer: tets, exact orientation, neighbors, invariants. */
static int run_pipeline(tpk_mesh *src, tpk_tetmesh *tm, int32_t **nb, tpk_orient_stats *os, char *msg, size_t cap)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_tetrahedralize(src, NULL, 0, 0, tm, &diag) || tpk_orient(tm, 0, 1, os, &diag))
        return snprintf(msg, cap, "%s", diag.message), -1;
    *nb = malloc(sizeof(int32_t) * 4 * (size_t)tm->tet_count);
    if (tpk_connect(tm->tets, tm->tet_count, tm->vertex_count, *nb, 1, &diag))
        return snprintf(msg, cap, "%s", diag.message), -1;
    return tpk_check_invariants(tm, *nb, msg, cap);
}

/* The boundary faces of the tet mesh, outward, as triangles. */
static int32_t *shell_triangles(const tpk_tetmesh *tm, const int32_t *nb, int64_t *count)
{
    int32_t *tri = malloc(sizeof(int32_t) * 3 * (size_t)(4 * tm->tet_count));
    *count = 0;
    for (int64_t t = 0; t < tm->tet_count; t++)
        for (int k = 0; k < 4; k++)
            if (nb[4 * t + k] < 0) {
                for (int j = 0; j < 3; j++)
                    tri[3 * *count + j] = tm->tets[4 * t + tpk_tet_faces[k][j]];
                ++*count;
            }
    return tri;
}

static int point_cmp(const void *a, const void *b)
{
    const double *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* Every surface vertex (rounded to float when the format stores float) is a vertex of the tet mesh. */
static int64_t missing_vertices(const test_surface *s, const tpk_tetmesh *tm, int as_float)
{
    double *sorted = malloc(sizeof(double) * 3 * (size_t)tm->vertex_count);
    memcpy(sorted, tm->points, sizeof(double) * 3 * (size_t)tm->vertex_count);
    qsort(sorted, (size_t)tm->vertex_count, 3 * sizeof(double), point_cmp);
    int64_t missing = 0;
    for (int64_t i = 0; i < s->point_count; i++) {
        double p[3];
        for (int k = 0; k < 3; k++)
            p[k] = as_float ? (double)(float)s->points[3 * i + k] : s->points[3 * i + k];
        missing += !bsearch(p, sorted, (size_t)tm->vertex_count, 3 * sizeof(double), point_cmp);
    }
    free(sorted);
    return missing;
}

/* Sum of the tets' signed volumes. */
static double tets_volume(const tpk_tetmesh *tm)
{
    double sum = 0;
    for (int64_t t = 0; t < tm->tet_count; t++) {
        const int32_t *v = tm->tets + 4 * t;
        const double *a = tm->points + 3 * v[0];
        double u[3], w[3], n[3];
        for (int k = 0; k < 3; k++)
            u[k] = tm->points[3 * v[1] + k] - a[k];
        cross(a, tm->points + 3 * v[2], tm->points + 3 * v[3], n);
        for (int k = 0; k < 3; k++)
            w[k] = n[k];
        sum += (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / 6.0;
    }
    return sum;
}

#ifndef TPK_WITH_TETGEN
#define TPK_WITH_TETGEN 0
#endif

/* Built without TetGen, the TetGen tests check that a surface is refused saying so, then skip visibly. */
static int without_tetgen(void)
{
    if (TPK_WITH_TETGEN)
        return 0;
    const char *path = tpk_temp_path("four.csv");
    FILE *f = fopen(path, "w");
    fputs("x,y,z\n0,0,0\n1,0,0\n0,1,0\n0,0,1\n", f);
    fclose(f);
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_import_any(path, NULL, &src, &diag) == 0 || !strstr(diag.message, "built without TetGen")) {
        fprintf(stderr, "expected a refusal saying tetpack was built without TetGen, got '%s'\n", diag.message);
        tpk_test_failures++;
    }
    return 1;
}

#define REQUIRE_TETGEN()                                                       \
    do {                                                                       \
        if (without_tetgen())                                                  \
            TPK_SKIP("built without TetGen (TETPACK_WITH_TETGEN=OFF)");        \
    } while (0)

/* Convert `path` (written from s) and check everything the issue asks for. */
static void check_converted(const char *path, const test_surface *s, int as_float, const char *field)
{
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = tpk_import_any(path, NULL, &src, &diag);
    CHECK_MSG(rc == 0, "%s", diag.message);
    int has_field = field && src.field_count == 1 && !strcmp(src.fields[0].name, field);
    CHECK_MSG(!field || has_field, "expected field %s", field);
    tpk_tetmesh tm;
    int32_t *nb = NULL;
    tpk_orient_stats os;
    char msg[1200] = "";
    rc = run_pipeline(&src, &tm, &nb, &os, msg, sizeof msg);
    tpk_mesh_free(&src);
    CHECK_MSG(rc == 0, "%s", msg);
    CHECK_EQ_INT(os.inverted_fixed, 0); /* TetGen's tets come positive */
    CHECK_EQ_INT(os.degenerate, 0);
    CHECK_EQ_INT(missing_vertices(s, &tm, as_float), 0);

    /* The input surface's area and enclosed volume, in the coordinates the file holds. */
    test_surface in = {s->point_count, s->triangle_count, malloc(sizeof(double) * 3 * (size_t)s->point_count), s->triangles};
    for (int64_t i = 0; i < 3 * s->point_count; i++)
        in.points[i] = as_float ? (double)(float)s->points[i] : s->points[i];
    double ref[3] = {in.points[0], in.points[1], in.points[2]}, area0, vol0, area1, vol1;
    area_volume(in.points, in.triangles, in.triangle_count, ref, &area0, &vol0);
    vol0 = fabs(vol0); /* TetGen's .face files run inward; the shell runs outward */
    free(in.points);
    int64_t nshell;
    int32_t *shell = shell_triangles(&tm, nb, &nshell);
    area_volume(tm.points, shell, nshell, ref, &area1, &vol1);
    double vol_tets = tets_volume(&tm);
    free(shell);
    CHECK_MSG(fabs(vol1 - vol0) <= 1e-9 * fabs(vol0), "shell volume %.17g vs surface %.17g", vol1, vol0);
    CHECK_MSG(fabs(vol_tets - vol0) <= 1e-9 * fabs(vol0), "tet volume %.17g vs surface %.17g", vol_tets, vol0);
    CHECK_MSG(fabs(area1 - area0) <= 1e-9 * area0, "shell area %.17g vs surface %.17g", area1, area0);
    CHECK(nshell >= s->triangle_count);

    if (field) { /* values on the surface vertices, NaN on TetGen's Steiner points */
        int64_t nan = 0, exact = 0;
        for (int64_t v = 0; v < tm.vertex_count; v++) {
            float val = tm.fields[0].values[v];
            const double *p = tm.points + 3 * v;
            nan += isnan(val);
            exact += val == (float)p[0] + 2.0f * (float)p[1];
        }
        CHECK_EQ_INT(exact, s->point_count);
        CHECK_EQ_INT(nan, tm.vertex_count - s->point_count);
    }
    free(nb);
    tpk_tetmesh_free(&tm);
}

static void check_part(const char *stem)
{
    test_surface s;
    CHECK(load_boundary(stem, &s) == 0);
    const char *base = strrchr(stem, '/') + 1;
    char path[4][256];
    snprintf(path[0], sizeof path[0], "%s", tpk_temp_path(base)), strcat(path[0], ".stl");
    snprintf(path[1], sizeof path[1], "%s", tpk_temp_path(base)), strcat(path[1], "_bin.stl");
    snprintf(path[2], sizeof path[2], "%s", tpk_temp_path(base)), strcat(path[2], ".off");
    snprintf(path[3], sizeof path[3], "%s", tpk_temp_path(base)), strcat(path[3], ".ply");
    write_stl_ascii(path[0], &s);
    write_stl_binary(path[1], &s);
    write_off(path[2], &s);
    write_ply(path[3], &s, strstr(stem, "hinge") != NULL);
    fprintf(stderr, "%s: %lld surface points, %lld triangles\n", stem, (long long)s.point_count,
            (long long)s.triangle_count);
    int before = tpk_test_failures;
    check_converted(path[0], &s, 0, NULL);
    if (tpk_test_failures == before)
        check_converted(path[1], &s, 1, NULL);
    if (tpk_test_failures == before)
        check_converted(path[2], &s, 0, NULL);
    if (tpk_test_failures == before)
        check_converted(path[3], &s, 1, "scalar");
    surface_free(&s);
}

TPK_TEST(hinge_all_formats)
{
    REQUIRE_TETGEN();
    check_part("tetgen/hinge_small");
}

TPK_TEST(part1_all_formats)
{
    REQUIRE_TETGEN();
    check_part("tetgen/part1_small");
}

/* Import a surface written by `write` and expect a failure whose message has all of `needles`. */
static int refused_with(const char *path, const char *needle1, const char *needle2, char *message, size_t cap)
{
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = tpk_import_any(path, NULL, &src, &diag);
    snprintf(message, cap, "%s", diag.message);
    if (rc == 0) {
        tpk_mesh_free(&src);
        return 0;
    }
    return strstr(diag.message, path) && strstr(diag.message, needle1) && (!needle2 || strstr(diag.message, needle2));
}

TPK_TEST(open_surface_refused)
{
    REQUIRE_TETGEN();
    test_surface s;
    CHECK(load_boundary("tetgen/part1_small", &s) == 0);
    int32_t *t = s.triangles + 3 * 100; /* drop triangle 100: its three edges become open */
    int32_t a = t[0], b = t[1], c = t[2];
    memmove(t, t + 3, sizeof(int32_t) * 3 * (size_t)(s.triangle_count - 101));
    s.triangle_count--;
    const char *path = tpk_temp_path("open.off");
    write_off(path, &s);
    char msg[1024], edge[64];
    /* The first open edge in file order: one of the dropped triangle's edges, lower id first. */
    int found = 0;
    int32_t pairs[3][2] = {{a, b}, {b, c}, {c, a}};
    for (int k = 0; k < 3 && !found; k++) {
        snprintf(edge, sizeof edge, "edge (%d, %d)", pairs[k][0] < pairs[k][1] ? pairs[k][0] : pairs[k][1],
                 pairs[k][0] < pairs[k][1] ? pairs[k][1] : pairs[k][0]);
        found = refused_with(path, edge, "only one face", msg, sizeof msg);
    }
    CHECK_MSG(found, "message: %s", msg);
    fprintf(stderr, "%s\n", msg);
    surface_free(&s);
}

TPK_TEST(flipped_face_refused)
{
    REQUIRE_TETGEN();
    test_surface s;
    CHECK(load_boundary("tetgen/part1_small", &s) == 0);
    int32_t *t = s.triangles + 3 * 7, keep = t[1];
    t[1] = t[2], t[2] = keep;
    const char *path = tpk_temp_path("flipped.stl");
    write_stl_ascii(path, &s);
    char msg[1024];
    CHECK_MSG(refused_with(path, "not consistently oriented", "faces 7, ", msg, sizeof msg), "message: %s", msg);
    surface_free(&s);
}

TPK_TEST(self_intersection_refused)
{
    REQUIRE_TETGEN();
    test_surface s;
    CHECK(load_boundary("tetgen/hinge_small", &s) == 0);
    /* Push the highest vertex down through the part and out of its bottom. */
    int64_t top = 0;
    double zmin = INFINITY;
    for (int64_t i = 0; i < s.point_count; i++) {
        if (s.points[3 * i + 2] > s.points[3 * top + 2])
            top = i;
        zmin = fmin(zmin, s.points[3 * i + 2]);
    }
    s.points[3 * top + 2] = zmin - (s.points[3 * top + 2] - zmin);
    const char *path = tpk_temp_path("crossed.off");
    write_off(path, &s);
    char msg[1024];
    CHECK_MSG(refused_with(path, "intersects itself", "face ", msg, sizeof msg), "message: %s", msg);
    fprintf(stderr, "%s\n", msg);
    surface_free(&s);
}

TPK_TEST(max_volume_option)
{
    REQUIRE_TETGEN();
    test_surface s;
    CHECK(load_boundary("tetgen/part1_small", &s) == 0);
    const char *path = tpk_temp_path("part.off");
    write_off(path, &s);
    tpk_tetgen_options opt = {0};
    opt.max_volume = 0.01;
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_import_any_with(path, NULL, &opt, &src, &diag) == 0, "%s", diag.message);
    tpk_tetmesh tm;
    int32_t *nb = NULL;
    tpk_orient_stats os;
    char msg[1200];
    CHECK_MSG(run_pipeline(&src, &tm, &nb, &os, msg, sizeof msg) == 0, "%s", msg);
    /* With the input facets kept (p180), TetGen meets the bound everywhere (with its default facet
     * merging it left 1.2 times the bound near the boundary of this part). */
    double largest = 0;
    int64_t above = 0;
    for (int64_t t = 0; t < tm.tet_count; t++) {
        tpk_tetmesh one = tm;
        one.tets = tm.tets + 4 * t, one.tet_count = 1;
        double v = tets_volume(&one);
        largest = fmax(largest, v);
        above += v > 0.01;
    }
    fprintf(stderr, "max volume 0.01: %lld tets, %lld above the bound, largest %.4g\n", (long long)tm.tet_count,
            (long long)above, largest);
    CHECK_MSG(tm.tet_count > 30000 && above == 0 && largest <= 0.01, "%lld tets, %lld above, largest %g",
              (long long)tm.tet_count, (long long)above, largest);
    tpk_mesh_free(&src);
    free(nb);
    tpk_tetmesh_free(&tm);
    surface_free(&s);
}

/* The vertices of sfepy/cylinder.vtk as a CSV point cloud with value = x + 2y + 3z, each point twice
 * in the second half of the file (duplicates merged). */
TPK_TEST(point_cloud_cylinder)
{
    REQUIRE_TETGEN();
    tpk_mesh cyl;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_import_vtk_legacy(tpk_data_path("sfepy/cylinder.vtk"), &cyl, &diag) == 0, "%s", diag.message);
    const char *path = tpk_temp_path("cylinder.csv");
    FILE *f = fopen(path, "w");
    fprintf(f, "x, y, z, value\n# the vertices of sfepy/cylinder.vtk\n");
    for (int64_t i = 0; i < cyl.point_count; i++) {
        const double *p = cyl.points + 3 * i;
        fprintf(f, "%.17g,%.17g,%.17g,%.9g\n", p[0], p[1], p[2], p[0] + 2 * p[1] + 3 * p[2]);
    }
    for (int64_t i = cyl.point_count / 2; i < cyl.point_count; i++)
        fprintf(f, "%.17g,%.17g,%.17g,0\n", cyl.points[3 * i], cyl.points[3 * i + 1], cyl.points[3 * i + 2]);
    fclose(f);
    tpk_tetmesh ctm;
    CHECK_MSG(tpk_tetrahedralize(&cyl, NULL, 0, 0, &ctm, &diag) == 0, "%s", diag.message);
    double ref[3] = {0, 0, 0}, cyl_volume = fabs(tets_volume(&ctm));
    tpk_tetmesh_free(&ctm);

    tpk_mesh src;
    diag.warning_count = 0;
    CHECK_MSG(tpk_import_any(path, NULL, &src, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(diag.warning_count, 1); /* the duplicates */
    CHECK_EQ_INT(src.point_count, cyl.point_count);
    CHECK(src.field_count == 1 && !strcmp(src.fields[0].name, "value"));
    tpk_tetmesh tm;
    int32_t *nb = NULL;
    tpk_orient_stats os;
    char msg[1200];
    CHECK_MSG(run_pipeline(&src, &tm, &nb, &os, msg, sizeof msg) == 0, "%s", msg);
    tpk_mesh_free(&src);
    /* Delaunay without new points: the same vertices, each with its own value (the first copy's). */
    CHECK_EQ_INT(tm.vertex_count, cyl.point_count);
    for (int64_t v = 0; v < tm.vertex_count; v++) {
        const double *p = tm.points + 3 * v;
        double want = p[0] + 2 * p[1] + 3 * p[2];
        CHECK_MSG(fabs(tm.fields[0].values[v] - want) <= 1e-6 * fmax(1, fabs(want)), "vertex %lld: %.9g, want %.9g",
                  (long long)v, tm.fields[0].values[v], want);
    }
    /* Convex hull: no point lies outside any boundary face (exact), and every vertex is used. */
    int64_t nshell;
    int32_t *shell = shell_triangles(&tm, nb, &nshell);
    for (int64_t t = 0; t < nshell; t++) {
        const int32_t *tri = shell + 3 * t;
        for (int64_t v = 0; v < tm.vertex_count; v++)
            CHECK_MSG(tpk_orient3d_exact(tm.points + 3 * tri[0], tm.points + 3 * tri[1], tm.points + 3 * tri[2],
                                         tm.points + 3 * v) <= 0,
                      "point %lld outside shell face %lld", (long long)v, (long long)t);
    }
    double area, hull_volume, tet_volume = tets_volume(&tm);
    area_volume(tm.points, shell, nshell, ref, &area, &hull_volume);
    fprintf(stderr, "cylinder: %lld points -> %lld Delaunay tets, hull volume %.17g (source mesh %.17g)\n",
            (long long)tm.vertex_count, (long long)tm.tet_count, hull_volume, cyl_volume);
    CHECK_MSG(fabs(tet_volume - hull_volume) <= 1e-9 * hull_volume, "%.17g vs %.17g", tet_volume, hull_volume);
    /* A closed shell with every point on the inner side of every face bounds a convex region holding
     * all points: the convex hull; the tets fill exactly its volume (the source mesh is not convex). */
    free(shell);
    free(nb);
    tpk_tetmesh_free(&tm);
    tpk_mesh_free(&cyl);
}

TPK_TEST(point_cloud_options_refused)
{
    REQUIRE_TETGEN();
    const char *path = tpk_temp_path("four.csv");
    FILE *f = fopen(path, "w");
    fputs("x,y,z\n0,0,0\n1,0,0\n0,1,0\n0,0,1\n", f);
    fclose(f);
    tpk_tetgen_options opt = {0};
    opt.max_volume = 1;
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_import_any_with(path, NULL, &opt, &src, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "apply to closed surfaces"), "%s", diag.message);
    CHECK_MSG(tpk_import_any(path, NULL, &src, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(src.cell_count, 1);
    tpk_mesh_free(&src);
    f = fopen(path, "w"); /* all on one plane: no tets */
    fputs("x,y,z\n0,0,0\n1,0,0\n0,1,0\n1,1,0\n", f);
    fclose(f);
    CHECK(tpk_import_any(path, NULL, &src, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "four.csv"), "%s", diag.message);
}


/* Reading only (no TetGen): a small closed cube in every PLY encoding gives the same mesh. */
static const char cube_ascii[] =
    "ply\nformat ascii 1.0\ncomment a unit cube\nelement vertex 8\nproperty float x\nproperty float y\n"
    "property float z\nproperty uchar red\nelement face 6\nproperty list uchar int vertex_indices\n"
    "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
    "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n0 0 1 5\n1 0 1 6\n1 1 1 7\n0 1 1 8\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n0 1\n";

TPK_TEST(ply_cube_readers)
{
    tpk_mesh m;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_read_surface_memory("cube.ply", cube_ascii, sizeof cube_ascii - 1, TPK_SURFACE_UNKNOWN, &m,
                                      &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(m.point_count, 8);
    CHECK_EQ_INT(m.cell_count, 6);
    CHECK_EQ_INT(m.cell_offsets[6], 24);
    CHECK(m.field_count == 1 && !strcmp(m.fields[0].name, "red") && m.fields[0].values[7] == 8.0f);
    CHECK_MSG(tpk_surface_check_closed("cube.ply", &m, &diag) == 0, "%s", diag.message);
    /* The same cube in binary, both byte orders. */
    for (int big = 0; big < 2; big++) {
        char buf[1024];
        int n = snprintf(buf, sizeof buf, "ply\nformat binary_%s_endian 1.0\nelement vertex 8\nproperty double x\n"
                         "property double y\nproperty double z\nproperty short red\nelement face 6\n"
                         "property list uchar uint vertex_indices\nend_header\n", big ? "big" : "little");
        for (int i = 0; i < 8; i++) {
            for (int k = 0; k < 4; k++) {
                double d = k < 3 ? m.points[3 * i + k] : 0;
                unsigned char b[8];
                memcpy(b, &d, 8);
                int size = k < 3 ? 8 : 2;
                int16_t red = (int16_t)(-i);
                if (k == 3)
                    memcpy(b, &red, 2);
                for (int j = 0; j < size; j++)
                    buf[n++] = (char)b[big ? size - 1 - j : j];
            }
        }
        for (int f = 0; f < 6; f++) {
            buf[n++] = 4;
            for (int k = 0; k < 4; k++) {
                uint32_t v = (uint32_t)m.cell_conn[4 * f + k];
                for (int j = 0; j < 4; j++)
                    buf[n++] = (char)(v >> (8 * (big ? 3 - j : j)));
            }
        }
        tpk_mesh b;
        CHECK_MSG(tpk_read_ply("cube_bin.ply", buf, (size_t)n, &b, &diag) == 0, "%s", diag.message);
        CHECK(!memcmp(b.points, m.points, sizeof(double) * 24) && !memcmp(b.cell_conn, m.cell_conn, 4 * 24));
        CHECK(b.fields[0].values[5] == -5.0f);
        tpk_mesh_free(&b);
        CHECK_MSG(tpk_read_ply("cube_bin.ply", buf, (size_t)n - 3, &b, &diag) != 0 && strstr(diag.message, "byte "),
                  "%s", diag.message);
    }
    tpk_mesh_free(&m);
}

/* Bad files: each fails naming the file and the place. */
TPK_TEST(bad_files)
{
    static const struct {
        const char *name, *data, *needle;
        size_t size;
    } cases[] = {
        {"short.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n", "short.off:9: expected the corner count of face 2, found end of file", 0},
        {"long.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "long.off:6: expected end of line after the 3 coordinates of vertex 3, found '2'", 0},
        {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "index.off:6: expected a vertex index of face 0 from 0 to 2, found 3", 0},
        {"fmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "fmt.ply:2: expected ascii, binary_little_endian", 0},
        {"type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n", "type.ply:4: expected a PLY type", 0},
        {"noxyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n", "lacks scalar property x, y or z", 0},
        {"stl.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nendloop\n", "stl.stl:5: expected a vertex coordinate of facet 0, found end of line", 0},
        {"cols.csv", "x,y,z,t\n0,0,0,1\n1,0,0\n", "cols.csv:3: expected 4 comma-separated values, found 3", 0},
        {"num.csv", "x,y,z\n0,0,zero\n", "num.csv:2: expected a number in column 'z', found 'zero'", 0},
        {"hdr.csv", "a,b,c\n0,0,0\n", "expected a header line naming columns x, y and z", 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tpk_mesh m;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        size_t size = cases[i].size ? cases[i].size : strlen(cases[i].data);
        int rc = tpk_read_surface_memory(cases[i].name, cases[i].data, size,
                                         tpk_surface_kind_from_name(cases[i].name), &m, &diag);
        CHECK_MSG(rc != 0 && strstr(diag.message, cases[i].needle), "%s: got '%s'", cases[i].name, diag.message);
        CHECK(m.points == NULL && m.cell_count == 0);
    }
}

TPK_TEST(binary_stl_truncated_offset)
{
    char buf[84 + 50 * 2 - 7] = "solid header of a binary STL";
    uint32_t n = 2;
    memcpy(buf + 80, &n, 4);
    tpk_mesh m;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_read_stl("t.stl", buf, sizeof buf, &m, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "t.stl: byte 134: truncated binary STL: the header says 2 triangles (184 bytes)"),
              "%s", diag.message);
}

TPK_TEST(switches)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    char buf[160];
    CHECK(tpk_tetgen_surface_switches(NULL, buf, sizeof buf, &diag) == 0 && !strcmp(buf, "p180zQq1.414"));
    tpk_tetgen_options o = {0};
    o.radius_edge_ratio = 2, o.min_dihedral = 12, o.max_volume = 0.5;
    CHECK(tpk_tetgen_surface_switches(&o, buf, sizeof buf, &diag) == 0 && !strcmp(buf, "p180zQq2/12a0.5"));
    o.radius_edge_ratio = -1, o.min_dihedral = 0, o.max_volume = 0;
    CHECK(tpk_tetgen_surface_switches(&o, buf, sizeof buf, &diag) == 0 && !strcmp(buf, "p180zQ"));
    o.radius_edge_ratio = 0.5;
    CHECK(tpk_tetgen_surface_switches(&o, buf, sizeof buf, &diag) != 0 && strstr(diag.message, "from 1.0"));
    memset(&o, 0, sizeof o);
    o.switches = "-pq1.2/15a1e-3YT1e-9";
    CHECK_MSG(tpk_tetgen_surface_switches(&o, buf, sizeof buf, &diag) == 0 && !strcmp(buf, "p180zQpq1.2/15a1e-3YT1e-9"),
              "%s / %s", buf, diag.message);
    const char *refused[] = {"pr", "pV", "pqw", "pk", "pd", "p q", "pNEF"};
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; i++) {
        o.switches = refused[i];
        CHECK_MSG(tpk_tetgen_surface_switches(&o, buf, sizeof buf, &diag) != 0 && strstr(diag.message, "not allowed"),
                  "%s accepted", refused[i]);
    }
}

TPK_TEST(sniff)
{
    CHECK(tpk_surface_kind_sniff("ply\nformat", 10) == TPK_SURFACE_PLY);
    CHECK(tpk_surface_kind_sniff("  OFF\n", 6) == TPK_SURFACE_OFF);
    CHECK(tpk_surface_kind_sniff("solid x\n", 8) == TPK_SURFACE_STL);
    CHECK(tpk_surface_kind_sniff("x,y,z,temp\n1,2,3,4\n", 19) == TPK_SURFACE_CSV);
    CHECK(tpk_surface_kind_sniff("hello", 5) == TPK_SURFACE_UNKNOWN);
    CHECK(tpk_surface_kind_from_name("a/b.STL") == TPK_SURFACE_STL);
}
