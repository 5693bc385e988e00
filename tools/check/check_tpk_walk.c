/* Reference ids for a file without Tet32: the walk of spec §6.6 from the shell through neighbors, as a
 * reader of a Tet20- or Tet16-only file does it. Unlike tpk_recover_tets it does not stop at the first
 * inconsistency: an entry that does not fit (a fourth id out of range or repeated, a Tet20 tet that does
 * not name the tet it was entered from, a Tet16 decoding outside [-1, T)) is refused and the tet waits
 * for another entry. Tets no entry fits are reported with the first reason found, and the later checks
 * skip them. Deterministic: shell order, then depth first.
 *
 * With several threads the walk is first tried in parallel, each worker starting from its share of the
 * shell and claiming tets atomically. Which worker enters a tet first varies, but in a file whose
 * entries all fit, every entry gives a tet the same ids, so the checks see the same mesh; the parallel
 * result is kept only when no entry was refused and every tet was reached, and check_tpk.c redoes the
 * walk serially if any later check then finds a problem, so findings never depend on timing. */
#include <inttypes.h>
#include <stdlib.h>

#include "check_tpk_internal.h"
#include "base/parallel.h"

typedef struct walker {
    tpkc *c;
    uint8_t *cause;   /* TPKC_WALK_* per tet not (yet) assigned: c->face_class, unused until later */
    int32_t *stack;   /* tets assigned whose neighbors are still to enter; grows as needed */
    int64_t top, capacity;
    uint64_t *done;   /* bit per tet: assigned (a bitmap stays in cache where tets[] would not) */
    int parallel;     /* walkers share `done`: claim tets atomically, keep no causes */
    int refused;      /* an entry did not fit */
    int failed;       /* out of memory */
    int64_t assigned;
} walker;

static int32_t vx_of(const tpkc *c, int64_t t)
{
    return c->ref == TPK_LAYOUT_TET20 ? c->tet20[t].vx : c->tet16[t].vx;
}

/* 0 when tet u with ids q (apex q[3] opposite `from`) fits its record, else a TPKC_WALK_* reason. */
static int entry_fits(const tpkc *c, int32_t u, const int32_t q[4], int32_t from)
{
    if (q[3] < 0 || q[3] >= c->V || !tpkc_distinct(q))
        return TPKC_WALK_BAD_APEX;
    int entry = tpkc_rank(q, 3);
    if (c->ref == TPK_LAYOUT_TET20)
        return c->tet20[u].n[entry] == from ? 0 : TPKC_WALK_NO_BACKLINK;
    const int32_t *nx = c->tet16[u].nx;
    int32_t n3 = entry == 3 ? from : nx[entry] ^ from;
    for (int r = 0; r < 4; r++) {
        int32_t n = r == 3 ? n3 : nx[r] ^ n3;
        if (n < -1 || n >= c->T)
            return TPKC_WALK_BAD_DECODE;
    }
    return 0;
}

static void enter(walker *w, int32_t u, const int32_t face[3], int32_t from)
{
    tpkc *c = w->c;
    int32_t q[4] = {face[0], face[1], face[2], vx_of(c, u) ^ face[0] ^ face[1] ^ face[2]};
    int why = entry_fits(c, u, q, from);
    if (why) {
        w->refused = 1;
        if (!w->parallel && !w->cause[u]) {
            w->cause[u] = (uint8_t)why;
            c->walked[5 * (int64_t)u + 4] = from;
        }
        return;
    }
    if (w->top == w->capacity) {
        int64_t grown = w->capacity * 2 < c->T ? w->capacity * 2 : c->T;
        int32_t *stack = realloc(w->stack, sizeof *stack * (size_t)grown);
        if (!stack) {
            w->failed = 1;
            return;
        }
        w->stack = stack;
        w->capacity = grown;
    }
    uint64_t bit = 1ull << (u & 63);
    if (w->parallel && (__atomic_fetch_or(&w->done[u >> 6], bit, __ATOMIC_RELAXED) & bit))
        return; /* another worker claimed it first */
    if (!w->parallel)
        w->done[u >> 6] |= bit;
    memcpy(c->walked + 5 * (int64_t)u, q, sizeof q);
    c->walked[5 * (int64_t)u + 4] = from;
    w->stack[w->top++] = u;
    w->assigned++;
}

static int is_done(const walker *w, int32_t u)
{
    return (__atomic_load_n(&w->done[u >> 6], __ATOMIC_RELAXED) >> (u & 63)) & 1;
}

/* Depth first: the next tet is a neighbor of the last, so a space-filling-curve ordered file is walked
 * through memory that is still in cache (a breadth-first front spans the whole mesh). */
static void drain(walker *w)
{
    tpkc *c = w->c;
    while (w->top > 0 && !(w->parallel && w->refused)) {
        int32_t t = w->stack[--w->top], q[4], n[4];
        memcpy(q, c->walked + 5 * (int64_t)t, sizeof q);
        tpkc_neighbors(c, t, q, n);
        for (int k = 0; k < 4; k++) /* overlap the neighbors' cache misses */
            if (n[k] >= 0 && n[k] < c->T) {
                __builtin_prefetch(c->ref == TPK_LAYOUT_TET20 ? (const void *)(c->tet20 + n[k])
                                                              : (const void *)(c->tet16 + n[k]));
                __builtin_prefetch(c->walked + 5 * (int64_t)n[k], 1);
            }
        for (int k = 0; k < 4; k++) {
            int32_t u = n[k];
            if (u < 0 || is_done(w, u))
                continue;
            int32_t face[3] = {q[tpk_tet_faces[k][0]], q[tpk_tet_faces[k][1]], q[tpk_tet_faces[k][2]]};
            enter(w, u, face, t);
        }
    }
}

