/* The cells group (2xx): node lists (201, 202, 212, 213), a mesh without volume cells (214), flat
 * polyhedra (215), orientation of tets by their exact sign (203, 204), the shape checks of split cells (check_cells_shape.c), tet quality (209, 210 and histograms)
 * and duplicate cells (211, check_cells_dup.c).
 *
 * Cells are cut into fixed chunks; each worker takes a contiguous run of chunks and reports in cell
 * order, so merging the workers in order gives the same counts, examples and histograms for any
 * --threads (the histogram sums are added per chunk, in chunk order). Memory beyond the mesh: the
 * chunk buffers per worker, the per-chunk sums and the duplicate search (check_cells_dup.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/cell_types.h"
#include "check_cells_internal.h"
#include "base/parallel.h"
#include "base/predicates.h"

#define CHUNK_CELLS 2048
#define HIST_COUNT 4

enum { SKIP = 0, TET = 1, SPLIT = 2 };

typedef struct cells_job {
    const tpk_mesh *mesh;
    tpk_check_report *report; /* options; progress from worker 0 */
    const tpk_cell_type_info *type_info[256]; /* tpk_cell_type per code, looked up once */
    int nonfinite_points; /* some coordinate is NaN or infinite (101): cells using one are not measured */
    int64_t chunk_count;
    tpk_cell_hits hits[TPK_MAX_THREADS];
    tpk_histogram hist[TPK_MAX_THREADS][HIST_COUNT];
    double (*chunk_sums)[HIST_COUNT]; /* per chunk, so the means do not depend on the thread count */
    int failed[TPK_MAX_THREADS];
} cells_job;

static const struct { const char *name; double lo, hi; } hist_defs[HIST_COUNT] = {
    {"min_dihedral_deg", 0, 90}, {"max_dihedral_deg", 60, 180}, {"radius_ratio", 0, 1}, {"aspect_ratio", 1, 10}};

static int repeated_at(const int32_t *ids, int64_t n)
{
    for (int64_t i = 1; i < n; i++)
        for (int64_t j = 0; j < i; j++)
            if (ids[i] == ids[j])
                return (int)i;
    return -1;
}

/* Whether b differs from a, and c does not lie on the line through a and b, decided exactly: each
 * component of (b - a) x (c - a) is, up to a nonzero factor, det[b - a, c - a, d - a] for a point d that
 * differs from a in one coordinate only (by a_k itself, or by 1 when a_k = 0: exact, never rounded). */
static int spans_plane(const double a[3], const double b[3], const double c[3])
{
    for (int k = 0; k < 3; k++) {
        double d[3] = {a[0], a[1], a[2]};
        d[k] = a[k] == 0.0 ? 1.0 : 2.0 * a[k];
        if (isfinite(d[k]) && tpk_orient3d_exact(a, b, c, d) != 0)
            return 1;
    }
    return 0;
}

/* 215: all points of a polyhedron in one plane (coincident or collinear included), exactly: b is the
 * first point other than a, c the first off the line ab, and no point leaves the plane abc. Returns 1
 * when the polyhedron is flat. */
static int polyhedron_is_flat(const tpk_mesh *mesh, int64_t cell)
{
    const int32_t *ids = mesh->cell_conn + mesh->cell_offsets[cell];
    int64_t n = mesh->cell_offsets[cell + 1] - mesh->cell_offsets[cell];
    for (int64_t i = 0; i < n; i++)
        if (ids[i] < 0 || ids[i] >= mesh->point_count)
            return 0; /* 201 reports it */
    const double *a = mesh->points + 3 * (int64_t)ids[0], *b = NULL, *c = NULL;
    for (int64_t i = 1; i < n && !c; i++) {
        const double *p = mesh->points + 3 * (int64_t)ids[i];
        if (!b && (p[0] != a[0] || p[1] != a[1] || p[2] != a[2]))
            b = p;
        else if (b && spans_plane(a, b, p))
            c = p;
    }
    for (int64_t i = 1; c && i < n; i++)
        if (tpk_orient3d_exact(a, b, c, mesh->points + 3 * (int64_t)ids[i]) != 0)
            return 0;
    return 1;
}

