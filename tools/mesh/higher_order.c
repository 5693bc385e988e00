/* Higher-order volume cells reduced to corners, or split into the linear cells of their node lattice
 * (higher_order.h). The lattices are written on the fullest node set of each shape (27 for hexahedra,
 * 18 for wedges, 14 for pyramids: the 13 nodes and the base centre; 19 for the triquadratic pyramid, 15
 * for tetra with face centres); a cell with fewer nodes gets the missing ones as added points, listed
 * after its own in the same local order. Lagrange cells of order 3 and more have their own lattices. */
#include "higher_order.h"

#include <stdlib.h>
#include <string.h>

#include "cell_map.h"
#include "cell_types.h"
#include "tetpack_format.h"

int tpk_is_higher_order_volume(int type)
{
    const tpk_cell_type_info *t = tpk_cell_type(type);
    return t && t->dim == 3 && t->linear_type != t->type;
}

int64_t tpk_reduce_higher_order(tpk_mesh *mesh, const char *name, tpk_diag *diag)
{
    int64_t reduced[256] = {0}, total = 0, at = 0;
    for (int64_t c = 0; c < mesh->cell_count; c++) {
        int64_t begin = mesh->cell_offsets[c], end = mesh->cell_offsets[c + 1];
        int type = mesh->cell_types[c];
        mesh->cell_offsets[c] = at;
        if (tpk_is_higher_order_volume(type) && end - begin >= tpk_cell_type(type)->corners) {
            reduced[type]++, total++;
            end = begin + tpk_cell_type(type)->corners;
            mesh->cell_types[c] = (uint8_t)tpk_cell_type(type)->linear_type;
        }
        memmove(mesh->cell_conn + at, mesh->cell_conn + begin, sizeof *mesh->cell_conn * (size_t)(end - begin));
        at += end - begin;
    }
    if (mesh->cell_count)
        mesh->cell_offsets[mesh->cell_count] = at;
    if (total)
        tpk_warn_cell_counts(diag, name, reduced, total, "reduced higher-order cells to their corner nodes:");
    return total;
}

/* ---- the lattices ------------------------------------------------------------------------------ */

/* A cell's linear pieces in the local numbering of its full lattice. */
typedef struct piece {
    int type, nodes[8];
} piece;

/* Hexahedra on the 27-node lattice: node of lattice point (i, j, k), i, j, k in 0..2. */
static int lattice27(int i, int j, int k)
{
    for (int n = 0; n < 27; n++) {
        double r[3];
        tpk_cell_map_node(29, n, r);
        if ((int)(2 * r[0] + 0.5) == i && (int)(2 * r[1] + 0.5) == j && (int)(2 * r[2] + 0.5) == k)
            return n;
    }
    return -1;
}

static int hex_pieces(piece *p)
{
    static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    int n = 0;
    for (int c = 0; c < 8; c++, n++) {
        p[n].type = TPK_CELL_HEXAHEDRON;
        for (int v = 0; v < 8; v++)
            p[n].nodes[v] = lattice27(corner[c][0] + corner[v][0], corner[c][1] + corner[v][1],
                                      corner[c][2] + corner[v][2]);
    }
    return n;
}

/* Wedges: per layer the triangle's corners 0, 1, 2 and mid-edges 01, 12, 20 (18-node numbering). */
static int wedge_pieces(int layers, piece *p)
{
    static const int layer[3][6] = {{0, 1, 2, 6, 7, 8}, {12, 13, 14, 15, 16, 17}, {3, 4, 5, 9, 10, 11}};
    static const int two[2][6] = {{0, 1, 2, 6, 7, 8}, {3, 4, 5, 9, 10, 11}}; /* 31's two layers */
    static const int tri[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {3, 4, 5}};
    int n = 0;
    for (int l = 0; l + 1 < layers; l++)
        for (int t = 0; t < 4; t++, n++) {
            const int *lo = layers == 3 ? layer[l] : two[0], *hi = layers == 3 ? layer[l + 1] : two[1];
            p[n].type = TPK_CELL_WEDGE;
            for (int v = 0; v < 3; v++)
                p[n].nodes[v] = lo[tri[t][v]], p[n].nodes[3 + v] = hi[tri[t][v]];
        }
    return n;
}

/* The pyramid: base corners 0-3, apex 4, base mid-edges 5-8, lateral 9-12, base centre 13. */
static int pyramid_pieces(piece *p)
{
    static const piece pyr[10] = {
        {TPK_CELL_PYRAMID, {0, 5, 13, 8, 9}},    {TPK_CELL_PYRAMID, {5, 1, 6, 13, 10}},
        {TPK_CELL_PYRAMID, {13, 6, 2, 7, 11}},   {TPK_CELL_PYRAMID, {8, 13, 7, 3, 12}},
        {TPK_CELL_PYRAMID, {9, 10, 11, 12, 4}},  {TPK_CELL_PYRAMID, {9, 12, 11, 10, 13}},
        {TPK_CELL_TETRA, {5, 13, 9, 10}},        {TPK_CELL_TETRA, {6, 13, 10, 11}},
        {TPK_CELL_TETRA, {7, 13, 11, 12}},       {TPK_CELL_TETRA, {8, 13, 12, 9}},
    };
    memcpy(p, pyr, sizeof pyr);
    return 10;
}

