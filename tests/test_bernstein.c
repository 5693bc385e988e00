/* The Bernstein bound of convert --max-error (tools/mesh/bernstein.c, tools/convert/refine.c): on a tet
 * of a cell's parameter space each mapped type's functions are polynomials of the degree
 * tpk_cell_map_degree states (the Bernstein form fitted at the domain points reproduces them at random
 * points; one degree less does not), the bound is never below the error sampled densely, and a
 * function that is linear on the tet gets a bound at rounding level. The rough bound by nonlinear
 * monomials (tpk_cell_map_nonlinear) holds too, and the quadratic tetra's closed form
 * (tpk_cell_map_quadratic_tet) gives the Bernstein coefficients. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "mesh/bernstein.h"
#include "mesh/cell_map.h"

static const int mapped[] = {12, 13, 24, 25, 26, 29, 31, 32, 33, TPK_CELL_MAP_LAGRANGE_TETRA + 3,
                             TPK_CELL_MAP_LAGRANGE_TETRA + 4, TPK_CELL_MAP_LAGRANGE_TETRA + 5,
                             TPK_CELL_MAP_LAGRANGE_TETRA + 6, TPK_CELL_MAP_LAGRANGE_TETRA + 7,
                             TPK_CELL_MAP_LAGRANGE_TETRA + 8, TPK_CELL_MAP_LAGRANGE_TETRA + 9,
                             TPK_CELL_MAP_LAGRANGE_TETRA + 10, TPK_CELL_MAP_LAGRANGE_HEX + 3,
                             TPK_CELL_MAP_LAGRANGE_HEX + 4, TPK_CELL_MAP_LAGRANGE_WEDGE + 3,
                             TPK_CELL_MAP_LAGRANGE_WEDGE + 4, TPK_CELL_MAP_LAGRANGE_WEDGE + 5,
                             TPK_CELL_MAP_LAGRANGE_WEDGE + 6};

/* The table of degree n, made once (degree 12 takes a fraction of a second); NULL if it cannot be. */
static const tpk_bernstein *table(int n)
{
    static tpk_bernstein tables[TPK_BERNSTEIN_MAX_DEGREE + 1];
    if (n < 1 || n > TPK_BERNSTEIN_MAX_DEGREE)
        return NULL;
    if (!tables[n].points && tpk_bernstein_make(n, &tables[n]) != 0)
        return NULL;
    return &tables[n];
}

static double uniform(unsigned *seed)
{
    *seed = *seed * 1103515245u + 12345u;
    return (double)((*seed >> 8) & 0xffffff) / 16777216.0;
}

/* A random point of the type's reference cell (r, s, t in [0, 1], r + s <= 1 for wedges and tetra). */
static void reference_point(int type, unsigned *seed, double xi[3])
{
    for (int i = 0; i < 3; i++)
        xi[i] = uniform(seed);
    if ((type == 24 || (type > TPK_CELL_MAP_LAGRANGE_TETRA && type < TPK_CELL_MAP_LAGRANGE_HEX)) &&
        xi[0] + xi[1] + xi[2] > 1)
        xi[0] *= 0.3, xi[1] *= 0.3, xi[2] *= 0.3;
    if ((type == 13 || type == 26 || type == 31 || type == 32 || type > TPK_CELL_MAP_LAGRANGE_WEDGE) &&
        xi[0] + xi[1] > 1)
        xi[0] = 1 - xi[0], xi[1] = 1 - xi[1];
}

static void random_lambda(unsigned *seed, double lambda[4])
{
    double sum = 0;
    for (int k = 0; k < 4; k++)
        sum += lambda[k] = -log(uniform(seed) + 1e-12);
    for (int k = 0; k < 4; k++)
        lambda[k] /= sum;
}

