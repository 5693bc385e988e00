/* Higher-order cells kept whole (tools/mesh/higher_order.c, tools/mesh/cell_map.c): for each format's
 * node order, written here from the format's own documentation (not from the readers' tables), one cell
 * of each kind whose map is known in closed form (an affine map of the reference cell, and a curved
 * quadratic one) and whose point field is a quadratic polynomial of position. Split and tetrahedralized:
 * every node is a tet vertex with its value, the tets are positive and fill the cell's volume exactly,
 * and the points the split adds sit where the cell's map puts them and carry the field's own value (the
 * quadratic cells reproduce quadratic fields) at every step; a cell field is its cell's value on each of
 * the cell's tets. A wrong node order folds the pieces, so the volume or the
 * signs fail. */
#include <exodusII.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/pipeline.h"
#include "check/check_against.h"
#include "convert/convert.h"
#include "convert/refine.h"
#include "harness.h"
#include "import/importers.h"
#include "mesh/cell_map.h"
#include "mesh/cell_types.h"
#include "mesh/higher_order.h"
#include "tetpack_format.h"
#include "tpk_assert.h"

#ifdef TPK_TEST_CGNS
#include <cgnslib.h>
#endif

/* A format's node order for one kind: its corners (of `shape`, in VTK's corner order, which every
 * format here shares), then mid-edge nodes on `edges`, then face centres on `faces` (a triangle's 4th
 * corner repeats its 3rd), then the centre (the centroid: a pyramid's at a quarter of its height). */
typedef struct node_order {
    const char *name;   /* the format's element name */
    int code;           /* its type code in the format (gmsh element type, VTK cell type, ...) */
    int shape, edge_count, face_count, centre; /* centre: 1 after the face centres, 2 before them */
    int edges[12][2];
    int faces[6][4];
} node_order;

static const double corner_ref[15][8][3] = {
    [10] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    [12] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
    [13] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}},
    [14] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}},
};
static const int corner_count[15] = {[10] = 4, [12] = 8, [13] = 6, [14] = 5};
static const double ref_volume[15] = {[10] = 1.0 / 6, [12] = 1, [13] = 0.5, [14] = 1.0 / 3};

/* Node k's reference coordinates; returns the node count. */
static int order_nodes(const node_order *o, double r[27][3])
{
    int n = corner_count[o->shape];
    memcpy(r, corner_ref[o->shape], sizeof(double) * 3 * (size_t)n);
    for (int e = 0; e < o->edge_count; e++, n++)
        for (int a = 0; a < 3; a++)
            r[n][a] = 0.5 * (r[o->edges[e][0]][a] + r[o->edges[e][1]][a]);
    int corners = corner_count[o->shape];
    double centre[3] = {0, 0, 0};
    for (int k = 0; k < corners; k++)
        for (int a = 0; a < 3; a++)
            centre[a] += r[k][a] / corners;
    if (o->shape == 14)
        centre[2] = 0.25;
    if (o->centre == 2)
        memcpy(r[n++], centre, sizeof centre);
    for (int f = 0; f < o->face_count; f++, n++) {
        const int *q = o->faces[f];
        int tri = q[3] == q[2];
        for (int a = 0; a < 3; a++)
            r[n][a] = tri ? (r[q[0]][a] + r[q[1]][a] + r[q[2]][a]) / 3
                          : 0.25 * (r[q[0]][a] + r[q[1]][a] + r[q[2]][a] + r[q[3]][a]);
    }
    if (o->centre == 1)
        memcpy(r[n++], centre, sizeof centre);
    return n;
}

/* The cells' maps: x = A r + shift (+ a quadratic bend when curved). det A = 2.961. */
static const double A[3][3] = {{1.5, 0.3, 0.1}, {0.2, 1.4, -0.2}, {0.1, 0.4, 1.5}};

static void map_point(const double r[3], double shift, int curved, double x[3])
{
    for (int i = 0; i < 3; i++)
        x[i] = A[i][0] * r[0] + A[i][1] * r[1] + A[i][2] * r[2] + (i == 0 ? shift : 0);
    if (curved) { /* a bend quadratic in r: the quadratic cells hold it exactly */
        x[2] += 0.2 * r[0] * (1 - r[0]);
        x[1] += 0.15 * r[2] * r[2];
    }
}

static double det_a(void)
{
    return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
           A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
}

/* The field: a quadratic polynomial of position (step 0), and twice it (step 1); only its linear part
 * with linear_field set. */
static int linear_field;

static double field_at(const double x[3])
{
    if (linear_field)
        return 1 + x[0] - 2 * x[1] + 0.5 * x[2];
    return 1 + x[0] - 2 * x[1] + 0.5 * x[2] + x[0] * x[0] - 0.7 * x[0] * x[1] + 0.3 * x[1] * x[2] - 0.4 * x[2] * x[2];
}

static double tet_volume(const double *p, const int32_t *t)
{
    const double *a = p + 3 * t[0], *b = p + 3 * t[1], *c = p + 3 * t[2], *d = p + 3 * t[3];
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++)
        u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = d[k] - a[k];
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6;
}

/* The checks, on a mesh of cells of the kinds in `orders` (cell c of kind orders[c], shifted by 3c,
 * curved or not) as read: every node a tet vertex, tets positive, volumes exact (affine), the field
 * reproduced at every vertex, added points on the map. */
static void check_whole(tpk_mesh *m, const node_order *const *orders, int curved, int expect_type_of_first)
{
    CHECK_EQ_INT(m->cell_types[0], expect_type_of_first);
    int64_t cells = m->cell_count, points = m->point_count;
    /* a cell field: 10 c + 1 in cell c, which each of the cell's tets must carry */
    float *cell_values = malloc(sizeof *cell_values * (size_t)cells);
    for (int64_t c = 0; c < cells; c++)
        cell_values[c] = 10.0f * (float)c + 1;
    CHECK(tpk_mesh_add_field(m, "cell", TPK_ASSOC_TET, 1, 1, cell_values) == 0);
    tpk_diag d;
    memset(&d, 0, sizeof d);
    tpk_higher_split h;
    CHECK_MSG(tpk_split_higher_order(m, "test", &h, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(h.split_cells, cells);
    CHECK_EQ_INT(h.reduced_cells, 0);
    uint8_t *used = calloc((size_t)m->point_count, 1);
    for (int64_t k = 0; k < m->cell_offsets[m->cell_count]; k++)
        used[m->cell_conn[k]] = 1;
    for (int64_t p = 0; p < m->point_count; p++)
        CHECK_MSG(used[p], "point %lld is no linear cell's corner", (long long)p);
    free(used);
    tpk_tetmesh t;
    const char *names[] = {"f", "cell"};
    CHECK_MSG(tpk_tetrahedralize(m, names, 2, 0, &t, &d) == 0, "%s", d.message);
    CHECK(t.field_count == 2 && t.fields[1].association == TPK_ASSOC_TET);
    for (int64_t k = 0; k < t.tet_count; k++)
        CHECK_MSG(t.fields[1].values[k] == 10.0f * (float)h.cell_source[t.tet_source[k]] + 1,
                  "tet %lld: cell field %g, its cell %d", (long long)k, t.fields[1].values[k],
                  h.cell_source[t.tet_source[k]]);
    CHECK_EQ_INT(t.mirrored_cells, 0);
    double *volume = calloc((size_t)cells, sizeof *volume);
    for (int64_t k = 0; k < t.tet_count; k++) {
        double v = tet_volume(t.points, t.tets + 4 * k);
        CHECK_MSG(v > 0, "tet %lld of cell %d: volume %g", (long long)k, h.cell_source[t.tet_source[k]], v);
        volume[h.cell_source[t.tet_source[k]]] += v;
    }
    for (int64_t c = 0; c < cells && !curved; c++) {
        double want = det_a() * ref_volume[orders[c]->shape];
        CHECK_MSG(fabs(volume[c] - want) < 1e-12 * want, "%s: volume %.17g, expected %.17g", orders[c]->name,
                  volume[c], want);
    }
    free(volume);
    /* Values: the field at every vertex, exact at the nodes (as float), reproduced at added points. */
    CHECK(t.fields[0].step_count == 2);
    for (int64_t v = 0; v < t.vertex_count; v++) {
        double want = field_at(t.points + 3 * v);
        for (int s = 0; s < 2; s++) {
            double got = t.fields[0].values[s * t.vertex_count + v];
            CHECK_MSG(fabs(got - (s + 1) * want) < 2e-6 * (1 + fabs(want)) || curved,
                      "vertex %lld (%s) step %d: %.9g, expected %.9g", (long long)v, v < points ? "a node" : "added", s,
                      got, (s + 1) * want);
        }
    }
    /* Added points on the cell's map: at the map of a face or cell centre of some cell. */
    for (int64_t v = points; v < t.vertex_count; v++) {
        double best = 1e300;
        for (int64_t c = 0; c < cells; c++) {
            double centres[8][3];
            int nc = 0, shape = orders[c]->shape;
            if (shape == 12) {
                static const double hc[7][3] = {{0, .5, .5}, {1, .5, .5}, {.5, 0, .5}, {.5, 1, .5},
                                                {.5, .5, 0}, {.5, .5, 1}, {.5, .5, .5}};
                memcpy(centres, hc, sizeof hc), nc = 7;
            } else if (shape == 13) {
                static const double wc[3][3] = {{.5, 0, .5}, {.5, .5, .5}, {0, .5, .5}};
                memcpy(centres, wc, sizeof wc), nc = 3;
            } else if (shape == 14) {
                centres[0][0] = centres[0][1] = 0.5, centres[0][2] = 0, nc = 1;
            }
            for (int i = 0; i < nc; i++) {
                double x[3];
                map_point(centres[i], 3.0 * (double)c, curved, x);
                double dist = fabs(x[0] - t.points[3 * v]) + fabs(x[1] - t.points[3 * v + 1]) +
                              fabs(x[2] - t.points[3 * v + 2]);
                best = dist < best ? dist : best;
            }
        }
        CHECK_MSG(best < 1e-12, "added point %lld is %g from every face and cell centre", (long long)v, best);
    }
    free(h.cell_source);
    tpk_tetmesh_free(&t);
}

/* ---- VTK legacy: VTK's own orders (vtkQuadraticTetra, ...: the class comments' edge and face lists) ---- */

static const node_order vtk_tet10 = {"VTK quadratic tetra", 24, 10, 6, 0, 0,
                                     {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}, {{0}}};
static const node_order vtk_hex20 = {"VTK quadratic hexahedron", 25, 12, 12, 0, 0,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5},
                                      {2, 6}, {3, 7}}, {{0}}};
