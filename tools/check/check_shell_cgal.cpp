// Shell face pairs for `tetpack check` (303 nonconforming_face, 406 shell_self_intersection). Candidate
// pairs are triangles whose bounding boxes overlap, found with a uniform grid (boxes sorted into the
// cells they cover; a pair is examined only in the cell of the lower corner of its boxes' overlap, so
// once) in parallel over runs of cells; CGAL's box_self_intersection_d was 5 to 10 times slower on
// surfaces of 10^5 to 10^6 triangles. Each candidate is decided with exact Epick predicates
// (orientation, do_intersect), so no tolerance is involved and the result does not depend on the grid.
#include "check_shell_cgal.h"
#include "base/predicates.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <new>
#include <thread>
#include <vector>

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point3;
typedef K::Point_2 Point2;

struct Tri {
    int32_t v[3];
    uint32_t face;
};

struct Context {
    const double *points;
    const tpk_bface *faces;
    const std::vector<Tri> *tris;
    int test_intersections;
};

Point3 point(const double *points, int32_t id)
{
    const double *p = points + 3 * (int64_t)id;
    return Point3(p[0], p[1], p[2]);
}

int face_size(const tpk_bface &f)
{
    return f.v[3] < 0 ? 3 : 4;
}

// Triangle t of face f, cut along the diagonal through its smallest id (as the converter cuts it).
Tri face_triangle(const tpk_bface &f, uint32_t index, int t)
{
    int n = face_size(f), m = 0;
    for (int i = 1; i < n; i++)
        if (f.v[i] < f.v[m])
            m = i;
    Tri tri;
    tri.v[0] = f.v[m];
    tri.v[1] = f.v[(m + 1 + t) % n];
    tri.v[2] = f.v[(m + 2 + t) % n];
    tri.face = index;
    return tri;
}

bool usable_triangle(const double *points, const Tri &t)
{
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++)
            if (!std::isfinite(points[3 * (int64_t)t.v[k] + c]))
                return false;
    return !CGAL::collinear(point(points, t.v[0]), point(points, t.v[1]), point(points, t.v[2]));
}

int shared_vertices(const tpk_bface &a, const tpk_bface &b)
{
    int shared = 0;
    for (int i = 0; i < face_size(a); i++)
        for (int j = 0; j < face_size(b); j++)
            shared += a.v[i] == b.v[j];
    return shared;
}

// Drops coordinate `axis`: exact, and one-to-one on a plane not perpendicular to that coordinate plane.
Point2 project(const Point3 &p, int axis)
{
    return axis == 0 ? Point2(p.y(), p.z()) : axis == 1 ? Point2(p.z(), p.x()) : Point2(p.x(), p.y());
}

// True when some edge line of `a` (counter-clockwise) has all of `b` on its closed outer side.
bool separated_by_edge_of(const Point2 a[3], const Point2 b[3])
{
    for (int e = 0; e < 3; e++) {
        bool all_out = true;
        for (int k = 0; k < 3 && all_out; k++)
            all_out = CGAL::orientation(a[e], a[(e + 1) % 3], b[k]) != CGAL::LEFT_TURN;
        if (all_out)
            return true;
    }
    return false;
}

// For coplanar triangles: 0 when their interiors are disjoint, else +1 when they face the same way and
// -1 when they face opposite ways. Two convex polygons have disjoint interiors exactly when an edge line
// of one of them separates them (closed half-planes), so the test is exact with orientation signs.
int coplanar_overlap(const Point3 p[3], const Point3 q[3])
{
    int axis = 0;
    CGAL::Orientation op = CGAL::COLLINEAR;
    for (axis = 0; axis < 3 && op == CGAL::COLLINEAR; axis++)
        op = CGAL::orientation(project(p[0], axis), project(p[1], axis), project(p[2], axis));
    axis--;
    Point2 a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = project(p[k], axis);
        b[k] = project(q[k], axis);
    }
    CGAL::Orientation oq = CGAL::orientation(b[0], b[1], b[2]);
    if (op == CGAL::RIGHT_TURN)
        std::swap(a[1], a[2]);
    if (oq == CGAL::RIGHT_TURN)
        std::swap(b[1], b[2]);
    if (separated_by_edge_of(a, b) || separated_by_edge_of(b, a))
        return 0;
    return op == oq ? 1 : -1;
}

