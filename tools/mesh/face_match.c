/* The face matcher (face_match.h): a parallel counting sort of items into buckets by the smallest ids of
 * their faces, then each bucket's faces grouped, by a hash table (neighbours) or by sorting (runs). */
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "face_buckets.h"
#include "face_match.h"

/* Scratch of one worker for a bucket. */
typedef struct bucket_scratch {
    tpk_match_face *faces;
    int64_t face_cap;
    int32_t *table; /* neighbours: open addressing over face indices */
    int64_t table_cap;
    int64_t bad_bucket; /* neighbours: first bucket with a face of 3+ tets, or -1 */
    uint64_t bad_key;   /* that face's key */
    int failed;         /* out of memory */
} bucket_scratch;

typedef struct match_job {
    const tpk_face_matcher *m;
    int64_t lo, hi;                   /* the bucket window */
    int64_t first_item;               /* the workers' item ranges start here */
    int plain;                        /* tets from the array, every one kept, untagged, from item 0: the
                                       * tight loops below (connect's case; a window costs a compare) */
    int64_t buckets;                  /* hi - lo */
    int64_t wa, wb;                   /* the buckets of the window being scattered and matched, from lo: the
                                       * count pass covers all of them, each window is then matched alone */
    uint32_t item_mask;
    uint32_t *starts[TPK_MAX_THREADS]; /* per worker, per bucket: count, then next slot (< 2^32 entries;
                                        * 32 bits: these arrays are part of the converter's peak memory) */
    const uint32_t *bucket_end;       /* after the scatter: the last worker's next slots, which are where each
                                       * bucket ends (no array of its own, as that would add to the peak) */
    int64_t entry_count, largest;     /* of the window */
    int64_t entries_cap;              /* entries allocated */
    uint32_t *entries;                /* item | tag << (32 - tag_bits) */
    int64_t bad_item[TPK_MAX_THREADS]; /* check_ids: first tet with an id out of range or repeated, or -1 */
    /* Plain tets over all vertices, in order of their smallest id (as reorder leaves them): bucket v's tets
     * of smallest id v are items [first[v], first[v + 1]), so only the faces opposite the smallest id go
     * through entries, a quarter of the faces (SORTED TETS below). */
    int32_t *first;                   /* [buckets + 1], filled by the count pass */
    int unsorted[TPK_MAX_THREADS];    /* a worker saw a tet's smallest id go down */
    int sorted;                       /* after the count: the entries hold only the faces opposite s0 */
    int32_t *second;                  /* plain tets in neighbours mode: the count pass's second smallest ids,
                                       * kept in the neighbors' first quarter (not yet written then), so
                                       * that a scatter of sorted tets in one window reads 4 bytes a tet,
                                       * not the tets' 16 */
    int64_t bucket_begin[TPK_MAX_THREADS + 1];
    bucket_scratch scratch[TPK_MAX_THREADS];
} match_job;

static inline int has_repeat(const int32_t *v)
{
    return (v[0] == v[1]) | (v[0] == v[2]) | (v[0] == v[3]) | (v[1] == v[2]) | (v[1] == v[3]) | (v[2] == v[3]);
}

/* The ids of tet t, or NULL to leave it out. */
static inline const int32_t *tet_ids(const tpk_face_matcher *m, int64_t t, int32_t *own)
{
    if (m->tets)
        return m->tets + 4 * t;
    return m->tet(m->user, t, own) ? own : NULL;
}

static inline int in_window(const match_job *job, int64_t v)
{
    return v >= job->lo && v < job->hi;
}

/* The buckets of item i in the window (relative to its start), or -1 when check_ids finds it bad. */
static inline int item_buckets(const match_job *job, int64_t i, int32_t *b)
{
    const tpk_face_matcher *m = job->m;
    if (!m->tets && !m->tet) {
        int n = m->cell_buckets(m->user, i, b), kept = 0;
        for (int k = 0; k < n; k++)
            if (in_window(job, b[k]))
                b[kept++] = (int32_t)(b[k] - job->lo);
        return kept;
    }
    int32_t own[4];
    const int32_t *v = tet_ids(m, i, own);
    if (!v)
        return 0;
    if (m->check_ids && has_repeat(v))
        return -1;
    tpk_sorted_tet s;
    tpk_sort_tet(v, &s);
    if (m->check_ids && (s.id[0] < 0 || s.id[3] >= m->vertex_count))
        return -1;
    int n = 0;
    for (int r = 0; r < 2; r++)
        if (in_window(job, s.id[r]))
            b[n++] = (int32_t)(s.id[r] - job->lo);
    return n;
}

