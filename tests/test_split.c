/* Conformal split of hexahedra, voxels, wedges and pyramids (tools/convert/cell_split.c, docs/ARCHITECTURE.md §5):
 * every labelling of a cube gives positive tets filling it exactly and cut along the smallest-id
 * diagonals; grids of each cell type with random global ids give a conforming tet mesh; mirrored cells
 * are turned over and warped ones refused. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "convert/cell_split.h"
#include "harness.h"
#include "import/importers.h"
#include "convert/pipeline.h"
#include "mesh/cell_types.h"
#include "mesh/polyhedron.h"

static const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* 6 x volume of a tet: exact in double for integer and half-integer coordinates. */
static double vol6(const double *p, const int32_t *t)
{
    const double *a = p + 3 * t[0], *b = p + 3 * t[1], *c = p + 3 * t[2], *d = p + 3 * t[3];
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Does some tet have both a and b as vertices (i.e. is a-b an edge of the split)? */
static int has_edge(const int32_t *tets, int n, int32_t a, int32_t b)
{
    for (int i = 0; i < n; i++) {
        int ha = 0, hb = 0;
        for (int k = 0; k < 4; k++) {
            ha |= tets[4 * i + k] == a;
            hb |= tets[4 * i + k] == b;
        }
        if (ha && hb)
            return 1;
    }
    return 0;
}

TPK_TEST(every_cube_labelling)
{
    const int (*faces)[4] = tpk_cell_shape_of(TPK_CELL_HEXAHEDRON)->faces; /* outward: tested below */
    int32_t label[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    double points[8][3];
    int fives = 0, total = 0;
    for (;;) {
        /* vertex label[i] sits at cube corner i */
        for (int i = 0; i < 8; i++)
            memcpy(points[label[i]], cube[i], sizeof cube[i]);
        int32_t tets[6 * 4];
        int mirrored;
        int n = tpk_split_cell(12, label, &points[0][0], tets, &mirrored);
        CHECK_MSG(n == 5 || n == 6, "labelling %d gave %d tets", total, n);
        CHECK(!mirrored);
        double sum = 0;
        for (int i = 0; i < n; i++) {
            double v = vol6(&points[0][0], tets + 4 * i);
            CHECK_MSG(v > 0, "labelling %d: tet %d has 6V = %g", total, i, v);
            sum += v;
        }
        CHECK_MSG(sum == 6, "labelling %d: tets fill 6V = %g of the cube's 6", total, sum);
        for (int f = 0; f < 6; f++) { /* each face is cut along the diagonal through its smallest id */
            int at = 0;
            for (int i = 1; i < 4; i++)
                if (label[faces[f][i]] < label[faces[f][at]])
                    at = i;
            int32_t m = label[faces[f][at]], opposite = label[faces[f][(at + 2) % 4]];
            int32_t other_a = label[faces[f][(at + 1) % 4]], other_b = label[faces[f][(at + 3) % 4]];
            CHECK_MSG(has_edge(tets, n, m, opposite) && !has_edge(tets, n, other_a, other_b),
                      "labelling %d: face %d not cut along its smallest-id diagonal", total, f);
        }
        fives += n == 5;
        total++;
        /* next permutation of label[] */
        int i = 6;
        while (i >= 0 && label[i] > label[i + 1])
            i--;
        if (i < 0)
            break;
        int j = 7;
        while (label[j] < label[i])
            j--;
        int32_t t = label[i];
        label[i] = label[j];
        label[j] = t;
        for (int a = i + 1, b = 7; a < b; a++, b--) {
            t = label[a];
            label[a] = label[b];
            label[b] = t;
        }
    }
    CHECK_EQ_INT(total, 40320);
    /* docs/ARCHITECTURE.md §5: 5 tets suffice for about 21% of labellings. */
    CHECK_MSG(fives > 40320 * 20 / 100 && fives < 40320 * 22 / 100, "%d of 40320 labellings gave 5 tets", fives);
}

/* A mesh of n^3 unit cubes, each as one hexahedron, two wedges or six pyramids around its centre, with
 * vertex ids shuffled; returns its tet mesh after splitting, orienting and connecting. */
static int grid_of(int type, int n, uint64_t seed, tpk_tetmesh *out, int32_t **nb, char *msg, size_t cap)
{
    int64_t corners = (int64_t)(n + 1) * (n + 1) * (n + 1), cells_per = type == 12 ? 1 : type == 13 ? 2 : 6;
    int64_t points = corners + (type == 14 ? (int64_t)n * n * n : 0), cells = (int64_t)n * n * n * cells_per;
    int per = type == 12 ? 8 : type == 13 ? 6 : 5;
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = points;
    m.points = malloc(sizeof(double) * 3 * (size_t)points);
    m.cell_count = cells;
    m.cell_types = malloc((size_t)cells);
    m.cell_offsets = malloc(sizeof(int64_t) * (size_t)(cells + 1));
    m.cell_conn = malloc(sizeof(int32_t) * (size_t)(cells * per));
    int32_t *label = malloc(sizeof(int32_t) * (size_t)points);
    for (int64_t i = 0; i < points; i++)
        label[i] = (int32_t)i;
    for (int64_t i = points - 1; i > 0; i--) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        int64_t j = (int64_t)((seed >> 33) % (uint64_t)(i + 1));
        int32_t t = label[i];
        label[i] = label[j];
        label[j] = t;
    }
#define CORNER(i, j, k) label[((int64_t)(k) * (n + 1) + (j)) * (n + 1) + (i)]
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                double *p = m.points + 3 * CORNER(i, j, k);
                p[0] = i, p[1] = j, p[2] = k;
            }
    int64_t c = 0, at = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                int32_t h[8] = {CORNER(i, j, k), CORNER(i + 1, j, k), CORNER(i + 1, j + 1, k), CORNER(i, j + 1, k),
                                CORNER(i, j, k + 1), CORNER(i + 1, j, k + 1), CORNER(i + 1, j + 1, k + 1),
                                CORNER(i, j + 1, k + 1)};
                int cell_list[6][8], count = 0;
                if (type == 12) {
                    memcpy(cell_list[count++], h, sizeof h);
                } else if (type == 13) { /* split by the x+y diagonal plane: triangles (0,1,2) and (0,2,3) */
                    int w0[6] = {h[0], h[1], h[2], h[4], h[5], h[6]}, w1[6] = {h[0], h[2], h[3], h[4], h[6], h[7]};
                    memcpy(cell_list[count++], w0, sizeof w0);
                    memcpy(cell_list[count++], w1, sizeof w1);
                } else { /* six pyramids from the cube's faces to its centre */
                    int32_t centre = label[corners + ((int64_t)k * n + j) * n + i];
                    double *p = m.points + 3 * centre;
                    p[0] = i + 0.5, p[1] = j + 0.5, p[2] = k + 0.5;
                    static const int faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                                                    {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}};
                    for (int f = 0; f < 6; f++) {
                        int pyr[5] = {h[faces[f][0]], h[faces[f][1]], h[faces[f][2]], h[faces[f][3]], centre};
                        memcpy(cell_list[count++], pyr, sizeof pyr);
                    }
                }
                for (int q = 0; q < count; q++) {
                    m.cell_types[c] = (uint8_t)type;
                    m.cell_offsets[c++] = at;
                    for (int v = 0; v < per; v++)
                        m.cell_conn[at++] = cell_list[q][v];
                }
            }
    m.cell_offsets[c] = at;
    m.step_count = 1;
