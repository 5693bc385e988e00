/* Shape functions of the linear and quadratic volume cells, VTK's Lagrange tetra of orders 3-10,
 * hexahedra of orders 3-4 and wedges of orders 3-6, in VTK node order (vtkCellType.h; the node orders of vtkQuadraticTetra, vtkQuadraticHexahedron,
 * vtkTriQuadraticHexahedron, vtkBiQuadraticQuadraticHexahedron, vtkQuadraticWedge, vtkQuadraticLinearWedge,
 * vtkBiQuadraticQuadraticWedge and vtkQuadraticPyramid): corners first, then mid-edge nodes in the order
 * of `edges`, then mid-face nodes in the order of `faces`, then the centre. */
#include "cell_map.h"

#include <pthread.h>
#include <string.h>

#include "cell_types.h"
#include "mesh.h"

typedef struct node_table {
    int type, linear, nodes;
    int edge_count;
    int edges[12][2];
    int face_count;  /* mid-face nodes (4 corners each; a triangle's 4th repeats its 3rd) */
    int faces[6][4];
    int centre;      /* 1: a mid-cell node last */
} node_table;

#define HEX_EDGES {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}}
#define WEDGE_EDGES {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}}

static const node_table tables[] = {
    {10, 10, 4, 0, {{0}}, 0, {{0}}, 0},
    {12, 12, 8, 0, {{0}}, 0, {{0}}, 0},
    {13, 13, 6, 0, {{0}}, 0, {{0}}, 0},
    {14, 14, 5, 0, {{0}}, 0, {{0}}, 0},
    {24, 10, 10, 6, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}, 0, {{0}}, 0},
    {25, 12, 20, 12, HEX_EDGES, 0, {{0}}, 0},
    {26, 13, 15, 9, WEDGE_EDGES, 0, {{0}}, 0},
    {27, 14, 13, 8, {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}}, 0, {{0}}, 0},
    /* faces x = 0, x = 1, y = 0, y = 1, z = 0, z = 1 (vtkTriQuadraticHexahedron's parametric coordinates) */
    {29, 12, 27, 12, HEX_EDGES, 6,
     {{0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 2, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}}, 1},
    {31, 13, 12, 6, {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}}, 0, {{0}}, 0},
    /* the triquadratic hexahedron's nodes but the centres of faces z = 0, z = 1 and of the cell */
    {33, 12, 24, 12, HEX_EDGES, 4, {{0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 2, 6, 7}}, 0},
    {32, 13, 18, 9, WEDGE_EDGES, 3, {{0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}}, 0},
};

/* The node at barycentric lattice point (a, b, c), a + b + c = q, of an order-q Lagrange triangle in
 * VTK 9's numbering (vtkHigherOrderTriangle): rings from the outside in, each its 3 corners (a = q,
 * b = q, c = q), then its edges ab, bc, ca, each from its first corner; the innermost ring a single
 * point when q is a multiple of 3. */
static int lagrange_tri_node(int q, int a, int b, int c)
{
    int at = 0;
    for (; a > 0 && b > 0 && c > 0; a--, b--, c--, q -= 3)
        at += 3 * q;
    if (q == 0 || a == q)
        return at;
    if (b == q || c == q)
        return at + (b == q ? 1 : 2);
    if (c == 0)
        return at + 3 + (b - 1);
    if (a == 0)
        return at + 3 + (q - 1) + (c - 1);
    return at + 3 + 2 * (q - 1) + (a - 1);
}

/* VTK 9's numbering of the Lagrange tetra (vtkHigherOrderTetra; corners 0-3 at weights
 * w = (p - i - j - k, i, j, k)): shells from the outside in, each a tetra of order m = p - 4 L: its 4
 * corners; its edges 01, 12, 20, 03, 13, 23, each from its first corner; its faces' inner points, the
 * faces (0 1 3), (2 3 1), (0 3 2), (0 2 1) each numbered as a triangle with the corners in that order
 * (less its boundary ring); then the next shell, offset by (1, 1, 1). */