/* The smallest id of tet t, within [-1, vertex_count - 1] whatever the ids (an unchecked neighbour's). */
static int32_t clamped_smallest(const match_job *job, int64_t t)
{
    const int32_t *v = job->m->tets + 4 * t;
    int32_t a = v[0] < v[1] ? v[0] : v[1], b = v[2] < v[3] ? v[2] : v[3], lo = a < b ? a : b;
    return lo < 0 ? -1 : lo >= job->buckets ? (int32_t)(job->buckets - 1) : lo;
}

/* A tet's ids ascending by min and max in registers (no stores and loads of a rank sort): what the count
 * and scatter passes need, the bucket ids s0 and s1 and, to check them, all four. */
typedef struct ascending {
    int32_t id[4];
} ascending;

static inline ascending two_smallest(const int32_t *v)
{
    int32_t a = v[0] < v[1] ? v[0] : v[1], b = v[0] < v[1] ? v[1] : v[0];
    int32_t c = v[2] < v[3] ? v[2] : v[3], d = v[2] < v[3] ? v[3] : v[2];
    int32_t lo = a < c ? a : c, x = a < c ? c : a, y = b < d ? b : d, hi = b < d ? d : b;
    return (ascending){{lo, x < y ? x : y, x < y ? y : x, hi}};
}

/* SORTED TETS. The count pass fills first[v] for v in (smallest id of item begin - 1, smallest id of item
 * end - 1] and says whether its smallest ids go down. When none do, those ranges of the workers are
 * disjoint and cover every v; when some do, they may overlap (three workers or more) and first[] is not
 * used: relaxed atomic stores, so that such writes are no data race. */
static void count_plain(match_job *job, int64_t begin, int64_t end, uint32_t *count, int worker)
{
    const tpk_face_matcher *m = job->m;
    int32_t *first = job->first;
    int32_t prev = begin > 0 ? clamped_smallest(job, begin - 1) : -1;
    int32_t last = end > begin ? clamped_smallest(job, end - 1) : prev, seen = prev; /* prev stops at last */
    job->unsorted[worker] = 0;
    int check = m->check_ids;
    uint32_t vertex_count = (uint32_t)m->vertex_count;
    for (int64_t t = begin; t < end; t++) {
        ascending s = two_smallest(m->tets + 4 * t);
        /* distinct ids in range: strictly ascending, the smallest >= 0, the largest below vertex_count */
        if (check && ((s.id[0] < 0) | (s.id[0] >= s.id[1]) | (s.id[1] >= s.id[2]) | (s.id[2] >= s.id[3]) |
                      ((uint32_t)s.id[3] >= vertex_count))) {
            job->bad_item[worker] = t;
            return;
        }
        uint64_t b0 = (uint64_t)((int64_t)s.id[0] - job->lo), b1 = (uint64_t)((int64_t)s.id[1] - job->lo);
        if (b0 < (uint64_t)job->buckets)
            count[b0]++;
        if (b1 < (uint64_t)job->buckets)
            count[b1]++;
        if (job->second)
            job->second[t] = s.id[1];
        if (first) {
            if (s.id[0] < seen)
                job->unsorted[worker] = 1;
            seen = s.id[0];
            for (; prev < seen && prev < last; prev++)
                __atomic_store_n(&first[prev + 1], (int32_t)t, __ATOMIC_RELAXED);
        }
    }
}

static void count_entries(void *ctx, int64_t begin, int64_t end, int worker)
{
    match_job *job = ctx;
    const tpk_face_matcher *m = job->m;
    uint32_t *count = job->starts[worker];
    int32_t b[256];
    memset(count, 0, sizeof *count * (size_t)job->buckets);
    job->bad_item[worker] = -1;
    if (job->plain) {
        count_plain(job, begin, end, count, worker);
        return;
    }
    for (int64_t i = begin + job->first_item; i < end + job->first_item; i++) {
        if (m->keep && !m->keep(m->user, i))
            continue;
        int n = item_buckets(job, i, b);
        if (n < 0) {
            job->bad_item[worker] = i;
            return;
        }
        for (int k = 0; k < n; k++)
            count[b[k]]++;
    }
}

