/* Hard cases for the converter and the marcher (issue 13), each with a measured outcome asserted:
 * axis-aligned rays exactly through the vertices and edges of split hexahedra; slivers and near-flat tets;
 * tets of 1e-9 and 2^30 in one mesh; cells of 1e-3 at an offset of 1e7; non-convex shells with a tunnel,
 * a cavity and components touching at a vertex and along an edge. Meshes are written as VTK here and go
 * through the real converter; rays are marched on all three layouts. */
#include "hard_common.h"

/* Every ray the line of which runs through the interior of the box must give the chord exactly (the
 * grid's points are integers, exact in float32); a line in a boundary plane gives 0 or the chord (the
 * tie-break decides); layouts give the same tets. */
TPK_TEST(hex_split_axis_rays)
{
    enum { N = 4 };
    hard_mesh m = {0};
    const double zero[3] = {0, 0, 0};
    hard_hex_grid(&m, N, 1.0, zero, NULL, 7);
    CHECK(hard_mesh_write(&m, tpk_temp_path("hex.vtk")) == 0);
    hard_mesh_free(&m);
    tpk_convert_report rep;
    tpk_diag diag;
    CHECK_MSG(hard_convert(tpk_temp_path("hex.vtk"), tpk_temp_path("hex.tpk"), 0, &rep, &diag) == 0, "%s", diag.message);
    hard_tpk t;
    CHECK(hard_tpk_open(&t, tpk_temp_path("hex.tpk")) == 0);
    hard_ray *r[3] = {malloc(sizeof(hard_ray)), malloc(sizeof(hard_ray)), malloc(sizeof(hard_ray))};
    CHECK(r[0] && r[1] && r[2]);
    const double lo[3] = {0, 0, 0}, hi[3] = {N, N, N};
    long rays = 0, through_vertices = 0, along_edges = 0, interior = 0, boundary = 0;
    double max_err = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int sgn = -1; sgn <= 1; sgn += 2)
            for (int iu = -2; iu <= 4 * N + 2; iu++)
                for (int iv = -2; iv <= 4 * N + 2; iv++) {
                    double org[3], dir[3] = {0, 0, 0};
                    int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    org[u] = iu * 0.25, org[v] = iv * 0.25, org[axis] = sgn > 0 ? -1.5 : N + 1.5;
                    dir[axis] = sgn;
                    for (int l = 0; l < 3; l++) {
                        tpk_march_stats st;
                        CHECK_MSG(hard_march(&t, l, org, dir, 0, r[l], &st) == TPK_OK, "ray (%g %g %g) dir (%g %g %g)",
                                  org[0], org[1], org[2], dir[0], dir[1], dir[2]);
                        CHECK(st.shell_entries <= 1);
                    }
                    for (int l = 1; l < 3; l++)
                        CHECK(r[l]->pieces == r[0]->pieces &&
                              !memcmp(r[l]->tets, r[0]->tets, sizeof(int32_t) * (size_t)r[0]->pieces));
                    double chord = hard_box_chord(lo, hi, org, dir, 0);
                    int on_plane = iu == 0 || iu == 4 * N || iv == 0 || iv == 4 * N;
                    int inside = iu > 0 && iu < 4 * N && iv > 0 && iv < 4 * N;
                    if (on_plane) {
                        boundary++;
                        CHECK_MSG(r[0]->length == 0 || fabs(r[0]->length - N) <= 1e-12 * N, "boundary ray length %.17g",
                                  r[0]->length);
                    } else {
                        double err = fabs(r[0]->length - chord);
                        max_err = fmax(max_err, err);
                        CHECK_MSG(err <= 1e-12 * N, "ray (%g %g %g) axis %d: length %.17g, chord %.17g", org[0], org[1],
                                  org[2], axis, r[0]->length, chord);
                        interior += inside;
                        through_vertices += inside && iu % 4 == 0 && iv % 4 == 0;
                        along_edges += inside && ((iu % 4 == 0) != (iv % 4 == 0));
                    }
                    rays++;
                }
    CHECK(through_vertices == 3 * 2 * (N - 1) * (N - 1));
    hard_report("hex_split_axis_rays", "every interior ray enters and leaves; length = chord",
                "\"hexahedra\":%d,\"tets\":%lld,\"hexes_in_5\":%lld,\"hexes_in_6\":%lld,\"rays\":%ld,"
                "\"interior_rays\":%ld,\"along_vertex_lines\":%ld,\"in_face_planes\":%ld,\"boundary_plane_rays\":%ld,"
                "\"max_length_error\":%.3g",
                N * N * N, (long long)rep.tets, (long long)rep.cells_into[5], (long long)rep.cells_into[6], rays,
                interior, through_vertices, along_edges, boundary, max_err);
    for (int l = 0; l < 3; l++)
        free(r[l]);
    hard_tpk_close(&t);
}