/* The quadratic tetra: 4 corner tetra and the octahedron of mid-edges cut along `diagonal` (0: 4-9,
 * 1: 5-7, 2: 6-8; the mid-edges of opposite edges). */
static int tetra_pieces(int diagonal, piece *p)
{
    static const piece corners[4] = {{TPK_CELL_TETRA, {0, 4, 6, 7}}, {TPK_CELL_TETRA, {4, 1, 5, 8}},
                                     {TPK_CELL_TETRA, {6, 5, 2, 9}}, {TPK_CELL_TETRA, {7, 8, 9, 3}}};
    static const int axis[3][2] = {{4, 9}, {5, 7}, {6, 8}};
    memcpy(p, corners, sizeof corners);
    const int *d = axis[diagonal], *u = axis[(diagonal + 1) % 3], *v = axis[(diagonal + 2) % 3];
    const int ring[4] = {u[0], v[0], u[1], v[1]}; /* opposite mid-edges are not neighbours on the ring */
    for (int i = 0; i < 4; i++) {
        p[4 + i].type = TPK_CELL_TETRA;
        int t[4] = {d[0], d[1], ring[i], ring[(i + 1) % 4]};
        memcpy(p[4 + i].nodes, t, sizeof t);
    }
    return 8;
}

/* ---- Lagrange cells of order 3 and up: every node a corner of a cell of the node lattice ------- */

#define LAGRANGE_MAX_ORDER 10

/* The node count of a Lagrange tetra (71), hexahedron (72) or wedge (73) of order p. */
static int64_t lagrange_nodes(int type, int p)
{
    if (type == 71)
        return (int64_t)(p + 1) * (p + 2) * (p + 3) / 6;
    if (type == 72)
        return (int64_t)(p + 1) * (p + 1) * (p + 1);
    return (int64_t)(p + 1) * (p + 1) * (p + 2) / 2;
}

/* The order p of a Lagrange tetra, hexahedron or wedge with n nodes, 3 <= p <= LAGRANGE_MAX_ORDER; else
 * 0 (order 2 is split as the quadratic types; an anisotropic order is not read here). */
static int lagrange_order(int type, int64_t n)
{
    if (type != 71 && type != 72 && type != 73)
        return 0;
    for (int p = 3; p <= LAGRANGE_MAX_ORDER; p++)
        if (lagrange_nodes(type, p) == n)
            return p;
    return 0;
}

/* The linear cells of an order-p Lagrange cell, and their nodes in all into *conn: a tetra's lattice
 * has C(p+2,3) upright tetra, C(p+1,3) octahedra (4 tetra each) and C(p,3) upside-down tetra; a
 * hexahedron's p^3 hexahedra, a wedge's p^3 wedges (p^2 triangles in each of p layers). */
static int64_t lagrange_cells(int type, int p, int64_t *conn)
{
    if (type == 71) {
        int64_t up = (int64_t)(p + 2) * (p + 1) * p / 6, oct = (int64_t)(p + 1) * p * (p - 1) / 6,
                down = (int64_t)p * (p - 1) * (p - 2) / 6;
        *conn = 4 * (up + 4 * oct + down);
        return up + 4 * oct + down;
    }
    int64_t cells = (int64_t)p * p * p;
    *conn = cells * (type == 72 ? 8 : 6);
    return cells;
}

/* Orientation of tetra (a, b, c, d) of lattice points: the sign of det(b - a, c - a, d - a). */
static int lattice_orientation(const int x[4][3])
{
    int u[3], s[3], w[3];
    for (int k = 0; k < 3; k++)
        u[k] = x[1][k] - x[0][k], s[k] = x[2][k] - x[0][k], w[k] = x[3][k] - x[0][k];
    int det = u[0] * (s[1] * w[2] - s[2] * w[1]) - u[1] * (s[0] * w[2] - s[2] * w[0]) + u[2] * (s[0] * w[1] - s[1] * w[0]);
    return det > 0 ? 1 : det < 0 ? -1 : 0;
}

/* A tetra of an order-p Lagrange tetra's lattice at lattice points x, positive. */
static piece lattice_tet(int p, int x[4][3])
{
    if (lattice_orientation((const int(*)[3])x) < 0)
        for (int k = 0; k < 3; k++) {
            int t = x[2][k];
            x[2][k] = x[3][k], x[3][k] = t;
        }
    piece q = {TPK_CELL_TETRA, {0}};
    for (int v = 0; v < 4; v++)
        q.nodes[v] = tpk_cell_map_lagrange_tet_node(p, x[v][0], x[v][1], x[v][2]);
    return q;
}

/* The pieces of an order-p Lagrange tetra or wedge in its local numbering, into out (NULL: counted only).
 * A tetra's octahedron is an entry of type 0 with its 3 pairs of opposite corners in nodes[0..5], then
 * 12 tetra: 4 for the cut along each pair. Returns the entry count. */
