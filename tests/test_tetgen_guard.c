/* TetGen kept from crashing or hanging tetpack (mesher/tetgen_guard.h, mesher.h): inputs that crash
 * TetGen in-process (issue 10) end as an error code and message from its child process; point sets
 * that span no volume or hold coordinates beyond TetGen's arithmetic are refused before it starts,
 * decided exactly; a volume bound estimated to make too many tets is refused naming --max-tets; the
 * child's result is the in-process result, byte for byte; its memory and time are bounded. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "import/surface/surface.h"
#include "mesher/mesher.h"
#include "mesher/tetgen_guard.h"

static int without_tetgen(void)
{
    tpk_diag diag = {0};
    if (tpk_tetgen_available("test", &diag) == 0)
        return 0;
    fprintf(stderr, "built without TetGen: %s\n", diag.message);
    return 1;
}

#define REQUIRE_TETGEN()      \
    do {                      \
        if (without_tetgen()) \
            return;           \
    } while (0)

/* The unit cube: corner (x, y, z) is point 4x + 2y + z; six outward quads. */
static const int32_t cube_quads[24] = {0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4, 1, 5, 7, 3};
static const int64_t cube_offsets[7] = {0, 4, 8, 12, 16, 20, 24};

static void cube_points(double scale, double *p)
{
    for (int i = 0; i < 8; i++)
        p[3 * i] = scale * (i >> 2), p[3 * i + 1] = scale * ((i >> 1) & 1), p[3 * i + 2] = scale * (i & 1);
}

/* The cube as the surface readers produce it (owned arrays: tpk_surface_tetrahedralize frees them). */
static void cube_surface(double scale, tpk_mesh *m)
{
    memset(m, 0, sizeof *m);
    m->point_count = 8, m->cell_count = 6;
    m->points = malloc(sizeof(double) * 24);
    m->cell_types = malloc(6);
    m->cell_offsets = malloc(sizeof cube_offsets);
    m->cell_conn = malloc(sizeof cube_quads);
    cube_points(scale, m->points);
    memset(m->cell_types, TPK_CELL_SURF_POLYGON, 6);
    memcpy(m->cell_offsets, cube_offsets, sizeof cube_offsets);
    memcpy(m->cell_conn, cube_quads, sizeof cube_quads);
    strcpy(m->format, "test-cube");
}

static int refused(const double *p, int64_t n, const char *needle, char *msg, size_t cap)
{
    tpk_diag diag = {0};
    int rc = tpk_tetgen_check_points("pts", p, n, &diag);
    snprintf(msg, cap, "%s", diag.message);
    return rc != 0 && strstr(diag.message, "pts: ") == diag.message && strstr(diag.message, needle);
}

TPK_TEST(degenerate_point_sets_refused)
{
    double p[3 * 20];
    char msg[1024];
    for (int i = 0; i < 20; i++) /* issue 10: 20 collinear points i,i,i */
        p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = i;
    CHECK_MSG(refused(p, 20, "all 20 points lie on one line", msg, sizeof msg), "%s", msg);
    for (int i = 0; i < 20; i++)
        p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = 0.5;
    CHECK_MSG(refused(p, 20, "are the same point", msg, sizeof msg), "%s", msg);
    /* Exactly on the plane z = x/2 + y/4 (dyadic coordinates: no rounding anywhere). */
    for (int i = 0; i < 20; i++) {
        p[3 * i] = (i * 7 % 13) / 8.0, p[3 * i + 1] = (i * 5 % 11) / 16.0;
        p[3 * i + 2] = p[3 * i] / 2 + p[3 * i + 1] / 4;
    }
    CHECK_MSG(refused(p, 20, "lie on one plane", msg, sizeof msg), "%s", msg);
    /* One point 2^-60 off that plane is a real tetrahedron: exact, no tolerance. */
    CHECK(p[2] == 0);
    p[2] = ldexp(1.0, -60); /* point 0 is (0, 0, 0) */
    tpk_diag diag = {0};
    CHECK_MSG(tpk_tetgen_check_points("pts", p, 20, &diag) == 0, "%s", diag.message);
}

