/* Face matching for `tetpack check` (301, 302, 305, components, the shell), sort-based like
 * tools/convert/connect.c (tets by the same rule, mesh/face_buckets.h) but for any volume cell: a
 * counting sort puts every cell into the bucket of each distinct smallest id of its faces (4 bytes per
 * entry: the cell id), so bucket v holds exactly the faces whose smallest id is v. A worker expands its
 * buckets into faces keyed by their other sorted ids, sorts each bucket (a few dozen faces) and walks
 * runs of equal keys: one face is shell, two are neighbours (orientation and fold-over are checked, the
 * cells joined), more is a non-manifold face. Workers take contiguous cell and bucket ranges and their
 * results are merged in order, so counts, examples and the shell order (by sorted vertex ids) do not
 * depend on the thread count. */
#include <stdlib.h>
#include <string.h>

#include "check_topo.h"
#include "base/parallel.h"
#include "mesh/face_buckets.h"

enum { HIT_NONMANIFOLD, HIT_ORIENTATION, HIT_FOLDED, HIT_KINDS };
static const int HIT_IDS[HIT_KINDS] = {301, 302, 305};

/* A face in a bucket: the ids after the smallest, sorted, as key = id1 << 32 | id2 and key3 = id3
 * (UINT32_MAX for a triangle); its vertices in order are looked up again only for shared faces. */
typedef struct face_rec {
    uint64_t key;
    uint32_t key3, cell;
    uint16_t local;
    int8_t sign; /* tets_only: the tet's orientation, carried in its bucket entry */
} face_rec;

/* tets_only entries: the cell id, and its orientation + 1 in the top two bits (cells < 2^30). */
#define ENTRY_CELL 0x3fffffffu
#define ENTRY_SIGN_SHIFT 30

typedef struct worker_out {
    int64_t counts[HIT_KINDS];
    int kept[HIT_KINDS];
    tpk_example *examples[HIT_KINDS]; /* max_examples each: the worker's first hits */
    tpk_bface *shell;
    int64_t shell_count, shell_cap;
    face_rec *recs;
    int64_t rec_cap;
    int failed; /* out of memory */
} worker_out;

typedef struct match_job {
    const tpk_mesh *mesh;
    int threads, max_examples;
    int tets_only;                    /* every cell a tet at offset 4 c: the fast paths below */
    int8_t *signs;                    /* tets_only: orientation of each tet (exact), for 305, until the
                                         entries carry it */
    int64_t *starts[TPK_MAX_THREADS]; /* per worker, per vertex: count, then next slot */
    int64_t *bucket_start;            /* point_count + 1 */
    uint32_t *entries;
    uint32_t *parent;
    int64_t bucket_begin[TPK_MAX_THREADS + 1];
    worker_out out[TPK_MAX_THREADS];
} match_job;

/* The distinct smallest ids of a cell's faces (the buckets the cell goes to). */
static int face_mins(const tpk_topo_face *faces, int count, int32_t *mins)
{
    int n = 0;
    for (int f = 0; f < count; f++) {
        int32_t m = faces[f].v[tpk_topo_min_index(&faces[f])], seen = 0;
        for (int i = 0; i < n && !seen; i++)
            seen = mins[i] == m;
        if (!seen)
            mins[n++] = m;
    }
    return n;
}

/* The buckets of a cell: for a tet its two smallest ids (three faces hold the smallest, the fourth
 * face's smallest is the second). */
static int cell_buckets(const match_job *job, int64_t c, int32_t *mins)
{
    if (job->tets_only) {
        tpk_sorted_tet s;
        tpk_sort_tet(job->mesh->cell_conn + 4 * c, &s);
        mins[0] = s.id[0];
        mins[1] = s.id[1];
        return 2;
    }
    tpk_topo_face faces[TPK_TOPO_MAX_CELL_FACES];
    return face_mins(faces, tpk_topo_cell_faces(job->mesh, c, faces), mins);
}