static void scatter_entries(void *ctx, int64_t begin, int64_t end, int worker)
{
    match_job *job = ctx;
    const tpk_face_matcher *m = job->m;
    uint32_t *next = job->starts[worker];
    int32_t b[256];
    if (job->sorted && job->second && job->wa == 0 && job->wb == job->buckets) {
        for (int64_t t = begin; t < end; t++) {
            uint64_t b1 = (uint64_t)((int64_t)job->second[t] - job->lo);
            if (b1 < (uint64_t)job->buckets)
                job->entries[next[b1]++] = (uint32_t)t;
        }
        return;
    }
    if (job->plain) {
        for (int64_t t = begin; t < end; t++) {
            ascending s = two_smallest(m->tets + 4 * t);
            uint64_t b0 = (uint64_t)((int64_t)s.id[0] - job->lo), b1 = (uint64_t)((int64_t)s.id[1] - job->lo);
            if (!job->sorted && b0 - (uint64_t)job->wa < (uint64_t)(job->wb - job->wa))
                job->entries[next[b0]++] = (uint32_t)t;
            if (b1 - (uint64_t)job->wa < (uint64_t)(job->wb - job->wa))
                job->entries[next[b1]++] = (uint32_t)t;
        }
        return;
    }
    for (int64_t i = begin + job->first_item; i < end + job->first_item; i++) {
        uint32_t entry = (uint32_t)i;
        if (m->tag) {
            int tag = m->tag(m->user, i);
            if (tag < 0)
                continue;
            if (m->tag_bits) /* (a shift by 32 is undefined) */
                entry |= (uint32_t)tag << (32 - m->tag_bits);
        } else if (m->keep && !m->keep(m->user, i)) {
            continue;
        }
        int n = item_buckets(job, i, b);
        for (int k = 0; k < n; k++)
            if (b[k] >= job->wa && b[k] < job->wb)
                job->entries[next[b[k]]++] = entry;
    }
}

static inline int64_t bucket_first(const match_job *job, int64_t b)
{
    return b > job->wa ? (int64_t)job->bucket_end[b - 1] : 0;
}

static int grow_faces(bucket_scratch *s, int64_t need)
{
    if (need <= s->face_cap)
        return 0;
    int64_t cap = 2 * need + 64;
    tpk_match_face *grown = realloc(s->faces, sizeof *grown * (size_t)cap);
    if (!grown)
        return -1;
    s->faces = grown;
    s->face_cap = cap;
    return 0;
}

/* A tet's ids ascending, each as id << 2 | its corner: five compare-exchanges by min and max, in
 * registers (the rank sort of face_buckets.h stores to memory and loads back, and that store forwarding
 * was most of this matcher's face expansion). Ties go by corner, as tpk_sort_tet breaks them; ids >= 0. */
typedef struct corners {
    uint64_t c[4];
} corners;

static inline corners sort_corners(const int32_t *v)
{
    uint64_t a = (uint64_t)(uint32_t)v[0] << 2, b = (uint64_t)(uint32_t)v[1] << 2 | 1;
    uint64_t c = (uint64_t)(uint32_t)v[2] << 2 | 2, d = (uint64_t)(uint32_t)v[3] << 2 | 3;
#define CORNER_SWAP(p, q)                                                                                  \
    do {                                                                                                   \
        uint64_t lo_ = p < q ? p : q, hi_ = p < q ? q : p;                                                 \
        p = lo_, q = hi_;                                                                                  \
    } while (0)
    CORNER_SWAP(a, b);
    CORNER_SWAP(c, d);
    CORNER_SWAP(a, c);
    CORNER_SWAP(b, d);
    CORNER_SWAP(b, c);
#undef CORNER_SWAP
    return (corners){{a, b, c, d}};
}

/* The parity of the permutation that sorts a tet's (distinct) ids. Face k's outward order (tpk_tet_faces)
 * followed by corner k is an odd permutation of the tet's order for every k, and putting corner k back
 * at its rank r among the four takes 3 - r swaps: so that face's parity (tpk_face_parity) is this one
 * xor (r & 1), with no table lookups. */
static inline int tet_parity(const int32_t *v)
{
    return (v[0] > v[1]) ^ (v[0] > v[2]) ^ (v[0] > v[3]) ^ (v[1] > v[2]) ^ (v[1] > v[3]) ^ (v[2] > v[3]);
}

