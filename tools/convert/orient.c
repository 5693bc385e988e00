/* Exact orientation (pipeline stage 2): every tet made positive, det[p1-p0, p2-p0, p3-p0] > 0, decided
 * by the filtered exact predicate (predicates.h: a static error bound, CGAL when uncertain).
 * Inverted tets get v2 and v3 swapped, or are refused (TPK_ORIENT_REFUSE_INVERTED); zero-volume tets
 * are refused or, when asked, dropped. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "pipeline.h"
#include "base/predicates.h"

enum { TET_POSITIVE = 1, TET_INVERTED = -1, TET_FLAT = 0, TET_REPEATED = 2 };

typedef struct orient_job {
    const double *points;
    int32_t *tets;
    int8_t *kinds;
    uint8_t *turned_over; /* mark_range: per tet, turned over */
    int swap_inverted;
    int64_t inverted[TPK_MAX_THREADS];
    int64_t flat[TPK_MAX_THREADS];
    int64_t repeated[TPK_MAX_THREADS];
} orient_job;

static void mark_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const orient_job *job = ctx;
    (void)worker;
    for (int64_t t = begin; t < end; t++)
        job->turned_over[t] = job->kinds[t] == TET_INVERTED;
}

static int repeats_vertex(const int32_t *v)
{
    return v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3];
}

static void orient_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    orient_job *job = ctx;
    int64_t inverted = 0, flat = 0, repeated = 0;
    tpk_orient3d_batch(job->points, job->tets + 4 * begin, end - begin, job->kinds + begin);
    for (int64_t t = begin; t < end; t++) {
        int32_t *v = job->tets + 4 * t;
        if (repeats_vertex(v)) {
            job->kinds[t] = TET_REPEATED;
            repeated++;
        } else if (job->kinds[t] == TET_INVERTED) {
            if (job->swap_inverted) {
                int32_t swap = v[2];
                v[2] = v[3];
                v[3] = swap;
            }
            inverted++;
        } else if (job->kinds[t] == TET_FLAT) {
            flat++;
        }
    }
    job->inverted[worker] = inverted;
    job->flat[worker] = flat;
    job->repeated[worker] = repeated;
}

/* "cell C <what>: points a (x, y, z), ...": tet t in source terms (the mesh may have been reordered,
 * and its points may be stored relative to mesh->origin). */
static void describe_tet(const tpk_tetmesh *mesh, int64_t t, const char *what, char *text, size_t cap)
{
    const int32_t *v = mesh->tets + 4 * t;
    int used = snprintf(text, cap, "cell %d %s", mesh->tet_source ? mesh->tet_source[t] : (int32_t)t, what);
    for (int k = 0; k < 4 && used > 0 && (size_t)used < cap; k++) {
        const double *p = mesh->points + 3 * (int64_t)v[k];
        used += snprintf(text + used, cap - (size_t)used, "%s %d (%.17g, %.17g, %.17g)", k ? "," : ": points",
                         mesh->vertex_source ? mesh->vertex_source[v[k]] : v[k], mesh->origin[0] + p[0],
                         mesh->origin[1] + p[1], mesh->origin[2] + p[2]);
    }
}

/* The tet of either kind from the lowest source cell (tets may have been reordered), so that the
 * message names the same cell whatever the order. */
static int64_t first_of(const tpk_tetmesh *mesh, const int8_t *kinds, int kind_a, int kind_b)
{
    int64_t first = -1;
    for (int64_t t = 0; t < mesh->tet_count; t++)
        if ((kinds[t] == kind_a || kinds[t] == kind_b) &&
            (first < 0 || (mesh->tet_source && mesh->tet_source[t] < mesh->tet_source[first])))
            first = t;
    return first;
}

static int refuse_degenerate(const tpk_tetmesh *mesh, const int8_t *kinds, const tpk_orient_stats *stats,
                             tpk_diag *diag)
{
    char tet[600];
    int64_t t = first_of(mesh, kinds, TET_FLAT, TET_REPEATED);
    const char *what = kinds[t] == TET_REPEATED
                           ? "has a repeated vertex"
                           : "has zero volume (its 4 vertices are coplanar as the file stores them: float32 offsets "
                             "from the origin, shown here in world coordinates)";
    describe_tet(mesh, t, what, tet, sizeof tet);
    return tpk_diag_fail(diag, "%s; %lld degenerate tets in all (%lld with a repeated vertex, %lld flat); "
                               "pass --drop-degenerate to remove them",
                         tet, (long long)stats->degenerate, (long long)stats->repeated_vertex,
                         (long long)(stats->degenerate - stats->repeated_vertex));
}

/* Only with TPK_ORIENT_REFUSE_INVERTED (--strict-orientation): a tet's node order is a labeling, so
 * turning it over changes no geometry and is the default; who wants to catch a node-order bug in a
 * writer or an importer asks for the refusal, and the message says what it looks like. */