#undef CORNER
    free(label);
    tpk_diag d;
    memset(&d, 0, sizeof d);
    tpk_orient_stats os;
    int rc = tpk_tetrahedralize(&m, NULL, 0, 0, out, &d);
    tpk_mesh_free(&m);
    if (rc == 0)
        rc = tpk_orient(out, 0, 0, &os, &d);
    if (rc == 0 && os.inverted_fixed != 0)
        rc = tpk_diag_fail(&d, "%lld tets came out inverted", (long long)os.inverted_fixed);
    *nb = rc == 0 ? malloc(sizeof(int32_t) * 4 * (size_t)out->tet_count) : NULL;
    if (rc == 0)
        rc = tpk_connect(out->tets, out->tet_count, out->vertex_count, *nb, 2, &d);
    snprintf(msg, cap, "%.1000s", d.message);
    return rc;
}

static void check_conforming_grid(int type)
{
    const int n = 4;
    for (uint64_t seed = 1; seed <= 5; seed++) {
        tpk_tetmesh m;
        int32_t *nb = NULL;
        char msg[1100] = "";
        int rc = grid_of(type, n, seed, &m, &nb, msg, sizeof msg);
        if (rc) {
            free(nb);
            tpk_tetmesh_free(&m);
        }
        CHECK_MSG(rc == 0, "type %d seed %llu: %s", type, (unsigned long long)seed, msg);
        int64_t open = 0;
        long sum = 0;
        for (int64_t i = 0; i < 4 * m.tet_count; i++)
            open += nb[i] < 0;
        for (int64_t t = 0; t < m.tet_count; t++) /* volumes: points are integers or half-integers */
            sum += (long)(8 * vol6(m.points, m.tets + 4 * t)); /* 8 x 6V: an exact integer */
        free(nb);
        tpk_tetmesh_free(&m);
        /* Conforming: the only open faces are the grid's boundary, 2 triangles per boundary square. */
        CHECK_MSG(open == 2 * 6 * n * n, "type %d seed %llu: %lld open faces, expected %d", type,
                  (unsigned long long)seed, (long long)open, 2 * 6 * n * n);
        CHECK_MSG(sum == 8L * 6 * n * n * n, "type %d: the tets do not fill the grid", type);
    }
}

