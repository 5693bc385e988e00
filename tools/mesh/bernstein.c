/* Bernstein-Bezier coefficients from values at the domain points (bernstein.h). */
#include "bernstein.h"

typedef double pair __attribute__((vector_size(2 * sizeof(double)))); /* two numbers side by side */

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* B_beta(alpha / n) = n! / prod beta_k! prod (alpha_k / n)^beta_k, in long double: the multinomial and
 * the integer powers exactly (each under 2^64 for n <= 12: 12! / ... <= 4.8e8, prod alpha_k^beta_k <=
 * 12^12), then one product and one division by n^n: a relative error of a few long double units. */
static long double basis(int n, const int beta[4], const int alpha[4])
{
    long double multinomial = 1, power = 1, scale = 1;
    for (int i = 2; i <= n; i++)
        multinomial *= i;
    for (int k = 0; k < 4; k++)
        for (int i = 2; i <= beta[k]; i++)
            multinomial /= i; /* exact: each quotient is an integer (a product of binomials) */
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < beta[k]; i++)
            power *= alpha[k];
    for (int i = 0; i < n; i++)
        scale *= n;
    return multinomial * power / scale;
}

/* Degrees up to 6 keep the tables of before, built and inverted in double (the files --max-error wrote
 * stay byte-identical; bernstein.inverse_accurate checks them as the others): B_beta(lambda) = n! / prod
 * beta_k! prod lambda_k^beta_k. */
static double factorial(int n)
{
    double f = 1;
    for (int i = 2; i <= n; i++)
        f *= i;
    return f;
}

static double basis_double(int n, const int beta[4], const double lambda[4])
{
    double b = factorial(n);
    for (int k = 0; k < 4; k++)
        b *= pow(lambda[k], beta[k]) / factorial(beta[k]);
    return b;
}

static int invert_double(double *a, double *inv, int m)
{
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            inv[i * m + j] = i == j;
    for (int col = 0; col < m; col++) {
        int pivot = col;
        for (int r = col + 1; r < m; r++)
            if (fabs(a[r * m + col]) > fabs(a[pivot * m + col]))
                pivot = r;
        if (a[pivot * m + col] == 0)
            return -1;
        for (int j = 0; j < m; j++) {
            double s = a[col * m + j];
            a[col * m + j] = a[pivot * m + j], a[pivot * m + j] = s;
            s = inv[col * m + j];
            inv[col * m + j] = inv[pivot * m + j], inv[pivot * m + j] = s;
        }
        double d = a[col * m + col];
        for (int j = 0; j < m; j++)
            a[col * m + j] /= d, inv[col * m + j] /= d;
        for (int r = 0; r < m; r++) {
            double f = a[r * m + col];
            if (r == col || f == 0)
                continue;
            for (int j = 0; j < m; j++)
                a[r * m + j] -= f * a[col * m + j], inv[r * m + j] -= f * inv[col * m + j];
        }
    }
    return 0;
}

/* Gauss-Jordan with partial pivoting in long double: a (m x m) inverted into inv; -1 when singular. */
static int invert(long double *a, long double *inv, int m)
{
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            inv[(size_t)i * m + j] = i == j;
    for (int col = 0; col < m; col++) {
        int pivot = col;
        for (int r = col + 1; r < m; r++)
            if (fabsl(a[(size_t)r * m + col]) > fabsl(a[(size_t)pivot * m + col]))
                pivot = r;
        if (a[(size_t)pivot * m + col] == 0)
            return -1;
        for (int j = 0; j < m; j++) {
            long double s = a[(size_t)col * m + j];
            a[(size_t)col * m + j] = a[(size_t)pivot * m + j], a[(size_t)pivot * m + j] = s;
            s = inv[(size_t)col * m + j];
            inv[(size_t)col * m + j] = inv[(size_t)pivot * m + j], inv[(size_t)pivot * m + j] = s;
        }
        long double d = a[(size_t)col * m + col];
        for (int j = 0; j < m; j++)
            a[(size_t)col * m + j] /= d, inv[(size_t)col * m + j] /= d;
        for (int r = 0; r < m; r++) {
            long double f = a[(size_t)r * m + col];
            if (r == col || f == 0)
                continue;
            for (int j = col; j < m; j++) /* left of col, row col of a is 0 */
                a[(size_t)r * m + j] -= f * a[(size_t)col * m + j];
            for (int j = 0; j < m; j++)
                inv[(size_t)r * m + j] -= f * inv[(size_t)col * m + j];
        }
    }
    return 0;
}