static void count_entries(void *ctx, int64_t begin, int64_t end, int worker)
{
    match_job *job = ctx;
    int64_t *count = job->starts[worker];
    memset(count, 0, sizeof *count * (size_t)job->mesh->point_count);
    int32_t mins[TPK_TOPO_MAX_CELL_FACES], ring[16][2]; /* tets: buckets of the cells ahead */
    for (int64_t c = begin; c < end && job->tets_only && c < begin + 16; c++)
        cell_buckets(job, c, ring[c & 15]);
    for (int64_t c = begin; c < end; c++) {
        if (job->tets_only) { /* counts of a shuffled mesh are random accesses: ask 16 cells ahead */
            mins[0] = ring[c & 15][0];
            mins[1] = ring[c & 15][1];
            if (c + 16 < end) {
                cell_buckets(job, c + 16, ring[c & 15]);
                __builtin_prefetch(count + ring[c & 15][0], 1);
                __builtin_prefetch(count + ring[c & 15][1], 1);
            }
        }
        if (tpk_topo_face_count(job->mesh, c) == 0 || !tpk_check_cell_usable(job->mesh, c)) {
            job->parent[c] = TPK_UF_NONE;
            continue;
        }
        job->parent[c] = (uint32_t)c;
        int nm = 2;
        if (job->tets_only) {
            const int32_t *v = job->mesh->cell_conn + 4 * c;
            if (c + 8 < end)
                for (int k = 0; k < 4; k++)
                    __builtin_prefetch(job->mesh->points + 3 * (int64_t)v[32 + k]);
            job->signs[c] = (int8_t)tpk_topo_orient(job->mesh->points, v[0], v[1], v[2], v[3]);
        } else {
            nm = cell_buckets(job, c, mins);
        }
        for (int i = 0; i < nm; i++)
            count[mins[i]]++;
    }
}

static void scatter_entries(void *ctx, int64_t begin, int64_t end, int worker)
{
    match_job *job = ctx;
    int64_t *next = job->starts[worker];
    int32_t mins[TPK_TOPO_MAX_CELL_FACES], ring[16][2];
    for (int64_t c = begin; c < end && job->tets_only && c < begin + 16; c++)
        cell_buckets(job, c, ring[c & 15]);
    for (int64_t c = begin; c < end; c++) {
        int nm = 2;
        if (job->tets_only) { /* two stages ahead: the slot (16 cells), then where it points (8) */
            mins[0] = ring[c & 15][0];
            mins[1] = ring[c & 15][1];
            if (c + 16 < end) {
                cell_buckets(job, c + 16, ring[c & 15]);
                __builtin_prefetch(next + ring[c & 15][0], 1);
                __builtin_prefetch(next + ring[c & 15][1], 1);
            }
            if (c + 8 < end) {
                const int32_t *at = ring[(c + 8) & 15];
                __builtin_prefetch(job->entries + next[at[0]], 1);
                __builtin_prefetch(job->entries + next[at[1]], 1);
            }
        }
        if (job->parent[c] == TPK_UF_NONE)
            continue;
        if (!job->tets_only)
            nm = cell_buckets(job, c, mins);
        uint32_t entry = (uint32_t)c;
        if (job->tets_only)
            entry |= (uint32_t)(job->signs[c] + 1) << ENTRY_SIGN_SHIFT;
        for (int i = 0; i < nm; i++)
            job->entries[next[mins[i]]++] = entry;
    }
}

static int rec_less(const face_rec *a, const face_rec *b)
{
    if (a->key != b->key)
        return a->key < b->key;
    if (a->key3 != b->key3)
        return a->key3 < b->key3;
    if (a->cell != b->cell)
        return a->cell < b->cell;
    return a->local < b->local;
}

static void swap_recs(face_rec *a, face_rec *b)
{
    face_rec t = *a;
    *a = *b;
    *b = t;
}

