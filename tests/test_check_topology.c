/* The connectivity (3xx) and shell (4xx) checks of `tetpack check`: face tables against exact
 * orientation, small in-memory meshes with exact counts, the hard real meshes (hanging nodes,
 * non-manifold cubes, two components) with counts derived from how they were made, clean real meshes,
 * and results that do not depend on the thread count. */
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "check/check_topo.h"
#include "harness.h"
#include "convert/pipeline.h"

static const int TOPO_IDS[] = {301, 302, 303, 304, 305, 401, 402, 403, 404, 405, 406};
#define TOPO_ID_COUNT ((int)(sizeof TOPO_IDS / sizeof TOPO_IDS[0]))

static int64_t count_of(tpk_check_report *r, int id)
{
    return tpk_check_finding(r, id)->count;
}

/* A mesh from literal arrays: `nodes` per cell given by `types` (all cells listed back to back). */
static void make_mesh(tpk_mesh *m, const double *pts, int npts, const uint8_t *types, const int32_t *conn,
                      int ncells)
{
    memset(m, 0, sizeof *m);
    m->point_count = npts;
    m->points = malloc(sizeof(double) * 3 * (size_t)npts);
    memcpy(m->points, pts, sizeof(double) * 3 * (size_t)npts);
    m->cell_count = ncells;
    m->cell_types = malloc((size_t)ncells);
    m->cell_offsets = malloc(sizeof(int64_t) * (size_t)(ncells + 1));
    int64_t at = 0;
    for (int c = 0; c < ncells; c++) {
        m->cell_types[c] = types[c];
        m->cell_offsets[c] = at;
        at += types[c] == 10 ? 4 : types[c] == 14 ? 5 : types[c] == 13 ? 6 : 8;
    }
    m->cell_offsets[ncells] = at;
    m->cell_conn = malloc(sizeof(int32_t) * (size_t)(at ? at : 1));
    memcpy(m->cell_conn, conn, sizeof(int32_t) * (size_t)at);
}

static int run_topology(tpk_mesh *m, int threads, tpk_check_report *r)
{
    tpk_check_options options;
    tpk_check_options_default(&options);
    options.threads = threads;
    if (tpk_check_report_init(r, &options))
        return -1;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    tpk_check_input in = {m, "memory", NULL};
    return tpk_check_topology(&in, r, &diag);
}

static int run_path(const char *path, int threads, tpk_check_report *r)
{
    tpk_check_options options;
    tpk_check_options_default(&options);
    options.threads = threads;
    if (tpk_check_report_init(r, &options))
        return -1;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = tpk_check_path(path, NULL, r, &diag);
    if (rc)
        fprintf(stderr, "%s: %s\n", path, diag.message);
    return rc;
}

/* Every count of 3xx/4xx except those listed in `allowed` is 0. Returns the first offending id or 0. */
static int others_zero(tpk_check_report *r, const int *allowed, int n)
{
    for (int i = 0; i < TOPO_ID_COUNT; i++) {
        int ok = 0;
        for (int j = 0; j < n; j++)
            ok |= allowed[j] == TOPO_IDS[i];
        if (!ok && count_of(r, TOPO_IDS[i]) != 0)
            return TOPO_IDS[i];
    }
    return 0;
}

