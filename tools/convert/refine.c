/* convert --max-error (refine.h): per tet, the Bernstein bound of its source cell's map and interpolant
 * against the tet's own linear ones, on the tet's corners' parametric points in the cell; tets over the
 * bound get their longest edge marked, the marks closed (a tet with a marked edge marks its longest), then
 * every tet bisects its greatest marked edge, round after round, until none is left (docs/ARCHITECTURE.md
 * §5). The greatest edge is by a global order (squared length from the two vertices taken in id order,
 * then the ids), so a face shared by two tets is cut alike from both sides. */
#include "refine.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "base/predicates.h"
#include "mesh/bernstein.h"
#include "mesh/cell_map.h"
#include "mesh/cell_types.h"
#include "tetpack_format.h"

#define MAX_PASSES 60
static const int tet_edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/* ---- source cells ------------------------------------------------------------------------------ */

int tpk_refine_cells_copy(const tpk_mesh *mesh, tpk_refine_cells *out)
{
    memset(out, 0, sizeof *out);
    int64_t n = mesh->cell_count, conn = n ? mesh->cell_offsets[n] : 0;
    out->types = malloc((size_t)(n ? n : 1));
    out->offsets = malloc(sizeof *out->offsets * (size_t)(n + 1));
    out->conn = malloc(sizeof *out->conn * (size_t)(conn ? conn : 1));
    if (!out->types || !out->offsets || !out->conn) {
        tpk_refine_cells_free(out);
        return -1;
    }
    out->cell_count = n;
    if (n)
        memcpy(out->types, mesh->cell_types, (size_t)n);
    memcpy(out->offsets, mesh->cell_offsets, sizeof *out->offsets * (size_t)(n + 1));
    if (conn)
        memcpy(out->conn, mesh->cell_conn, sizeof *out->conn * (size_t)conn);
    return 0;
}

void tpk_refine_cells_free(tpk_refine_cells *cells)
{
    free(cells->types), free(cells->offsets), free(cells->conn);
    memset(cells, 0, sizeof *cells);
}

/* The type whose functions cell c has (tpk_cell_map_source_type) when they are polynomials, or 0. */
static int mapped_type(const tpk_refine_cells *cells, int64_t c)
{
    int type = tpk_cell_map_source_type(cells->types[c], cells->offsets[c + 1] - cells->offsets[c]);
    return type && tpk_cell_map_degree(type) > 0 ? type : 0;
}

int64_t tpk_refine_unbounded_cell(const tpk_refine_cells *cells)
{
    for (int64_t c = 0; c < cells->cell_count; c++) {
        const tpk_cell_type_info *t = tpk_cell_type(cells->types[c]);
        if ((!t || t->dim == 3) && !mapped_type(cells, c))
            return c;
    }
    return -1;
}

/* ---- edges: marks and midpoints, keyed by the vertex pair --------------------------------------- */

typedef struct edge_table {
    uint64_t *keys; /* 0: empty (a key has b > a >= 0, so never 0) */
    int32_t *values;
    int64_t cap, count;
} edge_table;

static uint64_t edge_key(int32_t a, int32_t b)
{
    return a < b ? (uint64_t)a << 32 | (uint32_t)b : (uint64_t)b << 32 | (uint32_t)a;
}

static int64_t edge_slot(const edge_table *e, uint64_t key)
{
    uint64_t mask = (uint64_t)e->cap - 1, i = (key * 0x9E3779B97F4A7C15ull >> 20) & mask;
    while (e->keys[i] && e->keys[i] != key)
        i = (i + 1) & mask;
    return (int64_t)i;
}

static int edge_find(const edge_table *e, uint64_t key, int32_t *value)
{
    if (!e->cap)
        return 0;
    int64_t i = edge_slot(e, key);
    if (!e->keys[i])
        return 0;
    if (value)
        *value = e->values[i];
    return 1;
}

static int edge_put(edge_table *e, uint64_t key, int32_t value)
{
    if (2 * (e->count + 1) > e->cap) {
        edge_table grown = {calloc((size_t)(e->cap ? 2 * e->cap : 1024), sizeof *grown.keys),
                            malloc(sizeof *grown.values * (size_t)(e->cap ? 2 * e->cap : 1024)), e->cap ? 2 * e->cap : 1024,
                            0};
        if (!grown.keys || !grown.values) {
            free(grown.keys), free(grown.values);
            return -1;
        }
        for (int64_t i = 0; i < e->cap; i++)
            if (e->keys[i]) {
                int64_t j = edge_slot(&grown, e->keys[i]);
                grown.keys[j] = e->keys[i], grown.values[j] = e->values[i], grown.count++;
            }
        free(e->keys), free(e->values);
        *e = grown;
    }
    int64_t i = edge_slot(e, key);
    if (!e->keys[i])
        e->count++;
    e->keys[i] = key, e->values[i] = value;
    return 0;
}

static void edge_clear(edge_table *e)
{
    if (e->cap)
        memset(e->keys, 0, sizeof *e->keys * (size_t)e->cap);
    e->count = 0;
}

/* The tets by vertex, for the tets around a marked edge: a list per vertex linked through the tets'
 * corners, in no particular order. Made by one reading of the tets in the first pass; after that, where
 * few tets are cut (under 1 in 32), the tets about to be cut are taken out of their corners' lists (while
 * their corners are still those the lists went through), and the tets cut and their pieces put in after;
 * else the lists are made again in the next pass (t5 at order 2 cuts 14% of its tets first, and taking
 * them out walks more than making the lists does). The first pass of a million
 * hexahedra's tets visits the edges at some 2,000 of 180,000 vertices: counting every tet by vertex, then
 * scattering them into lists (CSR), took about three times as long as linking them, and its lists had to
 * be kept by the tets changed since, with a second index of those. */
typedef struct vertex_tets {
    int64_t vertices;              /* the vertices with a list (head); 0: to be made again */
    int64_t vertex_cap, corner_cap;
    int32_t *head;                 /* per vertex: an entry of a tet at it, -1: none */
    int32_t *next;                 /* per tet corner (4 t + k): the entry of another tet at that corner's vertex, -1: none */
    /* an entry names a tet's corner, 4 t + k, so a walk goes from entry to next entry without reading the
     * tet for the corner that is the vertex (one load a step, not two that wait on each other: the
     * closure's walks took half its time); lists made while 4 t + 3 might not fit an int32 (over 2^29
     * tets) name the tet alone, t, and a walk finds the corner in the tet (shift 0) */
    int shift;                     /* entries 4 t + k (2) or t (0) */
} vertex_tets;

/* The place in `next` of entry e, a tet at vertex v. */
static int64_t link_at(const vertex_tets *vt, const int32_t *tets, int32_t e, int32_t v)
{
    if (vt->shift)
        return e;
    int k = 0;
    while (tets[4 * (int64_t)e + k] != v)
        k++;
    return 4 * (int64_t)e + k;
}

/* ---- the state --------------------------------------------------------------------------------- */

typedef struct refine {
    tpk_tetmesh *m;
    const tpk_refine_cells *cells;
    const tpk_refine_options *o;
    tpk_diag *diag;
    int threads;
    int32_t *cell_type;    /* per source cell: mapped_type, found once */
    int32_t *vertex_of;    /* source point id -> vertex */
    int64_t point_ids;     /* size of vertex_of */
    int64_t n0;            /* vertices given; those after are added, their values in `added` */
    int slots;             /* point (field, step) pairs */
    float **slot_values;   /* per slot: the given vertices' values */
    int *slot_field;
    float *added;          /* per added vertex, `slots` values */
    int64_t added_cap, vertex_cap;
    int bounded;           /* slots bounded: bound_slot[0 .. bounded) */
    int *bound_slot;
    double *bound_range;
    double *slot_allowed;  /* per slot: the largest error --max-error allows it (its range times E), else inf */
    double diag_length;
    int64_t count, cap;    /* tets */
    int64_t tets_given;
    int32_t *tets, *cell;
    /* the tets' corners' parametric points in their cells, 12 numbers an entry (xi_read), entries given
     * out in the order tets first need them: a tet whose corners are nodes needs none until it is cut
     * (ensure_xi_all), and the tets cut are scattered over the tets, so entries by tet number would touch
     * most pages for a few tets each (bench/README). An entry holds float32 numbers where each is one
     * exactly (the nodes' points of the linear and quadratic cells, 0, 1/2, 1 or -1, and their midpoints
     * down to some 20 bisections): half the fresh memory of doubles, which the cut tets' pieces fault in
     * (gmsh's t5 at order 2, 1%: 1,100 of the refinement's 3,000 pages). Otherwise its first number is a
     * NaN and the doubles are in xi_wide, at the same entry (made when first needed, xi_widen). */
    float *xi;
    double *xi_wide;
    int64_t xi_count, xi_cap;
    int32_t *xi_at;        /* per tet: its entry; -1: its corners are nodes, their points not written yet */
    int64_t *root;         /* the given tet each comes from, for cell fields (NULL: the mesh has none) */
    double *field_error, *geometry_error;
    int *worst_slot;
    tpk_bernstein table[TPK_BERNSTEIN_MAX_DEGREE + 1]; /* made for the degrees the cells have */
    double *inverse_t[TPK_BERNSTEIN_MAX_DEGREE + 1];  /* their inverses transposed */
    edge_table marks;      /* this pass's marked edges: their midpoint vertex once made, else -1 */
    edge_table mids;       /* --subdivide: the edges cut at this level, their midpoint vertex */
    struct coef_cache *cache; /* per worker */
    int report_fields;     /* fields bounded (not constant) */
    int64_t *todo, todo_count; /* tets whose bound is not known yet (new or cut since) */
    /* 1: the tets to bound are every tet, 0 .. todo_count (todo_tet), and todo is not written: a list of
     * every tet of the first pass would fault in 8 bytes a tet (a million hexahedra's tets: 2,000 pages) */
    int todo_every;
    uint8_t *marked;       /* per tet: which of its 6 edges (tet_edges) are marked this pass */
    /* per tet: BOUND_ROUGH bounded by rough_bound, BOUND_OVER its criterion over the bound (the criterion
     * is only compared: a bit, not 8 bytes a tet to fault in) */
    uint8_t *bound_flags;
    /* for the hexahedron (NULL when no cell is one), per set of 4 nodes (bits in node order), per
     * monomial of tpk_cell_map_nonlinear: the Bernstein bound of the monomial less its linear interpolant
     * on the tet of those 4 nodes' parametric points; -1 for sets of other sizes and flat tets */
    double *departure;
    /* the quadratic tetra's monomials at the differences of its nodes' parametric points (node_pairs[j][l]:
     * at r_j - r_l, by tpk_cell_map_quadratic_tet), for bound_quadratic on tets whose corners are nodes */
    double node_pairs[10][10][6];
    /* of those, the monomials not 0 (most are: a difference of two nodes has 1 to 3 coordinates), in
     * order: node_terms[j][l] of them, node_term[j][l][i] the i-th's index */
    uint8_t node_terms[10][10], node_term[10][10][6];
    int exact;             /* bound_tet: every tet through its Bernstein coefficients */
    /* 1: place_corners took every corner for a node of its cell without looking (every vertex is a source
     * point): the first bound checks it (bound_tet, cache->missed), else place_corners looks after all */
    int corners_unchecked;
    vertex_tets by_vertex; /* the tets by vertex (refine_pass) */
} refine;

enum { BOUND_ROUGH = 1, BOUND_OVER = 2 };

/* The i-th tet to bound. */
static int64_t todo_tet(const refine *r, int64_t i)
{
    return r->todo_every ? i : r->todo[i];
}

/* Tet t's entry of parametric points (xi_at[t] >= 0) as doubles: in buf, or where xi_wide holds them. */
static const double *xi_read(const refine *r, int64_t t, double *buf)
{
    const float *f = r->xi + 12 * (int64_t)r->xi_at[t];
    if (isnan(f[0]))
        return r->xi_wide + 12 * (int64_t)r->xi_at[t];
    for (int k = 0; k < 12; k++)
        buf[k] = f[k];
    return buf;
}

/* Whether n numbers are each a float32 exactly. */
static int xi_fits(const double *x, int n)
{
    int fits = 1;
    for (int k = 0; k < n; k++)
        fits &= (double)(float)x[k] == x[k];
    return fits;
}

/* Entry e set to the 12 numbers x: as float32 when they fit, else (xi_wide made) as doubles; -1 with
 * nothing written when they do not fit and xi_wide is not made. */
static int xi_write(refine *r, int64_t e, const double *x)
{
    float *f = r->xi + 12 * e;
    if (xi_fits(x, 12)) {
        for (int k = 0; k < 12; k++)
            f[k] = (float)x[k];
        return 0;
    }
    if (!r->xi_wide)
        return -1;
    f[0] = NAN;
    memcpy(r->xi_wide + 12 * e, x, 12 * sizeof *x);
    return 0;
}

/* realloc: a large block grows in place or is moved by its pages, neither copied nor touched afresh */
static int grow(void **array, size_t item, int64_t cap)
{
    void *grown = realloc(*array, item * (size_t)cap);
    if (!grown)
        return -1;
    *array = grown;
    return 0;
}

/* Room for `more` entries of parametric points. */
static int reserve_xi(refine *r, int64_t more)
{
    if (r->xi_count + more <= r->xi_cap)
        return 0;
    int64_t cap = r->xi_count + more + (r->xi_count + more) / 2 + 1024;
    if (grow((void **)&r->xi, 12 * sizeof *r->xi, cap) != 0 ||
        (r->xi_wide && grow((void **)&r->xi_wide, 12 * sizeof *r->xi_wide, cap) != 0))
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    r->xi_cap = cap;
    return 0;
}

/* xi_wide made, for entries whose numbers are not all float32 (its pages are touched by those alone). */
static int xi_widen(refine *r)
{
    if (!r->xi_wide && !(r->xi_wide = malloc(12 * sizeof *r->xi_wide * (size_t)(r->xi_cap ? r->xi_cap : 1))))
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    return 0;
}

static float value_of(const refine *r, int32_t v, int slot)
{
    return v < r->n0 ? r->slot_values[slot][v] : r->added[(int64_t)(v - r->n0) * r->slots + slot];
}

static const double *point_of(const refine *r, int32_t v)
{
    return r->m->points + 3 * (int64_t)v;
}

/* Cell c's type (mapped_type) and its nodes as vertices; 0 when some node is no vertex. */
static int cell_nodes(const refine *r, int64_t c, int32_t *verts)
{
    int type = r->cell_type[c];
    int n = type ? (int)(r->cells->offsets[c + 1] - r->cells->offsets[c]) : 0; /* mapped_type: nodes(type) */
    const int32_t *conn = r->cells->conn + r->cells->offsets[c];
    int voxel = r->cells->types[c] == TPK_CELL_VOXEL; /* the one type whose nodes are in another order */
    for (int k = 0; k < n; k++) {
        int32_t id = conn[voxel ? tpk_cell_map_source_node(TPK_CELL_VOXEL, k) : k];
        if (id < 0 || id >= r->point_ids || r->vertex_of[id] < 0)
            return 0;
        verts[k] = r->vertex_of[id];
    }
    for (int k = n; k < 16; k++) /* for node_indices, which reads 16 */
        verts[k] = -1;
    return type;
}

static void map_point(const refine *r, int type, const int32_t *verts, const double xi[3], double *w, double x[3])
{
    int n = tpk_cell_map_weights(type, xi, w);
    x[0] = x[1] = x[2] = 0;
    for (int k = 0; k < n; k++)
        for (int i = 0; i < 3; i++)
            x[i] += w[k] * point_of(r, verts[k])[i];
}

