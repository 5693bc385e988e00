/* Face use (TPK-M05, 605): a triple of vertex ids is a face of at most two tets, and a face has neighbor
 * -1 exactly when no other tet has it, or when its two tets lie on the same side of it (a fold whose
 * adjacency the writer cut, spec §6.7; decided exactly, after the pass, for the few such faces). The face
 * matcher (mesh/face_match.h, runs mode) compares the faces bucket by bucket. A mutual neighbor pair counts
 * as one face of weight 2 (the other side is skipped), and the matcher runs a vertex window at a time, so
 * the faces in memory never exceed a fixed budget, whatever the mesh size. */
#include <inttypes.h>
#include <stdlib.h>

#include "check_tpk_internal.h"
#include "base/grow.h"
#include "base/parallel.h"
#include "mesh/face_buckets.h"
#include "mesh/face_match.h"

#define KEY_BUDGET ((int64_t)1 << 22) /* faces bucketed at once, over all workers */

static void sorted_face(const int32_t q[4], int k, int32_t f[3])
{
    const int *p = tpk_tet_faces[k];
    int32_t a = q[p[0]], b = q[p[1]], d = q[p[2]], s;
    if (a > b) { s = a; a = b; b = s; }
    if (b > d) { s = b; b = d; d = s; }
    if (a > b) { s = a; a = b; b = s; }
    f[0] = a;
    f[1] = b;
    f[2] = d;
}

static int face_class(const tpkc *c, int64_t t, int k)
{
    return (c->face_class[t] >> (2 * k)) & 3;
}

/* Pass 1: start[v + 1] = number of keys whose smallest id is v, then prefix sums; span[2v], span[2v+1]
 * = the first and last tet with such a face, so a window scans only the tets that can feed it (few, in
 * a file whose tets follow their smallest vertex, as the converter writes them). */
static void count_keys(const tpkc *c, int64_t *start, int32_t *span)
{
    for (int64_t v = 0; v < c->V; v++) {
        span[2 * v] = INT32_MAX;
        span[2 * v + 1] = -1;
    }
    for (int64_t t = 0; t < c->T; t++) {
        int32_t q[4];
        if (!c->face_class[t] || !tpkc_tet(c, t, q))
            continue;
        tpk_sorted_tet s;
        tpk_sort_tet(q, &s);
        for (int k = 0; k < 4; k++) {
            if (face_class(c, t, k) == TPKC_FACE_SKIP)
                continue;
            int32_t v = tpk_tet_face_bucket(&s, k);
            start[v + 1]++;
            span[2 * v] = span[2 * v] < t ? span[2 * v] : (int32_t)t;
            span[2 * v + 1] = (int32_t)t;
        }
    }
    for (int64_t v = 0; v < c->V; v++)
        start[v + 1] += start[v];
}

/* A face of two tets that both record neighbor -1 across it: allowed when they lie on the same side. */
typedef struct cut_face {
    int32_t ids[3];  /* ascending */
    int32_t apex[2]; /* the fourth vertex of each of its tets */
    int found;
} cut_face;

typedef struct cut_list {
    cut_face *faces;
    int64_t count, cap;
    int failed;
} cut_list;

static void add_cut(cut_list *cuts, const int32_t ids[3])
{
    if (cuts->count == cuts->cap) {
        cut_face *grown = tpk_grow(cuts->faces, &cuts->cap, cuts->count + 1, sizeof *grown, 16);
        if (!grown) {
            cuts->failed = 1;
            return;
        }
        cuts->faces = grown;
    }
    cut_face *f = &cuts->faces[cuts->count++];
    memset(f, 0, sizeof *f);
    memcpy(f->ids, ids, sizeof f->ids);
}

/* The tets of one window: those with a recorded face class, as their layout gives them. */
static int window_tet(void *user, int64_t t, int32_t q[4]);

typedef struct window_match {
    const tpkc *c;
    tpkc_sink *sink;
    cut_list *cuts;
} window_match;

static int window_tet(void *user, int64_t t, int32_t q[4])
{
    const tpkc *c = ((const window_match *)user)->c;
    return c->face_class[t] && tpkc_tet(c, t, q);
}

/* A run of equal faces from the matcher; faces of class SKIP (the other side of a mutual pair, counted by
 * the pair's weight 2) are left out. */
