/* Private to tools/extract/. Owners: extract.c (tpk_extract: the file in, the chunks out),
 * extract_subset.c (the kept tets: selection, renumbering, neighbours and shell by the converter's
 * stages). */
#ifndef TPK_EXTRACT_INTERNAL_H
#define TPK_EXTRACT_INTERNAL_H

#include "extract.h"

/* The kept part of a mesh, renumbered: new ids follow the old order. */
typedef struct tpk_subset {
    int64_t tet_count, vertex_count;
    int32_t *tet_old;    /* new tet -> old tet */
    int32_t *vertex_old; /* new vertex -> old vertex */
    int32_t *tets;       /* 4 per tet, new vertex ids, positively oriented (as recovered) */
    int32_t *neighbors;  /* 4 per tet: tpk_connect's, with folds cut as the source cut them */
    float *positions;    /* 3 per vertex, the source's stored values */
} tpk_subset;

/* Keep the tets of `mesh` (vertex quadruples `tets`, from tpk_recover_tets) that meet the clip box
 * (all without one), renumber, connect. 0, or -1 with a message (out of memory, no tet kept). */
int tpk_subset_build(const tpk_mesh_arrays *mesh, const int32_t *tets, const tpk_extract_options *options,
                     tpk_subset *out, tpk_diag *diag);
void tpk_subset_free(tpk_subset *subset);

#endif