TPK_TEST(hexahedra_grid_conforms) { check_conforming_grid(12); }
TPK_TEST(wedge_grid_conforms) { check_conforming_grid(13); }
TPK_TEST(pyramid_grid_conforms) { check_conforming_grid(14); }

TPK_TEST(voxel_mirrored_and_warped_cells)
{
    double p[8][3];
    memcpy(p, cube, sizeof p);
    int32_t tets[24];
    int mirrored;
    const int32_t voxel[8] = {0, 1, 3, 2, 4, 5, 7, 6}; /* the cube as a VTK voxel (x, y, z order) */
    CHECK_EQ_INT(tpk_split_cell(11, voxel, &p[0][0], tets, &mirrored), 6);
    CHECK(!mirrored && vol6(&p[0][0], tets) > 0);
    const int32_t upside_down[8] = {4, 5, 6, 7, 0, 1, 2, 3}; /* top and bottom exchanged: mirrored */
    int n = tpk_split_cell(12, upside_down, &p[0][0], tets, &mirrored);
    CHECK(n == 6 && mirrored);
    for (int i = 0; i < n; i++)
        CHECK(vol6(&p[0][0], tets + 4 * i) > 0);
    const int32_t twisted[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    double q[8][3];
    memcpy(q, cube, sizeof q);
    /* Rotate the top face by 90 degrees about the vertical axis: sides fold. */
    const double top[4][3] = {{1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, 1}};
    memcpy(q[4], top, sizeof top);
    CHECK_EQ_INT(tpk_split_cell(12, twisted, &q[0][0], tets, &mirrored), -1);
    const int32_t repeated[8] = {0, 1, 2, 3, 4, 5, 6, 6};
    CHECK_EQ_INT(tpk_split_cell(12, repeated, &p[0][0], tets, &mirrored), -1);
}

/* sfepy's cross3d.mesh: six hexahedra and one with its top face rotated (a twisted cell), which gets a
 * point at its centre; a linear point field there is the mean of the cell's corners. */
TPK_TEST(real_twisted_hexahedron)
{
    tpk_mesh src;
    tpk_tetmesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(tpk_data_path("sfepy/cross3d.mesh"), NULL, &src, &d) == 0, "%s", d.message);
    float *linear = malloc(sizeof *linear * (size_t)src.point_count);
    for (int64_t v = 0; v < src.point_count; v++)
        linear[v] = (float)(src.points[3 * v] + 2 * src.points[3 * v + 1] + 4 * src.points[3 * v + 2]);
    CHECK(tpk_mesh_add_field(&src, "linear", TPK_ASSOC_POINT, 1, 1, linear) == 0);
    int rc = tpk_tetrahedralize(&src, NULL, 0, 0, &m, &d);
    tpk_mesh_free(&src);
    CHECK_MSG(rc == 0, "%s", d.message);
    int ok = m.tet_count == 48 && m.steiner_cells == 1 && m.vertex_count == 33 && m.vertex_source[32] == -1 &&
             m.cells_into[5] + m.cells_into[6] == 6 && m.field_count == 1;
    /* Cell 2's corners are 9..16 (1-based): the centre's value is their mean. */
    const double *c = m.points + 3 * 32;
    double expect = c[0] + 2 * c[1] + 4 * c[2];
    ok = ok && fabs(m.fields[0].values[32] - expect) < 1e-5;
    int32_t *nb = malloc(sizeof *nb * 4 * (size_t)m.tet_count);
    tpk_orient_stats os;
    ok = ok && tpk_orient(&m, 0, 0, &os, &d) == 0 && os.inverted_fixed == 0 &&
         tpk_connect(m.tets, m.tet_count, m.vertex_count, nb, 2, &d) == 0;
    int64_t open = 0;
    for (int64_t i = 0; ok && i < 4 * m.tet_count; i++)
        open += nb[i] < 0;
    free(nb);
    tpk_tetmesh_free(&m);
    CHECK_MSG(ok, "%s", d.message);
    /* Conforming: the cross has 7*6 - 2*6 = 30 boundary squares, 2 triangles each. */
    CHECK_EQ_INT(open, 60);
}

