/* Levels of detail (levels_internal.h): the stars (the tets around each vertex a pass may collapse),
 * built on all threads as one thread would build them, and a star's neighbours with their costs. */
#include <math.h>

#include "base/parallel.h"
#include "levels_internal.h"

/* build_stars' counting and filling, side by side: worker w takes the corners whose vertex lies in its
 * range of ids [cut[w], cut[w + 1]) and reads every tet in order, so each star is filled in tet order, as
 * one thread would fill it. */
typedef struct star_job {
    simplifier *s;
    int32_t cut[TPK_MAX_THREADS + 1];
    int fill; /* 0: count, 1: fill */
} star_job;

static void star_ranges(void *ctx, int64_t begin, int64_t end, int worker)
{
    star_job *j = ctx;
    simplifier *s = j->s;
    const int32_t *tets = s->tets;
    int64_t *star_start = s->star_start, *star_end = s->star_end;
    int32_t *star = s->star;
    int64_t corners = 4 * s->tet_count;
    (void)worker;
    for (int64_t w = begin; w < end; w++) {
        uint32_t lo = (uint32_t)j->cut[w], span = (uint32_t)j->cut[w + 1] - lo;
        if (!j->fill) {
            for (int64_t i = 0; i < corners; i++)
                if ((uint32_t)tets[i] - lo < span)
                    star_end[tets[i]]++;
        } else {
            for (int64_t i = 0; i < corners; i++) {
                int32_t v = tets[i];
                if ((uint32_t)v - lo < span && star_start[v] >= 0)
                    star[star_end[v]++] = (int32_t)(i / 4);
            }
        }
    }
}

/* build_stars' lists, on all threads: each worker takes a range of the vertices that were alive and
 * counts (phase 0), then writes at the offsets the counts before it make (phase 1: the live and the
 * active vertices; phase 2: the stars' starts, after the counting of the stars). The same lists and
 * starts as one thread makes. */
typedef struct list_job {
    simplifier *s;
    int phase;
    int64_t live[TPK_MAX_THREADS + 1], act[TPK_MAX_THREADS + 1], entries[TPK_MAX_THREADS + 1];
} list_job;

static void list_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    list_job *j = ctx;
    simplifier *s = j->s;
    const uint8_t *removed = s->removed, *pinned = s->pinned, *stuck = s->stuck;
    if (j->phase == 0) { /* over the old list: the live, the active, and each live star's count cleared */
        int64_t live = 0, act = 0;
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            if (removed[v])
                continue;
            live++;
            act += !(pinned[v] | stuck[v]);
            s->star_end[v] = 0;
        }
        j->live[worker] = live, j->act[worker] = act;
    } else if (j->phase == 1) {
        int64_t live = j->live[worker], act = j->act[worker];
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            if (removed[v])
                continue;
            s->alive_next[live++] = v;
            if (!(pinned[v] | stuck[v]))
                s->active[act++] = v;
        }
    } else if (j->phase == 2) { /* over the new list: the entries of the stars kept */
        int64_t entries = 0;
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            entries += !(pinned[v] | stuck[v]) ? s->star_end[v] : 0;
        }
        j->entries[worker] = entries;
    } else { /* only the active vertices' stars are kept; the others' are empty (-1, -1) */
        int64_t at = j->entries[worker];
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            int keep = !(pinned[v] | stuck[v]);
            s->star_start[v] = keep ? at : -1;
            at += keep ? s->star_end[v] : 0;
            s->star_end[v] = s->star_start[v]; /* the fill's cursor, its end once filled */
        }
    }
}


/* The vertices a pass may collapse (not pinned, not removed, not stuck), in id order, and their stars:
 * the tets that hold them, in tet order. */
void levels_build_stars(simplifier *s)
{
    /* over the vertices still there (the live tets use no other), not all of the full mesh's: a coarse
     * level's passes would spend most of their time on vertices long gone */
    list_job list;
    list.s = s;
    int lists = tpk_threads_for(s->alive_count, s->threads, 1 << 16);
    for (list.phase = 0; list.phase < 2; list.phase++) {
        tpk_parallel_for(s->alive_count, lists, list_range, &list);
        if (list.phase == 0)
            levels_offsets(list.live, lists), levels_offsets(list.act, lists);
    }
    int32_t *old = s->alive;
    s->alive = s->alive_next, s->alive_next = old;
    int64_t live = s->alive_count = list.live[lists];
    s->active_count = list.act[lists];
    /* each worker reads all the corners but writes only its own vertices' counts and stars: the
     * writes, scattered, are the cost */
    star_job job = {s, {0}, 0};
    int parts = tpk_threads_for(4 * s->tet_count, s->threads, 1 << 20);
    for (int w = 0; w <= parts; w++)
        job.cut[w] = w == 0 ? 0 : w == parts ? (int32_t)s->mesh->vertex_count : s->alive[live * w / parts];
    tpk_parallel_for(parts, parts, star_ranges, &job);
    lists = tpk_threads_for(live, s->threads, 1 << 16);
    list.phase = 2;
    tpk_parallel_for(live, lists, list_range, &list);
    levels_offsets(list.entries, lists);
    list.phase = 3;
    tpk_parallel_for(live, lists, list_range, &list);
    job.fill = 1;
    tpk_parallel_for(parts, parts, star_ranges, &job);
}

/* u's neighbours (each once, in the order the star first meets them) with their costs: the field
 * difference, or the squared distance without a field. The ones met are marked (s->vert[].seen), and
 * cleared again.
 * The count; -1 past NEIGHBOURS_MAX; -2 when lo < hi and one lies outside [lo, hi) (then none is marked,
 * so blocks side by side touch only their own marks). */
int levels_star_neighbours(simplifier *s, int32_t u, const int32_t *star, int n, int32_t lo, int32_t hi,
                           int32_t *nb, double *cost)
{
    /* Every entry is stored at nb[m] and m only grows for a new one (not u, not seen): which corner is u
     * and whether a vertex is new are as random as the mesh, and branches on them mispredict (this loop
     * was a fifth of the simplification). u lies in [lo, hi) (run_blocks), and its mark is cleared with the
     * others. */
    const int32_t *tets = s->tets;
    level_vertex *vert = s->vert;
    const float *field = s->field;
    uint32_t first = lo < hi ? (uint32_t)lo : 0, span = lo < hi ? (uint32_t)hi - (uint32_t)lo : UINT32_MAX;
    double field_u = vert[u].field;
    const double *p = point(s, u);
    int m = 0, over = 0;
    for (int i = 0; i < n; i++) {
        const int32_t *t = tets + 4 * (size_t)star[i];
        for (int k = 0; k < 4; k++) {
            int32_t w = t[k];
            if ((uint32_t)w - first >= span) {
                for (int j = 0; j < m; j++)
                    vert[nb[j]].seen = -1;
                vert[u].seen = -1;
                return -2;
            }
            if (m == NEIGHBOURS_MAX) {
                over |= (vert[w].seen != u) & (w != u);
                continue;
            }
            int fresh = (vert[w].seen != u) & (w != u);
            vert[w].seen = u;
            double c = 0;
            if (field)
                c = fabs((double)vert[w].field - field_u);
            else
                for (int a = 0; a < 3; a++)
                    c += (point(s, w)[a] - p[a]) * (point(s, w)[a] - p[a]);
            nb[m] = w;
            cost[m] = c;
            m += fresh;
        }
    }
    for (int j = 0; j < m; j++)
        vert[nb[j]].seen = -1;
    vert[u].seen = -1;
    return over ? -1 : m;
}