/* The cell's interpolant of node values `value` at barycentric lambda of the tet with corners xi[4][3]. */
static double cell_value(int type, const double xi[4][3], const double *value, const double lambda[4])
{
    double at[3] = {0, 0, 0}, w[TPK_CELL_MAP_MAX_NODES], f = 0;
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 3; j++)
            at[j] += lambda[k] * xi[k][j];
    int n = tpk_cell_map_weights(type, at, w);
    for (int k = 0; k < n; k++)
        f += w[k] * value[k];
    return f;
}

static double factorial(int n)
{
    return n <= 1 ? 1 : n * factorial(n - 1);
}

/* sum_i c_i B_i(lambda) for the table's domain points. */
static double bernstein_sum(const tpk_bernstein *b, const double *c, const double lambda[4])
{
    double s = 0;
    for (int i = 0; i < b->points; i++) {
        double term = factorial(b->degree) * c[i];
        for (int k = 0; k < 4; k++) {
            int a = (int)lround(b->lambda[i][k] * b->degree);
            term *= pow(lambda[k], a) / factorial(a);
        }
        s += term;
    }
    return s;
}

/* The largest misfit at random points of the degree-n Bernstein form fitted to the cell's function. */
static double misfit(int type, int degree, unsigned *seed)
{
    if (!table(degree))
        return INFINITY;
    const tpk_bernstein b = *table(degree);
    double xi[4][3], value[TPK_CELL_MAP_MAX_NODES], at[TPK_BERNSTEIN_MAX_POINTS], c[TPK_BERNSTEIN_MAX_POINTS];
    for (int k = 0; k < 4; k++)
        reference_point(type, seed, xi[k]);
    for (int k = 0; k < tpk_cell_map_nodes(type); k++)
        value[k] = 2 * uniform(seed) - 1;
    for (int i = 0; i < b.points; i++)
        at[i] = cell_value(type, xi, value, b.lambda[i]);
    tpk_bernstein_coefficients(&b, at, 1, c);
    double worst = 0;
    for (int s = 0; s < 200; s++) {
        double lambda[4];
        random_lambda(seed, lambda);
        worst = fmax(worst, fabs(bernstein_sum(&b, c, lambda) - cell_value(type, xi, value, lambda)));
    }
    return worst;
}

TPK_TEST(degrees)
{
    unsigned seed = 1;
    for (size_t i = 0; i < sizeof mapped / sizeof mapped[0]; i++) {
        int type = mapped[i], degree = tpk_cell_map_degree(type);
        CHECK(degree >= 2 && degree <= TPK_BERNSTEIN_MAX_DEGREE);
        for (int trial = 0; trial < 5; trial++) {
            double exact = misfit(type, degree, &seed), lower = misfit(type, degree - 1, &seed);
            /* one degree less misses: by less at high degrees on small tets (the top terms scale as the
             * tet's size^n), yet far above the fit's rounding */
            if (!(exact < 1e-9) || !(lower > 1e-9 && lower > 1000 * exact))
                fprintf(stderr, "type %d degree %d: misfit %g, at degree %d %g\n", type, degree, exact, degree - 1,
                        lower);
            CHECK(exact < 1e-9);
            CHECK(lower > 1e-9 && lower > 1000 * exact);
        }
    }
    CHECK_EQ_INT(tpk_cell_map_degree(10), 1);
    CHECK_EQ_INT(tpk_cell_map_degree(14), 0); /* pyramids: not polynomials on their tets */
    CHECK_EQ_INT(tpk_cell_map_degree(27), 0);
    CHECK_EQ_INT(tpk_cell_map_degree(42), 0);
}