/* ---- slivers and near-flat tets: a hexahedral grid squashed along (1,2,3) ------------------------- */

/* x -> x - (1 - s)(x.n)n: every cell keeps its shape in the plane normal to n and is s times as thick;
 * no lattice edge is parallel to n, so every tet is a sliver (no short edge, volume s times). A ray
 * org + t dir maps to A org + t A dir: the same t, so the chord in t is the unsquashed box's. */
static void squash(double s, const double in[3], double out[3])
{
    const double n[3] = {1 / sqrt(14.0), 2 / sqrt(14.0), 3 / sqrt(14.0)};
    double d = in[0] * n[0] + in[1] * n[1] + in[2] * n[2];
    for (int k = 0; k < 3; k++)
        out[k] = in[k] - (1 - s) * d * n[k];
}

/* An n^3 grid of unit cubes as tets (6 per cube around its main diagonal, positively oriented): given as
 * tets, not hexahedra, so that float32 flattening them is decided by orient (exactly, at once), not by
 * the hexahedron splitter's TetGen diagnosis (seconds per cell). */
static void kuhn_grid(hard_mesh *m, int n)
{
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++)
                hard_add_point(m, i, j, k);
    static const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {i, j, k};
                    int32_t tet[4];
                    tet[0] = (int32_t)((c[2] * (n + 1) + c[1]) * (n + 1) + c[0]);
                    for (int s = 0; s < 3; s++) {
                        c[axes[p][s]]++;
                        tet[s + 1] = (int32_t)((c[2] * (n + 1) + c[1]) * (n + 1) + c[0]);
                    }
                    if (p == 1 || p == 2 || p == 5) { /* odd permutations walk the cube the other way round */
                        int32_t t = tet[2];
                        tet[2] = tet[3], tet[3] = t;
                    }
                    hard_add_cell(m, 10, tet, 4);
                }
}

static void sliver_case(double s, long *rays, double *max_rel, tpk_convert_report *rep, char *outcome, size_t cap,
                        int *converted)
{
    enum { N = 4 };
    hard_mesh m = {0};
    kuhn_grid(&m, N);
    for (int64_t p = 0; p < m.point_count; p++) {
        double q[3];
        squash(s, m.points + 3 * p, q);
        memcpy(m.points + 3 * p, q, sizeof q);
    }
    char vtk[64], tpk[64];
    snprintf(vtk, sizeof vtk, "sliver_%g.vtk", s);
    snprintf(tpk, sizeof tpk, "sliver_%g.tpk", s);
    CHECK(hard_mesh_write(&m, tpk_temp_path(vtk)) == 0);
    hard_mesh_free(&m);
    tpk_diag diag;
    *converted = hard_convert(tpk_temp_path(vtk), tpk_temp_path(tpk), 0, rep, &diag) == 0;
    if (!*converted) { /* a refusal must say what and where */
        CHECK_MSG(strstr(diag.message, "cell ") && (strstr(diag.message, "fold") || strstr(diag.message, "volume") ||
                                                    strstr(diag.message, "warped") || strstr(diag.message, "degenerate")),
                  "%s", diag.message);
        char clause[160];
        hard_clause(clause, sizeof clause, diag.message);
        snprintf(outcome, cap, "refused: %s", clause);
        return;
    }
    snprintf(outcome, cap, "converted");
    hard_tpk t;
    CHECK(hard_tpk_open(&t, tpk_temp_path(tpk)) == 0);
    hard_ray *r = malloc(sizeof *r);
    CHECK(r);
    uint64_t rng = 99;
    const double lo[3] = {0, 0, 0}, hi[3] = {N, N, N};
    for (int i = 0; i < 3000; i++) {
        double target[3], from[3], dir_u[3], org[3], dir[3];
        for (int k = 0; k < 3; k++)
            target[k] = N * hard_uniform(&rng), from[k] = N * (3 * hard_uniform(&rng) - 1);
        for (int k = 0; k < 3; k++)
            dir_u[k] = target[k] - from[k];
        squash(s, from, org);
        squash(s, dir_u, dir); /* linear part: the same map */
        double chord = hard_box_chord(lo, hi, from, dir_u, 0);
        double dir_len = sqrt(dir_u[0] * dir_u[0] + dir_u[1] * dir_u[1] + dir_u[2] * dir_u[2]);
        /* float32 rounds the squashed points by 2^-24 N; seen back in the unsquashed frame that is 1/s larger */
        double bound = 16 * ldexp(1.0, -24) * N / s;
        for (int l = 0; l < 3; l++) {
            CHECK(hard_march(&t, l, org, dir, 0, r, NULL) == TPK_OK);
            double err = fabs(r->length - chord) * dir_len;
            *max_rel = fmax(*max_rel, err / bound);
            CHECK_MSG(err <= bound, "s %g: ray length %.9g, chord %.9g (error %.3g, bound %.3g)", s, r->length, chord,
                      err, bound);
        }
        (*rays)++;
    }
    free(r);
    hard_tpk_close(&t);
}

