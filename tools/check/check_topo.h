/* Internal to the connectivity (3xx) and shell (4xx) checks: the faces of volume cells, the face
 * matching, the shell (faces of exactly one cell) and the shared union-find.
 *
 * Who defines what. check_topology.c, the entry (tpk_check_topology, check.h), sits on top and calls
 * check_topo_match.c (tpk_topo_match_faces, tpk_topo_match_free) and check_shell.c (tpk_check_shell),
 * which calls check_topo_shell_edges.c (tpk_check_shell_edges) and check_shell_cgal.cpp. At the bottom
 * check_topo_faces.c holds what they share: tpk_topo_cell_faces, tpk_topo_cell_face,
 * tpk_topo_face_count, tpk_topo_face_triangle, tpk_topo_face_centre,
 * tpk_topo_orient, tpk_uf_find, tpk_uf_union, and tpk_check_cell_usable (declared in check.h). */
#ifndef TPK_CHECK_TOPO_H
#define TPK_CHECK_TOPO_H

#include <stdint.h>

#include "check.h"
#include "check_shell_cgal.h"
#include "tetpack_format.h" /* tpk_tet_faces */

/* Faces of up to 32 vertices, cells of up to 64 faces: the polyhedra of snappyHexMesh and foamToVTK
 * (quads whose edges carry the points of finer neighbours) fit; a cell beyond either is left out of the
 * checks (the rest of the mesh is still checked). The matching keys a face by its smallest four ids and
 * a hash of the rest, and compares polygons of more than four vertices in full (check_topo_match.c);
 * the shell keeps triangles and quads as they are and cuts larger polygons about their centre. */
#define TPK_TOPO_MAX_FACE_VERTS 32
#define TPK_TOPO_MAX_CELL_FACES 64 /* the local face index is stored in 16 bits */

typedef struct tpk_topo_face {
    int n;                                /* 3 to TPK_TOPO_MAX_FACE_VERTS */
    int32_t v[TPK_TOPO_MAX_FACE_VERTS];   /* outward order (VTK cell faces, right-hand rule) */
} tpk_topo_face;

/* The faces of cell `cell` in outward order (outward for a positively oriented cell, the convention
 * of cell_split.c), or 0 when the cell is not a volume cell the checks handle. Ids are not checked:
 * callers use cells for which tpk_check_cell_usable() holds. */
int tpk_topo_cell_faces(const tpk_mesh *mesh, int64_t cell, tpk_topo_face *faces);

/* Face `local` of a volume cell (local < tpk_topo_face_count), as tpk_topo_cell_faces gives it. */
void tpk_topo_cell_face(const tpk_mesh *mesh, int64_t cell, int local, tpk_topo_face *face);

/* The number of faces tpk_topo_cell_faces gives, without building them. */
int tpk_topo_face_count(const tpk_mesh *mesh, int64_t cell);

/* Smallest id of a face, and the index of it in v[]. */
static inline int tpk_topo_min_index(const tpk_topo_face *f)
{
    int best = 0;
    for (int i = 1; i < f->n; i++)
        if (f->v[i] < f->v[best])
            best = i;
    return best;
}

/* Triangle t (0, or 1 for quads) of the split along the diagonal through the smallest id, the split
 * the converter uses, in the face's own (outward) order. */
void tpk_topo_face_triangle(const tpk_topo_face *f, int t, int32_t tri[3]);

/* Centre (vertex average) of a face, for example locations. */
void tpk_topo_face_centre(const double *points, const tpk_topo_face *f, double out[3]);

/* Union-find over uint32 ids, safe to call concurrently (links the larger root to the smaller with a
 * compare-and-swap, so the partition and each set's smallest-id root do not depend on timing). */
uint32_t tpk_uf_find(uint32_t *parent, uint32_t x);
void tpk_uf_union(uint32_t *parent, uint32_t a, uint32_t b);
#define TPK_UF_NONE UINT32_MAX /* marks an element outside every set */

static inline int tpk_bface_n(const tpk_bface *f)
{
    return f->v[3] < 0 ? 3 : 4;
}

/* The result of face matching (check_topo_match.c). */
typedef struct tpk_topo_match {
    uint32_t *parent;        /* union-find over cells: TPK_UF_NONE for cells the checks skip */
    tpk_bface *shell;   /* boundary faces, in the order of their sorted vertex ids */
    int64_t shell_count;
    /* The points the shell's ids index: the mesh's, then the centres of the boundary polygons of more
     * than 4 vertices, which the shell cuts into triangles about their centre as OpenFOAM does (a fan
     * from a corner can fold a non-planar polygon over its neighbour). */
    const double *points;
    int64_t point_count;
    double *own_points;      /* points, when centres were added */
} tpk_topo_match;

/* Matches the faces of all usable volume cells (sort-based, multithreaded, deterministic), reports
 * 301 nonmanifold_face, 302 inconsistent_orientation and 305 folded_face, unions the cells of every
 * shared face and collects the shell. Returns 0, or -1 (diag set) when out of memory or past the
 * 2^31 - 1 cell limit. */
int tpk_topo_match_faces(const tpk_mesh *mesh, tpk_check_report *report, tpk_topo_match *out,
                         tpk_diag *diag);
void tpk_topo_match_free(tpk_topo_match *m);

/* 303 nonconforming_face (unions the cells of every nonconforming pair) and 401..406 on the shell. */
int tpk_check_shell(const tpk_mesh *mesh, tpk_topo_match *m, tpk_check_report *report, tpk_diag *diag);

/* 401, 402, 403, 404 and 405 on the shell's polygons (quads as quads: the combinatorial checks do not
 * depend on how a quad would be cut). */
int tpk_check_shell_edges(const tpk_topo_match *m, tpk_check_report *report,
                          tpk_diag *diag);

/* Sign of orient3d (exact: the static filter, then CGAL). */
int tpk_topo_orient(const double *points, int32_t a, int32_t b, int32_t c, int32_t d);

#endif