TPK_TEST(bound_holds)
{
    unsigned seed = 7;
    for (size_t i = 0; i < sizeof mapped / sizeof mapped[0]; i++) {
        int type = mapped[i];
        CHECK(table(tpk_cell_map_degree(type)) != NULL);
        const tpk_bernstein b = *table(tpk_cell_map_degree(type));
        for (int trial = 0; trial < 20; trial++) {
            double xi[4][3], value[TPK_CELL_MAP_MAX_NODES], at[TPK_BERNSTEIN_MAX_POINTS], corner[4];
            for (int k = 0; k < 4; k++)
                reference_point(type, &seed, xi[k]);
            for (int k = 0; k < tpk_cell_map_nodes(type); k++)
                value[k] = 2 * uniform(&seed) - 1;
            for (int i2 = 0; i2 < b.points; i2++)
                at[i2] = cell_value(type, xi, value, b.lambda[i2]);
            for (int k = 0; k < 4; k++) { /* the tet's own values: the cell's, a little off */
                double l[4] = {k == 0, k == 1, k == 2, k == 3};
                corner[k] = cell_value(type, xi, value, l) + 0.01 * (uniform(&seed) - 0.5);
            }
            double gap = tpk_bernstein_gap(&b, at, 1, corner, 1), sampled = 0;
            for (int s = 0; s < 2000; s++) {
                double lambda[4];
                random_lambda(&seed, lambda);
                double linear = 0;
                for (int k = 0; k < 4; k++)
                    linear += lambda[k] * corner[k];
                sampled = fmax(sampled, fabs(cell_value(type, xi, value, lambda) - linear));
            }
            CHECK(sampled <= gap);
            CHECK(gap < 50 * sampled + 1e-9); /* not absurdly loose either */
        }
    }
}

/* f(r) less the sum of its nonlinear monomials' terms, for node values `value`. */
static double affine_part(int type, const double *value, const double *a, int count, const double r[3])
{
    double w[TPK_CELL_MAP_MAX_NODES], m[TPK_CELL_MAP_MAX_NONLINEAR], f = 0;
    int n = tpk_cell_map_weights(type, r, w);
    for (int k = 0; k < n; k++)
        f += w[k] * value[k];
    tpk_cell_map_nonlinear(type, r, m);
    for (int q = 0; q < count; q++)
        f -= a[q] * m[q];
    return f;
}

