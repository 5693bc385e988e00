/* The Bernstein bound of convert --max-error (tools/mesh/bernstein.c, tools/convert/refine.c): on a tet
 * of a cell's parameter space each mapped type's functions are polynomials of the degree
 * tpk_cell_map_degree states (the Bernstein form fitted at the domain points reproduces them at random
 * points; one degree less does not), the bound is never below the error sampled densely, and a
 * function that is linear on the tet gets a bound at rounding level. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "mesh/bernstein.h"
#include "mesh/cell_map.h"

static const int mapped[] = {12, 13, 24, 25, 26, 29, 31, 32, 33, TPK_CELL_MAP_LAGRANGE_TETRA + 3,
                             TPK_CELL_MAP_LAGRANGE_TETRA + 4, TPK_CELL_MAP_LAGRANGE_TETRA + 5,
                             TPK_CELL_MAP_LAGRANGE_TETRA + 6, TPK_CELL_MAP_LAGRANGE_WEDGE + 3};

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
    if ((type == 24 || (type > TPK_CELL_MAP_LAGRANGE_TETRA && type < TPK_CELL_MAP_LAGRANGE_WEDGE)) &&
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
    tpk_bernstein b;
    if (tpk_bernstein_make(degree, &b) != 0)
        return INFINITY;
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
            if (!(exact < 1e-9) || !(lower > 1e-6))
                fprintf(stderr, "type %d degree %d: misfit %g, at degree %d %g\n", type, degree, exact, degree - 1,
                        lower);
            CHECK(exact < 1e-9);
            CHECK(lower > 1e-6);
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
        tpk_bernstein b;
        CHECK(tpk_bernstein_make(tpk_cell_map_degree(type), &b) == 0);
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

TPK_TEST(linear_is_exact)
{
    /* a hexahedron whose nodes carry a linear function of position: on any tet its trilinear
     * interpolant is that function, so the bound against the tet's own linear values is rounding only */
    tpk_bernstein b;
    CHECK(tpk_bernstein_make(3, &b) == 0);
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
    CHECK(tpk_bernstein_make(0, &b) != 0 && tpk_bernstein_make(TPK_BERNSTEIN_MAX_DEGREE + 1, &b) != 0);
}
