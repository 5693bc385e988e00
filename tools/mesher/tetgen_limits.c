/* What TetGen is not asked to do (mesher.h): point sets that span no volume (TetGen fails on them and
 * then crashes freeing its memory pools), coordinates its double arithmetic cannot hold, and volume
 * bounds that would make more tets than --max-tets. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/predicates.h"
#include "mesher.h"

/* orient2d of a, b, c projected on axes (i, j), exactly: the points lifted to z = 0 with a fourth point
 * above a (differences of copied coordinates and of 0 and 1 are exact, so the sign is orient2d's). */
static int orient2d_exact(const double *a, const double *b, const double *c, int i, int j)
{
    double pa[3] = {a[i], a[j], 0}, pb[3] = {b[i], b[j], 0}, pc[3] = {c[i], c[j], 0}, up[3] = {a[i], a[j], 1};
    return tpk_orient3d_exact(pa, pb, pc, up);
}

static int collinear(const double *a, const double *b, const double *c)
{
    return !orient2d_exact(a, b, c, 0, 1) && !orient2d_exact(a, b, c, 1, 2) && !orient2d_exact(a, b, c, 2, 0);
}

/* The first points (in input order) forming a tetrahedron of nonzero volume, decided exactly: tet[k] =
 * -1 from the first k that does not exist (all points equal, collinear or coplanar). */
static void find_tetrahedron(const double *p, int64_t count, int64_t tet[4])
{
    tet[0] = count > 0 ? 0 : -1, tet[1] = tet[2] = tet[3] = -1;
    for (int64_t i = 1; i < count && tet[0] >= 0 && tet[1] < 0; i++)
        if (memcmp(p + 3 * i, p, 3 * sizeof(double)))
            tet[1] = i;
    for (int64_t i = tet[1] + 1; tet[1] >= 0 && i < count && tet[2] < 0; i++)
        if (!collinear(p, p + 3 * tet[1], p + 3 * i))
            tet[2] = i;
    for (int64_t i = tet[2] + 1; tet[2] >= 0 && i < count && tet[3] < 0; i++)
        if (tpk_orient3d_exact(p, p + 3 * tet[1], p + 3 * tet[2], p + 3 * i))
            tet[3] = i;
}

static int check_magnitudes(const char *name, const double *p, int64_t count, tpk_diag *diag)
{
    double longest = 0;
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (int64_t i = 0; i < count; i++) {
            double v = p[3 * i + k];
            if (!(fabs(v) <= TPK_TETGEN_MAX_COORDINATE))
                return tpk_diag_fail(diag, "%s: point %lld has coordinate %.17g, beyond what TetGen's double "
                                     "arithmetic holds (|x| <= %g; its exact predicates multiply five coordinate "
                                     "differences); scale the input", name, (long long)i, v,
                                     TPK_TETGEN_MAX_COORDINATE);
            lo = fmin(lo, v), hi = fmax(hi, v);
        }
        longest = fmax(longest, hi - lo);
    }
    if (longest > 0 && longest < 1.0 / TPK_TETGEN_MAX_COORDINATE) /* 0: the degenerate cases below */
        return tpk_diag_fail(diag, "%s: the points span at most %g in any axis, below what TetGen's double "
                             "arithmetic holds (%g; products of five differences would underflow); scale the "
                             "input", name, longest, 1.0 / TPK_TETGEN_MAX_COORDINATE);
    return 0;
}

int tpk_tetgen_check_points(const char *name, const double *points, int64_t count, tpk_diag *diag)
{
    if (check_magnitudes(name, points, count, diag))
        return -1;
    int64_t tet[4];
    find_tetrahedron(points, count, tet);
    if (tet[3] >= 0)
        return 0;
    if (tet[1] < 0)
        return tpk_diag_fail(diag, "%s: all %lld points are the same point: they span no volume (TetGen needs 4 "
                             "points not on one plane)", name, (long long)count);
    const char *shape = tet[2] < 0 ? "on one line" : "on one plane";
    return tpk_diag_fail(diag, "%s: all %lld points lie %s (decided exactly): they span no volume, and TetGen "
                         "needs 4 points not on one plane", name, (long long)count, shape);
}

double tpk_surface_enclosed_volume(const tpk_mesh *surface)
{
    /* Divergence theorem: the signed volumes of the tets from the first point to each face's fan
     * triangles sum to the enclosed volume (positive when the faces are oriented outward). */
    const double *o = surface->points, *p = surface->points;
    double sum = 0;
    for (int64_t f = 0; f < surface->cell_count; f++) {
        const int32_t *c = surface->cell_conn + surface->cell_offsets[f];
        int64_t n = surface->cell_offsets[f + 1] - surface->cell_offsets[f];
        for (int64_t k = 1; k + 1 < n; k++) {
            const double *a = p + 3 * c[0], *b = p + 3 * c[k], *d = p + 3 * c[k + 1];
            double ax = a[0] - o[0], ay = a[1] - o[1], az = a[2] - o[2], bx = b[0] - o[0], by = b[1] - o[1],
                   bz = b[2] - o[2], dx = d[0] - o[0], dy = d[1] - o[1], dz = d[2] - o[2];
            sum += ax * (by * dz - bz * dy) + ay * (bz * dx - bx * dz) + az * (bx * dy - by * dx);
        }
    }
    return fabs(sum) / 6.0;
}

/* TetGen's 'a' bound in a switch string (the last one: TetGen reads left to right), or 0. */
static double max_volume_switch(const char *switches)
{
    double bound = 0;
    for (const char *a = strchr(switches, 'a'); a; a = strchr(a + 1, 'a'))
        if ((a[1] >= '0' && a[1] <= '9') || a[1] == '.')
            bound = strtod(a + 1, NULL);
    return bound;
}

int tpk_tetgen_check_tet_estimate(const char *name, const tpk_mesh *surface, const char *switches,
                                  int64_t max_tets, tpk_diag *diag)
{
    double bound = max_volume_switch(switches);
    if (!(bound > 0))
        return 0;
    double volume = tpk_surface_enclosed_volume(surface);
    double estimate = TPK_TETGEN_TETS_PER_VOLUME_BOUND * volume / bound;
    int64_t limit = max_tets > 0 ? max_tets : TPK_TETGEN_DEFAULT_MAX_TETS;
    if (!(estimate <= (double)limit))
        return tpk_diag_fail(diag, "%s: a largest tet volume of %g in an enclosed volume of %g makes about %.3g "
                             "tets, more than the limit of %lld (--max-tets N raises it; TetGen needs about 300 "
                             "bytes and a few microseconds per tet)", name, bound, volume, estimate,
                             (long long)limit);
    return 0;
}
