/* tpk_recover_tets: positively oriented vertex quadruples from any tet layout (spec/tetpack-format.md §6).
 * Tet32 stores three vertices, so the fourth is vx ^ v0 ^ v1 ^ v2. Tet20 and Tet16 store only vx and
 * neighbors, so the order is found by a breadth-first walk from the shell:
 *   - a shell face (a,b,c) of t faces out of t, so t = (a,c,b,x) is positive, x = vx ^ a ^ b ^ c;
 *   - for a positive tet (p0..p3) the face opposite p_j in outward order is F_j = tpk_tet_faces[j]
 *     (format/tetpack_format.h); seen from the neighbor u across it, F_j faces inward, so
 *     u = (F_j, y) is positive, y = vx[u] ^ F_j[0] ^ F_j[1] ^ F_j[2].
 * Tet16 neighbors are decoded from the tet we arrived from: it is n[rank of the apex y].
 * Untrusted input: every decoded id is range-checked, every tet is assigned once and each later visit
 * must agree with that assignment; no recursion. Deterministic (shell order, then FIFO order). */
#include <stdlib.h>
#include <string.h>

#include "internal_mesh.h"

typedef struct walk {
    const tpk_mesh_arrays *mesh;
    int64_t tet_count, vertex_count;
    int32_t *dst;     /* 4 per tet; dst[4t] = -1 while unassigned */
    int32_t *nbr;     /* 4 per assigned tet: its neighbors by rank, decoded and checked once */
    int32_t *queue;
    int64_t head, tail;
} walk;

static int32_t vx_of(const walk *w, int64_t t)
{
    switch (w->mesh->layout) {
    case TPK_LAYOUT_TET20: return w->mesh->tet20[t].vx;
    case TPK_LAYOUT_TET16: return w->mesh->tet16[t].vx;
    default: return w->mesh->tet32[t].vx;
    }
}

static int rank_of(const int32_t *q, int k)
{
    return (q[0] < q[k]) + (q[1] < q[k]) + (q[2] < q[k]) + (q[3] < q[k]);
}

/* Neighbors by rank (n[r]) of tet t, just assigned and entered from `from` (Tet16 decodes them from
 * it); each checked in [-1, tet_count). */
static tpk_result neighbors_of(const walk *w, int64_t t, int32_t from, int32_t n[4])
{
    if (w->mesh->layout == TPK_LAYOUT_TET20) {
        memcpy(n, w->mesh->tet20[t].n, 4 * sizeof *n);
    } else {
        const int32_t *q = w->dst + 4 * t;
        const int32_t *nx = w->mesh->tet16[t].nx;
        int entry_rank = rank_of(q, 3); /* the apex we arrived through is stored last */
        n[3] = entry_rank == 3 ? from : nx[entry_rank] ^ from;
        for (int r = 0; r < 3; r++)
            n[r] = nx[r] ^ n[3];
    }
    for (int r = 0; r < 4; r++)
        if (n[r] < -1 || n[r] >= w->tet_count)
            return TPK_ERR_CORRUPT;
    return TPK_OK;
}

/* Assigns (f0, f1, f2, y) to unassigned tet u, entered from `from`. */
static tpk_result assign(walk *w, int64_t u, const int32_t f[3], int32_t from)
{
    int32_t y = vx_of(w, u) ^ f[0] ^ f[1] ^ f[2];
    if (y < 0 || y >= w->vertex_count)
        return TPK_ERR_CORRUPT;
    if (y == f[0] || y == f[1] || y == f[2] || f[0] == f[1] || f[0] == f[2] || f[1] == f[2])
        return TPK_ERR_CORRUPT;
    int32_t *q = w->dst + 4 * u;
    q[0] = f[0];
    q[1] = f[1];
    q[2] = f[2];
    q[3] = y;
    int32_t *n = w->nbr + 4 * u;
    tpk_result rc = neighbors_of(w, u, from, n);
    if (rc)
        return rc;
    if (n[rank_of(q, 3)] != from) /* Tet20: the stored neighbor must be where we came from */
        return TPK_ERR_MESH;
    w->queue[w->tail++] = (int32_t)u;
    return TPK_OK;
}