static inline tpk_match_face corner_face(uint64_t mid, uint64_t max, uint64_t opposite, uint32_t item, uint8_t tag,
                                         int odd)
{
    return (tpk_match_face){(mid >> 2) << 32 | max >> 2, UINT32_MAX, item, (uint16_t)(opposite & 3), tag, (uint8_t)odd};
}

/* The faces a tet brings to bucket s0 (`smallest`: 3, in face_buckets.h's order) or s1 (1). */
static inline int corner_faces(const int32_t *ids, uint32_t item, uint8_t tag, int smallest, int agreeing,
                               tpk_match_face *out)
{
    corners s = sort_corners(ids);
    int odd = agreeing ? tet_parity(ids) : 0, flip = agreeing ? 1 : 0;
    if (!smallest) {
        out[0] = corner_face(s.c[2], s.c[3], s.c[0], item, tag, odd);
        return 1;
    }
    out[0] = corner_face(s.c[1], s.c[2], s.c[3], item, tag, odd ^ flip);
    out[1] = corner_face(s.c[1], s.c[3], s.c[2], item, tag, odd);
    out[2] = corner_face(s.c[2], s.c[3], s.c[1], item, tag, odd ^ flip);
    return 3;
}

/* The faces of tet entry i in bucket v (its smallest or second smallest id, by face_buckets.h). */
static inline int tet_faces(const tpk_face_matcher *m, uint32_t entry, uint32_t item, int32_t v,
                            tpk_match_face *out)
{
    int32_t own[4];
    const int32_t *ids = tet_ids(m, item, own);
    uint8_t tag = m->tag_bits ? (uint8_t)(entry >> (32 - m->tag_bits)) : 0;
    int32_t a = ids[0] < ids[1] ? ids[0] : ids[1], b = ids[2] < ids[3] ? ids[2] : ids[3];
    if ((a < b ? a : b) == v)
        return corner_faces(ids, item, tag, 1, m->agreeing != NULL, out);
    return corner_faces(ids, item, tag, 0, m->agreeing != NULL, out);
}

/* Expands bucket b of the window into the worker's faces; returns their count, or -1 when out of memory. */
static int64_t expand_bucket(const match_job *job, bucket_scratch *s, int64_t b)
{
    const tpk_face_matcher *m = job->m;
    int cells = !m->tets && !m->tet, most = cells ? m->max_cell_faces : 3;
    int64_t n = 0, end = job->bucket_end[b];
    int32_t v = (int32_t)(b + job->lo);
    if (job->sorted) {
        /* The entries' tets have a smaller smallest id than v, so they all come before the tets of smallest
         * id v in the array: entries, then that run, is item order. */
        int64_t i = bucket_first(job, b), next = job->first[b], stop = job->first[b + 1];
        int agreeing = m->agreeing != NULL;
        if (n + (end - i) + 3 * (stop - next) > s->face_cap && grow_faces(s, n + (end - i) + 3 * (stop - next)))
            return -1;
        for (; i < end; i++) {
            if (i + 8 < job->entry_count)
                __builtin_prefetch(m->tets + 4 * (int64_t)job->entries[i + 8]);
            uint32_t item = job->entries[i];
            n += corner_faces(m->tets + 4 * (int64_t)item, item, 0, 0, agreeing, s->faces + n);
        }
        for (; next < stop; next++)
            n += corner_faces(m->tets + 4 * next, (uint32_t)next, 0, 1, agreeing, s->faces + n);
        return n;
    }
    for (int64_t i = bucket_first(job, b); i < end; i++) {
        if (m->tets && i + 8 < job->entry_count) /* the tets of a bucket are scattered in memory */
            __builtin_prefetch(m->tets + 4 * (int64_t)(job->entries[i + 8] & job->item_mask));
        if (n + most > s->face_cap && grow_faces(s, n + most))
            return -1;
        uint32_t entry = job->entries[i], item = entry & job->item_mask;
        if (!cells) {
            n += tet_faces(m, entry, item, v, s->faces + n);
            continue;
        }
        int got = m->cell_faces(m->user, item, v, s->faces + n);
        for (int k = 0; k < got; k++) {
            s->faces[n + k].item = item;
            s->faces[n + k].tag = m->tag_bits ? (uint8_t)(entry >> (32 - m->tag_bits)) : 0;
        }
        n += got;
    }
    return n;
}

