/* Bernstein-Bezier bounds on a tetrahedron (docs/ARCHITECTURE.md §5): a polynomial p of total degree n in
 * the barycentric coordinates of a tet is sum_i c_i B_i with the Bernstein polynomials B_i >= 0, sum 1, so
 * |p| <= max_i |c_i| over the whole tet (the convex-hull property). The coefficients come from p's values
 * at the degree-n domain points (barycentric alpha / n, |alpha| = n) through the inverse of the
 * collocation matrix, computed once per degree. convert --max-error bounds |f - L| this way, f the
 * source cell's map or interpolant on a tet of its parameter space and L the tet's linear one. */
#ifndef TPK_BERNSTEIN_H
#define TPK_BERNSTEIN_H

#define TPK_BERNSTEIN_MAX_DEGREE 12
#define TPK_BERNSTEIN_MAX_POINTS 455 /* (n + 1)(n + 2)(n + 3) / 6 at n = 12 */

/* The error the inverse may have, as a row-sum norm: || inverse - exact inverse ||_inf <=
 * TPK_BERNSTEIN_INVERSE_ERROR x (inverse_norm + 1). Degrees up to 6 are built and inverted in double as
 * before (their files stay byte-identical); degrees 7-12 in long double (unit roundoff 5.4e-20; the
 * collocation matrix is integers over n^n, exact up to one rounding), by Gauss-Jordan with partial
 * pivoting, rounded to double once (unit roundoff u = 1.1e-16, so within u x inverse_norm).
 * bernstein.inverse_accurate compares every degree's inverse with the exact one (__float128) and checks
 * this bound. Measured, as multiples of (inverse_norm + 1): at most 1.6e-15 (degree 6), 4.2e-16 at degree
 * 12; inverse_norm is 10 at degree 3, 229 at 6, 1.3e4 at 10, 9.8e4 at 12 (the Lebesgue constant of the
 * equispaced domain points grows with n). */
#define TPK_BERNSTEIN_INVERSE_ERROR 1e-14

typedef struct tpk_bernstein {
    int degree, points;
    double (*lambda)[4];          /* domain point i: barycentric alpha_i / n (points rows) */
    double *lambda_by_corner[4];  /* the same, transposed */
    double *inverse;              /* points x points: coefficients = inverse x values */
    double *inverse_t;            /* the same transposed (inverse_t[j * points + i] = inverse[i * points + j]) */
    double inverse_norm;          /* its infinity norm (rows' absolute sums), for the margin */
} tpk_bernstein;

/* The table of degree n (1 <= n <= TPK_BERNSTEIN_MAX_DEGREE) into t, its arrays allocated (free with
 * tpk_bernstein_free). Returns 0, or -1 for another n or out of memory (t then holds nothing to free).
 * Degree 12 takes about 0.3 s (a long double inversion of 455 x 455). */
int tpk_bernstein_make(int n, tpk_bernstein *t);

void tpk_bernstein_free(tpk_bernstein *t);

/* The margin for rounding, relative to the largest magnitude involved, of a Bernstein coefficient
 * computed in double as sum_j inverse_ij d_j (d_j = value_j - linear_j, |d_j| <= 2 x largest): the
 * inverse's own error (TPK_BERNSTEIN_INVERSE_ERROR), the m products' and sums' in any order (gamma_m =
 * m u / (1 - m u), times sum_j |inverse_ij| |d_j|) and d's own (8 u: 4 products and 4 sums), so
 * 2 (gamma_m + 8 u) inverse_norm + 2 TPK_BERNSTEIN_INVERSE_ERROR (inverse_norm + 1); never below the
 * constant of before, 1e-13 x (inverse_norm + 1), which it exceeds from m = 364 (degree 11): 1.2e-8 at
 * degree 12, 1.3e-9 at 10, 2.3e-11 at 6 (bernstein.inverse_accurate prints them). The values themselves
 * are taken as exact: a caller adds their error through inverse_norm (convert/refine.c does). */
double tpk_bernstein_margin(const tpk_bernstein *t);

/* The bound of |p - L| over the tet, where p has degree t->degree with `values` at the domain points
 * (point i's `components` numbers at values[i * stride ...]) and L is linear with `corner` at the tet's
 * 4 corners (corner[k * components ...]): the largest Euclidean norm of the Bernstein coefficients of
 * p - L, plus a margin for the rounding of this computation (tpk_bernstein_margin x the largest magnitude
 * involved). components <= 3. */
double tpk_bernstein_gap(const tpk_bernstein *t, const double *values, int stride, const double *corner,
                         int components);

/* The Bernstein coefficients of each of n functions given by their values at the domain points
 * (values[i * n + k]: function k at point i) into coef (same layout): coef = inverse x values. Returns the
 * largest row sum of |coef| (for a margin on what is computed with them). */
double tpk_bernstein_coefficients(const tpk_bernstein *t, const double *values, int n, double *coef);

#endif