static int lagrange_layout(int type, int p, piece *out)
{
    int n = 0;
    if (type == 73) {
        for (int k = 0; k < p; k++)
            for (int j = 0; j < p; j++)
                for (int i = 0; i + j < p; i++)
                    for (int down = 0; down < 2 && (down == 0 || i + j + 2 <= p); down++, n++) {
                        /* the triangle (i, j) (i+1, j) (i, j+1), or (i+1, j) (i+1, j+1) (i, j+1) */
                        const int tri[2][3][2] = {{{i, j}, {i + 1, j}, {i, j + 1}}, {{i + 1, j}, {i + 1, j + 1}, {i, j + 1}}};
                        if (!out)
                            continue;
                        out[n].type = TPK_CELL_WEDGE;
                        for (int v = 0; v < 3; v++) {
                            out[n].nodes[v] = tpk_cell_map_lagrange_wedge_node(p, tri[down][v][0], tri[down][v][1], k);
                            out[n].nodes[3 + v] = tpk_cell_map_lagrange_wedge_node(p, tri[down][v][0], tri[down][v][1], k + 1);
                        }
                    }
        return n;
    }
    for (int k = 0; k < p; k++)
        for (int j = 0; j + k < p; j++)
            for (int i = 0; i + j + k < p; i++) {
                int up[4][3] = {{i, j, k}, {i + 1, j, k}, {i, j + 1, k}, {i, j, k + 1}};
                if (out)
                    out[n] = lattice_tet(p, up);
                n++;
                if (i + j + k + 2 > p)
                    continue;
                /* the octahedron: opposite corners (i+1, j, k)-(i, j+1, k+1), (i, j+1, k)-(i+1, j, k+1),
                 * (i, j, k+1)-(i+1, j+1, k) */
                int pair[3][2][3] = {{{i + 1, j, k}, {i, j + 1, k + 1}},
                                     {{i, j + 1, k}, {i + 1, j, k + 1}},
                                     {{i, j, k + 1}, {i + 1, j + 1, k}}};
                if (out) {
                    out[n].type = 0;
                    for (int a = 0; a < 3; a++)
                        for (int b = 0; b < 2; b++)
                            out[n].nodes[2 * a + b] =
                                tpk_cell_map_lagrange_tet_node(p, pair[a][b][0], pair[a][b][1], pair[a][b][2]);
                    for (int d = 0; d < 3; d++) {
                        const int *u0 = pair[(d + 1) % 3][0], *u1 = pair[(d + 1) % 3][1];
                        const int *v0 = pair[(d + 2) % 3][0], *v1 = pair[(d + 2) % 3][1];
                        const int *ring[4] = {u0, v0, u1, v1}; /* opposite corners are not neighbours on it */
                        for (int r = 0; r < 4; r++) {
                            int t[4][3];
                            memcpy(t[0], pair[d][0], sizeof t[0]), memcpy(t[1], pair[d][1], sizeof t[1]);
                            memcpy(t[2], ring[r], sizeof t[2]), memcpy(t[3], ring[(r + 1) % 4], sizeof t[3]);
                            out[n + 1 + 4 * d + r] = lattice_tet(p, t);
                        }
                    }
                }
                n += 13;
                if (i + j + k + 3 > p)
                    continue;
                int down[4][3] = {{i + 1, j + 1, k}, {i + 1, j, k + 1}, {i, j + 1, k + 1}, {i + 1, j + 1, k + 1}};
                if (out)
                    out[n] = lattice_tet(p, down);
                n++;
            }
    return n;
}

/* Sub-hexahedron (a, b, c) of an order-p Lagrange hexahedron: its 8 nodes, VTK's corner order. */
static void lagrange_hex_piece(int p, int a, int b, int c, int32_t *local)
{
    static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (int v = 0; v < 8; v++)
        local[v] = tpk_cell_map_lagrange_hex_node(p, a + corner[v][0], b + corner[v][1], c + corner[v][2]);
}

/* The full lattice type of a split type (whose pieces are written in its numbering). */
static int full_type(int type)
{
    return type == 25 || type == 33 ? 29 : type == 26 ? 32 : type;
}

static int split_type(int type)
{
    return type == 24 || type == 25 || type == 26 || type == 27 || type == 29 || type == 31 || type == 32 ||
           type == 33 || type == 37;
}

/* A cell split by a fixed table: a split type with its node count; a quadratic tetra or pyramid with
 * face centres, as the importers keep Exodus's TETRA14 (24, 14 nodes: the 10, then the centres of
 * faces 012, 013, 123, 023) and PYRAMID14 (27, 14 nodes: the 13, then the base centre); VTK's 15-node
 * Lagrange tetra (71: those 14, then the body centre; Exodus's TETRA15). */
static int fixed_split(int type, int64_t n)
{
    return split_type(type) || (type == 71 && n == 15);
}

static int fixed_nodes_ok(int type, int64_t n)
{
    return n == tpk_cell_map_nodes(type) || ((type == 24 || type == 27) && n == 14) || (type == 71 && n == 15) ||
           (type == 37 && n == 19);
}

/* The tetra's faces: their mid-edge nodes and their centre in the 15-node numbering. */
static const int tet_face_nodes[4][4] = {{4, 5, 6, 10}, {4, 7, 8, 11}, {5, 8, 9, 12}, {6, 7, 9, 13}};

/* Tetra pieces with a face on one of the cell's triangles whose middle quarter (its mid-edges' triangle,
 * faces[f][0..2]) they are: fanned into 3 about that triangle's centre (faces[f][3]), as the other cell
 * on it does. Other pieces copied. Returns the count. */