/* A later visit of assigned tet u through face f from `from`: f must be a face of u whose neighbor
 * is `from`. */
static tpk_result check_visit(const walk *w, int64_t u, const int32_t f[3], int32_t from)
{
    const int32_t *q = w->dst + 4 * u;
    int apex = -1, matched = 0;
    for (int k = 0; k < 4; k++) {
        int in_face = q[k] == f[0] || q[k] == f[1] || q[k] == f[2];
        matched += in_face;
        if (!in_face)
            apex = k;
    }
    if (matched != 3 || apex < 0)
        return TPK_ERR_MESH;
    return w->nbr[4 * u + rank_of(q, apex)] == from ? TPK_OK : TPK_ERR_MESH;
}

static tpk_result visit(walk *w, int64_t u, const int32_t f[3], int32_t from)
{
    if (w->dst[4 * u] < 0)
        return assign(w, u, f, from);
    return check_visit(w, u, f, from);
}

static tpk_result drain(walk *w)
{
    while (w->head < w->tail) {
        int32_t t = w->queue[w->head++];
        int32_t q[4], n[4];
        memcpy(q, w->dst + 4 * (int64_t)t, sizeof q);
        memcpy(n, w->nbr + 4 * (int64_t)t, sizeof n);
        tpk_result rc = TPK_OK;
        for (int j = 0; j < 4 && !rc; j++) {
            int32_t u = n[rank_of(q, j)];
            if (u < 0)
                continue;
            int32_t f[3] = {q[tpk_tet_faces[j][0]], q[tpk_tet_faces[j][1]], q[tpk_tet_faces[j][2]]};
            rc = visit(w, u, f, t);
        }
        if (rc)
            return rc;
    }
    return TPK_OK;
}

static tpk_result walk_from_shell(walk *w)
{
    const tpk_mesh_arrays *m = w->mesh;
    for (uint64_t s = 0; s < m->shell_face_count; s++) {
        const tpk_shell_face *sf = &m->shell[s];
        if (sf->t < 0 || sf->t >= w->tet_count || sf->a < 0 || sf->a >= w->vertex_count || sf->b < 0 ||
            sf->b >= w->vertex_count || sf->c < 0 || sf->c >= w->vertex_count)
            return TPK_ERR_CORRUPT;
        int32_t inward[3] = {sf->a, sf->c, sf->b};
        tpk_result rc = visit(w, sf->t, inward, -1);
        if (!rc)
            rc = drain(w);
        if (rc)
            return rc;
    }
    return w->tail == w->tet_count ? TPK_OK : TPK_ERR_MESH; /* a tet the shell does not reach */
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
static tpk_result recover(const tpk_mesh_arrays *mesh, int32_t *dst, int32_t *nbr)
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
    walk w = {mesh, (int64_t)mesh->tet_count, (int64_t)mesh->vertex_count, dst, NULL, NULL, 0, 0};
    w.nbr = nbr ? nbr : malloc(sizeof *w.nbr * 4 * mesh->tet_count);
    w.queue = malloc(sizeof *w.queue * mesh->tet_count);
    tpk_result rc = TPK_ERR_OUT_OF_MEMORY;
    if (w.nbr && w.queue) {
        for (uint64_t i = 0; i < 4 * mesh->tet_count; i++)
            dst[i] = -1;
        rc = walk_from_shell(&w);
    }
    if (!nbr)
        free(w.nbr);
    free(w.queue);
    return rc;
}

tpk_result tpk_recover_tets(const tpk_mesh_arrays *mesh, int32_t *dst)
{
    return recover(mesh, dst, NULL);
}

tpk_result tpki_recover_tets_neighbors(const tpk_mesh_arrays *mesh, int32_t *dst, int32_t *nbr)
{
    return nbr ? recover(mesh, dst, nbr) : TPK_ERR_INVALID_ARGUMENT;
}
