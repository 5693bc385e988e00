// Exact triangle and segment tests (exact_triangles.h): check's faces that cross (207) and convert's
// search of cuts (fixed_boundary.c). CGAL's Epick kernel decides every predicate exactly; the degenerate
// inputs its preconditions exclude are screened out first.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include "exact_triangles.h"

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point point(const double *p)
{
    return Point(p[0], p[1], p[2]);
}

Kernel::Triangle_3 triangle(const double *a, const double *b, const double *c)
{
    return Kernel::Triangle_3(point(a), point(b), point(c));
}
} // namespace

extern "C" int tpk_exact_triangles_meet(const double *a, const double *b, const double *c, const double *d,
                                        const double *e, const double *f)
{
    if (CGAL::collinear(point(a), point(b), point(c)) || CGAL::collinear(point(d), point(e), point(f)))
        return 0;
    return CGAL::do_intersect(triangle(a, b, c), triangle(d, e, f)) ? 1 : 0;
}

extern "C" int tpk_exact_segment_meets_triangle(const double *p, const double *q, const double *a,
                                                const double *b, const double *c)
{
    if (point(p) == point(q) || CGAL::collinear(point(a), point(b), point(c)))
        return 0;
    return CGAL::do_intersect(Kernel::Segment_3(point(p), point(q)), triangle(a, b, c)) ? 1 : 0;
}

extern "C" int tpk_exact_coplanar_side(const double *u, const double *v, const double *p, const double *q)
{
    if (!CGAL::coplanar(point(u), point(v), point(p), point(q)))
        return 2;
    if (CGAL::collinear(point(u), point(v), point(p)))
        return 0;
    CGAL::Orientation o = CGAL::coplanar_orientation(point(u), point(v), point(p), point(q));
    return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
}
