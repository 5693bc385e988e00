/* Face use (TPK-M05, 605): a triple of vertex ids is a face of at most two tets, and a face has neighbor
 * -1 exactly when no other tet has it, or when its two tets lie on the same side of it (a fold whose
 * adjacency the writer cut, spec §6.7; decided exactly, after the pass, for the few such faces). Faces
 * are bucketed by their smallest id (a counting sort, by the rule of mesh/face_buckets.h that connect
 * and check_topo_match.c use) and compared within buckets. A mutual neighbor pair is one entry of
 * weight 2, so interior faces cost one key, not two; the buckets are filled a vertex window at a time so
 * the keys never exceed a fixed budget, whatever the mesh size. */
#include <inttypes.h>
#include <stdlib.h>

#include "check_tpk_internal.h"
#include "base/parallel.h"
#include "mesh/face_buckets.h"

#define KEY_BUDGET ((int64_t)1 << 22) /* keys in memory at once, over all workers: 32 MiB */
#define KEY_BOUNDARY 1u
#define KEY_PAIR 2u

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

/* Keys of the faces whose smallest id is in [lo, hi); start[v] advances to the end of bucket v. */
static void fill_window(const tpkc *c, int64_t lo, int64_t hi, int64_t first_tet, int64_t end_tet, int64_t *start,
                        int64_t base, uint64_t *keys)
{
    for (int64_t t = first_tet; t < end_tet; t++) {
        int32_t q[4];
        if (!c->face_class[t] || !tpkc_tet(c, t, q))
            continue;
        tpk_sorted_tet s;
        tpk_sort_tet(q, &s);
        if ((s.id[0] < lo || s.id[0] >= hi) && (s.id[1] < lo || s.id[1] >= hi))
            continue; /* no face of t starts in this window: the common case */
        for (int smallest = 1; smallest >= 0; smallest--) {
            int32_t v = s.id[smallest ? 0 : 1];
            if (v < lo || v >= hi)
                continue;
            tpk_bucket_face f[3];
            int n = tpk_tet_bucket_faces(&s, smallest, f);
            for (int i = 0; i < n; i++) {
                int cls = face_class(c, t, f[i].opposite);
                if (cls == TPKC_FACE_SKIP)
                    continue;
                uint64_t flags = cls == TPKC_FACE_BOUNDARY ? KEY_BOUNDARY : cls == TPKC_FACE_PAIR ? KEY_PAIR : 0;
                keys[start[v]++ - base] = ((uint64_t)f[i].mid << 33) | ((uint64_t)f[i].max << 2) | flags;
            }
        }
    }
}

static int compare_keys(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return a < b ? -1 : a > b;
}