static void check_face(void *user, int worker, int64_t v, const tpk_match_face *faces, int64_t n)
{
    window_match *w = user;
    int64_t tets = 0, boundaries = 0;
    (void)worker;
    for (int64_t i = 0; i < n; i++) {
        int cls = face_class(w->c, faces[i].item, faces[i].local);
        tets += cls == TPKC_FACE_PAIR ? 2 : cls != TPKC_FACE_SKIP;
        boundaries += cls == TPKC_FACE_BOUNDARY;
    }
    int32_t ids[3] = {(int32_t)v, (int32_t)(faces[0].key >> 32), (int32_t)(uint32_t)faces[0].key};
    if (tets == 2 && boundaries == 2) {
        add_cut(w->cuts, ids); /* decided by resolve_cuts */
    } else if (tets >= 3 || (tets == 2 && boundaries)) {
        tpk_example *ex = tpkc_hit(w->sink, 605, "face");
        tpk_example_ids(ex, 3, (const int64_t[]){ids[0], ids[1], ids[2]});
        if (tets >= 3)
            tpk_example_note(ex, "a face of %" PRId64 " tets (their ids follow the 3 vertex ids)", tets);
        else
            tpk_example_note(ex, "a face of 2 tets, but one records neighbor -1 across it (tet ids follow)");
    }
}

static int compare_example_faces(const void *pa, const void *pb)
{
    const tpk_example *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->ids[k] != b->ids[k])
            return a->ids[k] < b->ids[k] ? -1 : 1;
    return 0;
}

/* Name the tets of each example face (lowest tet ids first, as many as fit). */
static void add_example_tets(const tpkc *c, tpk_finding *finding)
{
    if (!finding->example_count)
        return;
    tpk_example *examples = finding->examples;
    size_t count = (size_t)finding->example_count;
    qsort(examples, count, sizeof *examples, compare_example_faces);
    for (int64_t t = 0; t < c->T; t++) {
        int32_t q[4], f[3];
        if (!tpkc_usable(c, t, q))
            continue;
        for (int k = 0; k < 4; k++) {
            sorted_face(q, k, f);
            tpk_example key = {.ids = {f[0], f[1], f[2]}};
            tpk_example *ex = bsearch(&key, examples, count, sizeof key, compare_example_faces);
            if (ex && ex->id_count < TPK_CHECK_MAX_IDS)
                ex->ids[ex->id_count++] = t;
        }
    }
}

static int compare_cut_ids(const void *pa, const void *pb)
{
    const cut_face *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->ids[k] != b->ids[k])
            return a->ids[k] < b->ids[k] ? -1 : 1;
    return 0;
}

/* The cut faces (ascending, from the windows in order) get their two tets' fourth vertices from one scan
 * over the tets; those whose tets lie on opposite sides are 605 (a cut only a fold allows). */
static void resolve_cuts(const tpkc *c, cut_face *cuts, int64_t count, tpkc_sink *sink)
{
    for (int64_t t = 0; count > 0 && t < c->T; t++) {
        int32_t q[4], f[3];
        if (!tpkc_usable(c, t, q))
            continue;
        for (int k = 0; k < 4; k++) {
            if (face_class(c, t, k) != TPKC_FACE_BOUNDARY)
                continue;
            sorted_face(q, k, f);
            cut_face key = {.ids = {f[0], f[1], f[2]}};
            cut_face *hit = bsearch(&key, cuts, (size_t)count, sizeof key, compare_cut_ids);
            if (hit && hit->found < 2)
                hit->apex[hit->found++] = q[k];
        }
    }
    for (int64_t i = 0; i < count; i++) {
        const cut_face *f = &cuts[i];
        int same_side = f->found == 2 && tpkc_orient(c, f->ids[0], f->ids[1], f->ids[2], f->apex[0]) ==
                                             tpkc_orient(c, f->ids[0], f->ids[1], f->ids[2], f->apex[1]);
        if (same_side)
            continue;
        tpk_example *ex = tpkc_hit(sink, 605, "face");
        tpk_example_ids(ex, 3, (const int64_t[]){f->ids[0], f->ids[1], f->ids[2]});
        tpk_example_note(ex, "a face of 2 tets on opposite sides, both record neighbor -1 across it (tet ids follow)");
    }
}

typedef struct window {
    int64_t lo, hi;             /* vertices [lo, hi) */
    int64_t first_tet, end_tet; /* the tets with a face starting in the window lie in [first_tet, end_tet) */
} window;