TPK_TEST(slivers_and_flat_tets)
{
    const double thickness[4] = {1e-2, 1e-4, 1e-6, 1e-8};
    char figures[1500] = "";
    size_t used = 0;
    for (int i = 0; i < 4; i++) {
        long rays = 0;
        double max_rel = 0;
        int converted = 0, failures_before = tpk_test_failures;
        char outcome[200];
        tpk_convert_report rep;
        sliver_case(thickness[i], &rays, &max_rel, &rep, outcome, sizeof outcome, &converted);
        if (tpk_test_failures != failures_before)
            return;
        /* float32 keeps a 1e-2 squash: its tets must convert and march (1e-4 of a chord at most) */
        if (thickness[i] >= 1e-2)
            CHECK_MSG(converted, "%s", outcome);
        used += (size_t)snprintf(figures + used, sizeof figures - used, "%s\"s=%g\":\"%s; tets %lld; rays %ld; largest "
                                 "length error / bound %.2g\"", i ? "," : "", thickness[i], outcome,
                                 (long long)rep.tets, rays, max_rel);
    }
    hard_report("slivers_and_flat_tets", "converted and watertight, or refused by name", "%s", figures);
}

/* ---- tets of 1e-9 and of 2^30 in one mesh ------------------------------------------------------- */

