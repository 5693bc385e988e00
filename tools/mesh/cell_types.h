/* What the tools know about each VTK cell type, in one table shared by the importers (which keep,
 * reduce or drop cells) and the tetrahedralizer (which splits them). */
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

/* What an importer does with a cell type: volumes are kept, higher-order volumes reduced to their
 * corners, everything of lower dimension dropped; VTK's convex point set (41) and codes the table does
 * not know are unknown (an error). */
enum { TPK_RULE_UNKNOWN, TPK_RULE_DROP, TPK_RULE_KEEP, TPK_RULE_REDUCE };

typedef struct tpk_cell_rule {
    int kind;          /* TPK_RULE_* */
    int nodes;         /* node count the cell must have when > 0; at least -nodes when < 0; any when 0 */
    unsigned char out_type;  /* the type it is stored as */
    int out_nodes;     /* the nodes it keeps (its first ones) */
    const char *name;
} tpk_cell_rule;

tpk_cell_rule tpk_cell_rule_for(int type);

/* One warning "NAME: WHAT TOTAL cells (n1 type1, n2 type2, ...)" from per-type counts (256 entries). */
void tpk_warn_cell_counts(tpk_diag *diag, const char *name, const int64_t *by_type, int64_t total,
                          const char *what);

#endif