int tpk_cell_map_lagrange_tet_node(int p, int i, int j, int k)
{
    static const int edge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
    static const int face[4][3] = {{0, 1, 3}, {2, 3, 1}, {0, 3, 2}, {0, 2, 1}};
    int w[4] = {p - i - j - k, i, j, k}, m = p, at = 0;
    for (; w[0] > 0 && w[1] > 0 && w[2] > 0 && w[3] > 0; m -= 4) {
        at += 2 * m * m + 2; /* the points on the surface of an order-m tetra (m >= 4 here) */
        for (int v = 0; v < 4; v++)
            w[v]--;
    }
    if (m == 0)
        return at;
    for (int v = 0; v < 4; v++)
        if (w[v] == m)
            return at + v;
    at += 4;
    for (int e = 0; e < 6; e++)
        if (w[edge[e][0]] + w[edge[e][1]] == m)
            return at + e * (m - 1) + w[edge[e][1]] - 1;
    at += 6 * (m - 1);
    int f = 0;
    while (f < 3 && w[face[f][0]] + w[face[f][1]] + w[face[f][2]] != m)
        f++;
    return at + f * ((m - 1) * (m - 2) / 2) + lagrange_tri_node(m, w[face[f][0]], w[face[f][1]], w[face[f][2]]) - 3 * m;
}

/* VTK 9's numbering of the Lagrange wedge (vtkHigherOrderWedge::PointIndexFromIJK): the 6 corners; the
 * bottom triangle's edges 01, 12, 20, the top's, then the vertical edges at corners 0, 1, 2, each from
 * its first corner; the bottom and top triangles' inner points (by rows: i fastest, then j); the quad
 * faces j = 0, i + j = p, i = 0, each along its bottom edge's direction fastest, then up; then the
 * body, by layers of the triangle's inner points. */
int tpk_cell_map_lagrange_wedge_node(int p, int i, int j, int k)
{
    int m = p - 1, tri = (p - 1) * (p - 2) / 2, top = k == p, layer = k == 0 || k == p;
    int corner = i == p ? 1 : j == p ? 2 : i == 0 && j == 0 ? 0 : -1;
    if (corner >= 0)
        return layer ? corner + 3 * top : 6 + 6 * m + corner * m + (k - 1);
    int side = j == 0 ? 0 : i + j == p ? 1 : i == 0 ? 2 : -1;
    int along = side == 0 ? i - 1 : side == 1 ? j - 1 : p - j - 1;
    if (layer && side >= 0)
        return 6 + 3 * m * top + side * m + along;
    int inner = (j - 1) * (p - 1) - (j - 1) * j / 2 + (i - 1);
    int at = 6 + 9 * m;
    if (layer)
        return at + tri * top + inner;
    at += 2 * tri;
    if (side >= 0)
        return at + side * m * m + along + m * (k - 1);
    return at + 3 * m * m + tri * (k - 1) + inner;
}

int tpk_cell_map_lagrange_hex_node(int p, int i, int j, int k)
{
    int ib = i == 0 || i == p, jb = j == 0 || j == p, kb = k == 0 || k == p, m = p - 1;
    int corner_of_ij = i ? (j ? 2 : 1) : (j ? 3 : 0);
    if (ib && jb && kb)
        return corner_of_ij + (k ? 4 : 0);
    int at = 8;
    if (ib + jb + kb == 2) {
        if (!ib) /* along r: bottom edges 01 then 32, then the top's */
            return at + (i - 1) + (j ? 2 * m : 0) + (k ? 4 * m : 0);
        if (!jb) /* along s: bottom edges 12 then 03 */
            return at + (j - 1) + (i ? m : 3 * m) + (k ? 4 * m : 0);
        return at + 8 * m + (k - 1) + m * corner_of_ij; /* vertical */
    }
    at += 12 * m;
    if (ib + jb + kb == 1) {
        if (ib)
            return at + (j - 1) + m * (k - 1) + (i ? m * m : 0);
        at += 2 * m * m;
        if (jb)
            return at + (i - 1) + m * (k - 1) + (j ? m * m : 0);
        at += 2 * m * m;
        return at + (i - 1) + m * (j - 1) + (k ? m * m : 0);
    }
    return at + 6 * m * m + (i - 1) + m * ((j - 1) + m * (k - 1));
}

enum { TETRA, HEX, WEDGE };

