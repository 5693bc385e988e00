/* tetpack check, cells group (2xx, tools/check/check_cells*.c): exact counts on real meshes (inverted and
 * degenerate tets, the sfepy cross, clean meshes), near-degenerate tets floating point gets wrong, near
 * misses that must stay quiet, every node-list check, and examples that do not depend on --threads. */
#include <math.h>
#include <string.h>

#include "check/check.h"
#include "harness.h"
#include "import/importers.h"

/* ---- helpers ---------------------------------------------------------------------------------- */

typedef struct cell_spec {
    int type, n;
    int32_t ids[8];
} cell_spec;

/* A mesh owning copies of `points` (3 per point) and `cells`. */
static int build(tpk_mesh *m, const double *points, int64_t point_count, const cell_spec *cells, int64_t count)
{
    memset(m, 0, sizeof *m);
    int64_t conn = 0;
    for (int64_t c = 0; c < count; c++)
        conn += cells[c].n;
    m->point_count = point_count;
    m->cell_count = count;
    m->points = malloc(sizeof *m->points * 3 * (size_t)(point_count ? point_count : 1));
    m->cell_types = malloc((size_t)(count ? count : 1));
    m->cell_offsets = malloc(sizeof *m->cell_offsets * (size_t)(count + 1));
    m->cell_conn = malloc(sizeof *m->cell_conn * (size_t)(conn ? conn : 1));
    m->step_count = 1;
    if (!m->points || !m->cell_types || !m->cell_offsets || !m->cell_conn)
        return -1;
    memcpy(m->points, points, sizeof *m->points * 3 * (size_t)point_count);
    m->cell_offsets[0] = 0;
    for (int64_t c = 0; c < count; c++) {
        m->cell_types[c] = (uint8_t)cells[c].type;
        memcpy(m->cell_conn + m->cell_offsets[c], cells[c].ids, sizeof(int32_t) * (size_t)cells[c].n);
        m->cell_offsets[c + 1] = m->cell_offsets[c] + cells[c].n;
    }
    return 0;
}

/* Run the cells group with default options changed by `tweak` (may be NULL). */
static int run_cells(const tpk_mesh *m, tpk_check_report *r, void (*tweak)(tpk_check_options *))
{
    tpk_check_options opt;
    tpk_check_options_default(&opt);
    if (tweak)
        tweak(&opt);
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_check_report_init(r, &opt))
        return -1;
    tpk_check_input in = {.mesh = m, .path = "test"};
    return tpk_check_cells(&in, r, &diag);
}

static int64_t count_of(tpk_check_report *r, int id)
{
    return tpk_check_finding(r, id)->count;
}

/* Errors and warnings of the cells group (info excluded). */
static int64_t problems_2xx(tpk_check_report *r, char *first, size_t cap)
{
    int64_t n = 0;
    for (int i = 0; i < r->finding_count; i++) {
        const tpk_finding *f = &r->findings[i];
        if (f->check->id / 100 != 2 || f->check->severity == TPK_SEV_INFO || !f->count)
            continue;
        if (!n)
            snprintf(first, cap, "%d %s x%lld: %s", f->check->id, f->check->name, (long long)f->count,
                     f->example_count ? f->examples[0].note : "");
        n += f->count;
    }
    return n;
}

static int import_data(const char *relative, tpk_mesh *m)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = tpk_import_any(tpk_data_path(relative), NULL, m, &diag);
    if (rc)
        fprintf(stderr, "import %s: %s\n", relative, diag.message);
    return rc;
}

static const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* ---- real meshes ------------------------------------------------------------------------------ */

