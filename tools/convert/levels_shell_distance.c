/* Levels of detail (levels_internal.h): the shell distance: how far the full mesh's shell lies from a
 * level's, at the shell vertices the level removed. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "levels_internal.h"
#include "tetpack_format.h"

/* shell_distance's search, for the removed shell vertices of [begin, end) (tpk_parallel_for): each
 * one's distance to its owner's level faces, and the tet of the nearest in near_tet. */
typedef struct shell_job {
    const simplifier *s;
    const tpk_tetmesh *lvl;
    const int64_t *start;
    const int32_t *tri, *at, *tet, *level_of, *owner;
    int32_t *near_tet;
    double worst[TPK_MAX_THREADS]; /* per worker */
} shell_job;

static void shell_vertices(void *ctx, int64_t begin, int64_t end, int worker)
{
    shell_job *j = ctx;
    const simplifier *s = j->s;
    const tpk_tetmesh *lvl = j->lvl;
    const int64_t *start = j->start;
    const int32_t *tri = j->tri, *at = j->at, *owner = j->owner;
    double worst = 0;
    for (int64_t u = begin; u < end; u++) {
        if (!(s->boundary[u] && s->removed[u]))
            continue;
        const double *p = point(s, (int32_t)u);
        int32_t from = owner && owner[u] >= 0 ? owner[u] : survivor(s, (int32_t)u);
        int32_t around[3] = {j->level_of[from], -1, -1}, face = -1;
        double best = INFINITY;
        /* the owner's faces hold a witness: they alone give the bound (a descent would make it
         * tighter, at twice the cost, and the bound is what the tolerance is about) */
        int rounds = owner && owner[u] >= 0 ? 1 : 256;
        for (int steps = 0, nearer = 1; nearer && steps < rounds; steps++) {
            nearer = 0;
            for (int k = 0; k < 3 && around[k] >= 0; k++)
                for (int64_t i = start[around[k]]; i < start[around[k] + 1]; i++) {
                    const int32_t *c = tri + 3 * at[i];
                    double d = levels_point_triangle(p, lvl->points + 3 * (size_t)c[0], lvl->points + 3 * (size_t)c[1],
                                              lvl->points + 3 * (size_t)c[2]);
                    if (d < best)
                        best = d, face = at[i], nearer = 1;
                }
            if (face >= 0)
                memcpy(around, tri + 3 * face, sizeof around);
        }
        j->near_tet[u] = face >= 0 ? j->tet[face] : -1;
        worst = best > worst ? best : worst;
    }
    j->worst[worker] = worst;
}

/* shell_distance's preparation on all threads, in phases over ranges that depend on the counts alone:
 * 0, over the full mesh's vertices: the removed shell vertices, counted; 1, over the level's tets: their
 * shell faces, counted; 2, the same: the faces written at the offsets the counts before make (in tet
 * order, as one thread writes them); 3, over the full mesh's vertices: each live one's chain of removed
 * shell vertices (disjoint chains) gives them their owner; 4, over the level's vertices: level_of. */
typedef struct shell_prep {
    const simplifier *s;
    const tpk_tetmesh *lvl;
    const int32_t *neighbors, *vertex_old;
    int32_t *tri, *tet, *owner, *level_of;
    int phase;
    int64_t count[TPK_MAX_THREADS + 1];
} shell_prep;

static void shell_prep_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    shell_prep *j = ctx;
    const simplifier *s = j->s;
    const int32_t *neighbors = j->neighbors;
    int64_t count = 0;
    if (j->phase == 0) {
        for (int64_t v = begin; v < end; v++)
            count += s->boundary[v] & s->removed[v];
    } else if (j->phase == 1) {
        for (int64_t i = 4 * begin; i < 4 * end; i++)
            count += neighbors[i] < 0;
    } else if (j->phase == 2) {
        int64_t f = j->count[worker];
        for (int64_t t = begin; t < end; t++)
            for (int k = 0; k < 4; k++)
                if (neighbors[4 * t + k] < 0) {
                    for (int c = 0; c < 3; c++)
                        j->tri[3 * f + c] = j->lvl->tets[4 * t + tpk_tet_faces[k][c]];
                    j->tet[f++] = (int32_t)t;
                }
    } else if (j->phase == 3) {
        for (int64_t x = begin; x < end; x++)
            for (int32_t p = s->removed[x] ? -1 : s->chain_head[x]; p >= 0; p = s->chain_next[p])
                j->owner[p] = (int32_t)x;
    } else {
        for (int64_t v = begin; v < end; v++)
            j->level_of[j->vertex_old[v]] = (int32_t)v;
    }
    j->count[worker] = count;
}