static double interpolate(const refine *r, int n, const int32_t *verts, const double *w, int slot)
{
    double s = 0;
    for (int k = 0; k < n; k++)
        s += w[k] * value_of(r, verts[k], slot);
    return s;
}

static double dist2(const double *a, const double *b)
{
    return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

/* Tet t's greatest edge among those of `edges` (bits by tet_edges), as 0..5, or -1, in the global edge
 * order: squared length (from the two points in id order, so alike from every tet), then the smaller id,
 * then the larger. */
static int greatest_edge(const refine *r, int64_t t, unsigned edges)
{
    const int32_t *v = r->tets + 4 * t;
    int best = -1;
    int32_t best_lo = 0, best_hi = 0;
    double best_length = 0;
    for (int e = 0; e < 6; e++) {
        if (!(edges >> e & 1))
            continue;
        int32_t a = v[tet_edges[e][0]], b = v[tet_edges[e][1]], lo = a < b ? a : b, hi = a < b ? b : a;
        double length = dist2(point_of(r, hi), point_of(r, lo));
        if (best < 0 || (length != best_length ? length > best_length : lo != best_lo ? lo > best_lo : hi > best_hi))
            best = e, best_lo = lo, best_hi = hi, best_length = length;
    }
    return best;
}

/* ---- parametric points of the given tets' corners ------------------------------------------------ */

static void shape_centre(int type, double xi[3])
{
    const tpk_cell_type_info *t = tpk_cell_type(type);
    int linear = t ? t->linear_type : type;
    xi[0] = xi[1] = xi[2] = linear == TPK_CELL_TETRA ? 0.25 : 0.5;
    if (linear == TPK_CELL_WEDGE)
        xi[0] = xi[1] = 1.0 / 3;
}

static int solve3(double m[3][3], const double b[3], double x[3])
{
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(fabs(det) > 0))
        return -1;
    for (int c = 0; c < 3; c++) {
        double q[3][3];
        memcpy(q, m, sizeof q);
        for (int k = 0; k < 3; k++)
            q[k][c] = b[k];
        x[c] = (q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
                q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0])) / det;
    }
    return 0;
}

/* Newton's method from the cell's centre for the parametric point that the cell maps onto `target`. */
static int invert_map(const refine *r, int type, const int32_t *verts, const double target[3], double xi[3])
{
    double w[TPK_CELL_MAP_MAX_NODES], x[3], lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    int n = tpk_cell_map_nodes(type);
    for (int k = 0; k < n; k++)
        for (int i = 0; i < 3; i++)
            lo[i] = fmin(lo[i], point_of(r, verts[k])[i]), hi[i] = fmax(hi[i], point_of(r, verts[k])[i]);
    double size = sqrt(dist2(lo, hi)), h = 1e-6;
    shape_centre(type, xi);
    for (int it = 0; it < 60; it++) {
        map_point(r, type, verts, xi, w, x);
        double res[3] = {x[0] - target[0], x[1] - target[1], x[2] - target[2]};
        if (sqrt(res[0] * res[0] + res[1] * res[1] + res[2] * res[2]) <= 1e-10 * size)
            return 0;
        double jac[3][3], step[3];
        for (int j = 0; j < 3; j++) {
            double a[3], b[3], xa[3], xb[3];
            memcpy(a, xi, sizeof a), memcpy(b, xi, sizeof b);
            a[j] += h, b[j] -= h;
            map_point(r, type, verts, a, w, xa);
            map_point(r, type, verts, b, w, xb);
            for (int i = 0; i < 3; i++)
                jac[i][j] = (xa[i] - xb[i]) / (2 * h);
        }
        if (solve3(jac, res, step) != 0)
            return -1;
        for (int j = 0; j < 3; j++)
            xi[j] -= step[j];
    }
    return -1;
}

/* The nodes of `verts` (n of them) that are a tet's 4 corners (node[k]: corner k's, the first that is it,
 * -1: none); whether all 4 are. cell_nodes pads verts with -1 to 16: up to 16 nodes, the lanes are loaded
 * once for the 4 corners and compared at once, with no branch on where a corner is, which a predictor
 * cannot guess (a miss a corner, 4 a tet, 2 passes). */
static int node_indices(const int32_t *verts, int n, const int32_t *corner, int node[4])
{
    int all = 1;
    if (n > 16) {
        for (int k = 0; k < 4; k++) {
            node[k] = -1;
            for (int j = 0; j < n && node[k] < 0; j++)
                if (verts[j] == corner[k])
                    node[k] = j;
            all &= node[k] >= 0;
        }
        return all;
    }
    typedef int32_t lanes __attribute__((vector_size(4 * sizeof(int32_t))));
    const lanes bit = {1, 2, 4, 8};
    lanes a, b, c, d;
    memcpy(&a, verts, sizeof a), memcpy(&b, verts + 4, sizeof b);
    memcpy(&c, verts + 8, sizeof c), memcpy(&d, verts + 12, sizeof d);
    for (int k = 0; k < 4; k++) {
        const lanes at = {corner[k], corner[k], corner[k], corner[k]};
        lanes hit = ((a == at) & bit) | ((b == at) & (bit << 4)) | ((c == at) & (bit << 8)) | ((d == at) & (bit << 12));
        uint32_t found = (uint32_t)(hit[0] | hit[1] | hit[2] | hit[3]);
        node[k] = found ? __builtin_ctz(found) : -1;
        all &= found != 0;
    }
    return all;
}

/* Each given tet's corners in its cell's parameter space: nodes by their place in the cell, other points
 * (face and cell centres, Steiner points) by inverting the map. An added point then takes every point
 * field's value from the interpolant of the first cell (in tet order) that has it, so that its values
 * are those the bound measures against. */
/* The parametric points of type's nodes into nodes, unless *held says they are there already (a cell of
 * the same type came last: the cells are mostly alike). */
static void hold_node_points(int type, int *held, double (*nodes)[3])
{
    if (type == *held)
        return;
    for (int j = 0, n = tpk_cell_map_nodes(type); j < n; j++)
        tpk_cell_map_node(type, j, nodes[j]);
    *held = type;
}

typedef struct corner_job {
    refine *r;
    uint8_t *failed; /* per tet: 1 a node is no vertex, 2 the map does not invert */
    int write;       /* 0: mark the tets whose corners are not all nodes (xi_at -2); 1: write their points */
} corner_job;

static void corner_range(void *ctx, int64_t begin, int64_t end, int w)
{
    corner_job *job = ctx;
    refine *r = job->r;
    int32_t verts[TPK_CELL_MAP_MAX_NODES];
    int nodes_of = 0; /* the type whose nodes' parametric points `nodes` holds (the cells are mostly alike) */
    double nodes[TPK_CELL_MAP_MAX_NODES][3];
    int64_t verts_of = -1; /* the cell whose nodes `verts` holds (a cell's tets are together) */
    int type = 0;
    (void)w;
    for (int64_t t = begin; t < end; t++) {
        int64_t c = r->cell[t];
        if (c != verts_of || !type)
            type = c >= 0 && c < r->cells->cell_count ? cell_nodes(r, c, verts) : 0, verts_of = c;
        if (!type) {
            job->failed[t] = 1, r->xi_at[t] = -1;
            continue;
        }
        int n = tpk_cell_map_nodes(type);
        hold_node_points(type, &nodes_of, nodes);
        if (job->write && r->xi_at[t] < 0)
            continue;
        int node[4], all = node_indices(verts, n, r->tets + 4 * t, node);
        /* corners that are all nodes: their points are those of the nodes, written when first needed (most
         * such tets are never cut and never need them: 96 bytes a tet of fresh memory spared) */
        if (!job->write) {
            r->xi_at[t] = all ? -1 : -2;
            continue;
        }
        double xi[12] = {0};
        for (int k = 0; k < 4; k++) {
            if (node[k] >= 0)
                memcpy(xi + 3 * k, nodes[node[k]], sizeof nodes[node[k]]);
            else if (invert_map(r, type, verts, point_of(r, r->tets[4 * t + k]), xi + 3 * k) != 0)
                job->failed[t] = 2;
        }
        xi_write(r, r->xi_at[t], xi); /* xi_wide made (place_corners) */
    }
}

/* Tet t's corners' parametric points, when corner_range left them for later, into xi (12 numbers), from
 * its cell's type and nodes as vertices (cell_nodes) and those nodes' parametric points
 * (hold_node_points). */
static void xi_of_nodes(const refine *r, int64_t t, int type, const int32_t *verts, const double (*nodes)[3],
                        double *xi)
{
    int n = tpk_cell_map_nodes(type);
    int node[4];
    node_indices(verts, n, r->tets + 4 * t, node); /* found: corner_range found every corner */
    for (int k = 0; k < 4; k++)
        memcpy(xi + 3 * k, nodes[node[k]], sizeof nodes[node[k]]);
}

/* The listed tets' corners' parametric points written (xi_of_nodes) into the entries
 * ensure_xi_all gave them. */
static void ensure_xi_range(void *ctx, int64_t begin, int64_t end, int w)
{
    refine *r = ((void **)ctx)[0];
    const int64_t *tets = ((void **)ctx)[1];
    int32_t verts[TPK_CELL_MAP_MAX_NODES];
    int nodes_of = 0; /* the type whose nodes' parametric points `nodes` holds (the cells are mostly alike) */
    double nodes[TPK_CELL_MAP_MAX_NODES][3];
    int64_t verts_of = -1; /* the cell whose nodes `verts` holds (the tets listed in order: a cell's together) */
    int type = 0;
    (void)w;
    for (int64_t i = begin; i < end; i++) {
        int64_t t = tets[i];
        if (r->cell[t] != verts_of)
            type = cell_nodes(r, verts_of = r->cell[t], verts);
        hold_node_points(type, &nodes_of, nodes);
        double xi[12];
        xi_of_nodes(r, t, type, verts, (const double (*)[3])nodes, xi);
        xi_write(r, r->xi_at[t], xi); /* nodes' points that do not fit float32: xi_wide made (set_up) */
    }
}

/* Of the `count` tets listed (all tets 0 .. count when NULL), those without an entry of parametric points
 * given one, in list order, and their points written (ensure_xi_range), on all threads. */
static int ensure_xi_all(refine *r, const int64_t *tets, int64_t count)
{
    int64_t need = 0;
    for (int64_t i = 0; i < count; i++)
        need += r->xi_at[tets ? tets[i] : i] < 0;
    if (need == 0)
        return 0;
    int64_t *list = malloc(sizeof *list * (size_t)need);
    if (!list || reserve_xi(r, need) != 0) {
        free(list);
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    }
    need = 0;
    for (int64_t i = 0; i < count; i++) {
        int64_t t = tets ? tets[i] : i;
        if (r->xi_at[t] < 0)
            r->xi_at[t] = (int32_t)r->xi_count++, list[need++] = t;
    }
    void *ctx[2] = {r, list};
    tpk_parallel_for(need, tpk_threads_for(need, r->threads, 4096), ensure_xi_range, ctx);
    free(list);
    return 0;
}

/* A vertex added (by the refinement, or by the higher-order split: a 20-node hexahedron's face and body
 * centres) whose float32 value is farther from the interpolant than the bound allows its slot: every tet
 * that has it then misses the bound at that very point, however finely it is cut, so the refinement
 * stops there (float_floor_fail). */
typedef struct floor_hit {
    int32_t vertex; /* -1: none */
    int slot;
    double exact;   /* the interpolant's value at the vertex */
    float stored;
} floor_hit;

static int float_floor_fail(const refine *r, const floor_hit *h);

static int place_corners(refine *r, int threads, int unchecked)
{
    int added = 0; /* a vertex that is no source point: a corner no cell has as a node */
    for (int64_t v = 0; v < r->m->vertex_count && unchecked && !added; v++)
        added = r->m->vertex_source[v] < 0;
    if (unchecked && !added) { /* every corner a node, as a split makes them: what the pass below would
                                    * find; the first bound confirms it, tet by tet, as it finds the nodes */
        memset(r->xi_at, 0xff, sizeof *r->xi_at * (size_t)r->count);
        r->corners_unchecked = 1;
        return 0;
    }
    corner_job job = {r, calloc((size_t)(r->count ? r->count : 1), 1), 0};
    uint8_t *valued = calloc((size_t)(r->n0 ? r->n0 : 1), 1);
    if (!valued || !job.failed) {
        free(valued), free(job.failed);
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    }
    tpk_parallel_for(r->count, tpk_threads_for(r->count, threads, 1024), corner_range, &job);
    int64_t need = 0; /* the tets whose corners are not all nodes: entries in tet order, their points written */
    for (int64_t t = 0; t < r->count; t++)
        need += r->xi_at[t] == -2;
    /* the points found by inverting the map seldom fit float32: entries of doubles at hand */
    if ((need > 0 && xi_widen(r) != 0) || reserve_xi(r, need) != 0) {
        free(valued), free(job.failed);
        return -1;
    }
    for (int64_t t = 0; t < r->count; t++)
        if (r->xi_at[t] == -2)
            r->xi_at[t] = (int32_t)r->xi_count++;
    job.write = 1;
    if (need > 0)
        tpk_parallel_for(r->count, tpk_threads_for(r->count, threads, 1024), corner_range, &job);
    int32_t verts[TPK_CELL_MAP_MAX_NODES];
    double w[TPK_CELL_MAP_MAX_NODES];
    int rc = 0;
    floor_hit hit = {-1, 0, 0, 0}; /* the first point whose float32 value misses the bound, in tet order */
    for (int64_t t = 0; t < r->count && rc == 0; t++) {
        int64_t c = r->cell[t];
        if (job.failed[t] == 1) {
            rc = tpk_diag_fail(r->diag, "--max-error: cell %lld has a node that is no vertex of the tets", (long long)c);
        } else if (job.failed[t] == 2) {
            rc = tpk_diag_fail(r->diag, "--max-error: cell %lld (a %s): no parametric point maps onto a point added "
                               "inside it (the map does not invert there); convert it without --max-error",
                               (long long)c, tpk_cell_type(r->cells->types[c])->name);
        }
        if (rc == 0 && r->xi_at[t] < 0)
            continue; /* its corners are nodes: source points, valued already */
        for (int k = 0; rc == 0 && k < 4; k++) {
            int32_t v = r->tets[4 * t + k];
            if (r->m->vertex_source[v] >= 0 || valued[v])
                continue;
            valued[v] = 1;
            int type = cell_nodes(r, c, verts), n = tpk_cell_map_nodes(type);
            double buf[12];
            tpk_cell_map_weights(type, xi_read(r, t, buf) + 3 * k, w);
            for (int s = 0; s < r->slots; s++) {
                double exact = interpolate(r, n, verts, w, s);
                float stored = (float)exact;
                r->slot_values[s][v] = stored;
                if (hit.vertex < 0 && fabs((double)stored - exact) > r->slot_allowed[s])
                    hit = (floor_hit){v, s, exact, stored};
            }
        }
    }
    free(valued), free(job.failed);
    return rc == 0 && hit.vertex >= 0 ? float_floor_fail(r, &hit) : rc; /* as an added vertex's (place_vertex) */
}

/* ---- the bound --------------------------------------------------------------------------------- */

/* Gradients of the barycentric coordinates 1..3 of tet p; -1 when flat. by_inverse: multiplied by 1 / det
 * rather than divided by det (rough_bound: the gradient only carries the geometry's bound to the field's,
 * and the divisions cost). */