TPK_TEST(real_inverted_tets)
{
    /* hard/make_hard.py swaps nodes 0 and 1 of every 10th tet of sfepy/cylinder.vtk: cells 0, 10, ...,
     * 1340, exactly 135 of 1348, nothing else wrong. */
    tpk_mesh m;
    tpk_check_report r;
    CHECK(import_data("hard/inverted_tets.vtk", &m) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 204), 135);
    CHECK_EQ_INT(count_of(&r, 203), 0);
    const tpk_finding *f = tpk_check_finding(&r, 204);
    CHECK_EQ_INT(f->example_count, 5);
    for (int i = 0; i < f->example_count; i++)
        CHECK_EQ_INT(f->examples[i].ids[0], 10 * i);
    CHECK(f->examples[0].has_point);
    char first[300] = "";
    CHECK_MSG(problems_2xx(&r, first, sizeof first) == 135, "%s", first);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(real_degenerate_tets)
{
    /* hard/make_hard.py: 20 tets of sfepy/elbow.mesh get a repeated node (202; skipped by the geometry
     * checks), 20 get their 4th node moved "onto" the plane of the other three as (a+b+d)/3 + 0.1 (b-a),
     * computed in doubles. Decided exactly, none of those 20 is flat: the rounding puts 11 just above the
     * plane and 9 just below (inverted: 204 = 9, test_pipeline finds the same 9). All 20 are near-flat
     * (min dihedral < 1e-5 deg), so they are the slivers (209 = 20) and nothing else is. */
    tpk_mesh m;
    tpk_check_report r;
    CHECK(import_data("hard/degenerate_tets.vtk", &m) == 0);
    CHECK(m.field_count == 1 && !strcmp(m.fields[0].name, "degenerate_kind"));
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 202), 20);
    CHECK_EQ_INT(count_of(&r, 203), 0);
    CHECK_EQ_INT(count_of(&r, 204), 9);
    CHECK_EQ_INT(count_of(&r, 209), 20);
    CHECK_EQ_INT(count_of(&r, 201), 0);
    CHECK_EQ_INT(count_of(&r, 211), 0);
    const float *kind = m.fields[0].values;
    for (int id = 202; id <= 209; id += 2) { /* 202, 204, 206 (none), 208 (none) */
        const tpk_finding *f = tpk_check_finding(&r, id);
        for (int i = 0; i < f->example_count; i++)
            CHECK_MSG(kind[f->examples[i].ids[0]] == (id == 202 ? 1.0f : 2.0f), "check %d, cell %lld", id,
                      (long long)f->examples[i].ids[0]);
    }
    const tpk_finding *slivers = tpk_check_finding(&r, 209);
    for (int i = 0; i < slivers->example_count; i++)
        CHECK(kind[slivers->examples[i].ids[0]] == 2.0f);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(real_cross3d)
{
    /* sfepy's special/cross3d.mesh: 7 hexahedra in a cross; the upper arm (cell 2) has its top face turned
     * by about 56 deg against its bottom, so its four side faces are warped by up to 79 deg (205 = 4), a
     * corner lies outside a side face's plane (206) and the smallest-id split folds (208: 5 positive
     * tets, 1 negative). It is still no error: no flat or inverted tet, no faces that cross. */
    tpk_mesh m;
    tpk_check_report r;
    CHECK(import_data("sfepy/cross3d.mesh", &m) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 205), 4);
    CHECK_EQ_INT(count_of(&r, 206), 1);
    CHECK_EQ_INT(count_of(&r, 208), 1);
    for (int id = 201; id <= 213; id++) {
        const tpk_finding *f = tpk_check_finding(&r, id);
        CHECK_MSG(f->count == 0 || id == 205 || id == 206 || id == 208, "check %d fired %lld times", id,
                  (long long)f->count);
        for (int i = 0; i < f->example_count; i++)
            CHECK_EQ_INT(f->examples[i].ids[0], 2);
    }
    CHECK(strstr(tpk_check_finding(&r, 208)->examples[0].note, "5 positive, 1 negative") != NULL);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(real_clean_meshes)
{
    /* No 2xx error or warning with the default thresholds (which check_report.c chose from these). */
    static const char *clean[] = {
        "sfepy/acoustic_wg.vtk", "sfepy/cylinder.vtk", "sfepy/piezo_mesh_micro.vtk",
        "sfepy/cube_big_tetra.mesh", "sfepy/cube_cylinder.mesh", "sfepy/cube_medium_hexa.mesh",
        "sfepy/cube_medium_tetra.mesh", "sfepy/elbow.mesh", "sfepy/acoustics_mesh3d.mesh",
        "tetgen/hinge_small.node", "tetgen/part1_small.node", "gmsh/t3_hex_prism_ascii41.msh",
        "gmsh/t5_small_tet_ascii22.msh", "gmsh/t5_small_tet_bin.vtk", "nasa_refine/cube_polar1.ugrid",
        "nasa_refine/cube_cylinder_ega.ugrid", "nasa_refine/cube-sphere_cube-sphere.meshb",
        "nasa_refine/om6_om6-curv-no-geom.meshb", "seacas/exomerge_unit_test.e", "seacas/8-block.g",
        "hard/huge_offset_hex.vtu", "hard/hanging_nodes_hex.vtk"};
    for (size_t i = 0; i < sizeof clean / sizeof clean[0]; i++) {
        tpk_mesh m;
        tpk_check_report r;
        CHECK_MSG(import_data(clean[i], &m) == 0, "%s", clean[i]);
        CHECK(run_cells(&m, &r, NULL) == 0);
        char first[300] = "";
        CHECK_MSG(problems_2xx(&r, first, sizeof first) == 0, "%s: %s", clean[i], first);
        tpk_check_report_free(&r);
        tpk_mesh_free(&m);
    }
}