/* The family (TETRA, HEX, WEDGE) and order p of a mapped Lagrange type; p = 0 for another type. */
static int lagrange_order_of(int type, int *family)
{
    static const int base[3] = {TPK_CELL_MAP_LAGRANGE_TETRA, TPK_CELL_MAP_LAGRANGE_HEX, TPK_CELL_MAP_LAGRANGE_WEDGE};
    static const int top[3] = {TPK_CELL_MAP_LAGRANGE_MAX_ORDER, TPK_CELL_MAP_LAGRANGE_HEX_MAX_ORDER,
                               TPK_CELL_MAP_LAGRANGE_WEDGE_MAX_ORDER};
    for (int f = 0; f < 3; f++)
        if (type - base[f] >= 3 && type - base[f] <= top[f]) {
            *family = f;
            return type - base[f];
        }
    *family = -1;
    return 0;
}

static int lagrange_order(int type)
{
    int family;
    return lagrange_order_of(type, &family);
}

static int family_of(int type)
{
    int family;
    lagrange_order_of(type, &family);
    return family;
}

/* The node count of a Lagrange tetra, hexahedron or wedge of order p. */
static int lagrange_count(int family, int p)
{
    return family == WEDGE ? (p + 1) * (p + 1) * (p + 2) / 2
           : family == HEX ? (p + 1) * (p + 1) * (p + 1)
                           : (p + 1) * (p + 2) * (p + 3) / 6;
}

int tpk_cell_map_type(int type, int64_t n)
{
    for (int p = 3; p <= TPK_CELL_MAP_LAGRANGE_MAX_ORDER; p++) {
        if (type == 71 && lagrange_count(TETRA, p) == n)
            return TPK_CELL_MAP_LAGRANGE_TETRA + p;
        if (type == 72 && p <= TPK_CELL_MAP_LAGRANGE_HEX_MAX_ORDER && lagrange_count(HEX, p) == n)
            return TPK_CELL_MAP_LAGRANGE_HEX + p;
        if (type == 73 && p <= TPK_CELL_MAP_LAGRANGE_WEDGE_MAX_ORDER && lagrange_count(WEDGE, p) == n)
            return TPK_CELL_MAP_LAGRANGE_WEDGE + p;
    }
    return type;
}

int tpk_cell_map_source_type(int type, int64_t n)
{
    if (type == TPK_CELL_VOXEL)
        type = TPK_CELL_HEXAHEDRON;
    else if ((type == 71 && n == 10) || (type == 72 && n == 27) || (type == 73 && n == 18))
        type = type == 71 ? 24 : type == 72 ? 29 : 32;
    else
        type = tpk_cell_map_type(type, n);
    return n > 0 && tpk_cell_map_nodes(type) == n ? type : 0;
}