/* Neighbours mode. Table values: -1 empty; i >= 0 the first face i of a key seen once; -2 - i seen
 * twice. A key seen three times or more marks the bucket bad (its first such key kept). Whether a face is
 * a key's first or second is a coin toss to the branch predictor, so that choice is made by selects: an
 * empty slot stands for the face itself, the probe stops at the face of its key, and the first face
 * pairs with itself (its neighbour -1). */
static void match_neighbors(const tpk_face_matcher *m, bucket_scratch *s, int64_t b, int64_t n, int worker)
{
    const tpk_match_face *f = s->faces;
    int32_t *nb = m->neighbors;
    if (n == 1) {
        nb[4 * (int64_t)f[0].item + f[0].local] = -1;
        return;
    }
    int bits = 2;
    while (((int64_t)1 << bits) < 4 * n)
        bits++;
    if (((int64_t)1 << bits) > s->table_cap) {
        int32_t *grown = realloc(s->table, sizeof *grown << bits);
        if (!grown) {
            s->failed = 1;
            return;
        }
        s->table = grown;
        s->table_cap = (int64_t)1 << bits;
    }
    int32_t *table = s->table;
    uint32_t mask = (1u << bits) - 1;
    memset(table, 0xff, sizeof *table << bits);
    for (int64_t i = 0; i < n; i++) {
        uint64_t key = f[i].key;
        uint32_t h = (uint32_t)((key * 0x9e3779b97f4a7c15ull) >> (64 - bits));
        int32_t at, j;
        for (;; h = (h + 1) & mask) {
            at = table[h];
            j = at == -1 ? (int32_t)i : at >= 0 ? at : -2 - at;
            if (f[j].key == key)
                break;
        }
        int64_t si = 4 * (int64_t)f[i].item + f[i].local;
        if (__builtin_expect(at < -1, 0)) {
            nb[si] = -1;
            if (s->bad_bucket < 0) {
                s->bad_bucket = b;
                s->bad_key = key;
            }
            continue;
        }
        int fresh = at == -1;
        int64_t sj = 4 * (int64_t)f[j].item + f[j].local;
        table[h] = fresh ? (int32_t)i : -2 - at;
        nb[si] = fresh ? -1 : (int32_t)f[j].item;
        nb[sj] = fresh ? -1 : (int32_t)f[i].item;
        if (m->agreeing && !fresh && f[i].odd == f[j].odd)
            m->agreeing(m->user, worker, si, sj);
    }
}

static int face_less(const tpk_match_face *a, const tpk_match_face *b)
{
    if (a->key != b->key)
        return a->key < b->key;
    if (a->key3 != b->key3)
        return a->key3 < b->key3;
    if (a->item != b->item)
        return a->item < b->item;
    return a->local < b->local;
}

static void swap_faces(tpk_match_face *a, tpk_match_face *b)
{
    tpk_match_face t = *a;
    *a = *b;
    *b = t;
}

/* Buckets hold a few dozen faces: insertion sort, with quicksort (median of three) above that. */
static void sort_faces(tpk_match_face *r, int64_t n)
{
    while (n > 24) {
        int64_t mid = n / 2, last = n - 1;
        if (face_less(&r[mid], &r[0]))
            swap_faces(&r[mid], &r[0]);
        if (face_less(&r[last], &r[0]))
            swap_faces(&r[last], &r[0]);
        if (face_less(&r[last], &r[mid]))
            swap_faces(&r[last], &r[mid]);
        tpk_match_face pivot = r[mid];
        int64_t i = 0, j = last;
        for (;;) {
            while (face_less(&r[i], &pivot))
                i++;
            while (face_less(&pivot, &r[j]))
                j--;
            if (i >= j)
                break;
            swap_faces(&r[i++], &r[j--]);
        }
        if (j + 1 < n - j - 1) { /* recurse into the smaller part, loop on the larger */
            sort_faces(r, j + 1);
            r += j + 1;
            n -= j + 1;
        } else {
            sort_faces(r + j + 1, n - j - 1);
            n = j + 1;
        }
    }
    for (int64_t i = 1; i < n; i++) {
        tpk_match_face x = r[i];
        int64_t j = i;
        for (; j > 0 && face_less(&x, &r[j - 1]); j--)
            r[j] = r[j - 1];
        r[j] = x;
    }
}

static void match_runs(const tpk_face_matcher *m, tpk_match_face *f, int64_t bucket, int64_t n, int worker)
{
    sort_faces(f, n);
    for (int64_t i = 0, j; i < n; i = j) {
        for (j = i + 1; j < n && f[j].key == f[i].key && f[j].key3 == f[i].key3; j++)
            ;
        m->run(m->user, worker, bucket, f + i, j - i);
    }
}