static int barycentric_gradients(const double p[4][3], double g[3][3], int by_inverse)
{
    double e[3][3];
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            e[k][i] = p[k + 1][i] - p[0][i];
    for (int k = 0; k < 3; k++) {
        const double *a = e[(k + 1) % 3], *b = e[(k + 2) % 3];
        g[k][0] = a[1] * b[2] - a[2] * b[1], g[k][1] = a[2] * b[0] - a[0] * b[2], g[k][2] = a[0] * b[1] - a[1] * b[0];
    }
    double det = e[0][0] * g[0][0] + e[0][1] * g[0][1] + e[0][2] * g[0][2];
    if (!(fabs(det) > 0))
        return -1;
    double inverse = by_inverse ? 1 / det : 0;
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            g[k][i] = by_inverse ? g[k][i] * inverse : g[k][i] / det;
    return 0;
}

/* Slot s's bound `gap` (a fraction of its range) on a tet with values v there: the larger of gap and the
 * tet's criterion, gap plus the gradient (g: barycentric_gradients) times the geometry's bound (flat:
 * gap alone), into *crit; the slot into *worst and *worst_slot when its gap is the largest yet. */
static void fold_slot(const refine *r, int s, double gap, const double v[4], const double g[3][3], int flat,
                      double geometry, double *worst, int *worst_slot, double *crit)
{
    double grad[3] = {0, 0, 0};
    for (int k = 0; k < 3 && !flat; k++)
        for (int j = 0; j < 3; j++)
            grad[j] += (v[k + 1] - v[0]) * g[k][j];
    double located = gap + sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]) * geometry /
                               r->bound_range[s];
    if (gap > *worst || *worst_slot < 0)
        *worst = gap, *worst_slot = s;
    double c = flat ? gap : located;
    *crit = c > *crit ? c : *crit;
}

/* Tet t's bounds: field_error (the largest over bounded slots, as a fraction of the range), geometry
 * error (a fraction of the diagonal), and the criterion refinement meets: the larger of the geometry
 * error and, per slot, the field's bound plus its gradient times the geometry's (a point located by
 * position rather than parameter, as check --against samples, then also stays within E). */
/* Per worker, the Bernstein coefficients of the cell's functions on the tets of parameter space met
 * lately, by node (by_node[k * m + i]: node k's share of coefficient i), keyed by the cell type and the
 * 4 parametric corners: a pure function of the key, so that a hit gives the very numbers a miss would.
 * The tets of a regular mesh's cells, and their pieces, repeat the same few parametric tets. */
typedef double pair __attribute__((vector_size(2 * sizeof(double)))); /* two numbers side by side */

/* Cells of degree above DIRECT_DEGREE (Lagrange tetra of order 7-10, hexahedra of order 3-4, wedges of
 * order 4-6) are bounded from their values at the tet's domain points through the inverse
 * (tpk_bernstein_gap: m^2 a component, m = 120 .. 455 domain points), not through cached coefficients of
 * every node's function (m^2 n per tet of parameter space: too much at these sizes, where the parametric
 * tets seldom repeat). The values carry the rounding of their sums, gamma_n sum_k |w_k| |x_k| (the
 * Lebesgue sum sum_k |w_k| measured at the points), and of the weights, each within WEIGHT_ERROR
 * (higher_order.lagrange_high_order_shape_functions checks them against a long double evaluation),
 * both through the inverse's norm. Cost a tet: about m (7 n + 3 m) multiply-adds for the map (its
 * weights included) and m (n + m) per field: 0.8M and 0.16M at m = n = 286 (tetra of order 10), 1.2M and
 * 0.3M at m = 455, n = 196 (wedge of order 6). */
#define DIRECT_DEGREE 6
#define WEIGHT_ERROR 1e-13

typedef struct coef_cache {
    int entries, size; /* a power of two; doubles per entry */
    int *type;         /* 0: empty */
    double *key, *norm, *by_node;
    double work[TPK_BERNSTEIN_MAX_POINTS * TPK_CELL_MAP_MAX_NODES];
    /* the cell of the tet bounded last (its tets come together): its nodes, their points and largest
     * coordinate, and the bounded slots' values at them, filled for slots 0 .. filled as they are met */
    int64_t cell;
    int cell_type, filled;
    int cell_degree, cell_node_count; /* tpk_cell_map_degree and _nodes of cell_type, found once a cell */
    int xi_type;                              /* the type whose nodes' parametric points xi_node holds */
    double xi_node[TPK_CELL_MAP_MAX_NODES][3]; /* for xi_of_nodes */
    int32_t verts[TPK_CELL_MAP_MAX_NODES];
    double node[TPK_CELL_MAP_MAX_NODES][3], largest;
    double *value, *big; /* per bounded slot: TPK_CELL_MAP_MAX_NODES values, their largest magnitude */
    uint8_t *finite;     /* per bounded slot: every value finite */
    /* the magnitudes of the cell's tpk_cell_map_nonlinear_coefficients, of its map (Euclidean) and per
     * bounded slot as filled (rough[s * TPK_CELL_MAP_MAX_NONLINEAR + q]); rough_count 0: none */
    int rough_count;
    double rough_geometry[TPK_CELL_MAP_MAX_NONLINEAR], *rough;
    /* the same coefficients with their signs, for form_minus_linear: the map's (form_geometry[q * 3 + c])
     * and per bounded slot as filled (form[s * TPK_CELL_MAP_MAX_NONLINEAR + q]) */
    double form_geometry[3 * TPK_CELL_MAP_MAX_NONLINEAR], *form;
    /* bound_quadratic: qc components (3 axes, the bounded slots, a multiple of 4), the cell they were
     * gathered for, its node values (10 nodes) and nonlinear coefficients (6), a tet's corner values (4)
     * and its coefficients' largest magnitudes (1), qc numbers each */
    int qc;
    int64_t quad_cell;
    double *quad_node, *quad_a, *quad_v, *quad_largest;
    /* quadratic_edges: per ordered pair of nodes (10 j + l), its edge coefficients (qc numbers), made
     * when the bit pair_made[p / 64] >> p % 64 is set */
    uint64_t pair_made[2];
    double *pair_coef;
    int missed; /* refine.corners_unchecked: a tet bounded here had a corner that is no node of its cell */
    /* bound_quadratic's tets waiting for fold_batch (batched of 4): each one's number, corners' points
     * (batch_p[corner][axis][tet]), criterion so far and geometry's bound; per bounded slot s, its gap
     * (batch_gap[4 s + tet]), whether it is bounded there (batch_ok: all finite, -1, else 0) and its values
     * at the corners (batch_value[16 s + 4 corner + tet]) */
    int batched;
    int64_t batch_tet[4];
    double batch_p[4][3][4], batch_crit[4], batch_geometry[4];
    double *batch_gap, *batch_value;
    long long *batch_ok;
} coef_cache;

static const double *coefficients(coef_cache *cc, const tpk_bernstein *b, const double *inverse_t, int type,
                                  int n, const double *xi, double *norm)
{
    uint64_t h = 1469598103934665603ull ^ (uint64_t)type;
    for (int i = 0; i < 12; i++) { /* the 12 numbers' bits, a word at a time */
        uint64_t bits;
        memcpy(&bits, xi + i, sizeof bits);
        h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
        h ^= h >> 29;
    }
    int e = (int)(h & (uint64_t)(cc->entries - 1)), m = b->points;
    double *by_node = cc->by_node + (int64_t)e * cc->size;
    if (cc->type[e] == type && !memcmp(cc->key + 12 * e, xi, 12 * sizeof *xi)) {
        *norm = cc->norm[e];
        return by_node;
    }
    double *weights = cc->work;
    for (int i = 0; i < m; i++) { /* the nodes' weights at the domain points */
        double at[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int j = 0; j < 3; j++)
                at[j] += b->lambda[i][k] * xi[3 * k + j];
        tpk_cell_map_weights(type, at, weights + i * n);
    }
    /* by_node = inverse x weights, node by node (the products and sums of tpk_bernstein_coefficients, in
     * its order), two domain points side by side through the transposed inverse */
    int even = m & ~1;
    for (int k = 0; k < n; k++) {
        double *out = by_node + k * m;
        for (int i = 0; i < even; i += 2) {
            pair acc = {0, 0}, a, w;
            for (int j = 0; j < m; j++) {
                memcpy(&a, inverse_t + j * m + i, sizeof a);
                w = (pair){weights[j * n + k], weights[j * n + k]};
                acc += a * w;
            }
            memcpy(out + i, &acc, sizeof acc);
        }
        for (int i = even; i < m; i++) {
            double acc = 0;
            for (int j = 0; j < m; j++)
                acc += inverse_t[j * m + i] * weights[j * n + k];
            out[i] = acc;
        }
    }
    double largest = 0; /* tpk_bernstein_coefficients' norm: the largest row sum of |coefficients| */
    for (int i = 0; i < m; i++) {
        double sum = 0;
        for (int k = 0; k < n; k++)
            sum += fabs(by_node[k * m + i]);
        largest = sum > largest ? sum : largest;
    }
    *norm = cc->norm[e] = largest;
    cc->type[e] = type;
    memcpy(cc->key + 12 * e, xi, 12 * sizeof *xi);
    return by_node;
}

/* The Bernstein coefficients of f - L for `axes` (1 or 3) components: out[c][i] = -sum_k corner[k][c]
 * lambda_k(i) + sum_k node[k * stride + c] by_node[k m + i], each summed in that order (k ascending), four
 * domain points side by side (the numbers are those of one at a time: no fused multiply-add, lanes
 * apart). Built twice, and the processor picks at load time: 256-bit AVX2 where it has it, else SSE2
 * pairs (the first bound of a million hexahedra's tets: 0.14 s in here on one core with pairs). */
typedef double quad __attribute__((vector_size(4 * sizeof(double))));
typedef long long quad_bits __attribute__((vector_size(4 * sizeof(long long)))); /* a quad's bits, masks */
__attribute__((target_clones("avx2", "default"))) static void
minus_linear(int m, int n, int axes, const tpk_bernstein *b, const double (*corner)[3], const double *node, int stride,
             const double *by_node, double (*out)[TPK_BERNSTEIN_MAX_POINTS])
{
    int quads = m & ~3;
    for (int c = 0; c < axes; c++) {
        for (int i = 0; i < quads; i += 4) {
            quad acc = {0, 0, 0, 0}, x, y;
            for (int k = 0; k < 4; k++) {
                memcpy(&y, b->lambda_by_corner[k] + i, sizeof y);
                x = (quad){corner[k][c], corner[k][c], corner[k][c], corner[k][c]};
                acc -= x * y;
            }
            for (int k = 0; k < n; k++) {
                memcpy(&y, by_node + k * m + i, sizeof y);
                double v = node[k * stride + c];
                x = (quad){v, v, v, v};
                acc += x * y;
            }
            memcpy(out[c] + i, &acc, sizeof acc);
        }
        for (int i = quads; i < m; i++) {
            double acc = 0;
            for (int k = 0; k < 4; k++)
                acc -= corner[k][c] * b->lambda_by_corner[k][i];
            for (int k = 0; k < n; k++)
                acc += node[k * stride + c] * by_node[k * m + i];
            out[c][i] = acc;
        }
    }
}

/* Slot s's values at the cell's nodes, their largest magnitude, whether all are finite, and the
 * magnitudes of their tpk_cell_map_nonlinear_coefficients, when first met (slots are met in order). */
static void fill_slot(const refine *r, coef_cache *cache, int s)
{
    if (s != cache->filled)
        return;
    int finite = 1, n = cache->cell_node_count;
    double big = 0, *value = cache->value + (int64_t)s * TPK_CELL_MAP_MAX_NODES;
    for (int k = 0; k < n; k++) {
        finite &= isfinite(value[k] = value_of(r, cache->verts[k], r->bound_slot[s]));
        big = fabs(value[k]) > big ? fabs(value[k]) : big;
    }
    cache->big[s] = big, cache->finite[s] = (uint8_t)finite, cache->filled++;
    double a[TPK_CELL_MAP_MAX_NONLINEAR];
    for (int q = 0, count = tpk_cell_map_nonlinear_coefficients(cache->cell_type, value, 1, a); q < count; q++) {
        cache->form[s * TPK_CELL_MAP_MAX_NONLINEAR + q] = a[q];
        cache->rough[s * TPK_CELL_MAP_MAX_NONLINEAR + q] = fabs(a[q]);
    }
}

/* The quadratic tetra's (24) Bernstein coefficients of f - L on a tet of its parameter space, in closed
 * form, for the map's 3 axes and every bounded slot at once (qc components, a multiple of 4: axes 0-2, slot
 * s at 3 + s, then zeros): f is quadratic, so they are f's blossom at the tet's corners less L's
 * (tpk_cell_map_quadratic_tet): d_k = f(r_k) - v_k at corner k, (d_k + d_l) / 2 - sum_q a_q m_q(r_k - r_l)
 * / 2 on edge (k, l). Of these 10 per component it returns the largest Euclidean norm of the axes' and
 * writes the largest magnitude of each component's into largest[c]. w, m: as tpk_cell_map_quadratic_tet;
 * node[j * qc + c]: node j's values; a[q * qc + c]: the nonlinear coefficients
 * (tpk_cell_map_nonlinear_coefficients); v[k * qc + c]: the tet's values at its corners. The same numbers
 * as the cached Bernstein coefficients, to rounding (FORM_MARGIN), with no coefficients to make for a tet
 * of parameter space met first: the pieces of a cut tet seldom repeat a parametric tet, and missed the
 * cache often (bench/README). Four components side by side, as minus_linear. A tet whose corners are
 * nodes has d_k 0 exactly (the weights there are 0 but one 1): quadratic_edges. */
__attribute__((target_clones("avx2", "default"))) static double
quadratic_coefficients(int qc, const double (*w)[10], const double (*m)[6], const double *node, const double *a,
                       const double *v, double *largest)
{
    double geometry = 0;
    for (int c = 0; c < qc; c += 4) {
        quad d[4], x, y, coef[10];
        for (int k = 0; k < 4; k++) {
            quad acc = {0, 0, 0, 0};
#pragma GCC unroll 10 /* at -O2 these fixed loops did not unroll: their counting was a third of the work */
            for (int j = 0; j < 10; j++) {
                memcpy(&y, node + j * qc + c, sizeof y);
                x = (quad){w[k][j], w[k][j], w[k][j], w[k][j]};
                acc += x * y;
            }
            memcpy(&y, v + k * qc + c, sizeof y);
            coef[k] = d[k] = acc - y;
        }
        const quad half = {0.5, 0.5, 0.5, 0.5};
        for (int e = 0; e < 6; e++) {
            quad n = {0, 0, 0, 0};
#pragma GCC unroll 6
            for (int q = 0; q < 6; q++) {
                memcpy(&y, a + q * qc + c, sizeof y);
                x = (quad){m[e][q], m[e][q], m[e][q], m[e][q]};
                n += x * y;
            }
            coef[4 + e] = half * (d[tet_edges[e][0]] + d[tet_edges[e][1]]) - half * n;
        }
        quad top = {0, 0, 0, 0}; /* the magnitudes' maxima, lane by lane */
        for (int i = 0; i < 10; i++) {
            quad magnitude = (quad)((quad_bits)coef[i] & ~(quad_bits)(quad){-0.0, -0.0, -0.0, -0.0});
            quad_bits above = magnitude > top;
            top = (quad)(((quad_bits)magnitude & above) | ((quad_bits)top & ~above));
            if (c == 0) {
                quad sq = coef[i] * coef[i];
                double norm = sq[0] + sq[1] + sq[2];
                geometry = norm > geometry ? norm : geometry;
            }
        }
        memcpy(largest + c, &top, sizeof top);
    }
    return sqrt(geometry);
}

