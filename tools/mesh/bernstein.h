/* Bernstein-Bezier bounds on a tetrahedron (docs/ARCHITECTURE.md §5): a polynomial p of total degree n in
 * the barycentric coordinates of a tet is sum_i c_i B_i with the Bernstein polynomials B_i >= 0, sum 1, so
 * |p| <= max_i |c_i| over the whole tet (the convex-hull property). The coefficients come from p's values
 * at the degree-n domain points (barycentric alpha / n, |alpha| = n) through the inverse of the
 * collocation matrix, computed once per degree. convert --max-error bounds |f - L| this way, f the
 * source cell's map or interpolant on a tet of its parameter space and L the tet's linear one. */
#ifndef TPK_BERNSTEIN_H
#define TPK_BERNSTEIN_H

#define TPK_BERNSTEIN_MAX_DEGREE 6
#define TPK_BERNSTEIN_MAX_POINTS 84 /* (n + 1)(n + 2)(n + 3) / 6 at n = 6 */

typedef struct tpk_bernstein {
    int degree, points;
    double lambda[TPK_BERNSTEIN_MAX_POINTS][4]; /* domain point i: barycentric alpha_i / n */
    double lambda_by_corner[4][TPK_BERNSTEIN_MAX_POINTS]; /* the same, transposed */
    double inverse[TPK_BERNSTEIN_MAX_POINTS * TPK_BERNSTEIN_MAX_POINTS]; /* coefficients = inverse x values */
    double inverse_norm;                      /* its infinity norm (rows' absolute sums), for the margin */
} tpk_bernstein;

/* The table of degree n (1 <= n <= TPK_BERNSTEIN_MAX_DEGREE) into t. Returns 0, or -1 for another n. */
int tpk_bernstein_make(int n, tpk_bernstein *t);

/* The bound of |p - L| over the tet, where p has degree t->degree with `values` at the domain points
 * (point i's `components` numbers at values[i * stride ...]) and L is linear with `corner` at the tet's
 * 4 corners (corner[k * components ...]): the largest Euclidean norm of the Bernstein coefficients of
 * p - L, plus a margin for the rounding of this computation (relative 1e-13 x inverse_norm of the
 * largest magnitude involved). components <= 3. */
double tpk_bernstein_gap(const tpk_bernstein *t, const double *values, int stride, const double *corner,
                         int components);

/* The Bernstein coefficients of each of n functions given by their values at the domain points
 * (values[i * n + k]: function k at point i) into coef (same layout): coef = inverse x values. Returns the
 * largest row sum of |coef| (for a margin on what is computed with them). */
double tpk_bernstein_coefficients(const tpk_bernstein *t, const double *values, int n, double *coef);

#endif