/* 212 or 213; returns 1 when the type and node count are ones the geometric checks handle. */
static int check_type(const cells_job *job, int64_t cell, tpk_cell_hits *hits)
{
    const tpk_mesh *mesh = job->mesh;
    int type = mesh->cell_types[cell];
    int64_t n = mesh->cell_offsets[cell + 1] - mesh->cell_offsets[cell];
    const tpk_cell_type_info *info = job->type_info[type];
    tpk_example *ex = NULL;
    if (!info) {
        ex = tpk_cell_hit(hits, 212, cell);
        tpk_example_note(ex, "unknown cell type %d", type);
    } else if (info->dim < 3) {
        ex = tpk_cell_hit(hits, 213, cell);
        tpk_example_note(ex, "%s (type %d, dimension %d)", info->name, type, info->dim);
    } else if (type == TPK_CELL_POLYHEDRON) {
        if (n >= 4 && !polyhedron_is_flat(mesh, cell))
            return 0; /* handled by the converter's polyhedron path, not checked here */
        ex = tpk_cell_hit(hits, n >= 4 ? 215 : 212, cell);
        if (n >= 4)
            tpk_example_note(ex, "all %lld points lie in one plane (exact): the faces enclose no volume", (long long)n);
        else
            tpk_example_note(ex, "polyhedron with %lld nodes, expected at least 4", (long long)n);
    } else if (type < TPK_CELL_TETRA || type > TPK_CELL_PYRAMID) {
        ex = tpk_cell_hit(hits, 212, cell);
        tpk_example_note(ex, "%s (type %d) is not converted: only linear tetra, voxel, hexahedron, wedge, "
                         "pyramid and polyhedron cells are", info->name, type);
    } else if (n != info->nodes) {
        ex = tpk_cell_hit(hits, 212, cell);
        tpk_example_note(ex, "%s with %lld nodes, expected %d", info->name, (long long)n, info->nodes);
    } else {
        return 1;
    }
    tpk_cell_example_vertices(ex, mesh, cell);
    return 0;
}

/* 201, 202; returns 1 when every id is in range and none repeats. */
static int check_ids(const tpk_mesh *mesh, int64_t cell, tpk_cell_hits *hits)
{
    const int32_t *ids = mesh->cell_conn + mesh->cell_offsets[cell];
    int64_t n = mesh->cell_offsets[cell + 1] - mesh->cell_offsets[cell];
    int ok = 1;
    for (int64_t i = 0; i < n; i++)
        if (ids[i] < 0 || ids[i] >= mesh->point_count) {
            tpk_example *ex = tpk_cell_hit(hits, 201, cell);
            tpk_cell_example_vertices(ex, mesh, cell);
            tpk_example_note(ex, "node %lld is vertex %d, expected 0 <= id < %lld", (long long)i, ids[i],
                             (long long)mesh->point_count);
            ok = 0;
            break;
        }
    int r = repeated_at(ids, n);
    if (r >= 0) {
        tpk_example *ex = tpk_cell_hit(hits, 202, cell);
        tpk_cell_example_vertices(ex, mesh, cell);
        if (ids[r] >= 0 && ids[r] < mesh->point_count)
            tpk_example_point(ex, mesh->points + 3 * (int64_t)ids[r]);
        tpk_example_note(ex, "vertex %d is named twice (node %d)", ids[r], r);
        ok = 0;
    }
    return ok;
}

static void tet_point(const tpk_mesh *mesh, int64_t cell, tpk_example *ex)
{
    if (!ex)
        return;
    double centre[3];
    tpk_cell_centre(mesh, cell, centre);
    tpk_example_point(ex, centre);
}