TPK_TEST(bow_tie_cell_cannot_be_starred)
{
    double p[9][3];
    memcpy(p, cube, sizeof cube);
    const int32_t bow[8] = {0, 1, 2, 3, 6, 7, 4, 5}; /* top face turned half a turn */
    int32_t tets[48];
    int mirrored;
    CHECK_EQ_INT(tpk_split_cell(12, bow, &p[0][0], tets, &mirrored), -1);
    const double centre[3] = {0.5, 0.5, 0.5};
    CHECK_EQ_INT(tpk_star_cell(12, bow, &p[0][0], centre, 8, tets, &mirrored), -1);
    const int32_t plain[8] = {0, 1, 2, 3, 4, 5, 6, 7}; /* a plain cube is starred too: 12 positive tets */
    memcpy(p[8], centre, sizeof centre);
    int n = tpk_star_cell(12, plain, &p[0][0], centre, 8, tets, &mirrored);
    CHECK_EQ_INT(n, 12);
    double sum = 0;
    for (int i = 0; i < n; i++) {
        double v = vol6(&p[0][0], tets + 4 * i);
        CHECK(v > 0);
        sum += v;
    }
    CHECK(sum == 6);
}

/* --cell-to-point: two unit hexahedra side by side with cell values 1 and 3 (and 10, 30 in a second
 * step): the four shared points get the means 2 and 20, the others their one cell's value, and a point
 * in no cell NaN. Without field names the cell field is kept (as a point field). */
TPK_TEST(cell_to_point_means)
{
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = 13;
    m.points = calloc(3 * 13, sizeof(double));
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 3; i++) {
                double *p = m.points + 3 * (k * 6 + j * 3 + i);
                p[0] = i, p[1] = j, p[2] = k;
            }
    m.points[3 * 12] = 9; /* point 12: in no cell */
    m.cell_count = 2;
    m.cell_types = malloc(2);
    m.cell_types[0] = m.cell_types[1] = 12;
    m.cell_offsets = malloc(3 * sizeof(int64_t));
    m.cell_offsets[0] = 0, m.cell_offsets[1] = 8, m.cell_offsets[2] = 16;
    const int32_t conn[16] = {0, 1, 4, 3, 6, 7, 10, 9, 1, 2, 5, 4, 7, 8, 11, 10};
    m.cell_conn = malloc(sizeof conn);
    memcpy(m.cell_conn, conn, sizeof conn);
    m.step_count = 2;
    float *values = malloc(4 * sizeof(float));
    values[0] = 1, values[1] = 3, values[2] = 10, values[3] = 30;
    CHECK(tpk_mesh_add_field(&m, "material", TPK_ASSOC_TET, 1, 2, values) == 0);
    tpk_tetmesh out;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    int rc = tpk_tetrahedralize(&m, NULL, 0, TPK_TETRA_CELL_TO_POINT, &out, &d);
    tpk_mesh_free(&m);
    CHECK_MSG(rc == 0, "%s", d.message);
    int ok = out.field_count == 1 && out.fields[0].association == TPK_ASSOC_POINT && out.fields[0].step_count == 2;
    const float *v = out.fields[0].values;
    const int shared[4] = {1, 4, 7, 10}, left[4] = {0, 3, 6, 9}, right[4] = {2, 5, 8, 11};
    for (int i = 0; ok && i < 4; i++)
        ok = v[shared[i]] == 2 && v[left[i]] == 1 && v[right[i]] == 3 && v[13 + shared[i]] == 20 &&
             v[13 + right[i]] == 30;
    ok = ok && isnan(v[12]) && isnan(v[13 + 12]);
    tpk_tetmesh_free(&out);
    CHECK(ok);
}