/* quadratic_coefficients' coefficient on an edge of a tet whose corners are nodes j and l (no weights:
 * d_k is 0 at the corners, and so are the corners' coefficients), for the qc components into out, from
 * the monomials at the nodes' difference that are not 0 (node_terms, node_term; a term left out is +-0
 * times a finite number: only a finite slot's numbers are used, and the axes are finite), in the same
 * operations and order otherwise: the same magnitudes (a sum of zeros may differ in its sign alone). */
__attribute__((target_clones("avx2", "default"))) static void
pair_coefficients(const refine *r, int qc, int j, int l, const double *a, double *out)
{
    const quad half = {0.5, 0.5, 0.5, 0.5}, zero = {0, 0, 0, 0};
    const double *m = r->node_pairs[j][l];
    const uint8_t *term = r->node_term[j][l];
    for (int c = 0; c < qc; c += 4) {
        quad n = {0, 0, 0, 0}, y;
        for (int i = 0, terms = r->node_terms[j][l]; i < terms; i++) {
            memcpy(&y, a + term[i] * qc + c, sizeof y);
            n += (quad){m[term[i]], m[term[i]], m[term[i]], m[term[i]]} * y;
        }
        quad coef = half * (zero + zero) - half * n;
        memcpy(out + c, &coef, sizeof coef);
    }
}

/* The rounding of quadratic_coefficients' numbers, as a fraction of the largest value at a node: the
 * values at the corners sum 10 terms of weights within [-1/8, 1] (corners in the cell), the monomials at
 * differences are under 1 and their 6 coefficients under 8 times the largest value (4 f_ij - 2 f_i -
 * 2 f_j): a few units in the last place of numbers under 64, far under 1e-12. */
#define FORM_MARGIN 1e-12

/* The margin for the rounding of the rough bound of numbers up to `big`: the coefficients' sums of at
 * most 8 terms of integer weights up to 4, times departures up to 1, summed over at most 6 monomials,
 * err by under 1e-13 of big. */
#define ROUGH_MARGIN 1e-12

/* Tet t of a hexahedron bounded roughly, when its corners are nodes of its cell (its linear interpolants
 * are then those of the cell's functions at the tet's parametric corners), by sum_q |a_q| departure_q over
 * the cell's nonlinear monomials (tpk_cell_map_nonlinear), and when that meets the criterion; 0, with
 * nothing written, otherwise. (The quadratic tetra's tets need none: bound_quadratic is exact and as
 * cheap.) Most tets of a first split are far under the bound: the first bound of a million
 * hexahedra's tets at 1% took 0.29 s of one core through Bernstein coefficients, 0.12 s so (bench/README). */
static int rough_bound(refine *r, int64_t t, coef_cache *cache, const double p[4][3])
{
    const int32_t *tv = r->tets + 4 * t;
    int n = cache->cell_node_count, count = cache->rough_count, set = 0, node[4];
    if (!node_indices(cache->verts, n, tv, node))
        return 0;
    for (int k = 0; k < 4; k++)
        set |= 1 << node[k];
    const double *departure = r->departure + (int64_t)set * count;
    if (!(departure[0] >= 0))
        return 0;
    double geometry = ROUGH_MARGIN * cache->largest;
    for (int q = 0; q < count; q++)
        geometry += cache->rough_geometry[q] * departure[q];
    double limit = r->o->max_error;
    double crit = geometry / r->diag_length, worst = 0, g[3][3];
    if (!(crit <= limit))
        return 0;
    int flat = barycentric_gradients(p, g, 1) != 0, worst_slot = -1;
    for (int s = 0; s < r->bounded; s++) {
        fill_slot(r, cache, s);
        if (!cache->finite[s])
            continue; /* as bound_tet: no bound for missing values */
        double v[4], gap = ROUGH_MARGIN * cache->big[s];
        for (int q = 0; q < count; q++)
            gap += cache->rough[s * TPK_CELL_MAP_MAX_NONLINEAR + q] * departure[q];
        gap /= r->bound_range[s];
        for (int k = 0; k < 4; k++)
            v[k] = value_of(r, tv[k], r->bound_slot[s]);
        fold_slot(r, s, gap, v, (const double (*)[3])g, flat, geometry, &worst, &worst_slot, &crit);
        if (!(crit <= limit))
            return 0;
    }
    r->field_error[t] = worst, r->geometry_error[t] = geometry / r->diag_length;
    r->worst_slot[t] = worst_slot, r->bound_flags[t] = BOUND_ROUGH | (crit <= r->o->max_error ? 0 : BOUND_OVER);
    return 1;
}

/* bound_quadratic's fold over the slots (fold_slot's numbers, from barycentric_gradients' by inverse) for
 * the tets staged, four side by side, a lane a tet: the same operations in the same order, so the same
 * numbers; a lane stops taking slots once its criterion is over the bound, as the loop it replaces. Lanes
 * past `batched` repeat the first tet and are not written. Each tet's field error, worst slot and flag
 * are written; its geometry error was at staging. */
__attribute__((target_clones("avx2", "default"))) static void
fold_batch(refine *r, coef_cache *cc)
{
    int n = cc->batched;
    if (n == 0)
        return;
    for (int l = n; l < 4; l++) {
        for (int k = 0; k < 4; k++)
            for (int i = 0; i < 3; i++)
                cc->batch_p[k][i][l] = cc->batch_p[k][i][0];
        cc->batch_crit[l] = cc->batch_crit[0], cc->batch_geometry[l] = cc->batch_geometry[0];
        for (int s = 0; s < r->bounded; s++) {
            cc->batch_gap[4 * s + l] = cc->batch_gap[4 * s], cc->batch_ok[4 * s + l] = cc->batch_ok[4 * s];
            for (int k = 0; k < 4; k++)
                cc->batch_value[16 * s + 4 * k + l] = cc->batch_value[16 * s + 4 * k];
        }
    }
    quad p[4][3], e[3][3], g[3][3];
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            memcpy(&p[k][i], cc->batch_p[k][i], sizeof p[k][i]);
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            e[k][i] = p[k + 1][i] - p[0][i];
    for (int k = 0; k < 3; k++) {
        const quad *a = e[(k + 1) % 3], *b = e[(k + 2) % 3];
        g[k][0] = a[1] * b[2] - a[2] * b[1], g[k][1] = a[2] * b[0] - a[0] * b[2], g[k][2] = a[0] * b[1] - a[1] * b[0];
    }
    const quad zero = {0, 0, 0, 0}, one = {1, 1, 1, 1};
    const quad_bits sign = (quad_bits)(quad){-0.0, -0.0, -0.0, -0.0};
    quad det = e[0][0] * g[0][0] + e[0][1] * g[0][1] + e[0][2] * g[0][2];
    quad_bits flat = ~((quad)((quad_bits)det & ~sign) > zero); /* barycentric_gradients: !(fabs(det) > 0) */
    quad inverse = one / det;
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            g[k][i] = g[k][i] * inverse;
    double bound = r->o->uniform_levels > 0 ? INFINITY : r->o->max_error;
    quad crit, geometry, worst = zero, limit = {bound, bound, bound, bound};
    quad_bits slot = {-1, -1, -1, -1};
    memcpy(&crit, cc->batch_crit, sizeof crit), memcpy(&geometry, cc->batch_geometry, sizeof geometry);
    for (int s = 0; s < r->bounded; s++) {
        quad_bits live = crit <= limit, ok;
        if (!(live[0] | live[1] | live[2] | live[3]))
            break; /* every tet over the bound: no need to finish */
        memcpy(&ok, cc->batch_ok + 4 * s, sizeof ok);
        live &= ok;
        const double rs = r->bound_range[s];
        quad v[4], gap, grad[3], root, range = {rs, rs, rs, rs};
        for (int k = 0; k < 4; k++)
            memcpy(&v[k], cc->batch_value + 16 * s + 4 * k, sizeof v[k]);
        memcpy(&gap, cc->batch_gap + 4 * s, sizeof gap);
        for (int j = 0; j < 3; j++) {
            grad[j] = zero;
            for (int k = 0; k < 3; k++)
                grad[j] += (v[k + 1] - v[0]) * g[k][j];
        }
        quad norm = grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2];
        for (int l = 0; l < 4; l++)
            root[l] = sqrt(norm[l]);
        quad located = gap + root * geometry / range;
        quad_bits take = live & ((gap > worst) | (slot < 0));
        worst = (quad)(((quad_bits)gap & take) | ((quad_bits)worst & ~take));
        slot = (slot & ~take) | ((quad_bits){s, s, s, s} & take);
        quad c = (quad)(((quad_bits)gap & flat) | ((quad_bits)located & ~flat));
        quad_bits above = live & (c > crit);
        crit = (quad)(((quad_bits)c & above) | ((quad_bits)crit & ~above));
    }
    for (int l = 0; l < n; l++) {
        int64_t t = cc->batch_tet[l];
        r->field_error[t] = worst[l], r->worst_slot[t] = (int)slot[l];
        r->bound_flags[t] = crit[l] <= r->o->max_error ? 0 : BOUND_OVER;
    }
    cc->batched = 0;
}

/* quadratic_coefficients for a tet whose corners are nodes (node[k]: corner k's): its edges'
 * coefficients (pair_coefficients) are made once a cell for each ordered pair of nodes met
 * (cache->pair_made, cleared with each cell's gathering): a split's 8 tets have 48 edges on 25 pairs,
 * and the first bound of gmsh's t5 at order 2 made each of them for every tet. The largest magnitudes
 * and the geometry's norm are taken over the tet's edges in edge order, as before. Built twice, as
 * minus_linear: the default build of these four-lane numbers without AVX2 is slow. */
__attribute__((target_clones("avx2", "default"))) static double
quadratic_edges(const refine *r, coef_cache *cache, int qc, const int *node, double *largest)
{
    const double *coef[6];
    for (int e = 0; e < 6; e++) {
        int j = node[tet_edges[e][0]], l = node[tet_edges[e][1]], pair = 10 * j + l;
        double *at = cache->pair_coef + pair * qc;
        if (!(cache->pair_made[pair >> 6] >> (pair & 63) & 1)) {
            pair_coefficients(r, qc, j, l, cache->quad_a, at);
            cache->pair_made[pair >> 6] |= 1ull << (pair & 63);
        }
        coef[e] = at;
    }
    double geometry = 0;
    for (int c = 0; c < qc; c += 4) {
        quad top = {0, 0, 0, 0};
        for (int e = 0; e < 6; e++) {
            quad x;
            memcpy(&x, coef[e] + c, sizeof x);
            quad magnitude = (quad)((quad_bits)x & ~(quad_bits)(quad){-0.0, -0.0, -0.0, -0.0});
            quad_bits above = magnitude > top;
            top = (quad)(((quad_bits)magnitude & above) | ((quad_bits)top & ~above));
            if (c == 0) {
                double norm = coef[e][0] * coef[e][0] + coef[e][1] * coef[e][1] + coef[e][2] * coef[e][2];
                geometry = norm > geometry ? norm : geometry;
            }
        }
        memcpy(largest + c, &top, sizeof top);
    }
    return sqrt(geometry);
}

/* bound_tet for a tet of a quadratic tetra (xi: its corners' parametric points, p: their points), through
 * quadratic_coefficients: its cell's node values and nonlinear coefficients of every component are
 * gathered once a cell (cache->quad_cell). */
static void bound_quadratic(refine *r, int64_t t, coef_cache *cache, const double *xi, const int *node,
                            const double p[4][3])
{
    int qc = cache->qc;
    const int32_t *tv = r->tets + 4 * t;
    if (cache->quad_cell != cache->cell) {
        memset(cache->quad_node, 0, sizeof *cache->quad_node * 16 * (size_t)qc);
        for (int j = 0; j < 10; j++)
            for (int c = 0; c < 3; c++)
                cache->quad_node[j * qc + c] = cache->node[j][c];
        for (int q = 0; q < 6; q++)
            for (int c = 0; c < 3; c++)
                cache->quad_a[q * qc + c] = cache->form_geometry[q * 3 + c];
        for (int s = 0; s < r->bounded; s++) {
            fill_slot(r, cache, s);
            for (int j = 0; j < 10; j++)
                cache->quad_node[j * qc + 3 + s] = cache->value[(int64_t)s * TPK_CELL_MAP_MAX_NODES + j];
            for (int q = 0; q < 6; q++)
                cache->quad_a[q * qc + 3 + s] = cache->form[s * TPK_CELL_MAP_MAX_NONLINEAR + q];
        }
        cache->quad_cell = cache->cell;
        cache->pair_made[0] = cache->pair_made[1] = 0;
    }
    double w[4][10], m[6][6], *v = cache->quad_v, *largest = cache->quad_largest;
    if (!node) /* corners at nodes: quadratic_edges, from the monomials at the nodes' differences */
        tpk_cell_map_quadratic_tet(24, xi, w, m);
    for (int k = 0; k < 4 && !node; k++) { /* corners at nodes: their values are the cell's, at hand */
        for (int c = 0; c < 3; c++)
            v[k * qc + c] = p[k][c];
        for (int s = 0; s < r->bounded; s++)
            v[k * qc + 3 + s] = value_of(r, tv[k], r->bound_slot[s]);
        for (int c = 3 + r->bounded; c < qc; c++)
            v[k * qc + c] = 0;
    }
    double geometry = node ? quadratic_edges(r, cache, qc, node, largest)
                           : quadratic_coefficients(qc, (const double (*)[10])w, (const double (*)[6])m,
                                                    cache->quad_node, cache->quad_a, v, largest);
    geometry += 2 * FORM_MARGIN * cache->largest; /* 2 > sqrt 3: each axis's rounding */
    int l = cache->batched++; /* the fold over the slots: fold_batch, four tets at once */
    cache->batch_tet[l] = t, cache->batch_geometry[l] = geometry, cache->batch_crit[l] = geometry / r->diag_length;
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            cache->batch_p[k][i][l] = p[k][i];
    for (int s = 0; s < r->bounded; s++) {
        const double *at = cache->value + (int64_t)s * TPK_CELL_MAP_MAX_NODES;
        double vs[4] = {node ? at[node[0]] : v[3 + s], node ? at[node[1]] : v[qc + 3 + s],
                        node ? at[node[2]] : v[2 * qc + 3 + s], node ? at[node[3]] : v[3 * qc + 3 + s]};
        int ok = cache->finite[s] && isfinite(vs[0]) && isfinite(vs[1]) && isfinite(vs[2]) && isfinite(vs[3]);
        cache->batch_ok[4 * s + l] = ok ? -1 : 0;
        cache->batch_gap[4 * s + l] = ok ? (largest[3 + s] + FORM_MARGIN * cache->big[s]) / r->bound_range[s] : 0;
        for (int k = 0; k < 4; k++)
            cache->batch_value[16 * s + 4 * k + l] = vs[k];
    }
    r->geometry_error[t] = geometry / r->diag_length;
    if (cache->batched == 4)
        fold_batch(r, cache);
}

