/* Vertex checks (1xx): non-finite coordinates, exact and near duplicates, unused vertices.
 *
 * Duplicates are found on a uniform grid (a hash table over the occupied cells) whose cells are at least
 * h = tol * (bounding-box diagonal) wide and hold about one point on average: a point is compared with
 * the points of its own cell, and of a neighbouring cell only when it lies within h of that side, so most
 * points look at one cell. Every pair is reported once, from its higher id: vertex j duplicates the
 * lowest-id vertex i < j with the same coordinates (exact, 102), else the lowest within h (near, 103).
 * With --tol 0, h = 0 and only exact duplicates are found (they always share a cell). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/parallel.h"

static int point_finite(const double *p)
{
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

static void check_nonfinite(const tpk_mesh *m, tpk_check_report *report)
{
    for (int64_t v = 0; v < m->point_count; v++) {
        const double *p = m->points + 3 * v;
        if (point_finite(p))
            continue;
        tpk_example *ex = tpk_check_hit(report, 101, "vertex");
        int64_t id = v;
        tpk_example_ids(ex, 1, &id);
        tpk_example_note(ex, "(%g, %g, %g)", p[0], p[1], p[2]);
    }
}

static void check_unused(const tpk_mesh *m, tpk_check_report *report, uint8_t *used)
{
    for (int64_t c = 0; c < m->cell_count; c++) {
        for (int64_t i = m->cell_offsets[c]; i < m->cell_offsets[c + 1]; i++) {
            int32_t v = m->cell_conn[i];
            if (v >= 0 && v < m->point_count)
                used[v] = 1;
        }
    }
    for (int64_t v = 0; v < m->point_count; v++) {
        if (used[v])
            continue;
        tpk_example *ex = tpk_check_hit(report, 104, "vertex");
        int64_t id = v;
        tpk_example_ids(ex, 1, &id);
        if (point_finite(m->points + 3 * v))
            tpk_example_point(ex, m->points + 3 * v);
    }
}

/* ---- near duplicates on a grid -------------------------------------------------------------------- */

typedef struct grid {
    double lo[3], h;
    int64_t slots;       /* power of two */
    uint64_t *keys;      /* per slot: cell key + 1, 0 = empty */
    int64_t *first;      /* per slot: start of the cell's run in `ids` */
    int64_t *count;
    int32_t *ids;        /* point ids grouped by cell, ascending within a cell */
} grid;

static uint64_t cell_key(int64_t x, int64_t y, int64_t z)
{
    uint64_t k = (uint64_t)x * 0x9E3779B97F4A7C15ull ^ (uint64_t)y * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)z * 0x165667B19E3779F9ull;
    k ^= k >> 29;
    return k * 0xBF58476D1CE4E5B9ull;
}

static void cell_of(const grid *g, const double *p, int64_t c[3])
{
    for (int k = 0; k < 3; k++)
        c[k] = (int64_t)floor((p[k] - g->lo[k]) / g->h);
}

static int64_t find_slot(const grid *g, uint64_t key)
{
    int64_t s = (int64_t)(key & (uint64_t)(g->slots - 1));
    while (g->keys[s] && g->keys[s] != key + 1)
        s = (s + 1) & (g->slots - 1);
    return s;
}

/* Keys of distinct cells can collide in 64 bits only astronomically rarely; a collision merges two
 * cells' runs, which costs comparisons, never correctness (distances are always computed). */
static int grid_build(grid *g, const tpk_mesh *m, double h)
{
    g->h = h;
    for (int k = 0; k < 3; k++)
        g->lo[k] = INFINITY;
    for (int64_t v = 0; v < m->point_count; v++)
        if (point_finite(m->points + 3 * v))
            for (int k = 0; k < 3; k++)
                g->lo[k] = fmin(g->lo[k], m->points[3 * v + k]);
    g->slots = 16;
    while (g->slots < 2 * m->point_count)
        g->slots *= 2;
    g->keys = calloc((size_t)g->slots, sizeof *g->keys);
    g->first = calloc((size_t)g->slots, sizeof *g->first);
    g->count = calloc((size_t)g->slots, sizeof *g->count);
    g->ids = malloc(sizeof *g->ids * (size_t)(m->point_count ? m->point_count : 1));
    int64_t *slot_of = malloc(sizeof *slot_of * (size_t)(m->point_count ? m->point_count : 1));
    if (!g->keys || !g->first || !g->count || !g->ids || !slot_of) {
        free(slot_of);
        return -1;
    }
    for (int64_t v = 0; v < m->point_count; v++) {
        slot_of[v] = -1;
        if (!point_finite(m->points + 3 * v))
            continue;
        int64_t c[3];
        cell_of(g, m->points + 3 * v, c);
        uint64_t key = cell_key(c[0], c[1], c[2]);
        int64_t s = find_slot(g, key);
        g->keys[s] = key + 1;
        g->count[s]++;
        slot_of[v] = s;
    }
    int64_t at = 0;
    for (int64_t s = 0; s < g->slots; s++) {
        g->first[s] = at;
        at += g->count[s];
        g->count[s] = 0;
    }
    for (int64_t v = 0; v < m->point_count; v++)
        if (slot_of[v] >= 0)
            g->ids[g->first[slot_of[v]] + g->count[slot_of[v]]++] = (int32_t)v;
    free(slot_of);
    return 0;
}

static void grid_free(grid *g)
{
    free(g->keys);
    free(g->first);
    free(g->count);
    free(g->ids);
}

