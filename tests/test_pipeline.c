/* Tests of the converter pipeline stages (tools/convert/pipeline.h) and tpk_recover_tets: exact predicates on
 * constructed degenerate cases, orientation, face matching, layouts, shell and reordering on generated
 * Kuhn grids, and the whole chain on real meshes from ../shared/data. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "harness.h"
#include "import/importers.h"
#include "invariants.h"
#include "meshgen.h"
#include "convert/pipeline.h"
#include "base/predicates.h"

/* ---- helpers -------------------------------------------------------------------------------------- */

static int sign_i128(__int128 x)
{
    return (x > 0) - (x < 0);
}

/* Exact det[b-a, c-a, d-a] for integer coordinates below 2^40 in magnitude. */
static int orient_int(const int64_t a[3], const int64_t b[3], const int64_t c[3], const int64_t d[3])
{
    __int128 bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
    __int128 cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
    __int128 dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
    return sign_i128(bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx));
}

/* The three predicates must agree with each other and with the expected sign; the filter may only
 * abstain (0) or agree. */
static int all_orient_agree(const double a[3], const double b[3], const double c[3], const double d[3],
                            int expected)
{
    int filter = tpk_orient3d_filter(a, b, c, d);
    return tpk_orient3d_exact(a, b, c, d) == expected && tpk_orient3d_cgal(a, b, c, d) == expected &&
           (filter == 0 || filter == expected);
}

static uint64_t rng_state = 12345;
static int64_t rand_range(int64_t lo, int64_t hi)
{
    return lo + (int64_t)(tpk_gen_next(&rng_state) % (uint64_t)(hi - lo + 1));
}

/* Runs orient + connect on a generated or imported mesh and returns neighbors (caller frees). */
static int32_t *orient_connect(tpk_tetmesh *m, int threads, tpk_orient_stats *stats, tpk_diag *diag)
{
    if (tpk_orient(m, 0, 0, stats, diag))
        return NULL;
    int32_t *nb = malloc(sizeof *nb * 4 * (size_t)(m->tet_count + 1));
    if (nb && tpk_connect(m->tets, m->tet_count, m->vertex_count, nb, threads, diag)) {
        free(nb);
        return NULL;
    }
    return nb;
}

/* ---- predicates ----------------------------------------------------------------------------------- */

TPK_TEST(predicates_convention)
{
    double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    /* det[x, y, z] = +1: CGAL::orientation(o,x,y,z) must be POSITIVE under our wrapper. */
    CHECK(all_orient_agree(o, x, y, z, 1));
    CHECK(all_orient_agree(o, x, z, y, -1));
    CHECK(all_orient_agree(x, o, y, z, -1));
    double w[3] = {1, 1, 0};
    CHECK(all_orient_agree(o, x, y, w, 0));
    CHECK(all_orient_agree(o, o, y, z, 0));
}

TPK_TEST(predicates_tiny_height)
{
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    double above[3] = {0.3, 0.7, 1e-300}, below[3] = {0.3, 0.7, -1e-300}, on[3] = {0.3, 0.7, 0};
    CHECK(all_orient_agree(a, b, c, above, 1));
    CHECK(all_orient_agree(a, b, c, below, -1));
    CHECK(all_orient_agree(a, b, c, on, 0));
    double sub[3] = {0.3, 0.7, 4.9e-324}; /* the smallest subnormal */
    CHECK(all_orient_agree(a, b, c, sub, 1));
    /* A tilted plane with large coordinates, apex 1e-300 off it along z. */
    double p[3] = {1e15, 0, 0}, q[3] = {0, 1e15, 0}, r[3] = {1e15, 1e15, 0};
    double s_up[3] = {5e14, 5e14, 1e-300};
    CHECK(all_orient_agree(p, q, r, s_up, -1)); /* (q-p)x(r-p) points along -z */
}

/* Plane x + y + z = 1 through a = (1,0,0), b = (0,1,0), c = (0,0,1): det[b-a, c-a, d-a] = x+y+z-1 exactly,
 * computed here in integers (all coordinates are multiples of 2^-60 below 1). */
TPK_TEST(predicates_plane_last_bit)
{
    double a[3] = {1, 0, 0}, b[3] = {0, 1, 0}, c[3] = {0, 0, 1};
    double on[3] = {0.25, 0.25, 0.5};
    CHECK(all_orient_agree(a, b, c, on, 0));
    double up[3] = {0.25, 0.25, nextafter(0.5, 1)}, down[3] = {0.25, 0.25, nextafter(0.5, 0)};
    CHECK(all_orient_agree(a, b, c, up, 1));
    CHECK(all_orient_agree(a, b, c, down, -1));
    int zeros = 0;
    for (int i = 0; i < 20000; i++) {
        double x = ldexp((double)rand_range(1 << 20, 1 << 29), -31); /* in [2^-11, 2^-2] */
        double y = ldexp((double)rand_range(1 << 20, 1 << 29), -31);
        double z = 1.0 - x - y; /* rounded: on the plane or a few ulps off */
        int wiggle = (int)rand_range(-2, 2);
        for (int k = 0; k < (wiggle < 0 ? -wiggle : wiggle); k++)
            z = nextafter(z, wiggle < 0 ? 0 : 2);
        double d[3] = {x, y, z};
        int64_t sum = (int64_t)ldexp(x, 60) + (int64_t)ldexp(y, 60) + (int64_t)ldexp(z, 60) - ((int64_t)1 << 60);
        CHECK_MSG(ldexp(ldexp(z, 60), -60) == z && fmod(ldexp(z, 60), 1.0) == 0, "z not on 2^-60 grid");
        int expected = (sum > 0) - (sum < 0);
        zeros += expected == 0;
        CHECK_MSG(all_orient_agree(a, b, c, d, expected), "x=%a y=%a z=%a expected %d", x, y, z, expected);
    }
    CHECK(zeros > 1000); /* plenty of exactly coplanar cases were exercised */
}

/* Integer coordinates up to 2^38 (exact in double), exactly coplanar, then one unit off. */
TPK_TEST(predicates_large_coplanar_integers)
{
    for (int i = 0; i < 20000; i++) {
        int64_t a[3], b[3], c[3], d[3];
        const int64_t big = (int64_t)1 << 38;
        for (int k = 0; k < 3; k++) {
            a[k] = rand_range(-big, big);
            b[k] = a[k] + rand_range(-1000000, 1000000);
            c[k] = a[k] + rand_range(-1000000, 1000000);
        }
        int64_t s = rand_range(-50, 50), t = rand_range(-50, 50);
        for (int k = 0; k < 3; k++)
            d[k] = a[k] + s * (b[k] - a[k]) + t * (c[k] - a[k]);
        if (i % 3 == 1)
            d[i % 9 / 3] += 1;
        else if (i % 3 == 2)
            d[i % 9 / 3] -= 1;
        double da[3], db[3], dc[3], dd[3];
        for (int k = 0; k < 3; k++) {
            da[k] = (double)a[k];
            db[k] = (double)b[k];
            dc[k] = (double)c[k];
            dd[k] = (double)d[k];
        }
        int expected = orient_int(a, b, c, d);
        CHECK_MSG(all_orient_agree(da, db, dc, dd, expected), "case %d expected %d", i, expected);
    }
}