/* A grid of n^3 hexahedra, ids shuffled, every inner point moved by up to `jitter` along each axis:
 * cells warp, some need a point at their centre, some a point on a face that the cell across then
 * shares. Whatever splits must still fill the cube exactly (the boundary is not moved) and conform
 * (its only open faces the cube's 2 x 6 n^2 triangles); what cannot is refused naming the cell. */
static void jittered_grid(int n, double jitter, uint64_t seed, tpk_mesh *m)
{
    int64_t points = (int64_t)(n + 1) * (n + 1) * (n + 1), cells = (int64_t)n * n * n;
    memset(m, 0, sizeof *m);
    m->point_count = points;
    m->points = malloc(sizeof(double) * 3 * (size_t)points);
    m->cell_count = cells;
    m->cell_types = malloc((size_t)cells);
    m->cell_offsets = malloc(sizeof(int64_t) * (size_t)(cells + 1));
    m->cell_conn = malloc(sizeof(int32_t) * 8 * (size_t)cells);
    int32_t *label = malloc(sizeof(int32_t) * (size_t)points);
    for (int64_t i = 0; i < points; i++)
        label[i] = (int32_t)i;
    for (int64_t i = points - 1; i > 0; i--) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        int64_t j = (int64_t)((seed >> 33) % (uint64_t)(i + 1));
        int32_t t = label[i];
        label[i] = label[j];
        label[j] = t;
    }
#define CORNER(i, j, k) label[((int64_t)(k) * (n + 1) + (j)) * (n + 1) + (i)]
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                double *p = m->points + 3 * CORNER(i, j, k);
                int inner = i > 0 && i < n && j > 0 && j < n && k > 0 && k < n;
                p[0] = i, p[1] = j, p[2] = k;
                for (int a = 0; inner && a < 3; a++) { /* multiples of 1/64: coordinates stay exact */
                    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                    p[a] += jitter * (double)((int)((seed >> 33) % 129) - 64) / 64;
                }
            }
    int64_t c = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++, c++) {
                int32_t h[8] = {CORNER(i, j, k), CORNER(i + 1, j, k), CORNER(i + 1, j + 1, k), CORNER(i, j + 1, k),
                                CORNER(i, j, k + 1), CORNER(i + 1, j, k + 1), CORNER(i + 1, j + 1, k + 1),
                                CORNER(i, j + 1, k + 1)};
                m->cell_types[c] = TPK_CELL_HEXAHEDRON;
                m->cell_offsets[c] = 8 * c;
                memcpy(m->cell_conn + 8 * c, h, sizeof h);
            }
#undef CORNER
    m->cell_offsets[cells] = 8 * cells;
    m->step_count = 1;
    free(label);
}