TPK_TEST(coordinate_range_refused)
{
    char msg[1024];
    double p[3 * 11];
    cube_points(1.0, p);
    p[24] = 0.5, p[25] = 0.5, p[26] = 0.5;
    /* issue 10: 1e-300 among normal points is fine for TetGen; 1e300 is not. */
    p[27] = 1e-300, p[28] = 0.25, p[29] = 0.5;
    tpk_diag diag = {0};
    CHECK_MSG(tpk_tetgen_check_points("pts", p, 10, &diag) == 0, "%s", diag.message);
    p[30] = 1e300, p[31] = 0.25, p[32] = 0.5;
    CHECK_MSG(refused(p, 11, "point 10 has coordinate 1.0000000000000001e+300", msg, sizeof msg), "%s", msg);
    CHECK_MSG(strstr(msg, "1e+50"), "%s", msg);
    cube_points(1e60, p);
    CHECK_MSG(refused(p, 8, "point 4 has coordinate 9.99", msg, sizeof msg), "%s", msg);
    cube_points(1e-60, p);
    CHECK_MSG(refused(p, 8, "span at most 1e-60", msg, sizeof msg), "%s", msg);
    cube_points(1e45, p); /* inside both limits */
    CHECK_MSG(tpk_tetgen_check_points("pts", p, 8, &diag) == 0, "%s", diag.message);
}

