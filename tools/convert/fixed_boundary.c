/* Tetrahedralization of one cell inside its fixed boundary triangulation (tools/convert/fixed_boundary.h),
 * through TetGen's C interface (tools/mesher/tetgen_shim.h) when the build has it. */
#include "fixed_boundary.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/exact_triangles.h"
#include "base/predicates.h"
#include "tetpack_format.h"
#ifdef TPK_WITH_TETGEN
#include "mesher/mesher.h"
#include "mesher/tetgen_guard.h"
#endif

void tpk_fixed_tets_free(tpk_fixed_tets *tets)
{
    free(tets->points);
    free(tets->tets);
    memset(tets, 0, sizeof *tets);
}

/* Does segment pq pass through the interior of triangle abc: p and q strictly on either side of its plane,
 * and the line pq strictly inside its three edges? */
static int segment_pierces(const double *p, const double *q, const double *a, const double *b, const double *c)
{
    int sp = tpk_orient3d_exact(a, b, c, p), sq = tpk_orient3d_exact(a, b, c, q);
    if (sp == 0 || sq == 0 || sp == sq)
        return 0;
    int s1 = tpk_orient3d_exact(p, q, a, b), s2 = tpk_orient3d_exact(p, q, b, c), s3 = tpk_orient3d_exact(p, q, c, a);
    return s1 != 0 && s1 == s2 && s2 == s3;
}

int tpk_fixed_boundary_surely_crosses(const double *points, int32_t point_count, const int32_t *triangles,
                                      int32_t triangle_count)
{
    for (int64_t i = 0; i < 3 * (int64_t)point_count; i++)
        if (!(fabs(points[i]) < 1e100))
            return 0;
    for (int32_t i = 0; i < triangle_count; i++)
        for (int32_t j = i + 1; j < triangle_count; j++) {
            const int32_t *s = triangles + 3 * i, *t = triangles + 3 * j;
            int shared = 0, corner[2] = {-1, -1}; /* the shared corner's place in s and in t */
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    if (s[a] == t[b])
                        shared++, corner[0] = a, corner[1] = b;
            if (shared > 2) /* the same triangle twice, or ids repeated within one: not a sign to go by */
                continue;
            if (shared == 2) { /* an edge in common: they cross only folded onto each other, in one plane
                                  (the corners not shared on the same side of it), as check's 207 says */
                int a = 0, b = 0; /* the corners not shared (each has one: a third match would make 3) */
                while (s[a] == t[0] || s[a] == t[1] || s[a] == t[2])
                    a++;
                while (t[b] == s[0] || t[b] == s[1] || t[b] == s[2])
                    b++;
                if (tpk_exact_coplanar_side(points + 3 * (size_t)s[(a + 1) % 3], points + 3 * (size_t)s[(a + 2) % 3],
                                            points + 3 * (size_t)s[a], points + 3 * (size_t)t[b]) == 1)
                    return 1;
                continue;
            }
            /* Sharing a corner, two triangles that cross do so along a segment from it, whose far end lies
             * on the edge opposite it in one of them, inside the other: that edge pierces the other. */
            for (int pass = 0; pass < 2; pass++, s = triangles + 3 * j, t = triangles + 3 * i) {
                const double *a = points + 3 * (size_t)t[0], *b = points + 3 * (size_t)t[1];
                const double *c = points + 3 * (size_t)t[2];
                for (int e = 0; e < 3; e++)
                    if ((!shared || e == (corner[pass] + 1) % 3) &&
                        segment_pierces(points + 3 * (size_t)s[e], points + 3 * (size_t)s[(e + 1) % 3], a, b, c))
                        return 1;
            }
        }
    return 0;
}

int tpk_fixed_boundary_available(void)
{
#ifdef TPK_WITH_TETGEN
    return 1;
#else
    return 0;
#endif
}

#ifdef TPK_WITH_TETGEN

typedef struct triple {
    int32_t v[3];
} triple;