// Sign of orient3d(a, b, c, d): the static filter, then CGAL's exact predicate where it is unsure.
int orient(const double *points, int32_t a, int32_t b, int32_t c, int32_t d)
{
    const double *pa = points + 3 * (int64_t)a, *pb = points + 3 * (int64_t)b;
    const double *pc = points + 3 * (int64_t)c, *pd = points + 3 * (int64_t)d;
    int sign = tpk_orient3d_filter(pa, pb, pc, pd);
    if (sign)
        return sign;
    return (int)CGAL::orientation(Point3(pa[0], pa[1], pa[2]), Point3(pb[0], pb[1], pb[2]),
                                  Point3(pc[0], pc[1], pc[2]), Point3(pd[0], pd[1], pd[2]));
}

// The kind of pair two triangles of different faces make, or 0. Most candidate pairs are neighbours
// that share a corner, or lie apart with one entirely on one side of the other's plane: both are
// settled by orientation signs before any CGAL construction.
int classify(const Context &ctx, const Tri &s, const Tri &t)
{
    const tpk_bface &fa = ctx.faces[s.face], &fb = ctx.faces[t.face];
    int side[3], shared = shared_vertices(fa, fb);
    for (int k = 0; k < 3; k++) // a shared corner is on the plane
        side[k] = t.v[k] == s.v[0] || t.v[k] == s.v[1] || t.v[k] == s.v[2]
                      ? 0
                      : orient(ctx.points, s.v[0], s.v[1], s.v[2], t.v[k]);
    bool coplanar = side[0] == 0 && side[1] == 0 && side[2] == 0;
    if (!coplanar && (shared > 0 || !ctx.test_intersections || (side[0] == side[1] && side[1] == side[2])))
        return 0;
    Point3 p[3], q[3];
    for (int k = 0; k < 3; k++) {
        p[k] = point(ctx.points, s.v[k]);
        q[k] = point(ctx.points, t.v[k]);
    }
    if (coplanar) {
        int overlap = coplanar_overlap(p, q);
        if (overlap < 0)
            return TPK_PAIR_NONCONFORMING;
        return overlap > 0 && shared == 0 && ctx.test_intersections ? TPK_PAIR_INTERSECTING : 0;
    }
    return CGAL::do_intersect(K::Triangle_3(p[0], p[1], p[2]), K::Triangle_3(q[0], q[1], q[2]))
               ? TPK_PAIR_INTERSECTING
               : 0;
}

void examine(const Context &ctx, uint32_t x, uint32_t y, std::vector<tpk_shell_pair> &out)
{
    const Tri &s = (*ctx.tris)[x], &t = (*ctx.tris)[y];
    if (s.face == t.face || ctx.faces[s.face].cell == ctx.faces[t.face].cell)
        return;
    int kind = classify(ctx, s, t);
    if (kind)
        out.push_back(tpk_shell_pair{std::min(s.face, t.face), std::max(s.face, t.face), kind});
}

struct Bounds {
    double lo[3], hi[3];
};

Bounds triangle_bounds(const double *points, const Tri &t)
{
    Bounds b;
    for (int c = 0; c < 3; c++) {
        b.lo[c] = b.hi[c] = points[3 * (int64_t)t.v[0] + c];
        for (int k = 1; k < 3; k++) {
            double x = points[3 * (int64_t)t.v[k] + c];
            b.lo[c] = std::min(b.lo[c], x);
            b.hi[c] = std::max(b.hi[c], x);
        }
    }
    return b;
}