TPK_TEST(nonlinear_monomials)
{
    /* convert --max-error's rough bound (refine.c rough_bound): on the hexahedron and the quadratic tetra,
     * f less sum_q a_q m_q is affine, and on a tet whose corners are nodes, |f - L| stays within
     * sum_q |a_q| max|m_q - L m_q|, the latter bounded through the Bernstein form as refine.c does */
    unsigned seed = 11;
    const int types[2] = {12, 24};
    for (int i = 0; i < 2; i++) {
        int type = types[i], n = tpk_cell_map_nodes(type);
        const tpk_bernstein b = *table(tpk_cell_map_degree(type));
        double origin[3] = {0, 0, 0}, m0[TPK_CELL_MAP_MAX_NONLINEAR];
        int count = tpk_cell_map_nonlinear(type, origin, m0);
        CHECK(count == (type == 12 ? 4 : 6) && count <= TPK_CELL_MAP_MAX_NONLINEAR);
        int sets = 0;
        for (int trial = 0; trial < 40; trial++) {
            double value[TPK_CELL_MAP_MAX_NODES], xyz[TPK_CELL_MAP_MAX_NODES * 3], a[TPK_CELL_MAP_MAX_NONLINEAR],
                a3[3 * TPK_CELL_MAP_MAX_NONLINEAR];
            for (int k = 0; k < n; k++)
                value[k] = 2 * uniform(&seed) - 1, xyz[3 * k] = uniform(&seed), xyz[3 * k + 1] = value[k],
                xyz[3 * k + 2] = -value[k];
            CHECK(tpk_cell_map_nonlinear_coefficients(type, value, 1, a) == count);
            CHECK(tpk_cell_map_nonlinear_coefficients(type, xyz, 3, a3) == count);
            for (int q = 0; q < count; q++)
                CHECK(a3[3 * q + 1] == a[q] && a3[3 * q + 2] == -a[q]);
            for (int s = 0; s < 20; s++) { /* affine: the midpoint's value is the mean of the ends' */
                double x[3], y[3], mid[3];
                reference_point(type, &seed, x);
                reference_point(type, &seed, y);
                for (int j = 0; j < 3; j++)
                    mid[j] = 0.5 * (x[j] + y[j]);
                double gap = affine_part(type, value, a, count, x) + affine_part(type, value, a, count, y) -
                             2 * affine_part(type, value, a, count, mid);
                CHECK(fabs(gap) < 1e-12);
            }
            int corner[4]; /* four distinct nodes */
            for (int k = 0; k < 4; k++) {
                int fresh;
                do {
                    corner[k] = (int)(uniform(&seed) * n) % n, fresh = 1;
                    for (int j = 0; j < k; j++)
                        fresh &= corner[j] != corner[k];
                } while (!fresh);
            }
            double xi[4][3], cm[4][TPK_CELL_MAP_MAX_NONLINEAR], e[3][3], at[TPK_BERNSTEIN_MAX_POINTS][TPK_CELL_MAP_MAX_NONLINEAR];
            for (int k = 0; k < 4; k++)
                tpk_cell_map_node(type, corner[k], xi[k]), tpk_cell_map_nonlinear(type, xi[k], cm[k]);
            for (int k = 0; k < 3; k++)
                for (int j = 0; j < 3; j++)
                    e[k][j] = xi[k + 1][j] - xi[0][j];
            double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
            if (fabs(det) < 1e-9)
                continue; /* flat in parameter space: no tet of a split */
            sets++;
            for (int p = 0; p < b.points; p++) {
                double r[3] = {0, 0, 0};
                for (int k = 0; k < 4; k++)
                    for (int j = 0; j < 3; j++)
                        r[j] += b.lambda[p][k] * xi[k][j];
                tpk_cell_map_nonlinear(type, r, at[p]);
            }
            double bound = 0, sampled = 0, fc[4];
            for (int q = 0; q < count; q++) {
                double c[4] = {cm[0][q], cm[1][q], cm[2][q], cm[3][q]};
                bound += fabs(a[q]) * tpk_bernstein_gap(&b, &at[0][q], TPK_CELL_MAP_MAX_NONLINEAR, c, 1);
            }
            for (int k = 0; k < 4; k++)
                fc[k] = value[corner[k]];
            for (int s = 0; s < 2000; s++) {
                double lambda[4], linear = 0;
                random_lambda(&seed, lambda);
                for (int k = 0; k < 4; k++)
                    linear += lambda[k] * fc[k];
                sampled = fmax(sampled, fabs(cell_value(type, xi, value, lambda) - linear));
            }
            CHECK(sampled <= bound + 1e-12);
        }
        CHECK(sets > 10);
    }
    double r[3] = {0.2, 0.3, 0.1}, m[TPK_CELL_MAP_MAX_NONLINEAR], v[TPK_CELL_MAP_MAX_NODES] = {0};
    CHECK(tpk_cell_map_nonlinear(13, r, m) == 0 && tpk_cell_map_nonlinear_coefficients(25, v, 1, m) == 0);
}

