/* What the tools know about each VTK cell type, in one table shared by the importers (which keep,
 * reduce or drop cells) and the tetrahedralizer (which splits them), and the shape of each linear
 * volume cell (corners, outward faces, edges), shared by the converter's split and the checker. */
#ifndef TPK_CELL_TYPES_H
#define TPK_CELL_TYPES_H

#include <stdint.h>

#include "base/diag.h"

typedef struct tpk_cell_type_info {
    int type;          /* VTK cell type code */
    const char *name;  /* in words, as VTK names it */
    int dim;           /* 0..3 */
    int nodes;         /* exact node count; 0: any (poly vertex, polygon, polyhedron); -k: at least k
                          (arbitrary-order Lagrange and Bezier cells) */
    int linear_type;   /* the linear cell of the same shape: the type itself for linear cells */
    int corners;       /* node count of that linear cell: a higher-order cell's first `corners` nodes */
} tpk_cell_type_info;

/* The entry for a VTK cell type, or NULL for a type the tools do not know. */
const tpk_cell_type_info *tpk_cell_type(int type);

/* What an importer does with a cell type: volumes are kept (higher-order ones whole, with all their
 * nodes in VTK order: mesh/higher_order.h splits or reduces them), everything of lower dimension dropped;
 * VTK's convex point set (41) and codes the table does not know are unknown (an error). */
enum { TPK_RULE_UNKNOWN, TPK_RULE_DROP, TPK_RULE_KEEP };

typedef struct tpk_cell_rule {
    int kind;          /* TPK_RULE_* */
    int nodes;         /* node count the cell must have when > 0; at least -nodes when < 0; any when 0 */
    unsigned char out_type;  /* the type it is stored as (its own) */
    const char *name;
} tpk_cell_rule;

tpk_cell_rule tpk_cell_rule_for(int type);

/* A linear volume cell in VTK node order: the one owner of its faces and edges (a tet's faces are
 * format/tetpack_format.h's TPK_TET_FACE_LIST, face k opposite corner k). */
typedef struct tpk_cell_shape {
    int type;          /* VTK type: tetra, voxel, hexahedron, wedge or pyramid */
    int corners;       /* vertex count */
    int face_count;    /* at most 6 */
    int face_size[6];  /* 3 or 4 */
    int faces[6][4];   /* local corners of each face, outward (right-hand rule) on a positive cell */
    int edge_count;    /* at most 12 */
    int edges[12][2];  /* local corners of each edge */
    double ref[8][3];  /* VTK parametric coordinates of the corners: a valid, positively oriented cell */
} tpk_cell_shape;

/* The shape of a tetra, voxel, hexahedron, wedge or pyramid; NULL for any other type. */
const tpk_cell_shape *tpk_cell_shape_of(int type);

/* The faces of a voxel, hexahedron, wedge or pyramid as global-id polygons, outward when the cell is not
 * mirrored (VTK node order): face f is ids[starts[f] .. starts[f+1]). Returns the face count (at most 6;
 * `ids` holds 24, `starts` 7), or 0 for another type (a tet too: its faces are tpk_tet_faces). */
int tpk_cell_faces(int type, const int32_t *nodes, int32_t *ids, int *starts);

/* Has tet v (ids into points, x y z each) a dihedral angle under TPK_FLAT_TET_DEG (mesh.h), or no
 * volume? What convert counts as flat_tets among the tets it splits cells into. */
int tpk_tet_is_flat(const double *points, const int32_t v[4]);

/* One warning "NAME: WHAT TOTAL cells (n1 type1, n2 type2, ...)" from per-type counts (256 entries). */
void tpk_warn_cell_counts(tpk_diag *diag, const char *name, const int64_t *by_type, int64_t total,
                          const char *what);

#endif
