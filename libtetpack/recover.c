/* tpk_recover_tets: positively oriented vertex quadruples from any tet layout (spec/tetpack-format.md §6).
 * Tet32 stores three vertices, so the fourth is vx ^ v0 ^ v1 ^ v2. Tet20 and Tet16 store only vx and
 * neighbors, so the order is found by a walk from the shell:
 *   - a shell face (a,b,c) of t faces out of t, so t = (a,c,b,x) is positive, x = vx ^ a ^ b ^ c;
 *   - for a positive tet (p0..p3) the face opposite p_j in outward order is F_j = tpk_tet_faces[j]
 *     (format/tetpack_format.h); seen from the neighbor u across it, F_j faces inward, so
 *     u = (F_j, y) is positive, y = vx[u] ^ F_j[0] ^ F_j[1] ^ F_j[2].
 * Tet16 neighbors are decoded from the tet we arrived from: it is n[rank of the apex y]. Per tet only n3
 * (its neighbor by rank 3) is kept: the other three follow from it (Tet16: nx[r] ^ n3) or from the record
 * (Tet20), and n3 == UNSET marks a tet not reached yet.
 * The walk stores each tet in the order it was entered in (the faces are then walked in that order: in
 * canonical order the one-thread walk was 1.5x slower, its branches mispredicted, its front elsewhere);
 * a last pass turns each into the canonical rotation of its positive quadruple (canon), so the result
 * does not depend on which neighbor reached a tet first: the walk's order, and so the thread count, do
 * not show. The four neighbors' lines are prefetched together when a tet leaves the queue (111 against
 * 120 ns/tet, grid 55, one thread).
 * Untrusted input: every decoded id is range-checked, every tet is assigned once and each later visit
 * must agree with that assignment (face present, neighbor across is where we came from, same
 * orientation); no recursion. Threads: each takes a slice of the shell faces as seeds and walks from its
 * own FIFO queue; a tet is claimed by a compare-and-swap of its n3 (UNSET -> BUSY), its quadruple written,
 * then n3 published (release). Any error stops them all, and the one-thread walk runs again to give its
 * error: the errors do not depend on the thread count either. */
#include <stdlib.h>
#include <string.h>
#include <pthread.h>

#include "internal_mesh.h"
#include "internal_threads.h"

#define UNSET INT32_MIN
#define BUSY (INT32_MIN + 1)

typedef struct walk {
    const tpk_mesh_arrays *mesh;
    int64_t tet_count, vertex_count;
    int32_t *dst;     /* 4 per tet: the order of entry, then (canon_all) the canonical rotation */
    int32_t *n3;      /* per tet: its neighbor by rank 3, UNSET while unassigned, BUSY while being assigned */
    int threads;      /* 1: plain stores, no compare-and-swap */
    int stop;         /* set (atomically) by the first thread with an error */
} walk;

typedef struct queue {
    int32_t *ids;
    int64_t head, tail, cap;
} queue;

/* The walk runs on Tet20 and Tet16 only (recover reads Tet32 directly), as vx_ptr and neighbor assume. */
static int32_t vx_of(const walk *w, int64_t t)
{
    return w->mesh->layout == TPK_LAYOUT_TET20 ? w->mesh->tet20[t].vx : w->mesh->tet16[t].vx;
}

static const void *vx_ptr(const walk *w, int64_t t)
{
    return w->mesh->layout == TPK_LAYOUT_TET20 ? (const void *)&w->mesh->tet20[t] : (const void *)&w->mesh->tet16[t];
}

static int rank_of(const int32_t *q, int k)
{
    return (q[0] < q[k]) + (q[1] < q[k]) + (q[2] < q[k]) + (q[3] < q[k]);
}

/* The even permutation of q (distinct ids) with the smallest id first, then the smallest of the other
 * three: the ids in ascending order, the last two swapped when that order is an odd permutation of q. */
static void canon(int32_t q[4])
{
    int r[4], s[4];
    for (int k = 0; k < 4; k++)
        r[k] = rank_of(q, k);
    for (int k = 0; k < 4; k++)
        s[r[k]] = q[k];
    int odd = ((r[0] > r[1]) + (r[0] > r[2]) + (r[0] > r[3]) + (r[1] > r[2]) + (r[1] > r[3]) + (r[2] > r[3])) & 1;
    q[0] = s[0], q[1] = s[1], q[2] = s[2 + odd], q[3] = s[3 - odd];
}