typedef struct near_job {
    const tpk_mesh *mesh;
    const grid *g;
    int32_t *exact;      /* lowest i < j with the same coordinates, or -1 */
    int32_t *match;      /* lowest i < j within tol, or -1 */
    double *distance;    /* its distance */
    double tol;          /* absolute tolerance (<= the grid's cell size) */
} near_job;

/* The neighbouring cells along one axis a point within `tol` of a cell side must also look at. */
static void axis_range(const grid *g, const double *p, const int64_t c[3], int k, double tol, int *lo, int *hi)
{
    double offset = p[k] - (g->lo[k] + (double)c[k] * g->h);
    *lo = offset <= tol ? -1 : 0;
    *hi = g->h - offset <= tol ? 1 : 0;
}

static void near_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    near_job *job = ctx;
    const grid *g = job->g;
    const double tol2 = job->tol * job->tol;
    (void)worker;
    for (int64_t j = begin; j < end; j++) {
        const double *p = job->mesh->points + 3 * j;
        job->exact[j] = job->match[j] = -1;
        if (!point_finite(p))
            continue;
        int64_t c[3], best = -1, same = -1;
        int lo[3], hi[3];
        double best_d2 = 0;
        cell_of(g, p, c);
        for (int k = 0; k < 3; k++)
            axis_range(g, p, c, k, job->tol, &lo[k], &hi[k]);
        for (int dx = lo[0]; dx <= hi[0]; dx++)
            for (int dy = lo[1]; dy <= hi[1]; dy++)
                for (int dz = lo[2]; dz <= hi[2]; dz++) {
                    int64_t s = find_slot(g, cell_key(c[0] + dx, c[1] + dy, c[2] + dz));
                    if (!g->keys[s])
                        continue;
                    for (int64_t k = g->first[s]; k < g->first[s] + g->count[s]; k++) {
                        int64_t i = g->ids[k];
                        if (i >= j)
                            break; /* ids ascend within a cell */
                        const double *q = job->mesh->points + 3 * i;
                        if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) {
                            if (same < 0 || i < same)
                                same = i;
                            continue;
                        }
                        double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                    (p[2] - q[2]) * (p[2] - q[2]);
                        if (d2 <= tol2 && (best < 0 || i < best)) {
                            best = i;
                            best_d2 = d2;
                        }
                    }
                }
        job->exact[j] = (int32_t)same;
        job->match[j] = (int32_t)best;
        job->distance[j] = sqrt(best_d2);
    }
}

static double bbox_diagonal(const tpk_mesh *m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = 0; v < m->point_count; v++)
        if (point_finite(m->points + 3 * v))
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], m->points[3 * v + k]);
                hi[k] = fmax(hi[k], m->points[3 * v + k]);
            }
    if (!(hi[0] >= lo[0]))
        return 0;
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

static void report_pair(tpk_check_report *report, const tpk_mesh *m, int id, int64_t j, int64_t i, double d)
{
    tpk_example *ex = tpk_check_hit(report, id, "vertex");
    int64_t ids[2] = {j, i};
    tpk_example_ids(ex, 2, ids);
    tpk_example_point(ex, m->points + 3 * j);
    if (id == 102)
        tpk_example_note(ex, "same coordinates as vertex %lld", (long long)i);
    else
        tpk_example_note(ex, "%.3g from vertex %lld", d, (long long)i);
}

static int check_duplicates(const tpk_mesh *m, tpk_check_report *report, tpk_diag *diag)
{
    size_t n = (size_t)(m->point_count ? m->point_count : 1);
    double diagonal = bbox_diagonal(m);
    double h = report->options.tol * diagonal;
    if (!isfinite(h))
        h = 0;
    /* Cells about one point wide on average, never narrower than the tolerance nor than 2^-40 of the
     * diagonal (cell coordinates stay far from overflow). */
    double cell = fmax(fmax(h, diagonal * 0x1p-40), diagonal / (2.0 * cbrt((double)n)));
    if (!(cell > 0))
        cell = 1; /* all points equal (or none finite): any width puts equal points in one cell */
    grid g;
    memset(&g, 0, sizeof g);
    int32_t *exact = malloc(sizeof *exact * n), *near = malloc(sizeof *near * n);
    double *distance = malloc(sizeof *distance * n);
    if (!exact || !near || !distance || grid_build(&g, m, cell)) {
        free(exact), free(near), free(distance);
        grid_free(&g);
        return tpk_diag_fail(diag, "check: out of memory for the duplicate-vertex search");
    }
    near_job job = {m, &g, exact, near, distance, h};
    tpk_parallel_for(m->point_count, tpk_threads_for(m->point_count, report->options.threads, 1 << 16),
                     near_range, &job);
    grid_free(&g);
    for (int64_t j = 0; j < m->point_count; j++) {
        if (exact[j] >= 0)
            report_pair(report, m, 102, j, exact[j], 0);
        else if (near[j] >= 0)
            report_pair(report, m, 103, j, near[j], distance[j]);
    }
    free(exact), free(near), free(distance);
    return 0;
}

int tpk_check_vertices(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag)
{
    const tpk_mesh *m = in->mesh;
    check_nonfinite(m, report);
    uint8_t *used = calloc((size_t)(m->point_count ? m->point_count : 1), 1);
    if (!used)
        return tpk_diag_fail(diag, "check: out of memory");
    check_unused(m, report, used);
    free(used);
    tpk_check_progress(report, "vertices", 0.5);
    int rc = check_duplicates(m, report, diag);
    tpk_check_progress(report, "vertices", 1.0);
    return rc;
}