static void sort_bucket(uint64_t *keys, int64_t n)
{
    if (n > 24) {
        qsort(keys, (size_t)n, sizeof *keys, compare_keys);
        return;
    }
    for (int64_t i = 1; i < n; i++) {
        uint64_t key = keys[i];
        int64_t j = i;
        for (; j > 0 && keys[j - 1] > key; j--)
            keys[j] = keys[j - 1];
        keys[j] = key;
    }
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

static void add_cut(cut_list *cuts, int64_t v, uint64_t key)
{
    if (cuts->count == cuts->cap) {
        int64_t cap = cuts->cap ? 2 * cuts->cap : 16;
        cut_face *grown = realloc(cuts->faces, sizeof *grown * (size_t)cap);
        if (!grown) {
            cuts->failed = 1;
            return;
        }
        cuts->faces = grown;
        cuts->cap = cap;
    }
    cut_face *f = &cuts->faces[cuts->count++];
    memset(f, 0, sizeof *f);
    f->ids[0] = (int32_t)v;
    f->ids[1] = (int32_t)(key >> 33);
    f->ids[2] = (int32_t)((key >> 2) & 0x7fffffff);
}

static void check_bucket(tpkc_sink *sink, cut_list *cuts, int64_t v, uint64_t *keys, int64_t n)
{
    sort_bucket(keys, n);
    for (int64_t i = 0; i < n;) {
        int64_t tets = 0, j = i, boundaries = 0;
        int boundary = 0;
        for (; j < n && keys[j] >> 2 == keys[i] >> 2; j++) {
            tets += (keys[j] & KEY_PAIR) ? 2 : 1;
            boundary |= (keys[j] & KEY_BOUNDARY) != 0;
            boundaries += (keys[j] & KEY_BOUNDARY) != 0;
        }
        if (tets == 2 && boundaries == 2) {
            add_cut(cuts, v, keys[i]); /* decided by resolve_cuts */
        } else if (tets >= 3 || (tets == 2 && boundary)) {
            tpk_example *ex = tpkc_hit(sink, 605, "face");
            int64_t mid = (int64_t)(keys[i] >> 33), max = (int64_t)((keys[i] >> 2) & 0x7fffffff);
            tpk_example_ids(ex, 3, (const int64_t[]){v, mid, max});
            if (tets >= 3)
                tpk_example_note(ex, "a face of %" PRId64 " tets (their ids follow the 3 vertex ids)", tets);
            else
                tpk_example_note(ex, "a face of 2 tets, but one records neighbor -1 across it (tet ids follow)");
        }
        i = j;
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
    int64_t lo, hi, base;      /* vertices [lo, hi), their keys from start[lo] */
    int64_t first_tet, end_tet; /* the tets with a face starting in the window lie in [first_tet, end_tet) */
} window;

typedef struct face_pass {
    const tpkc *c;
    int64_t *start;
    const window *windows;
    uint64_t **keys;   /* one buffer per worker */
    tpkc_sink *sinks;  /* one per window, merged in window order */
    cut_list *cuts;    /* one per window: faces whose two tets both record -1 */
} face_pass;

static void window_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    face_pass *p = ctx;
    for (int64_t i = begin; i < end; i++) {
        const window *w = &p->windows[i];
        fill_window(p->c, w->lo, w->hi, w->first_tet, w->end_tet, p->start, w->base, p->keys[worker]);
        for (int64_t v = w->lo, first = w->base; v < w->hi; first = p->start[v], v++)
            check_bucket(&p->sinks[i], &p->cuts[i], v, p->keys[worker] + (first - w->base), p->start[v] - first);
    }
}

/* Vertex windows whose keys fit `capacity` (a window of one vertex may need more: capacity grows). */
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
        window w = {lo, hi, start[lo], INT32_MAX, 0};
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
    uint64_t *keys[TPK_MAX_THREADS] = {NULL};
    tpkc_sink *sinks = calloc((size_t)window_count + 1, sizeof *sinks); /* the last: the cut faces */
    cut_list *cuts = calloc((size_t)window_count + 1, sizeof *cuts);
    cut_list all = {0};
    int ok = windows && sinks && cuts;
    for (int w = 0; ok && w < threads; w++)
        ok = (keys[w] = malloc(sizeof *keys[w] * (size_t)(capacity + 1))) != NULL;
    if (ok) {
        for (int64_t i = 0; i <= window_count; i++)
            sinks[i].max_examples = c->report->options.max_examples;
        face_pass pass = {c, start, windows, keys, sinks, cuts};
        tpk_parallel_for(window_count, threads < window_count ? threads : (int)window_count, window_range, &pass);
        for (int64_t i = 0; i < window_count && ok; i++) {
            for (int64_t k = 0; k < cuts[i].count && !all.failed; k++) {
                add_cut(&all, 0, 0);
                if (!all.failed)
                    all.faces[all.count - 1] = cuts[i].faces[k];
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
    for (int w = 0; w < threads; w++)
        free(keys[w]);
    free(sinks);
    free(windows);
    free(start);
    return ok ? 0 : tpk_diag_fail(diag, "out of memory for the face keys of %" PRId64 " tets", c->T);
}
