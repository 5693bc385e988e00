/* The map of a volume cell from VTK parametric coordinates: where its nodes sit, and the shape functions
 * that place a point (the geometry map) and value it (the field interpolant, the same functions: the
 * cells are isoparametric). The one place the tools evaluate a cell's own functions: the higher-order
 * split (mesh/higher_order.h) places and values the points it adds with them. */
#ifndef TPK_CELL_MAP_H
#define TPK_CELL_MAP_H

#include <stdint.h>

/* Most nodes a cell this module knows has (the order-10 Lagrange tetra's 286). */
#define TPK_CELL_MAP_MAX_NODES 286

/* VTK's Lagrange tetra (71) of order p, 3 <= p <= TPK_CELL_MAP_LAGRANGE_MAX_ORDER, is mapped as type
 * TPK_CELL_MAP_LAGRANGE_TETRA + p (its degree p fits the Bernstein tables of mesh/bernstein.h, up to
 * 12); orders 2 and 15 nodes are the quadratic tetra's numbering, mapped as type 24 by the callers. */
#define TPK_CELL_MAP_LAGRANGE_TETRA 7100
#define TPK_CELL_MAP_LAGRANGE_MAX_ORDER 10
/* VTK's Lagrange hexahedron (72) of order p: TPK_CELL_MAP_LAGRANGE_HEX + p, p = 3 and 4 (degree 3 p); order 2
 * is the triquadratic hexahedron's numbering (type 29). */
#define TPK_CELL_MAP_LAGRANGE_HEX 7200
#define TPK_CELL_MAP_LAGRANGE_HEX_MAX_ORDER 4
/* VTK's Lagrange wedge (73) of order p: TPK_CELL_MAP_LAGRANGE_WEDGE + p, p = 3..6 (degree 2 p). */
#define TPK_CELL_MAP_LAGRANGE_WEDGE 7300
#define TPK_CELL_MAP_LAGRANGE_WEDGE_MAX_ORDER 6

/* The type this module maps a source cell of VTK type `type` with n nodes as: type itself, or
 * TPK_CELL_MAP_LAGRANGE_TETRA + p for a Lagrange tetra of order p = 3..TPK_CELL_MAP_LAGRANGE_MAX_ORDER
 * ((p+1)(p+2)(p+3)/6 nodes), TPK_CELL_MAP_LAGRANGE_HEX + p for a Lagrange hexahedron of order
 * p = 3..TPK_CELL_MAP_LAGRANGE_HEX_MAX_ORDER ((p+1)^3 nodes), TPK_CELL_MAP_LAGRANGE_WEDGE + p for a
 * Lagrange wedge of order p = 3..TPK_CELL_MAP_LAGRANGE_WEDGE_MAX_ORDER ((p+1)^2(p+2)/2 nodes). */
int tpk_cell_map_type(int type, int64_t n);

/* The type whose map and interpolant a source cell of VTK type `type` with n nodes has, for everything
 * that measures a cell (convert --max-error, check --against): voxels as hexahedra, VTK's Lagrange cells
 * of order 2 as the quadratic ones (which number their nodes alike: mesh/higher_order.c), higher orders
 * as tpk_cell_map_type says; 0 where this module has no functions for it (tpk_cell_map_degree says
 * which of them are polynomials, as --max-error needs: not pyramids). Node k of that type is the
 * cell's node tpk_cell_map_source_node(type, k) (a voxel's corners 2, 3 and 6, 7 swapped). */
int tpk_cell_map_source_type(int type, int64_t n);
int tpk_cell_map_source_node(int type, int k);

/* The node of lattice point (i, j, k), i + j + k <= p, of an order-p Lagrange tetra (parametric point
 * (i, j, k) / p) in VTK 9's numbering (vtkHigherOrderTetra); the higher-order split uses it too. */
int tpk_cell_map_lagrange_tet_node(int p, int i, int j, int k);

/* The node of lattice point (i, j, k), 0 <= i, j, k <= p, of an order-p Lagrange hexahedron (parametric
 * point (i, j, k) / p) in VTK 9's numbering (vtkHigherOrderHexahedron::PointIndexFromIJK): the 8 corners;
 * the 12 edges' inner points, each edge in increasing parametric order, the edges as the triquadratic
 * hexahedron lists its mid-edges (bottom 01 12 32 03, top likewise, then the vertical edges at corners 0,
 * 1, 2, 3); the faces' (r = 0, r = 1, s = 0, s = 1, t = 0, t = 1, each with its lower axis fastest); then
 * the body's (r fastest). For p = 2 this is the 27-node numbering. The higher-order split uses it too. */
int tpk_cell_map_lagrange_hex_node(int p, int i, int j, int k);

/* The node of lattice point (i, j, k), i + j <= p, 0 <= k <= p, of an order-p Lagrange wedge (parametric
 * point (i, j, k) / p) in VTK 9's numbering (vtkHigherOrderWedge). */
int tpk_cell_map_lagrange_wedge_node(int p, int i, int j, int k);

