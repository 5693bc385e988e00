/* Ownership helpers for the converter's in-memory meshes. */
#include "mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"

static void free_fields(tpk_src_field *fields, int count)
{
    for (int i = 0; i < count; i++)
        free(fields[i].values);
    free(fields);
}

void tpk_mesh_free(tpk_mesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->points);
    free(mesh->cell_types);
    free(mesh->cell_offsets);
    free(mesh->cell_conn);
    free(mesh->face_offsets);
    free(mesh->faces);
    free_fields(mesh->fields, mesh->field_count);
    free(mesh->times);
    free(mesh->global_point_ids);
    free(mesh->global_cell_ids);
    memset(mesh, 0, sizeof *mesh);
}

int tpk_mesh_same_cells(const tpk_mesh *a, const tpk_mesh *b)
{
    return a->point_count == b->point_count && a->cell_count == b->cell_count &&
           !memcmp(a->points, b->points, sizeof *a->points * 3 * (size_t)a->point_count) &&
           !memcmp(a->cell_types, b->cell_types, (size_t)a->cell_count) &&
           !memcmp(a->cell_offsets, b->cell_offsets, sizeof *a->cell_offsets * (size_t)(a->cell_count + 1)) &&
           !memcmp(a->cell_conn, b->cell_conn, sizeof *a->cell_conn * (size_t)a->cell_offsets[a->cell_count]);
}

int tpk_mesh_add_field(tpk_mesh *mesh, const char *name, int association, int components,
                       int step_count, float *values)
{
    tpk_src_field *grown = realloc(mesh->fields, sizeof *grown * (size_t)(mesh->field_count + 1));
    if (!grown)
        return -1;
    mesh->fields = grown;
    tpk_src_field *f = &grown[mesh->field_count++];
    memset(f, 0, sizeof *f);
    strncpy(f->name, name, TPK_NAME_MAX - 1);
    f->association = association;
    f->components = components;
    f->step_count = step_count;
    f->values = values;
    return 0;
}

void tpk_tetmesh_free(tpk_tetmesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->points);
    free(mesh->vertex_source);
    free(mesh->tets);
    free(mesh->tet_source);
    free_fields(mesh->fields, mesh->field_count);
    free(mesh->times);
    memset(mesh, 0, sizeof *mesh);
}

int tpk_compare_int32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* The origin of one axis (spec §6.8): the number in [lo, hi] with the fewest significant bits, that is
 * 0 when the box straddles 0, else the one multiple of the largest power of two q that has a multiple
 * in [lo, hi] (two would make one of them a multiple of 2q). Every stored |x - origin| is at most
 * hi - lo, so float32 keeps all but at most one bit of the precision a centred origin gives, and a
 * coordinate that is a float32 multiple of q's granularity (0 and 1 of a unit cube, 10 and 11 of a
 * cube at 10) is stored exactly, where the centre 0.5 * (lo + hi) may not even be exact itself. */
static double axis_origin(double lo, double hi)
{
    if (!(lo <= hi) || !isfinite(lo) || !isfinite(hi) || (lo <= 0.0 && hi >= 0.0))
        return 0.0;
    int e;
    frexp(fmax(fabs(lo), fabs(hi)), &e);
    /* q = 2^e exceeds both bounds; halving it ends at the lowest set bit of lo at the latest, whose
     * multiples include lo itself (ldexp and the division by a power of two are exact). */
    for (double q = ldexp(1.0, e); q > 0.0; q *= 0.5) {
        double candidate = ceil(lo / q) * q;
        if (candidate <= hi)
            return candidate;
    }
    return lo;
}

typedef struct bounds_job {
    const double *points;
    double lo[TPK_MAX_THREADS][3], hi[TPK_MAX_THREADS][3];
} bounds_job;

static void bounds_range(void *ctx, int64_t begin, int64_t end, int w)
{
    bounds_job *job = ctx;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = begin; i < end; i++)
        for (int k = 0; k < 3; k++) {
            double x = job->points[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    memcpy(job->lo[w], lo, sizeof lo);
    memcpy(job->hi[w], hi, sizeof hi);
}

void tpk_points_origin_threads(const double *points, int64_t count, int threads, double origin[3])
{
    /* Each worker's bounds over its range, merged in worker order by the same strict comparisons: the
     * bound kept is the first of equal values in point order (0.0 or -0.0), as one pass would keep. */
    bounds_job *job = malloc(sizeof *job);
    int n = job ? tpk_threads_for(count, tpk_thread_count(threads), (int64_t)1 << 16) : 1;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    if (job) {
        job->points = points;
        tpk_parallel_for(count, n, bounds_range, job);
        for (int w = 0; w < n; w++)
            for (int k = 0; k < 3; k++) {
                lo[k] = job->lo[w][k] < lo[k] ? job->lo[w][k] : lo[k];
                hi[k] = job->hi[w][k] > hi[k] ? job->hi[w][k] : hi[k];
            }
        free(job);
    } else {
        bounds_job one = {.points = points};
        bounds_range(&one, 0, count, 0);
        memcpy(lo, one.lo[0], sizeof lo);
        memcpy(hi, one.hi[0], sizeof hi);
    }
    for (int k = 0; k < 3; k++)
        origin[k] = count ? axis_origin(lo[k], hi[k]) : 0.0;
}

void tpk_points_origin(const double *points, int64_t count, double origin[3])
{
    tpk_points_origin_threads(points, count, 0, origin);
}

typedef struct ids_job {
    const int32_t *ids;
    int64_t limit;
    int64_t first[TPK_MAX_THREADS];
} ids_job;

static void ids_range(void *ctx, int64_t begin, int64_t end, int w)
{
    ids_job *job = ctx;
    job->first[w] = -1;
    for (int64_t i = begin; i < end; i++)
        if (job->ids[i] < 0 || job->ids[i] >= job->limit) {
            job->first[w] = i;
            return;
        }
}

int64_t tpk_first_id_out_of_range(const int32_t *ids, int64_t count, int64_t limit, int threads)
{
    ids_job *job = malloc(sizeof *job);
    if (!job) { /* the same answer on one thread */
        for (int64_t i = 0; i < count; i++)
            if (ids[i] < 0 || ids[i] >= limit)
                return i;
        return -1;
    }
    job->ids = ids;
    job->limit = limit;
    threads = tpk_threads_for(count, tpk_thread_count(threads), (int64_t)1 << 16);
    tpk_parallel_for(count, threads, ids_range, job);
    int64_t first = -1;
    for (int w = 0; w < threads && first < 0; w++) /* ranges in order: the first worker's find is the first */
        first = job->first[w];
    free(job);
    return first;
}
