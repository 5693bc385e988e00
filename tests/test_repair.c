/* The converter's repairs (issues 4 and 9): orientation is a labeling, so inverted tets and mirrored
 * cells are turned over by default and counted (refused with --strict-orientation); an inverted tet that
 * would fold once turned over is a bad cell. Degenerate tets and duplicate points are errors naming the
 * first case, and with --drop-degenerate and --merge-duplicates[=TOL] they are fixed, counted in the
 * report and recorded in META's "repairs". Every file written is held to the 6xx checks (tpk_assert.h).
 * Real meshes from ../shared/data; meshes with duplicated points are generated here from sfepy's
 * cylinder (each tet given its own 4 points). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/convert.h"
#include "harness.h"
#include "import/importers.h"
#include "convert/merge_vertices.h"
#include "convert/pipeline.h"
#include "convert/write_tpk.h"
#include "base/predicates.h"
#include "tetpack.h"
#include "tpk_assert.h"

enum { STRICT = 1, DROP = 2, MERGE = 4, SKIP_BAD = 8, CUT_FOLDS = 16 };

static int convert(const char *input, const char *output, unsigned repairs, double tolerance,
                   tpk_convert_report *report, tpk_diag *diag)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = input;
    o.output = output;
    o.strict_orientation = (repairs & STRICT) != 0;
    o.skip_bad_cells = (repairs & SKIP_BAD) != 0;
    o.cut_folds = (repairs & CUT_FOLDS) != 0;
    o.drop_degenerate = (repairs & DROP) != 0;
    o.merge_duplicates = (repairs & MERGE) != 0;
    o.merge_tolerance = tolerance;
    o.threads = 2;
    memset(diag, 0, sizeof *diag);
    return tpk_convert_checked(&o, report, diag);
}

/* A chunk of `path` read whole into a new NUL-terminated buffer (NULL when absent). */
static char *read_chunk(const char *path, uint32_t tag, uint32_t index, uint64_t *size)
{
    tpk_file *file = NULL;
    uint64_t i;
    tpk_dir_entry entry;
    char *data = NULL;
    if (tpk_open_path(&file, path, NULL, NULL, 0) == TPK_OK && tpk_find_chunk(file, tag, index, 0, &i) == TPK_OK &&
        tpk_get_chunk(file, i, &entry) == TPK_OK && (data = calloc(1, (size_t)entry.raw_size + 1)) != NULL &&
        tpk_read_chunk(file, i, data, entry.raw_size) == TPK_OK) {
        *size = entry.raw_size;
    } else {
        free(data);
        data = NULL;
    }
    tpk_close(file);
    return data;
}

/* ---- generated inputs ---------------------------------------------------------------------------- */

/* Legacy VTK, ASCII: tets (types all 10) or hexahedra (12), optional point and cell scalars. */
static int write_vtk(const char *path, const double *points, int64_t point_count, const int32_t *conn,
                     int64_t cell_count, int nodes, const float *point_values, const float *cell_values)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "# vtk DataFile Version 2.0\ntest_repair\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %lld double\n",
            (long long)point_count);
    for (int64_t p = 0; p < point_count; p++)
        fprintf(f, "%.17g %.17g %.17g\n", points[3 * p], points[3 * p + 1], points[3 * p + 2]);
    fprintf(f, "CELLS %lld %lld\n", (long long)cell_count, (long long)(cell_count * (nodes + 1)));
    for (int64_t c = 0; c < cell_count; c++) {
        fprintf(f, "%d", nodes);
        for (int k = 0; k < nodes; k++)
            fprintf(f, " %d", conn[nodes * c + k]);
        fprintf(f, "\n");
    }
    fprintf(f, "CELL_TYPES %lld\n", (long long)cell_count);
    for (int64_t c = 0; c < cell_count; c++)
        fprintf(f, "%d\n", nodes == 4 ? 10 : 12);
    if (cell_values) {
        fprintf(f, "CELL_DATA %lld\nSCALARS mat float 1\nLOOKUP_TABLE default\n", (long long)cell_count);
        for (int64_t c = 0; c < cell_count; c++)
            fprintf(f, "%.9g\n", cell_values[c]);
    }
    if (point_values) {
        fprintf(f, "POINT_DATA %lld\nSCALARS copy float 1\nLOOKUP_TABLE default\n", (long long)point_count);
        for (int64_t p = 0; p < point_count; p++)
            fprintf(f, "%.9g\n", point_values[p]);
    }
    return fclose(f) == 0 ? 0 : -1;
}

