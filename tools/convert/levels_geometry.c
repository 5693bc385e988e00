/* Levels of detail (levels_internal.h): the geometry the collapses and the shell distance measure with. */
#include <math.h>

#include "levels_internal.h"

/* 6 V / L^3 of the tet (a, b, c, d): 0 flat, 0.707 regular; negative when inverted. */
double levels_quality(const double *a, const double *b, const double *c, const double *d)
{
    double ab[3], ac[3], ad[3], e[3];
    double l2 = edge(a, b, ab), x;
    l2 = (x = edge(a, c, ac)) > l2 ? x : l2;
    l2 = (x = edge(a, d, ad)) > l2 ? x : l2;
    l2 = (x = edge(b, c, e)) > l2 ? x : l2;
    l2 = (x = edge(b, d, e)) > l2 ? x : l2;
    l2 = (x = edge(c, d, e)) > l2 ? x : l2;
    double det = ab[0] * (ac[1] * ad[2] - ac[2] * ad[1]) - ab[1] * (ac[0] * ad[2] - ac[2] * ad[0]) +
                 ab[2] * (ac[0] * ad[1] - ac[1] * ad[0]);
    return l2 > 0 ? det / (l2 * sqrt(l2)) : 0;
}

/* The distance from p to the triangle (a, b, c): to its closest point, found by the region of the
 * triangle's plane (corner, edge or inside) that p projects into. */
double levels_point_triangle(const double *p, const double *a, const double *b, const double *c)
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
    edge(a, b, ab), edge(a, c, ac), edge(a, p, ap), edge(b, p, bp), edge(c, p, cp);
    double d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2], d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2];
    double d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2], d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2];
    double d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2], d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2];
    double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
    const double *from = a, *dir = ab;
    double x = 0, y = 0, bc[3];
    if (d1 <= 0 && d2 <= 0)
        from = a;
    else if (d3 >= 0 && d4 <= d3)
        from = b;
    else if (d6 >= 0 && d5 <= d6)
        from = c;
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        x = d1 / (d1 - d3);
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        dir = ac, x = d2 / (d2 - d6);
    else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
        from = b, dir = bc, x = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    else {
        double den = 1 / (va + vb + vc);
        x = vb * den, y = vc * den;
    }
    edge(b, c, bc);
    for (int k = 0; k < 3; k++)
        q[k] = from[k] + x * dir[k] + y * ac[k];
    double e[3];
    return sqrt(edge(p, q, e));
}