void tpk_bernstein_free(tpk_bernstein *t)
{
    free(t->lambda), free(t->lambda_by_corner[0]), free(t->inverse), free(t->inverse_t);
    memset(t, 0, sizeof *t);
}

int tpk_bernstein_make(int n, tpk_bernstein *t)
{
    memset(t, 0, sizeof *t);
    if (n < 1 || n > TPK_BERNSTEIN_MAX_DEGREE)
        return -1;
    int m = (n + 1) * (n + 2) * (n + 3) / 6;
    int (*alpha)[4] = malloc(sizeof *alpha * (size_t)m);
    long double *work = malloc(sizeof *work * (size_t)m * (size_t)m);
    long double *inv = malloc(sizeof *inv * (size_t)m * (size_t)m);
    t->lambda = malloc(sizeof *t->lambda * (size_t)m);
    t->lambda_by_corner[0] = malloc(sizeof *t->lambda_by_corner[0] * 4 * (size_t)m);
    t->inverse = malloc(sizeof *t->inverse * (size_t)m * (size_t)m);
    t->inverse_t = malloc(sizeof *t->inverse_t * (size_t)m * (size_t)m);
    int rc = alpha && work && inv && t->lambda && t->lambda_by_corner[0] && t->inverse && t->inverse_t ? 0 : -1;
    if (rc == 0) {
        t->degree = n, t->points = m;
        for (int c = 1; c < 4; c++)
            t->lambda_by_corner[c] = t->lambda_by_corner[0] + (size_t)c * m;
        int i = 0;
        for (int a = 0; a <= n; a++)
            for (int b = 0; a + b <= n; b++)
                for (int c = 0; a + b + c <= n; c++, i++) {
                    alpha[i][0] = n - a - b - c, alpha[i][1] = a, alpha[i][2] = b, alpha[i][3] = c;
                    for (int k = 0; k < 4; k++)
                        t->lambda[i][k] = t->lambda_by_corner[k][i] = (double)alpha[i][k] / n;
                }
        if (n <= 6) {
            double *a = (double *)work; /* room enough */
            for (int r = 0; r < m; r++)
                for (int j = 0; j < m; j++)
                    a[r * m + j] = basis_double(n, alpha[j], t->lambda[r]);
            rc = invert_double(a, t->inverse, m);
        } else {
            for (int r = 0; r < m; r++)
                for (int j = 0; j < m; j++)
                    work[(size_t)r * m + j] = basis(n, alpha[j], alpha[r]);
            if ((rc = invert(work, inv, m)) == 0)
                for (size_t k = 0; k < (size_t)m * m; k++)
                    t->inverse[k] = (double)inv[k];
        }
    }
    for (int r = 0; rc == 0 && r < m; r++) {
        double row = 0;
        for (int j = 0; j < m; j++)
            row += fabs(t->inverse_t[(size_t)j * m + r] = t->inverse[(size_t)r * m + j]);
        t->inverse_norm = row > t->inverse_norm ? row : t->inverse_norm;
    }
    free(alpha), free(work), free(inv);
    if (rc != 0)
        tpk_bernstein_free(t);
    return rc;
}

double tpk_bernstein_margin(const tpk_bernstein *t)
{
    const double u = DBL_EPSILON / 2, m = t->points, gamma = m * u / (1 - m * u);
    double norm = t->inverse_norm, derived = 2 * (gamma + 8 * u) * norm + 2 * TPK_BERNSTEIN_INVERSE_ERROR * (norm + 1);
    return fmax(1e-13 * (norm + 1), derived);
}