/* Buckets hold a few dozen faces: insertion sort, with quicksort (median of three) above that. */
static void sort_recs(face_rec *r, int64_t n)
{
    while (n > 24) {
        int64_t mid = n / 2, last = n - 1;
        if (rec_less(&r[mid], &r[0]))
            swap_recs(&r[mid], &r[0]);
        if (rec_less(&r[last], &r[0]))
            swap_recs(&r[last], &r[0]);
        if (rec_less(&r[last], &r[mid]))
            swap_recs(&r[last], &r[mid]);
        face_rec pivot = r[mid];
        int64_t i = 0, j = last;
        for (;;) {
            while (rec_less(&r[i], &pivot))
                i++;
            while (rec_less(&pivot, &r[j]))
                j--;
            if (i >= j)
                break;
            swap_recs(&r[i++], &r[j--]);
        }
        if (j + 1 < n - j - 1) { /* recurse into the smaller part, loop on the larger */
            sort_recs(r, j + 1);
            r += j + 1;
            n -= j + 1;
        } else {
            sort_recs(r + j + 1, n - j - 1);
            n = j + 1;
        }
    }
    for (int64_t i = 1; i < n; i++) {
        face_rec x = r[i];
        int64_t j = i;
        for (; j > 0 && rec_less(&x, &r[j - 1]); j--)
            r[j] = r[j - 1];
        r[j] = x;
    }
}

static void sort_ids(int32_t *v, int n)
{
    for (int i = 1; i < n; i++) {
        int32_t x = v[i];
        int j = i;
        for (; j > 0 && x < v[j - 1]; j--)
            v[j] = v[j - 1];
        v[j] = x;
    }
}

static void make_rec(face_rec *r, const tpk_topo_face *f, uint32_t cell, uint32_t local)
{
    int32_t s[TPK_TOPO_MAX_FACE_VERTS];
    memcpy(s, f->v, sizeof s);
    sort_ids(s, f->n);
    r->key = (uint64_t)(uint32_t)s[1] << 32 | (uint32_t)s[2];
    r->key3 = f->n == 4 ? (uint32_t)s[3] : UINT32_MAX;
    r->cell = cell;
    r->local = (uint16_t)local;
    r->sign = 0;
}

/* The face `local` of a cell in outward order. */
static void face_of(const match_job *job, uint32_t cell, uint32_t local, tpk_topo_face *out)
{
    if (!job->tets_only) {
        tpk_topo_cell_face(job->mesh, cell, (int)local, out);
        return;
    }
    const int32_t *v = job->mesh->cell_conn + 4 * (int64_t)cell; /* no offsets or types to read */
    out->n = 3;
    for (int i = 0; i < 3; i++)
        out->v[i] = v[tpk_tet_faces[local][i]];
}

/* A tet's faces whose smallest id is v (its smallest or second smallest id), by mesh/face_buckets.h. */
static int tet_recs(const int32_t *conn, uint32_t entry, int32_t v, face_rec *r)
{
    uint32_t c = entry & ENTRY_CELL;
    int8_t sign = (int8_t)((int)(entry >> ENTRY_SIGN_SHIFT) - 1);
    tpk_sorted_tet s;
    tpk_sort_tet(conn + 4 * (int64_t)c, &s);
    tpk_bucket_face f[3];
    int n = tpk_tet_bucket_faces(&s, s.id[0] == v, f);
    for (int i = 0; i < n; i++)
        r[i] = (face_rec){(uint64_t)(uint32_t)f[i].mid << 32 | (uint32_t)f[i].max, UINT32_MAX, c,
                          (uint16_t)f[i].opposite, sign};
    return n;
}

static int cell_recs(const tpk_mesh *mesh, uint32_t c, int32_t v, face_rec *r)
{
    tpk_topo_face faces[TPK_TOPO_MAX_CELL_FACES];
    int nf = tpk_topo_cell_faces(mesh, c, faces), n = 0;
    for (int f = 0; f < nf; f++)
        if (faces[f].v[tpk_topo_min_index(&faces[f])] == v)
            make_rec(&r[n++], &faces[f], c, (uint32_t)f);
    return n;
}

static int grow_recs(worker_out *o, int64_t need)
{
    if (need <= o->rec_cap)
        return 0;
    int64_t cap = 2 * need + 64;
    face_rec *grown = realloc(o->recs, sizeof *grown * (size_t)cap);
    if (!grown)
        return -1;
    o->recs = grown;
    o->rec_cap = cap;
    return 0;
}