/* Coordinates 1e7 + k * 2^-28 (exact doubles; integers after scaling by 2^28). */
TPK_TEST(predicates_huge_offset)
{
    const double offset = 1e7, unit = ldexp(1.0, -28);
    for (int i = 0; i < 20000; i++) {
        int64_t p[4][3];
        for (int k = 0; k < 3; k++) {
            p[0][k] = rand_range(-1000, 1000);
            p[1][k] = p[0][k] + rand_range(-200, 200);
            p[2][k] = p[0][k] + rand_range(-200, 200);
        }
        int64_t s = rand_range(-3, 3), t = rand_range(-3, 3);
        for (int k = 0; k < 3; k++)
            p[3][k] = p[0][k] + s * (p[1][k] - p[0][k]) + t * (p[2][k] - p[0][k]) + (k == i % 3 ? rand_range(-1, 1) : 0);
        double q[4][3];
        int64_t exact[4][3];
        for (int v = 0; v < 4; v++)
            for (int k = 0; k < 3; k++) {
                q[v][k] = offset + (double)p[v][k] * unit;
                exact[v][k] = (int64_t)ldexp(offset, 28) + p[v][k];
                CHECK(ldexp(q[v][k], 28) == (double)exact[v][k]);
            }
        int expected = orient_int(exact[0], exact[1], exact[2], exact[3]);
        CHECK_MSG(all_orient_agree(q[0], q[1], q[2], q[3], expected), "case %d", i);
    }
}

/* Nearly coplanar points from rounding (no closed form): the filtered predicate must equal CGAL. */
TPK_TEST(predicates_filter_matches_cgal)
{
    int uncertain = 0;
    for (int i = 0; i < 50000; i++) {
        double a[3], b[3], c[3], d[3];
        for (int k = 0; k < 3; k++) {
            a[k] = (double)rand_range(-1000000, 1000000) / 7.0;
            b[k] = (double)rand_range(-1000000, 1000000) / 3.0;
            c[k] = (double)rand_range(-1000000, 1000000) / 11.0;
        }
        double s = (double)rand_range(-1000, 1000) / 997.0, t = (double)rand_range(-1000, 1000) / 991.0;
        for (int k = 0; k < 3; k++)
            d[k] = a[k] + s * (b[k] - a[k]) + t * (c[k] - a[k]);
        uncertain += tpk_orient3d_filter(a, b, c, d) == 0;
        CHECK_MSG(all_orient_agree(a, b, c, d, tpk_orient3d_cgal(a, b, c, d)), "case %d", i);
    }
    CHECK(uncertain > 100); /* the exact fallback was exercised */
    double inf[3] = {INFINITY, 0, 0}, o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
    CHECK(tpk_orient3d_filter(o, x, y, inf) == 0);
}

/* ---- orient --------------------------------------------------------------------------------------- */

/* Two tets sharing face (0,1,2): tet 0 positive, tet 1 given inverted; plus extra tets per case. */
static void small_mesh(tpk_tetmesh *m, const int32_t *tets, int tet_count)
{
    static const double pts[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
                                     {0, 0, -1}, {1, 1, 0}, {2, 2, 0}, {0.5, 0.5, 0}};
    memset(m, 0, sizeof *m);
    m->vertex_count = 8;
    m->points = malloc(sizeof pts);
    memcpy(m->points, pts, sizeof pts);
    m->vertex_source = malloc(8 * sizeof *m->vertex_source);
    for (int i = 0; i < 8; i++)
        m->vertex_source[i] = i;
    m->tet_count = tet_count;
    m->tets = malloc(sizeof *m->tets * 4 * (size_t)tet_count);
    memcpy(m->tets, tets, sizeof *m->tets * 4 * (size_t)tet_count);
    m->tet_source = malloc(sizeof *m->tet_source * (size_t)tet_count);
    for (int t = 0; t < tet_count; t++)
        m->tet_source[t] = 100 + t;
    m->step_count = 1;
}

TPK_TEST(orient_fixes_inverted)
{
    int32_t tets[] = {0, 1, 2, 3, 0, 1, 2, 4, 1, 0, 2, 3};
    tpk_tetmesh m;
    small_mesh(&m, tets, 3);
    tpk_orient_stats stats;
    tpk_diag diag = {0};
    CHECK(tpk_orient(&m, 0, 0, &stats, &diag) == 0);
    CHECK_EQ_INT(stats.inverted_fixed, 2);
    CHECK_EQ_INT(stats.degenerate, 0);
    for (int t = 0; t < 3; t++)
        CHECK(tpk_inv_orient(&m, m.tets + 4 * t) > 0);
    CHECK(m.tets[4] == 0 && m.tets[5] == 1 && m.tets[6] == 4 && m.tets[7] == 2); /* v2, v3 swapped */
    tpk_tetmesh_free(&m);
}