static int compare_triples(const void *a, const void *b)
{
    const int32_t *x = ((const triple *)a)->v, *y = ((const triple *)b)->v;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

static triple sorted_triple(int32_t a, int32_t b, int32_t c)
{
    triple t = {{a, b, c}};
    for (int i = 1; i < 3; i++)
        for (int j = i; j > 0 && t.v[j - 1] > t.v[j]; j--) {
            int32_t s = t.v[j];
            t.v[j] = t.v[j - 1];
            t.v[j - 1] = s;
        }
    return t;
}

/* The faces of `tets` used by one tet only, sorted, must be exactly the input triangles, and none may be
 * used by three. Returns 0, 1 with `why`, -1 when out of memory. */
static int boundary_matches(const tpk_fixed_tets *r, const int32_t *triangles, int32_t triangle_count, char *why,
                            size_t cap)
{
    const int (*opposite)[3] = tpk_tet_faces; /* face k opposite corner k; sorted below, so unoriented */
    triple *faces = malloc(sizeof *faces * (size_t)(4 * r->tet_count + 1));
    triple *input = malloc(sizeof *input * (size_t)(triangle_count + 1));
    int rc = faces && input ? 0 : -1;
    int64_t once = 0;
    for (int64_t t = 0; rc == 0 && t < r->tet_count; t++)
        for (int k = 0; k < 4; k++) {
            const int32_t *v = r->tets + 4 * t;
            faces[4 * t + k] = sorted_triple(v[opposite[k][0]], v[opposite[k][1]], v[opposite[k][2]]);
        }
    for (int32_t i = 0; rc == 0 && i < triangle_count; i++)
        input[i] = sorted_triple(triangles[3 * i], triangles[3 * i + 1], triangles[3 * i + 2]);
    if (rc == 0) {
        qsort(faces, (size_t)(4 * r->tet_count), sizeof *faces, compare_triples);
        qsort(input, (size_t)triangle_count, sizeof *input, compare_triples);
    }
    for (int64_t i = 0; rc == 0 && i < 4 * r->tet_count;) {
        int64_t end = i + 1;
        while (end < 4 * r->tet_count && !compare_triples(&faces[i], &faces[end]))
            end++;
        if (end - i > 2 || (end - i == 1 && (once >= triangle_count || compare_triples(&faces[i], &input[once])))) {
            snprintf(why, cap, "TetGen's tets put face (%d %d %d) on %lld tets%s", faces[i].v[0], faces[i].v[1],
                     faces[i].v[2], (long long)(end - i), end - i == 1 ? ", not on the cell's boundary" : "");
            rc = 1;
        }
        once += end - i == 1;
        i = end;
    }
    if (rc == 0 && once != triangle_count) {
        snprintf(why, cap, "TetGen's tets cover %lld of the cell's %d boundary triangles", (long long)once,
                 triangle_count);
        rc = 1;
    }
    free(faces);
    free(input);
    return rc;
}

/* Every tet positive (exact), the input points where they were, the boundary kept. */
static int check_result(const tpk_fixed_tets *r, const double *points, int32_t point_count, const int32_t *triangles,
                        int32_t triangle_count, char *why, size_t cap)
{
    if (r->point_count < point_count || memcmp(r->points, points, sizeof *points * 3 * (size_t)point_count)) {
        snprintf(why, cap, "TetGen moved or dropped boundary points (%d points in, %d out)", point_count,
                 r->point_count);
        return 1;
    }
    for (int64_t t = 0; t < r->tet_count; t++) {
        const int32_t *v = r->tets + 4 * t;
        for (int k = 0; k < 4; k++)
            if (v[k] < 0 || v[k] >= r->point_count) {
                snprintf(why, cap, "TetGen's tet %lld names point %d of %d", (long long)t, v[k], r->point_count);
                return 1;
            }
        if (tpk_orient3d_exact(r->points + 3 * v[0], r->points + 3 * v[1], r->points + 3 * v[2],
                               r->points + 3 * v[3]) <= 0) {
            snprintf(why, cap, "TetGen's tet %lld (points %d %d %d %d) is flat or inverted", (long long)t, v[0], v[1],
                     v[2], v[3]);
            return 1;
        }
    }
    return boundary_matches(r, triangles, triangle_count, why, cap);
}

/* TetGen with `switches` on the triangles. Returns 0, 1 with `why`, -1 when out of memory. Points TetGen
 * cannot take (tpk_tetgen_check_points: coordinates past its arithmetic, or all on one plane, where it
 * fails or crashes whatever the cuts) are refused before its child process starts: a search of cuts
 * asks for up to 3^6 - 1 runs on such a cell. */
static int run_tetgen(const char *switches, const double *points, int32_t point_count, const int32_t *triangles,
                      int32_t triangle_count, tpk_tetgen_output *t, char *why, size_t why_cap)
{
    tpk_diag checked;
    memset(&checked, 0, sizeof checked);
    if (tpk_tetgen_check_points("its boundary", points, point_count, &checked) != 0) {
        snprintf(why, why_cap, "TetGen cannot take %s", checked.message);
        return 1;
    }
    int64_t *offsets = malloc(sizeof *offsets * (size_t)(triangle_count + 1));
    if (!offsets)
        return -1;
    for (int32_t i = 0; i <= triangle_count; i++)
        offsets[i] = 3 * (int64_t)i;
    tpk_tetgen_input in = {point_count, points, triangle_count, offsets, triangles};
    char message[400];
    /* In a child process: TetGen can crash or loop on a cell's boundary (issue 10), and a cell that
     * makes it do so is then refused by name instead of taking the converter down. */
    tpk_tetgen_guard guard = {.what = "tetrahedralizing a cell inside its boundary", .time_limit = 600};
    int code = tpk_tetgen_run_guarded(switches, &in, &guard, t, message, sizeof message);
    free(offsets);
    if (code == TPK_TETGEN_OUT_OF_MEMORY)
        return -1;
    if (code)
        snprintf(why, why_cap, "TetGen (switches %s) failed on its boundary: %s", switches, message);
    return code ? 1 : 0;
}

int tpk_fixed_boundary_crossing(const double *points, int32_t point_count, const int32_t *triangles,
                                int32_t triangle_count, char *why, size_t why_cap)
{
    tpk_tetgen_output d;
    int rc = run_tetgen("dQ", points, point_count, triangles, triangle_count, &d, why, why_cap);
    if (rc)
        return rc;
    if (d.triangle_count >= 2) {
        const int32_t *t = d.triangles;
        snprintf(why, why_cap, "its boundary triangles cross (TetGen -d finds %d crossing, among them (%d %d %d) "
                 "and (%d %d %d), in the cell's own numbering)", d.triangle_count, t[0], t[1], t[2], t[3], t[4], t[5]);
        rc = 1;
    }
    tpk_tetgen_output_free(&d);
    return rc;
}

int tpk_fixed_boundary_tets(const double *points, int32_t point_count, const int32_t *triangles,
                            int32_t triangle_count, tpk_fixed_tets *out, char *why, size_t why_cap)
{
    memset(out, 0, sizeof *out);
    /* TetGen 1.5 can crash, rather than report, on crossing input under -pY: look first. */
    int rc = tpk_fixed_boundary_crossing(points, point_count, triangles, triangle_count, why, why_cap);
    if (rc)
        return rc;
    tpk_tetgen_output t;
    /* p: the triangles are a piecewise linear complex; Y: no Steiner point on it, so the neighbours' faces
     * still match; Q: quiet. */
    if ((rc = run_tetgen("pYQ", points, point_count, triangles, triangle_count, &t, why, why_cap)))
        return rc;
    out->point_count = t.point_count;
    out->points = t.points;
    out->tet_count = t.tet_count;
    out->tets = t.tets;
    free(t.triangles);
    rc = check_result(out, points, point_count, triangles, triangle_count, why, why_cap);
    if (rc)
        tpk_fixed_tets_free(out);
    return rc;
}

#else

int tpk_fixed_boundary_crossing(const double *points, int32_t point_count, const int32_t *triangles,
                                int32_t triangle_count, char *why, size_t why_cap)
{
    (void)points, (void)point_count, (void)triangles, (void)triangle_count;
    snprintf(why, why_cap, "this build has no TetGen (TETPACK_WITH_TETGEN=OFF) to tell whether its boundary "
             "triangles cross");
    return 1;
}

int tpk_fixed_boundary_tets(const double *points, int32_t point_count, const int32_t *triangles,
                            int32_t triangle_count, tpk_fixed_tets *out, char *why, size_t why_cap)
{
    (void)points, (void)point_count, (void)triangles, (void)triangle_count;
    memset(out, 0, sizeof *out);
    snprintf(why, why_cap, "this build has no TetGen (TETPACK_WITH_TETGEN=OFF) to tetrahedralize it inside its "
             "boundary");
    return 1;
}

#endif