static void scales_case(int far)
{
    const double big = 1073741824.0; /* 2^30: exact in float32, as its tet's corners */
    {
        /* far = 0: the tiny tet at the origin (float32 keeps 1e-9 there); far = 1: at (1,1,1), where
         * float32 steps are 1.2e-7 and flatten it: refused by name, dropped with --drop-degenerate */
        hard_mesh m = {0};
        double at = far ? 1.0 : 0.0;
        int32_t tiny[4] = {hard_add_point(&m, at, at, at), hard_add_point(&m, at + 1e-9, at, at),
                           hard_add_point(&m, at, at + 1e-9, at), hard_add_point(&m, at, at, at + 1e-9)};
        int32_t huge[4] = {hard_add_point(&m, 2, 0, 0), hard_add_point(&m, big, 0, 0), hard_add_point(&m, 2, big, 0),
                           hard_add_point(&m, 2, 0, big)};
        hard_add_cell(&m, 10, tiny, 4);
        hard_add_cell(&m, 10, huge, 4);
        const char *vtk = far ? "scales_far.vtk" : "scales.vtk", *out = far ? "scales_far.tpk" : "scales.tpk";
        CHECK(hard_mesh_write(&m, tpk_temp_path(vtk)) == 0);
        hard_mesh_free(&m);
        tpk_convert_report rep;
        tpk_diag diag;
        int rc = hard_convert(tpk_temp_path(vtk), tpk_temp_path(out), 0, &rep, &diag);
        if (far) {
            CHECK_MSG(rc != 0 && strstr(diag.message, "zero volume"), "%s", diag.message);
            char refusal[200];
            hard_clause(refusal, sizeof refusal, diag.message);
            CHECK_MSG(hard_convert(tpk_temp_path(vtk), tpk_temp_path(out), HARD_DROP, &rep, &diag) == 0, "%s",
                      diag.message);
            CHECK_EQ_INT(rep.tets, 1);
            CHECK_EQ_INT(rep.degenerate_dropped, 1);
            hard_report("tiny_tet_far_from_origin", "refused by name; --drop-degenerate drops it, file valid",
                        "\"refusal\":\"%s\",\"dropped\":%lld,\"tets_left\":%lld", refusal,
                        (long long)rep.degenerate_dropped, (long long)rep.tets);
            return;
        }
        CHECK_MSG(rc == 0, "%s", diag.message);
        CHECK_EQ_INT(rep.tets, 2);
        hard_tpk t;
        CHECK(hard_tpk_open(&t, tpk_temp_path(out)) == 0);
        hard_ray *r = malloc(sizeof *r);
        CHECK(r);
        double worst_tiny = 0, worst_huge = 0, worst_far = 0;
        long rays = 0;
        for (int i = 1; i < 8; i++)
            for (int j = 1; i + j < 8; j++) {
                /* along +x at (y, z) = (i, j) 1e-10: through the tiny tet (chord 1e-9 - y - z), then the huge
                 * one beyond x = 2, where (x - 2) / (big - 2) + (y + z) / big = 1 */
                double y = i * 1e-10, z = j * 1e-10, org[3] = {-1, y, z}, dir[3] = {1, 0, 0};
                double tiny_chord = 1e-9 - y - z, huge_chord = (big - 2) * (1 - (y + z) / big);
                for (int l = 0; l < 3; l++) {
                    tpk_march_stats st;
                    CHECK(hard_march(&t, l, org, dir, 0, r, &st) == TPK_OK);
                    CHECK_EQ_INT(r->pieces, 2);
                    CHECK_EQ_INT(st.shell_entries, 2);
                    double e1 = fabs(r->t_out[0] - r->t_in[0] - tiny_chord) / tiny_chord;
                    double e2 = fabs(r->t_out[1] - r->t_in[1] - huge_chord) / big;
                    worst_tiny = fmax(worst_tiny, e1), worst_huge = fmax(worst_huge, e2);
                    CHECK_MSG(e1 <= 1e-5 && e2 <= 1e-6, "tiny %.9g of %.9g, huge %.12g of %.12g", r->t_out[0] - r->t_in[0],
                              tiny_chord, r->t_out[1] - r->t_in[1], huge_chord);
                    /* from 1e3 away the tiny piece is the difference of two t near 1e3: a few double ulps */
                    org[0] = -1e3;
                    CHECK(hard_march(&t, l, org, dir, 0, r, NULL) == TPK_OK && r->pieces == 2);
                    double e3 = fabs(r->t_out[0] - r->t_in[0] - tiny_chord);
                    worst_far = fmax(worst_far, e3);
                    CHECK_MSG(e3 <= 16 * ldexp(1.0, -53) * 1e3, "from 1e3 away: %.9g of %.9g", r->t_out[0] - r->t_in[0],
                              tiny_chord);
                    org[0] = -1;
                    rays++;
                }
            }
        hard_report("tiny_and_huge_tets", "both tets found by every ray, lengths exact to float32",
                    "\"tiny_edge\":1e-9,\"huge_edge\":%.0f,\"rays\":%ld,\"tiny_max_rel_error\":%.2g,"
                    "\"huge_max_error_over_edge\":%.2g,\"tiny_abs_error_from_1e3_away\":%.2g",
                    big, rays, worst_tiny, worst_huge, worst_far);
        free(r);
        hard_tpk_close(&t);
    }
}

TPK_TEST(tiny_and_huge_tets)
{
    scales_case(0);
}

TPK_TEST(tiny_tet_far_from_origin)
{
    scales_case(1);
}