static void check_tet(cells_job *job, int64_t chunk, int worker, int64_t cell, int sign)
{
    const tpk_mesh *mesh = job->mesh;
    const tpk_check_options *opt = &job->report->options;
    tpk_cell_hits *hits = &job->hits[worker];
    if (sign <= 0) {
        tpk_example *ex = tpk_cell_hit(hits, sign == 0 ? 203 : 204, cell);
        tpk_cell_example_vertices(ex, mesh, cell);
        tet_point(mesh, cell, ex);
        tpk_example_note(ex, sign == 0 ? "det = 0 (exact): the four vertices are coplanar"
                                       : "det < 0 (exact): vertices in mirrored order");
        if (sign == 0)
            return; /* no shape to measure */
    }
    const int32_t *t = mesh->cell_conn + mesh->cell_offsets[cell];
    tpk_tet_quality q;
    tpk_tet_quality_of(mesh->points + 3 * (int64_t)t[0], mesh->points + 3 * (int64_t)t[1],
                       mesh->points + 3 * (int64_t)t[2], mesh->points + 3 * (int64_t)t[3], &q);
    double values[HIST_COUNT] = {q.min_dihedral_deg, q.max_dihedral_deg, q.radius_ratio, q.aspect_ratio};
    for (int h = 0; h < HIST_COUNT; h++) {
        tpk_histogram_add(&job->hist[worker][h], values[h]);
        if (isfinite(values[h])) /* as tpk_histogram_add counts it */
            job->chunk_sums[chunk][h] += values[h];
    }
    if (q.min_dihedral_deg < opt->sliver_deg) {
        tpk_example *ex = tpk_cell_hit(hits, 209, cell);
        tpk_cell_example_vertices(ex, mesh, cell);
        tet_point(mesh, cell, ex);
        tpk_example_note(ex, "min dihedral %.3g deg (max %.4g deg)", q.min_dihedral_deg, q.max_dihedral_deg);
    }
    if (q.radius_ratio < opt->radius_ratio_min) {
        tpk_example *ex = tpk_cell_hit(hits, 210, cell);
        tpk_cell_example_vertices(ex, mesh, cell);
        tet_point(mesh, cell, ex);
        tpk_example_note(ex, "radius ratio %.3g", q.radius_ratio);
    }
}

static int finite_corners(const tpk_mesh *mesh, int64_t cell)
{
    for (int64_t i = mesh->cell_offsets[cell]; i < mesh->cell_offsets[cell + 1]; i++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(mesh->points[3 * (int64_t)mesh->cell_conn[i] + k]))
                return 0;
    return 1;
}

/* One chunk: node lists first (gathering the usable tets for one batch of exact signs), then the
 * geometry of every usable cell, in cell order so each check's examples stay sorted. */
static void check_chunk(cells_job *job, int64_t chunk, int worker, uint8_t *kind, int32_t *tets, int8_t *signs)
{
    const tpk_mesh *mesh = job->mesh;
    tpk_cell_hits *hits = &job->hits[worker];
    int64_t begin = chunk * CHUNK_CELLS, end = begin + CHUNK_CELLS;
    end = end < mesh->cell_count ? end : mesh->cell_count;
    int64_t tet_count = 0;
    for (int64_t c = begin; c < end; c++) {
        int known = check_type(job, c, hits);
        int ids_ok = check_ids(mesh, c, hits);
        int type = mesh->cell_types[c];
        int finite = !job->nonfinite_points || (known && ids_ok && finite_corners(mesh, c));
        kind[c - begin] = !known || !ids_ok || !finite ? SKIP : type == TPK_CELL_TETRA ? TET : SPLIT;
        if (kind[c - begin] == TET)
            memcpy(tets + 4 * tet_count++, mesh->cell_conn + mesh->cell_offsets[c], 4 * sizeof *tets);
    }
    tpk_orient3d_batch(mesh->points, tets, tet_count, signs);
    int64_t next_tet = 0;
    for (int64_t c = begin; c < end; c++) {
        if (kind[c - begin] == TET) {
            if (next_tet + 8 < tet_count) /* the point gather misses cache on unordered input */
                for (int k = 0; k < 4; k++)
                    __builtin_prefetch(mesh->points + 3 * (int64_t)tets[4 * (next_tet + 8) + k]);
            check_tet(job, chunk, worker, c, signs[next_tet++]);
        }
        else if (kind[c - begin] == SPLIT)
            tpk_check_split_cell(mesh, c, job->report->options.warp_deg, hits);
    }
}