static int64_t shell_prep_run(shell_prep *j, int phase, int64_t n)
{
    int parts = tpk_threads_for(n, j->s->threads, 1 << 16);
    j->phase = phase;
    tpk_parallel_for(n, parts, shell_prep_range, j);
    levels_offsets(j->count, parts);
    return j->count[parts];
}

/* How far the full mesh's shell lies from the level's, measured at the shell vertices the level removed:
 * each one's distance to the nearest level shell face at its owner (one of them is within the tolerance:
 * needs_witness), or without an owner by a descent from the vertex it ended on (the faces at that
 * vertex, then at the corners of the nearest so far, while one comes nearer). That
 * face may not be the nearest of all, so the figure is at most too large. near_tet[u] gets the level
 * tet of u's face (levels_measure() evaluates the field there when u lies outside the level). */
double levels_shell_distance(const simplifier *s, const tpk_tetmesh *lvl, const int32_t *vertex_old,
                             const int32_t *neighbors, int32_t *near_tet)
{
    const tpk_tetmesh *m = s->mesh;
    shell_prep prep = {s, lvl, neighbors, vertex_old, NULL, NULL, NULL, NULL, 0, {0}};
    int64_t n = lvl->vertex_count;
    if (shell_prep_run(&prep, 0, m->vertex_count) == 0)
        return 0; /* no shell vertex removed */
    int64_t faces = shell_prep_run(&prep, 1, lvl->tet_count);
    size_t fn = (size_t)(faces ? faces : 1);
    int32_t *level_of = malloc(sizeof *level_of * (size_t)m->vertex_count);
    int64_t *start = calloc((size_t)n + 1, sizeof *start), *fill = malloc(sizeof *fill * (size_t)(n ? n : 1));
    int32_t *tri = malloc(sizeof *tri * 3 * fn), *at = malloc(sizeof *at * 3 * fn), *tet = malloc(sizeof *tet * fn);
    double worst = INFINITY;
    if (level_of && start && fill && tri && at && tet) {
        prep.tri = tri, prep.tet = tet;
        prep.phase = 2; /* at the offsets phase 1 left */
        tpk_parallel_for(lvl->tet_count, tpk_threads_for(lvl->tet_count, s->threads, 1 << 16), shell_prep_range,
                         &prep);
        for (int64_t i = 0; i < 3 * faces; i++)
            start[tri[i] + 1]++;
        for (int64_t v = 0; v < n; v++)
            start[v + 1] += start[v];
        memcpy(fill, start, sizeof *fill * (size_t)n);
        for (int64_t i = 0; i < 3 * faces; i++)
            at[fill[tri[i]]++] = (int32_t)(i / 3);
        levels_fill_i32(level_of, m->vertex_count, -1, s->threads);
        prep.level_of = level_of;
        shell_prep_run(&prep, 4, n);
        worst = 0;
        /* from the owner (one of whose faces is p's witness), or without a tolerance the vertex p ended on */
        int32_t *owner = malloc(sizeof *owner * (size_t)m->vertex_count);
        if (owner) {
            levels_fill_i32(owner, m->vertex_count, -1, s->threads);
            prep.owner = owner;
            shell_prep_run(&prep, 3, m->vertex_count);
        }
        shell_job job = {s, lvl, start, tri, at, tet, level_of, owner, near_tet, {0}};
        int threads = tpk_threads_for(m->vertex_count, s->threads, 1 << 14);
        tpk_parallel_for(m->vertex_count, threads, shell_vertices, &job);
        for (int w = 0; w < threads; w++) /* a maximum: the same whatever the split */
            worst = job.worst[w] > worst ? job.worst[w] : worst;
        free(owner);
    }
    free(level_of);
    free(start);
    free(fill);
    free(tri);
    free(at);
    free(tet);
    return worst;
}