/* sfepy's cylinder with every tet given its own 4 points (point 4t+k = corner k of tet t), each
 * coordinate of each copy moved by up to +-jitter/2 (0: exact copies); the point scalar "copy"
 * is the copy's own id, so a merge shows whose value a kept point took. *shell is the cylinder's own
 * shell face count. */
static int write_split_cylinder(const char *path, double jitter, int64_t *tets, int64_t *shell)
{
    tpk_mesh src;
    tpk_diag diag;
    tpk_convert_report report;
    memset(&diag, 0, sizeof diag);
    if (convert(tpk_data_path("sfepy/cylinder.vtk"), tpk_temp_path("cyl.tpk"), 0, 0, &report, &diag) != 0 ||
        tpk_import_any(tpk_data_path("sfepy/cylinder.vtk"), NULL, &src, &diag) != 0)
        return -1;
    *shell = report.shell_faces;
    *tets = src.cell_count;
    int64_t n = 4 * src.cell_count;
    double *points = malloc(sizeof *points * 3 * (size_t)n);
    int32_t *conn = malloc(sizeof *conn * (size_t)n);
    float *copy = malloc(sizeof *copy * (size_t)n);
    uint64_t state = 12345;
    for (int64_t i = 0; points && conn && copy && i < n; i++) {
        for (int a = 0; a < 3; a++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            double unit = (double)(state >> 11) / 9007199254740992.0 - 0.5; /* [-0.5, 0.5) */
            points[3 * i + a] = src.points[3 * (int64_t)src.cell_conn[i] + a] + jitter * unit;
        }
        conn[i] = (int32_t)i;
        copy[i] = (float)i;
    }
    int rc = points && conn && copy ? write_vtk(path, points, n, conn, src.cell_count, 4, copy, NULL) : -1;
    free(points);
    free(conn);
    free(copy);
    tpk_mesh_free(&src);
    return rc;
}

/* ---- inverted tets ------------------------------------------------------------------------------- */