static int fan_sides(const piece *in, int count, const int (*faces)[4], piece *out)
{
    int n = 0;
    for (int i = 0; i < count; i++) {
        int centre = -1, off = -1;
        for (int o = 0; o < 4 && centre < 0 && in[i].type == TPK_CELL_TETRA; o++) /* the face without corner o */
            for (int f = 0; f < 4 && centre < 0; f++) {
                int hits = 0;
                for (int v = 0; v < 4; v++)
                    for (int e = 0; e < 3; e++)
                        hits += v != o && in[i].nodes[v] == faces[f][e];
                if (hits == 3)
                    centre = faces[f][3], off = o;
            }
        if (centre < 0) {
            out[n++] = in[i];
            continue;
        }
        for (int v = 0; v < 4; v++)
            if (v != off) {
                out[n] = in[i];
                out[n++].nodes[v] = centre;
            }
    }
    return n;
}

/* The triquadratic pyramid (37; vtkTriQuadraticPyramid: the 14-node pyramid's nodes, then the centres of
 * the sides 014, 124, 234, 304, then the centroid at a quarter of the height): as the 14-node pyramid,
 * its inner upside-down pyramid coned from the centroid (a pyramid on its square and 4 tetra), and the
 * 4 tetra on the sides' middle quarters fanned about their centres (22 pieces). */
static const int pyramid_side_nodes[4][4] = {{5, 9, 10, 14}, {6, 10, 11, 15}, {7, 11, 12, 16}, {8, 12, 9, 17}};

static int fan_sides(const piece *in, int count, const int (*faces)[4], piece *out);

static int pyramid19_pieces(piece *p)
{
    piece cut[14];
    int n = pyramid_pieces(cut); /* 0-3 base pyramids, 4 the top one, 5 the upside-down one, 6-9 tetra */
    static const piece cone[5] = {{TPK_CELL_PYRAMID, {9, 12, 11, 10, 18}}, {TPK_CELL_TETRA, {13, 9, 10, 18}},
                                  {TPK_CELL_TETRA, {13, 10, 11, 18}},      {TPK_CELL_TETRA, {13, 11, 12, 18}},
                                  {TPK_CELL_TETRA, {13, 12, 9, 18}}};
    cut[5] = cone[0];
    memcpy(cut + n, cone + 1, 4 * sizeof *cut);
    return fan_sides(cut, n + 4, pyramid_side_nodes, p);
}

/* The 15-node tetra: the 4 corner tetra, and a cone from the body centre over the octahedron's 8 faces,
 * the 4 on the cell's faces fanned about their centres (20 tetra). */
static int tetra15_pieces(piece *p)
{
    static const int inner[4][3] = {{4, 6, 7}, {4, 5, 8}, {5, 6, 9}, {7, 8, 9}}; /* faces of the corner tetra */
    piece cone[12];
    tetra_pieces(0, cone);
    for (int f = 0; f < 8; f++) {
        const int *tri = f < 4 ? inner[f] : tet_face_nodes[f - 4];
        piece t = {TPK_CELL_TETRA, {tri[0], tri[1], tri[2], 14}};
        cone[4 + f] = t;
    }
    return fan_sides(cone, 12, tet_face_nodes, p);
}

/* Pieces (linear cells) of a split type; tetra pieces put positive on the parametric cell. */
static int pieces_of(int type, int64_t n, const int32_t *nodes, const double *points, piece *p)
{
    if (type == 71)
        return tetra15_pieces(p);
    if (type == 24) {
        /* the shortest of the octahedron's three diagonals (the best-shaped inner tetra) */
        static const int axis[3][2] = {{4, 9}, {5, 7}, {6, 8}};
        int best = 0;
        double best_len = 0;
        for (int d = 0; d < 3; d++) {
            const double *a = points + 3 * (int64_t)nodes[axis[d][0]], *b = points + 3 * (int64_t)nodes[axis[d][1]];
            double len = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
            if (d == 0 || len < best_len)
                best = d, best_len = len;
        }
        if (n == 10)
            return tetra_pieces(best, p);
        piece cut[8];
        tetra_pieces(best, cut);
        return fan_sides(cut, 8, tet_face_nodes, p);
    }
    if (type == 25 || type == 29 || type == 33)
        return hex_pieces(p);
    if (type == 37)
        return pyramid19_pieces(p);
    if (type == 26 || type == 32 || type == 31)
        return wedge_pieces(type == 31 ? 2 : 3, p);
    return pyramid_pieces(p);
}

/* Parametric coordinates of local node k of a split type's full lattice (the pyramid's 13: base centre;
 * the tetra's 10-13 its face centres, 14 its body centre). */
static void local_node(int type, int k, double r[3])
{
    if ((type == 27 || type == 37) && k >= 13) {
        double apex[3] = {0.5, 0.5, 1}, c[5][3];
        for (int i = 0; i < 4; i++)
            tpk_cell_map_node(27, i, c[i]);
        memcpy(c[4], apex, sizeof apex);
        r[0] = r[1] = 0.5, r[2] = k == 18 ? 0.25 : 0; /* base centre, centroid */
        if (k >= 14 && k < 18) /* a side's centre: the mean of its corners */
            for (int i = 0; i < 3; i++)
                r[i] = (c[k - 14][i] + c[(k - 13) % 4][i] + c[4][i]) / 3;
        return;
    }
    if ((type == 24 || type == 71) && k >= 10) {
        memset(r, 0, 3 * sizeof *r);
        for (int e = 0; e < 3 && k < 14; e++) {
            double m[3];
            tpk_cell_map_node(24, tet_face_nodes[k - 10][e], m);
            for (int i = 0; i < 3; i++)
                r[i] += m[i] / 3;
        }
        if (k == 14)
            r[0] = r[1] = r[2] = 0.25;
        return;
    }
    tpk_cell_map_node(full_type(type == 71 ? 24 : type == 37 ? 27 : type), k, r);
}