TPK_TEST(real_mirrored_hexes)
{
    /* sfepy/matrix_fiber_rand.vtk really mixes orientations: 97 of its 603 hexahedra are given in mirrored
     * node order (every tet of their split is negative). The converter turns them over; check says so. */
    tpk_mesh m;
    tpk_check_report r;
    CHECK(import_data("sfepy/matrix_fiber_rand.vtk", &m) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 204), 97);
    char first[300] = "";
    CHECK_MSG(problems_2xx(&r, first, sizeof first) == 97, "%s", first);
    CHECK(strstr(tpk_check_finding(&r, 204)->examples[0].note, "mirrored") != NULL);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

/* ---- exact decisions where doubles fail --------------------------------------------------------- */

/* Naive double determinant det[b-a, c-a, d-a], as a non-exact validator would compute it. */
static double naive_det(const double *a, const double *b, const double *c, const double *d)
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Four points on the plane 3x + 5y + 7z = 0, integers near 2^30 scaled by 2^-20 (so coordinates carry
 * fraction bits) plus `offset`: exactly coplanar (every step is exact), yet the triple products need
 * ~100 bits and the double determinant rounds. Picks the first seed where the naive determinant is
 * nonzero. Returns the naive determinant. */
static double coplanar_tet(double points[4][3], double offset)
{
    uint64_t seed = 1;
    for (int attempt = 0; attempt < 1000; attempt++) {
        for (int i = 0; i < 4; i++) {
            int64_t x, y;
            do {
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                x = (int64_t)(seed >> 34) + (1 << 29);
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                y = (int64_t)(seed >> 34) - (1 << 29);
            } while ((3 * x + 5 * y) % 7 != 0);
            int64_t z = -(3 * x + 5 * y) / 7;
            points[i][0] = ldexp((double)x, -20) + offset;
            points[i][1] = ldexp((double)y, -20) + offset;
            points[i][2] = ldexp((double)z, -20) + offset;
        }
        double det = naive_det(points[0], points[1], points[2], points[3]);
        if (det != 0)
            return det;
    }
    return 0;
}

TPK_TEST(coplanar_to_the_last_bit)
{
    for (int pass = 0; pass < 2; pass++) {
        double p[4][3];
        double naive = coplanar_tet(p, pass ? 1e7 : 0);
        CHECK_MSG(naive != 0, "no seed gave a rounded determinant"); /* doubles would call it a tet */
        cell_spec tet = {10, 4, {0, 1, 2, 3}};
        tpk_mesh m;
        tpk_check_report r;
        CHECK(build(&m, &p[0][0], 4, &tet, 1) == 0);
        CHECK(run_cells(&m, &r, NULL) == 0);
        CHECK_MSG(count_of(&r, 203) == 1, "offset %g: naive det %g", pass ? 1e7 : 0, naive);
        CHECK_EQ_INT(count_of(&r, 204), 0);
        CHECK_EQ_INT(count_of(&r, 209), 0); /* flat tets are not measured */
        CHECK(strstr(tpk_check_finding(&r, 203)->examples[0].note, "det = 0") != NULL);
        tpk_check_report_free(&r);
        tpk_mesh_free(&m);
    }
}