static const node_order vtk_hex27 = {"VTK triquadratic hexahedron", 29, 12, 12, 6, 1,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5},
                                      {2, 6}, {3, 7}},
                                     {{0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 2, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}}};
static const node_order vtk_wedge15 = {"VTK quadratic wedge", 26, 13, 9, 0, 0,
                                       {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}}, {{0}}};
static const node_order vtk_wedge18 = {"VTK biquadratic quadratic wedge", 32, 13, 9, 3, 0,
                                       {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}},
                                       {{0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}}};
static const node_order vtk_wedge12 = {"VTK quadratic linear wedge", 31, 13, 6, 0, 0,
                                       {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}}, {{0}}};
static const node_order vtk_pyramid13 = {"VTK quadratic pyramid", 27, 14, 8, 0, 0,
                                         {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}}, {{0}}};
/* vtkBiQuadraticQuadraticHexahedron: the 20 nodes, then the centres of faces x-, x+, y-, y+ (none on z-,
 * z+, nor the cell's); vtkTriQuadraticPyramid: the 13, then the centres of the base and of sides 014,
 * 124, 234, 304, then the centroid. */
static const node_order vtk_hex24 = {"VTK biquadratic-quadratic hexahedron", 33, 12, 12, 4, 0,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5},
                                      {2, 6}, {3, 7}},
                                     {{0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 2, 6, 7}}};
static const node_order vtk_pyramid19 = {"VTK triquadratic pyramid", 37, 14, 8, 5, 1,
                                         {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
                                         {{0, 3, 2, 1}, {0, 1, 4, 4}, {1, 2, 4, 4}, {2, 3, 4, 4}, {3, 0, 4, 4}}};

/* A legacy VTK file of the cells `orders` (cell c shifted by 3c) with the point field "f" (its second
 * step is added after reading: add_second_step). */
static char *write_vtk(const node_order *const *orders, int count, int curved)
{
    size_t cap = 1 << 16, at = 0;
    char *text = malloc(cap);
    int total = 0, ns[16];
    double r[16][27][3];
    for (int c = 0; c < count; c++)
        total += ns[c] = order_nodes(orders[c], r[c]);
    at += (size_t)snprintf(text + at, cap - at, "# vtk DataFile Version 3.0\nwhole\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                                                "POINTS %d double\n", total);
    for (int c = 0; c < count; c++)
        for (int k = 0; k < ns[c]; k++) {
            double x[3];
            map_point(r[c][k], 3.0 * c, curved, x);
            at += (size_t)snprintf(text + at, cap - at, "%.17g %.17g %.17g\n", x[0], x[1], x[2]);
        }
    at += (size_t)snprintf(text + at, cap - at, "CELLS %d %d\n", count, count + total);
    for (int c = 0, first = 0; c < count; first += ns[c], c++) {
        at += (size_t)snprintf(text + at, cap - at, "%d", ns[c]);
        for (int k = 0; k < ns[c]; k++)
            at += (size_t)snprintf(text + at, cap - at, " %d", first + k);
        at += (size_t)snprintf(text + at, cap - at, "\n");
    }
    at += (size_t)snprintf(text + at, cap - at, "CELL_TYPES %d\n", count);
    for (int c = 0; c < count; c++)
        at += (size_t)snprintf(text + at, cap - at, "%d\n", orders[c]->code);
    at += (size_t)snprintf(text + at, cap - at, "POINT_DATA %d\nSCALARS f double 1\nLOOKUP_TABLE default\n", total);
    for (int c = 0; c < count; c++)
        for (int k = 0; k < ns[c]; k++) {
            double x[3];
            map_point(r[c][k], 3.0 * c, curved, x);
            at += (size_t)snprintf(text + at, cap - at, "%.17g\n", field_at(x));
        }
    return text;
}

/* The point field "f" given a second step, twice the first (time steps through the split). */
static void add_second_step(tpk_mesh *m)
{
    for (int i = 0; i < m->field_count; i++) {
        tpk_src_field *f = &m->fields[i];
        if (strcmp(f->name, "f") || f->step_count != 1)
            continue;
        float *v = realloc(f->values, sizeof *v * 2 * (size_t)m->point_count);
        for (int64_t p = 0; p < m->point_count; p++)
            v[m->point_count + p] = 2 * v[p];
        f->values = v, f->step_count = 2;
        m->step_count = 2;
    }
}

static void quiet_warn(void *user, const char *text)
{
    (void)user, (void)text;
}

static void quiet(tpk_diag *d)
{
    memset(d, 0, sizeof *d);
    d->warn = quiet_warn;
}

TPK_TEST(vtk_types)
{
    const node_order *orders[] = {&vtk_tet10,    &vtk_hex20,     &vtk_hex27, &vtk_wedge15,  &vtk_wedge18,
                                  &vtk_wedge12,  &vtk_pyramid13, &vtk_hex24, &vtk_pyramid19};
    for (int curved = 0; curved < 2; curved++) {
        char *text = write_vtk(orders, 9, curved);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_vtk_legacy_memory("whole.vtk", text, strlen(text), &m, &d) == 0, "%s", d.message);
        free(text);
        add_second_step(&m);
        check_whole(&m, orders, curved, 24);
        tpk_mesh_free(&m);
    }
}

/* VTK's Lagrange cells of order 2 in VTK 9's numbering: the quadratic tetra's, triquadratic hexahedron's
 * and biquadratic-quadratic wedge's (vtkHigherOrderHexahedron: corners, edges, faces -x +x -y +y -z +z,
 * body); and the 15-node tetra (vtkHigherOrderTetra's special case: the 10, the centres of faces 012,
 * 013, 123, 023, the body centre). */
static const node_order vtk_tet15 = {"VTK Lagrange tetra of 15 nodes", 71, 10, 6, 4, 1,
                                     {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
                                     {{0, 1, 2, 2}, {0, 1, 3, 3}, {1, 2, 3, 3}, {0, 2, 3, 3}}};

TPK_TEST(lagrange_types)
{
    node_order tet = vtk_tet10, hex = vtk_hex27, wedge = vtk_wedge18;
    tet.code = 71, hex.code = 72, wedge.code = 73;
    tet.name = "VTK Lagrange tetra", hex.name = "VTK Lagrange hexahedron", wedge.name = "VTK Lagrange wedge";
    const node_order *orders[] = {&tet, &hex, &wedge, &vtk_tet15};
    for (int curved = 0; curved < 2; curved++) {
        char *text = write_vtk(orders, 4, curved);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_vtk_legacy_memory("lagrange.vtk", text, strlen(text), &m, &d) == 0, "%s", d.message);
        free(text);
        add_second_step(&m);
        check_whole(&m, orders, curved, 71);
        tpk_mesh_free(&m);
    }
}

/* Every shape function table: weights sum to 1, are 1 at their node and 0 at the others, and reproduce
 * quadratic polynomials (the quadratic-linear wedge: those linear in t). */
TPK_TEST(shape_functions)
{
    const node_order *orders[] = {&vtk_tet10,   &vtk_hex20,     &vtk_hex27, &vtk_wedge15,
                                  &vtk_wedge18, &vtk_wedge12,   &vtk_pyramid13, &vtk_hex24};
    for (int i = 0; i < 8; i++) {
        double r[27][3], w[TPK_CELL_MAP_MAX_NODES];
        int n = order_nodes(orders[i], r);
        CHECK_EQ_INT(tpk_cell_map_nodes(orders[i]->code), n);
        for (int k = 0; k < n; k++) {
            double at[3];
            tpk_cell_map_node(orders[i]->code, k, at);
            CHECK_MSG(at[0] == r[k][0] && at[1] == r[k][1] && at[2] == r[k][2], "%s node %d", orders[i]->name, k);
            CHECK_EQ_INT(tpk_cell_map_weights(orders[i]->code, r[k], w), n);
            for (int j = 0; j < n; j++)
                CHECK_MSG(fabs(w[j] - (j == k)) < 1e-15, "%s: N%d at node %d = %g", orders[i]->name, j, k, w[j]);
        }
        const double inside[3] = {0.21, 0.17, 0.33};
        double sum = 0;
        tpk_cell_map_weights(orders[i]->code, inside, w);
        for (int j = 0; j < n; j++)
            sum += w[j];
        CHECK_MSG(fabs(sum - 1) < 1e-15, "%s: weights sum to %.17g", orders[i]->name, sum);
        /* every quadratic polynomial of the parametric coordinates reproduced (points inside every shape) */
        for (int trial = 0; trial < 20; trial++) {
            const double at[3] = {0.05 + 0.01 * trial, 0.3 - 0.01 * trial, 0.02 + 0.03 * trial};
            double c[10], want, got = 0;
            for (int k = 0; k < 10; k++)
                c[k] = sin(1.7 * k + trial);
            if (orders[i]->code == 31)
                c[6] = 0; /* linear in t */
#define P2(p) (c[0] + c[1] * (p)[0] + c[2] * (p)[1] + c[3] * (p)[2] + c[4] * (p)[0] * (p)[0] + c[5] * (p)[1] * (p)[1] + \
               c[6] * (p)[2] * (p)[2] + c[7] * (p)[0] * (p)[1] + c[8] * (p)[1] * (p)[2] + c[9] * (p)[0] * (p)[2])
            want = P2(at);
            tpk_cell_map_weights(orders[i]->code, at, w);
            for (int k = 0; k < n; k++)
                got += w[k] * P2(r[k]);
#undef P2
            CHECK_MSG(fabs(got - want) < 1e-13, "%s at (%g %g %g): %.17g, expected %.17g", orders[i]->name, at[0],
                      at[1], at[2], got, want);
        }
    }
}

/* VTK's Lagrange tetra of orders 3, 4 and 6 (mapped as TPK_CELL_MAP_LAGRANGE_TETRA + p): the node of lattice
 * point (i, j, k) sits at (i, j, k) / p with weight 1 there and 0 at the others; the weights reproduce a
 * random polynomial of degree p; and they are VTK's own (vtkLagrangeTetra::InterpolateFunctions of
 * python3-paraview's VTK 9.2, at random points, seed 36, printed to 17 digits) to 1e-12. */
