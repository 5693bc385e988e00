/* One cell tetrahedralized inside its fixed boundary triangulation (TetGen's -pY: no point added on the
 * boundary, Steiner points allowed inside): the last resort of tools/convert/steiner.c for cells that
 * neither a centre point nor face-centre points split into positive tets. */
#ifndef TPK_FIXED_BOUNDARY_H
#define TPK_FIXED_BOUNDARY_H

#include <stddef.h>
#include <stdint.h>

typedef struct tpk_fixed_tets {
    int32_t point_count; /* the input points first, unchanged, then the interior points added */
    double *points;      /* 3 * point_count */
    int64_t tet_count;
    int32_t *tets;       /* 4 * tet_count; det[b-a, c-a, d-a] > 0, decided exactly */
} tpk_fixed_tets;

/* 1 when this build can tetrahedralize inside a fixed boundary (it has TetGen), else 0. */
int tpk_fixed_boundary_available(void);

/* 0 when no two of `triangles` cross (they meet only along shared edges and corners), 1 with `why` naming
 * two that do (or saying that this build has no TetGen to tell), -1 when out of memory. TetGen's -d. */
int tpk_fixed_boundary_crossing(const double *points, int32_t point_count, const int32_t *triangles,
                                int32_t triangle_count, char *why, size_t why_cap);

/* 1 when two of `triangles` surely cross: an edge of one (the edge opposite the corner they share, if they
 * share one) passes through the other's interior, every sign of the test nonzero; or, sharing an edge,
 * they fold onto each other (one plane, the same side of the edge). Decided exactly, in-process: a search
 * of cuts asks this first, where each TetGen -d runs in a child process. 0 does not mean that none cross
 * (ask tpk_fixed_boundary_crossing). Coordinates past 1e100 in size give 0 (exact signs could overflow). */
int tpk_fixed_boundary_surely_crosses(const double *points, int32_t point_count, const int32_t *triangles,
                                      int32_t triangle_count);

/* Tetrahedralize the region enclosed by `triangles` (3 ids each into points[0 .. point_count), a closed
 * surface, outward: (b-a)x(c-a) points out). The result is checked, not trusted: every tet positive
 * (exact predicate), the input points kept in place, and the faces used by one tet only exactly the input
 * triangles (so the cells on the other side still match, and the cell's volume is kept). Returns 0 with
 * *out filled (free with tpk_fixed_tets_free); 1 with `why` when it cannot (no TetGen, crossing triangles,
 * TetGen failed, or its result fails a check); -1 when out of memory. Not thread-safe (TetGen). */
int tpk_fixed_boundary_tets(const double *points, int32_t point_count, const int32_t *triangles,
                            int32_t triangle_count, tpk_fixed_tets *out, char *why, size_t why_cap);
void tpk_fixed_tets_free(tpk_fixed_tets *tets);

#endif
