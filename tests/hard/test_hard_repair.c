/* Hard case for the repair options (issue 13): one input holding an inverted tet, a mirrored hexahedron,
 * a zero-volume tet, two tets folded over their shared face and an inverted tet that folds once turned over,
 * converted with every combination of --strict-orientation, --drop-degenerate, --skip-bad-cells and
 * --cut-folds. Measured outcome, asserted: each combination is a refusal naming the problem, or a file
 * that passes the format's MUSTs (6xx) and marches every ray, with each repair counted. */
#include "hard_common.h"

/* The defects, each its own component away from a valid 3^3 block of hexahedra. */
static void defect_mesh(hard_mesh *m)
{
    const double zero[3] = {0, 0, 0};
    hard_hex_grid(m, 3, 1.0, zero, NULL, 23);
    /* an inverted tet (negative orientation): turned over by default */
    int32_t inv[4] = {hard_add_point(m, 10, 0, 0), hard_add_point(m, 11, 0, 0), hard_add_point(m, 10, 0, 1),
                      hard_add_point(m, 10, 1, 0)};
    hard_add_cell(m, 10, inv, 4);
    /* a hexahedron in mirrored node order (top face first): turned over by default */
    int32_t hex[8];
    static const int top_first[8][3] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (int c = 0; c < 8; c++)
        hex[c] = hard_add_point(m, 13 + top_first[c][0], top_first[c][1], top_first[c][2]);
    hard_add_cell(m, 12, hex, 8);
    /* a zero-volume tet: four coplanar points */
    int32_t flat[4] = {hard_add_point(m, 20, 0, 0), hard_add_point(m, 21, 0, 0), hard_add_point(m, 20, 1, 0),
                       hard_add_point(m, 21, 1, 0)};
    hard_add_cell(m, 10, flat, 4);
    /* two tets on the same side of their shared face: a fold */
    int32_t a = hard_add_point(m, 30, 0, 0), b = hard_add_point(m, 31, 0, 0), c = hard_add_point(m, 30, 1, 0);
    int32_t up1 = hard_add_point(m, 30.2, 0.2, 1), up2 = hard_add_point(m, 30.3, 0.3, 0.5);
    int32_t f1[4] = {a, b, c, up1}, f2[4] = {a, b, c, up2};
    hard_add_cell(m, 10, f1, 4);
    hard_add_cell(m, 10, f2, 4);
    /* a tet given inverted whose turned-over self folds against its neighbour: a bad cell. (A hexahedron
     * folded through itself is a bad cell too, but is diagnosed by a TetGen child: about 2 s per run.) */
    int32_t d = hard_add_point(m, 50, 0, 0), e = hard_add_point(m, 51, 0, 0), f = hard_add_point(m, 50, 1, 0);
    int32_t up3 = hard_add_point(m, 50.2, 0.2, 1), up4 = hard_add_point(m, 50.3, 0.3, 0.5);
    int32_t good[4] = {d, e, f, up3}, inverted_over[4] = {d, f, e, up4};
    hard_add_cell(m, 10, good, 4);
    hard_add_cell(m, 10, inverted_over, 4);
}

static const char *words[] = {"cell", "face", "tet", NULL};

TPK_TEST(repairs_on_inverted_flat_and_folded_cells)
{
    hard_mesh m = {0};
    defect_mesh(&m);
    CHECK(hard_mesh_write(&m, tpk_temp_path("defects.vtk")) == 0);
    hard_mesh_free(&m);
    char figures[4096] = "";
    size_t used = 0;
    int valid = 0, refused = 0;
    hard_ray *r = malloc(sizeof *r);
    CHECK(r);
    for (unsigned opts = 0; opts < 16; opts++) {
        char name[96];
        snprintf(name, sizeof name, "%s%s%s%s", opts & HARD_STRICT ? "strict " : "", opts & HARD_DROP ? "drop " : "",
                 opts & HARD_SKIP_BAD ? "skip-bad " : "", opts & HARD_CUT_FOLDS ? "cut-folds " : "");
        if (!opts)
            snprintf(name, sizeof name, "none ");
        name[strlen(name) - 1] = 0;
        tpk_convert_report rep;
        tpk_diag diag;
        int rc = hard_convert(tpk_temp_path("defects.vtk"), tpk_temp_path("defects.tpk"), opts, &rep, &diag);
        /* the written file is held to the 6xx MUSTs by hard_convert; 1 means it broke one */
        CHECK_MSG(rc != 1 || !strstr(diag.message, "check"), "%s: %s", name, diag.message);
        int expect_valid = (opts & HARD_DROP) && (opts & HARD_SKIP_BAD) && (opts & HARD_CUT_FOLDS) && !(opts & HARD_STRICT);
        CHECK_MSG((rc == 0) == expect_valid, "options '%s': %s", name, rc ? diag.message : "converted");
        if (rc != 0) {
            int named = 0;
            for (int w = 0; words[w]; w++)
                named |= strstr(diag.message, words[w]) != NULL;
            CHECK_MSG(named && strlen(diag.message) > 20, "options '%s': refusal names nothing: %s", name, diag.message);
            char first[120];
            hard_clause(first, sizeof first, diag.message);
            used += (size_t)snprintf(figures + used, sizeof figures - used, "\"%s\":\"refused: %s\",", name, first);
            refused++;
            continue;
        }
        CHECK_EQ_INT(rep.degenerate_dropped, 1);
        CHECK_EQ_INT(rep.folds_cut, 1);
        CHECK(rep.bad_cells_skipped >= 1);
        CHECK(rep.inverted_fixed + rep.mirrored_cells >= 2);
        hard_tpk t;
        CHECK(hard_tpk_open(&t, tpk_temp_path("defects.tpk")) == 0);
        uint64_t rng = 31;
        long rays = 0;
        double max_overlap = 0;
        for (int i = 0; i < 2000; i++, rays++) {
            double org[3] = {-5, 3 * hard_uniform(&rng) - 1, 3 * hard_uniform(&rng) - 1};
            double dir[3] = {1, 0.2 * hard_uniform(&rng) - 0.1, 0.2 * hard_uniform(&rng) - 0.1};
            for (int l = 0; l < 3; l++) {
                /* the cut fold keeps both overlapping tets: pieces may overlap in t there, nothing else */
                hard_march(&t, l, org, dir, 0, r, NULL);
                CHECK_MSG(r->marcher == TPK_OK && !r->repeats && !r->overflow, "options %s: ray %d: %s", name, i,
                          tpk_result_string(r->marcher));
                max_overlap = fmax(max_overlap, r->overlap);
            }
        }
        hard_tpk_close(&t);
        used += (size_t)snprintf(figures + used, sizeof figures - used,
                                 "\"%s\":\"valid file: %lld tets; turned over %lld tets and %lld cells; dropped %lld "
                                 "zero-volume; skipped %lld bad cells; cut %lld folds; %ld rays marched, pieces overlapping in t by "
                                 "up to %.3g (the cut fold's two tets)\",",
                                 name, (long long)rep.tets, (long long)rep.inverted_fixed, (long long)rep.mirrored_cells,
                                 (long long)rep.degenerate_dropped, (long long)rep.bad_cells_skipped,
                                 (long long)rep.folds_cut, rays, max_overlap);
        valid++;
    }
    free(r);
    CHECK(valid == 1 && refused == 15);
    hard_report("repairs_on_inverted_flat_and_folded_cells",
                "15 option sets refused by name, the one with every repair a valid file", "%s\"valid\":%d,\"refused\":%d",
                figures, valid, refused);
}