static const struct {
    int p;
    double r[3], w[84];
} vtk_lagrange_tetra[] = {
    {3, {0.00040277468054383814, 0.6269890530143345, 0.24764264575700945}, {0.063473596595115922,
     0.00040204495108402577, -0.032874297467093049, 0.040013864451868095, -0.00014158484650394733,
     -0.00022622459184358027, -0.0011350357696764608, 0.0010011389376714621, 0.31061499279201882,
     -0.22040151260458354, -0.087052259441917371, -0.035800002321565542, -0.00044830648905300121,
     -0.0001153864981554391, 0.6155419078492409, -0.17961921318250498, 0.00033654379271245906,
     0.0016885398695087146, 0.52388912233938412, 0.00085207163429227195}},
    {3, {0.23482990489780686, 0.20321921682204891, 0.16753706468262608}, {-0.029514777490526185,
     0.044950742831862026, 0.05514449971228063, 0.062389498631748516, 0.07637333067087998, -0.12316594236953039,
     -0.063460470918057815, -0.083825540268354037, -0.14079105907955683, 0.066092640338043018,
     0.054487794670798374, -0.14790114623118594, -0.052317793500299595, -0.08805881261346514,
     -0.059804499636053242, -0.076205127883416671, 0.41896735537416874, 0.21587027354986985, 0.3625697411502839,
     0.50819929306051059}},
    {3, {0.063689989784567524, 0.23962476846549186, 0.37383353288300913}, {0.0052356302225503061,
     0.046598711767082086, 0.043151310894683728, -0.019951159793612828, -0.0029096224101823435,
     -0.074851023108187531, -0.055555410081776252, -0.01930705086538188, -0.09786960849190901,
     -0.010947051471044364, -0.017078263454480901, 0.065989110760982392, -0.086670820193721368,
     0.013017883055381112, -0.11332429254536544, 0.048977982625024695, 0.20754691764442462, 0.15404404164628466,
     0.78086654204994799, 0.13303617174930046}},
    {4, {0.27664620346315416, 0.27997800927695093, 0.0026129673440293821}, {0.016429089321921754,
     0.0083131952650926984, 0.0092584801943838523, -0.0025631832369546388, -0.05879041046785026,
     0.039667854802939558, -0.030963287201760191, -0.019668264017990652, 0.0039597406245269091,
     -0.021797477106762064, -0.034728535423069959, 0.045165349111797919, -0.059498456444770274,
     -0.00055528476722810263, -0.0034784805078967697, 0.0060464301472634195, -0.0001835591721131241,
     -0.00030496566172109744, 0.0037950613553676795, -0.00020588063435970184, -0.00034723028626501703,
     0.0038407674136082858, 0.0077797806618947734, 0.0010866982282343545, -0.010089056418380106,
     0.00077659640759123502, -0.006408693755158611, 0.00069028419113009796, 0.0078734769357452009,
     -0.010210564598899775, 0.0012373017169998253, 0.83359920563328926, 0.13099850762719467,
     0.11643911559823268, 0.022836394463966122}},
    {4, {0.2988569366495919, 0.49768933455669684, 0.079963351602203914}, {-0.039308749472997437,
     0.014133106817582314, 0.00076659687106388284, -0.040817649354945272, 0.075004067125827578,
     -0.0145991047799548, -0.015474494310781474, -0.062365108531418974, 0.11519541346146055,
     -0.0036320746430403435, -0.0015008059464340156, -0.12325436038937602, 0.12490499526422795,
     0.020068386761957546, 0.013594717174690723, 0.030091410235341735, -0.010020152643313981,
     -0.01270583094085086, 0.072823704056342239, -0.00097181234935635836, -0.10727021207357654,
     0.12127401564799611, -0.047788233509998133, 0.018455407939427893, -0.064230300260968307,
     0.37707690990310855, -0.25886013244323103, 0.074378748411320902, -0.079582205458785318,
     -0.10696333755417888, 0.1558115744482135, -0.29743243196643965, 0.58233389297878679, 0.11486586682908739,
     0.37599818270321173}},
    {6, {0.13797655911897022, 0.4511697845860736, 0.10689169636713647}, {0.0029897036483774605,
     -0.0066693964480987883, -0.0039414914603345865, -0.01498721893252143, -0.0046754589641086614,
     -0.000924577335383887, -0.0012284856938024424, -0.011356481661664287, 0.017492397207377688,
     0.025963910358456396, -0.034929788475824751, 0.015159247909410655, 0.0028418364703751806,
     0.0085382307853766118, 0.018809697679163954, -0.029959632525548899, -0.024027624331659309,
     0.029980080430287801, -0.015288291193427141, -0.0036221206207757723, -0.0014923445195603694,
     -0.0022983902226483446, -0.023071349159536785, 0.037626238988351268, 0.0061514013512360939,
     0.0017387304387828692, 0.0014500754089027197, 0.0021884447817048175, 0.017079568079616147,
     0.0066146451140013437, 0.0045869598136864453, 0.028361638522503518, -0.070961885027727517,
     0.055848508619926414, 0.0068894576039834794, -0.017683251344509748, -0.046371660610537914,
     0.0020165400503984218, 0.013412541316367363, -0.0058394883013365992, -0.0067686584983670181,
     0.03239112826513299, 0.004201400131386296, 0.006155923658531637, -0.02117585098706181,
     -0.068829310527945761, -0.02624719455611613, -0.051844369437612357, 0.099627269474989413,
     -0.010046698597976264, -0.0086675341862927687, 0.04125373025392743, -0.024883668322279295,
     0.018934130981049239, 0.0225278490995269, -0.15163077164806929, -0.046650338363756136,
     0.013738165412597538, 0.10591580522948903, 0.2194785859659206, -0.11421299564290964, 0.26233232157961128,
     -0.065387751341254532, -0.19961022117080363, 0.029079107252897484, -0.06021658733021748,
     -0.074637684413592267, -0.084402972777284035, 0.33862041961543993, -0.070760300851201094,
     0.11731093366923705, 0.056611819085301177, 0.0085114370065059782, -0.12366788230633111,
     -0.063422692901023633, 0.088150631135575377, 0.52726805438839219, 0.21288272911267894,
     -0.092927415506214348, -0.19256406263994452, 0.92150715739763644, -0.19361145623666581,
     0.040458295182270072, -0.40120139340445743}},
    {6, {0.42365420134658038, 0.14233683318225232, 0.35779401144052758}, {-0.021760001326612394,
     -0.0048433317864571262, -0.0055540717401878891, -0.0022640351937378293, 0.073056337571545532,
     -0.079492394058090735, 0.022589508840438394, 0.0050306033108822677, 0.0054061964201569633,
     0.010096455318952483, 0.0025270830898467458, 0.008429436140383946, -0.025034902432643044,
     0.020431413126953138, 0.0036755901565528313, 0.0015851826625949963, 0.0015194169073713686,
     0.0025284736765895949, 0.024545036260175217, 0.061699187681353539, -0.049929577914148662,
     0.0038425497234254838, 0.0015939163416397312, 0.0021771491475530446, 0.025379595492844572,
     -0.049902118103209631, 0.021317735344870935, -0.025172834046407369, 0.012102065730409936,
     0.017255198317060717, -0.015724549831400349, 0.0014338748017345786, 0.00080069104730933925,
     0.0040659804754793931, -0.22134849913619931, -0.039798466742345738, -0.014931046301973139,
     0.26845593368211296, -0.094303538390501679, 0.19926637506449474, 0.053965276964844516,
     -0.018994118646367329, 0.19965664816138765, -0.29933256774137051, -0.069710292980196334,
     -0.027884788146248226, -0.074326459861634775, 0.07450330051739458, -0.0095415426483626761,
     0.10078398291614958, 0.37214409097438705, -0.047372623610338865, 0.10017624400179755, -0.15036730655014788,
     -0.074367359739498609, -0.0050164446380217397, -0.01254080983514593, 0.067079459929223387,
     -0.0063815316562863041, -0.0017165136850169924, 0.013403066949450418, -0.0063430502923981433,
     -0.0085389774667431612, 0.0095210935215630805, -0.088056377103248554, -0.014849233371898427,
     -0.015832539227829647, -0.010110772017744719, -0.007510634107339733, 0.021338892176590338,
     -0.010091008276623743, -0.037515627940061573, 0.10679655395978632, 0.015158440141060265,
     0.29737759457391538, 0.29679630426452824, 0.059418662785093418, 0.059779137805624362, -0.44583939374064502,
     -0.11992252987127734, 0.042209044201356578, -0.33158067229747856, 0.94207281474178939,
     -0.089189052462834248}},
};

TPK_TEST(lagrange_tetra_shape_functions)
{
    CHECK_EQ_INT(tpk_cell_map_type(71, 20), TPK_CELL_MAP_LAGRANGE_TETRA + 3);
    CHECK_EQ_INT(tpk_cell_map_type(71, 84), TPK_CELL_MAP_LAGRANGE_TETRA + 6);
    CHECK_EQ_INT(tpk_cell_map_type(71, 120), TPK_CELL_MAP_LAGRANGE_TETRA + 7);
    CHECK_EQ_INT(tpk_cell_map_type(71, 286), TPK_CELL_MAP_LAGRANGE_TETRA + 10);
    CHECK_EQ_INT(tpk_cell_map_type(71, 364), 71); /* order 11: degree over the Bernstein tables' 12 */
    CHECK_EQ_INT(tpk_cell_map_type(71, 15), 71);
    for (int p = 3; p <= TPK_CELL_MAP_LAGRANGE_MAX_ORDER; p++) {
        int type = TPK_CELL_MAP_LAGRANGE_TETRA + p, n = (p + 1) * (p + 2) * (p + 3) / 6;
        double r[TPK_CELL_MAP_MAX_NODES][3], w[TPK_CELL_MAP_MAX_NODES];
        CHECK_EQ_INT(tpk_cell_map_nodes(type), n);
        CHECK_EQ_INT(tpk_cell_map_degree(type), p);
        for (int k = 0; k < n; k++) {
            tpk_cell_map_node(type, k, r[k]);
            int i = (int)lround(r[k][0] * p), j = (int)lround(r[k][1] * p), l = (int)lround(r[k][2] * p);
            CHECK_EQ_INT(tpk_cell_map_lagrange_tet_node(p, i, j, l), k);
            CHECK_EQ_INT(tpk_cell_map_weights(type, r[k], w), n);
            for (int m = 0; m < n; m++)
                CHECK_MSG(fabs(w[m] - (m == k)) < 1e-12, "order %d: N%d at node %d = %g", p, m, k, w[m]);
        }
        /* sum_k w_k f(node k) = f for f = (a.x + b)^p, a random polynomial of degree p */
        for (int trial = 0; trial < 10; trial++) {
            const double a[3] = {sin(trial + 1.0), cos(2.0 * trial), sin(0.7 * trial + 3)}, b = 0.3 * trial - 1;
            const double at[3] = {0.05 + 0.02 * trial, 0.3 - 0.02 * trial, 0.1 + 0.03 * trial};
            double got = 0;
            tpk_cell_map_weights(type, at, w);
            for (int k = 0; k < n; k++)
                got += w[k] * pow(a[0] * r[k][0] + a[1] * r[k][1] + a[2] * r[k][2] + b, p);
            double want = pow(a[0] * at[0] + a[1] * at[1] + a[2] * at[2] + b, p);
            CHECK_MSG(fabs(got - want) < 1e-12 * (1 + fabs(want)), "order %d: %.17g, expected %.17g", p, got, want);
        }
    }
    for (size_t c = 0; c < sizeof vtk_lagrange_tetra / sizeof vtk_lagrange_tetra[0]; c++) {
        double w[TPK_CELL_MAP_MAX_NODES];
        int p = vtk_lagrange_tetra[c].p;
        int n = tpk_cell_map_weights(TPK_CELL_MAP_LAGRANGE_TETRA + p, vtk_lagrange_tetra[c].r, w);
        CHECK_EQ_INT(n, (p + 1) * (p + 2) * (p + 3) / 6);
        for (int k = 0; k < n; k++)
            CHECK_MSG(fabs(w[k] - vtk_lagrange_tetra[c].w[k]) < 1e-12, "order %d point %d: N%d = %.17g, VTK %.17g", p,
                      (int)c, k, w[k], vtk_lagrange_tetra[c].w[k]);
    }
}