TPK_TEST(one_ulp_off_the_plane_at_offset)
{
    /* At 1e7 the spacing of doubles is 2^-29: a, b, c on the plane z = 1e7, d one ulp above (a valid,
     * very thin tet: no 203, no 204) or one ulp below (inverted: 204). The thin one is a sliver. */
    const double o = 1e7, up = nextafter(o, 2 * o), down = nextafter(o, 0);
    for (int below = 0; below < 2; below++) {
        double p[4][3] = {{o, o, o}, {o + 1, o, o}, {o, o + 1, o}, {o + 0.25, o + 0.25, below ? down : up}};
        cell_spec tet = {10, 4, {0, 1, 2, 3}};
        tpk_mesh m;
        tpk_check_report r;
        CHECK(build(&m, &p[0][0], 4, &tet, 1) == 0);
        CHECK(run_cells(&m, &r, NULL) == 0);
        CHECK_EQ_INT(count_of(&r, 203), 0);
        CHECK_EQ_INT(count_of(&r, 204), below);
        CHECK_EQ_INT(count_of(&r, 209), 1);
        tpk_check_report_free(&r);
        tpk_mesh_free(&m);
    }
}

TPK_TEST(thin_sliver_is_not_flat)
{
    /* Near miss: a square's corners with one lifted by 1e-6 of the edge: min dihedral ~1e-4 deg, a
     * sliver under the default 0.1 deg, but positive (no 203, no 204); with --sliver-deg 1e-5 it is not
     * one. Its radius ratio is tiny (210, info). */
    double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 1e-6}, {0, 1, 0}};
    cell_spec tet = {10, 4, {0, 1, 3, 2}};
    tpk_mesh m;
    tpk_check_report r;
    CHECK(build(&m, &p[0][0], 4, &tet, 1) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 203), 0);
    CHECK_EQ_INT(count_of(&r, 204), 0);
    CHECK_EQ_INT(count_of(&r, 209), 1);
    CHECK_EQ_INT(count_of(&r, 210), 1);
    tpk_check_report_free(&r);
    tpk_check_options opt;
    tpk_check_options_default(&opt);
    opt.sliver_deg = 1e-5;
    tpk_diag diag = {0};
    tpk_check_input in = {.mesh = &m, .path = "test"};
    CHECK(tpk_check_report_init(&r, &opt) == 0);
    CHECK(tpk_check_cells(&in, &r, &diag) == 0);
    CHECK_EQ_INT(count_of(&r, 209), 0);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(regular_tet_quality)
{
    const double s = 1.0 / sqrt(2.0);
    double p[4][3] = {{1, 0, -s}, {-1, 0, -s}, {0, 1, s}, {0, -1, s}};
    cell_spec tet = {10, 4, {0, 1, 2, 3}};
    tpk_mesh m;
    tpk_check_report r;
    CHECK(build(&m, &p[0][0], 4, &tet, 1) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    int positive = count_of(&r, 204) == 0;
    if (!positive) { /* take the other orientation */
        tpk_check_report_free(&r);
        m.cell_conn[0] = 1, m.cell_conn[1] = 0;
        CHECK(run_cells(&m, &r, NULL) == 0);
        CHECK_EQ_INT(count_of(&r, 204), 0);
    }
    const double want[4] = {acos(1.0 / 3.0) * 180 / M_PI, acos(1.0 / 3.0) * 180 / M_PI, 1, 1};
    static const char *names[4] = {"min_dihedral_deg", "max_dihedral_deg", "radius_ratio", "aspect_ratio"};
    for (int h = 0; h < 4; h++) {
        tpk_histogram *hist = tpk_check_histogram(&r, names[h], 0, 1);
        CHECK_EQ_INT(hist->count, 1);
        CHECK_MSG(fabs(hist->min - want[h]) < 1e-12 && hist->min == hist->max, "%s: %.17g", names[h], hist->min);
    }
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

/* ---- node lists ------------------------------------------------------------------------------- */

TPK_TEST(node_list_checks)
{
    double p[9][3];
    memcpy(p, cube, sizeof cube);
    p[8][0] = 0.5, p[8][1] = 0.5, p[8][2] = 2;
    cell_spec cells[] = {
        {10, 4, {0, 1, 3, 4}},                 /* 0: fine */
        {10, 4, {0, 1, 3, 9}},                 /* 1: 201 (9 is out of range) */
        {10, 4, {0, 1, -1, 4}},                /* 2: 201 */
        {12, 8, {0, 1, 2, 3, 4, 5, 6, 6}},     /* 3: 202 */
        {10, 4, {0, 0, 3, 99}},                /* 4: 201 and 202 */
        {15, 8, {0, 1, 2, 3, 4, 5, 6, 7}},     /* 5: 212, pentagonal prism with 8 nodes */
        {41, 4, {0, 1, 3, 4}},                 /* 6: 212, convex point set */
        {99, 4, {0, 1, 3, 4}},                 /* 7: 212, unknown */
        {12, 7, {0, 1, 2, 3, 4, 5, 6}},        /* 8: 212, hexahedron with 7 nodes */
        {5, 3, {0, 1, 2}},                     /* 9: 213 triangle */
        {3, 2, {0, 1}},                        /* 10: 213 line */
        {14, 5, {4, 5, 6, 7, 8}},              /* 11: fine pyramid */
        {24, 8, {0, 1, 3, 4, 8, 6, 7, 2}},     /* 12: 212 quadratic tetra: a 3-D type convert does not take */
    };
    tpk_mesh m;
    tpk_check_report r;
    CHECK(build(&m, &p[0][0], 9, cells, sizeof cells / sizeof cells[0]) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 201), 3);
    CHECK_EQ_INT(count_of(&r, 202), 2);
    CHECK_EQ_INT(count_of(&r, 212), 5);
    CHECK_EQ_INT(count_of(&r, 213), 2);
    for (int id = 203; id <= 211; id++)
        CHECK_MSG(count_of(&r, id) == 0, "check %d", id);
    const tpk_finding *f = tpk_check_finding(&r, 201);
    CHECK_EQ_INT(f->examples[0].ids[0], 1);
    CHECK_EQ_INT(f->examples[0].id_count, 5);
    CHECK_EQ_INT(f->examples[0].ids[4], 9);
    CHECK_EQ_INT(f->examples[2].ids[0], 4);
    f = tpk_check_finding(&r, 202);
    CHECK_EQ_INT(f->examples[0].ids[0], 3);
    CHECK(f->examples[0].has_point && f->examples[0].point[2] == 1.0); /* vertex 6 */
    f = tpk_check_finding(&r, 212);
    CHECK(strstr(f->examples[3].note, "7 nodes, expected 8") != NULL);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(duplicate_cells)
{
    double p[9][3];
    memcpy(p, cube, sizeof cube);
    p[8][0] = 0.5, p[8][1] = 0.5, p[8][2] = 2;
    static const int32_t voxel_order[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    cell_spec cells[] = {
        {12, 8, {0, 1, 2, 3, 4, 5, 6, 7}},     /* 0 */
        {10, 4, {4, 5, 6, 8}},                 /* 1 */
        {14, 5, {4, 5, 6, 7, 8}},              /* 2 */
        {10, 4, {8, 6, 4, 5}},                 /* 3: same set as 1, other order (and orientation) */
        {11, 8, {0}},                          /* 4: the voxel on the hexahedron's corners: same set as 0 */
        {10, 4, {5, 4, 8, 6}},                 /* 5: same as 1 again */
        {5, 3, {4, 5, 6}},                     /* 6: triangle: lower-dimensional cells take no part */
        {5, 3, {6, 5, 4}},                     /* 7 */
    };
    for (int i = 0; i < 8; i++)
        cells[4].ids[i] = voxel_order[i];
    tpk_mesh m;
    tpk_check_report r;
    CHECK(build(&m, &p[0][0], 9, cells, sizeof cells / sizeof cells[0]) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    CHECK_EQ_INT(count_of(&r, 211), 3);
    const tpk_finding *f = tpk_check_finding(&r, 211);
    CHECK_EQ_INT(f->example_count, 3);
    CHECK(f->examples[0].ids[0] == 3 && f->examples[0].ids[1] == 1);
    CHECK(f->examples[1].ids[0] == 4 && f->examples[1].ids[1] == 0);
    CHECK(f->examples[2].ids[0] == 5 && f->examples[2].ids[1] == 1);
    CHECK_EQ_INT(count_of(&r, 204), 1); /* cell 3 is also mirrored */
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

/* ---- split cells ------------------------------------------------------------------------------ */

static void warp_zero(tpk_check_options *o)
{
    o->warp_deg = 0;
}

static void run_hex(const double (*corners)[3], const int32_t *order, int type, tpk_check_report *r,
                    void (*tweak)(tpk_check_options *), int *ok)
{
    cell_spec cell = {type, 8, {0}};
    cell.n = type == 13 ? 6 : type == 14 ? 5 : 8;
    for (int i = 0; i < cell.n; i++)
        cell.ids[i] = order ? order[i] : i;
    tpk_mesh m;
    *ok = build(&m, &corners[0][0], 8, &cell, 1) == 0 && run_cells(&m, r, tweak) == 0;
    tpk_mesh_free(&m);
}

TPK_TEST(planar_hex_at_large_coordinates)
{
    /* Near miss: a frustum (bottom 4 x 4, top 2 x 2, height 2) at 1e7: every face exactly planar, so no
     * warp even with --warp-deg 0 (rounded normals differ by ~1e-9 rad there), convex, valid split. */
    const double o = 1e7;
    double p[8][3] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {1, 1, 2}, {3, 1, 2}, {3, 3, 2}, {1, 3, 2}};
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            p[i][k] += o + 0.125 * k; /* representable: the translation is exact */
    tpk_check_report r;
    int ok;
    run_hex(p, NULL, 12, &r, warp_zero, &ok);
    CHECK(ok);
    for (int id = 203; id <= 208; id++)
        CHECK_MSG(count_of(&r, id) == 0, "check %d: %s", id,
                  tpk_check_finding(&r, id)->example_count ? tpk_check_finding(&r, id)->examples[0].note : "");
    tpk_check_report_free(&r);
    /* A warped face for contrast: lift corner 6 by 0.5: faces 1, 3, 4 warp (4.x to 11 deg). */
    p[6][2] += 0.5;
    run_hex(p, NULL, 12, &r, warp_zero, &ok);
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 205), 3);
    tpk_check_report_free(&r);
}

TPK_TEST(convex_skewed_hex)
{
    /* Near miss: a parallelepiped sheared by 70 deg and stretched 20:1, in mirrored order for one run. */
    double u[3] = {20, 0, 0}, v[3] = {2.75, 1, 0}, w[3] = {-2.5, 0.5, 0.25};
    double p[8][3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            p[i][k] = 100 + cube[i][0] * u[k] + cube[i][1] * v[k] + cube[i][2] * w[k];
    static const int32_t mirrored[8] = {4, 5, 6, 7, 0, 1, 2, 3};
    for (int run = 0; run < 2; run++) {
        tpk_check_report r;
        int ok;
        run_hex(p, run ? mirrored : NULL, 12, &r, warp_zero, &ok);
        CHECK(ok);
        for (int id = 203; id <= 208; id++)
            CHECK_MSG(count_of(&r, id) == (run && id == 204), "run %d check %d", run, id);
        tpk_check_report_free(&r);
    }
}

TPK_TEST(twisted_hexes)
{
    double p[8][3];
    memcpy(p, cube, sizeof cube);
    tpk_check_report r;
    int ok;
    /* Bow-tie top face: nodes 6 and 7 swapped. Faces cross (207), the split folds (208). */
    static const int32_t bowtie[8] = {0, 1, 2, 3, 4, 5, 7, 6};
    run_hex(p, bowtie, 12, &r, NULL, &ok);
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 207), 1);
    CHECK_EQ_INT(count_of(&r, 208), 1);
    CHECK_EQ_INT(count_of(&r, 204), 0);
    tpk_check_report_free(&r);
    /* A corner pushed inside (a dent): non-convex (206), no crossing; the split may or may not fold
     * depending on the diagonals, so only 206 and 207 are asserted. */
    p[6][0] = p[6][1] = p[6][2] = 0.4;
    run_hex(p, NULL, 12, &r, NULL, &ok);
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 206), 1);
    CHECK_EQ_INT(count_of(&r, 207), 0);
    tpk_check_report_free(&r);
    /* A collapsed edge (corners 5 and 6 at one place, distinct ids): flat tets in the split (203, 208). */
    memcpy(p, cube, sizeof cube);
    memcpy(p[6], p[5], sizeof p[5]);
    run_hex(p, NULL, 12, &r, NULL, &ok);
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 203), 1);
    CHECK_EQ_INT(count_of(&r, 208), 1);
    CHECK(strstr(tpk_check_finding(&r, 203)->examples[0].note, "det = 0") != NULL);
    tpk_check_report_free(&r);
}