/* Reads ahead of entry i (up to `limit`, the end of the worker's entries, so across buckets): the
 * cells of a bucket lie anywhere in memory on a mesh in random order. 32 entries ahead the nodes (for
 * other cells first their offset), 16 ahead the union-find entry (and the points of cells other than
 * tets, which test fold-over on them), 8 ahead the entry's parent. */
static inline void read_ahead(const match_job *job, int64_t i, int64_t limit)
{
    const tpk_mesh *mesh = job->mesh;
    if (job->tets_only) {
        if (i + 32 < limit)
            __builtin_prefetch(mesh->cell_conn + 4 * (int64_t)(job->entries[i + 32] & ENTRY_CELL));
    } else {
        if (i + 48 < limit)
            __builtin_prefetch(mesh->cell_offsets + job->entries[i + 48]);
        if (i + 32 < limit)
            __builtin_prefetch(mesh->cell_conn + mesh->cell_offsets[job->entries[i + 32]]);
    }
    uint32_t mask = job->tets_only ? ENTRY_CELL : UINT32_MAX;
    if (i + 16 < limit)
        __builtin_prefetch(job->parent + (job->entries[i + 16] & mask), 1);
    if (!job->tets_only && i + 16 < limit) { /* other cells test fold-over on their points */
        uint32_t c = job->entries[i + 16];
        for (int64_t k = mesh->cell_offsets[c]; k < mesh->cell_offsets[c + 1]; k++)
            __builtin_prefetch(mesh->points + 3 * (int64_t)mesh->cell_conn[k]);
    }
    if (i + 8 < limit) { /* the union will walk up: its parent has arrived by now, ask for the next */
        uint32_t up = __atomic_load_n(job->parent + (job->entries[i + 8] & mask), __ATOMIC_RELAXED);
        __builtin_prefetch(job->parent + up, 1);
    }
}

/* Expands bucket v into the worker's records; returns their count, or -1 when out of memory. */
static int64_t expand_bucket(match_job *job, worker_out *o, int64_t v, int64_t limit)
{
    const tpk_mesh *mesh = job->mesh;
    int64_t n = 0, begin = job->bucket_start[v], end = job->bucket_start[v + 1];
    for (int64_t i = begin; i < end; i++) {
        read_ahead(job, i, limit);
        if (grow_recs(o, n + TPK_TOPO_MAX_CELL_FACES))
            return -1;
        uint32_t c = job->entries[i];
        n += job->tets_only ? tet_recs(mesh->cell_conn, c, (int32_t)v, o->recs + n)
                            : cell_recs(mesh, c, (int32_t)v, o->recs + n);
    }
    return n;
}

/* Side of triangle `tri` that cell `cell` lies on: the sign every vertex of the cell off the face
 * shares, or 0 when they do not agree (a cell that is itself warped or flat: the cell checks say so).
 * With `first_only`, the sign of the first vertex off the face. */
static int cell_side(const tpk_mesh *mesh, uint32_t cell, const tpk_topo_face *face, const int32_t tri[3],
                     int first_only)
{
    int pos = 0, neg = 0;
    for (int64_t i = mesh->cell_offsets[cell]; i < mesh->cell_offsets[cell + 1]; i++) {
        int32_t p = mesh->cell_conn[i], on_face = 0;
        for (int k = 0; k < face->n; k++)
            on_face |= face->v[k] == p;
        if (on_face)
            continue;
        int s = tpk_topo_orient(mesh->points, tri[0], tri[1], tri[2], p);
        if (first_only)
            return s;
        pos |= s > 0;
        neg |= s < 0;
    }
    return pos && !neg ? 1 : neg && !pos ? -1 : 0;
}

/* 305: both cells on the same side of a triangle of the face (quads: the smallest-id diagonal split).
 * One vertex of each strictly on opposite sides already rules it out: the usual case, two tests. */
static int folded(const tpk_mesh *mesh, uint32_t cell_a, const tpk_topo_face *fa, uint32_t cell_b)
{
    int triangles = fa->n == 4 ? 2 : 1;
    for (int t = 0; t < triangles; t++) {
        int32_t tri[3];
        tpk_topo_face_triangle(fa, t, tri);
        if (cell_side(mesh, cell_a, fa, tri, 1) * cell_side(mesh, cell_b, fa, tri, 1) < 0)
            continue;
        int sa = cell_side(mesh, cell_a, fa, tri, 0);
        if (sa != 0 && sa == cell_side(mesh, cell_b, fa, tri, 0))
            return 1;
    }
    return 0;
}