/* VTK's Lagrange wedge of order 3 (TPK_CELL_MAP_LAGRANGE_WEDGE + 3, degree 6): nodes at (i, j, k) / 3 in
 * VTK's numbering with weight 1 there and 0 at the others, a random polynomial of degree 3 in (r, s) times
 * one of degree 3 in t reproduced, and the weights VTK's own (vtkLagrangeWedge::InterpolateFunctions, VTK
 * 9.2, SetOrder(3, 3, 3, 40), random points, seed 73) to 1e-12. */
static const struct {
    int p;
    double r[3], w[40];
} vtk_lagrange_wedge[] = {
    {3, {0.27981547357298786, 0.50214044362473464, 0.56414781647276868}, {-0.0023552948935231673,
     -0.0012098887582365494, 0.0029126084293357776, -0.0030485896860203295, -0.0015660265726108354,
     0.0037699517124188012, 0.0044071429732198495, 0.002045818309149623, 0.0047113780852449999,
     -0.014860723571941847, -0.011580105987873606, 0.0079088003941747732, 0.0057044112182816336,
     0.002648016863576554, 0.0060981997104129658, -0.019235064251531049, -0.014988777742750405,
     0.010236801929464027, 0.017270161559071667, 0.038882638719146836, 0.0088714896723586338,
     0.019973578512921867, -0.021356654010190539, -0.048083109083126276, -0.038390478166810946,
     -0.049690939381972249, -0.032315304283440288, -0.015000929529749895, -0.072755793120666587,
     -0.033773611286818765, -0.034546103301883853, 0.10896601426763795, -0.077778291143773159,
     0.24532985119692846, 0.084910939106480607, -0.057991150459098341, 0.19117142345703872, -0.1305632807484873,
     0.28149755773429946, 0.63377333212934328}},
    {3, {0.51789927855511131, 0.20223217048411235, 0.11039453016296663}, {0.012930094429146641,
     -0.031768745073428133, 0.027509120194263142, 0.0016045446525075019, -0.0039423045441600345,
     0.0034137114732428271, -0.051937842801667002, 0.17929479227414147, 0.12955787591575241,
     -0.092027747417978409, -0.049731044982162881, -0.020280975693473643, -0.0064451646804941452,
     0.022249373486199958, 0.016077330148668582, -0.011420073597372309, -0.0061713147360986306,
     -0.002516743499045385, 0.019208119167720132, -0.0076980938238613789, -0.047193610574397214,
     0.01891392066637243, 0.040865784993761721, -0.016377899591356167, 0.39291294994347925,
     0.048758064079688669, -0.077155528856766159, 0.26634884648561902, 0.03092184586022264,
     -0.10674540241135497, 0.19246287282301849, -0.13671052047050217, -0.077133905702301608,
     0.054789873183390972, -0.073877251522569021, -0.030128117013572903, 0.02960800111160725,
     0.012074533143074353, 0.58368628368577957, -0.23392565072509491}},
    {3, {0.35218703417241026, 0.42235866560204871, 0.5530605539011666}, {-0.0024243902075537283,
     0.00047176071642357806, 0.0020753530076396943, -0.0030000363645810877, 0.00058377537586230138,
     0.0025681239236418729, 0.0058056314497403104, -0.0010146331069353456, -0.0019007802676292691,
     -0.0089752986079415439, -0.0057455825190263418, 0.0069623765617936404, 0.00718411805752625,
     -0.0012555471507968753, -0.0023521007081281097, -0.011106389607953373, -0.0071098111348061278,
     0.0086155202261618893, 0.018306806788851535, 0.035407458940961513, -0.0035623111573491314,
     -0.0068899173675433375, -0.015671192867858428, -0.030309880058519811, -0.045459412852533056,
     -0.056253276079560988, -0.043838889014866017, 0.007661593497764475, -0.084789427272292481,
     0.014818398441809948, 0.014352977090540973, 0.067773354708286007, 0.027760299918791712,
     0.13108142243497181, 0.043385453685424159, -0.052573584116475162, 0.083912431464406897,
     -0.10168332699708689, 0.34326845787159183, 0.66392047329724702}},
};

TPK_TEST(lagrange_wedge_shape_functions)
{
    const int type = TPK_CELL_MAP_LAGRANGE_WEDGE + 3, n = 40;
    CHECK_EQ_INT(tpk_cell_map_type(73, 40), type);
    CHECK_EQ_INT(tpk_cell_map_type(73, 75), TPK_CELL_MAP_LAGRANGE_WEDGE + 4);
    CHECK_EQ_INT(tpk_cell_map_type(73, 196), TPK_CELL_MAP_LAGRANGE_WEDGE + 6);
    CHECK_EQ_INT(tpk_cell_map_type(73, 288), 73); /* order 7: degree 14, over the Bernstein tables' 12 */
    CHECK_EQ_INT(tpk_cell_map_nodes(type), n);
    CHECK_EQ_INT(tpk_cell_map_degree(type), 6);
    double r[40][3], w[TPK_CELL_MAP_MAX_NODES];
    for (int k = 0; k < n; k++) {
        tpk_cell_map_node(type, k, r[k]);
        int i = (int)lround(r[k][0] * 3), j = (int)lround(r[k][1] * 3), l = (int)lround(r[k][2] * 3);
        CHECK_EQ_INT(tpk_cell_map_lagrange_wedge_node(3, i, j, l), k);
        CHECK_EQ_INT(tpk_cell_map_weights(type, r[k], w), n);
        for (int m = 0; m < n; m++)
            CHECK_MSG(fabs(w[m] - (m == k)) < 1e-12, "wedge: N%d at node %d = %g", m, k, w[m]);
    }
    for (int trial = 0; trial < 10; trial++) {
        const double a[2] = {sin(trial + 1.0), cos(2.0 * trial)}, b = 0.3 * trial - 1, c = 0.2 * trial + 0.5;
        const double at[3] = {0.05 + 0.02 * trial, 0.3 - 0.02 * trial, 0.1 + 0.08 * trial};
#define F(x) (pow(a[0] * (x)[0] + a[1] * (x)[1] + b, 3) * pow((x)[2] - c, 3))
        double got = 0, want = F(at);
        tpk_cell_map_weights(type, at, w);
        for (int k = 0; k < n; k++)
            got += w[k] * F(r[k]);
#undef F
        CHECK_MSG(fabs(got - want) < 1e-12 * (1 + fabs(want)), "wedge: %.17g, expected %.17g", got, want);
    }
    for (size_t c = 0; c < sizeof vtk_lagrange_wedge / sizeof vtk_lagrange_wedge[0]; c++) {
        CHECK_EQ_INT(tpk_cell_map_weights(type, vtk_lagrange_wedge[c].r, w), n);
        for (int k = 0; k < n; k++)
            CHECK_MSG(fabs(w[k] - vtk_lagrange_wedge[c].w[k]) < 1e-12, "wedge point %d: N%d = %.17g, VTK %.17g", (int)c,
                      k, w[k], vtk_lagrange_wedge[c].w[k]);
    }
}

/* The Lagrange tetra of orders 7-10, hexahedra of orders 3-4 and wedges of orders 4-6 against VTK's own
 * weights (vtkLagrangeTetra, vtkLagrangeHexahedron, vtkLagrangeWedge ::InterpolateFunctions of
 * python3-paraview's VTK 9.2 after SetOrder(p, p, p), at 3 random points per order, seed 44), as two
 * sums sum_k w_k sin(k + 1) and sum_k w_k cos(0.7 k) (printed to 17 digits): a node out of place changes
 * them. Each type's weights are 1 at their node and 0 at the others, its nodes at their lattice points
 * in VTK's numbering, and it reproduces a random polynomial of its degree in each variable (tetra: total
 * degree p; hexahedra and wedges: degree p in (r, s) times degree p in t). */
