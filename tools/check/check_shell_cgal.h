/* The one CGAL unit of the shell checks: which shell faces overlap or intersect (303 and 406), decided
 * exactly on CGAL's Epick kernel for the triangle pairs whose bounding boxes overlap.
 * check_shell_cgal.cpp defines tpk_shell_face_pairs; check_shell.c is its caller. */
#ifndef TPK_CHECK_SHELL_CGAL_H
#define TPK_CHECK_SHELL_CGAL_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A face of exactly one cell (the shell): a triangle or a quad. */
typedef struct tpk_bface {
    int32_t v[4];   /* outward order; v[3] = -1 for a triangle */
    uint32_t cell;
    uint32_t local; /* the face's index among its cell's faces */
} tpk_bface;

enum { TPK_PAIR_NONCONFORMING = 303, TPK_PAIR_INTERSECTING = 406 };

typedef struct tpk_shell_pair {
    uint32_t a, b; /* shell face indices, a < b */
    int kind;      /* TPK_PAIR_* */
} tpk_shell_pair;

/* Pairs of shell faces of different cells, with quads cut along the diagonal through their smallest id:
 *  - TPK_PAIR_NONCONFORMING: a triangle of each is coplanar with the other, they face opposite ways and
 *    their interiors overlap (positive area): a boundary face lies against another inside the volume;
 *  - TPK_PAIR_INTERSECTING (only when test_intersections): the faces share no vertex and a triangle of
 *    each intersects the other (CGAL::do_intersect), or they are coplanar, face the same way and overlap.
 * Faces that only touch along an edge or at a point, or share a vertex and are not coplanar, are no
 * pair. Triangles with a non-finite or collinear corner are skipped (the vertex and cell checks report
 * them). *pairs (malloc'd, sorted by a, b, kind, no repeats) and *pair_count are set; the result does
 * not depend on `threads` (>= 1). Returns 0, or -1 when out of memory. */
int tpk_shell_face_pairs(const double *points, const tpk_bface *faces, int64_t face_count,
                         int test_intersections, int threads, tpk_shell_pair **pairs, int64_t *pair_count);

#ifdef __cplusplus
}
#endif
#endif