static void bound_tet(refine *r, int64_t t, coef_cache *cache)
{
    if (r->corners_unchecked && (r->cell[t] < 0 || r->cell[t] >= r->cells->cell_count)) {
        cache->missed = 1; /* as corner_range: no cell to bound it in */
        return;
    }
    if (r->cell[t] != cache->cell) { /* a new cell: its nodes and their points */
        cache->cell = r->cell[t], cache->filled = 0;
        cache->cell_type = cell_nodes(r, cache->cell, cache->verts);
        cache->cell_degree = tpk_cell_map_degree(cache->cell_type);
        cache->cell_node_count = tpk_cell_map_nodes(cache->cell_type);
        double largest = 0; /* summed here, not in the cache, whose stores the loads would wait on */
        for (int k = 0, n = cache->cell_node_count; k < n; k++) {
            const double *x = point_of(r, cache->verts[k]);
            memcpy(cache->node[k], x, sizeof cache->node[k]);
            for (int j = 0; j < 3; j++)
                largest = fabs(x[j]) > largest ? fabs(x[j]) : largest;
        }
        cache->largest = largest;
        double a[3 * TPK_CELL_MAP_MAX_NONLINEAR];
        cache->rough_count = tpk_cell_map_nonlinear_coefficients(cache->cell_type, cache->node[0], 3, a);
        memcpy(cache->form_geometry, a, sizeof a);
        for (int q = 0; q < cache->rough_count && cache->cell_type == 12; q++) /* for rough_bound */
            cache->rough_geometry[q] = sqrt(a[3 * q] * a[3 * q] + a[3 * q + 1] * a[3 * q + 1] + a[3 * q + 2] * a[3 * q + 2]);
    }
    int type = cache->cell_type, degree = cache->cell_degree;
    if (r->corners_unchecked) { /* as place_corners checks them; the quadratic tetra's below, as found */
        int node[4];
        if (!type || (type != 24 && !node_indices(cache->verts, cache->cell_node_count, r->tets + 4 * t, node))) {
            cache->missed = 1;
            return;
        }
    }
    r->field_error[t] = r->geometry_error[t] = 0;
    r->worst_slot[t] = -1, r->bound_flags[t] = 0 <= r->o->max_error ? 0 : BOUND_OVER;
    if (degree <= 1)
        return; /* a tet of a tetra: exactly its own interpolant */
    const tpk_bernstein *b = &r->table[degree];
    double xi_here[12]; /* a tet whose corners are nodes: their points read here, not written (ensure_xi_all) */
    const double *xi = r->xi_at[t] >= 0 ? xi_read(r, t, xi_here) : NULL;
    const int32_t *tv = r->tets + 4 * t;
    int n = cache->cell_node_count, m = b->points, direct = degree > DIRECT_DEGREE;
    double norm = 0, p[4][3], g[3][3], geometry = 0, largest = cache->largest, *weights = cache->work, lebesgue = 0;
    if (!xi && type == 24) { /* corners at nodes: their points are the cell's, at hand */
        int node[4];
        if (!node_indices(cache->verts, n, tv, node)) { /* corner_range found every corner, else the first
                                                          * bound finds here that one is no node */
            cache->missed = 1;
            return;
        }
        for (int k = 0; k < 4; k++)
            memcpy(p[k], cache->node[node[k]], sizeof p[k]);
        bound_quadratic(r, t, cache, NULL, node, (const double (*)[3])p);
        return;
    }
    for (int k = 0; k < 4; k++)
        memcpy(p[k], point_of(r, tv[k]), sizeof p[k]);
    if (!r->exact && type == 12 && rough_bound(r, t, cache, (const double (*)[3])p))
        return;
    if (!xi) { /* the cell's nodes are at hand */
        hold_node_points(type, &cache->xi_type, cache->xi_node);
        xi_of_nodes(r, t, type, cache->verts, (const double (*)[3])cache->xi_node, xi_here);
        xi = xi_here;
    }
    if (type == 24) {
        bound_quadratic(r, t, cache, xi, NULL, (const double (*)[3])p);
        return;
    }
    const double *by_node = NULL;
    double value_margin = 0; /* direct: the rounding of the values at the domain points, through the inverse */
    if (direct) { /* the cell's map at the domain points, then the inverse */
        double x[TPK_BERNSTEIN_MAX_POINTS * 3];
        for (int i = 0; i < m; i++) {
            double at[3] = {0, 0, 0}, *w = weights + (int64_t)i * n, sum = 0;
            for (int k = 0; k < 4; k++)
                for (int j = 0; j < 3; j++)
                    at[j] += b->lambda[i][k] * xi[3 * k + j];
            tpk_cell_map_weights(type, at, w);
            x[3 * i] = x[3 * i + 1] = x[3 * i + 2] = 0;
            for (int k = 0; k < n; k++) {
                sum += fabs(w[k]);
                for (int j = 0; j < 3; j++)
                    x[3 * i + j] += w[k] * cache->node[k][j];
            }
            lebesgue = sum > lebesgue ? sum : lebesgue;
        }
        const double u = DBL_EPSILON / 2, gamma = n * u / (1 - n * u);
        value_margin = 2 * b->inverse_norm * (gamma * lebesgue + n * WEIGHT_ERROR);
        geometry = tpk_bernstein_gap(b, x, 3, p[0], 3) + sqrt(3.0) * value_margin * largest;
    } else {
        by_node = coefficients(cache, b, r->inverse_t[degree], type, n, xi, &norm);
        double gx[3][TPK_BERNSTEIN_MAX_POINTS]; /* the Bernstein coefficients of x - L, per axis */
        minus_linear(m, n, 3, b, (const double (*)[3])p, cache->node[0], 3, by_node, gx);
        for (int i = 0; i < m; i++) {
            double sq = gx[0][i] * gx[0][i] + gx[1][i] * gx[1][i] + gx[2][i] * gx[2][i];
            geometry = sq > geometry ? sq : geometry;
        }
        geometry = sqrt(geometry) + 1e-12 * (norm + 1) * largest; /* the rounding of the sums above */
    }
    double crit = geometry / r->diag_length, worst = 0, limit = r->o->uniform_levels > 0 ? INFINITY : r->o->max_error;
    int flat = barycentric_gradients(p, g, 0) != 0;
    for (int s = 0; s < r->bounded && crit <= limit; s++) { /* a tet over the bound is cut: no need to finish */
        int slot = r->bound_slot[s];
        double v[4], gap = 0, cv[4][3];
        double *value = cache->value + (int64_t)s * TPK_CELL_MAP_MAX_NODES;
        fill_slot(r, cache, s);
        int finite = cache->finite[s];
        for (int k = 0; k < 4; k++)
            finite &= isfinite(v[k] = cv[k][0] = value_of(r, tv[k], slot));
        if (!finite)
            continue; /* no bound for missing values (NaN): nothing to interpolate */
        if (direct) {
            double f[TPK_BERNSTEIN_MAX_POINTS], corner[4] = {v[0], v[1], v[2], v[3]};
            for (int i = 0; i < m; i++) {
                const double *w = weights + (int64_t)i * n;
                f[i] = 0;
                for (int k = 0; k < n; k++)
                    f[i] += w[k] * value[k];
            }
            gap = (tpk_bernstein_gap(b, f, 1, corner, 1) + value_margin * cache->big[s]) / r->bound_range[s];
        } else {
            double acc[1][TPK_BERNSTEIN_MAX_POINTS]; /* the Bernstein coefficients of f - L */
            minus_linear(m, n, 1, b, (const double (*)[3])cv, value, 1, by_node, acc);
            for (int i = 0; i < m; i++)
                gap = fabs(acc[0][i]) > gap ? fabs(acc[0][i]) : gap;
            gap = (gap + 1e-12 * (norm + 1) * cache->big[s]) / r->bound_range[s];
        }
        fold_slot(r, s, gap, v, (const double (*)[3])g, flat, geometry, &worst, &r->worst_slot[t], &crit);
    }
    r->field_error[t] = worst, r->geometry_error[t] = geometry / r->diag_length;
    r->bound_flags[t] = crit <= r->o->max_error ? 0 : BOUND_OVER;
}

static void bound_range(void *ctx, int64_t begin, int64_t end, int w)
{
    refine *r = ctx;
    for (int64_t i = begin; i < end; i++) {
        if (i + 16 < end) { /* the tets and their corners are scattered: fetch them ahead */
            __builtin_prefetch(r->tets + 4 * todo_tet(r, i + 16));
            __builtin_prefetch(r->xi_at + todo_tet(r, i + 16));
        }
        if (i + 8 < end && r->xi_at[todo_tet(r, i + 8)] >= 0) {
            __builtin_prefetch(r->xi + 12 * (int64_t)r->xi_at[todo_tet(r, i + 8)]);
            __builtin_prefetch(r->xi + 12 * (int64_t)r->xi_at[todo_tet(r, i + 8)] + 11);
        }
        if (i + 8 < end)
            for (int k = 0; k < 4; k++) {
                int32_t v = r->tets[4 * todo_tet(r, i + 8) + k];
                __builtin_prefetch(point_of(r, v));
                if (v >= r->n0)
                    __builtin_prefetch(r->added + (int64_t)(v - r->n0) * r->slots);
            }
        bound_tet(r, todo_tet(r, i), &r->cache[w]);
    }
    fold_batch(r, &r->cache[w]); /* the quadratic tetra's tets left */
}

/* ---- growth ------------------------------------------------------------------------------------ */

static int reserve_tets(refine *r, int64_t need)
{
    if (need <= r->cap)
        return 0;
    int64_t cap = need + need / 2 + 1024;
    if (grow((void **)&r->tets, 4 * sizeof *r->tets, cap) || grow((void **)&r->cell, sizeof *r->cell, cap) ||
        grow((void **)&r->xi_at, sizeof *r->xi_at, cap) ||
        (r->root && grow((void **)&r->root, sizeof *r->root, cap)) ||
        grow((void **)&r->field_error, sizeof *r->field_error, cap) ||
        grow((void **)&r->geometry_error, sizeof *r->geometry_error, cap) ||
        grow((void **)&r->worst_slot, sizeof *r->worst_slot, cap) ||
        grow((void **)&r->marked, sizeof *r->marked, cap) ||
        grow((void **)&r->bound_flags, sizeof *r->bound_flags, cap) ||
        grow((void **)&r->todo, sizeof *r->todo, cap))
        return tpk_diag_fail(r->diag, "out of memory for %lld tets (--max-error)", (long long)need);
    r->cap = cap;
    return 0;
}

/* Every tet to be bounded again (after --subdivide cut them all). */
static void todo_all(refine *r)
{
    r->todo_every = 1, r->todo_count = r->count;
}

/* Room for `more` vertices. */
static int reserve_vertices(refine *r, int64_t more)
{
    tpk_tetmesh *m = r->m;
    if (m->vertex_count + more > INT32_MAX - 1)
        return tpk_diag_fail(r->diag, "--max-error: more than %d vertices", INT32_MAX - 1);
    if (m->vertex_count + more > r->vertex_cap) {
        int64_t need = m->vertex_count + more, cap = need + need / 2 + 1024;
        if (grow((void **)&m->points, 3 * sizeof *m->points, cap) ||
            grow((void **)&m->vertex_source, sizeof *m->vertex_source, cap) ||
            grow((void **)&r->added, sizeof *r->added * (size_t)(r->slots ? r->slots : 1), cap - r->n0))
            return tpk_diag_fail(r->diag, "out of memory for %lld vertices (--max-error)", (long long)cap);
        r->vertex_cap = cap;
    }
    return 0;
}

/* Vertex v (room made) at parametric point xi of tet t's cell: placed by the map (on the file's grid),
 * valued by the interpolant, every point field and step; the first slot whose float32 value misses the
 * bound at the vertex itself into *hit (where given and none is there yet). */
static void place_vertex(refine *r, int32_t v, int64_t t, const double xi[3], floor_hit *hit)
{
    tpk_tetmesh *m = r->m;
    int32_t verts[TPK_CELL_MAP_MAX_NODES];
    double w[TPK_CELL_MAP_MAX_NODES], x[3];
    int type = cell_nodes(r, r->cell[t], verts), n = tpk_cell_map_nodes(type);
    map_point(r, type, verts, xi, w, x);
    for (int a = 0; m->on_grid && a < 3; a++)
        x[a] = m->grid_origin[a] + (double)(float)(x[a] - m->grid_origin[a]);
    memcpy(m->points + 3 * (int64_t)v, x, sizeof x);
    m->vertex_source[v] = -1;
    for (int s = 0; s < r->slots; s++) {
        double exact = interpolate(r, n, verts, w, s);
        float stored = (float)exact;
        r->added[(int64_t)(v - r->n0) * r->slots + s] = stored;
        if (hit && hit->vertex < 0 && fabs((double)stored - exact) > r->slot_allowed[s])
            *hit = (floor_hit){v, s, exact, stored};
    }
}

static int32_t add_vertex(refine *r, int64_t t, const double xi[3])
{
    if (reserve_vertices(r, 1) != 0)
        return -1;
    int32_t v = (int32_t)r->m->vertex_count++;
    place_vertex(r, v, t, xi, NULL);
    return v;
}

static int sign_of(const refine *r, const int32_t *v)
{
    return tpk_orient3d_exact(point_of(r, v[0]), point_of(r, v[1]), point_of(r, v[2]), point_of(r, v[3]));
}

/* The edges (tet_edges) at each corner, and the edge between two corners. */
static const unsigned edges_at[4] = {0x07, 0x19, 0x2a, 0x34};
static const int edge_of[4][4] = {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}};

/* Tet t bisected at its edge e through vertex mid: t keeps the half of corner i, tet u (new) the other;
 * each keeps the marks of the edges it still has (not those at the corner it gave up, now at mid, new).
 * 1 when a piece turns over (a sign other than the parent's), else 0; 2, with nothing changed, when the
 * midpoint's parametric point does not fit float32 and xi_wide is not made (cut_marked makes it and
 * bisects those tets again). *sign: t's exact sign where known, else 2; then each piece's (the parent's
 * when neither turned over, 2 when the parent is flat), so a piece cut in the next round is not
 * measured again (a third of the round's orientation tests). */
static int bisect(refine *r, int64_t t, int64_t u, int e, int32_t mid, int8_t *sign)
{
    int i = tet_edges[e][0], j = tet_edges[e][1];
    int32_t *a = r->tets + 4 * t, *b = r->tets + 4 * u;
    double xa[12], xb[12], half[3]; /* t's entry written before the rounds, u's given (cut_marked) */
    const double *entry = xi_read(r, t, xa);
    if (entry != xa)
        memcpy(xa, entry, sizeof xa);
    for (int k = 0; k < 3; k++)
        half[k] = 0.5 * (xa[3 * i + k] + xa[3 * j + k]);
    if (!r->xi_wide && !xi_fits(half, 3))
        return 2;
    int parent = *sign != 2 ? *sign : sign_of(r, a);
    memcpy(b, a, 4 * sizeof *a);
    memcpy(xb, xa, sizeof xa);
    r->cell[u] = r->cell[t];
    if (r->root)
        r->root[u] = r->root[t];
    r->marked[u] = (uint8_t)(r->marked[t] & ~edges_at[i]);
    r->marked[t] = (uint8_t)(r->marked[t] & ~edges_at[j]);
    a[j] = mid, b[i] = mid;
    memcpy(xa + 3 * j, half, sizeof half);
    memcpy(xb + 3 * i, half, sizeof half);
    xi_write(r, r->xi_at[t], xa), xi_write(r, r->xi_at[u], xb); /* each fits, or xi_wide is made */
    *sign = (int8_t)(parent != 0 ? parent : 2);
    return parent != 0 && (sign_of(r, a) != parent || sign_of(r, b) != parent);
}

/* One round on all threads: each tet of `active` chooses its greatest marked edge; the midpoints not made
 * yet are numbered in the order of the tets (serial: the first tet in `active` that cuts an edge makes
 * its midpoint, in its cell); they are placed and valued, and the tets bisected, on all threads. The
 * result does not depend on the thread count. */