static const struct {
    int base, p;
    double r[3], sin_sum, cos_sum;
} vtk_lagrange_high[] = {
    {TPK_CELL_MAP_LAGRANGE_TETRA, 7, {0.17666564419544384, 0.2251595205781467, 0.029097253268111078}, 0.32600209150691112, 0.2819224211075031},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 7, {0.1166505334428638, 0.0088056258870669035, 0.15669033508336383}, 0.19720496731834725, -0.82629537267908759},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 7, {0.61721995591408318, 0.11200982712964758, 0.070066687379917281}, 1.1778414843089717, 0.14883618099555157},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 8, {0.18859316505523482, 0.25834686865744172, 0.24796464127719819}, 0.7253730887401435, -0.25617643411491914},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 8, {0.15726925439603556, 0.22314650478327425, 0.014588434845492881}, -0.82546021596672192, 0.42272942211463743},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 8, {0.047981654672824448, 0.6230878269221285, 0.12248957263441707}, 1.3113665307809943, -1.2908487833008044},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 9, {0.27204909231091834, 0.0067392471078761007, 0.27391238643523974}, -0.71039467240631415, 0.32480473463734666},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 9, {0.073010120573495541, 0.27172201025626408, 0.41244134822443645}, 1.9819939334660885, 3.3121609550473279},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 9, {0.12935757761115396, 0.18795489179810188, 0.01564689038106748}, 1.1335242140590363, 0.34446081369494175},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 10, {0.01630717541417237, 0.79568098638646356, 0.11715214844662192}, -1.1872748412203227, -1.1709516697369216},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 10, {0.016100974126273537, 0.075270207028388159, 0.56239207920202494}, -1.468115057097571, -1.9353663226409359},
    {TPK_CELL_MAP_LAGRANGE_TETRA, 10, {0.14903803392923243, 0.26336742768505206, 0.4045923931025962}, 0.30420060046204755, 2.3203017667954344},
    {TPK_CELL_MAP_LAGRANGE_HEX, 3, {0.7968774077548143, 0.65996706446882847, 0.17198624074591451}, -0.47252519990062836, -0.7141586039160891},
    {TPK_CELL_MAP_LAGRANGE_HEX, 3, {0.17871933642312421, 0.45057056779894733, 0.89046284174588619}, -0.77273620099223395, 0.04827151199023344},
    {TPK_CELL_MAP_LAGRANGE_HEX, 3, {0.47235919745936561, 0.78899665398096952, 0.68874006403772159}, 0.76968298636400423, 1.2576808186994064},
    {TPK_CELL_MAP_LAGRANGE_HEX, 4, {0.87796795699733743, 0.49632746722034693, 0.37792198717970227}, 0.076834419618405467, -0.68501380804932266},
    {TPK_CELL_MAP_LAGRANGE_HEX, 4, {0.45760914766939331, 0.80204083539710846, 0.27861194002479106}, -0.80377006798786566, -0.19927957062438467},
    {TPK_CELL_MAP_LAGRANGE_HEX, 4, {0.1932954210919865, 0.83682891894141898, 0.48033231417067768}, 1.013488508168048, -0.87517165128813779},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 4, {0.64146990161274464, 0.17415572214818642, 0.041407662359385755}, -1.342816303624228, -0.34959976251189301},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 4, {0.22502970266773947, 0.42938974727800872, 0.033002547900054746}, -0.72404997234760982, -0.12990195954075207},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 4, {0.7270111475965414, 0.056965874866295785, 0.43708779735368508}, 0.76474959510386709, 0.22959226406241584},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 5, {0.0045458840607556228, 0.8025110031450674, 0.3017180935996967}, -0.43803144814123146, 0.78775771098431691},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 5, {0.17280492762813826, 0.63794701703587764, 0.66459135469688002}, 0.77008578545997475, 0.20839540101389134},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 5, {0.67575460181819336, 0.28953866186387256, 0.87549653593685484}, 0.69711954913707153, -0.13325051488311265},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 6, {0.33966698828076114, 0.49708408823050743, 0.005462039804677965}, -0.8633730145826416, -0.75466744104303951},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 6, {0.59142055397961035, 0.29229991263234589, 0.65239504145414662}, 0.48776575157003527, 0.049166037521049019},
    {TPK_CELL_MAP_LAGRANGE_WEDGE, 6, {0.24188695427075357, 0.6594696951339647, 0.66725990183170425}, -1.4613138860929367, -0.3067169849506437},
};

/* l(p, m, L) = prod_{q<m} (p L - q) / (q + 1) in long double, and the 1-D basis on nodes k / p */
static long double lagrange_ld(int p, int m, long double L)
{
    long double v = 1;
    for (int q = 0; q < m; q++)
        v *= (p * L - q) / (q + 1);
    return v;
}

static long double line_ld(int p, int k, long double t)
{
    long double v = 1;
    for (int q = 0; q <= p; q++)
        if (q != k)
            v *= (p * t - q) / (k - q);
    return v;
}

static int lattice_node(int base, int p, int i, int j, int k)
{
    return base == TPK_CELL_MAP_LAGRANGE_TETRA ? tpk_cell_map_lagrange_tet_node(p, i, j, k)
           : base == TPK_CELL_MAP_LAGRANGE_HEX ? tpk_cell_map_lagrange_hex_node(p, i, j, k)
                                               : tpk_cell_map_lagrange_wedge_node(p, i, j, k);
}

TPK_TEST(lagrange_high_order_shape_functions)
{
    CHECK_EQ_INT(tpk_cell_map_type(72, 64), TPK_CELL_MAP_LAGRANGE_HEX + 3);
    CHECK_EQ_INT(tpk_cell_map_type(72, 125), TPK_CELL_MAP_LAGRANGE_HEX + 4);
    CHECK_EQ_INT(tpk_cell_map_type(72, 216), 72); /* order 5: degree 15, over the Bernstein tables' 12 */
    static const int kinds[][3] = {{TPK_CELL_MAP_LAGRANGE_TETRA, 7, 10}, {TPK_CELL_MAP_LAGRANGE_HEX, 3, 4},
                                   {TPK_CELL_MAP_LAGRANGE_WEDGE, 4, 6}};
    static double r[TPK_CELL_MAP_MAX_NODES][3], w[TPK_CELL_MAP_MAX_NODES];
    for (int kind = 0; kind < 3; kind++)
        for (int p = kinds[kind][1]; p <= kinds[kind][2]; p++) {
            int base = kinds[kind][0], type = base + p;
            int n = kind == 0 ? (p + 1) * (p + 2) * (p + 3) / 6 : kind == 1 ? (p + 1) * (p + 1) * (p + 1)
                                                                             : (p + 1) * (p + 1) * (p + 2) / 2;
            CHECK_EQ_INT(tpk_cell_map_nodes(type), n);
            CHECK_EQ_INT(tpk_cell_map_degree(type), (kind == 0 ? 1 : kind == 1 ? 3 : 2) * p);
            for (int k = 0; k < n; k++) {
                tpk_cell_map_node(type, k, r[k]);
                int i = (int)lround(r[k][0] * p), j = (int)lround(r[k][1] * p), l = (int)lround(r[k][2] * p);
                CHECK_EQ_INT(lattice_node(base, p, i, j, l), k);
                CHECK_EQ_INT(tpk_cell_map_weights(type, r[k], w), n);
                for (int m = 0; m < n; m++)
                    CHECK_MSG(fabs(w[m] - (m == k)) < 1e-11, "type %d: N%d at node %d = %g", type, m, k, w[m]);
            }
            for (int trial = 0; trial < 10; trial++) {
                const double a[3] = {sin(trial + 1.0), cos(2.0 * trial), sin(0.7 * trial + 3)}, b = 0.3 * trial - 1;
                const double at[3] = {0.05 + 0.02 * trial, 0.3 - 0.02 * trial, 0.1 + 0.03 * trial}, c = 0.2 * trial;
#define F(x) (kind == 0 ? pow(a[0] * (x)[0] + a[1] * (x)[1] + a[2] * (x)[2] + b, p)                              \
                        : pow(a[0] * (x)[0] + a[1] * (x)[1] + b, p) * pow((x)[2] - c, p))
                double got = 0, want = F(at);
                tpk_cell_map_weights(type, at, w);
                for (int k = 0; k < n; k++)
                    got += w[k] * F(r[k]);
#undef F
                CHECK_MSG(fabs(got - want) < 1e-10 * (1 + fabs(want)), "type %d: %.17g, expected %.17g", type, got, want);
                /* each weight within 1e-13 of the same formula in long double (refine.c's WEIGHT_ERROR) */
                const long double x[3] = {at[0], at[1], at[2]}, L0 = 1 - x[0] - x[1] - x[2], T0 = 1 - x[0] - x[1];
                double worst = 0;
                for (int i = 0; i <= p; i++)
                    for (int j = 0; j <= p; j++)
                        for (int l = 0; l <= p; l++) {
                            long double exact;
                            if (kind == 0 && i + j + l <= p)
                                exact = lagrange_ld(p, p - i - j - l, L0) * lagrange_ld(p, i, x[0]) *
                                        lagrange_ld(p, j, x[1]) * lagrange_ld(p, l, x[2]);
                            else if (kind == 1)
                                exact = line_ld(p, i, x[0]) * line_ld(p, j, x[1]) * line_ld(p, l, x[2]);
                            else if (kind == 2 && i + j <= p)
                                exact = lagrange_ld(p, p - i - j, T0) * lagrange_ld(p, i, x[0]) *
                                        lagrange_ld(p, j, x[1]) * line_ld(p, l, x[2]);
                            else
                                continue;
                            worst = fmax(worst, fabs((double)(w[lattice_node(base, p, i, j, l)] - exact)));
                        }
                CHECK_MSG(worst <= 1e-13, "type %d: a weight %.3g off its long double value", type, worst);
            }
        }
    for (size_t c = 0; c < sizeof vtk_lagrange_high / sizeof vtk_lagrange_high[0]; c++) {
        int type = vtk_lagrange_high[c].base + vtk_lagrange_high[c].p, n = tpk_cell_map_weights(type, vtk_lagrange_high[c].r, w);
        double s = 0, t = 0;
        for (int k = 0; k < n; k++)
            s += w[k] * sin(k + 1), t += w[k] * cos(0.7 * k);
        CHECK_MSG(fabs(s - vtk_lagrange_high[c].sin_sum) < 1e-12 && fabs(t - vtk_lagrange_high[c].cos_sum) < 1e-12,
                  "type %d point %d: sums %.17g %.17g, VTK %.17g %.17g", type, (int)c, s, t, vtk_lagrange_high[c].sin_sum,
                  vtk_lagrange_high[c].cos_sum);
    }
}

/* ---- Gmsh: the orders of Gmsh's reference manual ("Node ordering"), MSH 2.2 and 4.1 ---------------- */

static const node_order gmsh_tet10 = {"gmsh tetrahedron10", 11, 10, 6, 0, 0,
                                      {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}, {{0}}};
static const node_order gmsh_hex20 = {"gmsh hexahedron20", 17, 12, 12, 0, 0,
                                      {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 5}, {2, 3}, {2, 6}, {3, 7}, {4, 5}, {4, 7},
                                       {5, 6}, {6, 7}}, {{0}}};