TPK_TEST(orient_refuses_degenerate)
{
    /* tet 1 is flat (0,1,2,5 in z = 0), tet 2 repeats vertex 3, tet 3 is flat and collinear-ish. */
    int32_t tets[] = {0, 1, 2, 3, 0, 1, 2, 5, 0, 1, 3, 3, 0, 5, 6, 7};
    tpk_tetmesh m;
    small_mesh(&m, tets, 4);
    tpk_orient_stats stats;
    tpk_diag diag = {0};
    CHECK(tpk_orient(&m, 0, 0, &stats, &diag) != 0);
    CHECK_EQ_INT(stats.degenerate, 3);
    CHECK_EQ_INT(stats.repeated_vertex, 1);
    CHECK_MSG(strstr(diag.message, "cell 101 has zero volume") && strstr(diag.message, "as the file stores them") &&
                  strstr(diag.message, "5 (1, 1, 0)") && strstr(diag.message, "3 degenerate tets") &&
                  strstr(diag.message, "--drop-degenerate"),
              "%s", diag.message);
    tpk_tetmesh_free(&m);

    int32_t repeated[] = {0, 1, 2, 3, 0, 2, 2, 3};
    small_mesh(&m, repeated, 2);
    CHECK(tpk_orient(&m, 0, 0, &stats, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cell 101 has a repeated vertex"), "%s", diag.message);
    tpk_tetmesh_free(&m);
}

TPK_TEST(orient_drops_degenerate)
{
    int32_t tets[] = {0, 1, 2, 3, 0, 1, 2, 5, 0, 1, 3, 3, 0, 1, 2, 4, 0, 5, 6, 7};
    tpk_tetmesh m;
    small_mesh(&m, tets, 5);
    float *values = malloc(2 * 5 * sizeof *values); /* 2 steps */
    for (int i = 0; i < 10; i++)
        values[i] = (float)i;
    m.fields = calloc(1, sizeof *m.fields);
    m.field_count = 1;
    strcpy(m.fields[0].name, "cellvalue");
    m.fields[0].association = TPK_ASSOC_TET;
    m.fields[0].components = 1;
    m.fields[0].step_count = 2;
    m.fields[0].values = values;
    tpk_orient_stats stats;
    tpk_diag diag = {0};
    CHECK(tpk_orient(&m, 1, 0, &stats, &diag) == 0);
    CHECK_EQ_INT(stats.degenerate, 3);
    CHECK_EQ_INT(stats.inverted_fixed, 1);
    CHECK_EQ_INT(m.tet_count, 2);
    CHECK(m.tet_source[0] == 100 && m.tet_source[1] == 103);
    CHECK(values[0] == 0 && values[1] == 3 && values[2] == 5 && values[3] == 8);
    for (int t = 0; t < 2; t++)
        CHECK(tpk_inv_orient(&m, m.tets + 4 * t) > 0);
    tpk_tetmesh_free(&m);
}

/* ---- generated grids: connect, layouts, shell, recovery ------------------------------------------ */

static void check_grid(int n, const tpk_gen_options *opt, int threads)
{
    tpk_tetmesh m;
    tpk_diag diag = {0};
    tpk_orient_stats stats;
    char msg[512] = "";
    CHECK(tpk_gen_kuhn_grid(n, opt, &m) == 0);
    int32_t *nb = orient_connect(&m, threads, &stats, &diag);
    CHECK_MSG(nb, "%s", diag.message);
    CHECK(stats.inverted_fixed > 0 || !opt->scramble_order);
    CHECK_EQ_INT(tpk_count_shell_faces(nb, m.tet_count), 12 * n * n);
    CHECK_MSG(tpk_check_invariants(&m, nb, msg, sizeof msg) == 0, "%s", msg);
    CHECK_MSG(tpk_check_layouts(&m, nb, msg, sizeof msg) == 0, "%s", msg);
    free(nb);
    tpk_tetmesh_free(&m);
}

TPK_TEST(grid_plain)
{
    tpk_gen_options opt = {0};
    check_grid(1, &opt, 1);
    check_grid(4, &opt, 1);
    check_grid(7, &opt, 2);
}

TPK_TEST(grid_relabeled)
{
    for (int seed = 1; seed <= 4; seed++) {
        tpk_gen_options opt = {0.1 * seed, {-3, 5, 1e6}, 1, 1, 1, (uint64_t)seed};
        check_grid(3 + seed, &opt, seed % 3);
        if (tpk_test_failures)
            return;
    }
}

/* Large enough for every stage to split work across threads (orient and reorder use all cores; connect
 * is run with 1..5 threads and must give the same answer each time). */
TPK_TEST(grid_multithreaded)
{
    tpk_gen_options opt = {1, {0, 0, 0}, 1, 1, 1, 99};
    tpk_tetmesh m;
    tpk_diag diag = {0};
    tpk_orient_stats stats;
    char msg[512] = "";
    CHECK(tpk_gen_kuhn_grid(30, &opt, &m) == 0);
    CHECK(tpk_orient(&m, 0, 0, &stats, &diag) == 0);
    CHECK(tpk_reorder(&m, 0, &diag) == 0);
    size_t bytes = sizeof(int32_t) * 4 * (size_t)m.tet_count;
    int32_t *one = malloc(bytes), *other = malloc(bytes);
    CHECK(tpk_connect(m.tets, m.tet_count, m.vertex_count, one, 1, &diag) == 0);
    for (int threads = 0; threads <= 5; threads++) {
        memset(other, 0x55, bytes);
        CHECK(tpk_connect(m.tets, m.tet_count, m.vertex_count, other, threads, &diag) == 0);
        CHECK(!memcmp(one, other, bytes));
    }
    /* In windows of vertex ids (connect's way from 2^20 tets on): the same neighbors. */
    for (int windows = 2; windows <= 5; windows += 3) {
        memset(other, 0x55, bytes);
        CHECK(tpk_connect_windows(m.tets, m.tet_count, m.vertex_count, other, windows, 2, &diag) == 0);
        CHECK(!memcmp(one, other, bytes));
    }
    /* The tets in reverse order, no longer by smallest id (the matcher's general path): the same
     * neighbors, renumbered. */
    int64_t T = m.tet_count, differ = 0;
    int32_t *reversed = malloc(sizeof *reversed * 4 * (size_t)T);
    for (int64_t t = 0; t < T; t++)
        memcpy(reversed + 4 * (T - 1 - t), m.tets + 4 * t, 4 * sizeof *reversed);
    for (int threads = 1; threads <= 3; threads++) {
        CHECK(tpk_connect(reversed, T, m.vertex_count, other, threads, &diag) == 0);
        for (int64_t t = 0; t < T; t++)
            for (int k = 0; k < 4; k++) {
                int32_t n = one[4 * t + k];
                differ += other[4 * (T - 1 - t) + k] != (n < 0 ? -1 : (int32_t)(T - 1 - n));
            }
    }
    CHECK_EQ_INT(differ, 0);
    free(reversed);
    CHECK_EQ_INT(tpk_count_shell_faces(one, m.tet_count), 12 * 30 * 30);
    CHECK_MSG(tpk_check_invariants(&m, one, msg, sizeof msg) == 0, "%s", msg);
    CHECK_MSG(tpk_check_layouts(&m, one, msg, sizeof msg) == 0, "%s", msg);
    free(one);
    free(other);
    tpk_tetmesh_free(&m);
}

TPK_TEST(connect_face_shared_by_three)
{
    /* Three tets on face (12, 40, 77) and one more elsewhere. */
    int32_t tets[] = {1, 2, 3, 4, 12, 40, 77, 5, 77, 12, 40, 9, 40, 77, 12, 130};
    int32_t nb[16];
    tpk_diag diag = {0};
    CHECK(tpk_connect(tets, 4, 200, nb, 2, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "face (12, 40, 77) is shared by 3 tets: 1, 2, 3"), "%s", diag.message);
    /* Those tets by smallest id (1, 5, 9, 12) take the matcher's sorted path; in reverse order the
     * general one, with the same message. */
    int32_t backwards[16];
    for (int t = 0; t < 4; t++)
        memcpy(backwards + 4 * t, tets + 4 * (3 - t), 4 * sizeof *backwards);
    CHECK(tpk_connect(backwards, 4, 200, nb, 2, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "face (12, 40, 77) is shared by 3 tets: 0, 1, 2"), "%s", diag.message);
    int32_t bad[] = {0, 1, 2, 300};
    CHECK(tpk_connect(bad, 1, 200, nb, 1, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "tet 0") && strstr(diag.message, "out of range"), "%s", diag.message);
    int32_t repeated[] = {0, 1, 2, 1};
    CHECK(tpk_connect(repeated, 1, 200, nb, 1, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "repeated"), "%s", diag.message);
}

/* ---- recovery: one order whatever the walk's order and thread count ---------------------------- */

/* The even permutation of positive tet t with the smallest id first, then the smallest of the other
 * three: found among all 24 orders, independently of recover.c's turns. */
static void canonical_ref(const int32_t t[4], int32_t q[4])
{
    static const int perms[24][4] = {
        {0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 1, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {0, 3, 2, 1},
        {1, 0, 2, 3}, {1, 0, 3, 2}, {1, 2, 0, 3}, {1, 2, 3, 0}, {1, 3, 0, 2}, {1, 3, 2, 0},
        {2, 0, 1, 3}, {2, 0, 3, 1}, {2, 1, 0, 3}, {2, 1, 3, 0}, {2, 3, 0, 1}, {2, 3, 1, 0},
        {3, 0, 1, 2}, {3, 0, 2, 1}, {3, 1, 0, 2}, {3, 1, 2, 0}, {3, 2, 0, 1}, {3, 2, 1, 0}};
    for (int p = 0; p < 24; p++) {
        const int *k = perms[p];
        int inversions = 0;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++)
                inversions += k[i] > k[j];
        int32_t c[4] = {t[k[0]], t[k[1]], t[k[2]], t[k[3]]};
        if (inversions % 2 == 0 && c[0] < c[1] && c[0] < c[2] && c[0] < c[3] && c[1] < c[2] && c[1] < c[3]) {
            memcpy(q, c, sizeof c);
            return;
        }
    }
}

TPK_TEST(recover_canonical_any_order_and_threads)
{
    tpk_gen_options opt = {1, {0, 0, 0}, 1, 1, 1, 5};
    tpk_tetmesh m;
    tpk_diag diag = {0};
    tpk_orient_stats stats;
    CHECK(tpk_gen_kuhn_grid(8, &opt, &m) == 0);
    int32_t *nb = orient_connect(&m, 1, &stats, &diag);
    CHECK(nb);
    int64_t T = m.tet_count;
    size_t q4 = sizeof(int32_t) * 4 * (size_t)T;
    int32_t *perm = malloc(sizeof *perm * (size_t)T), *inv = malloc(sizeof *inv * (size_t)T);
    int32_t *tp = malloc(q4), *np = malloc(q4), *want = malloc(q4), *rec = malloc(q4), *first = malloc(q4);
    tpk_tet20 *t20 = malloc(sizeof *t20 * (size_t)T);
    tpk_tet16 *t16 = malloc(sizeof *t16 * (size_t)T);
    uint64_t state = 5;
    for (int order = 0; order < 3; order++) { /* file order, reversed, shuffled */
        for (int64_t i = 0; i < T; i++)
            perm[i] = (int32_t)(order == 1 ? T - 1 - i : i);
        for (int64_t i = T - 1; order == 2 && i > 0; i--) {
            int64_t j = (int64_t)(tpk_gen_next(&state) % (uint64_t)(i + 1));
            int32_t s = perm[i];
            perm[i] = perm[j], perm[j] = s;
        }
        for (int64_t i = 0; i < T; i++)
            inv[perm[i]] = (int32_t)i;
        for (int64_t i = 0; i < T; i++)
            for (int k = 0; k < 4; k++) {
                tp[4 * i + k] = m.tets[4 * (int64_t)perm[i] + k];
                int32_t u = nb[4 * (int64_t)perm[i] + k];
                np[4 * i + k] = u < 0 ? u : inv[u];
            }
        int64_t S = tpk_count_shell_faces(np, T);
        tpk_shell_face *shell = malloc(sizeof *shell * (size_t)S);
        tpk_build_tet20(tp, np, T, t20);
        tpk_build_tet16(tp, np, T, t16);
        tpk_build_shell(tp, np, T, shell);
        for (int64_t i = 0; i < T; i++)
            canonical_ref(tp + 4 * i, want + 4 * i);
        tpk_mesh_arrays arrays = {0};
        arrays.vertex_count = (uint64_t)m.vertex_count;
        arrays.tet_count = (uint64_t)T;
        arrays.shell_face_count = (uint64_t)S;
        arrays.shell = shell;
        arrays.tet20 = t20;
        arrays.tet16 = t16;
        static const int thread_counts[] = {1, 2, 3, 8, 0};
        for (int layout = 16; layout <= 20; layout += 4) {
            arrays.layout = (tpk_layout)layout;
            CHECK(tpk_recover_tets(&arrays, first) == TPK_OK);
            CHECK_MSG(!memcmp(first, want, q4), "order %d Tet%d: not the canonical rotation", order, layout);
            for (int c = 0; c < 5; c++) {
                memset(rec, 0x5a, q4);
                CHECK(tpk_recover_tets_threads(&arrays, rec, thread_counts[c]) == TPK_OK);
                CHECK_MSG(!memcmp(rec, first, q4), "order %d Tet%d, %d threads: other bytes", order, layout,
                          thread_counts[c]);
            }
        }
        free(shell);
    }
    free(perm);
    free(inv);
    free(tp);
    free(np);
    free(want);
    free(rec);
    free(first);
    free(t20);
    free(t16);
    free(nb);
    tpk_tetmesh_free(&m);
}

/* ---- recovery on hostile input -------------------------------------------------------------------- */

TPK_TEST(recover_rejects_damage)
{
    tpk_gen_options opt = {1, {0, 0, 0}, 1, 1, 1, 5};
    tpk_tetmesh m;
    tpk_diag diag = {0};
    tpk_orient_stats stats;
    CHECK(tpk_gen_kuhn_grid(3, &opt, &m) == 0);
    int32_t *nb = orient_connect(&m, 1, &stats, &diag);
    CHECK(nb);
    int64_t T = m.tet_count, S = tpk_count_shell_faces(nb, T);
    tpk_tet20 *t20 = malloc(sizeof *t20 * (size_t)T);
    tpk_tet16 *t16 = malloc(sizeof *t16 * (size_t)T);
    tpk_shell_face *shell = malloc(sizeof *shell * (size_t)S);
    int32_t *rec = malloc(sizeof *rec * 4 * (size_t)T), *rec3 = malloc(sizeof *rec3 * 4 * (size_t)T);
    tpk_build_tet20(m.tets, nb, T, t20);
    tpk_build_tet16(m.tets, nb, T, t16);
    tpk_build_shell(m.tets, nb, T, shell);
    tpk_mesh_arrays arrays = {0};
    arrays.vertex_count = (uint64_t)m.vertex_count;
    arrays.tet_count = (uint64_t)T;
    arrays.shell_face_count = (uint64_t)S;
    arrays.shell = shell;
    arrays.tet20 = t20;
    arrays.tet16 = t16;
    for (int layout = 16; layout <= 20; layout += 4) {
        arrays.layout = (tpk_layout)layout;
        CHECK(tpk_recover_tets(&arrays, rec) == TPK_OK);
        /* Deterministic: a second run gives the same quadruples. */
        int32_t *again = malloc(sizeof *again * 4 * (size_t)T);
        CHECK(tpk_recover_tets(&arrays, again) == TPK_OK);
        CHECK(!memcmp(rec, again, sizeof *again * 4 * (size_t)T));
        free(again);
    }
    /* Fewer shell faces: the unreached part is an error, not a crash. */
    arrays.layout = TPK_LAYOUT_TET20;
    arrays.shell_face_count = 0;
    CHECK(tpk_recover_tets(&arrays, rec) == TPK_ERR_MESH);
    arrays.shell_face_count = (uint64_t)S;
    /* Random single-word damage in each array: any result but a crash; most are caught. */
    uint64_t state = 77;
    int caught = 0, trials = 0;
    for (int i = 0; i < 3000; i++) {
        int layout = i % 2 ? 16 : 20;
        arrays.layout = (tpk_layout)layout;
        int32_t *words = i % 3 == 0 ? (int32_t *)shell : layout == 16 ? (int32_t *)t16 : (int32_t *)t20;
        int64_t count = i % 3 == 0 ? 4 * S : layout == 16 ? 4 * T : 5 * T;
        int64_t at = (int64_t)(tpk_gen_next(&state) % (uint64_t)count);
        int32_t saved = words[at];
        uint64_t r = tpk_gen_next(&state);
        words[at] = r % 4 == 0 ? (int32_t)(r >> 32) : r % 4 == 1 ? -1 : r % 4 == 2 ? saved ^ 1 : (int32_t)(T + 3);
        if (words[at] != saved) {
            trials++;
            tpk_result serial = tpk_recover_tets(&arrays, rec);
            caught += serial != TPK_OK;
            /* Three threads: the same result code (an error reruns the one-thread walk), the same bytes. */
            tpk_result three = tpk_recover_tets_threads(&arrays, rec3, 3);
            CHECK_MSG(three == serial, "damage %d: %s with 3 threads, %s with one", i, tpk_result_string(three),
                      tpk_result_string(serial));
            if (three == TPK_OK && serial == TPK_OK)
                CHECK(!memcmp(rec, rec3, sizeof *rec * 4 * (size_t)T));
        }
        words[at] = saved;
    }
    arrays.layout = TPK_LAYOUT_TET16;
    CHECK(tpk_recover_tets(&arrays, rec) == TPK_OK);
    CHECK_MSG(caught > trials / 2, "caught %d of %d", caught, trials);
    free(rec3);
    free(t20);
    free(t16);
    free(shell);
    free(rec);
    free(nb);
    tpk_tetmesh_free(&m);
}

/* ---- reorder ------------------------------------------------------------------------------------- */

static float coord_value(const double *p)
{
    return (float)(p[0] + 2 * p[1] + 3 * p[2]);
}

static void add_test_fields(tpk_tetmesh *m)
{
    m->fields = calloc(2, sizeof *m->fields);
    m->field_count = 2;
    float *pv = malloc(sizeof *pv * 2 * (size_t)m->vertex_count);
    for (int64_t v = 0; v < m->vertex_count; v++) {
        pv[v] = coord_value(m->points + 3 * v);
        pv[m->vertex_count + v] = -pv[v]; /* step 1 */
    }
    float *tv = malloc(sizeof *tv * (size_t)m->tet_count);
    for (int64_t t = 0; t < m->tet_count; t++)
        tv[t] = (float)m->tet_source[t];
    m->fields[0] = (tpk_src_field){"pointvalue", TPK_ASSOC_POINT, 1, 2, pv};
    m->fields[1] = (tpk_src_field){"tetvalue", TPK_ASSOC_TET, 1, 1, tv};
}

TPK_TEST(reorder_permutes_consistently)
{
    tpk_gen_options opt = {0.5, {10, 20, 30}, 1, 1, 0, 3};
    tpk_tetmesh m, copy, before;
    tpk_diag diag = {0};
    CHECK(tpk_gen_kuhn_grid(9, &opt, &m) == 0);
    CHECK(tpk_gen_kuhn_grid(9, &opt, &before) == 0);
    CHECK(tpk_gen_kuhn_grid(9, &opt, &copy) == 0);
    add_test_fields(&m);
    add_test_fields(&copy);
    CHECK(tpk_reorder(&m, 1, &diag) == 0); /* one thread and two: the same result */
    CHECK(tpk_reorder(&copy, 2, &diag) == 0);
    int64_t V = m.vertex_count, T = m.tet_count;
    /* Deterministic. */
    CHECK(!memcmp(m.tets, copy.tets, sizeof *m.tets * 4 * (size_t)T));
    CHECK(!memcmp(m.points, copy.points, sizeof *m.points * 3 * (size_t)V));
    CHECK(!memcmp(m.tet_source, copy.tet_source, sizeof *m.tet_source * (size_t)T));
    /* vertex_source is a bijection and positions followed it. */
    char *seen = calloc((size_t)V, 1);
    for (int64_t v = 0; v < V; v++) {
        int32_t s = m.vertex_source[v];
        CHECK(s >= 0 && s < V && !seen[s]);
        seen[s] = 1;
        CHECK(!memcmp(m.points + 3 * v, before.points + 3 * (int64_t)s, 3 * sizeof(double)));
        CHECK(m.fields[0].values[v] == coord_value(m.points + 3 * v));
        CHECK(m.fields[0].values[V + v] == -coord_value(m.points + 3 * v));
    }
    /* tet_source is a bijection; each tet has its source tet's vertices, in the same order. */
    memset(seen, 0, (size_t)V);
    char *tet_seen = calloc((size_t)T, 1);
    int32_t *old_index = malloc(sizeof *old_index * (size_t)T); /* source id -> index before */
    for (int64_t t = 0; t < T; t++)
        old_index[before.tet_source[t]] = (int32_t)t;
    for (int64_t t = 0; t < T; t++) {
        int32_t s = m.tet_source[t];
        CHECK(s >= 0 && s < T && !tet_seen[s]);
        tet_seen[s] = 1;
        CHECK(m.fields[1].values[t] == (float)s);
        for (int k = 0; k < 4; k++)
            CHECK(m.vertex_source[m.tets[4 * t + k]] == before.tets[4 * (int64_t)old_index[s] + k]);
    }
    /* Locality: consecutive tets are mostly close (the shuffled input is not). */
    int64_t near = 0;
    for (int64_t t = 1; t < T; t++) {
        const double *a = m.points + 3 * (int64_t)m.tets[4 * t], *b = m.points + 3 * (int64_t)m.tets[4 * t - 4];
        near += fabs(a[0] - b[0]) + fabs(a[1] - b[1]) + fabs(a[2] - b[2]) <= 3 * opt.spacing;
    }
    CHECK_MSG(near > T * 9 / 10, "%lld of %lld consecutive tets near", (long long)near, (long long)T);
    free(seen);
    free(tet_seen);
    free(old_index);
    tpk_tetmesh_free(&m);
    tpk_tetmesh_free(&copy);
    tpk_tetmesh_free(&before);
}

/* The tets after reorder: by smallest vertex, ties in input order, each with its input tet's vertices and
 * cell value (the input index, add_tet_field). */
static int32_t smallest_id(const int32_t *v)
{
    int32_t lo = v[0];
    for (int k = 1; k < 4; k++)
        lo = v[k] < lo ? v[k] : lo;
    return lo;
}

static void check_tets_sorted_stably(const tpk_tetmesh *m, const tpk_tetmesh *before)
{
    int64_t bad = 0, T = m->tet_count;
    int32_t *old_index = malloc(sizeof *old_index * (size_t)T); /* source id -> index before */
    for (int64_t t = 0; t < T; t++)
        old_index[before->tet_source[t]] = (int32_t)t;
    for (int64_t t = 0; t < T; t++) {
        const int32_t *v = m->tets + 4 * t;
        int32_t i = old_index[m->tet_source[t]];
        if (t > 0) {
            int32_t lo = smallest_id(v), prev = smallest_id(v - 4);
            bad += prev > lo || (prev == lo && old_index[m->tet_source[t - 1]] >= i);
        }
        for (int k = 0; k < 4; k++)
            bad += m->vertex_source[v[k]] != before->tets[4 * (int64_t)i + k];
        bad += m->fields[0].values[t] != (float)i;
    }
    CHECK_MSG(bad == 0, "%lld tets out of order or moved wrongly", (long long)bad);
    free(old_index);
}

static void add_tet_field(tpk_tetmesh *m)
{
    m->fields = calloc(1, sizeof *m->fields);
    m->field_count = 1;
    float *tv = malloc(sizeof *tv * (size_t)m->tet_count);
    for (int64_t t = 0; t < m->tet_count; t++)
        tv[t] = (float)t;
    m->fields[0] = (tpk_src_field){"tetvalue", TPK_ASSOC_TET, 1, 1, tv};
}

/* Over 2^21 tets, so the tets are sorted by two workers (and moved in two steps, through coarse
 * ranges): the same tets as on one, in order of their smallest vertex, ties in input order. */
TPK_TEST(reorder_tets_sorted_stably)
{
    tpk_gen_options opt = {1, {0, 0, 0}, 1, 1, 1, 7};
    tpk_tetmesh one, two, before;
    tpk_diag diag = {0};
    CHECK(tpk_gen_kuhn_grid(71, &opt, &one) == 0);
    CHECK(tpk_gen_kuhn_grid(71, &opt, &two) == 0);
    CHECK(tpk_gen_kuhn_grid(71, &opt, &before) == 0);
    CHECK(one.tet_count > (INT64_C(2) << 20));
    add_tet_field(&one);
    add_tet_field(&two);
    CHECK(tpk_reorder(&one, 1, &diag) == 0);
    CHECK(tpk_reorder(&two, 2, &diag) == 0);
    CHECK(!memcmp(one.tets, two.tets, sizeof *one.tets * 4 * (size_t)one.tet_count));
    CHECK(!memcmp(one.tet_source, two.tet_source, sizeof *one.tet_source * (size_t)one.tet_count));
    CHECK(!memcmp(one.fields[0].values, two.fields[0].values, sizeof(float) * (size_t)one.tet_count));
    check_tets_sorted_stably(&one, &before);
    tpk_tetmesh_free(&one);
    tpk_tetmesh_free(&two);
    tpk_tetmesh_free(&before);
}

/* A vertex in 300,000 tets, the smallest id of each (a fan), and a grid beside it: the fan's range is too
 * large for the two-step move's scratch, so the tets are moved in one step, in the same order. */
TPK_TEST(reorder_tets_sorted_stably_fan)
{
    tpk_gen_options opt = {1, {0, 0, 0}, 1, 1, 1, 11};
    tpk_tetmesh grid, m, before;
    tpk_diag diag = {0};
    CHECK(tpk_gen_kuhn_grid(20, &opt, &grid) == 0);
    int64_t fan = 300000, nv = grid.vertex_count + 1 + 3 * fan, nt = grid.tet_count + fan;
    uint64_t rng = 5;
    for (int copy = 0; copy < 2; copy++) {
        tpk_tetmesh *x = copy ? &before : &m;
        memset(x, 0, sizeof *x);
        x->vertex_count = nv, x->tet_count = nt;
        x->points = malloc(sizeof *x->points * 3 * (size_t)nv);
        x->tets = malloc(sizeof *x->tets * 4 * (size_t)nt);
        x->vertex_source = malloc(sizeof *x->vertex_source * (size_t)nv);
        x->tet_source = malloc(sizeof *x->tet_source * (size_t)nt);
        memcpy(x->points, grid.points, sizeof *x->points * 3 * (size_t)grid.vertex_count);
        memcpy(x->tets, grid.tets, sizeof *x->tets * 4 * (size_t)grid.tet_count);
        rng = 5;
        for (int64_t i = 3 * grid.vertex_count; i < 3 * nv; i++)
            x->points[i] = 100.0 * (double)(tpk_gen_next(&rng) >> 11) / 9007199254740992.0;
        for (int a = 0; a < 3; a++) /* the apex at the curve's start: the smallest id of all its tets */
            x->points[3 * grid.vertex_count + a] = -100.0;
        for (int64_t f = 0; f < fan; f++) { /* grid and fan tets interleaved at the start */
            int32_t *v = x->tets + 4 * (grid.tet_count + f);
            int32_t apex = (int32_t)grid.vertex_count, first = apex + 1 + 3 * (int32_t)f;
            v[0] = first, v[1] = apex, v[2] = first + 1, v[3] = first + 2;
        }
        for (int64_t i = 0; i < nv; i++)
            x->vertex_source[i] = (int32_t)i;
        for (int64_t t = 0; t < nt; t++)
            x->tet_source[t] = (int32_t)t;
    }
    add_tet_field(&m);
    CHECK(tpk_reorder(&m, 2, &diag) == 0);
    check_tets_sorted_stably(&m, &before);
    tpk_tetmesh_free(&m);
    tpk_tetmesh_free(&before);
    tpk_tetmesh_free(&grid);
}

/* An id out of range, found as the tets are renumbered: the first one is named, whichever worker sees it
 * (two workers here, a bad id in each one's range, the later one found first by neither). */
TPK_TEST(reorder_names_first_bad_id)
{
    tpk_gen_options opt = {1, {0, 0, 0}, 1, 1, 1, 7};
    for (int threads = 1; threads <= 2; threads++) {
        tpk_tetmesh m;
        tpk_diag diag = {0};
        CHECK(tpk_gen_kuhn_grid(71, &opt, &m) == 0);
        CHECK(m.tet_count > (INT64_C(2) << 20));
        int32_t nv = (int32_t)m.vertex_count;
        m.tets[4 * (m.tet_count - 5) + 1] = -3;
        m.tets[4 * 1000 + 2] = nv;
        CHECK(tpk_reorder(&m, threads, &diag) != 0);
        char want[160];
        snprintf(want, sizeof want, "reorder: tet 1000 names vertex %d; the mesh has %d vertices", nv, nv);
        CHECK_MSG(strstr(diag.message, want) != NULL, "%s", diag.message);
        tpk_tetmesh_free(&m);
    }
}

/* Defined in tools/convert/reorder.c for tests: the Hilbert index of one cell of the 2^21 grid. */
uint64_t tpk_hilbert_key(uint32_t x, uint32_t y, uint32_t z);

/* On a 2^k grid at the origin the keys are exactly 0..8^k-1 and consecutive keys are face neighbors. */
TPK_TEST(reorder_hilbert_curve)
{
    for (int k = 1; k <= 4; k++) {
        int n = 1 << k;
        int64_t cells = (int64_t)n * n * n;
        int32_t *at = malloc(sizeof *at * 3 * (size_t)cells);
        for (int64_t i = 0; i < cells; i++)
            at[3 * i] = -1;
        for (int x = 0; x < n; x++)
            for (int y = 0; y < n; y++)
                for (int z = 0; z < n; z++) {
                    uint64_t key = tpk_hilbert_key((uint32_t)x, (uint32_t)y, (uint32_t)z);
                    CHECK(key < (uint64_t)cells && at[3 * key] == -1);
                    at[3 * key] = x;
                    at[3 * key + 1] = y;
                    at[3 * key + 2] = z;
                }
        for (int64_t i = 1; i < cells; i++)
            CHECK_EQ_INT(abs(at[3 * i] - at[3 * i - 3]) + abs(at[3 * i + 1] - at[3 * i - 2]) +
                             abs(at[3 * i + 2] - at[3 * i - 1]),
                         1);
        free(at);
    }
    CHECK(tpk_hilbert_key(0x1fffff, 0x1fffff, 0x1fffff) < (1ull << 63));
}

/* ---- tetrahedralize ------------------------------------------------------------------------------ */

/* Points of a unit cube; cells: tet, tet, and optionally a hex and a triangle. */
static void source_mesh(tpk_mesh *m, int with_hex, int with_triangle)
{
    static const double pts[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    memset(m, 0, sizeof *m);
    m->point_count = 8;
    m->points = malloc(sizeof pts);
    memcpy(m->points, pts, sizeof pts);
    int cells = 2 + with_hex + with_triangle;
    m->cell_count = cells;
    m->cell_types = malloc((size_t)cells);
    m->cell_offsets = malloc(sizeof *m->cell_offsets * (size_t)(cells + 1));
    m->cell_conn = malloc(sizeof *m->cell_conn * 19);
    int32_t conn[] = {0, 1, 3, 4, 1, 2, 3, 6};
    memcpy(m->cell_conn, conn, sizeof conn);
    int c = 0, at = 8;
    m->cell_types[c] = TPK_CELL_TETRA;
    m->cell_offsets[c++] = 0;
    if (with_triangle) {
        m->cell_types[c] = 5;
        m->cell_offsets[c++] = 4;
        memmove(m->cell_conn + 7, m->cell_conn + 4, 4 * sizeof *conn);
        m->cell_conn[4] = 0;
        m->cell_conn[5] = 1;
        m->cell_conn[6] = 2;
        at = 11;
        m->cell_types[c] = TPK_CELL_TETRA;
        m->cell_offsets[c++] = 7;
    } else {
        m->cell_types[c] = TPK_CELL_TETRA;
        m->cell_offsets[c++] = 4;
    }
    if (with_hex) {
        m->cell_types[c] = TPK_CELL_HEXAHEDRON;
        m->cell_offsets[c++] = at;
        for (int i = 0; i < 8; i++)
            m->cell_conn[at + i] = i;
        at += 8;
    }
    m->cell_offsets[c] = at;
    m->step_count = 2;
    m->times = malloc(2 * sizeof *m->times);
    m->times[0] = 0.5;
    m->times[1] = 1.5;
    float *scalar = malloc(sizeof *scalar * 16), *vec = malloc(sizeof *vec * 48), *cellv = malloc(sizeof *cellv * 8);
    for (int i = 0; i < 16; i++)
        scalar[i] = (float)i;
    for (int i = 0; i < 48; i++)
        vec[i] = (float)(i % 3 + 1) * (i < 24 ? 1.0f : 2.0f); /* (1,2,3) then (2,4,6) */
    for (int i = 0; i < 8; i++)
        cellv[i] = 10.0f * (float)i;
    tpk_mesh_add_field(m, "temperature", TPK_ASSOC_POINT, 1, 2, scalar);
    tpk_mesh_add_field(m, "velocity", TPK_ASSOC_POINT, 3, 2, vec);
    tpk_mesh_add_field(m, "mat_id", TPK_ASSOC_TET, 1, 2, cellv);
}

static void collect_warning(void *user, const char *text)
{
    strncat((char *)user, text, 511 - strlen((char *)user));
}

TPK_TEST(tetrahedralize_default_fields)
{
    tpk_mesh src;
    tpk_tetmesh out;
    char warnings[512] = "";
    tpk_diag diag = {0};
    diag.warn = collect_warning;
    diag.warn_user = warnings;
    source_mesh(&src, 0, 1);
    CHECK_MSG(tpk_tetrahedralize(&src, NULL, 0, 0, &out, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(out.tet_count, 2);
    CHECK_EQ_INT(out.vertex_count, 8);
    CHECK(out.tet_source[0] == 0 && out.tet_source[1] == 2); /* the triangle (cell 1) is skipped */
    CHECK(!memcmp(out.tets, (int32_t[]){0, 1, 3, 4, 1, 2, 3, 6}, 8 * sizeof(int32_t)));
    CHECK(out.vertex_source[5] == 5);
    CHECK(out.step_count == 2 && out.times && out.times[1] == 1.5);
    CHECK_EQ_INT(out.field_count, 1);
    CHECK(!strcmp(out.fields[0].name, "temperature") && out.fields[0].step_count == 2);
    CHECK(out.fields[0].values[8 + 3] == 11.0f);
    CHECK_MSG(strstr(warnings, "'velocity'") && strstr(warnings, "dimension < 3"), "%s", warnings);
    tpk_tetmesh_free(&out);
    tpk_mesh_free(&src);
}

TPK_TEST(tetrahedralize_selected_fields)
{
    tpk_mesh src;
    tpk_tetmesh out;
    tpk_diag diag = {0};
    source_mesh(&src, 0, 0);
    const char *names[] = {"velocity:mag", "velocity:y", "mat_id", "temperature"};
    CHECK_MSG(tpk_tetrahedralize(&src, names, 4, 0, &out, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(out.field_count, 4);
    CHECK(!strcmp(out.fields[0].name, "velocity_mag") && out.fields[0].association == TPK_ASSOC_POINT);
    CHECK(fabsf(out.fields[0].values[0] - sqrtf(14.0f)) < 1e-6f);
    CHECK(fabsf(out.fields[0].values[8] - sqrtf(56.0f)) < 1e-5f);
    CHECK(!strcmp(out.fields[1].name, "velocity_y") && out.fields[1].values[0] == 2.0f &&
          out.fields[1].values[9] == 4.0f);
    CHECK(!strcmp(out.fields[2].name, "mat_id") && out.fields[2].association == TPK_ASSOC_TET);
    CHECK(out.fields[2].step_count == 2 && out.fields[2].values[1] == 10.0f && out.fields[2].values[3] == 30.0f);
    CHECK(out.fields[3].components == 1 && out.fields[3].values[15] == 15.0f);
    tpk_tetmesh_free(&out);

    const char *missing[] = {"pressure"};
    CHECK(tpk_tetrahedralize(&src, missing, 1, 0, &out, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "'pressure'") && strstr(diag.message, "temperature (point)") &&
                  strstr(diag.message, "velocity (point, vector)") && strstr(diag.message, "mat_id (cell)"),
              "%s", diag.message);
    const char *vector[] = {"velocity"};
    CHECK(tpk_tetrahedralize(&src, vector, 1, 0, &out, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "velocity:mag"), "%s", diag.message);
    const char *selector[] = {"velocity:w"};
    CHECK(tpk_tetrahedralize(&src, selector, 1, 0, &out, &diag) != 0);
    CHECK_MSG(strstr(diag.message, ":w"), "%s", diag.message);
    tpk_mesh_free(&src);
}

TPK_TEST(tetrahedralize_refuses_other_cells)
{
    tpk_mesh src;
    tpk_tetmesh out;
    tpk_diag diag = {0};
    source_mesh(&src, 1, 0);
    src.cell_types[2] = 15; /* the 8 corners as a pentagonal prism's first 8 of 10: refused by type */
    CHECK(tpk_tetrahedralize(&src, NULL, 0, 0, &out, &diag) != 0);
    CHECK_MSG(!strcmp(diag.message, "cell 2 is a pentagonal prism (VTK type 15); this converter splits tetra, "
                                    "voxels, hexahedra, wedges, pyramids and polyhedra"),
              "%s", diag.message);
    src.cell_types[2] = TPK_CELL_HEXAHEDRON;
    CHECK(out.tets == NULL && out.tet_count == 0);
    src.cell_conn[2] = 8; /* out of range */
    CHECK(tpk_tetrahedralize(&src, NULL, 0, 0, &out, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cell 0 names point 8"), "%s", diag.message);
    tpk_mesh_free(&src);
}

/* ---- real meshes ---------------------------------------------------------------------------------- */

/* Import, tetrahedralize (with `fields`), orient, reorder, connect; check every invariant and layout.
 * Returns the orient stats through *stats; tet_count expected (or -1 to skip). */
static void run_chain(const char *relative, const char *const *fields, int field_count, int64_t tets,
                      int drop, tpk_orient_stats *stats, tpk_tetmesh *out)
{
    tpk_mesh src;
    tpk_diag diag = {0};
    char msg[512] = "";
    memset(out, 0, sizeof *out);
    CHECK_MSG(tpk_import_any(tpk_data_path(relative), NULL, &src, &diag) == 0, "%s", diag.message);
    CHECK_MSG(tpk_tetrahedralize(&src, fields, field_count, 0, out, &diag) == 0, "%s", diag.message);
    tpk_mesh_free(&src);
    if (tets >= 0)
        CHECK_EQ_INT(out->tet_count, tets);
    CHECK_MSG(tpk_orient(out, drop, 0, stats, &diag) == 0, "%s", diag.message);
    CHECK_MSG(tpk_reorder(out, 0, &diag) == 0, "%s", diag.message);
    int32_t *nb = malloc(sizeof *nb * 4 * (size_t)out->tet_count);
    CHECK_MSG(tpk_connect(out->tets, out->tet_count, out->vertex_count, nb, 0, &diag) == 0, "%s",
              diag.message);
    int rc = tpk_check_invariants(out, nb, msg, sizeof msg);
    if (rc == 0)
        rc = tpk_check_layouts(out, nb, msg, sizeof msg);
    free(nb);
    CHECK_MSG(rc == 0, "%s: %s", relative, msg);
}

TPK_TEST(real_cylinder)
{
    tpk_tetmesh m;
    tpk_orient_stats stats;
    const char *fields[] = {"mat_id"};
    run_chain("sfepy/cylinder.vtk", fields, 1, 1348, 0, &stats, &m);
    CHECK_EQ_INT(stats.degenerate, 0);
    CHECK(m.field_count == 1 && m.fields[0].association == TPK_ASSOC_TET);
    tpk_tetmesh_free(&m);
}

/* The layouts are built four tets at a time where SSE2 is, one at a time for the rest: any start and
 * count (every remainder, unaligned starts) gives the records of one build over the whole mesh. */
TPK_TEST(layouts_in_pieces_match_whole)
{
    tpk_tetmesh m;
    tpk_orient_stats stats;
    tpk_diag diag = {0};
    run_chain("sfepy/cylinder.vtk", NULL, 0, 1348, 0, &stats, &m);
    int32_t *nb = malloc(sizeof *nb * 4 * (size_t)m.tet_count);
    CHECK_MSG(nb && tpk_connect(m.tets, m.tet_count, m.vertex_count, nb, 0, &diag) == 0, "%s", diag.message);
    int64_t T = m.tet_count;
    tpk_tet20 *w20 = malloc(sizeof *w20 * (size_t)T), p20[16];
    tpk_tet16 *w16 = malloc(sizeof *w16 * (size_t)T), p16[16];
    tpk_build_tet20(m.tets, nb, T, w20);
    tpk_build_tet16(m.tets, nb, T, w16);
    for (int64_t start = 0; start < 7; start++)
        for (int64_t count = 0; count <= 13; count++) {
            int64_t s = T - 13 - start; /* ending at or just before the last tet too */
            int64_t first[2] = {start, s};
            for (int f = 0; f < 2; f++) {
                tpk_build_tet20(m.tets + 4 * first[f], nb + 4 * first[f], count, p20);
                tpk_build_tet16(m.tets + 4 * first[f], nb + 4 * first[f], count, p16);
                CHECK_MSG(!memcmp(p20, w20 + first[f], sizeof *p20 * (size_t)count) &&
                              !memcmp(p16, w16 + first[f], sizeof *p16 * (size_t)count),
                          "tets %lld + %lld: other records than the whole build's", (long long)first[f],
                          (long long)count);
            }
        }
    /* Ids near INT32_MAX order as signed ints do: a tet renumbered high keeps its ranks. */
    int32_t high[16], hn[16];
    for (int k = 0; k < 16; k++)
        high[k] = INT32_MAX - 3 * k, hn[k] = k % 5 == 0 ? -1 : INT32_MAX - k;
    tpk_tet20 h20[4];
    tpk_tet16 h16[4];
    tpk_build_tet20(high, hn, 4, h20);
    tpk_build_tet16(high, hn, 4, h16);
    for (int t = 0; t < 4; t++)
        for (int k = 0; k < 4; k++) {
            int rank = 0;
            for (int j = 0; j < 4; j++)
                rank += high[4 * t + j] < high[4 * t + k];
            CHECK(h20[t].n[rank] == hn[4 * t + k]);
            CHECK(rank == 3 || h16[t].nx[rank] == (hn[4 * t + k] ^ h20[t].n[3]));
        }
    free(w20);
    free(w16);
    free(nb);
    tpk_tetmesh_free(&m);
}

TPK_TEST(real_hinge)
{
    tpk_tetmesh m;
    tpk_orient_stats stats;
    run_chain("tetgen/hinge_small", NULL, 0, 14487, 0, &stats, &m);
    CHECK_EQ_INT(stats.degenerate, 0);
    tpk_tetmesh_free(&m);
}

/* Every 10th cell of cylinder.vtk had nodes 0 and 1 swapped; cell field is_inverted marks them. */
TPK_TEST(real_inverted_tets)
{
    tpk_tetmesh m;
    tpk_orient_stats stats;
    const char *fields[] = {"is_inverted"};
    run_chain("hard/inverted_tets.vtk", fields, 1, 1348, 0, &stats, &m);
    CHECK_EQ_INT(stats.inverted_fixed, 135);
    int64_t marked = 0;
    for (int64_t t = 0; t < m.tet_count; t++) {
        marked += m.fields[0].values[t] == 1.0f;
        CHECK(m.fields[0].values[t] == (m.tet_source[t] % 10 == 0 ? 1.0f : 0.0f));
    }
    CHECK_EQ_INT(marked, 135);
    tpk_tetmesh_free(&m);
}

/* elbow.mesh with 20 tets given a repeated node (cell field degenerate_kind = 1) and 20 given a 4th
 * node "moved onto their base plane" (kind 2). The kind-2 nodes were computed in floating point,
 * (a+b+d)/3 + 0.1(b-a), so they are not exactly coplanar: exact rational arithmetic (Python Fraction on
 * the file's doubles) gives nonzero determinants for all 20 (9 negative, 11 positive, |det| ~ 1e-22).
 * Exact predicates therefore find 20 degenerate tets, not 40; the kind-2 slivers are kept. The 9 negative
 * ones, once made positive, lie on the same side of their base face as the neighbor across it: real
 * overlaps, which connect does not judge (the validator does); the test counts them. */
TPK_TEST(real_degenerate_tets)
{
    tpk_mesh src;
    tpk_tetmesh m;
    tpk_diag diag = {0};
    tpk_orient_stats stats;
    const char *fields[] = {"degenerate_kind"};
    CHECK_MSG(tpk_import_any(tpk_data_path("hard/degenerate_tets.vtk"), NULL, &src, &diag) == 0, "%s",
              diag.message);
    CHECK_MSG(tpk_tetrahedralize(&src, fields, 1, 0, &m, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(m.tet_count, 8161);
    float *kind = malloc(sizeof *kind * (size_t)m.tet_count);
    memcpy(kind, m.fields[0].values, sizeof *kind * (size_t)m.tet_count);
    int32_t first = -1;
    int64_t kinds[3] = {0, 0, 0};
    for (int64_t t = 0; t < m.tet_count; t++) {
        if (kind[t] == 1 && first < 0)
            first = (int32_t)t;
        kinds[(int)kind[t]]++;
    }
    CHECK(kinds[1] == 20 && kinds[2] == 20);
    CHECK(tpk_orient(&m, 0, 0, &stats, &diag) != 0);
    char expect[64];
    snprintf(expect, sizeof expect, "cell %d has a repeated vertex", first);
    CHECK_MSG(strstr(diag.message, expect) && strstr(diag.message, "20 degenerate tets in all") &&
                  strstr(diag.message, "--drop-degenerate"),
              "%s", diag.message);
    CHECK_EQ_INT(stats.repeated_vertex, 20);
    CHECK_EQ_INT(stats.degenerate, 20);
    tpk_tetmesh_free(&m);

    CHECK_MSG(tpk_tetrahedralize(&src, fields, 1, 0, &m, &diag) == 0, "%s", diag.message);
    tpk_mesh_free(&src);
    CHECK(tpk_orient(&m, 1, 0, &stats, &diag) == 0);
    CHECK_EQ_INT(stats.degenerate, 20);
    CHECK_EQ_INT(m.tet_count, 8161 - 20);
    int64_t slivers = 0;
    for (int64_t t = 0; t < m.tet_count; t++) {
        CHECK(m.fields[0].values[t] != 1.0f && kind[m.tet_source[t]] == m.fields[0].values[t]);
        slivers += m.fields[0].values[t] == 2.0f;
    }
    CHECK_EQ_INT(slivers, 20);
    free(kind);
    int32_t *nb = malloc(sizeof *nb * 4 * (size_t)m.tet_count);
    char msg[512] = "";
    CHECK(tpk_reorder(&m, 0, &diag) == 0);
    CHECK_MSG(tpk_connect(m.tets, m.tet_count, m.vertex_count, nb, 2, &diag) == 0, "%s", diag.message);
    /* No layout check: recovering Tet20/Tet16 orientation by walking assumes no overlaps. */
    int rc = tpk_check_invariants_flags(&m, nb, TPK_INV_ALLOW_SAME_SIDE, msg, sizeof msg);
    int64_t first_overlap, overlaps = tpk_count_same_side_pairs(&m, nb, &first_overlap);
    /* The overlapping pair is a sliver and its neighbor; which of the two has the lower id depends on
     * the tet order, so look at both. */
    int sliver_in_pair = overlaps > 0 && m.fields[0].values[first_overlap] == 2.0f;
    for (int k = 0; overlaps > 0 && k < 4; k++) {
        int32_t u = nb[4 * first_overlap + k];
        sliver_in_pair |= u >= 0 && m.fields[0].values[u] == 2.0f;
    }
    free(nb);
    CHECK_MSG(rc == 0, "%s", msg);
    CHECK_EQ_INT(overlaps, 9);
    CHECK(sliver_in_pair);
    tpk_tetmesh_free(&m);
}