int tpk_cell_map_source_node(int type, int k)
{
    static const int voxel_as_hex[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    return type == TPK_CELL_VOXEL && k >= 0 && k < 8 ? voxel_as_hex[k] : k;
}

/* The Lagrange cells' nodes by lattice point, per family and order (index (i (p + 1) + j) (p + 1) + k),
 * made once: the numbering functions walk the shells and faces, too slow to call per weight. */
#define LATTICE (TPK_CELL_MAP_LAGRANGE_MAX_ORDER + 1)
static int16_t lattice_node[3][TPK_CELL_MAP_LAGRANGE_MAX_ORDER + 1][LATTICE * LATTICE * LATTICE];
static pthread_once_t lattice_once = PTHREAD_ONCE_INIT;

static void lattice_make(void)
{
    for (int p = 3; p <= TPK_CELL_MAP_LAGRANGE_MAX_ORDER; p++)
        for (int i = 0; i <= p; i++)
            for (int j = 0; j <= p; j++)
                for (int k = 0; k <= p; k++) {
                    int at = (i * (p + 1) + j) * (p + 1) + k;
                    lattice_node[TETRA][p][at] = (int16_t)(i + j + k <= p ? tpk_cell_map_lagrange_tet_node(p, i, j, k) : -1);
                    lattice_node[HEX][p][at] = (int16_t)tpk_cell_map_lagrange_hex_node(p, i, j, k);
                    lattice_node[WEDGE][p][at] = (int16_t)(i + j <= p ? tpk_cell_map_lagrange_wedge_node(p, i, j, k) : -1);
                }
}

/* The family's node table of order p, (p + 1)^3 entries as lattice_node. */
static const int16_t *lattice_of(int family, int p)
{
    pthread_once(&lattice_once, lattice_make);
    return lattice_node[family][p];
}

/* l_m(L) = prod_{q<m} (p L - q) / (q + 1): 1 at L = m / p, 0 at L = 0, 1/p, ..., (m - 1) / p. */
static double lagrange_1d(int p, int m, double L)
{
    double v = 1;
    for (int q = 0; q < m; q++)
        v *= (p * L - q) / (q + 1);
    return v;
}

static int lagrange_tetra(int p, const double r[3], double *w)
{
    const double L[4] = {1 - r[0] - r[1] - r[2], r[0], r[1], r[2]};
    double l[4][TPK_CELL_MAP_LAGRANGE_MAX_ORDER + 1];
    for (int v = 0; v < 4; v++)
        for (int m = 0; m <= p; m++)
            l[v][m] = lagrange_1d(p, m, L[v]);
    const int16_t *node = lattice_of(TETRA, p);
    for (int i = 0; i <= p; i++)
        for (int j = 0; i + j <= p; j++)
            for (int k = 0; i + j + k <= p; k++)
                w[node[(i * (p + 1) + j) * (p + 1) + k]] = l[0][p - i - j - k] * l[1][i] * l[2][j] * l[3][k];
    return lagrange_count(TETRA, p);
}

/* The 1-D order-p Lagrange basis on nodes t = k / p at t into h[0 .. p]. */
static void lagrange_line(int p, double t, double *h)
{
    for (int k = 0; k <= p; k++) {
        h[k] = 1;
        for (int q = 0; q <= p; q++)
            if (q != k)
                h[k] *= (p * t - q) / (k - q);
    }
}

/* The order-p triangle's Lagrange basis in (L0, L1, L2) = (1 - r - s, r, s) times the 1-D order-p one in
 * t (nodes at t = k / p). */
static int lagrange_wedge(int p, const double r[3], double *w)
{
    const double L[3] = {1 - r[0] - r[1], r[0], r[1]};
    double l[3][TPK_CELL_MAP_LAGRANGE_WEDGE_MAX_ORDER + 1], h[TPK_CELL_MAP_LAGRANGE_WEDGE_MAX_ORDER + 1];
    for (int v = 0; v < 3; v++)
        for (int m = 0; m <= p; m++)
            l[v][m] = lagrange_1d(p, m, L[v]);
    lagrange_line(p, r[2], h);
    const int16_t *node = lattice_of(WEDGE, p);
    for (int i = 0; i <= p; i++)
        for (int j = 0; i + j <= p; j++)
            for (int k = 0; k <= p; k++)
                w[node[(i * (p + 1) + j) * (p + 1) + k]] = l[0][p - i - j] * l[1][i] * l[2][j] * h[k];
    return lagrange_count(WEDGE, p);
}

/* The product of the 1-D order-p Lagrange bases in r, s and t. */
static int lagrange_hex(int p, const double r[3], double *w)
{
    double h[3][TPK_CELL_MAP_LAGRANGE_HEX_MAX_ORDER + 1];
    for (int a = 0; a < 3; a++)
        lagrange_line(p, r[a], h[a]);
    const int16_t *node = lattice_of(HEX, p);
    for (int i = 0; i <= p; i++)
        for (int j = 0; j <= p; j++)
            for (int k = 0; k <= p; k++)
                w[node[(i * (p + 1) + j) * (p + 1) + k]] = h[0][i] * h[1][j] * h[2][k];
    return lagrange_count(HEX, p);
}

static const node_table *table_of(int type)
{
    for (size_t i = 0; i < sizeof tables / sizeof tables[0]; i++)
        if (tables[i].type == type)
            return &tables[i];
    return NULL;
}

int tpk_cell_map_nodes(int type)
{
    if (lagrange_order(type))
        return lagrange_count(family_of(type), lagrange_order(type));
    const node_table *t = table_of(type);
    return t ? t->nodes : 0;
}

int tpk_cell_map_degree(int type)
{
    switch (type) {
    case 10: return 1;
    case 13:
    case 24: return 2;
    case 12:
    case 26:
    case 31: return 3;
    case 25:
    case 32: return 4;
    case 33: return 5;
    case 29: return 6;
    default: return (family_of(type) == WEDGE ? 2 : family_of(type) == HEX ? 3 : 1) * lagrange_order(type);
    }
}

/* VTK's parametric corners (the pyramid's apex at (1/2, 1/2, 1), as vtkPyramid has it). */
static void corner(const node_table *t, int k, double r[3])
{
    memcpy(r, tpk_cell_shape_of(t->linear)->ref[k], 3 * sizeof *r);
    if (t->linear == TPK_CELL_PYRAMID && k == 4)
        r[0] = r[1] = 0.5;
}

void tpk_cell_map_node(int type, int k, double r[3])
{
    int p = lagrange_order(type);
    if (p && family_of(type) == HEX) {
        for (int i = 0; i <= p; i++)
            for (int j = 0; j <= p; j++)
                for (int l = 0; l <= p; l++)
                    if (tpk_cell_map_lagrange_hex_node(p, i, j, l) == k)
                        r[0] = (double)i / p, r[1] = (double)j / p, r[2] = (double)l / p;
        return;
    }
    if (p && family_of(type) == WEDGE) {
        for (int i = 0; i <= p; i++)
            for (int j = 0; i + j <= p; j++)
                for (int l = 0; l <= p; l++)
                    if (tpk_cell_map_lagrange_wedge_node(p, i, j, l) == k)
                        r[0] = (double)i / p, r[1] = (double)j / p, r[2] = (double)l / p;
        return;
    }
    if (p) {
        for (int i = 0; i <= p; i++)
            for (int j = 0; i + j <= p; j++)
                for (int l = 0; i + j + l <= p; l++)
                    if (tpk_cell_map_lagrange_tet_node(p, i, j, l) == k)
                        r[0] = (double)i / p, r[1] = (double)j / p, r[2] = (double)l / p;
        return;
    }
    const node_table *t = table_of(type);
    int corners = tpk_cell_shape_of(t->linear)->corners;
    double a[3], b[3];
    if (k < corners) {
        corner(t, k, r);
    } else if ((k -= corners) < t->edge_count) {
        corner(t, t->edges[k][0], a);
        corner(t, t->edges[k][1], b);
        for (int i = 0; i < 3; i++)
            r[i] = 0.5 * (a[i] + b[i]);
    } else if ((k -= t->edge_count) < t->face_count) {
        memset(r, 0, 3 * sizeof *r);
        for (int j = 0; j < 4; j++) {
            corner(t, t->faces[k][j], a);
            for (int i = 0; i < 3; i++)
                r[i] += 0.25 * a[i];
        }
    } else {
        r[0] = r[1] = r[2] = 0.5;
    }
}

/* 1-D quadratic Lagrange functions on [-1, 1] at nodes -1, 0, 1; node position given as -1, 0 or 1. */
static double lagrange2(double x, int at)
{
    return at < 0 ? 0.5 * x * (x - 1) : at > 0 ? 0.5 * x * (x + 1) : (1 - x) * (1 + x);
}

/* Node k's parametric coordinates as -1, 0, 1 per axis (2 r - 1), for the hexahedra: the triquadratic
 * one's 27 nodes (tpk_cell_map_node), of which the linear one has the first 8 and the serendipity one the
 * first 20 (higher_order.shape_functions: each weight 1 at its node, 0 at the others). */
static const signed char hex_signs[27][3] = {
    {-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1},
    {0, -1, -1},  {1, 0, -1},  {0, 1, -1}, {-1, 0, -1}, {0, -1, 1},  {1, 0, 1},  {0, 1, 1}, {-1, 0, 1},
    {-1, -1, 0},  {1, -1, 0},  {1, 1, 0},  {-1, 1, 0},  {-1, 0, 0},  {1, 0, 0},  {0, -1, 0}, {0, 1, 0},
    {0, 0, -1},   {0, 0, 1},   {0, 0, 0}};

static int hexahedron(int type, const double r[3], double *w)
{
    const double x[3] = {2 * r[0] - 1, 2 * r[1] - 1, 2 * r[2] - 1};
    int n = type == 12 ? 8 : type == 25 ? 20 : 27;
    for (int k = 0; k < n; k++) {
        const int s[3] = {hex_signs[k][0], hex_signs[k][1], hex_signs[k][2]};
        if (type == 29) {
            w[k] = lagrange2(x[0], s[0]) * lagrange2(x[1], s[1]) * lagrange2(x[2], s[2]);
        } else if (type == 12) {
            w[k] = 0.125 * (1 + x[0] * s[0]) * (1 + x[1] * s[1]) * (1 + x[2] * s[2]);
        } else if (s[0] && s[1] && s[2]) { /* serendipity corner */
            w[k] = 0.125 * (1 + x[0] * s[0]) * (1 + x[1] * s[1]) * (1 + x[2] * s[2]) *
                   (x[0] * s[0] + x[1] * s[1] + x[2] * s[2] - 2);
        } else { /* serendipity mid-edge: the zero axis quadratic, the others linear */
            double v = 0.25;
            for (int i = 0; i < 3; i++)
                v *= s[i] ? 1 + x[i] * s[i] : (1 - x[i]) * (1 + x[i]);
            w[k] = v;
        }
    }
    return n;
}

/* The biquadratic-quadratic hexahedron (vtkBiQuadraticQuadraticHexahedron): the triquadratic one with the
 * values at its 3 missing nodes given by the 8-node serendipity rule of their layer (-1/4 of its corners,
 * +1/2 of its mid-edges): at the z = 0 and z = 1 face centres those faces' nodes, at the cell centre the
 * middle layer's (vertical mid-edges 16-19 as corners, face centres 20-23 as mid-edges). Matches VTK's
 * InterpolationFunctions to 2e-16 at random points (checked with python3-paraview's VTK 9.2). */
static int hexahedron24(const double r[3], double *w)
{
    static const int layer[3][8] = {{0, 1, 2, 3, 8, 9, 10, 11}, {4, 5, 6, 7, 12, 13, 14, 15},
                                    {16, 17, 18, 19, 20, 21, 22, 23}};
    double full[27];
    hexahedron(29, r, full);
    memcpy(w, full, 24 * sizeof *w);
    for (int m = 0; m < 3; m++)
        for (int k = 0; k < 8; k++)
            w[layer[m][k]] += (k < 4 ? -0.25 : 0.5) * full[24 + m];
    return 24;
}

/* Wedges: a triangle's barycentric L (L0 = 1 - r - s, L1 = r, L2 = s) times a function of z = 2 t - 1. */
static int wedge(int type, const double r[3], double *w)
{
    const double L[3] = {1 - r[0] - r[1], r[0], r[1]}, z = 2 * r[2] - 1;
    static const int tri_edges[3][2] = {{0, 1}, {1, 2}, {2, 0}};
    double tri[6]; /* quadratic triangle: corners, then mid-edges */
    for (int i = 0; i < 3; i++) {
        tri[i] = L[i] * (2 * L[i] - 1);
        tri[3 + i] = 4 * L[tri_edges[i][0]] * L[tri_edges[i][1]];
    }
    switch (type) {
    case 13:
        for (int i = 0; i < 6; i++)
            w[i] = L[i % 3] * (i < 3 ? 1 - r[2] : r[2]);
        return 6;
    case 31: /* corners 0-5, then bottom and top mid-edges: quadratic triangle times linear in z */
        for (int i = 0; i < 3; i++) {
            w[i] = tri[i] * (1 - r[2]), w[3 + i] = tri[i] * r[2];
            w[6 + i] = tri[3 + i] * (1 - r[2]), w[9 + i] = tri[3 + i] * r[2];
        }
        return 12;
    case 26: /* serendipity */
        for (int i = 0; i < 3; i++) {
            w[i] = 0.5 * L[i] * ((2 * L[i] - 1) * (1 - z) - (1 - z) * (1 + z));
            w[3 + i] = 0.5 * L[i] * ((2 * L[i] - 1) * (1 + z) - (1 - z) * (1 + z));
            w[6 + i] = 0.5 * tri[3 + i] * (1 - z);
            w[9 + i] = 0.5 * tri[3 + i] * (1 + z);
            w[12 + i] = L[i] * (1 - z) * (1 + z);
        }
        return 15;
    default: /* 32: quadratic triangle times quadratic in z */
        for (int i = 0; i < 3; i++) {
            w[i] = tri[i] * lagrange2(z, -1), w[3 + i] = tri[i] * lagrange2(z, 1);
            w[6 + i] = tri[3 + i] * lagrange2(z, -1), w[9 + i] = tri[3 + i] * lagrange2(z, 1);
            w[12 + i] = tri[i] * lagrange2(z, 0), w[15 + i] = tri[3 + i] * lagrange2(z, 0);
        }
        return 18;
    }
}

/* The pyramids: the linear one as vtkPyramid; the quadratic one the rational 13-node pyramid of
 * Bedrosian (1992), as libMesh and VTK's vtkQuadraticPyramid use it, in x = 2r - 1, y = 2s - 1, z = t (the
 * cross-section at height z is [-(1 - z), 1 - z]^2): it reproduces quadratic polynomials, is the 8-node
 * serendipity quadrilateral on its base and the 6-node triangle on its sides (tests/test_higher_order.c). */
static int pyramid(int type, const double r[3], double *w)
{
    if (type == 14) {
        w[0] = (1 - r[0]) * (1 - r[1]) * (1 - r[2]), w[1] = r[0] * (1 - r[1]) * (1 - r[2]);
        w[2] = r[0] * r[1] * (1 - r[2]), w[3] = (1 - r[0]) * r[1] * (1 - r[2]), w[4] = r[2];
        return 5;
    }
    const double x = 2 * r[0] - 1, y = 2 * r[1] - 1, z = r[2], d = 1 - z;
    memset(w, 0, 13 * sizeof *w);
    if (d <= 0) { /* the apex */
        w[4] = 1;
        return 13;
    }
    const double xy = x * y * z / d;
    w[0] = 0.25 * (-x - y - 1) * ((1 - x) * (1 - y) - z + xy);
    w[1] = 0.25 * (x - y - 1) * ((1 + x) * (1 - y) - z - xy);
    w[2] = 0.25 * (x + y - 1) * ((1 + x) * (1 + y) - z + xy);
    w[3] = 0.25 * (-x + y - 1) * ((1 - x) * (1 + y) - z - xy);
    w[4] = z * (2 * z - 1);
    /* mid-edges 5-8 on the base's edges 01 (y = -1), 12 (x = 1), 23 (y = 1), 30 (x = -1), 9-12 to the apex */
    w[5] = 0.5 * (1 + x - z) * (1 - x - z) * (1 - y - z) / d;
    w[6] = 0.5 * (1 + y - z) * (1 - y - z) * (1 + x - z) / d;
    w[7] = 0.5 * (1 + x - z) * (1 - x - z) * (1 + y - z) / d;
    w[8] = 0.5 * (1 + y - z) * (1 - y - z) * (1 - x - z) / d;
    w[9] = z * (1 - x - z) * (1 - y - z) / d;
    w[10] = z * (1 + x - z) * (1 - y - z) / d;
    w[11] = z * (1 + x - z) * (1 + y - z) / d;
    w[12] = z * (1 - x - z) * (1 + y - z) / d;
    return 13;
}

int tpk_cell_map_weights(int type, const double r[3], double *w)
{
    switch (type) {
    case 10:
    case 24: {
        const double L[4] = {1 - r[0] - r[1] - r[2], r[0], r[1], r[2]};
        if (type == 10) {
            memcpy(w, L, sizeof L);
            return 4;
        }
        const node_table *t = table_of(24);
        for (int i = 0; i < 4; i++)
            w[i] = L[i] * (2 * L[i] - 1);
        for (int e = 0; e < 6; e++)
            w[4 + e] = 4 * L[t->edges[e][0]] * L[t->edges[e][1]];
        return 10;
    }
    case 12:
    case 25:
    case 29: return hexahedron(type, r, w);
    case 33: return hexahedron24(r, w);
    case 13:
    case 26:
    case 31:
    case 32: return wedge(type, r, w);
    case 14:
    case 27: return pyramid(type, r, w);
    default:
        if (!lagrange_order(type))
            return 0;
        return family_of(type) == WEDGE ? lagrange_wedge(lagrange_order(type), r, w)
               : family_of(type) == HEX ? lagrange_hex(lagrange_order(type), r, w)
                                        : lagrange_tetra(lagrange_order(type), r, w);
    }
}

int tpk_cell_map_point(int type, const int32_t *nodes, const double *points, const double r[3], double x[3])
{
    double w[TPK_CELL_MAP_MAX_NODES];
    int n = tpk_cell_map_weights(type, r, w);
    if (n == 0)
        return -1;
    x[0] = x[1] = x[2] = 0;
    for (int k = 0; k < n; k++)
        for (int i = 0; i < 3; i++)
            x[i] += w[k] * points[3 * (int64_t)nodes[k] + i];
    return 0;
}

int tpk_cell_map_nonlinear(int type, const double r[3], double *m)
{
    if (type == 12) {
        m[0] = r[0] * r[1], m[1] = r[1] * r[2], m[2] = r[2] * r[0], m[3] = r[0] * r[1] * r[2];
        return 4;
    }
    if (type == 24) {
        const double L[4] = {1 - r[0] - r[1] - r[2], r[0], r[1], r[2]};
        const node_table *t = table_of(24);
        for (int e = 0; e < 6; e++)
            m[e] = L[t->edges[e][0]] * L[t->edges[e][1]];
        return 6;
    }
    return 0;
}

int tpk_cell_map_quadratic_tet(int type, const double *xi, double (*w)[10], double (*m)[6])
{
    if (type != 24)
        return 0;
    /* the quadratic tetra's edges (its node_table's: 01, 12, 20, 03, 13, 23) written out, as
     * tpk_cell_map_weights and tpk_cell_map_nonlinear compute them: refine's bound calls this once a tet,
     * and at -O2 the loops over the edges' index tables did not unroll (callgrind: 840 instructions a
     * call, about half of them those loops) */
    for (int k = 0; k < 4; k++) {
        const double *r = xi + 3 * k;
        const double l0 = 1 - r[0] - r[1] - r[2], l1 = r[0], l2 = r[1], l3 = r[2];
        w[k][0] = l0 * (2 * l0 - 1), w[k][1] = l1 * (2 * l1 - 1);
        w[k][2] = l2 * (2 * l2 - 1), w[k][3] = l3 * (2 * l3 - 1);
        w[k][4] = 4 * l0 * l1, w[k][5] = 4 * l1 * l2, w[k][6] = 4 * l2 * l0;
        w[k][7] = 4 * l0 * l3, w[k][8] = 4 * l1 * l3, w[k][9] = 4 * l2 * l3;
    }
    static const int pair[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    for (int p = 0; p < 6; p++) {
        const double *r = xi + 3 * pair[p][0], *s = xi + 3 * pair[p][1];
        const double d0 = -(r[0] - s[0]) - (r[1] - s[1]) - (r[2] - s[2]), d1 = r[0] - s[0], d2 = r[1] - s[1],
                     d3 = r[2] - s[2];
        m[p][0] = d0 * d1, m[p][1] = d1 * d2, m[p][2] = d2 * d0;
        m[p][3] = d0 * d3, m[p][4] = d1 * d3, m[p][5] = d2 * d3;
    }
    return 10;
}

int tpk_cell_map_nonlinear_coefficients(int type, const double *v, int comps, double *a)
{
    if (type == 12) { /* corner (a, b, c)'s function is prod (1 - a + (2a - 1) x), corners in VTK's order */
        static const signed char coefficient[4][8] = {
            {1, -1, 1, -1, 0, 0, 0, 0},   /* xy: (2a - 1)(2b - 1)(1 - c) */
            {1, 0, 0, -1, -1, 0, 0, 1},   /* yz: (2b - 1)(2c - 1)(1 - a) */
            {1, -1, 0, 0, -1, 1, 0, 0},   /* zx: (2c - 1)(2a - 1)(1 - b) */
            {-1, 1, -1, 1, 1, -1, 1, -1}, /* xyz: (2a - 1)(2b - 1)(2c - 1) */
        };
        for (int q = 0; q < 4; q++)
            for (int c = 0; c < comps; c++) {
                double sum = 0;
                for (int k = 0; k < 8; k++)
                    sum += coefficient[q][k] * v[k * comps + c];
                a[q * comps + c] = sum;
            }
        return 4;
    }
    if (type == 24) {
        const node_table *t = table_of(24);
        for (int e = 0; e < 6; e++)
            for (int c = 0; c < comps; c++)
                a[e * comps + c] = 4 * v[(4 + e) * comps + c] - 2 * v[t->edges[e][0] * comps + c] -
                                   2 * v[t->edges[e][1] * comps + c];
        return 6;
    }
    return 0;
}