double tpk_bernstein_gap(const tpk_bernstein *t, const double *values, int stride, const double *corner,
                         int components)
{
    double d[TPK_BERNSTEIN_MAX_POINTS][3], largest = 0, worst = 0;
    int m = t->points, finite = 1;
    for (int i = 0; i < m; i++)
        d[i][1] = d[i][2] = 0; /* the components absent */
    for (int i = 0; i < m; i++)
        for (int c = 0; c < components; c++) {
            const double *lambda = t->lambda[i];
            double v = values[i * stride + c], l = lambda[0] * corner[c] + lambda[1] * corner[components + c] +
                                                    lambda[2] * corner[2 * components + c] +
                                                    lambda[3] * corner[3 * components + c];
            d[i][c] = v - l;
            finite &= isfinite(v) && isfinite(l);
            double a = fabs(v) > fabs(l) ? fabs(v) : fabs(l);
            largest = a > largest ? a : largest;
        }
    if (!finite)
        return INFINITY;
    /* coef_i = sum_j inverse_ij d_j, four rows at once (two pairs) through the transposed inverse: any
     * order of the sums is within the margin */
    int i = 0;
    for (; i + 4 <= m; i += 4) {
        pair a0, a1, x0, x1, x2, s0 = {0, 0}, s1 = {0, 0}, s2 = {0, 0}, u0 = {0, 0}, u1 = {0, 0}, u2 = {0, 0};
        if (components == 1) {
            for (int j = 0; j < m; j++) {
                memcpy(&a0, t->inverse_t + (size_t)j * m + i, sizeof a0);
                memcpy(&a1, t->inverse_t + (size_t)j * m + i + 2, sizeof a1);
                x0 = (pair){d[j][0], d[j][0]};
                s0 += a0 * x0, u0 += a1 * x0;
            }
        } else { /* the absent components are 0 */
            for (int j = 0; j < m; j++) {
                memcpy(&a0, t->inverse_t + (size_t)j * m + i, sizeof a0);
                memcpy(&a1, t->inverse_t + (size_t)j * m + i + 2, sizeof a1);
                x0 = (pair){d[j][0], d[j][0]}, x1 = (pair){d[j][1], d[j][1]}, x2 = (pair){d[j][2], d[j][2]};
                s0 += a0 * x0, s1 += a0 * x1, s2 += a0 * x2;
                u0 += a1 * x0, u1 += a1 * x1, u2 += a1 * x2;
            }
        }
        pair sq[2] = {s0 * s0 + s1 * s1 + s2 * s2, u0 * u0 + u1 * u1 + u2 * u2};
        for (int q = 0; q < 2; q++)
            for (int l = 0; l < 2; l++)
                worst = sq[q][l] > worst ? sq[q][l] : worst;
    }
    for (; i < m; i++) {
        double sq = 0;
        for (int c = 0; c < components; c++) {
            double coef = 0;
            for (int j = 0; j < m; j++)
                coef += t->inverse_t[(size_t)j * m + i] * d[j][c];
            sq += coef * coef;
        }
        worst = sq > worst ? sq : worst;
    }
    /* per component within the margin; the Euclidean norm of up to 3: sqrt(3) times */
    return sqrt(worst) + (components > 1 ? sqrt(3.0) : 1) * tpk_bernstein_margin(t) * largest;
}

double tpk_bernstein_coefficients(const tpk_bernstein *t, const double *values, int n, double *coef)
{
    int m = t->points;
    double norm = 0;
    for (int i = 0; i < m; i++) {
        const double *row = t->inverse + (size_t)i * m;
        double *out = coef + (size_t)i * n, sum = 0;
        for (int k = 0; k < n; k++)
            out[k] = 0;
        for (int j = 0; j < m; j++) {
            const double a = row[j], *in = values + (size_t)j * n;
            for (int k = 0; k < n; k++)
                out[k] += a * in[k];
        }
        for (int k = 0; k < n; k++)
            sum += fabs(out[k]);
        norm = sum > norm ? sum : norm;
    }
    return norm;
}