static const node_order gmsh_hex27 = {"gmsh hexahedron27", 12, 12, 12, 6, 1,
                                      {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 5}, {2, 3}, {2, 6}, {3, 7}, {4, 5}, {4, 7},
                                       {5, 6}, {6, 7}},
                                      {{0, 3, 2, 1}, {0, 1, 5, 4}, {0, 4, 7, 3}, {1, 2, 6, 5}, {2, 3, 7, 6}, {4, 5, 6, 7}}};
static const node_order gmsh_prism15 = {"gmsh prism15", 18, 13, 9, 0, 0,
                                        {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 4}, {2, 5}, {3, 4}, {3, 5}, {4, 5}}, {{0}}};
static const node_order gmsh_prism18 = {"gmsh prism18", 13, 13, 9, 3, 0,
                                        {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 4}, {2, 5}, {3, 4}, {3, 5}, {4, 5}},
                                        {{0, 1, 4, 3}, {0, 2, 5, 3}, {1, 2, 5, 4}}};
static const node_order gmsh_pyramid13 = {"gmsh pyramid13", 19, 14, 8, 0, 0,
                                          {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 4}, {2, 3}, {2, 4}, {3, 4}}, {{0}}};
static const node_order gmsh_pyramid14 = {"gmsh pyramid14", 14, 14, 8, 1, 0,
                                          {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 4}, {2, 3}, {2, 4}, {3, 4}},
                                          {{0, 1, 2, 3}}};

static char *write_msh(const node_order *const *orders, int count, int curved, int version41)
{
    size_t cap = 1 << 16, at = 0;
    char *text = malloc(cap);
    int total = 0, ns[16];
    double r[16][27][3];
    for (int c = 0; c < count; c++)
        total += ns[c] = order_nodes(orders[c], r[c]);
    if (version41) {
        at += (size_t)snprintf(text + at, cap - at, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 %d 1 %d\n3 1 0 %d\n",
                               total, total, total);
        for (int k = 1; k <= total; k++)
            at += (size_t)snprintf(text + at, cap - at, "%d\n", k);
    } else {
        at += (size_t)snprintf(text + at, cap - at, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n", total);
    }
    for (int c = 0, id = 1; c < count; c++)
        for (int k = 0; k < ns[c]; k++, id++) {
            double x[3];
            map_point(r[c][k], 3.0 * c, curved, x);
            if (version41)
                at += (size_t)snprintf(text + at, cap - at, "%.17g %.17g %.17g\n", x[0], x[1], x[2]);
            else
                at += (size_t)snprintf(text + at, cap - at, "%d %.17g %.17g %.17g\n", id, x[0], x[1], x[2]);
        }
    at += (size_t)snprintf(text + at, cap - at, "$EndNodes\n$Elements\n");
    if (version41)
        at += (size_t)snprintf(text + at, cap - at, "%d %d 1 %d\n", count, count, count);
    else
        at += (size_t)snprintf(text + at, cap - at, "%d\n", count);
    for (int c = 0, first = 1; c < count; first += ns[c], c++) {
        if (version41)
            at += (size_t)snprintf(text + at, cap - at, "3 1 %d 1\n%d", orders[c]->code, c + 1);
        else
            at += (size_t)snprintf(text + at, cap - at, "%d %d 2 0 1", c + 1, orders[c]->code);
        for (int k = 0; k < ns[c]; k++)
            at += (size_t)snprintf(text + at, cap - at, " %d", first + k);
        at += (size_t)snprintf(text + at, cap - at, "\n");
    }
    at += (size_t)snprintf(text + at, cap - at, "$EndElements\n$NodeData\n1\n\"f\"\n1\n0\n3\n0\n1\n%d\n", total);
    for (int c = 0, id = 1; c < count; c++)
        for (int k = 0; k < ns[c]; k++, id++) {
            double x[3];
            map_point(r[c][k], 3.0 * c, curved, x);
            at += (size_t)snprintf(text + at, cap - at, "%d %.17g\n", id, field_at(x));
        }
    at += (size_t)snprintf(text + at, cap - at, "$EndNodeData\n");
    return text;
}

TPK_TEST(gmsh_orders)
{
    const node_order *orders[] = {&gmsh_tet10,   &gmsh_hex20,     &gmsh_hex27,    &gmsh_prism15,
                                  &gmsh_prism18, &gmsh_pyramid13, &gmsh_pyramid14};
    for (int version = 0; version < 2; version++)
        for (int curved = 0; curved < 2; curved++) {
            char *text = write_msh(orders, 7, curved, version);
            tpk_mesh m;
            tpk_diag d;
            quiet(&d);
            CHECK_MSG(tpk_import_gmsh_memory("whole.msh", text, strlen(text), &m, &d) == 0, "%s", d.message);
            free(text);
            add_second_step(&m);
            /* the field "f" is a point field; physical and entity cell fields come along */
            check_whole(&m, orders, curved, 24);
            tpk_mesh_free(&m);
        }
}

/* ---- Abaqus / CalculiX: the Abaqus manual's C3D10, C3D15, C3D20 (corners, then edges); C3D27 (a "21 to
 * 27-node brick": the C3D20's nodes, the centroid (node 21, the one node of the 21 it needs beyond the
 * C3D20's), then the centres of faces 1-6 (1234, 5876, 1562, 2673, 3784, 4851; the manual's face
 * numbering), as gmsh's .inp writer lists them) ---- */

static const node_order inp_c3d10 = {"C3D10", 10, 10, 6, 0, 0, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}, {{0}}};
static const node_order inp_c3d15 = {"C3D15", 15, 13, 9, 0, 0,
                                     {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}}, {{0}}};
static const node_order inp_c3d20 = {"C3D20R", 20, 12, 12, 0, 0,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5},
                                      {2, 6}, {3, 7}}, {{0}}};
static const node_order inp_c3d27 = {"C3D27", 27, 12, 12, 6, 2,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5},
                                      {2, 6}, {3, 7}},
                                     {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1}, {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}}};

TPK_TEST(inp_orders)
{
    const node_order *orders[] = {&inp_c3d10, &inp_c3d15, &inp_c3d20, &inp_c3d27};
    for (int curved = 0; curved < 2; curved++) {
        size_t cap = 1 << 15, at = 0;
        char *text = malloc(cap);
        int ns[4], first = 1;
        double r[4][27][3];
        at += (size_t)snprintf(text + at, cap - at, "*NODE\n");
        for (int c = 0, id = 1; c < 4; c++) {
            ns[c] = order_nodes(orders[c], r[c]);
            for (int k = 0; k < ns[c]; k++, id++) {
                double x[3];
                map_point(r[c][k], 3.0 * c, curved, x);
                at += (size_t)snprintf(text + at, cap - at, "%d, %.17g, %.17g, %.17g\n", id, x[0], x[1], x[2]);
            }
        }
        for (int c = 0; c < 4; first += ns[c], c++) {
            at += (size_t)snprintf(text + at, cap - at, "*ELEMENT, TYPE=%s\n%d", orders[c]->name, c + 1);
            for (int k = 0; k < ns[c]; k++)
                at += (size_t)snprintf(text + at, cap - at, ",%s%d", k % 10 == 9 ? "\n" : " ", first + k);
            at += (size_t)snprintf(text + at, cap - at, "\n");
        }
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_inp_memory("whole.inp", text, at, &m, &d) == 0, "%s", d.message);
        free(text);
        /* the C3D27 whole, as VTK's triquadratic hexahedron */
        CHECK(m.cell_count == 4 && m.cell_types[3] == 29 && m.cell_offsets[4] - m.cell_offsets[3] == 27);
        /* .inp carries no point field: the field is made here from the points read */
        float *f = malloc(sizeof *f * (size_t)m.point_count);
        for (int64_t p = 0; p < m.point_count; p++)
            f[p] = (float)field_at(m.points + 3 * p);
        CHECK(tpk_mesh_add_field(&m, "f", TPK_ASSOC_POINT, 1, 1, f) == 0);
        add_second_step(&m);
        check_whole(&m, orders, curved, 24);
        tpk_mesh_free(&m);
    }
}

/* Two 20-node hexahedra sharing a face: its centre is made once, and both cells cut the face's four
 * quads alike (the tets' faces match: no face is used by one tet only but on the outside). */