TPK_TEST(quadratic_tet_blossom)
{
    /* convert --max-error's closed form for the quadratic tetra (refine.c quadratic_coefficients): on a
     * random tet of its parameter space, f at the corners and (f(r_k) + f(r_l)) / 2 - sum_q a_q m_q / 2 on
     * the edges, from tpk_cell_map_quadratic_tet, are the Bernstein coefficients that the inverse of the
     * domain points' table gives */
    static const int pair[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    const tpk_bernstein b = *table(2);
    unsigned seed = 17;
    double worst = 0;
    for (int trial = 0; trial < 200; trial++) {
        double xi[4][3], value[10], a[TPK_CELL_MAP_MAX_NONLINEAR], at[TPK_BERNSTEIN_MAX_POINTS],
            coef[TPK_BERNSTEIN_MAX_POINTS], w[4][10], m[6][6], f[4], big = 0;
        for (int k = 0; k < 4; k++)
            reference_point(24, &seed, xi[k]);
        for (int k = 0; k < 10; k++)
            value[k] = 200 * uniform(&seed) - 100, big = fmax(big, fabs(value[k]));
        CHECK(tpk_cell_map_quadratic_tet(24, xi[0], w, m) == 10);
        CHECK(tpk_cell_map_nonlinear_coefficients(24, value, 1, a) == 6);
        for (int k = 0; k < 4; k++) {
            double wk[TPK_CELL_MAP_MAX_NODES];
            tpk_cell_map_weights(24, xi[k], wk);
            f[k] = 0;
            for (int j = 0; j < 10; j++) {
                CHECK(w[k][j] == wk[j]);
                f[k] += w[k][j] * value[j];
            }
        }
        for (int i = 0; i < b.points; i++)
            at[i] = cell_value(24, xi, value, b.lambda[i]);
        tpk_bernstein_coefficients(&b, at, 1, coef);
        for (int i = 0; i < b.points; i++) {
            const double *l = b.lambda[i];
            double closed = NAN;
            for (int k = 0; k < 4; k++)
                if (l[k] == 1)
                    closed = f[k];
            for (int p = 0; p < 6; p++)
                if (l[pair[p][0]] == 0.5 && l[pair[p][1]] == 0.5) {
                    double n = 0;
                    for (int q = 0; q < 6; q++)
                        n += a[q] * m[p][q];
                    closed = 0.5 * (f[pair[p][0]] + f[pair[p][1]]) - 0.5 * n;
                }
            CHECK(isfinite(closed));
            worst = fmax(worst, fabs(closed - coef[i]) / big);
        }
    }
    printf("quadratic tetra: closed form against the inverse, largest difference %.2g of the largest value\n", worst);
    CHECK(worst < 1e-13);
    double xi[12] = {0}, w[4][10], m[6][6];
    CHECK(tpk_cell_map_quadratic_tet(12, xi, w, m) == 0);
}

TPK_TEST(linear_is_exact)
{
    /* a hexahedron whose nodes carry a linear function of position: on any tet its trilinear
     * interpolant is that function, so the bound against the tet's own linear values is rounding only */
    const tpk_bernstein b = *table(3);
    double value[8], xi[4][3] = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0.2}, {0.3, 0.4, 1}}, at[TPK_BERNSTEIN_MAX_POINTS],
                     corner[4];
    for (int k = 0; k < 8; k++) {
        double r[3];
        tpk_cell_map_node(12, k, r);
        value[k] = 3 * r[0] - 2 * r[1] + 0.5 * r[2] + 7;
    }
    for (int i = 0; i < b.points; i++)
        at[i] = cell_value(12, xi, value, b.lambda[i]);
    for (int k = 0; k < 4; k++)
        corner[k] = 3 * xi[k][0] - 2 * xi[k][1] + 0.5 * xi[k][2] + 7;
    double gap = tpk_bernstein_gap(&b, at, 1, corner, 1);
    CHECK(gap < 1e-9);
    CHECK(gap > 0); /* the rounding margin */
    tpk_bernstein none;
    CHECK(tpk_bernstein_make(0, &none) != 0 && tpk_bernstein_make(TPK_BERNSTEIN_MAX_DEGREE + 1, &none) != 0);
}

/* The exact inverse of the degree-n collocation matrix, in __float128 (unit roundoff 9.6e-35): the matrix
 * is integers over n^n (multinomial x prod alpha_k^beta_k < 2^73, exact), inverted by Gauss-Jordan with
 * partial pivoting (its rounding, about cond x m x 1e-34 < 1e-24 here, far below what is checked). */