static int consistent(const tpk_topo_face *a, const tpk_topo_face *b);

/* 305 for two tets from their exact orientations: a positive tet lies on the negative side of its own
 * outward face order, so a sits on side -sign(a) of its order of the face, and b on side sign(b) when
 * it traverses the face the other way (consistent), else -sign(b). */
static int tets_folded(const face_rec *a, const face_rec *b, int consistent_order)
{
    int side_a = -a->sign, side_b = consistent_order ? b->sign : -b->sign;
    return side_a != 0 && side_a == side_b;
}

/* 302: neighbours must traverse the shared face in opposite directions (b is a reversed). */
static int consistent(const tpk_topo_face *a, const tpk_topo_face *b)
{
    int n = a->n, ia = tpk_topo_min_index(a), ib = tpk_topo_min_index(b);
    for (int k = 1; k < n; k++) {
        int i = ia + k, j = ib - k;
        if (a->v[i >= n ? i - n : i] != b->v[j < 0 ? j + n : j])
            return 0;
    }
    return 1;
}

static tpk_example *worker_hit(match_job *job, worker_out *o, int kind)
{
    o->counts[kind]++;
    if (o->kept[kind] >= job->max_examples)
        return NULL;
    tpk_example *ex = &o->examples[kind][o->kept[kind]++];
    memset(ex, 0, sizeof *ex);
    ex->kind = "face";
    return ex;
}

/* Example ids: the face's sorted vertex ids, then cells as long as they fit. */
static void face_example(const tpk_mesh *mesh, tpk_example *ex, const tpk_topo_face *face, const face_rec *r,
                         int64_t cells_n)
{
    int64_t ids[TPK_CHECK_MAX_IDS];
    int n = 0;
    int32_t s[TPK_TOPO_MAX_FACE_VERTS];
    memcpy(s, face->v, sizeof s);
    sort_ids(s, face->n);
    for (int i = 0; i < face->n; i++)
        ids[n++] = s[i];
    for (int64_t i = 0; i < cells_n && n < TPK_CHECK_MAX_IDS; i++)
        ids[n++] = r[i].cell;
    tpk_example_ids(ex, n, ids);
    double centre[3];
    tpk_topo_face_centre(mesh, face, centre);
    tpk_example_point(ex, centre);
}

static void nonmanifold_face(match_job *job, worker_out *o, const face_rec *r, int64_t n)
{
    for (int64_t i = 1; i < n; i++)
        tpk_uf_union(job->parent, r[0].cell, r[i].cell);
    tpk_example *ex = worker_hit(job, o, HIT_NONMANIFOLD);
    if (!ex)
        return;
    tpk_topo_face face;
    face_of(job, r[0].cell, r[0].local, &face);
    face_example(job->mesh, ex, &face, r, n);
    tpk_example_note(ex, "face of %lld cells (at most 2 allowed); ids: the face's vertices, then cells",
                     (long long)n);
}

static void shared_face(match_job *job, worker_out *o, const face_rec *r)
{
    tpk_uf_union(job->parent, r[0].cell, r[1].cell);
    tpk_topo_face fa, fb;
    face_of(job, r[0].cell, r[0].local, &fa);
    face_of(job, r[1].cell, r[1].local, &fb);
    if (!consistent(&fa, &fb)) {
        tpk_example *ex = worker_hit(job, o, HIT_ORIENTATION);
        if (ex) {
            face_example(job->mesh, ex, &fa, r, 2);
            tpk_example_note(ex, "cells %u and %u traverse this face in the same direction; one of them is "
                             "turned over", r[0].cell, r[1].cell);
        }
    }
    if (job->tets_only ? tets_folded(&r[0], &r[1], consistent(&fa, &fb))
                       : folded(job->mesh, r[0].cell, &fa, r[1].cell)) {
        tpk_example *ex = worker_hit(job, o, HIT_FOLDED);
        if (ex) {
            face_example(job->mesh, ex, &fa, r, 2);
            tpk_example_note(ex, "cells %u and %u lie on the same side of this face (exact orientation)",
                             r[0].cell, r[1].cell);
        }
    }
}