// A uniform grid over the boxes: cell index along each axis is monotonic in the coordinate, so a box
// covers a contiguous range and the lower corner of two boxes' overlap lies in a cell both cover.
struct Grid {
    double origin[3], size;
    int64_t n[3];

    int64_t index(double x, int axis) const
    {
        double f = std::floor((x - origin[axis]) / size);
        return f < 0 ? 0 : f >= (double)n[axis] ? n[axis] - 1 : (int64_t)f;
    }
    uint64_t key(int64_t i, int64_t j, int64_t k) const
    {
        return ((uint64_t)i * (uint64_t)n[1] + (uint64_t)j) * (uint64_t)n[2] + (uint64_t)k;
    }
};

struct Entry {
    uint64_t cell;
    uint32_t box;
    bool operator<(const Entry &o) const { return cell != o.cell ? cell < o.cell : box < o.box; }
};

// Cell size: the mean largest extent of the boxes, doubled until the boxes cover at most 16 cells
// each on average (a few huge faces among small ones must not flood the grid).
bool make_entries(const std::vector<Bounds> &boxes, Grid &grid, std::vector<Entry> &entries)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, mean = 0;
    for (const Bounds &b : boxes) {
        double extent = 0;
        for (int c = 0; c < 3; c++) {
            lo[c] = std::min(lo[c], b.lo[c]);
            hi[c] = std::max(hi[c], b.hi[c]);
            extent = std::max(extent, b.hi[c] - b.lo[c]);
        }
        mean += extent / (double)boxes.size();
    }
    double span = std::max(hi[0] - lo[0], std::max(hi[1] - lo[1], hi[2] - lo[2]));
    grid.size = mean > 0 ? mean : span > 0 ? span : 1.0;
    grid.size = std::max(grid.size, span / 1e6); // at most ~10^6 cells per axis
    for (;;) {
        for (int c = 0; c < 3; c++) {
            grid.origin[c] = lo[c];
            grid.n[c] = (int64_t)std::floor((hi[c] - lo[c]) / grid.size) + 1;
        }
        uint64_t total = 0;
        for (const Bounds &b : boxes) {
            uint64_t cells = 1;
            for (int c = 0; c < 3; c++)
                cells *= (uint64_t)(grid.index(b.hi[c], c) - grid.index(b.lo[c], c) + 1);
            total += cells;
        }
        if (total <= 16 * (uint64_t)boxes.size() + 64)
            break;
        grid.size *= 2;
    }
    entries.clear();
    for (size_t i = 0; i < boxes.size(); i++) {
        const Bounds &b = boxes[i];
        for (int64_t x = grid.index(b.lo[0], 0); x <= grid.index(b.hi[0], 0); x++)
            for (int64_t y = grid.index(b.lo[1], 1); y <= grid.index(b.hi[1], 1); y++)
                for (int64_t z = grid.index(b.lo[2], 2); z <= grid.index(b.hi[2], 2); z++)
                    entries.push_back(Entry{grid.key(x, y, z), (uint32_t)i});
    }
    std::sort(entries.begin(), entries.end());
    return true;
}

bool boxes_overlap(const Bounds &a, const Bounds &b)
{
    for (int c = 0; c < 3; c++)
        if (a.hi[c] < b.lo[c] || b.hi[c] < a.lo[c])
            return false;
    return true;
}

// Pairs of boxes in the entries [begin, end) (whole cell runs), each reported in one cell only.
void scan_cells(const Context &ctx, const Grid &grid, const std::vector<Bounds> &boxes,
                const std::vector<Entry> &entries, size_t begin, size_t end, std::vector<tpk_shell_pair> &out)
{
    for (size_t i = begin, j; i < end; i = j) {
        for (j = i + 1; j < end && entries[j].cell == entries[i].cell; j++)
            ;
        for (size_t a = i; a < j; a++)
            for (size_t b = a + 1; b < j; b++) {
                const Bounds &x = boxes[entries[a].box], &y = boxes[entries[b].box];
                if (!boxes_overlap(x, y))
                    continue;
                uint64_t home = grid.key(grid.index(std::max(x.lo[0], y.lo[0]), 0),
                                         grid.index(std::max(x.lo[1], y.lo[1]), 1),
                                         grid.index(std::max(x.lo[2], y.lo[2]), 2));
                if (home == entries[i].cell)
                    examine(ctx, entries[a].box, entries[b].box, out);
            }
    }
}