TPK_TEST(shared_face_centre)
{
    double r[27][3];
    int n = order_nodes(&vtk_hex20, r);
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = 2 * n; /* the second cell's points: the first's moved by +1 in x; shared ones merged below */
    m.points = malloc(sizeof *m.points * 3 * (size_t)m.point_count);
    m.cell_count = 2;
    m.cell_types = malloc(2);
    m.cell_offsets = malloc(sizeof *m.cell_offsets * 3);
    m.cell_conn = malloc(sizeof *m.cell_conn * 40);
    m.cell_types[0] = m.cell_types[1] = 25;
    m.cell_offsets[0] = 0, m.cell_offsets[1] = 20, m.cell_offsets[2] = 40;
    int64_t count = 0;
    for (int c = 0; c < 2; c++)
        for (int k = 0; k < n; k++) {
            double x[3] = {r[k][0] + c, r[k][1], r[k][2]};
            int64_t found = -1;
            for (int64_t p = 0; p < count && found < 0; p++)
                if (!memcmp(m.points + 3 * p, x, sizeof x))
                    found = p;
            if (found < 0) {
                memcpy(m.points + 3 * count, x, sizeof x);
                found = count++;
            }
            m.cell_conn[20 * c + k] = (int32_t)found;
        }
    m.point_count = count;
    CHECK_EQ_INT(count, 2 * 20 - 8);
    tpk_diag d;
    quiet(&d);
    tpk_higher_split h;
    CHECK_MSG(tpk_split_higher_order(&m, "test", &h, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(h.added_points, 6 + 6 - 1 + 2); /* face centres, the shared one once, and 2 cell centres */
    tpk_tetmesh t;
    CHECK_MSG(tpk_tetrahedralize(&m, NULL, 0, 0, &t, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(t.tet_count, 2 * 8 * 6);
    /* every tet face is either on the box's boundary or shared by exactly two tets */
    int64_t faces = 4 * t.tet_count, boundary = 0;
    for (int64_t f = 0; f < faces; f++) {
        int32_t a[3];
        for (int i = 0, j = 0; i < 4; i++)
            if (i != f % 4)
                a[j++] = t.tets[4 * (f / 4) + i];
        int matches = 0;
        for (int64_t g = 0; g < faces; g++) {
            if (g / 4 == f / 4)
                continue;
            int32_t b[3];
            for (int i = 0, j = 0; i < 4; i++)
                if (i != g % 4)
                    b[j++] = t.tets[4 * (g / 4) + i];
            int same = 0;
            for (int i = 0; i < 3; i++)
                same += a[i] == b[0] || a[i] == b[1] || a[i] == b[2];
            matches += same == 3;
        }
        CHECK(matches <= 1);
        if (!matches) {
            const double *p[3] = {t.points + 3 * a[0], t.points + 3 * a[1], t.points + 3 * a[2]};
            int on_box = 0;
            for (int axis = 0; axis < 3; axis++)
                for (int side = 0; side < 2; side++) {
                    double at = axis == 0 ? 2.0 * side : side;
                    on_box |= p[0][axis] == at && p[1][axis] == at && p[2][axis] == at;
                }
            CHECK_MSG(on_box, "a hanging face inside the two cells");
            boundary++;
        }
    }
    CHECK_EQ_INT(boundary, 10 * 4 * 2); /* 10 outer quads, 4 pieces each, 2 triangles each */
    free(h.cell_source);
    tpk_tetmesh_free(&t);
    tpk_mesh_free(&m);
}

/* ---- Exodus II and CGNS, written with their own libraries ------------------------------------------ */

/* Nodes of cells `orders` (cell c shifted by 3c) into xyz[3][...] (component-major); returns the count. */
static int gather_nodes(const node_order *const *orders, int count, int curved, double (*xyz)[512], int *ns)
{
    int total = 0;
    for (int c = 0; c < count; c++) {
        double r[27][3];
        ns[c] = order_nodes(orders[c], r);
        for (int k = 0; k < ns[c]; k++, total++) {
            double x[3];
            map_point(r[k], 3.0 * c, curved, x);
            for (int a = 0; a < 3; a++)
                xyz[a][total] = x[a];
        }
    }
    return total;
}

/* The point field "f" made from the points read (formats whose fields these files do not carry). */
static void add_field(tpk_mesh *m)
{
    float *f = malloc(sizeof *f * (size_t)m->point_count);
    for (int64_t p = 0; p < m->point_count; p++)
        f[p] = (float)field_at(m->points + 3 * p);
    CHECK(tpk_mesh_add_field(m, "f", TPK_ASSOC_POINT, 1, 1, f) == 0);
    add_second_step(m);
}

/* The Exodus II manual's TETRA10, HEX20 (bottom, vertical, then top mid-edges), WEDGE15 (likewise) and
 * PYRAMID13 (base, then lateral mid-edges). */
static const node_order exo_tetra10 = {"TETRA10", 0, 10, 6, 0, 0, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}, {{0}}};
static const node_order exo_hex20 = {"HEX20", 0, 12, 12, 0, 0,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 5}, {2, 6}, {3, 7}, {4, 5}, {5, 6},
                                      {6, 7}, {7, 4}}, {{0}}};
static const node_order exo_wedge15 = {"WEDGE15", 0, 13, 9, 0, 0,
                                       {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 4}, {2, 5}, {3, 4}, {4, 5}, {5, 3}}, {{0}}};
/* HEX27 and WEDGE18 (SEACAS's Hex27 and Wedge18 topologies): HEX20's nodes, then the cell centre, then
 * the face centres z-, z+, x-, x+, y-, y+; WEDGE15's, then the centres of sides 1, 2 and 3. */
static const node_order exo_hex27 = {"HEX27", 0, 12, 12, 6, 2,
                                     {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 5}, {2, 6}, {3, 7}, {4, 5}, {5, 6},
                                      {6, 7}, {7, 4}},
                                     {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}}};
static const node_order exo_wedge18 = {"WEDGE18", 0, 13, 9, 3, 0,
                                       {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 4}, {2, 5}, {3, 4}, {4, 5}, {5, 3}},
                                       {{0, 1, 4, 3}, {1, 2, 5, 4}, {0, 3, 5, 2}}};
static const node_order exo_pyramid13 = {"PYRAMID13", 0, 14, 8, 0, 0,
                                         {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}}, {{0}}};
/* TETRA14 and TETRA15 (SEACAS's Tet14/Tet15 topologies): TETRA10's nodes, then the centres of sides 4
 * (1 3 2), 2 (2 3 4), 3 (1 4 3) and 1 (1 2 4), then (TETRA15) the body centre; PYRAMID14: PYRAMID13's,
 * then the centre of the base (side 5). */
static const node_order exo_tetra14 = {"TETRA14", 0, 10, 6, 4, 0, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
                                       {{0, 2, 1, 1}, {1, 2, 3, 3}, {0, 3, 2, 2}, {0, 1, 3, 3}}};
static const node_order exo_tetra15 = {"TETRA15", 0, 10, 6, 4, 1, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
                                       {{0, 2, 1, 1}, {1, 2, 3, 3}, {0, 3, 2, 2}, {0, 1, 3, 3}}};
static const node_order exo_pyramid14 = {"PYRAMID14", 0, 14, 8, 1, 0,
                                         {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
                                         {{0, 3, 2, 1}}};

TPK_TEST(exodus_orders)
{
    const node_order *orders[] = {&exo_tetra10, &exo_hex20,   &exo_wedge15, &exo_pyramid13, &exo_hex27,
                                  &exo_wedge18, &exo_tetra14, &exo_tetra15, &exo_pyramid14};
    enum { cells = sizeof orders / sizeof orders[0] };
    for (int curved = 0; curved < 2; curved++) {
        static double xyz[3][512];
        int ns[cells], total = gather_nodes(orders, cells, curved, xyz, ns);
        const char *path = tpk_temp_path("whole.exo");
        int cpu_ws = 8, io_ws = 8;
        int exoid = ex_create(path, EX_CLOBBER, &cpu_ws, &io_ws);
        CHECK(exoid >= 0);
        CHECK(ex_put_init(exoid, "higher order", 3, total, cells, cells, 0, 0) == 0);
        CHECK(ex_put_coord(exoid, xyz[0], xyz[1], xyz[2]) == 0);
        for (int c = 0, first = 1; c < cells; first += ns[c], c++) {
            int conn[27];
            for (int k = 0; k < ns[c]; k++)
                conn[k] = first + k;
            CHECK(ex_put_elem_block(exoid, c + 1, orders[c]->name, 1, ns[c], 0) == 0);
            CHECK(ex_put_elem_conn(exoid, c + 1, conn) == 0);
        }
        CHECK(ex_close(exoid) == 0);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_exodus(path, &m, &d) == 0, "%s", d.message);
        add_field(&m);
        check_whole(&m, orders, curved, 24);
        tpk_mesh_free(&m);
    }
}

#ifdef TPK_TEST_CGNS
/* The CGNS SIDS ("Unstructured Grid Element Numbering Conventions"): TETRA_10 and PYRA_13 as VTK,
 * PENTA_15/18 and HEXA_20/27 with their vertical mid-edges before the top ones, HEXA_27's face centres
 * bottom, y-, x+, y+, x-, top. */
static const node_order cgns_tetra10 = {"TETRA_10", CGNS_ENUMV(TETRA_10), 10, 6, 0, 0,
                                        {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}, {{0}}};
static const node_order cgns_pyra13 = {"PYRA_13", CGNS_ENUMV(PYRA_13), 14, 8, 0, 0,
                                       {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}}, {{0}}};
static const node_order cgns_pyra14 = {"PYRA_14", CGNS_ENUMV(PYRA_14), 14, 8, 1, 0,
                                       {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}}, {{0, 1, 2, 3}}};
static const node_order cgns_penta15 = {"PENTA_15", CGNS_ENUMV(PENTA_15), 13, 9, 0, 0,
                                        {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 4}, {2, 5}, {3, 4}, {4, 5}, {5, 3}}, {{0}}};
static const node_order cgns_penta18 = {"PENTA_18", CGNS_ENUMV(PENTA_18), 13, 9, 3, 0,
                                        {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 4}, {2, 5}, {3, 4}, {4, 5}, {5, 3}},
                                        {{0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}}};
static const node_order cgns_hexa20 = {"HEXA_20", CGNS_ENUMV(HEXA_20), 12, 12, 0, 0,
                                       {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 5}, {2, 6}, {3, 7}, {4, 5}, {5, 6},
                                        {6, 7}, {7, 4}}, {{0}}};
static const node_order cgns_hexa27 = {"HEXA_27", CGNS_ENUMV(HEXA_27), 12, 12, 6, 1,
                                       {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 5}, {2, 6}, {3, 7}, {4, 5}, {5, 6},
                                        {6, 7}, {7, 4}},
                                       {{0, 1, 2, 3}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {0, 3, 7, 4}, {4, 5, 6, 7}}};

/* A CGNS file at `path` with one unstructured zone of `points` points (xyz, coordinates by axis) and
 * `cells` cells, open for its sections: the file and the ids cg_section_write needs. */
static void cgns_zone_begin(const char *path, int points, int cells, const double *xyz, int stride, int *fn,
                            int *base, int *zone)
{
    cgsize_t size[3] = {points, cells, 0};
    int c;
    CHECK(cg_open(path, CG_MODE_WRITE, fn) == 0);
    CHECK(cg_base_write(*fn, "b", 3, 3, base) == 0);
    CHECK(cg_zone_write(*fn, *base, "z", size, CGNS_ENUMV(Unstructured), zone) == 0);
    CHECK(cg_coord_write(*fn, *base, *zone, CGNS_ENUMV(RealDouble), "CoordinateX", xyz, &c) == 0 &&
          cg_coord_write(*fn, *base, *zone, CGNS_ENUMV(RealDouble), "CoordinateY", xyz + stride, &c) == 0 &&
          cg_coord_write(*fn, *base, *zone, CGNS_ENUMV(RealDouble), "CoordinateZ", xyz + 2 * stride, &c) == 0);
}

