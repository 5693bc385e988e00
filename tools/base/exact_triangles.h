/* Exact triangle tests behind a C interface (CGAL, exact_triangles.cpp), for check's faces that cross
 * (207) and convert's search of cuts (fixed_boundary.c). Triangles are closed point sets; a degenerate
 * (collinear) triangle never meets anything here: callers report degenerate cells by other checks. */
#ifndef TPK_EXACT_TRIANGLES_H
#define TPK_EXACT_TRIANGLES_H

#ifdef __cplusplus
extern "C" {
#endif

int tpk_exact_triangles_meet(const double *a, const double *b, const double *c, const double *d,
                             const double *e, const double *f);
int tpk_exact_segment_meets_triangle(const double *p, const double *q, const double *a, const double *b,
                                     const double *c);
/* For coplanar u, v, p, q with u, v, p not collinear: +1 when p and q lie on the same side of line uv,
 * -1 on opposite sides, 0 when q is on the line; 2 when the four points are not coplanar. */
int tpk_exact_coplanar_side(const double *u, const double *v, const double *p, const double *q);

#ifdef __cplusplus
}
#endif

#endif