typedef struct round_job {
    refine *r;
    int64_t *active;
    int8_t *chosen;   /* per tet of active: the edge it cuts */
    int32_t *mid;     /* per tet of active: the vertex at that edge's midpoint */
    int64_t *maker;   /* per vertex made this round: the place in active of the tet that makes it */
    uint8_t *folded;  /* per tet of active: a piece turned over */
    int8_t *sign;     /* per tet of active: its exact sign where known (bisect), else 2 */
    int64_t first_child, first_xi; /* the first new tet, and its entry of parametric points */
    int32_t first_vertex;
    int64_t cap; /* the arrays' room (round_grow) */
    floor_hit hit[TPK_MAX_THREADS]; /* per worker of place_range: its first vertex whose value misses */
} round_job;

static void choose_range(void *ctx, int64_t begin, int64_t end, int w)
{
    round_job *job = ctx;
    (void)w;
    for (int64_t k = begin; k < end; k++)
        job->chosen[k] = (int8_t)greatest_edge(job->r, job->active[k], job->r->marked[job->active[k]]);
}

static void place_range(void *ctx, int64_t begin, int64_t end, int w)
{
    round_job *job = ctx;
    refine *r = job->r;
    for (int64_t n = begin; n < end; n++) {
        int64_t k = job->maker[n], t = job->active[k];
        int i = tet_edges[job->chosen[k]][0], j = tet_edges[job->chosen[k]][1];
        double half[3], buf[12];
        const double *xi = xi_read(r, t, buf);
        for (int c = 0; c < 3; c++)
            half[c] = 0.5 * (xi[3 * i + c] + xi[3 * j + c]);
        place_vertex(r, job->first_vertex + (int32_t)n, t, half, &job->hit[w]);
    }
}

static void bisect_range(void *ctx, int64_t begin, int64_t end, int w)
{
    round_job *job = ctx;
    (void)w;
    for (int64_t k = begin; k < end; k++) {
        job->r->xi_at[job->first_child + k] = (int32_t)(job->first_xi + k);
        job->folded[k] = (uint8_t)bisect(job->r, job->active[k], job->first_child + k, job->chosen[k], job->mid[k],
                                         &job->sign[k]);
    }
}

/* Room for cap tets in the arrays, kept when there is (a round after the first cuts fewer): not moved
 * again. */
static int round_grow(round_job *job, int64_t cap)
{
    if (cap <= job->cap)
        return 0;
    cap += cap / 2;
    void *p[6] = {realloc(job->active, sizeof *job->active * (size_t)cap), NULL, NULL, NULL, NULL, NULL};
    if (p[0])
        job->active = p[0];
    if (p[0] && (p[1] = realloc(job->chosen, (size_t)cap)))
        job->chosen = p[1];
    if (p[1] && (p[2] = realloc(job->mid, sizeof *job->mid * (size_t)cap)))
        job->mid = p[2];
    if (p[2] && (p[3] = realloc(job->maker, sizeof *job->maker * (size_t)cap)))
        job->maker = p[3];
    if (p[3] && (p[4] = realloc(job->folded, (size_t)cap)))
        job->folded = p[4];
    if (p[4] && (p[5] = realloc(job->sign, (size_t)cap)))
        job->sign = p[5];
    if (p[5])
        job->cap = cap;
    return p[5] ? 0 : -1;
}

/* The refinement cannot meet the bound: a vertex it added holds a value that float32 (the type the
 * file stores values in) cannot bring within the bound of the interpolant there. Said at once, with the
 * field, the point, the values and what would work, rather than after cutting up to the tet limit. */
static int float_floor_fail(const refine *r, const floor_hit *h)
{
    const tpk_src_field *f = &r->m->fields[r->slot_field[h->slot]];
    int64_t step = (r->slot_values[h->slot] - f->values) / (r->n0 > 0 ? r->n0 : 1);
    const double *x = r->m->points + 3 * (int64_t)h->vertex;
    double range = r->slot_allowed[h->slot] / r->o->max_error, off = fabs((double)h->stored - h->exact);
    float magnitude = fabsf(h->stored), lo = INFINITY;
    /* the offset to take out: the middle of the range, over every step (the range set_up bounds) */
    for (int64_t k = 0; k < (int64_t)f->step_count * r->n0; k++)
        lo = isfinite(f->values[k]) ? fminf(lo, f->values[k]) : lo;
    char step_text[32] = "";
    if (f->step_count > 1)
        snprintf(step_text, sizeof step_text, " (step %lld)", (long long)step);
    return tpk_diag_fail(r->diag, "--max-error %g: field '%s'%s cannot be stored that close to its interpolant: the "
                         "file holds values as float32, and at the point (%.9g, %.9g, %.9g) that the refinement "
                         "adds, the source cell's value %.17g is stored as %.9g (float32 steps by %g there), off "
                         "by %g, which is %.3g of the field's range %g; no refinement meets a smaller bound. Give "
                         "a bound above %.3g, or convert the field with its offset taken out (its values minus "
                         "about %.6g)", r->o->max_error, f->name, step_text, x[0], x[1], x[2], h->exact,
                         (double)h->stored, (double)(nextafterf(magnitude, INFINITY) - magnitude), off,
                         off / range, range, off / range, (double)lo + 0.5 * range);
}

/* The rounds: every tet of `active` (ascending; malloc'ed, taken over) with a marked edge bisects its
 * greatest marked one, its pieces keeping its other marks, until none has one. The tets cut, then their
 * pieces, become the tets to bound again. */
static int cut_marked(refine *r, int64_t *active, int64_t active_count)
{
    int rc = 0;
    round_job job = {.r = r, .active = active};
    memcpy(r->todo, active, sizeof *active * (size_t)active_count);
    r->todo_every = 0, r->todo_count = active_count;
    int64_t first_new = r->count;
    rc = ensure_xi_all(r, active, active_count); /* the tets cut read their corners' points */
    if (rc == 0 && round_grow(&job, 2 * active_count + 1) != 0) /* the first round's tets and pieces */
        rc = tpk_diag_fail(r->diag, "out of memory for --max-error");
    if (rc == 0)
        memset(job.sign, 2, (size_t)active_count); /* the signs of the tets given: not known yet */
    while (rc == 0 && active_count > 0) {
        tpk_parallel_for(active_count, tpk_threads_for(active_count, r->threads, 1024), choose_range, &job);
        int64_t n = 0;
        for (int64_t k = 0; k < active_count; k++)
            if (job.chosen[k] >= 0)
                job.active[n] = job.active[k], job.sign[n] = job.sign[k], job.chosen[n++] = job.chosen[k];
        active_count = n;
        if (n == 0)
            break;
        if (r->count + n > r->o->max_tets) {
            rc = r->o->uniform_levels > 0
                     ? tpk_diag_fail(r->diag, "--subdivide %d: more than %lld tets (from %lld)", r->o->uniform_levels,
                                     (long long)r->o->max_tets, (long long)r->tets_given)
                     : tpk_diag_fail(r->diag, "--max-error %g: refinement would pass %lld tets (from %lld) before "
                                     "meeting the bound; give a larger bound", r->o->max_error,
                                     (long long)r->o->max_tets, (long long)r->tets_given);
            break;
        }
        if (reserve_tets(r, r->count + n) != 0 || reserve_vertices(r, n) != 0 || reserve_xi(r, n) != 0) {
            rc = -1;
            break;
        }
        if (round_grow(&job, 2 * n) != 0) {
            rc = tpk_diag_fail(r->diag, "out of memory for --max-error");
            break;
        }
        int64_t made = 0;
        job.first_vertex = (int32_t)r->m->vertex_count;
        for (int64_t k = 0; k < n; k++) {
            const int32_t *v = r->tets + 4 * job.active[k];
            uint64_t key = edge_key(v[tet_edges[job.chosen[k]][0]], v[tet_edges[job.chosen[k]][1]]);
            int64_t slot = edge_slot(&r->marks, key); /* a marked edge: in the table */
            if (r->marks.values[slot] < 0)
                r->marks.values[slot] = job.first_vertex + (int32_t)made, job.maker[made++] = k;
            job.mid[k] = r->marks.values[slot];
        }
        r->m->vertex_count += made;
        for (int w = 0; w < TPK_MAX_THREADS; w++)
            job.hit[w].vertex = -1;
        tpk_parallel_for(made, tpk_threads_for(made, r->threads, 256), place_range, &job);
        const floor_hit *hit = NULL; /* the first vertex, whatever the threads: workers take ranges in order */
        for (int w = 0; w < TPK_MAX_THREADS; w++)
            if (job.hit[w].vertex >= 0 && (!hit || job.hit[w].vertex < hit->vertex))
                hit = &job.hit[w];
        if (hit) {
            rc = float_floor_fail(r, hit);
            break;
        }
        job.first_child = r->count, job.first_xi = r->xi_count;
        r->count += n, r->xi_count += n;
        tpk_parallel_for(n, tpk_threads_for(n, r->threads, 1024), bisect_range, &job);
        for (int64_t k = 0; k < n && rc == 0; k++)
            if (job.folded[k] == 2 && (rc = xi_widen(r)) == 0) /* a midpoint not float32: again, in doubles */
                job.folded[k] = (uint8_t)bisect(r, job.active[k], job.first_child + k, job.chosen[k], job.mid[k],
                                                &job.sign[k]);
        for (int64_t k = 0; k < n && rc == 0; k++)
            if (job.folded[k]) {
                int64_t c = r->cell[job.active[k]];
                rc = tpk_diag_fail(r->diag, "--max-error: cell %lld (a %s) folds when refined: a tet bisected at its "
                                   "map's midpoint of an edge turns over (the cell is too curved for its tets); "
                                   "convert it without --max-error or with a larger bound", (long long)c,
                                   tpk_cell_type(r->cells->types[c])->name);
                break;
            }
        for (int64_t k = 0; k < n; k++) /* the children: the cut tets, then the new ones */
            job.active[n + k] = job.first_child + k, job.sign[n + k] = job.sign[k];
        active_count = 2 * n;
    }
    for (int64_t u = first_new; rc == 0 && u < r->count; u++)
        r->todo[r->todo_count++] = u;
    free(job.active), free(job.chosen), free(job.mid), free(job.maker), free(job.folded), free(job.sign);
    return rc;
}

/* --subdivide: each tet cut into 8 at its edges' midpoints (red refinement: the 4 corner tets and the inner
 * octahedron cut along its shortest diagonal), so every edge is halved, as a lattice subdivision halves a
 * cell's; a face is cut into the same 4 triangles from both sides. A piece's vertex order is the one
 * whose parametric orientation is its parent's; its exact sign must then be its parent's too. */
static int cut_all(refine *r)
{
    static const int corner_tets[4][4] = {{0, 4, 5, 6}, {4, 1, 7, 8}, {5, 7, 2, 9}, {6, 8, 9, 3}};
    static const int diagonal[3][2] = {{4, 9}, {5, 8}, {6, 7}}; /* mid-edges of opposite edges */
    static const int ring[3][4] = {{5, 6, 8, 7}, {4, 6, 9, 7}, {4, 5, 9, 8}};
    int64_t n = r->count;
    if (8 * n > r->o->max_tets)
        return tpk_diag_fail(r->diag, "--subdivide %d: more than %lld tets (from %lld)", r->o->uniform_levels,
                             (long long)r->o->max_tets, (long long)r->tets_given);
    if (reserve_tets(r, 8 * n) != 0 || ensure_xi_all(r, NULL, n) != 0 || reserve_xi(r, 7 * n) != 0)
        return -1;
    edge_clear(&r->mids); /* the edges of the last level are all cut: no tet has one */
    for (int64_t t = 0; t < n; t++) {
        int32_t v[10];
        double x[10][3];
        double buf[12];
        const double *xi = xi_read(r, t, buf);
        for (int k = 0; k < 4; k++)
            v[k] = r->tets[4 * t + k], memcpy(x[k], xi + 3 * k, sizeof x[k]);
        for (int e = 0; e < 6; e++) {
            int i = tet_edges[e][0], j = tet_edges[e][1];
            for (int c = 0; c < 3; c++)
                x[4 + e][c] = 0.5 * (x[i][c] + x[j][c]);
            uint64_t key = edge_key(v[i], v[j]);
            if (!edge_find(&r->mids, key, &v[4 + e])) {
                if ((v[4 + e] = add_vertex(r, t, x[4 + e])) < 0)
                    return -1;
                if (edge_put(&r->mids, key, v[4 + e]) != 0)
                    return tpk_diag_fail(r->diag, "out of memory for --subdivide");
            }
        }
        int parent = sign_of(r, v), parent_xi = tpk_orient3d_exact(x[0], x[1], x[2], x[3]), d = 0;
        for (int k = 1; k < 3; k++)
            if (dist2(point_of(r, v[diagonal[k][0]]), point_of(r, v[diagonal[k][1]])) <
                dist2(point_of(r, v[diagonal[d][0]]), point_of(r, v[diagonal[d][1]])))
                d = k;
        int local[8][4];
        memcpy(local, corner_tets, sizeof corner_tets);
        for (int k = 0; k < 4; k++) {
            int l[4] = {diagonal[d][0], diagonal[d][1], ring[d][k], ring[d][(k + 1) % 4]};
            memcpy(local[4 + k], l, sizeof l);
        }
        int64_t cell = r->cell[t], root = r->root ? r->root[t] : 0;
        for (int c = 0; c < 8; c++) {
            int *l = local[c];
            if (tpk_orient3d_exact(x[l[0]], x[l[1]], x[l[2]], x[l[3]]) != parent_xi) {
                int swap = l[2];
                l[2] = l[3], l[3] = swap;
            }
            int64_t u = c == 0 ? t : r->count++;
            if (u != t)
                r->xi_at[u] = (int32_t)r->xi_count++;
            for (int k = 0; k < 4; k++)
                r->tets[4 * u + k] = v[l[k]], memcpy(buf + 3 * k, x[l[k]], sizeof x[0]);
            if (xi_write(r, r->xi_at[u], buf) != 0 && (xi_widen(r) != 0 || xi_write(r, r->xi_at[u], buf) != 0))
                return -1;
            r->cell[u] = (int32_t)cell, r->marked[u] = 0;
            if (r->root)
                r->root[u] = root;
            if (parent != 0 && sign_of(r, r->tets + 4 * u) != parent)
                return tpk_diag_fail(r->diag, "--subdivide: cell %lld (a %s) folds when subdivided: a piece cut at its "
                                     "map's edge midpoints turns over", (long long)cell,
                                     tpk_cell_type(r->cells->types[cell])->name);
        }
    }
    todo_all(r);
    return 0;
}

static int vertex_tets_room(refine *r)
{
    vertex_tets *vt = &r->by_vertex;
    int64_t nv = r->m->vertex_count, corners = 4 * r->count;
    if (nv > vt->vertex_cap) {
        if (grow((void **)&vt->head, sizeof *vt->head, nv + nv / 2 + 1024) != 0)
            return -1;
        vt->vertex_cap = nv + nv / 2 + 1024;
    }
    if (corners > vt->corner_cap) {
        if (grow((void **)&vt->next, sizeof *vt->next, corners + corners / 2 + 1024) != 0)
            return -1;
        vt->corner_cap = corners + corners / 2 + 1024;
    }
    for (int64_t v = vt->vertices; v < nv; v++) /* vertices new since: no list yet */
        vt->head[v] = -1;
    vt->vertices = nv;
    return 0;
}