static void exact_inverse(int n, const tpk_bernstein *b, __float128 *inv)
{
    int m = b->points, (*alpha)[4] = malloc(sizeof *alpha * (size_t)m);
    __float128 *a = malloc(sizeof *a * (size_t)m * (size_t)m), scale = 1;
    for (int i = 0; i < m; i++)
        for (int k = 0; k < 4; k++)
            alpha[i][k] = (int)lround(b->lambda[i][k] * n);
    for (int i = 0; i < n; i++)
        scale *= n;
    for (int r = 0; r < m; r++)
        for (int j = 0; j < m; j++) {
            __float128 v = 1;
            for (int i = 2; i <= n; i++)
                v *= i;
            for (int k = 0; k < 4; k++) {
                for (int i = 2; i <= alpha[j][k]; i++)
                    v /= i;
                for (int i = 0; i < alpha[j][k]; i++)
                    v *= alpha[r][k];
            }
            a[(size_t)r * m + j] = v / scale;
            inv[(size_t)r * m + j] = r == j;
        }
    for (int col = 0; col < m; col++) {
        int pivot = col;
        for (int r = col + 1; r < m; r++) {
            __float128 x = a[(size_t)r * m + col], y = a[(size_t)pivot * m + col];
            if ((x < 0 ? -x : x) > (y < 0 ? -y : y))
                pivot = r;
        }
        for (int j = 0; j < m; j++) {
            __float128 t = a[(size_t)col * m + j];
            a[(size_t)col * m + j] = a[(size_t)pivot * m + j], a[(size_t)pivot * m + j] = t;
            t = inv[(size_t)col * m + j];
            inv[(size_t)col * m + j] = inv[(size_t)pivot * m + j], inv[(size_t)pivot * m + j] = t;
        }
        __float128 d = a[(size_t)col * m + col];
        for (int j = 0; j < m; j++)
            a[(size_t)col * m + j] /= d, inv[(size_t)col * m + j] /= d;
        for (int r = 0; r < m; r++) {
            __float128 f = a[(size_t)r * m + col];
            if (r == col || f == 0)
                continue;
            for (int j = col; j < m; j++)
                a[(size_t)r * m + j] -= f * a[(size_t)col * m + j];
            for (int j = 0; j < m; j++)
                inv[(size_t)r * m + j] -= f * inv[(size_t)col * m + j];
        }
    }
    free(a), free(alpha);
}

/* Every degree's inverse is within what the margin assumes (bernstein.h: TPK_BERNSTEIN_INVERSE_ERROR x
 * (inverse_norm + 1), as a row-sum norm) of the exact one, and so inverse x collocation is the identity
 * within that too (the collocation matrix's rows are >= 0 and sum to 1). The margin of each degree is
 * printed with its inverse's norm. */
TPK_TEST(inverse_accurate)
{
    for (int n = 1; n <= TPK_BERNSTEIN_MAX_DEGREE; n++) {
        const tpk_bernstein *b = table(n);
        CHECK(b != NULL);
        if (!b)
            continue;
        int m = b->points;
        __float128 *inv = malloc(sizeof *inv * (size_t)m * (size_t)m);
        exact_inverse(n, b, inv);
        double worst = 0, norm = 0;
        for (int r = 0; r < m; r++) {
            double row = 0, exact_row = 0;
            for (int j = 0; j < m; j++) {
                __float128 e = (__float128)b->inverse[(size_t)r * m + j] - inv[(size_t)r * m + j];
                row += (double)(e < 0 ? -e : e);
                exact_row += fabs((double)inv[(size_t)r * m + j]);
            }
            worst = fmax(worst, row), norm = fmax(norm, exact_row);
        }
        printf("degree %2d: %3d points, inverse norm %.4g (exact %.4g), error %.3g = %.3g x (norm + 1), margin %.3g\n", n,
               m, b->inverse_norm, norm, worst, worst / (b->inverse_norm + 1), tpk_bernstein_margin(b));
        CHECK(worst <= TPK_BERNSTEIN_INVERSE_ERROR * (b->inverse_norm + 1));
        free(inv);
    }
}