static int add_shell_face(const match_job *job, worker_out *o, const face_rec *r)
{
    if (o->shell_count == o->shell_cap) {
        int64_t cap = 2 * o->shell_cap + 256;
        tpk_bface *grown = realloc(o->shell, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        o->shell = grown;
        o->shell_cap = cap;
    }
    tpk_topo_face face;
    face_of(job, r->cell, r->local, &face);
    tpk_bface *s = &o->shell[o->shell_count++];
    for (int i = 0; i < TPK_TOPO_MAX_FACE_VERTS; i++)
        s->v[i] = i < face.n ? face.v[i] : -1;
    s->cell = r->cell;
    s->local = r->local;
    return 0;
}

static void match_buckets(void *ctx, int64_t begin, int64_t end, int worker)
{
    match_job *job = ctx;
    worker_out *o = &job->out[worker];
    (void)begin;
    (void)end;
    int64_t limit = job->bucket_start[job->bucket_begin[worker + 1]];
    for (int64_t v = job->bucket_begin[worker]; v < job->bucket_begin[worker + 1] && !o->failed; v++) {
        int64_t n = expand_bucket(job, o, v, limit);
        if (n < 0) {
            o->failed = 1;
            return;
        }
        sort_recs(o->recs, n);
        for (int64_t i = 0, j; i < n; i = j) {
            for (j = i + 1; j < n && o->recs[j].key == o->recs[i].key && o->recs[j].key3 == o->recs[i].key3; j++)
                ;
            if (j - i == 1)
                o->failed |= add_shell_face(job, o, &o->recs[i]) != 0;
            else if (j - i == 2)
                shared_face(job, o, &o->recs[i]);
            else
                nonmanifold_face(job, o, &o->recs[i], j - i);
        }
    }
}

/* Bucket starts from the per-worker counts; each worker's count becomes its first slot. */
static void prefix_counts(match_job *job)
{
    int64_t running = 0, vertices = job->mesh->point_count;
    for (int64_t v = 0; v < vertices; v++) {
        job->bucket_start[v] = running;
        for (int w = 0; w < job->threads; w++) {
            int64_t c = job->starts[w][v];
            job->starts[w][v] = running;
            running += c;
        }
    }
    job->bucket_start[vertices] = running;
}

/* Worker results in worker order = bucket order: the first examples overall, exact totals. */
static void merge_hits(match_job *job, tpk_check_report *report)
{
    for (int kind = 0; kind < HIT_KINDS; kind++) {
        for (int w = 0; w < job->threads; w++) {
            worker_out *o = &job->out[w];
            for (int i = 0; i < o->kept[kind]; i++) {
                tpk_example *ex = tpk_check_hit(report, HIT_IDS[kind], "face");
                if (ex)
                    *ex = o->examples[kind][i];
            }
            tpk_check_count(report, HIT_IDS[kind], o->counts[kind] - o->kept[kind]);
        }
    }
}

static int merge_shell(match_job *job, tpk_topo_match *out)
{
    int64_t total = 0;
    for (int w = 0; w < job->threads; w++)
        total += job->out[w].shell_count;
    out->shell = malloc(sizeof *out->shell * (size_t)(total ? total : 1));
    if (!out->shell)
        return -1;
    for (int w = 0; w < job->threads; w++) {
        if (job->out[w].shell_count == 0) /* its list may never have been allocated */
            continue;
        memcpy(out->shell + out->shell_count, job->out[w].shell, sizeof *out->shell * (size_t)job->out[w].shell_count);
        out->shell_count += job->out[w].shell_count;
    }
    return 0;
}

static void free_job(match_job *job)
{
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        free(job->starts[w]);
        free(job->out[w].shell);
        free(job->out[w].recs);
        for (int k = 0; k < HIT_KINDS; k++)
            free(job->out[w].examples[k]);
    }
    free(job->bucket_start);
    free(job->entries);
    free(job->signs);
    free(job);
}