/* Tets t (the `count` listed) put in their corners' lists. */
static void vertex_tets_link(refine *r, const int64_t *tets, int64_t count)
{
    int32_t *head = r->by_vertex.head, *next = r->by_vertex.next;
    int shift = r->by_vertex.shift;
    /* eight stretches of the list side by side: neighbouring tets share corners, so each link waits on
     * the last one's store to the same head; tets an eighth of the list apart seldom do (the lists' order
     * changes nothing: the closure is a set; bench/README, stop 49, has how many stretches pay) */
    enum { STRETCHES = 8 };
    int64_t stretch = count / STRETCHES;
    for (int64_t i = 0; i < count; i++) { /* the i-th: stretch i % 8, its (i / 8)-th; then the rest in order */
        int64_t at = i < STRETCHES * stretch ? (i % STRETCHES) * stretch + i / STRETCHES : i;
        for (int64_t t = tets ? tets[at] : at, k = 0; k < 4; k++) {
            int32_t v = r->tets[4 * t + k];
            next[4 * t + k] = head[v];
            head[v] = (int32_t)(t << shift | (shift ? k : 0));
        }
    }
}

/* The tets of `active` (in_active), about to be cut, taken out of their corners' lists. */
static int vertex_tets_unlink(refine *r, const int64_t *active, int64_t count, const uint8_t *in_active)
{
    uint8_t *done = calloc((size_t)(r->by_vertex.vertices ? r->by_vertex.vertices : 1), 1);
    if (!done)
        return -1;
    int32_t *head = r->by_vertex.head, *next = r->by_vertex.next;
    for (int64_t i = 0; i < count; i++)
        for (int k = 0; k < 4; k++) {
            int32_t v = r->tets[4 * active[i] + k];
            if (done[v])
                continue;
            done[v] = 1;
            for (int32_t *slot = &head[v]; *slot >= 0;) {
                int32_t *after = &next[link_at(&r->by_vertex, r->tets, *slot, v)];
                if (in_active[*slot >> r->by_vertex.shift])
                    *slot = *after;
                else
                    slot = after;
            }
        }
    free(done);
    return 0;
}

/* Marks the failing tets' longest edges, closes the marks (every tet around a marked edge marks its own
 * longest, through the tets by vertex), then bisects round by round: each tet with a marked edge cuts
 * its greatest, until none is left. */
typedef struct edge_queue {
    uint64_t *keys;
    int64_t count, cap;
} edge_queue;

static int queue_push(edge_queue *q, uint64_t key)
{
    if (q->count >= q->cap) {
        int64_t cap = 2 * q->cap + 1024;
        uint64_t *grown = realloc(q->keys, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        q->keys = grown, q->cap = cap;
    }
    q->keys[q->count++] = key;
    return 0;
}

/* Marks edge (a, b) and queues it, when not marked yet. */
static int mark(refine *r, edge_queue *q, int32_t a, int32_t b)
{
    uint64_t key = edge_key(a, b);
    if (edge_find(&r->marks, key, NULL))
        return 0;
    if (queue_push(q, key) != 0)
        return -1;
    return edge_put(&r->marks, key, -1);
}

static int mark_longest(refine *r, edge_queue *q, int64_t t)
{
    int e = greatest_edge(r, t, 0x3f); /* found here, for the few tets marked, not for every tet bounded */
    return mark(r, q, r->tets[4 * t + tet_edges[e][0]], r->tets[4 * t + tet_edges[e][1]]);
}

/* The closure's state: tets found around marked edges mark the edge, and their longest once. */
typedef struct closure {
    edge_queue queue;
    uint8_t *in_active;
    int64_t active_count;
} closure;

/* The closure: the tets at each queued edge (a, b), found by walking a's list, mark the edge, and their
 * longest the first time (which may queue it). Eight walks go side by side, a step each in turn: a step
 * waits on its load of the next entry, and the walks overlap those waits (gmsh's t5 at order 2, 1%: the
 * closure 4.0 ms one walk at a time, 3.3 ms four, 3.2 ms eight). The closure is the same set in any
 * order. */
static int walk_closure(refine *r, closure *cl)
{
    enum { WALKS = 8 };
    const vertex_tets *vt = &r->by_vertex;
    int32_t from[WALKS], to[WALKS], at_entry[WALKS];
    int walks = 0, rc = 0;
    for (;;) {
        while (walks < WALKS && cl->queue.count > 0) {
            uint64_t key = cl->queue.keys[--cl->queue.count];
            from[walks] = (int32_t)(key >> 32), to[walks] = (int32_t)(key & 0xffffffffu);
            at_entry[walks] = vt->head[from[walks]];
            walks++;
        }
        if (walks == 0 || rc != 0)
            return rc;
        for (int w = 0; w < walks && rc == 0;) {
            if (at_entry[w] < 0) { /* this walk is done: the last takes its place */
                walks--;
                from[w] = from[walks], to[w] = to[walks], at_entry[w] = at_entry[walks];
                continue;
            }
            int64_t at = link_at(vt, r->tets, at_entry[w], from[w]), u = at >> 2;
            const int32_t *v = r->tets + 4 * u;
            int ia = (int)(at & 3), ib = 0;
            while (ib < 4 && v[ib] != to[w])
                ib++;
            if (ib < 4) {
                r->marked[u] |= (uint8_t)(1u << edge_of[ia][ib]);
                if (!cl->in_active[u]) /* once is enough: its longest is marked for good */
                    cl->in_active[u] = 1, cl->active_count++, rc = mark_longest(r, &cl->queue, u);
            }
            at_entry[w] = vt->next[at];
            w++;
        }
    }
}

/* The closure, as a set, does not depend on the order the edges are visited in. */
static int refine_pass(refine *r)
{
    edge_clear(&r->marks);
    closure cl = {{NULL, 0, 0}, calloc((size_t)(r->count ? r->count : 1), 1), 0};
    int64_t *active = NULL;
    int made = r->by_vertex.vertices > 0, rc = cl.in_active ? vertex_tets_room(r) : -1;
    if (rc == 0 && !made) { /* every vertex's list made (vertex_tets_room emptied them) */
        r->by_vertex.shift = 4 * r->count + 3 <= INT32_MAX ? 2 : 0;
        vertex_tets_link(r, NULL, r->count);
    }
    for (int64_t i = 0; rc == 0 && i < r->todo_count; i++)
        if (r->bound_flags[todo_tet(r, i)] & BOUND_OVER)
            rc = mark_longest(r, &cl.queue, todo_tet(r, i));
    if (rc == 0) /* the closure: every tet around a marked edge marks its longest */
        rc = walk_closure(r, &cl);
    free(cl.queue.keys);
    if (rc == 0 && !(active = malloc(sizeof *active * (size_t)(cl.active_count ? cl.active_count : 1))))
        rc = -1;
    for (int64_t t = 0, n = 0; rc == 0 && t < r->count; t++)
        if (cl.in_active[t])
            active[n++] = t;
    int keep = cl.active_count < r->count / 32; /* the lists kept, the tets cut taken out and put back */
    if (rc == 0 && keep)
        rc = vertex_tets_unlink(r, active, cl.active_count, cl.in_active);
    free(cl.in_active);
    if (rc != 0) {
        free(active);
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    }
    if ((rc = cut_marked(r, active, cl.active_count)) != 0)
        return rc;
    if (!keep || (r->by_vertex.shift && 4 * r->count + 3 > INT32_MAX)) { /* made again, by the tet if need be */
        r->by_vertex.vertices = 0;
        return 0;
    }
    if (vertex_tets_room(r) != 0) /* the tets cut and their pieces (r->todo) put in */
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    vertex_tets_link(r, r->todo, r->todo_count);
    return 0;
}

/* ---- set-up and hand-back ---------------------------------------------------------------------- */

static int pick_fields(refine *r)
{
    tpk_tetmesh *m = r->m;
    for (int f = 0; f < m->field_count; f++)
        if (m->fields[f].association == TPK_ASSOC_POINT)
            r->slots += m->fields[f].step_count;
    r->slot_values = calloc((size_t)(r->slots ? r->slots : 1), sizeof *r->slot_values);
    r->slot_field = calloc((size_t)(r->slots ? r->slots : 1), sizeof *r->slot_field);
    r->bound_slot = calloc((size_t)(r->slots ? r->slots : 1), sizeof *r->bound_slot);
    r->bound_range = calloc((size_t)(r->slots ? r->slots : 1), sizeof *r->bound_range);
    r->slot_allowed = calloc((size_t)(r->slots ? r->slots : 1), sizeof *r->slot_allowed);
    if (!r->slot_values || !r->slot_field || !r->bound_slot || !r->bound_range || !r->slot_allowed)
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    for (int i = 0; i < r->o->field_count; i++) {
        int found = 0;
        for (int f = 0; f < m->field_count; f++)
            found |= m->fields[f].association == TPK_ASSOC_POINT && !strcmp(m->fields[f].name, r->o->fields[i]);
        if (!found)
            return tpk_diag_fail(r->diag, "--max-error-field %s: the converted mesh has no point field of that name",
                                 r->o->fields[i]);
    }
    for (int f = 0, s = 0; f < m->field_count; f++) {
        tpk_src_field *field = &m->fields[f];
        if (field->association != TPK_ASSOC_POINT)
            continue;
        int chosen = r->o->field_count == 0;
        for (int i = 0; i < r->o->field_count; i++)
            chosen |= !strcmp(field->name, r->o->fields[i]);
        double lo = INFINITY, hi = -INFINITY;
        for (int64_t k = 0; k < (int64_t)field->step_count * r->n0; k++)
            if (isfinite(field->values[k]))
                lo = fmin(lo, field->values[k]), hi = fmax(hi, field->values[k]);
        r->report_fields += chosen && hi > lo;
        for (int step = 0; step < field->step_count; step++, s++) {
            r->slot_values[s] = field->values + (int64_t)step * r->n0;
            r->slot_field[s] = f;
            r->slot_allowed[s] = INFINITY;
            if (chosen && hi > lo) { /* a constant field is its own interpolant everywhere */
                r->bound_slot[r->bounded] = s, r->bound_range[r->bounded++] = hi - lo;
                if (r->o->uniform_levels <= 0)
                    r->slot_allowed[s] = r->o->max_error * (hi - lo);
            }
        }
    }
    return 0;
}

/* The refined tets, their cells and cell fields, and the point fields with the added vertices' values,
 * into the mesh. */
static int hand_back(refine *r)
{
    tpk_tetmesh *m = r->m;
    int64_t nv = m->vertex_count, nt = r->count, t0 = m->tet_count;
    for (int f = 0; f < m->field_count; f++) {
        tpk_src_field *field = &m->fields[f];
        int point = field->association == TPK_ASSOC_POINT;
        int64_t per = point ? nv : nt, old = point ? r->n0 : t0;
        int64_t total = (int64_t)field->step_count * per;
        float *values = malloc(sizeof *values * (size_t)(total > 0 ? total : 1));
        if (!values)
            return tpk_diag_fail(r->diag, "out of memory for the fields of %lld tets (--max-error)", (long long)nt);
        for (int step = 0; step < field->step_count; step++) {
            float *to = values + (int64_t)step * per;
            const float *from = field->values + (int64_t)step * old;
            if (point) {
                memcpy(to, from, sizeof *to * (size_t)r->n0);
                int s = 0;
                while (s < r->slots && !(r->slot_field[s] == f && r->slot_values[s] == from))
                    s++;
                for (int64_t v = r->n0; v < nv; v++)
                    to[v] = r->added[(v - r->n0) * r->slots + s];
            } else {
                for (int64_t t = 0; t < nt; t++)
                    to[t] = from[r->root[t]];
            }
        }
        free(field->values);
        field->values = values;
    }
    free(m->tets), free(m->tet_source);
    m->tets = r->tets, m->tet_source = r->cell, m->tet_count = nt;
    r->tets = r->cell = NULL;
    return 0;
}

static void release(refine *r, int threads)
{
    free(r->vertex_of), free(r->cell_type), free(r->slot_values), free(r->slot_field), free(r->added), free(r->bound_slot);
    free(r->slot_allowed);
    free(r->bound_range), free(r->tets), free(r->cell), free(r->xi), free(r->xi_wide), free(r->root), free(r->field_error);
    free(r->geometry_error), free(r->worst_slot), free(r->todo), free(r->marked);
    free(r->bound_flags), free(r->xi_at), free(r->by_vertex.head), free(r->by_vertex.next);
    free(r->marks.keys), free(r->marks.values), free(r->mids.keys), free(r->mids.values);
    for (int w = 0; r->cache && w < threads; w++)
        free(r->cache[w].type), free(r->cache[w].key), free(r->cache[w].norm), free(r->cache[w].by_node),
            free(r->cache[w].value), free(r->cache[w].big), free(r->cache[w].finite), free(r->cache[w].rough),
            free(r->cache[w].form), free(r->cache[w].quad_node), free(r->cache[w].batch_gap), free(r->cache[w].pair_coef),
            free(r->cache[w].batch_ok);
    free(r->cache), free(r->departure);
    for (int n = 0; n <= TPK_BERNSTEIN_MAX_DEGREE; n++)
        free(r->inverse_t[n]), tpk_bernstein_free(&r->table[n]);
}

/* r->departure when a cell is a hexahedron: each set of 4 nodes' tet in parameter space, each monomial's
 * values at the domain points and the corners, through tpk_bernstein_gap (its margin included; the
 * monomials' own rounding, a few units in the last place of numbers up to 1, is under ROUGH_MARGIN). 256
 * sets. And r->node_pairs when a cell is a quadratic tetra. */
static int make_departures(refine *r)
{
    for (int which = 0; which < 2; which++) {
        int type = which ? 24 : 12, degree = tpk_cell_map_degree(type), n = tpk_cell_map_nodes(type), used = 0;
        for (int64_t c = 0; c < r->cells->cell_count && !used; c++)
            used = r->cell_type[c] == type;
        if (!used)
            continue;
        double probe[TPK_CELL_MAP_MAX_NONLINEAR], origin[3] = {0, 0, 0};
        int count = tpk_cell_map_nonlinear(type, origin, probe);
        for (int j = 0; j < n && type == 24; j++)
            for (int l = 0; l < n; l++) {
                double xi[12], w[4][10], m[6][6];
                tpk_cell_map_node(type, j, xi), tpk_cell_map_node(type, l, xi + 3);
                memcpy(xi + 6, xi, 3 * sizeof *xi), memcpy(xi + 9, xi, 3 * sizeof *xi);
                tpk_cell_map_quadratic_tet(type, xi, w, m);
                memcpy(r->node_pairs[j][l], m[0], sizeof m[0]); /* pair 0: corners 0 and 1 */
                r->node_terms[j][l] = 0;
                for (int q = 0; q < 6; q++)
                    if (m[0][q] != 0)
                        r->node_term[j][l][r->node_terms[j][l]++] = (uint8_t)q;
            }
        if (type == 24)
            continue;
        const tpk_bernstein *b = &r->table[degree];
        double *d = r->departure = malloc(sizeof *d * (size_t)count << n);
        if (!d)
            return -1;
        for (int set = 0; set < 1 << n; set++) {
            double *out = d + (int64_t)set * count, xi[4][3], e[3][3];
            int k = 0;
            for (int j = 0; j < n; j++)
                if (set >> j & 1 && k < 4)
                    tpk_cell_map_node(type, j, xi[k++]);
            out[0] = -1;
            if (k != 4 || __builtin_popcount((unsigned)set) != 4)
                continue;
            for (int a = 0; a < 3; a++)
                for (int i = 0; i < 3; i++)
                    e[a][i] = xi[a + 1][i] - xi[0][i];
            double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                         e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) + e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
            if (!(fabs(det) > 1e-9))
                continue; /* a flat tet of parameter space: no tet of a split */
            double corner[4][TPK_CELL_MAP_MAX_NONLINEAR], at[TPK_BERNSTEIN_MAX_POINTS][TPK_CELL_MAP_MAX_NONLINEAR];
            for (k = 0; k < 4; k++)
                tpk_cell_map_nonlinear(type, xi[k], corner[k]);
            for (int i = 0; i < b->points; i++) {
                double x[3] = {0, 0, 0};
                for (k = 0; k < 4; k++)
                    for (int a = 0; a < 3; a++)
                        x[a] += b->lambda[i][k] * xi[k][a];
                tpk_cell_map_nonlinear(type, x, at[i]);
            }
            for (int q = 0; q < count; q++) {
                double c[4] = {corner[0][q], corner[1][q], corner[2][q], corner[3][q]};
                out[q] = tpk_bernstein_gap(b, &at[0][q], TPK_CELL_MAP_MAX_NONLINEAR, c, 1) + ROUGH_MARGIN;
            }
        }
    }
    return 0;
}