/* Orient a tetra piece positive on the parametric cell (exact in sign: coordinates are multiples of 1/12,
 * the pieces' volumes far from 0). */
static void orient_piece(int type, piece *p)
{
    double x[4][3];
    for (int v = 0; v < 4; v++)
        local_node(type, p->nodes[v], x[v]);
    double u[3], s[3], w[3];
    for (int k = 0; k < 3; k++)
        u[k] = x[1][k] - x[0][k], s[k] = x[2][k] - x[0][k], w[k] = x[3][k] - x[0][k];
    double det = u[0] * (s[1] * w[2] - s[2] * w[1]) - u[1] * (s[0] * w[2] - s[2] * w[0]) +
                 u[2] * (s[0] * w[1] - s[1] * w[0]);
    if (det < 0) {
        int t = p->nodes[2];
        p->nodes[2] = p->nodes[3];
        p->nodes[3] = t;
    }
}

/* ---- added points: face centres keyed by their corners ----------------------------------------- */

typedef struct face_key {
    int32_t ids[4]; /* sorted; ids[0] < 0: empty slot */
    int32_t point;
} face_key;

typedef struct face_map {
    face_key *slots;
    size_t mask;
} face_map;

static uint64_t key_hash(const int32_t *ids)
{
    uint64_t h = 1469598103934665603ull;
    for (int i = 0; i < 4; i++)
        h = (h ^ (uint32_t)ids[i]) * 1099511628211ull;
    return h ^ (h >> 29);
}

static void sort4(const int32_t *in, int32_t *out)
{
    memcpy(out, in, 4 * sizeof *out);
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && out[j - 1] > out[j]; j--) {
            int32_t t = out[j];
            out[j] = out[j - 1];
            out[j - 1] = t;
        }
}

/* The slot of a face's sorted corners: its entry, or the empty slot where it would go. */
static face_key *face_slot(face_map *m, const int32_t *sorted)
{
    for (size_t i = key_hash(sorted) & m->mask;; i = (i + 1) & m->mask) {
        face_key *k = &m->slots[i];
        if (k->ids[0] < 0 || !memcmp(k->ids, sorted, sizeof k->ids))
            return k;
    }
}

/* A quad face of the full lattice: its local corners and its centre's local node. */
typedef struct lattice_face {
    int corners[4], centre;
} lattice_face;

static int lattice_faces(int type, lattice_face *f)
{
    static const lattice_face hex[6] = {{{0, 3, 7, 4}, 20}, {{1, 2, 6, 5}, 21}, {{0, 1, 5, 4}, 22},
                                        {{3, 2, 6, 7}, 23}, {{0, 1, 2, 3}, 24}, {{4, 5, 6, 7}, 25}};
    static const lattice_face wedge[3] = {{{0, 1, 4, 3}, 15}, {{1, 2, 5, 4}, 16}, {{2, 0, 3, 5}, 17}};
    static const lattice_face base = {{0, 1, 2, 3}, 13};
    switch (type) {
    case 25:
    case 29:
    case 33: memcpy(f, hex, sizeof hex); return 6;
    case 26:
    case 32: memcpy(f, wedge, sizeof wedge); return 3;
    case 27:
    case 37: *f = base; return 1;
    default: return 0;
    }
}

/* What an added point is: its cell and its parametric coordinates there. */
typedef struct added_point {
    int64_t cell;
    double r[3];
} added_point;

typedef struct split_state {
    tpk_mesh *m;
    face_map faces;
    added_point *added;
    int64_t added_count, added_cap;
    int too_many; /* the added points would pass 2^31-1 points */
    piece *layout[2][LAGRANGE_MAX_ORDER + 1]; /* Lagrange tetra (0) and wedge (1) pieces by order, made once */
} split_state;

/* The pieces of an order-p Lagrange tetra or wedge (lagrange_layout), made on first use; NULL: out of
 * memory. */
static const piece *layout_of(split_state *s, int type, int p)
{
    piece **slot = &s->layout[type == 73][p];
    if (!*slot && (*slot = malloc(sizeof **slot * (size_t)lagrange_layout(type, p, NULL))) != NULL)
        lagrange_layout(type, p, *slot);
    return *slot;
}

/* Cell c's pieces from its layout into the new cells at k (advanced), its connectivity at `at`; an
 * octahedron cut along its shortest diagonal. Returns the new connectivity end. */