TPK_TEST(wedge_pyramid_voxel)
{
    double p[8][3];
    memcpy(p, cube, sizeof cube);
    tpk_check_report r;
    int ok;
    static const int32_t wedge[6] = {0, 1, 3, 4, 5, 7}, wedge_mirrored[6] = {4, 5, 7, 0, 1, 3};
    static const int32_t pyramid[5] = {0, 1, 2, 3, 6}, pyramid_flat[5] = {0, 1, 2, 3, 3};
    static const int32_t voxel[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    run_hex(p, wedge, 13, &r, warp_zero, &ok);
    CHECK(ok);
    for (int id = 201; id <= 212; id++)
        CHECK_MSG(count_of(&r, id) == 0, "wedge: check %d", id);
    tpk_check_report_free(&r);
    run_hex(p, wedge_mirrored, 13, &r, NULL, &ok);
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 204), 1);
    tpk_check_report_free(&r);
    run_hex(p, pyramid, 14, &r, warp_zero, &ok);
    CHECK(ok);
    for (int id = 201; id <= 212; id++)
        CHECK_MSG(count_of(&r, id) == 0, "pyramid: check %d", id);
    tpk_check_report_free(&r);
    run_hex(p, pyramid_flat, 14, &r, NULL, &ok); /* apex repeated: 202 only, geometry skipped */
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 202), 1);
    CHECK_EQ_INT(count_of(&r, 203), 0);
    tpk_check_report_free(&r);
    /* Apex in the base plane (distinct vertex): the whole pyramid is flat. */
    double flat[8][3];
    memcpy(flat, cube, sizeof cube);
    flat[6][0] = 0.5, flat[6][1] = 0.5, flat[6][2] = 0;
    run_hex(flat, pyramid, 14, &r, NULL, &ok);
    CHECK(ok);
    CHECK_EQ_INT(count_of(&r, 203), 1);
    CHECK_EQ_INT(count_of(&r, 208), 1);
    tpk_check_report_free(&r);
    run_hex(p, voxel, 11, &r, warp_zero, &ok);
    CHECK(ok);
    for (int id = 201; id <= 212; id++)
        CHECK_MSG(count_of(&r, id) == 0, "voxel: check %d", id);
    tpk_check_report_free(&r);
}