static int set_up(refine *r, int threads)
{
    tpk_tetmesh *m = r->m;
    for (int64_t v = 0; v < m->vertex_count; v++)
        r->point_ids = m->vertex_source[v] >= r->point_ids ? m->vertex_source[v] + 1 : r->point_ids;
    if (!(r->vertex_of = malloc(sizeof *r->vertex_of * (size_t)(r->point_ids ? r->point_ids : 1))))
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    for (int64_t p = 0; p < r->point_ids; p++)
        r->vertex_of[p] = -1;
    for (int64_t v = 0; v < m->vertex_count; v++)
        if (m->vertex_source[v] >= 0 && r->vertex_of[m->vertex_source[v]] < 0)
            r->vertex_of[m->vertex_source[v]] = (int32_t)v;
    if (pick_fields(r) != 0)
        return -1;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < m->vertex_count; v++)
        for (int i = 0; i < 3; i++)
            lo[i] = fmin(lo[i], m->points[3 * v + i]), hi[i] = fmax(hi[i], m->points[3 * v + i]);
    r->diag_length = m->vertex_count ? sqrt(dist2(lo, hi)) : 1;
    if (!(r->diag_length > 0))
        r->diag_length = 1;
    if (!(r->cell_type = malloc(sizeof *r->cell_type * (size_t)(r->cells->cell_count ? r->cells->cell_count : 1))))
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    int checked[16], types = 0; /* the types whose nodes' points were checked: 1/3 does not fit float32 */
    for (int64_t c = 0; c < r->cells->cell_count; c++) {
        int type = r->cell_type[c] = mapped_type(r->cells, c), k = 0;
        while (k < types && checked[k] != type)
            k++;
        if (k < types || r->xi_wide)
            continue;
        if (types == 16 && xi_widen(r) != 0) /* more types than a mesh has: doubles at hand, to be safe */
            return -1;
        checked[types < 16 ? types++ : 0] = type;
        for (int j = 0, n = tpk_cell_map_nodes(type); j < n && !r->xi_wide; j++) {
            double p[3];
            tpk_cell_map_node(type, j, p);
            if (!xi_fits(p, 3) && xi_widen(r) != 0)
                return -1;
        }
    }
    int used[TPK_BERNSTEIN_MAX_DEGREE + 1] = {0}; /* the degrees of the cells here (a table of 6 takes ms) */
    for (int64_t c = 0; c < r->cells->cell_count; c++) {
        int degree = tpk_cell_map_degree(r->cell_type[c]);
        if (degree > 1 && degree <= TPK_BERNSTEIN_MAX_DEGREE)
            used[degree] = 1;
    }
    for (int n = 2; n <= TPK_BERNSTEIN_MAX_DEGREE; n++) {
        if (!used[n])
            continue;
        if (tpk_bernstein_make(n, &r->table[n]) != 0)
            return tpk_diag_fail(r->diag, "--max-error: the Bernstein table of degree %d is singular", n);
        int p = r->table[n].points;
        if (!(r->inverse_t[n] = malloc(sizeof *r->inverse_t[n] * (size_t)(p * p))))
            return tpk_diag_fail(r->diag, "out of memory for --max-error");
        for (int i = 0; i < p; i++)
            for (int j = 0; j < p; j++)
                r->inverse_t[n][j * p + i] = r->table[n].inverse[i * p + j];
    }
    if (make_departures(r) != 0)
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    /* the mesh's tets and their cells taken over, grown by realloc, not copied (hand_back gives them back;
     * on failure the mesh is left without them, as convert stops) */
    r->tets = m->tets, r->cell = m->tet_source, m->tets = m->tet_source = NULL;
    for (int f = 0; f < m->field_count && !r->root; f++)
        if (m->fields[f].association != TPK_ASSOC_POINT && !(r->root = malloc(sizeof *r->root)))
            return tpk_diag_fail(r->diag, "out of memory for --max-error");
    if (reserve_tets(r, m->tet_count) != 0)
        return -1;
    r->count = m->tet_count;
    for (int64_t t = 0; t < r->count; t++)
        r->marked[t] = 0;
    for (int64_t t = 0; r->root && t < r->count; t++)
        r->root[t] = t;
    todo_all(r);
    int size = 1; /* doubles per cached entry: the most any cell here needs */
    for (int64_t c = 0; c < r->cells->cell_count; c++) {
        int type = r->cell_type[c], degree = tpk_cell_map_degree(type);
        if (degree > 1 && degree <= DIRECT_DEGREE && r->table[degree].points * tpk_cell_map_nodes(type) > size)
            size = r->table[degree].points * tpk_cell_map_nodes(type);
    }
    int entries = 4096;
    while (entries > 64 && (int64_t)entries * size * (int64_t)sizeof(double) > (8 << 20))
        entries /= 2; /* at most 8 MiB a worker */
    if (!(r->cache = calloc((size_t)threads, sizeof *r->cache)))
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    for (int w = 0; w < threads; w++) {
        coef_cache *cc = &r->cache[w];
        cc->entries = entries, cc->size = size;
        cc->type = calloc((size_t)entries, sizeof *cc->type);
        cc->key = malloc(sizeof *cc->key * 12 * (size_t)entries);
        cc->norm = malloc(sizeof *cc->norm * (size_t)entries);
        cc->by_node = malloc(sizeof *cc->by_node * (size_t)size * (size_t)entries);
        cc->cell = -1;
        cc->value = malloc(sizeof *cc->value * TPK_CELL_MAP_MAX_NODES * (size_t)(r->bounded ? r->bounded : 1));
        cc->big = malloc(sizeof *cc->big * (size_t)(r->bounded ? r->bounded : 1));
        cc->finite = malloc((size_t)(r->bounded ? r->bounded : 1));
        cc->rough = malloc(sizeof *cc->rough * TPK_CELL_MAP_MAX_NONLINEAR * (size_t)(r->bounded ? r->bounded : 1));
        cc->form = malloc(sizeof *cc->form * TPK_CELL_MAP_MAX_NONLINEAR * (size_t)(r->bounded ? r->bounded : 1));
        cc->qc = (3 + r->bounded + 3) & ~3, cc->quad_cell = -1;
        cc->quad_node = malloc(sizeof *cc->quad_node * 21 * (size_t)cc->qc); /* 10 + 6 + 4 + 1 rows */
        cc->batch_gap = malloc(sizeof *cc->batch_gap * 20 * (size_t)(r->bounded ? r->bounded : 1)); /* + values */
        cc->batch_ok = malloc(sizeof *cc->batch_ok * 4 * (size_t)(r->bounded ? r->bounded : 1));
        cc->pair_coef = malloc(sizeof *cc->pair_coef * 100 * (size_t)cc->qc);
        cc->batch_value = cc->batch_gap ? cc->batch_gap + 4 * (size_t)(r->bounded ? r->bounded : 1) : NULL;
        if (!cc->type || !cc->key || !cc->norm || !cc->by_node || !cc->value || !cc->big || !cc->finite || !cc->rough ||
            !cc->form || !cc->quad_node || !cc->batch_gap || !cc->batch_ok || !cc->pair_coef)
            return tpk_diag_fail(r->diag, "out of memory for --max-error");
        cc->quad_a = cc->quad_node + 10 * cc->qc, cc->quad_v = cc->quad_a + 6 * cc->qc;
        cc->quad_largest = cc->quad_v + 4 * cc->qc;
    }
    return place_corners(r, threads, r->o->uniform_levels == 0); /* --subdivide reads every tet's points first */
}

/* The tets bounded roughly (rough_bound) whose rough bound exceeds the largest Bernstein bound met, in
 * field or geometry, bounded again through their Bernstein coefficients: so the largest bound reported
 * is that of the Bernstein bounds (or smaller, where a rough one is smaller), as before the rough ones,
 * and the same for any thread count. In batches from the top: those within half the largest rough bound
 * left, then those still above the largest Bernstein bound met; where nothing was cut (a loose bound),
 * the first batch usually settles it. */
static int exact_where_it_shows(refine *r)
{
    double field = -1, geometry = -1;
    for (int64_t t = 0; t < r->count; t++)
        if (!(r->bound_flags[t] & BOUND_ROUGH)) {
            field = r->field_error[t] > field ? r->field_error[t] : field;
            geometry = r->geometry_error[t] > geometry ? r->geometry_error[t] : geometry;
        }
    int64_t count = 0, *left = NULL;
    for (int64_t t = 0; t < r->count; t++)
        count += (r->bound_flags[t] & BOUND_ROUGH) && (r->field_error[t] > field || r->geometry_error[t] > geometry);
    if (count && !(left = malloc(sizeof *left * (size_t)count)))
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    count = 0;
    for (int64_t t = 0; t < r->count; t++)
        if ((r->bound_flags[t] & BOUND_ROUGH) && (r->field_error[t] > field || r->geometry_error[t] > geometry))
            left[count++] = t;
    r->exact = 1;
    while (count > 0) {
        double top_field = 0, top_geometry = 0;
        for (int64_t i = 0; i < count; i++) {
            top_field = r->field_error[left[i]] > top_field ? r->field_error[left[i]] : top_field;
            top_geometry = r->geometry_error[left[i]] > top_geometry ? r->geometry_error[left[i]] : top_geometry;
        }
        int64_t batch = 0, kept = 0;
        for (int64_t i = 0; i < count; i++) {
            int64_t t = left[i];
            if ((top_field > 0 && r->field_error[t] >= top_field / 2) ||
                (top_geometry > 0 && r->geometry_error[t] >= top_geometry / 2) || (top_field <= 0 && top_geometry <= 0))
                r->todo[batch++] = t; /* the top one at least: each batch takes one or more */
            else
                left[kept++] = t;
        }
        r->todo_every = 0, r->todo_count = batch;
        tpk_parallel_for(batch, tpk_threads_for(batch, r->threads, 1024), bound_range, r);
        for (int64_t i = 0; i < batch; i++) {
            int64_t t = r->todo[i];
            field = r->field_error[t] > field ? r->field_error[t] : field;
            geometry = r->geometry_error[t] > geometry ? r->geometry_error[t] : geometry;
        }
        count = 0;
        for (int64_t i = 0; i < kept; i++)
            if (r->field_error[left[i]] > field || r->geometry_error[left[i]] > geometry)
                left[count++] = left[i];
    }
    free(left);
    return 0;
}

/* The tets to bound (r->todo) put in the order of their cells (a counting sort, stable): bound_tet
 * gathers a cell's nodes and coefficients once for a run of its tets, and after a pass of cuts the tets
 * cut and their pieces, listed in tet order and then new, visit each cell more than once. Each tet's
 * bound does not depend on the order. */
static int todo_by_cell(refine *r)
{
    int64_t cells = r->cells->cell_count, n = r->todo_count;
    int64_t *start = calloc((size_t)cells + 1, sizeof *start), *sorted = malloc(sizeof *sorted * (size_t)(n ? n : 1));
    if (!start || !sorted) {
        free(start), free(sorted);
        return tpk_diag_fail(r->diag, "out of memory for --max-error");
    }
    for (int64_t i = 0; i < n; i++)
        start[r->cell[r->todo[i]] + 1]++;
    for (int64_t c = 0; c < cells; c++)
        start[c + 1] += start[c];
    for (int64_t i = 0; i < n; i++)
        sorted[start[r->cell[r->todo[i]]]++] = r->todo[i];
    memcpy(r->todo, sorted, sizeof *sorted * (size_t)n);
    free(start), free(sorted);
    return 0;
}

int tpk_refine_max_error(tpk_tetmesh *mesh, const tpk_refine_cells *cells, const tpk_refine_options *options,
                         tpk_refine_report *report, tpk_diag *diag)
{
    refine r;
    memset(&r, 0, sizeof r);
    memset(report, 0, sizeof *report);
    tpk_refine_options o = *options;
    if (o.max_tets <= 0 && o.uniform_levels > 0)
        o.max_tets = INT32_MAX;
    if (o.max_tets <= 0)
        o.max_tets = mesh->tet_count * 64 > (1 << 24) ? mesh->tet_count * 64 : (1 << 24);
    if (o.max_tets > INT32_MAX)
        o.max_tets = INT32_MAX;
    r.m = mesh, r.cells = cells, r.o = &o, r.diag = diag;
    r.n0 = r.vertex_cap = mesh->vertex_count;
    r.tets_given = mesh->tet_count;
    report->tets_before = mesh->tet_count;
    int threads = tpk_thread_count(o.threads), rc = set_up(&r, threads);
    r.threads = threads;
    r.exact = o.uniform_levels > 0; /* --subdivide reports its tets' bounds, however small */
    for (int level = 0; rc == 0 && level < o.uniform_levels; level++)
        rc = cut_all(&r);
    for (int pass = 0; rc == 0; pass++) {
        if (pass > 0)
            rc = todo_by_cell(&r);
        if (rc != 0)
            break;
        tpk_parallel_for(r.todo_count, tpk_threads_for(r.todo_count, threads, 1024), bound_range, &r);
        if (r.corners_unchecked) { /* the first bound found every corner a node, else they are placed now */
            int missed = 0;
            for (int w = 0; w < threads; w++)
                missed |= r.cache[w].missed;
            r.corners_unchecked = 0;
            if (missed && (rc = place_corners(&r, threads, 0)) != 0)
                break;
            if (missed) /* bounded again, from the points placed */
                tpk_parallel_for(r.todo_count, tpk_threads_for(r.todo_count, threads, 1024), bound_range, &r);
        }
        int64_t over = 0;
        for (int64_t i = 0; i < r.todo_count; i++)
            over += (r.bound_flags[todo_tet(&r, i)] & BOUND_OVER) != 0;
        report->rounds = pass;
        if (over == 0 || o.uniform_levels > 0)
            break;
        if (pass == MAX_PASSES) {
            rc = tpk_diag_fail(diag, "--max-error %g: %lld tets still over the bound after %d passes of refinement",
                               o.max_error, (long long)over, MAX_PASSES);
            break;
        }
        rc = refine_pass(&r);
    }
    if (rc == 0)
        rc = exact_where_it_shows(&r);
    if (rc == 0) {
        int worst = -1;
        for (int64_t t = 0; t < r.count; t++) {
            if (r.field_error[t] > report->field_error || (worst < 0 && r.worst_slot[t] >= 0))
                report->field_error = r.field_error[t], worst = r.worst_slot[t];
            report->geometry_error = fmax(report->geometry_error, r.geometry_error[t]);
        }
        if (worst >= 0)
            snprintf(report->worst_field, sizeof report->worst_field, "%s",
                     mesh->fields[r.slot_field[r.bound_slot[worst]]].name);
        report->fields_bounded = r.report_fields;
        report->tets_after = r.count;
        report->vertices_added = mesh->vertex_count - r.n0;
        rc = hand_back(&r);
    }
    release(&r, threads);
    return rc;
}
