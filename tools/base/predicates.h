/* Exact geometric predicates for the converter and validator: a double-precision filter with a static
 * error bound (inline, below) in front of CGAL's exact orientation (predicates.cpp, the one CGAL unit).
 * tpk_orient3d_exact is the entry point for everything else (converter, mesher, validator). */
#ifndef TPK_PREDICATES_H
#define TPK_PREDICATES_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Exact orientation sign of four points: +1, 0, -1 for det[b-a, c-a, d-a] (filter, then CGAL). */
int tpk_orient3d_exact(const double a[3], const double b[3], const double c[3], const double d[3]);

/* Sign (+1, 0, -1) of det[b-a, c-a, d-a] decided by CGAL (Epick), no filter of ours in front. */
int tpk_orient3d_cgal(const double a[3], const double b[3], const double c[3], const double d[3]);

/* Signs of `count` tets at once: signs[i] = sign of det[p1-p0, p2-p0, p3-p0] for the four points
 * points[3*tets[4*i+k]]. Uses the filter below and CGAL only where the filter is uncertain.
 * Returns how many tets needed the exact fallback. Ids must be in range (not checked). */
int64_t tpk_orient3d_batch(const double *points, const int32_t *tets, int64_t count, int8_t *signs);

/* Double-precision filter for det[b-a, c-a, d-a] (the same expression Shewchuk's orient3d uses, with
 * `a` as the translation point; his bound (7 + 56 eps) eps times the permanent covers the rounding of the
 * differences, products and sums). Returns +1/-1 when the sign is certain, 0 when it is not (including
 * near-zero magnitudes where underflow would void the bound, and inf/NaN). */
static inline int tpk_orient3d_filter(const double a[3], const double b[3], const double c[3],
                                      const double d[3])
{
    const double eps = 1.1102230246251565e-16; /* 2^-53 */
    const double bound_factor = (7.0 + 56.0 * eps) * eps;
    double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
    double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
    double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
    double cydz = cy * dz, czdy = cz * dy;
    double czdx = cz * dx, cxdz = cx * dz;
    double cxdy = cx * dy, cydx = cy * dx;
    double det = bx * (cydz - czdy) + by * (czdx - cxdz) + bz * (cxdy - cydx);
    double permanent = (cydz < 0 ? -cydz : cydz) + (czdy < 0 ? -czdy : czdy);
    permanent *= bx < 0 ? -bx : bx;
    double p2 = (czdx < 0 ? -czdx : czdx) + (cxdz < 0 ? -cxdz : cxdz);
    permanent += p2 * (by < 0 ? -by : by);
    double p3 = (cxdy < 0 ? -cxdy : cxdy) + (cydx < 0 ? -cydx : cydx);
    permanent += p3 * (bz < 0 ? -bz : bz);
    double bound = bound_factor * permanent;
    /* Below ~1e-280 products may have underflowed and the relative bound no longer holds; above 1e300
     * they may overflow. Both go to the exact path (so do NaN and inf, which fail every comparison). */
    if (!(permanent > 1e-280) || !(permanent < 1e300))
        return 0;
    if (det > bound)
        return 1;
    if (-det > bound)
        return -1;
    return 0;
}

#ifdef __cplusplus
}
#endif
#endif