static int refuse_inverted(const tpk_tetmesh *mesh, const int8_t *kinds, const tpk_orient_stats *stats,
                           tpk_diag *diag)
{
    char tet[600];
    int64_t t = first_of(mesh, kinds, TET_INVERTED, TET_INVERTED);
    describe_tet(mesh, t, "is inverted (negative volume)", tet, sizeof tet);
    if (stats->inverted_fixed == mesh->tet_count)
        return tpk_diag_fail(diag, "%s, and so are all %lld tets: the file lists tet nodes in the mirrored "
                                   "(left-handed) order; without --strict-orientation they are turned over",
                             tet, (long long)stats->inverted_fixed);
    return tpk_diag_fail(diag, "%s; %lld of %lld tets are inverted; without --strict-orientation they are "
                               "turned over",
                         tet, (long long)stats->inverted_fixed, (long long)mesh->tet_count);
}

int64_t tpk_drop_tets(tpk_tetmesh *mesh, const uint8_t *drop)
{
    int64_t old_count = mesh->tet_count, kept = 0;
    for (int64_t t = 0; t < old_count; t++) {
        if (drop[t])
            continue;
        memmove(mesh->tets + 4 * kept, mesh->tets + 4 * t, 4 * sizeof *mesh->tets);
        if (mesh->tet_source)
            mesh->tet_source[kept] = mesh->tet_source[t];
        kept++;
    }
    for (int i = 0; i < mesh->field_count; i++) {
        tpk_src_field *f = &mesh->fields[i];
        if (f->association != TPK_ASSOC_TET)
            continue;
        int64_t out = 0;
        for (int s = 0; s < f->step_count; s++)
            for (int64_t t = 0; t < old_count; t++)
                if (!drop[t])
                    f->values[out++] = f->values[(int64_t)s * old_count + t];
    }
    mesh->tet_count = kept;
    return old_count - kept;
}

/* kinds[] becomes the drop mask of tpk_drop_tets (1 for the degenerate tets), and turned_over the marks
 * of the tets kept. */
static void drop_degenerate(tpk_tetmesh *mesh, int8_t *kinds, uint8_t *turned_over)
{
    int64_t kept = 0;
    for (int64_t t = 0; t < mesh->tet_count; t++) {
        int inverted = kinds[t] == TET_INVERTED;
        kinds[t] = kinds[t] == TET_FLAT || kinds[t] == TET_REPEATED;
        if (turned_over && !kinds[t])
            turned_over[kept++] = (uint8_t)inverted;
    }
    tpk_drop_tets(mesh, (const uint8_t *)kinds);
}

int tpk_orient(tpk_tetmesh *mesh, int flags, int threads, tpk_orient_stats *stats, tpk_diag *diag)
{
    return tpk_orient_marked(mesh, flags, threads, stats, NULL, diag);
}

int tpk_orient_marked(tpk_tetmesh *mesh, int flags, int threads_requested, tpk_orient_stats *stats,
                      uint8_t *turned_over, tpk_diag *diag)
{
    tpk_orient_stats local = {0, 0, 0};
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof *stats);
    if (!mesh || (mesh->tet_count > 0 && (!mesh->tets || !mesh->points)))
        return tpk_diag_fail(diag, "orient: invalid tet mesh");
    int64_t bad = tpk_first_id_out_of_range(mesh->tets, 4 * mesh->tet_count, mesh->vertex_count, threads_requested);
    if (bad >= 0)
        return tpk_diag_fail(diag, "orient: tet %lld names vertex %d; the mesh has %lld vertices",
                             (long long)(bad / 4), mesh->tets[bad], (long long)mesh->vertex_count);
    orient_job *job = calloc(1, sizeof *job);
    int8_t *kinds = tpk_alloc_large((size_t)(mesh->tet_count ? mesh->tet_count : 1));
    if (!job || !kinds) {
        free(job);
        free(kinds);
        return tpk_diag_fail(diag, "orient: out of memory (%lld tets)", (long long)mesh->tet_count);
    }
    job->points = mesh->points;
    job->tets = mesh->tets;
    job->kinds = kinds;
    job->swap_inverted = !(flags & TPK_ORIENT_REFUSE_INVERTED);
    int threads = tpk_threads_for(mesh->tet_count, tpk_thread_count(threads_requested), 65536);
    tpk_parallel_for(mesh->tet_count, threads, orient_range, job);
    for (int w = 0; w < threads; w++) {
        stats->inverted_fixed += job->inverted[w];
        stats->degenerate += job->flat[w] + job->repeated[w];
        stats->repeated_vertex += job->repeated[w];
    }
    int rc = 0;
    if (stats->degenerate > 0 && !(flags & TPK_ORIENT_DROP_DEGENERATE))
        rc = refuse_degenerate(mesh, kinds, stats, diag);
    else if (stats->inverted_fixed > 0 && (flags & TPK_ORIENT_REFUSE_INVERTED))
        rc = refuse_inverted(mesh, kinds, stats, diag);
    else if (stats->degenerate > 0)
        drop_degenerate(mesh, kinds, turned_over);
    else if (turned_over) {
        job->kinds = kinds;
        job->turned_over = turned_over;
        tpk_parallel_for(mesh->tet_count, threads, mark_range, job);
    }
    free(kinds); /* not kept: connect maps its arrays next, and a kept block would add to its peak */
    free(job);
    return rc;
}