/* Neighbor of tet t by rank r, from its n3. */
static int32_t neighbor(const walk *w, int64_t t, int32_t n3, int r)
{
    if (w->mesh->layout == TPK_LAYOUT_TET20)
        return w->mesh->tet20[t].n[r];
    return r == 3 ? n3 : w->mesh->tet16[t].nx[r] ^ n3;
}

/* Tet u entered from `from` through face f: its quadruple (f, y) into q and its n3; every id checked. */
static tpk_result decode(const walk *w, int64_t u, const int32_t f[3], int32_t from, int32_t q[4], int32_t *n3)
{
    int32_t y = vx_of(w, u) ^ f[0] ^ f[1] ^ f[2];
    if (y < 0 || y >= w->vertex_count)
        return TPK_ERR_CORRUPT;
    if (y == f[0] || y == f[1] || y == f[2] || f[0] == f[1] || f[0] == f[2] || f[1] == f[2])
        return TPK_ERR_CORRUPT;
    q[0] = f[0], q[1] = f[1], q[2] = f[2], q[3] = y;
    int entry_rank = rank_of(q, 3);
    int32_t n[4];
    if (w->mesh->layout == TPK_LAYOUT_TET20) {
        memcpy(n, w->mesh->tet20[u].n, sizeof n);
    } else {
        const int32_t *nx = w->mesh->tet16[u].nx;
        n[3] = entry_rank == 3 ? from : nx[entry_rank] ^ from;
        for (int r = 0; r < 3; r++)
            n[r] = nx[r] ^ n[3];
    }
    for (int r = 0; r < 4; r++)
        if (n[r] < -1 || n[r] >= w->tet_count)
            return TPK_ERR_CORRUPT;
    if (n[entry_rank] != from) /* Tet20: the stored neighbor must be where we came from */
        return TPK_ERR_MESH;
    *n3 = n[3];
    return TPK_OK;
}

/* A later visit of assigned tet u (quadruple q, n3) through face f from `from`: f must be a face of u
 * whose neighbor is `from`, and (f, apex) must be an even permutation of q (the same orientation). */
static tpk_result check_visit(const walk *w, int64_t u, const int32_t *q, int32_t n3, const int32_t f[3],
                              int32_t from)
{
    int p[4] = {-1, -1, -1, -1}, apex = -1, matched = 0;
    for (int k = 0; k < 4; k++) {
        int i = q[k] == f[0] ? 0 : q[k] == f[1] ? 1 : q[k] == f[2] ? 2 : -1;
        if (i < 0)
            apex = k;
        else if (p[i] < 0)
            p[i] = k, matched++;
    }
    if (matched != 3 || apex < 0)
        return TPK_ERR_MESH;
    p[3] = apex;
    int odd = (p[0] > p[1]) + (p[0] > p[2]) + (p[0] > p[3]) + (p[1] > p[2]) + (p[1] > p[3]) + (p[2] > p[3]);
    if (odd & 1)
        return TPK_ERR_MESH;
    return neighbor(w, u, n3, rank_of(q, apex)) == from ? TPK_OK : TPK_ERR_MESH;
}

static int push(queue *qu, int32_t t)
{
    if (qu->tail == qu->cap) {
        int64_t cap = qu->cap ? 2 * qu->cap : 4096;
        int32_t *ids = realloc(qu->ids, sizeof *ids * (size_t)cap);
        if (!ids)
            return 0;
        qu->ids = ids, qu->cap = cap;
    }
    qu->ids[qu->tail++] = t;
    return 1;
}

/* Visits tet u through face f from `from`: assigns it when unassigned (and queues it), else checks it. */
static tpk_result visit(walk *w, queue *qu, int64_t u, const int32_t f[3], int32_t from)
{
    int32_t *slot = w->n3 + u, cur;
    if (w->threads == 1) {
        cur = *slot;
        if (cur == UNSET) {
            int32_t q[4], n3;
            tpk_result rc = decode(w, u, f, from, q, &n3);
            if (rc)
                return rc;
            memcpy(w->dst + 4 * u, q, sizeof q);
            *slot = n3;
            return push(qu, (int32_t)u) ? TPK_OK : TPK_ERR_OUT_OF_MEMORY;
        }
    } else {
        cur = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
        if (cur == UNSET && __atomic_compare_exchange_n(slot, &cur, BUSY, 0, __ATOMIC_ACQUIRE, __ATOMIC_ACQUIRE)) {
            int32_t q[4], n3;
            tpk_result rc = decode(w, u, f, from, q, &n3);
            if (rc)
                return rc; /* stays BUSY: the others see the stop flag */
            memcpy(w->dst + 4 * u, q, sizeof q);
            __atomic_store_n(slot, n3, __ATOMIC_RELEASE);
            return push(qu, (int32_t)u) ? TPK_OK : TPK_ERR_OUT_OF_MEMORY;
        }
        while (cur == BUSY) { /* another thread is writing it */
            if (__atomic_load_n(&w->stop, __ATOMIC_RELAXED))
                return TPK_ERR_MESH;
            cur = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
        }
    }
    return check_visit(w, u, w->dst + 4 * u, cur, f, from);
}