static void report_unrecovered(tpkc *c, const uint8_t *cause)
{
    static const int ids[4] = {609, 601, 604, 608};
    tpkc_sink sink = {.max_examples = c->report->options.max_examples};
    const char *layout = tpkc_layout_name(c->ref);
    for (int64_t t = 0; t < c->T; t++) {
        if (c->walked[5 * t] >= 0)
            continue;
        int why = cause[t];
        tpk_example *ex = tpkc_hit(&sink, ids[why], "tet");
        int32_t from = c->walked[5 * t + 4];
        tpk_example_ids(ex, why ? 2 : 1, (const int64_t[]){t, from});
        if (why == TPKC_WALK_UNREACHED)
            tpk_example_note(ex, "no walk from a SHEL record through %s neighbors reaches it: its boundary "
                             "faces are missing from SHEL", layout);
        else if (why == TPKC_WALK_BAD_APEX && from < 0)
            tpk_example_note(ex, "entered through a SHEL record, vx ^ the face's ids is out of range or "
                             "repeats an id");
        else if (why == TPKC_WALK_BAD_APEX)
            tpk_example_note(ex, "entered from tet %d, vx ^ the face's ids is out of range or repeats an id",
                             from);
        else if (why == TPKC_WALK_NO_BACKLINK)
            tpk_example_note(ex, "entered from tet %d, it does not name that tet opposite its fourth vertex",
                             from);
        else
            tpk_example_note(ex, "Tet16 decoded from entry tet %d gives a neighbor outside [-1, %" PRId64 ")",
                             from, c->T);
        c->unrecovered++;
    }
    for (int k = 0; k < 4; k++) {
        if (!sink.lists[ids[k] - TPKC_FIRST_ID].count)
            continue;
        tpk_finding *f = tpk_check_finding(c->report, ids[k]);
        snprintf(f->summary, sizeof f->summary,
                 "%" PRId64 " tets not recoverable from %s (%" PRId64 " for this reason); checks 602, 604-607, "
                 "609, 610 skip them", c->unrecovered, layout, sink.lists[ids[k] - TPKC_FIRST_ID].count);
    }
    tpkc_merge(c->report, &sink, 1);
}

/* Walk from shell records [begin, end). */
static void walk_shell(walker *w, int64_t begin, int64_t end)
{
    for (int64_t s = begin; s < end && !w->failed && !(w->parallel && w->refused); s++) {
        const tpk_shell_face *sf = &w->c->shell[s];
        if (is_done(w, sf->t))
            continue;
        int32_t inward[3] = {sf->a, sf->c, sf->b};
        enter(w, sf->t, inward, -1);
        drain(w);
    }
}

static int start_walker(walker *w, tpkc *c, uint64_t *done, int parallel)
{
    *w = (walker){c, c->face_class, malloc(sizeof *w->stack * 4096), 0, c->T < 4096 ? c->T : 4096, done, parallel,
                  0, 0, 0};
    return w->stack ? 0 : -1;
}

static void walk_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    walker *walkers = ctx;
    walk_shell(&walkers[worker], begin, end);
}

/* The parallel attempt: 1 when it reached every tet with no entry refused, 0 when the serial walk must
 * decide, -1 out of memory. */
static int walk_in_parallel(tpkc *c, uint64_t *done, int threads)
{
    walker walkers[TPK_MAX_THREADS];
    int rc = 0, started = 0;
    for (; started < threads && rc == 0; started++)
        rc = start_walker(&walkers[started], c, done, 1);
    if (rc == 0) {
        tpk_parallel_for(c->S, threads, walk_range, walkers);
        int64_t assigned = 0;
        int refused = 0;
        for (int w = 0; w < threads; w++) {
            assigned += walkers[w].assigned;
            refused |= walkers[w].refused;
            rc = walkers[w].failed ? -1 : rc;
        }
        rc = rc < 0 ? -1 : !refused && assigned == c->T;
    }
    for (int w = 0; w < started; w++)
        free(walkers[w].stack);
    return rc;
}

int tpkc_walk(tpkc *c, tpk_diag *diag)
{
    size_t n = (size_t)c->T + 1;
    c->walked = malloc(5 * sizeof *c->walked * n);
    uint64_t *done = malloc((n / 64 + 1) * sizeof *done);
    int threads = c->serial_walk ? 1 : tpk_threads_for(c->S, c->threads, 1 << 12);
    int rc = c->walked && done ? 0 : -1;
    if (rc == 0 && threads > 1) {
        memset(done, 0, (n / 64 + 1) * sizeof *done);
        rc = walk_in_parallel(c, done, threads);
        c->walked_in_parallel = rc == 1;
        rc = rc < 0 ? -1 : 0;
    }
    walker w = {0};
    if (rc == 0 && !c->walked_in_parallel) {
        memset(done, 0, (n / 64 + 1) * sizeof *done);
        for (int64_t i = 0; i < 5 * c->T; i++)
            c->walked[i] = -1;
        rc = start_walker(&w, c, done, 0);
        if (rc == 0)
            walk_shell(&w, 0, c->S);
        rc = rc == 0 && !w.failed ? 0 : -1;
        free(w.stack);
    }
    free(done);
    if (rc)
        return tpk_diag_fail(diag, "out of memory recovering %" PRId64 " tets from %s", c->T,
                             tpkc_layout_name(c->ref));
    if (!c->walked_in_parallel)
        report_unrecovered(c, c->face_class);
    memset(c->face_class, 0, (size_t)c->T); /* back to its own use */
    return 0;
}