/* ---- determinism ------------------------------------------------------------------------------ */

static int threads_for_run;
static void set_threads(tpk_check_options *o)
{
    o->threads = threads_for_run;
    o->max_examples = 40;
    o->sliver_deg = 30; /* many hits spread over the whole mesh */
}

TPK_TEST(examples_do_not_depend_on_threads)
{
    tpk_mesh m;
    CHECK(import_data("sfepy/cube_big_tetra.mesh", &m) == 0);
    for (int64_t c = 0; c < m.cell_count; c += 997) { /* turn some over, duplicate others */
        int32_t *t = m.cell_conn + m.cell_offsets[c];
        int32_t swap = t[0];
        t[0] = t[1], t[1] = swap;
        if (c + 1 < m.cell_count && c % 3 == 0)
            memcpy(m.cell_conn + m.cell_offsets[c + 1], t, 4 * sizeof *t);
    }
    tpk_check_report base;
    threads_for_run = 1;
    CHECK(run_cells(&m, &base, set_threads) == 0);
    CHECK(count_of(&base, 204) > 100 && count_of(&base, 211) > 30 && count_of(&base, 209) > 40);
    static const int thread_counts[] = {2, 3, 7};
    for (int k = 0; k < 3; k++) {
        tpk_check_report r;
        threads_for_run = thread_counts[k];
        CHECK(run_cells(&m, &r, set_threads) == 0);
        for (int i = 0; i < r.finding_count; i++) {
            const tpk_finding *a = &base.findings[i], *b = &r.findings[i];
            CHECK_EQ_INT(a->count, b->count);
            CHECK_EQ_INT(a->example_count, b->example_count);
            for (int e = 0; e < a->example_count; e++) {
                CHECK_EQ_INT(a->examples[e].ids[0], b->examples[e].ids[0]);
                CHECK(!strcmp(a->examples[e].note, b->examples[e].note));
                if (e)
                    CHECK(a->examples[e].ids[0] >= a->examples[e - 1].ids[0]);
            }
        }
        for (int h = 0; h < r.histogram_count; h++) {
            CHECK(!memcmp(r.histograms[h].bins, base.histograms[h].bins, sizeof r.histograms[h].bins));
            CHECK(r.histograms[h].sum == base.histograms[h].sum); /* summed per chunk, in chunk order */
        }
        tpk_check_report_free(&r);
    }
    tpk_check_report_free(&base);
    tpk_mesh_free(&m);
}