static int64_t emit_lagrange(const piece *lay, int count, int64_t c, const int32_t *nodes, const double *points,
                             uint8_t *types, int64_t *offsets, int32_t *conn, int32_t *source, int64_t *k, int64_t at)
{
    for (int i = 0; i < count; i++) {
        const piece *q = &lay[i];
        if (q->type == 0) {
            int best = 0;
            double best_len = 0;
            for (int d = 0; d < 3; d++) {
                const double *a = points + 3 * (int64_t)nodes[q->nodes[2 * d]];
                const double *b = points + 3 * (int64_t)nodes[q->nodes[2 * d + 1]];
                double len = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
                if (d == 0 || len < best_len)
                    best = d, best_len = len;
            }
            for (int t = 0; t < 4; t++) {
                const piece *tet = &lay[i + 1 + 4 * best + t];
                types[*k] = TPK_CELL_TETRA, source[*k] = (int32_t)c;
                for (int v = 0; v < 4; v++)
                    conn[at + v] = nodes[tet->nodes[v]];
                offsets[++*k] = at += 4;
            }
            i += 12;
            continue;
        }
        int corners = q->type == TPK_CELL_TETRA ? 4 : 6;
        types[*k] = (uint8_t)q->type, source[*k] = (int32_t)c;
        for (int v = 0; v < corners; v++)
            conn[at + v] = nodes[q->nodes[v]];
        offsets[++*k] = at += corners;
    }
    return at;
}