static void match_buckets(void *ctx, int64_t begin, int64_t end, int worker)
{
    match_job *job = ctx;
    const tpk_face_matcher *m = job->m;
    bucket_scratch *s = &job->scratch[worker];
    (void)begin;
    (void)end;
    s->bad_bucket = -1;
    for (int64_t b = job->wa + job->bucket_begin[worker]; b < job->wa + job->bucket_begin[worker + 1] && !s->failed;
         b++) {
        int64_t n = expand_bucket(job, s, b);
        if (n < 0)
            s->failed = 1;
        else if (n > 0 && m->neighbors)
            match_neighbors(m, s, b, n, worker);
        else if (n > 0)
            match_runs(m, s->faces, b + job->lo, n, worker);
    }
}

/* Each worker's count becomes its first slot: the workers' parts of a bucket follow each other in
 * worker order, and the window's buckets in vertex order. */
static int prefix_counts(match_job *job, int64_t items)
{
    int64_t running = 0, largest = 0, range[TPK_MAX_THREADS][2];
    int threads = job->m->threads;
    for (int w = 0; w < threads; w++)
        tpk_parallel_range(items, threads, w, &range[w][0], &range[w][1]);
    for (int64_t v = job->wa; v < job->wb; v++) {
        int64_t begin = running;
        for (int w = 0; w < threads; w++) {
            int64_t c = job->starts[w][v];
            if (job->sorted) { /* less the worker's tets of smallest id v, which bring no entry */
                int64_t lo = job->first[v] > range[w][0] ? job->first[v] : range[w][0];
                int64_t hi = job->first[v + 1] < range[w][1] ? job->first[v + 1] : range[w][1];
                c -= hi > lo ? hi - lo : 0;
            }
            job->starts[w][v] = (uint32_t)running;
            running += c;
        }
        if (running - begin > largest)
            largest = running - begin;
        if (running > UINT32_MAX)
            return -1;
    }
    job->entry_count = running;
    job->largest = largest;
    return 0;
}

/* Where bucket b's work starts, for splitting the buckets among the workers: its entries, and with sorted
 * tets three faces for each tet of a smaller smallest id. */
static int64_t first_entry(const void *ctx, int64_t b)
{
    const match_job *job = ctx;
    int64_t tets_before = job->sorted ? (int64_t)job->first[job->wa + b] - job->first[job->wa] : 0;
    return bucket_first(job, job->wa + b) + 3 * tets_before;
}

/* The faces of the bad bucket `b` whose key is `key`: count and the first items, ascending. */
static void describe_shared(match_job *job, int w, tpk_match_failure *f)
{
    bucket_scratch *s = &job->scratch[w];
    int64_t b = s->bad_bucket, n = expand_bucket(job, s, b), run = 0;
    for (int64_t i = 0; i < n; i++)
        if (s->faces[i].key == s->bad_key && run++ < TPK_MATCH_LISTED)
            f->listed[run - 1] = (int32_t)s->faces[i].item;
    f->listed_count = run < TPK_MATCH_LISTED ? (int)run : TPK_MATCH_LISTED;
    for (int i = 1; i < f->listed_count; i++) /* insertion sort: at most 16 */
        for (int j = i; j > 0 && f->listed[j] < f->listed[j - 1]; j--) {
            int32_t t = f->listed[j];
            f->listed[j] = f->listed[j - 1];
            f->listed[j - 1] = t;
        }
    f->shared_count = run;
    f->shared_ids[0] = (int32_t)(b + job->lo);
    f->shared_ids[1] = (int32_t)(s->bad_key >> 32);
    f->shared_ids[2] = (int32_t)(uint32_t)s->bad_key;
}

static void free_job(match_job *job)
{
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        tpk_free_large(job->starts[w], sizeof *job->starts[w] * (size_t)(job->buckets ? job->buckets : 1));
        free(job->scratch[w].faces);
        free(job->scratch[w].table);
    }
    tpk_free_large(job->entries, sizeof *job->entries * (size_t)(job->entries_cap ? job->entries_cap : 1));
    tpk_free_large(job->first, sizeof *job->first * (size_t)(job->buckets + 1));
    free(job);
}

static int finish(match_job *job, int rc)
{
    free_job(job);
    return rc;
}