static const double CUBE[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* Each face of a positive reference cell faces away from the cell's centre (exact orientation). */
TPK_TEST(face_tables_outward)
{
    static const double wedge[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    static const double voxel[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
    static const double tet[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    struct { uint8_t type; int nodes, faces; const double (*p)[3]; } shapes[] = {
        {10, 4, 4, tet}, {11, 8, 6, voxel}, {12, 8, 6, CUBE}, {13, 6, 5, wedge}, {14, 5, 5, CUBE}};
    for (int s = 0; s < 5; s++) {
        double pts[9][3];
        int32_t conn[8];
        int n = shapes[s].nodes;
        memcpy(pts, shapes[s].p, sizeof(double) * 3 * (size_t)n);
        if (shapes[s].type == 14) { /* pyramid: the unit square and an apex above it */
            pts[4][0] = 0.5;
            pts[4][1] = 0.5;
            pts[4][2] = 1;
        }
        double centre[3] = {0, 0, 0};
        for (int i = 0; i < n; i++) {
            conn[i] = i;
            for (int k = 0; k < 3; k++)
                centre[k] += pts[i][k] / n;
        }
        memcpy(pts[n], centre, sizeof centre);
        tpk_mesh m;
        make_mesh(&m, &pts[0][0], n + 1, &shapes[s].type, conn, 1);
        tpk_topo_face faces[TPK_TOPO_MAX_CELL_FACES];
        CHECK_EQ_INT(tpk_topo_cell_faces(&m, 0, faces), shapes[s].faces);
        for (int f = 0; f < shapes[s].faces; f++)
            for (int t = 0; t < faces[f].n - 2; t++) {
                int32_t tri[3];
                tpk_topo_face_triangle(&faces[f], t, tri);
                CHECK_MSG(tpk_topo_orient(m.points, tri[0], tri[1], tri[2], n) < 0, "type %d face %d",
                          shapes[s].type, f);
            }
        tpk_mesh_free(&m);
    }
}

/* Tet 0 = (0,1,2,3) and a neighbour across (1,2,3) with apex 4: consistent, mirrored, folded. */
static void two_tets(const int32_t second[4], const double apex[3], tpk_check_report *r)
{
    double pts[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {apex[0], apex[1], apex[2]}};
    int32_t conn[8] = {0, 1, 2, 3, second[0], second[1], second[2], second[3]};
    uint8_t types[2] = {10, 10};
    tpk_mesh m;
    make_mesh(&m, &pts[0][0], 5, types, conn, 2);
    run_topology(&m, 2, r);
    tpk_mesh_free(&m);
}

TPK_TEST(two_tets_consistent)
{
    tpk_check_report r;
    two_tets((const int32_t[]){1, 2, 3, 4}, (const double[]){1, 1, 1}, &r);
    int bad = others_zero(&r, NULL, 0);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    CHECK_EQ_INT(r.component_count, 1);
    CHECK_EQ_INT(r.component_sizes[0], 2);
    tpk_check_report_free(&r);
}

TPK_TEST(two_tets_mirrored)
{
    tpk_check_report r;
    two_tets((const int32_t[]){1, 2, 4, 3}, (const double[]){1, 1, 1}, &r);
    CHECK_EQ_INT(count_of(&r, 302), 1);
    CHECK_EQ_INT(count_of(&r, 403), 3);
    int bad = others_zero(&r, (const int[]){302, 403}, 2);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    tpk_example *ex = &tpk_check_finding(&r, 302)->examples[0];
    CHECK(!strcmp(ex->kind, "face") && ex->id_count == 5 && ex->has_point && ex->note[0]);
    CHECK(ex->ids[0] == 1 && ex->ids[1] == 2 && ex->ids[2] == 3 && ex->ids[3] == 0 && ex->ids[4] == 1);
    tpk_check_report_free(&r);
}

TPK_TEST(two_tets_folded)
{
    tpk_check_report r;
    two_tets((const int32_t[]){1, 2, 3, 4}, (const double[]){0.1, 0.1, 0.1}, &r);
    CHECK_EQ_INT(count_of(&r, 305), 1);
    int bad = others_zero(&r, (const int[]){305}, 1);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    tpk_check_report_free(&r);
}

/* The fold test for quads uses the cells' vertices off the face: a hex folded over its neighbour. */
TPK_TEST(hexes_folded)
{
    /* hex 0: the unit cube; hex 1 across its face x = 1 (1, 2, 6, 5) with far corners 8..11 at x = 0.5
     * (folded back into hex 0), then at x = 2 (a proper neighbour) */
    double pts[12][3];
    memcpy(pts, CUBE, sizeof CUBE);
    static const double far[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}}; /* (y, z) of 8, 9, 10, 11 */
    for (int i = 0; i < 4; i++) {
        pts[8 + i][0] = 0.5;
        pts[8 + i][1] = far[i][0];
        pts[8 + i][2] = far[i][1];
    }
    int32_t conn[16] = {0, 1, 2, 3, 4, 5, 6, 7, 1, 8, 9, 2, 5, 10, 11, 6};
    uint8_t types[2] = {12, 12};
    tpk_mesh m;
    make_mesh(&m, &pts[0][0], 12, types, conn, 2);
    tpk_check_report r;
    run_topology(&m, 1, &r);
    CHECK_EQ_INT(count_of(&r, 302), 0);
    CHECK_EQ_INT(count_of(&r, 305), 1);
    tpk_check_report_free(&r);
    for (int i = 8; i < 12; i++) /* the far face at x = 2: a proper neighbour */
        m.points[3 * i] = 2;
    run_topology(&m, 1, &r);
    int bad = others_zero(&r, NULL, 0);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(three_tets_on_a_face)
{
    double pts[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.2, -1}, {0.3, 0.1, -2}};
    int32_t conn[12] = {0, 1, 2, 3, 0, 2, 1, 4, 0, 2, 1, 5};
    uint8_t types[3] = {10, 10, 10};
    tpk_mesh m;
    make_mesh(&m, &pts[0][0], 6, types, conn, 3);
    tpk_check_report r;
    run_topology(&m, 2, &r);
    CHECK_EQ_INT(count_of(&r, 301), 1);
    CHECK_EQ_INT(count_of(&r, 401), 3);
    tpk_example *ex = &tpk_check_finding(&r, 301)->examples[0];
    CHECK(ex->id_count == 6 && ex->ids[0] == 0 && ex->ids[1] == 1 && ex->ids[2] == 2);
    CHECK(ex->ids[3] == 0 && ex->ids[4] == 1 && ex->ids[5] == 2);
    CHECK_EQ_INT(r.component_count, 1);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

/* A hex against a cube of six tets: the quad and the two triangles lie against each other, whichever
 * diagonal the triangles use; a cell with a repeated id takes no part in anything. */
TPK_TEST(quad_against_two_triangles)
{
    double pts[12][3];
    for (int i = 0; i < 12; i++) {
        pts[i][0] = i % 3;
        pts[i][1] = i / 3 % 2;
        pts[i][2] = i / 6;
    }
    /* ids: x + 3 y + 6 z; hex x in [0,1]; cube x in [1,2] corners in hex order */
    int32_t c[8] = {1, 2, 5, 4, 7, 8, 11, 10};
    int32_t conn[8 + 24 + 4];
    int32_t hex[8] = {0, 1, 4, 3, 6, 7, 10, 9};
    memcpy(conn, hex, sizeof hex);
    static const int kuhn[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
    for (int t = 0; t < 6; t++)
        for (int k = 0; k < 4; k++)
            conn[8 + 4 * t + k] = c[kuhn[t][k]];
    int32_t bad_tet[4] = {0, 0, 1, 3};
    memcpy(conn + 32, bad_tet, sizeof bad_tet);
    uint8_t types[8] = {12, 10, 10, 10, 10, 10, 10, 10};
    tpk_mesh m;
    make_mesh(&m, &pts[0][0], 12, types, conn, 8);
    tpk_check_report r;
    run_topology(&m, 2, &r);
    CHECK_EQ_INT(count_of(&r, 303), 3);
    CHECK_EQ_INT(count_of(&r, 401), 4);
    CHECK_EQ_INT(count_of(&r, 406), 0);
    CHECK_EQ_INT(count_of(&r, 402), 0);
    /* face-connected, as checkMesh's regions: the hex apart from the tets, joined across the
     * nonconforming faces in the summary */
    CHECK_EQ_INT(r.component_count, 2);
    CHECK_EQ_INT(r.component_sizes[0] + r.component_sizes[1], 7);
    CHECK(strstr(tpk_check_finding(&r, 304)->summary, "1 once joined across faces") != NULL);
    tpk_check_report_free(&r);
    tpk_mesh_free(&m);
}

TPK_TEST(hanging_nodes_real)
{
    /* 250 hexes with centroid x < 0, y < 0 split 1 -> 8 (a 5 x 5 x 10 block of the 10^3 grid). The
     * block meets the rest on x = 0 and y = 0: 2 x 5 x 10 = 100 coarse faces, each against 4 fine ones:
     * 100 + 400 = 500 nonconforming faces. The two closed surfaces (coarse L, fine block) touch at the
     * coarse grid vertices of those two planes: 2 x 6 x 11 - 11 (the line x = y = 0) = 121. */
    tpk_check_report r;
    CHECK(run_path(tpk_data_path("hard/hanging_nodes_hex.vtk"), 2, &r) == 0);
    CHECK_EQ_INT(count_of(&r, 303), 500);
    CHECK_EQ_INT(count_of(&r, 402), 121);
    int bad = others_zero(&r, (const int[]){303, 304, 402}, 3);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    /* the coarse L and the fine block: face-connected apart, one once joined across the 303 faces */
    CHECK_EQ_INT(r.component_count, 2);
    CHECK_EQ_INT(r.component_sizes[0], 2000);
    CHECK_EQ_INT(r.component_sizes[1], 750);
    CHECK(strstr(tpk_check_finding(&r, 304)->summary, "; 1 once joined") != NULL);
    tpk_example *ex = &tpk_check_finding(&r, 303)->examples[0];
    CHECK(ex->has_point && ex->note[0] && !strcmp(ex->kind, "face"));
    tpk_check_report_free(&r);
}

TPK_TEST(nonmanifold_vertex_edge_real)
{
    /* cube_medium_tetra (1,782 tets, its edges cut in 6) three times: one copy touching at a corner
     * (1 vertex), one sharing a whole cube edge (6 mesh edges). */
    tpk_check_report r;
    CHECK(run_path(tpk_data_path("hard/nonmanifold_vertex_edge_tets.vtu"), 2, &r) == 0);
    CHECK_EQ_INT(count_of(&r, 401), 6);
    CHECK_EQ_INT(count_of(&r, 402), 1);
    CHECK_EQ_INT(count_of(&r, 304), 3);
    int bad = others_zero(&r, (const int[]){401, 402, 304}, 3);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    CHECK_EQ_INT(r.component_count, 3);
    for (int i = 0; i < 3; i++)
        CHECK_EQ_INT(r.component_sizes[i], 1782);
    CHECK(!strcmp(tpk_check_finding(&r, 304)->summary, "3 components: 1782, 1782, 1782"));
    tpk_check_report_free(&r);
}

TPK_TEST(two_components_real)
{
    tpk_check_report r;
    CHECK(run_path(tpk_data_path("hard/two_components_orphans.node"), 2, &r) == 0);
    CHECK_EQ_INT(r.component_count, 2);
    CHECK(!strcmp(tpk_check_finding(&r, 304)->summary, "2 components: 14487, 14487"));
    /* hinge_small has genus 5: V - E + F = -8 per copy, info only */
    CHECK_EQ_INT(count_of(&r, 405), 2);
    int bad = others_zero(&r, (const int[]){304, 405}, 2);
    CHECK_MSG(bad == 0, "check %d fired", bad);
    tpk_check_report_free(&r);
}

TPK_TEST(clean_real_meshes)
{
    static const char *files[] = {
        "sfepy/acoustic_wg.vtk", "sfepy/acoustics_mesh3d.mesh", "sfepy/cross3d.mesh", "sfepy/cube_big_tetra.mesh",
        "sfepy/cube_cylinder.mesh", "sfepy/cube_medium_hexa.mesh", "sfepy/cube_medium_tetra.mesh",
        "sfepy/cylinder.vtk", "sfepy/elbow.mesh", "sfepy/piezo_mesh_micro.vtk", "tetgen/hinge_small.node",
        "tetgen/part1_small.node", "gmsh/t3_hex_prism_ascii41.msh", "gmsh/t5_small_tet_ascii22.msh",
        "gmsh/t5_small_tet_bin.vtk", "nasa_refine/cube-sphere_cube-sphere.meshb",
        "nasa_refine/cube_cylinder_ega.ugrid", "nasa_refine/cube_polar1.ugrid",
        "nasa_refine/om6_om6-curv-no-geom.meshb", "seacas/2block1.g", "seacas/8-block.g",
        "seacas/8-block-omitted.g", "seacas/cube.g", "seacas/two-block.g", "seacas/ADeDA.e"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        tpk_check_report r;
        CHECK_MSG(run_path(tpk_data_path(files[i]), 2, &r) == 0, "%s", files[i]);
        int bad = others_zero(&r, (const int[]){304, 405}, 2);
        CHECK_MSG(bad == 0, "%s: check %d fired (%lld)", files[i], bad, (long long)count_of(&r, bad));
        tpk_check_report_free(&r);
    }
}

/* snappyHexMesh's flange as OpenFOAM wrote it (tests/data/openfoam/cases/flange_binary): polyhedra whose
 * faces carry the points of finer neighbours (up to 8 corners) and non-planar snapped faces. checkMesh
 * says one region and "Mesh OK" (flange.checkMesh.txt). check once dropped the cells with faces of more
 * than 4 corners (2 components, 34 x 401, 10 x 402, 24 x 303); now every face is matched whole and the
 * faces of polyhedra are cut about their centre as OpenFOAM cuts them. */
TPK_TEST(snapped_polyhedra_agree_with_checkmesh)
{
    tpk_check_report r;
    CHECK(run_path(TPK_SOURCE_DIR "/tests/data/openfoam/cases/flange_binary", 2, &r) == 0);
    int bad = others_zero(&r, (const int[]){304, 405}, 2);
    CHECK_MSG(bad == 0, "check %d fired (%lld)", bad, (long long)count_of(&r, bad));
    CHECK_EQ_INT(r.component_count, 1);
    tpk_check_report_free(&r);
}

/* Polygons matched whole (their runs cut by the full face) give the same counts on 1 and 2 threads. */
TPK_TEST(snapped_polyhedra_same_for_any_thread_count)
{
    tpk_check_report one, two;
    const char *path = TPK_SOURCE_DIR "/tests/data/openfoam/cases/flange_binary";
    CHECK(run_path(path, 1, &one) == 0 && run_path(path, 2, &two) == 0);
    CHECK_EQ_INT(one.component_count, two.component_count);
    for (int i = 0; i < TOPO_ID_COUNT; i++)
        CHECK_EQ_INT(count_of(&one, TOPO_IDS[i]), count_of(&two, TOPO_IDS[i]));
    tpk_check_report_free(&one);
    tpk_check_report_free(&two);
}

/* sfepy/matrix_fiber_rand.vtk has 97 of its 603 hexes in mirrored node order (negative corner
 * Jacobians): where they meet the others, faces are traversed the same way by both. */
TPK_TEST(mirrored_hexes_real)
{
    tpk_check_report r;
    CHECK(run_path(tpk_data_path("sfepy/matrix_fiber_rand.vtk"), 2, &r) == 0);
    CHECK_EQ_INT(count_of(&r, 302), 32);
    CHECK_EQ_INT(count_of(&r, 305), 0);
    CHECK_EQ_INT(count_of(&r, 303), 0);
    tpk_check_report_free(&r);
}

static int same_findings(tpk_check_report *a, tpk_check_report *b)
{
    for (int i = 0; i < TOPO_ID_COUNT; i++) {
        tpk_finding *x = tpk_check_finding(a, TOPO_IDS[i]), *y = tpk_check_finding(b, TOPO_IDS[i]);
        if (x->count != y->count || x->example_count != y->example_count || strcmp(x->summary, y->summary))
            return TOPO_IDS[i];
        for (int e = 0; e < x->example_count; e++)
            if (memcmp(x->examples[e].ids, y->examples[e].ids, sizeof x->examples[e].ids) ||
                strcmp(x->examples[e].note, y->examples[e].note) ||
                memcmp(x->examples[e].point, y->examples[e].point, sizeof x->examples[e].point))
                return TPK_CHECK_MAX_IDS * 1000 + TOPO_IDS[i];
    }
    return a->component_count == b->component_count ? 0 : 304;
}

TPK_TEST(same_for_any_thread_count)
{
    static const char *files[] = {"hard/hanging_nodes_hex.vtk", "hard/nonmanifold_vertex_edge_tets.vtu",
                                  "sfepy/matrix_fiber_rand.vtk"};
    for (int f = 0; f < 3; f++) {
        tpk_check_report one;
        CHECK(run_path(tpk_data_path(files[f]), 1, &one) == 0);
        for (int threads = 2; threads <= 5; threads += 3) {
            tpk_check_report many;
            CHECK(run_path(tpk_data_path(files[f]), threads, &many) == 0);
            int differs = same_findings(&one, &many);
            CHECK_MSG(differs == 0, "%s: %d threads differ at %d", files[f], threads, differs);
            tpk_check_report_free(&many);
        }
        tpk_check_report_free(&one);
    }
}

/* A 30^3 grid of Kuhn tets (162,000: enough for several workers) with every 7th tet mirrored and
 * random vertex ids: thousands of findings whose counts, examples and order must not depend on the
 * thread count. */
TPK_TEST(grid_same_for_any_thread_count)
{
    const int n = 30, s = n + 1;
    static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = (int64_t)s * s * s;
    m.cell_count = (int64_t)n * n * n * 6;
    m.points = malloc(sizeof(double) * 3 * (size_t)m.point_count);
    m.cell_types = malloc((size_t)m.cell_count);
    m.cell_offsets = malloc(sizeof(int64_t) * (size_t)(m.cell_count + 1));
    m.cell_conn = malloc(sizeof(int32_t) * 4 * (size_t)m.cell_count);
    int32_t *perm = malloc(sizeof(int32_t) * (size_t)m.point_count);
    uint32_t rng = 12345;
    for (int64_t i = 0; i < m.point_count; i++)
        perm[i] = (int32_t)i;
    for (int64_t i = m.point_count - 1; i > 0; i--) {
        rng = rng * 1664525u + 1013904223u;
        int64_t j = (int64_t)(rng % (uint32_t)(i + 1));
        int32_t t = perm[i];
        perm[i] = perm[j];
        perm[j] = t;
    }
    for (int64_t i = 0; i < m.point_count; i++) {
        m.points[3 * perm[i]] = (double)(i / (s * s));
        m.points[3 * perm[i] + 1] = (double)(i / s % s);
        m.points[3 * perm[i] + 2] = (double)(i % s);
    }
    for (int64_t q = 0, c = 0; q < (int64_t)n * n * n; q++) {
        int64_t i = q / (n * n), j = q / n % n, k = q % n;
        for (int t = 0; t < 6; t++, c++) {
            int32_t *v = m.cell_conn + 4 * c;
            for (int a = 0; a < 4; a++) {
                int b = kuhn[t][a];
                v[a] = perm[((i + (b >> 2 & 1)) * s + j + (b >> 1 & 1)) * s + k + (b & 1)];
            }
            if (tpk_topo_orient(m.points, v[0], v[1], v[2], v[3]) < 0 || c % 7 == 0) {
                int32_t x = v[2];
                v[2] = v[3];
                v[3] = x;
            }
            m.cell_types[c] = TPK_CELL_TETRA;
        }
    }
    for (int64_t c = 0; c <= m.cell_count; c++)
        m.cell_offsets[c] = 4 * c;
    free(perm);
    tpk_check_report one;
    CHECK(run_topology(&m, 1, &one) == 0);
    CHECK(count_of(&one, 302) > 1000 && count_of(&one, 403) > 100);
    CHECK_EQ_INT(count_of(&one, 305), 0);
    CHECK_EQ_INT(one.component_count, 1);
    for (int threads = 2; threads <= 7; threads += 5) {
        tpk_check_report many;
        CHECK(run_topology(&m, threads, &many) == 0);
        int differs = same_findings(&one, &many);
        CHECK_MSG(differs == 0, "%d threads differ at %d", threads, differs);
        tpk_check_report_free(&many);
    }
    tpk_check_report_free(&one);
    tpk_mesh_free(&m);
}