// Splits the entries into `threads` ranges at cell boundaries and scans them in parallel.
void scan_parallel(const Context &ctx, const Grid &grid, const std::vector<Bounds> &boxes,
                   const std::vector<Entry> &entries, int threads, std::vector<tpk_shell_pair> &found)
{
    std::vector<size_t> cut(threads + 1, entries.size());
    cut[0] = 0;
    for (int w = 1; w < threads; w++) {
        size_t at = std::max(cut[w - 1], entries.size() / threads * w);
        while (at < entries.size() && at > 0 && entries[at].cell == entries[at - 1].cell)
            at++;
        cut[w] = at;
    }
    std::vector<std::vector<tpk_shell_pair>> parts(threads);
    std::vector<std::thread> workers;
    for (int w = 1; w < threads; w++)
        workers.emplace_back([&, w] { scan_cells(ctx, grid, boxes, entries, cut[w], cut[w + 1], parts[w]); });
    scan_cells(ctx, grid, boxes, entries, cut[0], cut[1], parts[0]);
    for (std::thread &t : workers)
        t.join();
    for (const std::vector<tpk_shell_pair> &p : parts)
        found.insert(found.end(), p.begin(), p.end());
}

bool pair_less(const tpk_shell_pair &x, const tpk_shell_pair &y)
{
    if (x.a != y.a)
        return x.a < y.a;
    if (x.b != y.b)
        return x.b < y.b;
    return x.kind < y.kind;
}

bool pair_equal(const tpk_shell_pair &x, const tpk_shell_pair &y)
{
    return x.a == y.a && x.b == y.b && x.kind == y.kind;
}

} // namespace

extern "C" int tpk_shell_face_pairs(const double *points, const tpk_bface *faces, int64_t face_count,
                                    int test_intersections, int threads, tpk_shell_pair **pairs,
                                    int64_t *pair_count)
{
    *pairs = nullptr;
    *pair_count = 0;
    try {
        std::vector<Tri> tris;
        tris.reserve((size_t)face_count * 2);
        for (int64_t f = 0; f < face_count; f++)
            for (int t = 0; t < face_size(faces[f]) - 2; t++) {
                Tri tri = face_triangle(faces[f], (uint32_t)f, t);
                if (usable_triangle(points, tri))
                    tris.push_back(tri);
            }
        std::vector<Bounds> boxes;
        boxes.reserve(tris.size());
        for (const Tri &t : tris)
            boxes.push_back(triangle_bounds(points, t));
        std::vector<tpk_shell_pair> found;
        if (!boxes.empty()) {
            Grid grid;
            std::vector<Entry> entries;
            make_entries(boxes, grid, entries);
            Context ctx = {points, faces, &tris, test_intersections};
            int workers = (int)std::max<int64_t>(1, std::min<int64_t>(threads, (int64_t)entries.size() / 20000));
            scan_parallel(ctx, grid, boxes, entries, workers, found);
        }
        std::sort(found.begin(), found.end(), pair_less);
        found.erase(std::unique(found.begin(), found.end(), pair_equal), found.end());
        *pairs = static_cast<tpk_shell_pair *>(malloc(sizeof(tpk_shell_pair) * (found.empty() ? 1 : found.size())));
        if (!*pairs)
            return -1;
        std::copy(found.begin(), found.end(), *pairs);
        *pair_count = (int64_t)found.size();
        return 0;
    } catch (const std::bad_alloc &) {
        return -1;
    }
}