/* Walks from shell faces [s0, s1) through qu; the tets it assigned are qu's ids. */
static tpk_result walk_seeds(walk *w, queue *qu, uint64_t s0, uint64_t s1)
{
    const tpk_mesh_arrays *m = w->mesh;
    for (uint64_t s = s0; s < s1; s++) {
        const tpk_shell_face *sf = &m->shell[s];
        if (sf->t < 0 || sf->t >= w->tet_count || sf->a < 0 || sf->a >= w->vertex_count || sf->b < 0 ||
            sf->b >= w->vertex_count || sf->c < 0 || sf->c >= w->vertex_count)
            return TPK_ERR_CORRUPT;
        int32_t inward[3] = {sf->a, sf->c, sf->b};
        tpk_result rc = visit(w, qu, sf->t, inward, -1);
        if (rc)
            return rc;
        while (qu->head < qu->tail) {
            if (w->threads > 1 && (qu->head & 255) == 0 && __atomic_load_n(&w->stop, __ATOMIC_RELAXED))
                return TPK_ERR_MESH;
            int32_t t = qu->ids[qu->head++];
            int32_t q[4], n[4];
            memcpy(q, w->dst + 4 * (int64_t)t, sizeof q);
            int32_t n3 = __atomic_load_n(w->n3 + t, __ATOMIC_RELAXED); /* this thread wrote it; others may CAS */
            for (int r = 0; r < 4; r++) {
                n[r] = neighbor(w, t, n3, r);
                if (n[r] >= 0) { /* the four neighbors' lines are fetched side by side */
                    __builtin_prefetch(w->n3 + n[r]);
                    __builtin_prefetch(w->dst + 4 * (int64_t)n[r]);
                    __builtin_prefetch(vx_ptr(w, n[r]));
                }
            }
            for (int j = 0; j < 4; j++) {
                int32_t u = n[rank_of(q, j)];
                if (u < 0)
                    continue;
                int32_t f[3] = {q[tpk_tet_faces[j][0]], q[tpk_tet_faces[j][1]], q[tpk_tet_faces[j][2]]};
                rc = visit(w, qu, u, f, t);
                if (rc)
                    return rc;
            }
        }
    }
    return TPK_OK;
}

static tpk_result walk_serial(walk *w)
{
    for (int64_t t = 0; t < w->tet_count; t++)
        w->n3[t] = UNSET;
    queue qu = {malloc(sizeof *qu.ids * (size_t)w->tet_count), 0, 0, w->tet_count};
    if (!qu.ids)
        return TPK_ERR_OUT_OF_MEMORY;
    w->threads = 1;
    tpk_result rc = walk_seeds(w, &qu, 0, w->mesh->shell_face_count);
    if (!rc && qu.tail != w->tet_count)
        rc = TPK_ERR_MESH; /* a tet the shell does not reach */
    free(qu.ids);
    return rc;
}

typedef struct worker {
    walk *w;
    uint64_t s0, s1;
    int64_t assigned;
    tpk_result rc;
    pthread_t thread;
} worker;

static void *worker_run(void *arg)
{
    worker *k = arg;
    queue qu = {0};
    k->rc = walk_seeds(k->w, &qu, k->s0, k->s1);
    if (k->rc)
        __atomic_store_n(&k->w->stop, 1, __ATOMIC_RELAXED);
    k->assigned = qu.tail;
    free(qu.ids);
    return NULL;
}