TPK_TEST(inverted_tets_refused_with_strict_orientation)
{
    tpk_convert_report r;
    tpk_diag diag;
    const char *out = tpk_temp_path("inv.tpk");
    CHECK(convert(tpk_data_path("hard/inverted_tets.vtk"), out, STRICT, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cell 0 is inverted (negative volume): points ") != NULL, "%s", diag.message);
    CHECK_MSG(strstr(diag.message, "135 of 1348 tets are inverted; without --strict-orientation they are turned over"),
              "%s", diag.message);
    FILE *f = fopen(out, "rb");
    CHECK(f == NULL); /* nothing written */
}

TPK_TEST(inverted_tets_turned_over_by_default)
{
    tpk_convert_report r;
    tpk_diag diag;
    const char *out = tpk_temp_path("inv.tpk");
    CHECK_MSG(convert(tpk_data_path("hard/inverted_tets.vtk"), out, 0, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.inverted_fixed, 135);
    CHECK_EQ_INT(r.tets, 1348);
    CHECK_EQ_INT(r.bad_cells_skipped, 0);
    uint64_t size = 0;
    char *meta = read_chunk(out, TPK_TAG_META, 0, &size);
    CHECK(meta != NULL);
    int ok = strstr(meta, "\"repairs\":{\"reorient\":{\"requested\":true,\"inverted_tets\":135,\"mirrored_cells\":0}") &&
             strstr(meta, "\"drop_degenerate\":{\"requested\":false,\"degenerate_tets\":0,\"collapsed_cells\":0}") &&
             strstr(meta, "\"merge_duplicates\":{\"requested\":false,\"tolerance\":0,\"merged_vertices\":0}") &&
             strstr(meta, "\"cut_folds\":{\"requested\":false,\"folded_faces\":0}}");
    CHECK_MSG(ok, "META: %s", meta);
    free(meta);
}

/* A whole file in the mirrored (left-handed) tet order is turned over; --strict-orientation refuses it
 * and the message says what it looks like. */
TPK_TEST(all_tets_inverted_named_as_a_convention)
{
    tpk_mesh src;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK(tpk_import_any(tpk_data_path("sfepy/cylinder.vtk"), NULL, &src, &diag) == 0);
    for (int64_t c = 0; c < src.cell_count; c++) {
        int32_t *v = src.cell_conn + 4 * c, swap = v[2];
        v[2] = v[3];
        v[3] = swap;
    }
    const char *in = tpk_temp_path("left.vtk");
    int written = write_vtk(in, src.points, src.point_count, src.cell_conn, src.cell_count, 4, NULL, NULL);
    int64_t cells = src.cell_count;
    tpk_mesh_free(&src);
    CHECK(written == 0);
    tpk_convert_report r;
    CHECK(convert(in, tpk_temp_path("left.tpk"), STRICT, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "and so are all 1348 tets: the file lists tet nodes in the mirrored (left-handed) "
                                   "order; without --strict-orientation they are turned over"), "%s", diag.message);
    CHECK_MSG(convert(in, tpk_temp_path("left.tpk"), 0, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.inverted_fixed, cells);
    CHECK_EQ_INT(r.folds_cut, 0);
}

/* ---- mirrored hexahedra -------------------------------------------------------------------------- */

/* A 3 x 2 x 1 block of unit hexahedra (VTK order); the cells listed in `mirror` get their bottom and
 * top quads swapped, which is the mirror image. */
static int write_hex_block(const char *path, const int *mirror, int mirror_count)
{
    double points[4 * 3 * 2 * 3];
    int32_t conn[6 * 8];
    int p = 0;
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 4; i++, p++) {
                points[3 * p] = i;
                points[3 * p + 1] = j;
                points[3 * p + 2] = k;
            }
    for (int c = 0; c < 6; c++) {
        int i = c % 3, j = c / 3, base = 4 * j + i;
        int32_t quad[4] = {base, base + 1, base + 5, base + 4};
        int flip = 0;
        for (int m = 0; m < mirror_count; m++)
            flip |= mirror[m] == c;
        for (int q = 0; q < 4; q++) {
            conn[8 * c + q + (flip ? 4 : 0)] = quad[q];
            conn[8 * c + q + (flip ? 0 : 4)] = quad[q] + 12;
        }
    }
    return write_vtk(path, points, 24, conn, 6, 8, NULL, NULL);
}

TPK_TEST(mirrored_cells_turned_over_unless_strict)
{
    const int some[] = {4, 2}, all[] = {0, 1, 2, 3, 4, 5};
    const char *in = tpk_temp_path("hex.vtk"), *out = tpk_temp_path("hex.tpk");
    tpk_convert_report r;
    tpk_diag diag;
    CHECK(write_hex_block(in, some, 2) == 0);
    CHECK(convert(in, out, STRICT, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cell 2 (a hexahedron) is mirrored") != NULL, "%s", diag.message);
    CHECK_MSG(strstr(diag.message, "points 14 (2, 0, 1)") != NULL, "%s", diag.message);
    CHECK_MSG(strstr(diag.message, "2 of 6 split cells are mirrored; without --strict-orientation they are turned over"),
              "%s", diag.message);
    CHECK_MSG(convert(in, out, 0, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.mirrored_cells, 2);
    CHECK_EQ_INT(r.inverted_fixed, 0);
    CHECK(write_hex_block(in, all, 6) == 0);
    CHECK(convert(in, out, STRICT, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "so are all 6 split cells: the file lists their nodes in the mirrored"), "%s",
              diag.message);
    CHECK_MSG(convert(in, out, 0, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.mirrored_cells, 6);
    uint64_t size = 0;
    char *meta = read_chunk(out, TPK_TAG_META, 0, &size);
    CHECK(meta != NULL);
    int ok = strstr(meta, "\"reorient\":{\"requested\":true,\"inverted_tets\":0,\"mirrored_cells\":6}") != NULL;
    CHECK_MSG(ok, "META: %s", meta);
    free(meta);
}

/* ---- degenerate tets ----------------------------------------------------------------------------- */

/* 20 tets repeat a node (MANIFEST.md); the "flat" ones are not flat when decided exactly, and 10 slivers
 * are inverted in the stored float32 frame. Turned over, each would fold against a neighbour (issue 9:
 * --reorient used to write folds): they are bad cells, left out with --skip-bad-cells. */
TPK_TEST(degenerate_tets_dropped_and_counted)
{
    const char *in = tpk_data_path("hard/degenerate_tets.vtk"), *out = tpk_temp_path("deg.tpk");
    tpk_convert_report r;
    tpk_diag diag;
    CHECK(convert(in, out, 0, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "has a repeated vertex: points ") && strstr(diag.message, "pass --drop-degenerate"),
              "%s", diag.message);
    CHECK(convert(in, out, DROP, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "is inverted, and turning it over would fold it against its neighbour: the face of "
                                   "points ") &&
                  strstr(diag.message, "10 inverted tets are such bad cells") &&
                  strstr(diag.message, "--skip-bad-cells leaves them out"),
              "%s", diag.message);
    CHECK(convert(in, out, DROP | STRICT, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "10 of 8161 tets are inverted; without --strict-orientation"), "%s", diag.message);
    CHECK_MSG(convert(in, out, DROP | SKIP_BAD, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.degenerate_dropped, 20);
    CHECK_EQ_INT(r.bad_cells_skipped, 10);
    CHECK_EQ_INT(r.tets, 8161 - 20 - 10);
    CHECK_EQ_INT(r.inverted_fixed, 0);
    CHECK_EQ_INT(r.folds_cut, 0);
    uint64_t size = 0;
    char *meta = read_chunk(out, TPK_TAG_META, 0, &size);
    CHECK(meta != NULL);
    int ok = strstr(meta, "\"drop_degenerate\":{\"requested\":true,\"degenerate_tets\":20,\"collapsed_cells\":0}") &&
             strstr(meta, "\"bad_cells_skipped\":10");
    CHECK_MSG(ok, "META: %s", meta);
    free(meta);
}

/* ---- folds --------------------------------------------------------------------------------------- */

/* sfepy's cylinder plus one tet that overlaps a boundary tet, as gmsh's boundary layers do: it stands on
 * a shell face of that tet (found through the converted file's SHEL, VMAP and TMAP) with its apex at the
 * tet's centroid, listed positively, so both lie on the same side of the face they share. *cell is the
 * overlapped source cell, *shell the cylinder's shell face count. */
static int write_overlapping_cylinder(const char *path, int64_t *cell, int64_t *shell)
{
    tpk_mesh src;
    tpk_diag diag;
    tpk_convert_report report;
    uint64_t size = 0;
    const char *tpk = tpk_temp_path("cyl_plain.tpk");
    if (convert(tpk_data_path("sfepy/cylinder.vtk"), tpk, 0, 0, &report, &diag) != 0 ||
        tpk_import_any(tpk_data_path("sfepy/cylinder.vtk"), NULL, &src, &diag) != 0)
        return -1;
    *shell = report.shell_faces;
    tpk_shell_face *faces = (tpk_shell_face *)read_chunk(tpk, TPK_TAG_SHEL, 0, &size);
    int32_t *vmap = (int32_t *)read_chunk(tpk, TPK_TAG_VMAP, 0, &size);
    int32_t *tmap = (int32_t *)read_chunk(tpk, TPK_TAG_TMAP, 0, &size);
    int64_t n = src.point_count, cells = src.cell_count;
    double *points = malloc(sizeof *points * 3 * (size_t)(n + 1));
    int32_t *conn = malloc(sizeof *conn * 4 * (size_t)(cells + 1));
    int rc = -1;
    if (faces && vmap && tmap && points && conn) {
        *cell = tmap[faces[0].t];
        memcpy(points, src.points, sizeof *points * 3 * (size_t)n);
        memcpy(conn, src.cell_conn, sizeof *conn * 4 * (size_t)cells);
        for (int a = 0; a < 3; a++) {
            double sum = 0;
            for (int k = 0; k < 4; k++)
                sum += src.points[3 * (int64_t)src.cell_conn[4 * *cell + k] + a];
            points[3 * n + a] = sum / 4;
        }
        /* (a, b, c) faces out of the overlapped tet, so (a, c, b, centroid) is positive. */
        int32_t *added = conn + 4 * cells;
        added[0] = vmap[faces[0].a];
        added[1] = vmap[faces[0].c];
        added[2] = vmap[faces[0].b];
        added[3] = (int32_t)n;
        rc = write_vtk(path, points, n + 1, conn, cells + 1, 4, NULL, NULL);
    }
    free(faces), free(vmap), free(tmap), free(points), free(conn);
    tpk_mesh_free(&src);
    return rc;
}

TPK_TEST(folds_refused_by_name_then_cut)
{
    const char *in = tpk_temp_path("fold.vtk"), *out = tpk_temp_path("fold.tpk");
    int64_t cell = -1, shell = 0;
    CHECK(write_overlapping_cylinder(in, &cell, &shell) == 0);
    tpk_convert_report r;
    tpk_diag diag;
    char named[64];
    snprintf(named, sizeof named, "is shared by cell %lld (tet ", (long long)cell);
    CHECK(convert(in, out, 0, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "1 folded faces (tets on the same side of a face they share") &&
                  strstr(diag.message, "the first: the face of points ") && strstr(diag.message, named) &&
                  strstr(diag.message, ") and cell 1348 (tet ") && strstr(diag.message, "--cut-folds cuts"),
              "%s", diag.message);
    FILE *f = fopen(out, "rb");
    CHECK(f == NULL); /* nothing written */
    /* Strictness about orientation changes nothing here: both tets are listed positively. */
    CHECK(convert(in, out, STRICT, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "1 folded faces"), "%s", diag.message);
    CHECK_MSG(convert(in, out, CUT_FOLDS, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.folds_cut, 1);
    CHECK_EQ_INT(r.tets, 1349);
    CHECK_EQ_INT(r.shell_faces, shell + 4); /* the cut face stays a shell face of the cylinder, plus 4 of the new tet */
    CHECK_EQ_INT(r.inverted_fixed, 0);
    uint64_t size = 0;
    char *meta = read_chunk(out, TPK_TAG_META, 0, &size);
    CHECK(meta != NULL);
    int ok = strstr(meta, "\"cut_folds\":{\"requested\":true,\"folded_faces\":1}") != NULL;
    CHECK_MSG(ok, "META: %s", meta);
    free(meta);
}

/* The interior faces of positive tets whose fourth points lie on the same side (or on the plane), found
 * one exact orientation test per face: what tpk_find_folds decided before it read the vertex order. */
static int64_t folds_by_exact_test(const tpk_tetmesh *m, const int32_t *neighbors, int64_t *slots, int64_t cap)
{
    int64_t n = 0;
    for (int64_t t = 0; t < m->tet_count; t++)
        for (int k = 0; k < 4; k++) {
            int64_t u = neighbors[4 * t + k];
            if (u <= t)
                continue;
            const int32_t *v = m->tets + 4 * t, *w = m->tets + 4 * u;
            int32_t ia = v[tpk_tet_faces[k][0]], ib = v[tpk_tet_faces[k][1]], ic = v[tpk_tet_faces[k][2]];
            int32_t iy = w[0] ^ w[1] ^ w[2] ^ w[3] ^ ia ^ ib ^ ic;
            const double *p = m->points;
            if (tpk_orient3d_exact(p + 3 * (int64_t)ia, p + 3 * (int64_t)ib, p + 3 * (int64_t)ic, p + 3 * (int64_t)iy) <= 0 &&
                n < cap)
                slots[n++] = 4 * t + k;
        }
    return n;
}

/* The converter's shortcuts, against the long way on real meshes: (1) a mesh split only from hexahedra,
 * wedges and pyramids has every tet's sign checked by the split (tpk_tetmesh.positive_known), so the
 * converter skips orient: orient finds nothing to turn or drop there, also far from the origin
 * (huge_offset_hex: the stored frame is an exact translation of the grid the split decided on), and a
 * Steiner cell (cross3d) or a tetra cell leaves the signs to orient; (2) tpk_find_folds and
 * tpk_connect_folds (face matching) decide most faces by vertex order alone: both find exactly the folds
 * that one exact test per interior face finds, with a fold present (the overlapping cylinder) and
 * without, and the matching gives the same neighbors as tpk_connect. */
TPK_TEST(split_signs_and_folds_by_vertex_order_match_the_exact_tests)
{
    char fold[4096];
    snprintf(fold, sizeof fold, "%s", tpk_temp_path("fold_order.vtk"));
    int64_t cell = -1, shell = 0;
    CHECK(write_overlapping_cylinder(fold, &cell, &shell) == 0);
    struct {
        const char *name; /* in ../shared/data; NULL: the overlapping cylinder */
        int positive_known;
        int64_t folds;
    } cases[] = {
        {"sfepy/acoustic_wg.vtk", 1, 0},
        {"hard/huge_offset_hex.vtu", 1, 0},
        {"seacas/exomerge_unit_test.e", 1, 0},
        {"sfepy/cross3d.mesh", 0, 0}, /* one hexahedron split from its centre (Steiner) */
        {"gmsh/t3_hex_prism_ascii41.msh", 0, 0},
        {"sfepy/cylinder.vtk", 0, 0},
        {NULL, 0, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s", cases[i].name ? tpk_data_path(cases[i].name) : fold);
        tpk_mesh src;
        tpk_tetmesh m;
        tpk_diag diag;
        tpk_header_fields hdr;
        memset(&diag, 0, sizeof diag);
        memset(&hdr, 0, sizeof hdr);
        CHECK_MSG(tpk_import_any(path, NULL, &src, &diag) == 0, "%s", diag.message);
        CHECK_MSG(tpk_tetrahedralize(&src, NULL, 0, TPK_TETRA_FILE_GRID, &m, &diag) == 0, "%s", diag.message);
        CHECK_MSG(tpk_quantize_points(&m, &hdr, &diag) == 0, "%s", diag.message);
        CHECK_MSG(m.positive_known == cases[i].positive_known, "%s: positive_known %d", path, m.positive_known);
        tpk_orient_stats os;
        CHECK_MSG(tpk_orient(&m, 0, 2, &os, &diag) == 0, "%s", diag.message);
        if (m.positive_known)
            CHECK_MSG(os.inverted_fixed == 0 && os.degenerate == 0, "%s: orient turned %lld, found %lld flat",
                      path, (long long)os.inverted_fixed, (long long)os.degenerate);
        int32_t *neighbors = malloc(sizeof *neighbors * 4 * (size_t)m.tet_count);
        int64_t *exact = malloc(sizeof *exact * 64), *found = NULL, found_count = 0;
        CHECK(neighbors && exact);
        CHECK_MSG(tpk_connect(m.tets, m.tet_count, m.vertex_count, neighbors, 2, &diag) == 0, "%s", diag.message);
        CHECK_MSG(tpk_find_folds(m.tets, neighbors, m.tet_count, m.points, 2, &found, &found_count, &diag) == 0, "%s",
                  diag.message);
        int64_t exact_count = folds_by_exact_test(&m, neighbors, exact, 64);
        CHECK_MSG(found_count == exact_count && exact_count == cases[i].folds, "%s: %lld folds by order, %lld by the exact test",
                  path, (long long)found_count, (long long)exact_count);
        for (int64_t f = 0; f < found_count && f < exact_count; f++)
            CHECK_EQ_INT(found[f], exact[f]);
        free(found);
        /* The same folds when face matching finds them (the converter's way), and the same neighbors. */
        int32_t *again = malloc(sizeof *again * 4 * (size_t)m.tet_count);
        CHECK(again != NULL);
        CHECK_MSG(tpk_connect_folds(m.tets, m.tet_count, m.vertex_count, m.points, again, 2, &found, &found_count,
                                    &diag) == 0, "%s", diag.message);
        CHECK(memcmp(again, neighbors, sizeof *again * 4 * (size_t)m.tet_count) == 0);
        CHECK_MSG(found_count == exact_count, "%s: %lld folds in face matching, %lld by the exact test", path,
                  (long long)found_count, (long long)exact_count);
        for (int64_t f = 0; f < found_count && f < exact_count; f++)
            CHECK_EQ_INT(found[f], exact[f]);
        free(found), free(again), free(exact), free(neighbors);
        tpk_tetmesh_free(&m);
        tpk_mesh_free(&src);
    }
}

/* The overlapping tet listed in the mirrored order: turned over, it would fold, so it is a bad cell (not
 * a fold, and not silently flipped). */
TPK_TEST(inverted_overlap_is_a_bad_cell)
{
    const char *in = tpk_temp_path("fold_inv.vtk"), *out = tpk_temp_path("fold_inv.tpk");
    int64_t cell = -1, shell = 0;
    CHECK(write_overlapping_cylinder(in, &cell, &shell) == 0);
    tpk_mesh src;
    tpk_diag diag;
    CHECK(tpk_import_any(in, NULL, &src, &diag) == 0);
    int32_t *added = src.cell_conn + 4 * (src.cell_count - 1), swap = added[1];
    added[1] = added[2];
    added[2] = swap;
    int written = write_vtk(in, src.points, src.point_count, src.cell_conn, src.cell_count, 4, NULL, NULL);
    tpk_mesh_free(&src);
    CHECK(written == 0);
    tpk_convert_report r;
    CHECK(convert(in, out, CUT_FOLDS, 0, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cell 1348 is inverted, and turning it over would fold it against its neighbour") &&
                  strstr(diag.message, "1 inverted tets are such bad cells"),
              "%s", diag.message);
    CHECK_MSG(convert(in, out, SKIP_BAD, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.bad_cells_skipped, 1);
    CHECK_EQ_INT(r.tets, 1348);
    CHECK_EQ_INT(r.shell_faces, shell);
    CHECK_EQ_INT(r.inverted_fixed, 0);
    CHECK_EQ_INT(r.folds_cut, 0);
}

/* ---- duplicate points ---------------------------------------------------------------------------- */

TPK_TEST(merge_exact_duplicates_reconnects_the_cylinder)
{
    const char *in = tpk_temp_path("split.vtk"), *out = tpk_temp_path("split.tpk");
    int64_t tets = 0, shell = 0;
    CHECK(write_split_cylinder(in, 0.0, &tets, &shell) == 0);
    tpk_convert_report r;
    tpk_diag diag;
    /* Without merging: 1348 loose tets, every face on the shell. */
    CHECK_MSG(convert(in, out, 0, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.shell_faces, 4 * tets);
    CHECK_EQ_INT(r.vertices, 4 * tets);
    CHECK_EQ_INT(r.merged_vertices, 0);
    /* Merged: one connected mesh with the cylinder's shell and its 354 points. */
    CHECK_MSG(convert(in, out, MERGE, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.shell_faces, shell);
    CHECK_EQ_INT(r.vertices, 354);
    CHECK_EQ_INT(r.merged_vertices, 4 * tets - 354);
    CHECK_EQ_INT(r.source_points, 4 * tets);
    uint64_t size = 0;
    char *meta = read_chunk(out, TPK_TAG_META, 0, &size);
    CHECK(meta != NULL);
    char want[160];
    snprintf(want, sizeof want, "\"merge_duplicates\":{\"requested\":true,\"tolerance\":0,\"merged_vertices\":%lld}",
             (long long)(4 * tets - 354));
    int ok = strstr(meta, want) != NULL;
    CHECK_MSG(ok, "META lacks %s: %s", want, meta);
    free(meta);
    /* Each kept point is the lowest-id copy (VMAP), and its field value is that copy's own. */
    int32_t *vmap = (int32_t *)read_chunk(out, TPK_TAG_VMAP, 0, &size);
    float *copy = (float *)read_chunk(out, TPK_TAG_FDAT, 0, &size);
    tpk_mesh src;
    CHECK(vmap && copy && tpk_import_any(in, NULL, &src, &diag) == 0);
    int bad = 0;
    for (int64_t v = 0; v < 354; v++) {
        int32_t s = vmap[v];
        bad += copy[v] != (float)s;
        for (int32_t lower = 0; lower < s; lower++)
            bad += !memcmp(src.points + 3 * (int64_t)lower, src.points + 3 * (int64_t)s, 3 * sizeof(double));
    }
    tpk_mesh_free(&src);
    free(vmap);
    free(copy);
    CHECK_EQ_INT(bad, 0);
}

/* Copies moved by up to 5e-9 m per axis (the cylinder's diagonal is 0.115 m): exact merging finds
 * nothing, a tolerance of 1e-6 (0.1 um) finds every copy and nothing else (distinct points are about a
 * millimetre apart). */
TPK_TEST(merge_near_duplicates_within_tolerance)
{
    const char *in = tpk_temp_path("near.vtk"), *out = tpk_temp_path("near.tpk");
    int64_t tets = 0, shell = 0;
    CHECK(write_split_cylinder(in, 1e-8, &tets, &shell) == 0);
    tpk_convert_report r;
    tpk_diag diag;
    CHECK_MSG(convert(in, out, MERGE, 0, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.merged_vertices, 0);
    CHECK_EQ_INT(r.shell_faces, 4 * tets);
    CHECK_MSG(convert(in, out, MERGE, 1e-6, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.merged_vertices, 4 * tets - 354);
    CHECK_EQ_INT(r.shell_faces, shell);
    uint64_t size = 0;
    char *meta = read_chunk(out, TPK_TAG_META, 0, &size);
    CHECK(meta != NULL);
    int ok = strstr(meta, "\"merge_duplicates\":{\"requested\":true,\"tolerance\":9.9999999999999995e-07") ||
             strstr(meta, "\"merge_duplicates\":{\"requested\":true,\"tolerance\":1e-06");
    CHECK_MSG(ok, "META: %s", meta);
    free(meta);
}

/* Two tets, the second with two corners 1e-9 apart: merging within 1e-6 collapses it. Refused, or
 * dropped with --drop-degenerate, its cell value going with it and TMAP naming source cells. */
TPK_TEST(merge_collapsing_a_cell_needs_drop_degenerate)
{
    const double points[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 2, 0, 0, 3, 0, 0, 2, 1, 0, 2, 0, 1e-9,
                             4, 0, 0, 5, 0, 0, 4, 1, 0, 4, 0, 1};
    const int32_t conn[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    const float mat[] = {10, 20, 30};
    const char *in = tpk_temp_path("collapse.vtk"), *out = tpk_temp_path("collapse.tpk");
    CHECK(write_vtk(in, points, 12, conn, 3, 4, NULL, mat) == 0);
    tpk_convert_report r;
    tpk_diag diag;
    CHECK(convert(in, out, MERGE, 1e-6, &r, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "cell 1 (a tetra) collapses when duplicate points are merged: its points 4 "
                                   "(2, 0, 0) and 7 (2, 0, 1.0000000000000001e-09) become one; 1 cells collapse"),
              "%s", diag.message);
    CHECK_MSG(strstr(diag.message, "pass --drop-degenerate"), "%s", diag.message);
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    const char *field = "mat";
    o.input = in;
    o.output = out;
    o.fields = &field;
    o.field_count = 1;
    o.merge_duplicates = 1;
    o.merge_tolerance = 1e-6;
    o.drop_degenerate = 1;
    o.no_reorder = 1;
    CHECK_MSG(tpk_convert_checked(&o, &r, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(r.collapsed_cells_dropped, 1);
    CHECK_EQ_INT(r.merged_vertices, 1);
    CHECK_EQ_INT(r.tets, 2);
    CHECK_EQ_INT(r.vertices, 11); /* 12 less point 7; 4, 5, 6 stay, now in no cell (as source orphans do) */
    uint64_t size = 0;
    int32_t *tmap = (int32_t *)read_chunk(out, TPK_TAG_TMAP, 0, &size);
    float *values = (float *)read_chunk(out, TPK_TAG_FDAT, 0, &size);
    int32_t *vmap = (int32_t *)read_chunk(out, TPK_TAG_VMAP, 0, &size);
    CHECK(tmap && values && vmap);
    int ok = tmap[0] == 0 && tmap[1] == 2 && values[0] == 10 && values[1] == 30 && vmap[10] == 11;
    free(tmap);
    free(values);
    free(vmap);
    CHECK(ok);
}

/* Chains are not followed: 0.6 and 1.2 reach units along a line merge only the first into point 0. */
TPK_TEST(merge_does_not_follow_chains)
{
    double points[] = {0, 0, 0, 0.6, 0, 0, 1.2, 0, 0, 100, 0, 0, 0.3, 0, 0};
    int64_t offsets[] = {0};
    float values[] = {1, 2, 3, 4, 5};
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = 5;
    m.points = points;
    m.cell_offsets = offsets;
    tpk_src_field field = {"f", TPK_ASSOC_POINT, 1, 1, values};
    m.fields = &field;
    m.field_count = 1;
    tpk_merge_report rep;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    /* reach = 0.01 * diagonal 100 = 1: point 1 and point 4 join point 0; point 2 is 1.2 from point 0. */
    CHECK_MSG(tpk_merge_vertices(&m, 0.01, 0, &rep, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(rep.merged_vertices, 2);
    CHECK_EQ_INT(m.point_count, 3);
    CHECK(rep.point_source && rep.point_source[0] == 0 && rep.point_source[1] == 2 && rep.point_source[2] == 3);
    CHECK(points[3] == 1.2 && points[6] == 100 && values[0] == 1 && values[1] == 3 && values[2] == 4);
    CHECK(rep.cell_source == NULL);
    tpk_merge_report_free(&rep);
    CHECK(tpk_merge_vertices(&m, 1e-20, 0, &rep, &diag) != 0);
    CHECK_MSG(strstr(diag.message, "tolerance 1e-20 is outside"), "%s", diag.message);
}

/* -0 and +0 are the same coordinate; NaN is nobody's duplicate. */
TPK_TEST(merge_exact_signed_zero_and_nan)
{
    double points[] = {0, 0, 0, -0.0, 0, -0.0, NAN, 1, 1, NAN, 1, 1, 1, 1, 1};
    int64_t offsets[] = {0};
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = 5;
    m.points = points;
    m.cell_offsets = offsets;
    tpk_merge_report rep;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    CHECK_MSG(tpk_merge_vertices(&m, 0, 0, &rep, &diag) == 0, "%s", diag.message);
    CHECK_EQ_INT(rep.merged_vertices, 1);
    CHECK_EQ_INT(m.point_count, 4);
    tpk_merge_report_free(&rep);
}
