// CGAL's exact orientation behind a C interface (predicates.h); the exact triangle tests are in
// exact_triangles.cpp.
// CGAL::orientation(p, q, r, s) is the sign of det[q-p, r-p, s-p] (orientationC3 in
// CGAL/predicates/kernel_ftC3.h); tests check that convention on constructed cases.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "predicates.h"

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

int sign_of(CGAL::Orientation o)
{
    return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
}

int orient_cgal(const double *a, const double *b, const double *c, const double *d)
{
    return sign_of(CGAL::orientation(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]),
                                     Point(c[0], c[1], c[2]), Point(d[0], d[1], d[2])));
}
} // namespace

extern "C" int tpk_orient3d_cgal(const double a[3], const double b[3], const double c[3],
                                 const double d[3])
{
    return orient_cgal(a, b, c, d);
}

extern "C" int tpk_orient3d_exact(const double a[3], const double b[3], const double c[3],
                                  const double d[3])
{
    int s = tpk_orient3d_filter(a, b, c, d);
    return s != 0 ? s : orient_cgal(a, b, c, d);
}

extern "C" int64_t tpk_orient3d_batch(const double *points, const int32_t *tets, int64_t count,
                                      int8_t *signs)
{
    int64_t exact_calls = 0;
    for (int64_t i = 0; i < count; i++) {
        const int32_t *v = tets + 4 * i;
        if (i + 16 < count) // the point gather misses cache on unordered input
            for (int k = 0; k < 4; k++)
                __builtin_prefetch(points + 3 * (int64_t)tets[4 * (i + 16) + k]);
        const double *a = points + 3 * (int64_t)v[0], *b = points + 3 * (int64_t)v[1];
        const double *c = points + 3 * (int64_t)v[2], *d = points + 3 * (int64_t)v[3];
        int s = tpk_orient3d_filter(a, b, c, d);
        if (s == 0) {
            s = orient_cgal(a, b, c, d);
            exact_calls++;
        }
        signs[i] = (int8_t)s;
    }
    return exact_calls;
}
