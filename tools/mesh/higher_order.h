/* Higher-order volume cells (quadratic and triquadratic tetra, hexahedra, wedges, pyramids) as the
 * importers keep them, in VTK node order: reduced to their corners, or split whole into linear cells at
 * their own nodes (docs/ARCHITECTURE.md §5). */
#ifndef TPK_HIGHER_ORDER_H
#define TPK_HIGHER_ORDER_H

#include <stdint.h>

#include "base/diag.h"
#include "mesh.h"

/* A volume cell of higher order (any VTK type whose linear cell differs from it, of dimension 3). */
int tpk_is_higher_order_volume(int type);

/* Every higher-order volume cell reduced to its corners (its first nodes, the linear cell's), in place;
 * its other nodes stay points that no cell uses. With any reduced, one warning "NAME: reduced
 * higher-order cells to their corner nodes: N cells (n1 type1, ...)". Returns the count reduced. */
int64_t tpk_reduce_higher_order(tpk_mesh *mesh, const char *name, tpk_diag *diag);

/* What tpk_split_higher_order did. */
typedef struct tpk_higher_split {
    int64_t split_cells;      /* cells split whole */
    int64_t reduced_cells;    /* higher-order cells of a type not split (Lagrange pyramids, Lagrange cells
                                 of orders over 10 or anisotropic, Bezier cells): reduced to corners */
    int64_t added_points;     /* face and cell centres the cells lack, appended after the source points */
    int64_t source_points;    /* the point count before: points from here on are added */
    int64_t source_cells;     /* the cell count before */
    int32_t *cell_source;     /* per cell of the new mesh, its cell in the old one (malloc'ed); NULL
                                 when no cell was split (the mesh is then unchanged but for reductions) */
} tpk_higher_split;

/* Each quadratic tetra (24), quadratic, triquadratic and biquadratic-quadratic hexahedron (25, 29, 33),
 * quadratic, quadratic-linear and biquadratic-quadratic wedge (26, 31, 32), quadratic and triquadratic
 * pyramid (27, 37), Lagrange tetra, hexahedron and wedge of order 2 (71, 72, 73 with 10, 27, 18 nodes:
 * as 24, 29, 32), and Lagrange tetra, hexahedra and wedges of order p = 3..10 ((p+1)(p+2)(p+3)/6,
 * (p+1)^3 and (p+1)^2(p+2)/2 nodes, VTK 9's numbering: into p^3 tetra (the lattice's small tetra, and
 * its octahedra cut along their shortest diagonals), p^3 hexahedra, p^3 wedges) replaced by the linear
 * cells of its own node lattice: a tetra by 8 tetra (the inner octahedron cut along its shortest
 * diagonal), a hexahedron by 8 hexahedra, a wedge by 8 (31: 4) wedges, a pyramid by 6 pyramids and 4
 * tetra (37: its inner upside-down pyramid coned from its centroid, its sides' middle quarters fanned
 * about their centres). The importers keep two more kinds with face centres: a quadratic tetra of 14
 * nodes (24: the 10, then the centres of faces 012, 013, 123, 023; Exodus's TETRA14) into 16 tetra, the
 * 15-node Lagrange tetra (71: those and the body centre; VTK's and Exodus's TETRA15) into 20, each
 * face's middle quarter fanned about its centre; a quadratic pyramid of 14 nodes (27: the 13, then the
 * base centre; Exodus's PYRAMID14, CGNS's PYRA_14, gmsh's 14-node pyramid) as the 13-node one with its
 * own base centre. Every node is a corner of some linear cell. Points a cell lacks (a 20-node
 * hexahedron's face and cell centres, a 24-node one's z faces' and cell centres, a 15-node wedge's
 * quad-face centres, a 13-node pyramid's base centre) are placed and valued (every point field, every
 * step) by the cell's own shape functions (mesh/cell_map.h); a face centre is made once per face (keyed
 * by the face's corner ids, or the face's own centre node where a neighbour has one), so both cells on a
 * face use the same point with the same value. The linear cells' quad faces are then cut by the
 * converter's smallest-id rule, the same from both sides: the mesh stays conforming. A triangular face
 * with a centre node is conforming only with neighbours that have one too (a 10-node tetra beside a
 * 14-node one is not). Cell fields are copied to each linear cell of a cell. Other higher-order cells
 * are reduced to corners (warned, naming `name`). Returns 0, or -1 with a message (out of memory, a cell
 * with the wrong node count). */
int tpk_split_higher_order(tpk_mesh *mesh, const char *name, tpk_higher_split *out, tpk_diag *diag);

#endif