TPK_TEST(jittered_grid_conforms_with_added_points)
{
    const int n = 5;
    int64_t face_points = 0, steiner = 0, converted = 0, refused = 0;
    for (uint64_t seed = 1; seed <= 40; seed++) {
        tpk_mesh src;
        tpk_tetmesh m;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        jittered_grid(n, 0.45, seed, &src);
        int rc = tpk_tetrahedralize(&src, NULL, 0, 0, &m, &d);
        tpk_mesh_free(&src);
        if (rc) {
            CHECK_MSG(strstr(d.message, "is too warped, non-convex or degenerate to split"), "seed %llu: %s",
                      (unsigned long long)seed, d.message);
            refused++;
            continue;
        }
        tpk_orient_stats os;
        int32_t *nb = malloc(sizeof *nb * 4 * (size_t)m.tet_count);
        int ok = tpk_orient(&m, 0, 1, &os, &d) == 0 && os.inverted_fixed == 0 &&
                 tpk_connect(m.tets, m.tet_count, m.vertex_count, nb, 1, &d) == 0;
        int64_t open = 0;
        double sum = 0;
        for (int64_t i = 0; ok && i < 4 * m.tet_count; i++)
            open += nb[i] < 0;
        for (int64_t t = 0; ok && t < m.tet_count; t++)
            sum += vol6(m.points, m.tets + 4 * t);
        face_points += m.face_steiner_points;
        steiner += m.steiner_cells;
        converted++;
        free(nb);
        tpk_tetmesh_free(&m);
        CHECK_MSG(ok, "seed %llu: %s", (unsigned long long)seed, d.message);
        CHECK_MSG(open == 2 * 6 * n * n, "seed %llu: %lld open faces, expected %d", (unsigned long long)seed,
                  (long long)open, 2 * 6 * n * n);
        CHECK_MSG(fabs(sum - 6.0 * n * n * n) <= 1e-12 * 6 * n * n * n, "seed %llu: 6V %.17g", (unsigned long long)seed,
                  sum);
    }
    fprintf(stderr, "jittered grids: %lld converted (%lld cells from a centre point, %lld face points), %lld "
            "refused\n", (long long)converted, (long long)steiner, (long long)face_points, (long long)refused);
    CHECK(converted >= 20 && steiner > 0 && face_points > 0);
}

/* The plain split runs on several cores, each worker writing where its range of cells can start at the
 * most, the blocks then closed up (tools/convert/split_plain.c): the tets, their source cells and every
 * count must be those of one worker, on a grid big enough for 3 workers, with 5-tet hexahedra (ids
 * shuffled), mirrored cells (every 7th cell listed upside down) and cells only an added point splits
 * (jitter), spread over all ranges. */
TPK_TEST(split_is_the_same_on_any_thread_count)
{
    const int n = 60; /* 216,000 cells: 3 ranges of 65,536 or more */
    tpk_tetmesh runs[3];
    for (int r = 0; r < 3; r++) {
        tpk_mesh src;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        jittered_grid(n, 0.3, 7, &src);
        for (int64_t c = 0; c < src.cell_count; c += 7) {
            int32_t *h = src.cell_conn + 8 * c, low[4];
            memcpy(low, h, sizeof low);
            memmove(h, h + 4, sizeof low);
            memcpy(h + 4, low, sizeof low);
        }
        int rc = tpk_tetrahedralize_watched(&src, NULL, 0, 0, r + 1, NULL, &runs[r], &d);
        tpk_mesh_free(&src);
        CHECK_MSG(rc == 0, "%d threads: %s", r + 1, d.message);
        if (rc)
            return;
    }
    const tpk_tetmesh *one = &runs[0];
    fprintf(stderr, "split on 1-3 threads: %lld tets, %lld 5-tet and %lld 6-tet cells, %lld mirrored (first %lld), "
            "%lld from a centre point\n", (long long)one->tet_count, (long long)one->cells_into[5],
            (long long)one->cells_into[6], (long long)one->mirrored_cells, (long long)one->first_mirrored_cell,
            (long long)one->steiner_cells);
    CHECK(one->cells_into[5] > 1000 && one->mirrored_cells > 1000 && one->steiner_cells > 0);
    for (int r = 1; r < 3; r++) {
        const tpk_tetmesh *m = &runs[r];
        CHECK_MSG(m->tet_count == one->tet_count && m->vertex_count == one->vertex_count, "%d threads: counts", r + 1);
        CHECK_MSG(m->tet_count == one->tet_count &&
                      !memcmp(m->tets, one->tets, sizeof *m->tets * 4 * (size_t)m->tet_count) &&
                      !memcmp(m->tet_source, one->tet_source, sizeof *m->tet_source * (size_t)m->tet_count),
                  "%d threads: other tets", r + 1);
        CHECK_MSG(!memcmp(m->cells_into, one->cells_into, sizeof m->cells_into) &&
                      m->mirrored_cells == one->mirrored_cells && m->first_mirrored_cell == one->first_mirrored_cell &&
                      m->steiner_cells == one->steiner_cells && m->face_steiner_points == one->face_steiner_points,
                  "%d threads: other counts", r + 1);
    }
    for (int r = 0; r < 3; r++)
        tpk_tetmesh_free(&runs[r]);
}