static void cells_worker(void *ctx, int64_t begin, int64_t end, int worker)
{
    cells_job *job = ctx;
    uint8_t *kind = malloc(CHUNK_CELLS);
    int32_t *tets = malloc(4 * CHUNK_CELLS * sizeof *tets);
    int8_t *signs = malloc(CHUNK_CELLS);
    job->hits[worker].max_examples = job->report->options.max_examples;
    for (int h = 0; h < HIST_COUNT; h++) {
        tpk_histogram *hist = &job->hist[worker][h];
        memset(hist, 0, sizeof *hist);
        hist->lo = hist_defs[h].lo;
        hist->hi = hist_defs[h].hi;
        hist->min = INFINITY;
        hist->max = -INFINITY;
    }
    if (!kind || !tets || !signs) {
        job->failed[worker] = 1;
    } else {
        for (int64_t chunk = begin; chunk < end; chunk++) {
            check_chunk(job, chunk, worker, kind, tets, signs);
            if (worker == 0 && ((chunk - begin) & 15) == 0)
                tpk_check_progress(job->report, "cells", (double)(chunk - begin) / (double)(end - begin));
        }
    }
    free(kind);
    free(tets);
    free(signs);
}

static void merge_histograms(cells_job *job, int threads)
{
    for (int h = 0; h < HIST_COUNT; h++) {
        tpk_histogram *out = tpk_check_histogram(job->report, hist_defs[h].name, hist_defs[h].lo, hist_defs[h].hi);
        if (!out)
            return;
        for (int w = 0; w < threads; w++) {
            const tpk_histogram *in = &job->hist[w][h];
            for (int b = 0; b < TPK_HIST_BINS; b++)
                out->bins[b] += in->bins[b];
            out->count += in->count;
            out->min = in->min < out->min ? in->min : out->min;
            out->max = in->max > out->max ? in->max : out->max;
        }
        for (int64_t c = 0; c < job->chunk_count; c++)
            out->sum += job->chunk_sums[c][h];
    }
}

/* 214: convert has nothing to convert without a 3-D cell (importers already drop empty and
 * lower-dimensional cells with a warning), so check must not call such a mesh clean. */
static void check_has_volume(const cells_job *job, tpk_check_report *report)
{
    const tpk_mesh *mesh = job->mesh;
    for (int64_t c = 0; c < mesh->cell_count; c++) {
        const tpk_cell_type_info *info = job->type_info[mesh->cell_types[c]];
        if (info && info->dim == 3)
            return;
    }
    tpk_example *ex = tpk_check_hit(report, 214, "file");
    tpk_example_note(ex, "%lld cells, none of them 3-D, over %lld points: nothing to tetrahedralize",
                     (long long)mesh->cell_count, (long long)mesh->point_count);
}

int tpk_check_cells(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag)
{
    const tpk_mesh *mesh = in->mesh;
    cells_job *job = calloc(1, sizeof *job);
    int64_t chunk_count = (mesh->cell_count + CHUNK_CELLS - 1) / CHUNK_CELLS;
    if (!job || !(job->chunk_sums = calloc((size_t)(chunk_count ? chunk_count : 1), sizeof *job->chunk_sums))) {
        free(job);
        return tpk_diag_fail(diag, "check cells: out of memory for %lld cells", (long long)mesh->cell_count);
    }
    job->mesh = mesh;
    job->report = report;
    for (int t = 0; t < 256; t++)
        job->type_info[t] = t == 41 ? NULL : tpk_cell_type(t); /* 41, convex point set: not a cell we know */
    job->chunk_count = chunk_count;
    for (int64_t i = 0; i < 3 * mesh->point_count && !job->nonfinite_points; i++)
        job->nonfinite_points = !isfinite(mesh->points[i]);
    int threads = tpk_threads_for(chunk_count, tpk_thread_count(report->options.threads), 1);
    tpk_parallel_for(chunk_count, threads, cells_worker, job);
    tpk_check_progress(report, "cells", 1.0);
    int failed = 0;
    for (int w = 0; w < threads; w++)
        failed |= job->failed[w];
    for (int w = 1; w < threads; w++)
        tpk_cell_hits_append(&job->hits[0], &job->hits[w]);
    if (!failed) {
        check_has_volume(job, report);
        tpk_cell_hits_report(&job->hits[0], report);
        merge_histograms(job, threads);
    }
    tpk_cell_hits_free(&job->hits[0]);
    free(job->chunk_sums);
    free(job);
    if (failed)
        return tpk_diag_fail(diag, "check cells: out of memory for the chunk buffers");
    return tpk_check_duplicate_cells(mesh, tpk_thread_count(report->options.threads), report, diag);
}