typedef struct face_pass {
    const tpkc *c;
    const window *windows;
    tpkc_sink *sinks;  /* one per window, merged in window order */
    cut_list *cuts;    /* one per window: faces whose two tets both record -1 */
    int failed;        /* out of memory in a window */
} face_pass;

static void window_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    face_pass *p = ctx;
    (void)worker;
    for (int64_t i = begin; i < end; i++) {
        const window *w = &p->windows[i];
        window_match user = {p->c, &p->sinks[i], &p->cuts[i]};
        tpk_face_matcher m = {.item_count = p->c->T, .vertex_count = p->c->V, .window_lo = w->lo,
                              .window_hi = w->hi, .item_begin = w->first_tet, .item_end = w->end_tet,
                              .threads = 1, .user = &user, .tet = window_tet, .run = check_face};
        if (w->end_tet > w->first_tet && tpk_face_match(&m, NULL) != TPK_MATCH_OK)
            __atomic_store_n(&p->failed, 1, __ATOMIC_RELAXED);
    }
}

/* Vertex windows whose faces fit `capacity` (a window of one vertex may need more). */
static window *plan_windows(const int64_t *start, const int32_t *span, int64_t V, int64_t *capacity,
                            int64_t *count)
{
    window *windows = malloc(sizeof *windows * (size_t)(V + 1));
    if (!windows)
        return NULL;
    int64_t n = 0, need = 0;
    for (int64_t lo = 0, hi; lo < V; lo = hi) {
        for (hi = lo + 1; hi < V && start[hi + 1] - start[lo] <= *capacity; hi++)
            ;
        window w = {lo, hi, INT32_MAX, 0};
        for (int64_t v = lo; v < hi; v++) {
            w.first_tet = span[2 * v] < w.first_tet ? span[2 * v] : w.first_tet;
            w.end_tet = span[2 * v + 1] + 1 > w.end_tet ? span[2 * v + 1] + 1 : w.end_tet;
        }
        windows[n++] = w;
        need = start[hi] - start[lo] > need ? start[hi] - start[lo] : need;
    }
    *capacity = need;
    *count = n;
    return windows;
}

int tpkc_check_faces(tpkc *c, tpk_diag *diag)
{
    int64_t *start = calloc((size_t)c->V + 2, sizeof *start);
    int32_t *span = malloc(sizeof *span * (size_t)(2 * c->V + 1));
    if (!start || !span) {
        free(start);
        free(span);
        return tpk_diag_fail(diag, "out of memory for face buckets (%" PRId64 " vertices)", c->V);
    }
    count_keys(c, start, span);
    int threads = tpk_threads_for(start[c->V], c->threads, 1 << 20);
    int64_t capacity = KEY_BUDGET / threads, window_count = 0;
    window *windows = plan_windows(start, span, c->V, &capacity, &window_count);
    free(span);
    free(start);
    tpkc_sink *sinks = calloc((size_t)window_count + 1, sizeof *sinks); /* the last: the cut faces */
    cut_list *cuts = calloc((size_t)window_count + 1, sizeof *cuts);
    cut_list all = {0};
    int ok = windows && sinks && cuts;
    if (ok) {
        for (int64_t i = 0; i <= window_count; i++)
            sinks[i].max_examples = c->report->options.max_examples;
        face_pass pass = {c, windows, sinks, cuts, 0};
        tpk_parallel_for(window_count, threads < window_count ? threads : (int)window_count, window_range, &pass);
        ok = !pass.failed;
        for (int64_t i = 0; i < window_count && ok; i++) {
            for (int64_t k = 0; k < cuts[i].count && !all.failed; k++) {
                add_cut(&all, cuts[i].faces[k].ids);
            }
            ok = !cuts[i].failed && !all.failed;
        }
    }
    if (ok) {
        resolve_cuts(c, all.faces, all.count, &sinks[window_count]);
        tpkc_merge(c->report, sinks, (int)window_count + 1);
        add_example_tets(c, tpk_check_finding(c->report, 605));
    }
    for (int64_t i = 0; cuts && i <= window_count; i++)
        free(cuts[i].faces);
    free(cuts);
    free(all.faces);
    free(sinks);
    free(windows);
    return ok ? 0 : tpk_diag_fail(diag, "out of memory for the face keys of %" PRId64 " tets", c->T);
}