static tpk_result walk_parallel(walk *w, int threads)
{
    for (int64_t t = 0; t < w->tet_count; t++)
        w->n3[t] = UNSET;
    w->threads = threads;
    w->stop = 0;
    worker k[TPKI_THREADS_MAX];
    uint64_t S = w->mesh->shell_face_count;
    int started = 0;
    for (int i = 0; i < threads; i++)
        k[i] = (worker){w, S * (uint64_t)i / (uint64_t)threads, S * (uint64_t)(i + 1) / (uint64_t)threads, 0,
                        TPK_OK, 0};
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&k[i].thread, NULL, worker_run, &k[i]) != 0)
            break;
        started = i;
    }
    if (started < threads - 1) { /* a thread could not start: its seeds unwalked; fall back */
        __atomic_store_n(&w->stop, 1, __ATOMIC_RELAXED);
        k[0].rc = TPK_ERR_OUT_OF_MEMORY;
    } else {
        worker_run(&k[0]);
    }
    int64_t assigned = k[0].assigned;
    tpk_result rc = k[0].rc;
    for (int i = 1; i <= started; i++) {
        pthread_join(k[i].thread, NULL);
        assigned += k[i].assigned;
        rc = rc ? rc : k[i].rc;
    }
    return rc || assigned != w->tet_count ? TPK_ERR_MESH : TPK_OK;
}

/* Every quadruple into its canonical rotation, on `threads` threads by slices of the tets. */
typedef struct canon_job {
    int32_t *dst;
    int64_t tet_count;
} canon_job;

static void canon_run(void *arg, int share, int shares)
{
    const canon_job *c = arg;
    int64_t t0 = c->tet_count * share / shares, t1 = c->tet_count * (share + 1) / shares;
    for (int64_t t = t0; t < t1; t++)
        canon(c->dst + 4 * t);
}

static void canon_all(int32_t *dst, int64_t tet_count, int threads)
{
    canon_job c = {dst, tet_count};
    tpki_run_threads(threads, canon_run, &c);
}

/* Tet32 stores the vertices and the neighbors opposite each: nbr (when asked) gets them by rank. */
static tpk_result recover_tet32(const tpk_mesh_arrays *mesh, int32_t *dst, int32_t *nbr)
{
    for (uint64_t t = 0; t < mesh->tet_count; t++) {
        const tpk_tet32 *r = &mesh->tet32[t];
        int32_t *q = dst + 4 * t;
        q[0] = r->v[0];
        q[1] = r->v[1];
        q[2] = r->v[2];
        q[3] = r->vx ^ r->v[0] ^ r->v[1] ^ r->v[2];
        for (int k = 0; k < 4; k++)
            if (q[k] < 0 || (uint64_t)q[k] >= mesh->vertex_count)
                return TPK_ERR_CORRUPT;
        if (nbr && (q[0] == q[1] || q[0] == q[2] || q[0] == q[3] || q[1] == q[2] || q[1] == q[3] || q[2] == q[3]))
            return TPK_ERR_CORRUPT; /* the ranks would not tell the faces apart */
        for (int k = 0; nbr && k < 4; k++) {
            if (r->n[k] < -1 || (int64_t)r->n[k] >= (int64_t)mesh->tet_count)
                return TPK_ERR_CORRUPT;
            nbr[4 * t + rank_of(q, k)] = r->n[k];
        }
    }
    return TPK_OK;
}

/* The walk (or Tet32's direct read); nbr: the caller's 4 per tet for the neighbors by rank, or NULL. */
static tpk_result recover(const tpk_mesh_arrays *mesh, int32_t *dst, int32_t *nbr, int threads)
{
    if (!mesh || (mesh->tet_count > 0 && !dst))
        return TPK_ERR_INVALID_ARGUMENT;
    if (mesh->tet_count > INT32_MAX || mesh->vertex_count > INT32_MAX)
        return TPK_ERR_LIMIT;
    if (mesh->layout == TPK_LAYOUT_TET32)
        return mesh->tet32 || !mesh->tet_count ? recover_tet32(mesh, dst, nbr) : TPK_ERR_INVALID_ARGUMENT;
    if ((mesh->layout != TPK_LAYOUT_TET20 && mesh->layout != TPK_LAYOUT_TET16) ||
        (mesh->layout == TPK_LAYOUT_TET20 && !mesh->tet20 && mesh->tet_count) ||
        (mesh->layout == TPK_LAYOUT_TET16 && !mesh->tet16 && mesh->tet_count) ||
        (!mesh->shell && mesh->shell_face_count))
        return TPK_ERR_INVALID_ARGUMENT;
    if (mesh->tet_count == 0)
        return TPK_OK;
    if (threads <= 0)
        threads = tpki_cores();
    threads = threads > TPKI_THREADS_MAX ? TPKI_THREADS_MAX : threads;
    int64_t most = 1 + (int64_t)mesh->tet_count / 64; /* a few dozen tets each at least */
    threads = threads > most ? (int)most : threads;
    if ((uint64_t)threads > mesh->shell_face_count)
        threads = mesh->shell_face_count ? (int)mesh->shell_face_count : 1;
    walk w = {mesh, (int64_t)mesh->tet_count, (int64_t)mesh->vertex_count, dst, NULL, 1, 0};
    w.n3 = malloc(sizeof *w.n3 * mesh->tet_count);
    if (!w.n3)
        return TPK_ERR_OUT_OF_MEMORY;
    tpk_result rc = threads > 1 ? walk_parallel(&w, threads) : TPK_ERR_MESH;
    if (rc)
        rc = walk_serial(&w); /* one thread, or the error the one-thread walk finds */
    if (!rc)
        canon_all(dst, w.tet_count, threads);
    for (int64_t t = 0; !rc && nbr && t < w.tet_count; t++)
        for (int r = 0; r < 4; r++)
            nbr[4 * t + r] = neighbor(&w, t, w.n3[t], r);
    free(w.n3);
    return rc;
}