TPK_TEST(nonfinite_corners_are_not_measured)
{
    /* A NaN or infinite coordinate is 101's finding; no orientation or shape can be decided from it. */
    double p[9][3];
    memcpy(p, cube, sizeof cube);
    p[8][0] = NAN, p[8][1] = 0, p[8][2] = INFINITY;
    cell_spec cells[] = {{10, 4, {0, 1, 3, 8}}, {12, 8, {0, 1, 2, 3, 4, 5, 6, 8}}, {10, 4, {0, 1, 3, 4}}};
    tpk_mesh m;
    tpk_check_report r;
    CHECK(build(&m, &p[0][0], 9, cells, 3) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    for (int id = 201; id <= 213; id++)
        CHECK_MSG(count_of(&r, id) == 0, "check %d", id);
    CHECK_EQ_INT(tpk_check_histogram(&r, "radius_ratio", 0, 1)->count, 1);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

/* ---- input convert calls unusable (issue 10 item 6) ------------------------------------------- */

/* 214: no points and no cells, points without cells, and (through the VTK reader, which drops it with a
 * warning) one cell of VTK type 0 are each one 214 error; one tet is not. */
TPK_TEST(no_volume_cells)
{
    static const cell_spec tet = {10, 4, {0, 1, 2, 4}};
    static const int64_t counts[3][2] = {{0, 0}, {8, 0}, {8, 1}};
    for (int k = 0; k < 3; k++) {
        tpk_mesh m;
        tpk_check_report r;
        CHECK(build(&m, &cube[0][0], counts[k][0], &tet, counts[k][1]) == 0);
        CHECK(run_cells(&m, &r, NULL) == 0);
        int64_t found = count_of(&r, 214);
        tpk_check_report_free(&r);
        tpk_mesh_free(&m);
        CHECK_MSG(found == (counts[k][1] ? 0 : 1), "%lld points, %lld cells: 214 x%lld", (long long)counts[k][0],
                  (long long)counts[k][1], (long long)found);
    }
    const char *path = tpk_temp_path("type0.vtk");
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    fprintf(f, "# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
               "0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 1\n0\nCELL_TYPES 1\n0\n");
    fclose(f);
    tpk_check_report r;
    tpk_check_options opt;
    tpk_check_options_default(&opt);
    CHECK(tpk_check_report_init(&r, &opt) == 0);
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_check_path(path, NULL, &r, &diag) == 0, "%s", diag.message);
    const tpk_finding *found = tpk_check_finding(&r, 214);
    int ok = found->count == 1 && found->example_count == 1 && strstr(found->examples[0].note, "none of them 3-D");
    tpk_check_report_free(&r);
    CHECK(ok);
}

/* 215: polyhedra whose points coincide or lie on one line or plane, decided exactly, whatever the order
 * of the points (a repeated position before the one that leaves the line); one with a point off the
 * plane, found last, is not flat. */
TPK_TEST(flat_polyhedron)
{
    static const double points[6][3] = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 1e-300}};
    static const cell_spec cells[4] = {
        {42, 4, {0, 1, 2, 3}},       /* coincident and collinear */
        {42, 4, {0, 1, 2, 4}},       /* coplanar, after a repeated position */
        {42, 6, {0, 1, 2, 3, 4, 5}}, /* 1e-300 off the plane: a volume, exactly */
        {10, 4, {0, 2, 4, 5}},       /* a tet, not a polyhedron: 215 never looks at it */
    };
    tpk_mesh m;
    tpk_check_report r;
    CHECK(build(&m, &points[0][0], 6, cells, 4) == 0);
    CHECK(run_cells(&m, &r, NULL) == 0);
    const tpk_finding *f = tpk_check_finding(&r, 215);
    int ok = f->count == 2 && f->example_count == 2 && f->examples[0].ids[0] == 0 && f->examples[1].ids[0] == 1 &&
             strstr(f->examples[0].note, "one plane") && count_of(&r, 214) == 0;
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
    CHECK(ok);
}