/* The node count of a type this module maps, or 0: tetra (10), hexahedron (12), wedge (13), pyramid
 * (14), quadratic tetra (24), quadratic hexahedron (25, serendipity), quadratic wedge (26), quadratic
 * pyramid (27), triquadratic hexahedron (29), quadratic linear wedge (31), biquadratic quadratic wedge
 * (32), biquadratic quadratic hexahedron (33), Lagrange tetra, hexahedron and wedge of order p
 * (TPK_CELL_MAP_LAGRANGE_TETRA, _HEX or _WEDGE + p). */
int tpk_cell_map_nodes(int type);

/* The total degree of the type's shape functions as polynomials of the parametric coordinates (so on
 * any tet of its parameter space, in the tet's barycentric coordinates): tetra 1, wedge 2, hexahedron
 * 3, quadratic tetra 2, quadratic (26) and quadratic-linear (31) wedge 3, serendipity hexahedron and
 * biquadratic wedge 4, biquadratic-quadratic hexahedron 5, triquadratic hexahedron 6, Lagrange tetra of
 * order p p, Lagrange hexahedron of order p 3 p, Lagrange wedge of order p 2 p; 0 for the pyramids (a
 * collapsed hexahedron and a rational function, neither a polynomial on the pyramid's tets) and types
 * this module does not map. */
int tpk_cell_map_degree(int type);

/* VTK parametric coordinates of node k (0 <= k < tpk_cell_map_nodes(type)) into r: corners as
 * tpk_cell_shape's ref, mid-edge, mid-face and mid-cell nodes the means of their corners (a Lagrange
 * tetra's, hexahedron's or wedge's node at lattice point (i, j, k) at (i, j, k) / p). */
void tpk_cell_map_node(int type, int k, double r[3]);

/* The shape functions at parametric point r into w (tpk_cell_map_nodes(type) values, summing to 1;
 * w[k] is 1 at node k and 0 at the others). Returns the node count, or 0 for a type this module does not
 * map. Weights of nodes off a face are 0 on that face for every type here (exactly, on a quad face at its
 * centre), so a point on a face depends only on the face's nodes. The quadratic types reproduce every
 * quadratic polynomial of the parametric coordinates; the order-p Lagrange tetra's, the standard
 * barycentric Lagrange basis l_a(L0) l_b(L1) l_c(L2) l_d(L3), l_m(L) = prod_{q<m} (p L - q) / (q + 1), every
 * polynomial of degree p; the order-p Lagrange wedge's, the order-p triangle's basis in (L0, L1, L2) times
 * the 1-D one in t; the order-p Lagrange hexahedron's, the product of the 1-D ones in r, s and t
 * (l_i(r) = prod_{q != i} (p r - q) / (i - q)). */
int tpk_cell_map_weights(int type, const double r[3], double *w);

/* The nonlinear monomials of the type's functions, so that every interpolant f of node values is an
 * affine function of the parametric coordinates plus sum_q a_q m_q: hexahedron (12) xy, yz, zx, xyz;
 * quadratic tetra (24) L_i L_j for its 6 edges (i, j) in node order (f = affine + sum (4 f_ij - 2 f_i -
 * 2 f_j) L_i L_j, with L the barycentric coordinates). tpk_cell_map_nonlinear writes the monomials' values
 * at r into m, tpk_cell_map_nonlinear_coefficients the a_q of node values v (comps numbers a node, node
 * k's at v + k * comps) into a (a[q * comps + c]); both return the count (4, 6), or 0 for other types.
 * convert --max-error bounds f - L on a tet whose corners are nodes by sum_q |a_q| max|m_q - L m_q|. */
#define TPK_CELL_MAP_MAX_NONLINEAR 6
int tpk_cell_map_nonlinear(int type, const double r[3], double *m);
int tpk_cell_map_nonlinear_coefficients(int type, const double *v, int comps, double *a);

/* The quadratic tetra (24) on a tet of its parameter space with corners xi (4 points, 12 numbers): the
 * nodes' weights at each corner (w[k], as tpk_cell_map_weights), and the nonlinear monomials L_i L_j at the
 * barycentric difference r_k - r_l of each pair of corners (m[p], pairs 01, 02, 03, 12, 13, 23; the
 * difference's coordinates sum to 0). Returns 10, or 0 for other types. The monomials are homogeneous of
 * degree 2 in L, so f's blossom at r_k and r_l, the Bernstein coefficient of f on the tet's edge (k, l),
 * is (f(r_k) + f(r_l)) / 2 - sum_q a_q m[p][q] / 2 (a: tpk_cell_map_nonlinear_coefficients). */
int tpk_cell_map_quadratic_tet(int type, const double *xi, double (*w)[10], double (*m)[6]);

/* The point the cell with nodes `nodes` (ids into `points`, 3 doubles each) maps r to: sum w[k] x_k in
 * node order. Returns 0, or -1 as tpk_cell_map_weights. */
int tpk_cell_map_point(int type, const int32_t *nodes, const double *points, const double r[3], double x[3]);

#endif
