/* Levels of detail (levels_internal.h): the passes of collapses: blocks of vertex ids side by side, with
 * the loads of the collapses ahead prefetched, then the sweep one by one, until a level's target. */
#include <stdlib.h>

#include "base/parallel.h"
#include "levels_internal.h"

/* Blocks of vertex ids that a pass works on side by side: each of a fixed number of the vertices still
 * there (s->alive), so that the levels do not depend on the thread count, and a coarse level's blocks are
 * as large as the full mesh's (counted in ids, they would hold a sixth as many vertices a level, and
 * more stars would cross them). Vertices are in Hilbert order, so a block is a compact region and most
 * stars lie inside one. */
#define BLOCK_IDS ((int64_t)1 << 14)

typedef struct block_pass {
    simplifier *s;
    int64_t shift, size;    /* block b > 0 starts at alive[shift + (b - (shift > 0)) * size], block 0 at 0 */
    int64_t blocks;
    int64_t quota;          /* the tets a block may kill: its share of what the level still needs */
    int64_t *killed, *done; /* per block */
} block_pass;

static void block_range(const block_pass *p, int64_t b, int32_t *lo, int32_t *hi)
{
    const simplifier *s = p->s;
    int64_t n = s->alive_count, first = p->shift > 0;
    int64_t a = b == 0 ? 0 : p->shift + (b - first) * p->size, z = p->shift + (b + 1 - first) * p->size;
    *lo = a == 0 ? 0 : a < n ? s->alive[a] : (int32_t)s->mesh->vertex_count;
    *hi = z < n ? s->alive[z] : (int32_t)s->mesh->vertex_count;
}

/* The first active vertex at or after id lo. */
static int64_t first_active(const simplifier *s, int32_t lo)
{
    int64_t a = 0, z = s->active_count;
    while (a < z) {
        int64_t mid = a + (z - a) / 2;
        if (s->active[mid] < lo)
            a = mid + 1;
        else
            z = mid;
    }
    return a;
}

/* The collapses ahead of active[i], fetched in stages so that each stage reads what the one before
 * brought into cache: a star's bounds (12 ahead), its entries (8), its tets with their shape and mark
 * (4), their corners' vertices (2). A collapse reads these scattered lines and little else, so without
 * this it waits on memory (grid 120: a third of try_collapse's samples on the loads of tets and
 * vertices). Only what is read changes no result. Up to active[n - 1]: a block's thread reads no tet of
 * the next block, which another thread may be changing. */
#define PREFETCH_TETS 48 /* of a star; a typical interior star has 20-30 */

static void prefetch_ahead(const simplifier *s, int64_t i, int64_t n)
{
    const int32_t *active = s->active;
    if (i + 12 < n)
        __builtin_prefetch(s->star_start + active[i + 12]), __builtin_prefetch(s->star_end + active[i + 12]);
    if (i + 8 < n) {
        int64_t a = s->star_start[active[i + 8]];
        __builtin_prefetch(s->star + a), __builtin_prefetch(s->star + a + 16);
    }
    if (i + 4 < n) {
        int32_t a = active[i + 4];
        int64_t b = s->star_start[a], e = s->star_end[a];
        e = e - b > PREFETCH_TETS ? b + PREFETCH_TETS : e;
        for (int64_t j = b; j < e; j++) {
            int32_t t = s->star[j];
            __builtin_prefetch(s->tets + 4 * (size_t)t);
            __builtin_prefetch(s->tet_quality + t);
            __builtin_prefetch(s->dead + t);
        }
    }
    if (i + 2 < n) {
        int32_t a = active[i + 2];
        int64_t b = s->star_start[a], e = s->star_end[a];
        e = e - b > PREFETCH_TETS ? b + PREFETCH_TETS : e;
        for (int64_t j = b; j < e; j++) {
            const int32_t *t = s->tets + 4 * (size_t)s->star[j];
            for (int k = 0; k < 4; k++)
                __builtin_prefetch(s->vert + t[k]);
        }
    }
}