TPK_TEST(cgns_orders)
{
    const node_order *orders[] = {&cgns_tetra10, &cgns_pyra13, &cgns_penta15, &cgns_penta18,
                                  &cgns_hexa20,  &cgns_hexa27, &cgns_pyra14};
    enum { cells = sizeof orders / sizeof orders[0] };
    for (int curved = 0; curved < 2; curved++) {
        static double xyz[3][512];
        int ns[cells], total = gather_nodes(orders, cells, curved, xyz, ns), fn, base, zone, s;
        const char *path = tpk_temp_path("whole.cgns");
        cgns_zone_begin(path, total, cells, xyz[0], 512, &fn, &base, &zone);
        for (int e = 0, first = 1; e < cells; first += ns[e], e++) {
            cgsize_t conn[27];
            for (int k = 0; k < ns[e]; k++)
                conn[k] = first + k;
            CHECK(cg_section_write(fn, base, zone, orders[e]->name, (CGNS_ENUMT(ElementType_t))orders[e]->code, e + 1,
                                   e + 1, 0, conn, &s) == 0);
        }
        CHECK(cg_close(fn) == 0);
        tpk_mesh m;
        tpk_diag d;
        quiet(&d);
        CHECK_MSG(tpk_import_cgns(path, &m, &d) == 0, "%s", d.message);
        add_field(&m);
        check_whole(&m, orders, curved, 24);
        tpk_mesh_free(&m);
    }
}

static void keep_warning(void *user, const char *text)
{
    snprintf((char *)user, 512, "%s", text);
}

/* A cubic tetra (TETRA_20), which this reader does not keep whole, is read by its corners with a warning
 * that says so; TETRA_4 and PYRA_5 are not taken for the quartic PYRA_55 or the like. */
TPK_TEST(cgns_cubic_reduced_with_a_warning)
{
    static double xyz[3][24];
    for (int k = 0; k < 24; k++) /* a unit tetra's corners, then 16 more points inside it */
        xyz[0][k] = k == 1 ? 1.0 : k >= 4 ? 0.1 + 0.01 * k : 0.0, xyz[1][k] = k == 2 ? 1.0 : k >= 4 ? 0.1 : 0.0,
        xyz[2][k] = k == 3 ? 1.0 : k >= 4 ? 0.1 : 0.0;
    const char *path = tpk_temp_path("cubic.cgns");
    int fn, base, zone, s;
    cgsize_t conn[20];
    for (int k = 0; k < 20; k++)
        conn[k] = k + 1;
    cgns_zone_begin(path, 20, 1, xyz[0], 24, &fn, &base, &zone);
    CHECK(cg_section_write(fn, base, zone, "cubic", CGNS_ENUMV(TETRA_20), 1, 1, 0, conn, &s) == 0);
    CHECK(cg_close(fn) == 0);
    tpk_mesh m;
    tpk_diag d;
    char warning[512] = "";
    memset(&d, 0, sizeof d);
    d.warn = keep_warning, d.warn_user = warning;
    CHECK_MSG(tpk_import_cgns(path, &m, &d) == 0, "%s", d.message);
    CHECK_MSG(strstr(warning, "reduced 1 volume elements to their corner nodes") != NULL, "%s", warning);
    CHECK(m.cell_count == 1 && m.cell_types[0] == TPK_CELL_TETRA && m.cell_offsets[1] == 4);
    tpk_mesh_free(&m);
}
#endif

/* check --against on closed-form cells (affine maps: the split fills each cell exactly, so no sample
 * falls outside): a linear field is reproduced by both conversions; a quadratic one is closer to the
 * source with the cells split whole than reduced to corners. */
TPK_TEST(check_against)
{
    const node_order *orders[] = {&vtk_tet10, &vtk_hex20, &vtk_hex27, &vtk_wedge15, &vtk_wedge18, &vtk_wedge12,
                                  &vtk_pyramid13};
    double quadratic_error[2] = {0, 0};
    for (int linear = 1; linear >= 0; linear--) {
        linear_field = linear;
        char *text = write_vtk(orders, 7, 0);
        const char *source = tpk_temp_path("against.vtk");
        FILE *f = fopen(source, "wb");
        CHECK(f && fputs(text, f) >= 0 && fclose(f) == 0);
        free(text);
        for (int corners = 0; corners < 2; corners++) {
            tpk_convert_options o;
            memset(&o, 0, sizeof o);
            o.input = source;
            o.output = tpk_temp_path("against.tpk");
            o.threads = 1;
            o.higher_order_corners = corners;
            tpk_convert_report rep;
            tpk_diag d;
            quiet(&d);
            CHECK_MSG(tpk_convert_checked(&o, &rep, &d) == 0, "%s", d.message);
            tpk_against_report r;
            CHECK_MSG(tpk_check_against(o.output, source, NULL, 4, &r, &d) == 0, "%s", d.message);
            CHECK_EQ_INT(r.cells, 7);
            CHECK_EQ_INT(r.outside, 0);
            CHECK(r.field_count == 1 && !strcmp(r.fields[0].name, "f") && !r.has_bound && !r.bound_exceeded);
            if (linear)
                CHECK_MSG(r.fields[0].max_error < 1e-6, "linear field, %s: max error %g",
                          corners ? "corners" : "split", r.fields[0].max_error);
            else
                quadratic_error[corners] = r.fields[0].max_error;
        }
    }
    linear_field = 0;
    fprintf(stderr, "quadratic field, max error as a fraction of its range: split %.3g, corners %.3g\n",
            quadratic_error[0], quadratic_error[1]);
    CHECK_MSG(quadratic_error[0] > 0 && quadratic_error[0] < 0.5 * quadratic_error[1],
              "quadratic field: split %g, corners %g", quadratic_error[0], quadratic_error[1]);
}

/* One refinement of the mesh in `text` to 0.1%, as convert --max-error makes it (the split, the tets on
 * the file grid, ids led back to the source's), with `extra` an unused copy of vertex 0 that is no source
 * point, and with `alias` vertex 1 said to be source point 0 too (so point 1, a node of the first cell,
 * is no vertex): into *rc 0 and the report, or -1 and the message. */
static void refine_case(const char *text, int extra, int alias, int *rc, tpk_refine_report *rep,
                        char (*message)[sizeof(((tpk_diag *)0)->message)])
{
    tpk_mesh m;
    tpk_diag d;
    quiet(&d);
    CHECK_MSG(tpk_import_vtk_legacy_memory("refine.vtk", text, strlen(text), &m, &d) == 0, "%s", d.message);
    tpk_refine_cells cells;
    CHECK(tpk_refine_cells_copy(&m, &cells) == 0);
    tpk_higher_split split;
    memset(&split, 0, sizeof split);
    tpk_tetmesh tets;
    memset(&tets, 0, sizeof tets);
    CHECK_MSG(tpk_split_higher_order(&m, "refine.vtk", &split, &d) == 0, "%s", d.message);
    CHECK_MSG(tpk_tetrahedralize(&m, NULL, 0, TPK_TETRA_FILE_GRID, &tets, &d) == 0, "%s", d.message);
    for (int64_t v = 0; split.cell_source && v < tets.vertex_count; v++)
        if (tets.vertex_source[v] >= split.source_points)
            tets.vertex_source[v] = -1;
    for (int64_t t = 0; split.cell_source && t < tets.tet_count; t++)
        tets.tet_source[t] = split.cell_source[tets.tet_source[t]];
    for (int64_t v = 0; v < tets.vertex_count; v++)
        CHECK_MSG(tets.vertex_source[v] >= 0, "vertex %lld is no source point: the case needs every one to be",
                  (long long)v);
    CHECK(tets.vertex_count > 1 && tets.vertex_source[0] == 0 && tets.vertex_source[1] == 1);
    if (alias)
        tets.vertex_source[1] = 0;
    if (extra) { /* at vertex 0's point: the box is the same, and no tet has it */
        int64_t n = tets.vertex_count;
        tets.points = realloc(tets.points, sizeof *tets.points * 3 * (size_t)(n + 1));
        tets.vertex_source = realloc(tets.vertex_source, sizeof *tets.vertex_source * (size_t)(n + 1));
        CHECK(tets.points && tets.vertex_source);
        memcpy(tets.points + 3 * n, tets.points, 3 * sizeof *tets.points);
        tets.vertex_source[n] = -1;
        for (int f = 0; f < tets.field_count; f++) {
            tpk_src_field *field = &tets.fields[f];
            if (field->association != TPK_ASSOC_POINT)
                continue;
            CHECK(field->step_count == 1 && field->components == 1);
            field->values = realloc(field->values, sizeof *field->values * (size_t)(n + 1));
            CHECK(field->values);
            field->values[n] = field->values[0];
        }
        tets.vertex_count = n + 1;
    }
    tpk_refine_options o = {.max_error = 0.001, .threads = 1};
    *rc = tpk_refine_max_error(&tets, &cells, &o, rep, &d);
    memcpy(*message, *rc != 0 ? d.message : "", *rc != 0 ? sizeof *message : 1);
    tpk_tetmesh_free(&tets);
    free(split.cell_source);
    tpk_refine_cells_free(&cells);
    tpk_mesh_free(&m);
}

/* --max-error's first bound takes a split's tet corners for nodes of their cells, and checks it as it
 * finds the nodes (refine.c place_corners), rather than in a pass of its own: the result must be the
 * one of placing every corner first, which a vertex that is no source point forces. Also where a cell's
 * node is no vertex: the first bound finds it, and place_corners then refuses the cell. */
TPK_TEST(refine_corners_checked_by_the_first_bound)
{
    const node_order *orders[] = {&vtk_tet10, &vtk_hex27, &vtk_wedge18};
    char *text = write_vtk(orders, 3, 1);
    for (int alias = 0; alias < 2; alias++) {
        tpk_refine_report a, b;
        char ma[sizeof(((tpk_diag *)0)->message)], mb[sizeof ma];
        int ra, rb;
        refine_case(text, 0, alias, &ra, &a, &ma);
        refine_case(text, 1, alias, &rb, &b, &mb);
        CHECK_MSG(ra == rb && !strcmp(ma, mb), "alias %d: %d \"%s\", placed first: %d \"%s\"", alias, ra, ma, rb, mb);
        if (alias) {
            CHECK_MSG(ra != 0 && strstr(ma, "has a node that is no vertex of the tets"), "alias: %d \"%s\"", ra, ma);
            continue;
        }
        CHECK_MSG(ra == 0 && a.tets_after > a.tets_before, "the curved cells refined: %d, %lld -> %lld tets", ra,
                  (long long)a.tets_before, (long long)a.tets_after);
        CHECK_EQ_INT(a.tets_after, b.tets_after);
        CHECK_EQ_INT(a.vertices_added, b.vertices_added);
        CHECK_EQ_INT(a.rounds, b.rounds);
        CHECK_MSG(a.field_error == b.field_error && a.geometry_error == b.geometry_error,
                  "bounds %.17g %.17g, placed first %.17g %.17g", a.field_error, a.geometry_error, b.field_error,
                  b.geometry_error);
    }
    free(text);
}
