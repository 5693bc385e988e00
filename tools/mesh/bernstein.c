/* Bernstein-Bezier coefficients from values at the domain points (bernstein.h). */
#include "bernstein.h"

#include <math.h>
#include <string.h>

static double factorial(int n)
{
    double f = 1;
    for (int i = 2; i <= n; i++)
        f *= i;
    return f;
}

/* B_alpha(lambda) = n! / prod alpha_k! prod lambda_k^alpha_k */
static double basis(int n, const int alpha[4], const double lambda[4])
{
    double b = factorial(n);
    for (int k = 0; k < 4; k++)
        b *= pow(lambda[k], alpha[k]) / factorial(alpha[k]);
    return b;
}

/* Gauss-Jordan with partial pivoting: a (m x m) inverted into inv; -1 when singular. */
static int invert(double *a, double *inv, int m)
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

int tpk_bernstein_make(int n, tpk_bernstein *t)
{
    static double a[TPK_BERNSTEIN_MAX_POINTS * TPK_BERNSTEIN_MAX_POINTS];
    int alpha[TPK_BERNSTEIN_MAX_POINTS][4];
    if (n < 1 || n > TPK_BERNSTEIN_MAX_DEGREE)
        return -1;
    memset(t, 0, sizeof *t);
    t->degree = n;
    int m = 0;
    for (int i = 0; i <= n; i++)
        for (int j = 0; i + j <= n; j++)
            for (int k = 0; i + j + k <= n; k++, m++) {
                alpha[m][0] = n - i - j - k, alpha[m][1] = i, alpha[m][2] = j, alpha[m][3] = k;
                for (int c = 0; c < 4; c++)
                    t->lambda[m][c] = t->lambda_by_corner[c][m] = (double)alpha[m][c] / n;
            }
    t->points = m;
    double *work = a; /* static scratch: callers make their tables before starting threads */
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            work[i * m + j] = basis(n, alpha[j], t->lambda[i]);
    if (invert(work, t->inverse, m) != 0)
        return -1;
    for (int i = 0; i < m; i++) {
        double row = 0;
        for (int j = 0; j < m; j++)
            row += fabs(t->inverse[i * m + j]);
        t->inverse_norm = row > t->inverse_norm ? row : t->inverse_norm;
    }
    return 0;
}

double tpk_bernstein_gap(const tpk_bernstein *t, const double *values, int stride, const double *corner,
                         int components)
{
    double d[TPK_BERNSTEIN_MAX_POINTS][3], largest = 0, worst = 0;
    int m = t->points, finite = 1;
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
    for (int i = 0; i < m; i++) {
        const double *row = t->inverse + i * m;
        double sq = 0;
        for (int c = 0; c < components; c++) {
            double coef = 0;
            for (int j = 0; j < m; j++)
                coef += row[j] * d[j][c];
            sq += coef * coef;
        }
        worst = sq > worst ? sq : worst;
    }
    return sqrt(worst) + 1e-13 * (t->inverse_norm + 1) * largest;
}

double tpk_bernstein_coefficients(const tpk_bernstein *t, const double *values, int n, double *coef)
{
    int m = t->points;
    double norm = 0;
    for (int i = 0; i < m; i++) {
        const double *row = t->inverse + i * m;
        double *out = coef + i * n, sum = 0;
        for (int k = 0; k < n; k++)
            out[k] = 0;
        for (int j = 0; j < m; j++) {
            const double a = row[j], *in = values + j * n;
            for (int k = 0; k < n; k++)
                out[k] += a * in[k];
        }
        for (int k = 0; k < n; k++)
            sum += fabs(out[k]);
        norm = sum > norm ? sum : norm;
    }
    return norm;
}
