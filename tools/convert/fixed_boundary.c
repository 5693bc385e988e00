/* Tetrahedralization of one cell inside its fixed boundary triangulation (tools/convert/fixed_boundary.h),
 * through TetGen's C interface (tools/mesher/tetgen_shim.h) when the build has it. */
#include "fixed_boundary.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/predicates.h"
#include "tetpack_format.h"
#ifdef TPK_WITH_TETGEN
#include "mesher/tetgen_guard.h"
#endif

void tpk_fixed_tets_free(tpk_fixed_tets *tets)
{
    free(tets->points);
    free(tets->tets);
    memset(tets, 0, sizeof *tets);
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

/* TetGen with `switches` on the triangles. Returns 0, 1 with `why`, -1 when out of memory. */
static int run_tetgen(const char *switches, const double *points, int32_t point_count, const int32_t *triangles,
                      int32_t triangle_count, tpk_tetgen_output *t, char *why, size_t why_cap)
{
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