static void run_blocks(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_pass *p = ctx;
    (void)worker;
    for (int64_t b = begin; b < end; b++) {
        int32_t lo, hi;
        block_range(p, b, &lo, &hi);
        p->killed[b] = p->done[b] = 0;
        for (int64_t i = first_active(p->s, lo), n = first_active(p->s, hi); i < n && p->killed[b] < p->quota; i++) {
            int32_t u = p->s->active[i];
            prefetch_ahead(p->s, i, n);
            int64_t k = levels_try_collapse(p->s, u, lo, hi);
            if (k >= 0)
                p->killed[b] += k, p->done[b]++;
        }
    }
}

/* The collapses whose stars lie inside one block, the blocks side by side: no two touch the same tet or
 * vertex, and each reads only its own, so the result is that of the blocks one after the other. */
static int64_t blocks_pass(simplifier *s, int64_t shift, int64_t size, int64_t target, int64_t *live)
{
    int64_t n = s->alive_count, need = *live - target;
    if (need <= 0)
        return 0;
    /* with fewer than shift vertices, one block of them all (first > 0 counts it) */
    block_pass p = {s, shift, size, (n > shift ? (n - shift + size - 1) / size : 0) + (shift > 0), 0, NULL, NULL};
    p.killed = malloc(sizeof *p.killed * 2 * (size_t)p.blocks);
    if (!p.killed)
        return 0; /* the sweep one by one does it all */
    p.done = p.killed + p.blocks;
    p.quota = (need + p.blocks - 1) / p.blocks;
    tpk_parallel_for(p.blocks, tpk_threads_for(p.blocks, s->threads, 1), run_blocks, &p);
    int64_t done = 0;
    for (int64_t b = 0; b < p.blocks; b++)
        *live -= p.killed[b], done += p.done[b];
    free(p.killed);
    return done;
}

/* One pass; the number of collapses. Vertices in id order, skipping the targets of this pass's
 * collapses (the stars it began with, less the tets killed since, are the others'): first inside the
 * blocks, side by side, then inside the blocks shifted by half a block, then inside blocks 16 times as
 * large, shifted so that no boundary is one of the first two's (a star that crosses both of those spans
 * thousands of ids, where the Hilbert order jumps: grid 120's first pass left 221k collapses to the
 * sweep, now 88k), then one by one the rest, which stops at the target exactly. */
static int64_t collapse_pass(simplifier *s, int64_t target, int64_t *live)
{
    int64_t V = s->mesh->vertex_count, done = 0;
    if (V <= 0 || s->tet_count <= 0)
        return 0;
    levels_zero_bytes(s->locked, V, s->threads);
    levels_zero_bytes(s->dead, s->tet_count, s->threads);
    done += blocks_pass(s, 0, BLOCK_IDS, target, live);
    done += blocks_pass(s, BLOCK_IDS / 2, BLOCK_IDS, target, live);
    if (s->alive_count > 8 * BLOCK_IDS + BLOCK_IDS / 4) /* else one block of them all: the sweep's work, */
        done += blocks_pass(s, 8 * BLOCK_IDS + BLOCK_IDS / 4, 16 * BLOCK_IDS, target, live); /* on one thread */
    for (int64_t i = 0; i < s->active_count && *live > target; i++) {
        prefetch_ahead(s, i, s->active_count);
        int64_t k = levels_try_collapse(s, s->active[i], 0, 0);
        if (k >= 0)
            *live -= k, done++;
    }
    int64_t w = 0; /* compact, in order */
    for (int64_t t = 0; t < s->tet_count; t++) { /* each copied, kept only if live: no branch */
        for (int k = 0; k < 4; k++)
            s->tets[4 * w + k] = s->tets[4 * t + k];
        s->tet_quality[w] = s->tet_quality[t];
        s->origin[w] = s->origin[t];
        w += !s->dead[t];
    }
    s->tet_count = w;
    return done;
}

/* Simplify to about `target` live tets (or as far as passes go). */
void levels_simplify_to(simplifier *s, int64_t target)
{
    int64_t live = s->tet_count;
    for (;;) {
        levels_build_stars(s);
        int64_t before = live, done = collapse_pass(s, target, &live);
        if (live <= target || done == 0 || before - live < before / 200)
            return;
    }
}