static int alloc_job(match_job *job, int64_t vertices)
{
    job->bucket_start = malloc(sizeof *job->bucket_start * (size_t)(vertices + 1));
    if (!job->bucket_start)
        return -1;
    if (job->tets_only && !(job->signs = tpk_alloc_large((size_t)(job->mesh->cell_count ? job->mesh->cell_count : 1))))
        return -1;
    for (int w = 0; w < job->threads; w++) {
        if (!(job->starts[w] = malloc(sizeof *job->starts[w] * (size_t)(vertices ? vertices : 1))))
            return -1;
        for (int k = 0; k < HIT_KINDS; k++)
            if (!(job->out[w].examples[k] = calloc((size_t)job->max_examples + 1, sizeof(tpk_example))))
                return -1;
    }
    return 0;
}

void tpk_topo_match_free(tpk_topo_match *m)
{
    free(m->parent);
    free(m->shell);
    memset(m, 0, sizeof *m);
}

int tpk_topo_match_faces(const tpk_mesh *mesh, tpk_check_report *report, tpk_topo_match *out,
                         tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    if (mesh->cell_count > INT32_MAX || mesh->point_count > INT32_MAX)
        return tpk_diag_fail(diag, "check: %lld cells and %lld points exceed the connectivity checks' limit "
                             "of 2^31-1", (long long)mesh->cell_count, (long long)mesh->point_count);
    match_job *job = calloc(1, sizeof *job);
    out->parent = tpk_alloc_large(sizeof *out->parent * (size_t)(mesh->cell_count ? mesh->cell_count : 1));
    if (!job || !out->parent) {
        free(job);
        tpk_topo_match_free(out);
        return tpk_diag_fail(diag, "check: out of memory (face matching, %lld cells)", (long long)mesh->cell_count);
    }
    job->mesh = mesh;
    job->parent = out->parent;
    job->max_examples = report->options.max_examples;
    job->threads = tpk_threads_for(mesh->cell_count, tpk_thread_count(report->options.threads), 16384);
    job->tets_only = 1;
    for (int64_t c = 0; c < mesh->cell_count && job->tets_only; c++)
        job->tets_only = mesh->cell_types[c] == TPK_CELL_TETRA && mesh->cell_offsets[c] == 4 * c;
    job->tets_only &= mesh->cell_offsets[mesh->cell_count] == 4 * mesh->cell_count;
    job->tets_only &= mesh->cell_count <= (int64_t)ENTRY_CELL; /* the entries' top bits hold the sign */
    int rc = alloc_job(job, mesh->point_count);
    if (rc == 0) {
        tpk_parallel_for(mesh->cell_count, job->threads, count_entries, job);
        prefix_counts(job);
        tpk_check_progress(report, "faces", 0.2);
        int64_t entries = job->bucket_start[mesh->point_count];
        job->entries = tpk_alloc_large(sizeof *job->entries * (size_t)(entries ? entries : 1));
        rc = job->entries ? 0 : -1;
    }
    if (rc == 0) {
        tpk_parallel_for(mesh->cell_count, job->threads, scatter_entries, job);
        free(job->signs); /* the entries carry them now */
        job->signs = NULL;
        /* Workers get about the same number of entries. */
        tpk_split_prefix(job->bucket_start, job->mesh->point_count, job->bucket_start[job->mesh->point_count],
                         job->threads, job->bucket_begin);
        tpk_check_progress(report, "faces", 0.4);
        tpk_parallel_for(job->threads, job->threads, match_buckets, job);
        for (int w = 0; w < job->threads; w++)
            rc |= job->out[w].failed ? -1 : 0;
    }
    if (rc == 0) {
        merge_hits(job, report);
        rc = merge_shell(job, out);
    }
    free_job(job);
    if (rc != 0) {
        tpk_topo_match_free(out);
        return tpk_diag_fail(diag, "check: out of memory (face matching, %lld cells)", (long long)mesh->cell_count);
    }
    tpk_check_progress(report, "faces", 1.0);
    return 0;
}