/* tpk_cell_faces: outward faces (positive enclosed volume on the unit cube's corners) that close up,
 * for every type the split knows; nothing for a tetrahedron. */
TPK_TEST(cell_faces_are_outward_and_closed)
{
    const int32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7}, voxel[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    const int32_t wedge[6] = {0, 1, 3, 4, 5, 7}, pyramid[5] = {0, 1, 2, 3, 6};
    const struct { int type; const int32_t *nodes; double volume6; } cells[4] = {
        {TPK_CELL_HEXAHEDRON, hex, 6}, {TPK_CELL_VOXEL, voxel, 6}, {TPK_CELL_WEDGE, wedge, 3},
        {TPK_CELL_PYRAMID, pyramid, 2}};
    tpk_polygons p;
    memset(&p, 0, sizeof p);
    char why[200] = "";
    for (int i = 0; i < 4; i++) {
        int ok = tpk_polygons_from_cell(&p, cells[i].type, cells[i].nodes) == 0 &&
                 tpk_polygons_orient(&p, why, sizeof why) == 0;
        double v = ok ? tpk_polygons_volume6(&p, &cube[0][0]) : 0;
        if (!ok || v != cells[i].volume6)
            tpk_polygons_free(&p);
        CHECK_MSG(ok && v == cells[i].volume6, "type %d: 6V %g, expected %g %s", cells[i].type, v, cells[i].volume6, why);
    }
    int32_t ids[24];
    int starts[7];
    CHECK_EQ_INT(tpk_cell_faces(TPK_CELL_TETRA, hex, ids, starts), 0);
    tpk_polygons_free(&p);
}

/* tpk_cell_shape_of (mesh/cell_types.c), the one table of cell faces and edges: every shape's faces
 * enclose its reference cell with positive volume (outward), every edge bounds exactly two faces and the
 * faces have no other edges, a tet's faces are format's tpk_tet_faces. */
TPK_TEST(cell_shapes_are_outward_with_their_edges)
{
    static const double volume6[5] = {1, 6, 6, 3, 2}; /* tetra, voxel, hexahedron, wedge, pyramid */
    for (int type = TPK_CELL_TETRA; type <= TPK_CELL_PYRAMID; type++) {
        const tpk_cell_shape *s = tpk_cell_shape_of(type);
        CHECK(s != NULL && s->type == type);
        double v6 = 0;
        int uses[12] = {0}, face_edges = 0;
        for (int f = 0; f < s->face_count; f++) {
            const int *q = s->faces[f];
            for (int i = 1; i + 1 < s->face_size[f]; i++) { /* fan: 6V = sum of a . (b x c) */
                const double *a = s->ref[q[0]], *b = s->ref[q[i]], *c = s->ref[q[i + 1]];
                v6 += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                      a[2] * (b[0] * c[1] - b[1] * c[0]);
            }
            for (int i = 0; i < s->face_size[f]; i++, face_edges++) {
                int x = q[i], y = q[(i + 1) % s->face_size[f]], found = -1;
                for (int e = 0; e < s->edge_count; e++)
                    if ((s->edges[e][0] == x && s->edges[e][1] == y) || (s->edges[e][0] == y && s->edges[e][1] == x))
                        found = e;
                CHECK_MSG(found >= 0, "type %d: face %d has edge (%d, %d), not in the edge table", type, f, x, y);
                if (found >= 0)
                    uses[found]++;
            }
        }
        CHECK_MSG(v6 == volume6[type - TPK_CELL_TETRA], "type %d: 6V %g", type, v6);
        CHECK_EQ_INT(face_edges, 2 * s->edge_count);
        for (int e = 0; e < s->edge_count; e++)
            CHECK_MSG(uses[e] == 2, "type %d: edge %d bounds %d faces", type, e, uses[e]);
    }
    const tpk_cell_shape *tet = tpk_cell_shape_of(TPK_CELL_TETRA);
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            CHECK_EQ_INT(tet->faces[k][i], tpk_tet_faces[k][i]);
    CHECK(tpk_cell_shape_of(TPK_CELL_POLYHEDRON) == NULL && tpk_cell_shape_of(9) == NULL);
}