static int32_t add_point(split_state *s, int64_t cell, const double r[3])
{
    if (s->m->point_count + s->added_count >= INT32_MAX) {
        s->too_many = 1;
        return -1;
    }
    if (s->added_count == s->added_cap) {
        int64_t cap = s->added_cap ? 2 * s->added_cap : 1024;
        added_point *grown = realloc(s->added, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        s->added = grown, s->added_cap = cap;
    }
    s->added[s->added_count].cell = cell;
    memcpy(s->added[s->added_count].r, r, sizeof s->added[0].r);
    return (int32_t)(s->m->point_count + s->added_count++);
}

/* The map's slot of lattice face f of a cell with these nodes, keyed by its sorted corners; *fresh when
 * it was empty (its key is then set, its point left to the caller). */
static face_key *lattice_face_slot(split_state *s, const int32_t *nodes, const lattice_face *f, int *fresh)
{
    int32_t corner[4], sorted[4];
    for (int k = 0; k < 4; k++)
        corner[k] = nodes[f->corners[k]];
    sort4(corner, sorted);
    face_key *slot = face_slot(&s->faces, sorted);
    *fresh = slot->ids[0] < 0;
    if (*fresh)
        memcpy(slot->ids, sorted, sizeof sorted);
    return slot;
}

/* The global ids of cell c's full lattice into ids: its nodes, then the points it lacks (found or made). */
static int lattice_ids(split_state *s, int64_t c, int32_t *ids)
{
    const tpk_mesh *m = s->m;
    int type = m->cell_types[c], own = (int)(m->cell_offsets[c + 1] - m->cell_offsets[c]);
    const int32_t *nodes = m->cell_conn + m->cell_offsets[c];
    memcpy(ids, nodes, sizeof *ids * (size_t)own);
    if (type == 24 || type == 29 || type == 31 || type == 32 || type == 71 || type == 37 || (type == 27 && own == 14))
        return 0;
    lattice_face f[6];
    int nf = lattice_faces(type, f);
    for (int i = 0; i < nf; i++) {
        int fresh;
        face_key *slot = lattice_face_slot(s, nodes, &f[i], &fresh);
        if (fresh) {
            double r[3];
            local_node(type, f[i].centre, r);
            if ((slot->point = add_point(s, c, r)) < 0)
                return -1;
        }
        ids[f[i].centre] = slot->point;
    }
    if (type == 25 || type == 33) {
        double r[3] = {0.5, 0.5, 0.5};
        if ((ids[26] = add_point(s, c, r)) < 0)
            return -1;
    }
    return 0;
}

/* Face centre nodes that cells have (27-node hexahedra, 18-node wedges, 14-node pyramids) entered first,
 * so that a neighbour lacking one uses that node. */
static void enter_own_centres(split_state *s)
{
    const tpk_mesh *m = s->m;
    for (int64_t c = 0; c < m->cell_count; c++) {
        int type = m->cell_types[c];
        int64_t n = m->cell_offsets[c + 1] - m->cell_offsets[c];
        if (!((type == 29 || type == 32 || type == 33) && n == tpk_cell_map_nodes(type)) &&
            !((type == 27 || type == 37) && n == 14 + 5 * (type == 37)))
            continue;
        const int32_t *nodes = m->cell_conn + m->cell_offsets[c];
        lattice_face f[6];
        int nf = type == 33 ? 4 : lattice_faces(type, f); /* 33: its x and y faces' centres */
        if (type == 33)
            lattice_faces(29, f);
        for (int i = 0; i < nf; i++) {
            int fresh;
            face_key *slot = lattice_face_slot(s, nodes, &f[i], &fresh);
            if (fresh)
                slot->point = nodes[f[i].centre];
        }
    }
}

/* ---- the mesh rebuilt --------------------------------------------------------------------------- */

/* Points and point fields grown by the added points, placed and valued by their cells' functions. */
static int append_points(split_state *s)
{
    tpk_mesh *m = s->m;
    int64_t n0 = m->point_count, n = n0 + s->added_count;
    double *points = realloc(m->points, sizeof *points * 3 * (size_t)(n ? n : 1));
    if (!points)
        return -1;
    m->points = points;
    for (int64_t i = 0; i < s->added_count; i++) {
        const added_point *a = &s->added[i];
        tpk_cell_map_point(m->cell_types[a->cell], m->cell_conn + m->cell_offsets[a->cell], m->points, a->r,
                           m->points + 3 * (n0 + i));
    }
    for (int f = 0; f < m->field_count; f++) {
        tpk_src_field *field = &m->fields[f];
        if (field->association != TPK_ASSOC_POINT)
            continue;
        int nc = field->components;
        size_t total = (size_t)(n * nc) * (size_t)field->step_count;
        float *values = malloc(sizeof *values * (total ? total : 1));
        if (!values)
            return -1;
        for (int st = 0; st < field->step_count; st++) {
            const float *from = field->values + (size_t)st * (size_t)(n0 * nc);
            float *to = values + (size_t)st * (size_t)(n * nc);
            memcpy(to, from, sizeof *to * (size_t)(n0 * nc));
            for (int64_t i = 0; i < s->added_count; i++) {
                const added_point *a = &s->added[i];
                double w[TPK_CELL_MAP_MAX_NODES];
                int count = tpk_cell_map_weights(m->cell_types[a->cell], a->r, w);
                const int32_t *nodes = m->cell_conn + m->cell_offsets[a->cell];
                for (int comp = 0; comp < nc; comp++) {
                    double v = 0;
                    for (int k = 0; k < count; k++)
                        if (w[k] != 0)
                            v += w[k] * from[(int64_t)nodes[k] * nc + comp];
                    to[(n0 + i) * nc + comp] = (float)v;
                }
            }
        }
        free(field->values);
        field->values = values;
    }
    m->point_count = n;
    return 0;
}

/* Cell fields copied to every piece of their cell. */
static int spread_cell_fields(tpk_mesh *m, const int32_t *cell_source, int64_t cells)
{
    for (int f = 0; f < m->field_count; f++) {
        tpk_src_field *field = &m->fields[f];
        if (field->association == TPK_ASSOC_POINT)
            continue;
        int nc = field->components;
        size_t total = (size_t)(cells * nc) * (size_t)field->step_count;
        float *values = malloc(sizeof *values * (total ? total : 1));
        if (!values)
            return -1;
        for (int st = 0; st < field->step_count; st++) {
            const float *from = field->values + (size_t)st * (size_t)(m->cell_count * nc);
            float *to = values + (size_t)st * (size_t)(cells * nc);
            for (int64_t c = 0; c < cells; c++)
                memcpy(to + c * nc, from + (int64_t)cell_source[c] * nc, sizeof *to * (size_t)nc);
        }
        free(field->values);
        field->values = values;
    }
    return 0;
}

/* Polyhedra keep their face streams; the pieces of split cells have none. */
static int move_face_streams(tpk_mesh *m, const int32_t *cell_source, int64_t cells)
{
    if (!m->face_offsets)
        return 0;
    int64_t *offsets = malloc(sizeof *offsets * (size_t)(cells + 1));
    if (!offsets)
        return -1;
    offsets[0] = 0;
    for (int64_t c = 0; c < cells; c++) {
        int32_t from = cell_source[c];
        int64_t n = m->cell_offsets[from + 1] - m->cell_offsets[from];
        int whole = !fixed_split(m->cell_types[from], n) && !lagrange_order(m->cell_types[from], n);
        int64_t begin = m->face_offsets[from], end = m->face_offsets[from + 1];
        /* the stream stays where it is: a cell's range, or an empty one at the same place */
        offsets[c] = whole ? begin : end;
        offsets[c + 1] = end;
    }
    free(m->face_offsets);
    m->face_offsets = offsets;
    return 0;
}

static int fail_nodes(tpk_diag *diag, int64_t c, int type, int64_t got)
{
    const tpk_cell_type_info *t = tpk_cell_type(type);
    return tpk_diag_fail(diag, "cell %lld is a %s with %lld nodes; a %s has %d", (long long)c, t->name, (long long)got,
                         t->name, t->nodes);
}

/* VTK's Lagrange tetra, hexahedron and wedge of order 2 (10, 27 and 18 nodes) number their nodes as the
 * quadratic tetra, triquadratic hexahedron and biquadratic-quadratic wedge do (VTK 9's numbering, the
 * one vtkHigherOrderHexahedron documents; files from VTK 8 list two vertical mid-edges of a hexahedron
 * the other way, which the split then finds inverted): split as those. */
static void lagrange_as_quadratic(tpk_mesh *m)
{
    for (int64_t c = 0; c < m->cell_count; c++) {
        int type = m->cell_types[c];
        int64_t n = m->cell_offsets[c + 1] - m->cell_offsets[c];
        if ((type == 71 && n == 10) || (type == 72 && n == 27) || (type == 73 && n == 18))
            m->cell_types[c] = (uint8_t)(type == 71 ? 24 : type == 72 ? 29 : 32);
    }
}

int tpk_split_higher_order(tpk_mesh *m, const char *name, tpk_higher_split *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    lagrange_as_quadratic(m);
    out->source_points = m->point_count, out->source_cells = m->cell_count;
    int64_t cells = 0, conn = 0, keyed = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        int type = m->cell_types[c];
        int64_t n = m->cell_offsets[c + 1] - m->cell_offsets[c];
        int order = lagrange_order(type, n);
        if (order) {
            int64_t piece_conn;
            cells += lagrange_cells(type, order, &piece_conn), conn += piece_conn;
            out->split_cells++;
            continue;
        }
        if (!fixed_split(type, n)) {
            cells++, conn += n;
            continue;
        }
        if (!fixed_nodes_ok(type, n))
            return fail_nodes(diag, c, type, n);
        piece p[24];
        int np = pieces_of(type, n, m->cell_conn + m->cell_offsets[c], m->points, p);
        cells += np;
        for (int i = 0; i < np; i++)
            conn += tpk_cell_type(p[i].type)->nodes;
        keyed += type == 27 || type == 37 ? 1 : type == 26 || type == 32 ? 3 : type == 25 || type == 29 || type == 33 ? 6 : 0;
        out->split_cells++;
    }
    if (out->split_cells == 0) {
        out->reduced_cells = tpk_reduce_higher_order(m, name, diag);
        return 0;
    }
    if (cells > INT32_MAX || conn > INT32_MAX)
        return tpk_diag_fail(diag, "%lld cells after splitting the higher-order cells exceed the limit of 2^31-1",
                             (long long)cells);
    split_state s = {m, {NULL, 0}, NULL, 0, 0, 0, {{NULL}}};
    size_t cap = 64;
    while (cap < 2 * (size_t)keyed)
        cap *= 2;
    s.faces.slots = malloc(sizeof *s.faces.slots * cap);
    s.faces.mask = cap - 1;
    uint8_t *types = malloc((size_t)cells);
    int64_t *offsets = malloc(sizeof *offsets * (size_t)(cells + 1));
    int32_t *cconn = malloc(sizeof *cconn * (size_t)(conn ? conn : 1));
    int32_t *source = malloc(sizeof *source * (size_t)cells);
    int rc = -1;
    if (!s.faces.slots || !types || !offsets || !cconn || !source)
        goto fail;
    for (size_t i = 0; i < cap; i++)
        s.faces.slots[i].ids[0] = -1;
    enter_own_centres(&s);
    int64_t k = 0, at = 0;
    offsets[0] = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        int type = m->cell_types[c];
        const int32_t *nodes = m->cell_conn + m->cell_offsets[c];
        int64_t n = m->cell_offsets[c + 1] - m->cell_offsets[c];
        int order = lagrange_order(type, n);
        if (order && type != 72) { /* every node present: the cells of the node lattice */
            const piece *lay = layout_of(&s, type, order);
            if (!lay)
                goto fail;
            at = emit_lagrange(lay, lagrange_layout(type, order, NULL), c, nodes, m->points, types, offsets, cconn,
                               source, &k, at);
            continue;
        }
        for (int a = 0; a < order; a++) /* every node present: sub-hexahedra of the node lattice */
            for (int b = 0; b < order; b++)
                for (int d = 0; d < order; d++) {
                    int32_t local[8];
                    lagrange_hex_piece(order, a, b, d, local);
                    types[k] = TPK_CELL_HEXAHEDRON, source[k] = (int32_t)c;
                    for (int v = 0; v < 8; v++)
                        cconn[at + v] = nodes[local[v]];
                    offsets[++k] = at += 8;
                }
        if (order)
            continue;
        if (!fixed_split(type, n)) {
            types[k] = (uint8_t)type, source[k] = (int32_t)c;
            memcpy(cconn + at, nodes, sizeof *cconn * (size_t)n);
            offsets[++k] = at += n;
            continue;
        }
        int32_t ids[TPK_CELL_MAP_MAX_NODES];
        piece p[24];
        if (lattice_ids(&s, c, ids))
            goto fail;
        int np = pieces_of(type, n, nodes, m->points, p);
        for (int i = 0; i < np; i++) {
            if (p[i].type == TPK_CELL_TETRA)
                orient_piece(type, &p[i]);
            int corners = tpk_cell_type(p[i].type)->nodes;
            types[k] = (uint8_t)p[i].type, source[k] = (int32_t)c;
            for (int v = 0; v < corners; v++)
                cconn[at + v] = ids[p[i].nodes[v]];
            offsets[++k] = at += corners;
        }
    }
    /* Added points are valued from the cells as they were: place them before the cells are replaced. */
    if (append_points(&s) || spread_cell_fields(m, source, cells) || move_face_streams(m, source, cells))
        goto fail;
    out->added_points = s.added_count;
    free(m->cell_types), free(m->cell_offsets), free(m->cell_conn);
    m->cell_types = types, m->cell_offsets = offsets, m->cell_conn = cconn;
    m->cell_count = cells;
    types = NULL, offsets = NULL, cconn = NULL;
    free(m->global_point_ids), free(m->global_cell_ids);
    m->global_point_ids = NULL, m->global_cell_ids = NULL;
    out->cell_source = source;
    source = NULL;
    out->reduced_cells = tpk_reduce_higher_order(m, name, diag);
    rc = 0;
fail:
    if (rc && s.too_many)
        tpk_diag_fail(diag, "splitting %lld higher-order cells adds points past the limit of 2^31-1 per file; split "
                      "the mesh into parts", (long long)out->split_cells);
    else if (rc)
        tpk_diag_fail(diag, "out of memory splitting %lld higher-order cells", (long long)out->split_cells);
    free(s.faces.slots), free(s.added), free(types), free(offsets), free(cconn), free(source);
    for (int i = 0; i < 2; i++)
        for (int p = 0; p <= LAGRANGE_MAX_ORDER; p++)
            free(s.layout[i][p]);
    return rc;
}