int tpk_face_match(const tpk_face_matcher *m, tpk_match_failure *failure)
{
    tpk_match_failure unused;
    tpk_match_failure *f = failure ? failure : &unused;
    memset(f, 0, sizeof *f);
    f->bad_item = -1;
    int64_t items_begin = m->item_end > 0 ? m->item_begin : 0, items_end = m->item_end > 0 ? m->item_end : m->item_count;
    if (m->tag_bits && m->item_count > (int64_t)(UINT32_MAX >> m->tag_bits))
        return TPK_MATCH_LIMIT;
    match_job *job = calloc(1, sizeof *job);
    if (!job)
        return TPK_MATCH_NOMEM;
    job->m = m;
    job->first_item = items_begin;
    job->lo = m->window_hi > 0 ? m->window_lo : 0;
    job->hi = m->window_hi > 0 ? m->window_hi : m->vertex_count;
    job->buckets = job->hi - job->lo;
    job->plain = m->tets && !m->keep && !m->tag && items_begin == 0;
    job->item_mask = m->tag_bits ? UINT32_MAX >> m->tag_bits : UINT32_MAX;
    if (job->plain && m->neighbors)
        job->second = m->neighbors;
    int threads = m->threads;
    for (int w = 0; w < threads; w++)
        if (!(job->starts[w] = tpk_alloc_large(sizeof *job->starts[w] * (size_t)(job->buckets ? job->buckets : 1))))
            return finish(job, TPK_MATCH_NOMEM);
    if (job->plain && job->lo == 0 && job->hi == m->vertex_count && items_end <= INT32_MAX)
        job->first = tpk_alloc_large(sizeof *job->first * (size_t)(job->buckets + 1)); /* NULL: no matter */

    /* count over the items, scatter over them again, match over the buckets: each split among the workers */
    tpk_parallel_for(items_end - items_begin, threads, count_entries, job);
    for (int w = 0; w < threads; w++)
        if (job->bad_item[w] >= 0) {
            f->bad_item = job->bad_item[w];
            return finish(job, TPK_MATCH_BAD_ITEM);
        }
    int windows = m->windows > 1 ? m->windows : 1;
    if (job->first) {
        job->sorted = 1;
        for (int w = 0; w < threads; w++)
            job->sorted &= !job->unsorted[w];
        for (int64_t v = items_end > 0 ? clamped_smallest(job, items_end - 1) + 1 : 0; v <= job->buckets; v++)
            job->first[v] = (int32_t)items_end;
        if (!job->sorted) {
            tpk_free_large(job->first, sizeof *job->first * (size_t)(job->buckets + 1));
            job->first = NULL;
        } else {
            windows = (windows + 1) / 2; /* half the entries: a window holds twice the buckets */
        }
    }
    if (windows > job->buckets)
        windows = job->buckets > 0 ? (int)job->buckets : 1;
    for (int k = 0; k < windows; k++) {
        job->wa = job->buckets * k / windows, job->wb = job->buckets * (k + 1) / windows;
        if (prefix_counts(job, items_end - items_begin))
            return finish(job, TPK_MATCH_LIMIT);
        tpk_free_large(job->entries, sizeof *job->entries * (size_t)(job->entries_cap ? job->entries_cap : 1));
        job->entries_cap = job->entry_count;
        job->entries = tpk_alloc_large(sizeof *job->entries * (size_t)(job->entry_count ? job->entry_count : 1));
        if (!job->entries)
            return finish(job, TPK_MATCH_NOMEM);
        tpk_parallel_for(items_end - items_begin, threads, scatter_entries, job);
        job->bucket_end = job->starts[threads - 1];
        int64_t work = job->entry_count + (job->sorted ? 3 * (int64_t)(job->first[job->wb] - job->first[job->wa]) : 0);
        tpk_split_by(first_entry, job, job->wb - job->wa, work, threads, job->bucket_begin);
        tpk_parallel_for(threads, threads, match_buckets, job);
        for (int w = 0; w < threads; w++)
            if (job->scratch[w].failed) {
                f->largest = job->largest;
                return finish(job, TPK_MATCH_NOMEM);
            }
        for (int w = 0; w < threads; w++)
            if (m->neighbors && job->scratch[w].bad_bucket >= 0) {
                describe_shared(job, w, f);
                return finish(job, TPK_MATCH_SHARED);
            }
    }
    return finish(job, TPK_MATCH_OK);
}