TPK_TEST(tet_estimate_names_max_tets)
{
    tpk_mesh cube;
    cube_surface(2.0, &cube);
    CHECK(fabs(tpk_surface_enclosed_volume(&cube) - 8.0) < 1e-12);
    tpk_diag diag = {0};
    /* 8 / 0.01 * 2 = 1600 tets. */
    CHECK(tpk_tetgen_check_tet_estimate("cube", &cube, "p180zQq1.414a0.01", 1000, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cube: ") && strstr(diag.message, "about 1.6e+03 tets") &&
              strstr(diag.message, "limit of 1000") && strstr(diag.message, "--max-tets"), "%s", diag.message);
    CHECK(tpk_tetgen_check_tet_estimate("cube", &cube, "p180zQq1.414a0.01", 2000, &diag) == 0);
    CHECK(tpk_tetgen_check_tet_estimate("cube", &cube, "p180zQq1.414", 1, &diag) == 0); /* no bound */
    /* The last 'a' counts, as in TetGen; the default limit is 10 million. */
    CHECK(tpk_tetgen_check_tet_estimate("cube", &cube, "p180zQa1e-9a1", 0, &diag) == 0);
    CHECK(tpk_tetgen_check_tet_estimate("cube", &cube, "p180zQa1a1e-9", 0, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "limit of 10000000"), "%s", diag.message);
    tpk_mesh_free(&cube);
}

static tpk_tetgen_guard guard_for(const char *what)
{
    tpk_tetgen_guard g = {what, 600, 0, 0};
    return g;
}

/* issue 10: TetGen crashes on these in-process (SIGSEGV in its memory pools after failing on collinear
 * points; an assert on a cube scaled by 1e300). In the child it is a code and a message. */
TPK_TEST(child_crash_is_an_error)
{
    REQUIRE_TETGEN();
    double line[3 * 20], big[24];
    for (int i = 0; i < 20; i++)
        line[3 * i] = line[3 * i + 1] = line[3 * i + 2] = i;
    tpk_tetgen_input in = {20, line, 0, NULL, NULL};
    tpk_tetgen_guard g = guard_for("meshing a line");
    tpk_tetgen_output out;
    char msg[1024];
    int code = tpk_tetgen_run_guarded("zQ", &in, &g, &out, msg, sizeof msg);
    CHECK_EQ_INT(code, TPK_TETGEN_CRASHED);
    /* Under AddressSanitizer its SEGV handler ends the child with status 1 instead of the signal. */
    CHECK_MSG(strstr(msg, "TetGen crashed (") && strstr(msg, "while meshing a line") &&
              (strstr(msg, "signal 11, SIGSEGV") || strstr(msg, "exited with status")), "%s", msg);
    CHECK(out.points == NULL && out.tets == NULL && out.point_count == 0);
    cube_points(1e300, big);
    tpk_tetgen_input surface = {8, big, 6, cube_offsets, cube_quads};
    code = tpk_tetgen_run_guarded("p180zQq1.414", &surface, &g, &out, msg, sizeof msg);
    CHECK_EQ_INT(code, TPK_TETGEN_CRASHED);
    CHECK_MSG(strstr(msg, "signal 6, SIGABRT") && strstr(msg, "it said: ") && strstr(msg, "Assertion"), "%s", msg);
}

/* The child's result crosses the process boundary intact: the same points and tets as in-process. */
TPK_TEST(child_result_matches_in_process)
{
    REQUIRE_TETGEN();
    double p[24];
    cube_points(1.0, p);
    tpk_tetgen_input in = {8, p, 6, cube_offsets, cube_quads};
    tpk_tetgen_output direct, child;
    tpk_tetgen_guard g = guard_for("meshing a cube");
    char msg[1024];
    CHECK(tpk_tetgen_run("p180zQq1.2a0.01", &in, &direct, msg, sizeof msg) == 0);
    CHECK_MSG(tpk_tetgen_run_guarded("p180zQq1.2a0.01", &in, &g, &child, msg, sizeof msg) == 0, "%s", msg);
    CHECK(direct.tet_count > 100);
    CHECK_EQ_INT(child.point_count, direct.point_count);
    CHECK_EQ_INT(child.tet_count, direct.tet_count);
    CHECK(!memcmp(child.points, direct.points, sizeof(double) * 3 * (size_t)direct.point_count));
    CHECK(!memcmp(child.tets, direct.tets, sizeof(int32_t) * 4 * (size_t)direct.tet_count));
    tpk_tetgen_output_free(&direct);
    tpk_tetgen_output_free(&child);
}

/* A run past its time limit is stopped (a hang guard: the run would take far longer than the limit). */
TPK_TEST(child_time_limit)
{
    REQUIRE_TETGEN();
    double p[24];
    cube_points(1.0, p);
    tpk_tetgen_input in = {8, p, 6, cube_offsets, cube_quads};
    tpk_tetgen_guard g = {"meshing a fine cube", 0.2, 0, 0};
    tpk_tetgen_output out;
    char msg[1024];
    int code = tpk_tetgen_run_guarded("p180zQq1.414a1e-8", &in, &g, &out, msg, sizeof msg);
    CHECK_EQ_INT(code, TPK_TETGEN_TIMED_OUT);
    CHECK_MSG(strstr(msg, "time limit of 0.2 s while meshing a fine cube") && strstr(msg, "--tetgen-time-limit"),
              "%s", msg);
}

/* The child's address space is bounded: TetGen runs out of memory with a message saying so. */
TPK_TEST(child_memory_limit)
{
    REQUIRE_TETGEN();
    if (TPK_ASAN) {
        fprintf(stderr, "AddressSanitizer build: RLIMIT_AS is not applied, nothing to test\n");
        return;
    }
    tpk_mesh cube;
    cube_surface(1.0, &cube);
    tpk_tetgen_options o = {0};
    o.max_volume = 1e-7, o.max_tets = 100000000, o.memory_limit = INT64_C(128) << 20;
    tpk_mesh out;
    tpk_diag diag = {0};
    CHECK(tpk_surface_tetrahedralize("cube", &cube, &o, &out, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cube: ") && strstr(diag.message, "out of memory") &&
              strstr(diag.message, "at most 0.125 GiB"), "%s", diag.message);
}