tpk_result tpk_recover_tets(const tpk_mesh_arrays *mesh, int32_t *dst)
{
    return recover(mesh, dst, NULL, 1);
}

tpk_result tpk_recover_tets_threads(const tpk_mesh_arrays *mesh, int32_t *dst, int threads)
{
    return recover(mesh, dst, NULL, threads);
}

tpk_result tpki_recover_tets_neighbors(const tpk_mesh_arrays *mesh, int32_t *dst, int32_t *nbr)
{
    return nbr ? recover(mesh, dst, nbr, 1) : TPK_ERR_INVALID_ARGUMENT;
}

/* ---- One block of a CULL chunk (spec §17) --------------------------------------------------------- */

#define SPAN_BITS 65536 /* blocks whose intervals span at most this many ids check their vertices by bits */

/* Is v in one of the sorted intervals [first, end) of iv[0 .. count)? */
static int in_intervals(const int32_t *iv, int64_t count, int32_t v)
{
    int64_t lo = 0, hi = count; /* the first interval whose end is above v */
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (iv[2 * mid + 1] <= v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < count && iv[2 * lo] <= v;
}

/* The walk inside block [t0, t1) from its seeds; tets stored at dst[4 * (t - t0)], n3 at n3[t - t0]. */
static tpk_result walk_block(const walk *w, const tpk_cull *cull, uint64_t block, int64_t t0, int64_t t1,
                             int32_t *dst, int32_t *n3, int32_t *queue)
{
    int64_t count = t1 - t0, head = 0, tail = 0;
    for (int64_t i = 0; i < count; i++)
        n3[i] = UNSET;
    for (int32_t s = cull->seed_start[block]; s < cull->seed_start[block + 1]; s++) {
        const int32_t *seed = cull->seeds + (int64_t)TPK_CULL_SEED_WORDS * s;
        int64_t t = seed[0]; /* in [t0, t1), its ids in range and distinct: rule 17 (rules.c check_cull) */
        int32_t q[4] = {seed[1], seed[2], seed[3], seed[4]};
        if (vx_of(w, t) != (q[0] ^ q[1] ^ q[2] ^ q[3]))
            return TPK_ERR_MESH; /* not this tet's vertices */
        if (w->mesh->layout == TPK_LAYOUT_TET20 && w->mesh->tet20[t].n[3] != seed[5])
            return TPK_ERR_MESH;
        for (int r = 0; r < 4; r++) {
            int32_t u = neighbor(w, t, seed[5], r);
            if (u < -1 || u >= w->tet_count)
                return TPK_ERR_CORRUPT;
        }
        if (n3[t - t0] != UNSET) { /* reached from a seed before: it must agree */
            int32_t a[4], b[4];
            memcpy(a, q, sizeof a), memcpy(b, dst + 4 * (t - t0), sizeof b);
            canon(a), canon(b);
            if (memcmp(a, b, sizeof a) || n3[t - t0] != seed[5])
                return TPK_ERR_MESH;
            continue;
        }
        memcpy(dst + 4 * (t - t0), q, sizeof q);
        n3[t - t0] = seed[5];
        queue[tail++] = (int32_t)t;
        while (head < tail) {
            int32_t c = queue[head++], cq[4];
            memcpy(cq, dst + 4 * ((int64_t)c - t0), sizeof cq);
            int32_t cn3 = n3[c - t0];
            for (int j = 0; j < 4; j++) {
                int32_t u = neighbor(w, c, cn3, rank_of(cq, j));
                if (u < t0 || u >= t1)
                    continue; /* the shell, or another block */
                int32_t f[3] = {cq[tpk_tet_faces[j][0]], cq[tpk_tet_faces[j][1]], cq[tpk_tet_faces[j][2]]};
                tpk_result rc;
                if (n3[u - t0] == UNSET) {
                    rc = decode(w, u, f, c, dst + 4 * ((int64_t)u - t0), &n3[u - t0]);
                    if (rc == TPK_OK)
                        queue[tail++] = u;
                } else {
                    rc = check_visit(w, u, dst + 4 * ((int64_t)u - t0), n3[u - t0], f, c);
                }
                if (rc)
                    return rc;
            }
        }
    }
    return tail == count ? TPK_OK : TPK_ERR_MESH; /* a tet the seeds do not reach inside the block */
}

tpk_result tpk_recover_block(const tpk_mesh_arrays *mesh, const tpk_cull *cull, uint64_t block, int32_t *dst)
{
    if (!mesh || !cull || !dst || block >= cull->block_count || cull->block_tets == 0)
        return TPK_ERR_INVALID_ARGUMENT;
    if (mesh->tet_count > INT32_MAX || mesh->vertex_count > INT32_MAX)
        return TPK_ERR_LIMIT;
    const int64_t B = cull->block_tets, T = (int64_t)mesh->tet_count;
    if (cull->block_count != (uint64_t)((T + B - 1) / B))
        return TPK_ERR_INVALID_ARGUMENT; /* another file's blocks */
    const int64_t t0 = (int64_t)block * B, t1 = t0 + B < T ? t0 + B : T;
    tpk_result rc = TPK_OK;
    if (mesh->layout == TPK_LAYOUT_TET32) {
        if (!mesh->tet32)
            return TPK_ERR_INVALID_ARGUMENT;
        tpk_mesh_arrays part = *mesh; /* recover_tet32 reads tets [0, tet_count) of the view */
        part.tet32 = mesh->tet32 + t0;
        part.tet_count = (uint64_t)(t1 - t0);
        rc = recover_tet32(&part, dst, NULL);
    } else {
        if ((mesh->layout != TPK_LAYOUT_TET20 && mesh->layout != TPK_LAYOUT_TET16) ||
            (mesh->layout == TPK_LAYOUT_TET20 && !mesh->tet20) || (mesh->layout == TPK_LAYOUT_TET16 && !mesh->tet16))
            return TPK_ERR_INVALID_ARGUMENT;
        walk w = {mesh, T, (int64_t)mesh->vertex_count, NULL, NULL, 1, 0};
        int32_t *scratch = malloc(sizeof *scratch * 2 * (size_t)(t1 - t0));
        if (!scratch)
            return TPK_ERR_OUT_OF_MEMORY;
        rc = walk_block(&w, cull, block, t0, t1, dst, scratch, scratch + (t1 - t0));
        free(scratch);
        for (int64_t i = 0; rc == TPK_OK && i < t1 - t0; i++)
            canon(dst + 4 * i);
    }
    const int32_t *iv = cull->intervals + 2 * (int64_t)cull->interval_start[block];
    const int64_t iv_count = cull->interval_start[block + 1] - cull->interval_start[block];
    const int64_t base = iv_count ? iv[0] : 0, span = iv_count ? iv[2 * iv_count - 1] - base : 0;
    if (rc == TPK_OK && span <= SPAN_BITS) {
        /* the intervals' ids as bits, each vertex one test (a binary search a vertex cost a tenth of a
         * culled render of grid 120) */
        uint64_t bits[SPAN_BITS / 64 + 1];
        memset(bits, 0, sizeof *bits * (size_t)(span / 64 + 1)); /* the span's words alone */
        for (int64_t k = 0; k < iv_count; k++)
            for (int64_t v = iv[2 * k] - base; v < iv[2 * k + 1] - base; v++)
                bits[v >> 6] |= 1ull << (v & 63);
        for (int64_t i = 0; rc == TPK_OK && i < 4 * (t1 - t0); i++) {
            int64_t v = (int64_t)dst[i] - base;
            if (v < 0 || v >= span || !((bits[v >> 6] >> (v & 63)) & 1))
                rc = TPK_ERR_MESH; /* the block's scalars would not bound this vertex's */
        }
        return rc;
    }
    for (int64_t i = 0; rc == TPK_OK && i < 4 * (t1 - t0); i++)
        if (!in_intervals(iv, iv_count, dst[i]))
            rc = TPK_ERR_MESH;
    return rc;
}
