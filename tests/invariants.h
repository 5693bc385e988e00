/* Invariant checks for tet meshes after the pipeline (header-only so any test can include it):
 * orientation, neighbor symmetry, face multiplicity, outward shell, and the Tet32/Tet20/Tet16 layouts
 * and their recovery. Each returns 0, or -1 with a message naming the tet/face. Independent of the
 * code under test where it matters: faces are matched here by a plain qsort. */
#ifndef TPK_TEST_INVARIANTS_H
#define TPK_TEST_INVARIANTS_H

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/mesh.h"
#include "convert/pipeline.h"
#include "tetpack.h"

static inline int tpk_inv_fail(char *msg, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (msg && cap)
        vsnprintf(msg, cap, fmt, ap);
    va_end(ap);
    return -1;
}

static inline const double *tpk_inv_point(const tpk_tetmesh *m, int32_t v)
{
    return m->points + 3 * (int64_t)v;
}

static inline int tpk_inv_orient(const tpk_tetmesh *m, const int32_t v[4])
{
    return tpk_orient3d_exact(tpk_inv_point(m, v[0]), tpk_inv_point(m, v[1]), tpk_inv_point(m, v[2]),
                              tpk_inv_point(m, v[3]));
}

typedef struct tpk_inv_face {
    int32_t v[3]; /* sorted */
    int32_t tet, k;
} tpk_inv_face;

static inline int tpk_inv_face_cmp(const void *pa, const void *pb)
{
    const tpk_inv_face *a = pa, *b = pb;
    for (int i = 0; i < 3; i++)
        if (a->v[i] != b->v[i])
            return a->v[i] < b->v[i] ? -1 : 1;
    if (a->tet != b->tet)
        return a->tet < b->tet ? -1 : 1;
    return a->k - b->k;
}

/* Flags for tpk_check_invariants_flags. */
#define TPK_INV_ALLOW_SAME_SIDE 0x1 /* skip "neighbors' apexes on opposite sides" (meshes that overlap) */

/* Per tet: ids in range and distinct, positive (exact). Neighbors: symmetric across the same 3
 * vertices, apexes on opposite sides. Every face in at most 2 tets, and a face in 2 tets is matched
 * (qsort of all faces). The shell: as many faces as -1 entries, each outward (exact). */
static inline int tpk_check_invariants_flags(const tpk_tetmesh *m, const int32_t *nb, int flags, char *msg,
                                             size_t cap)
{
    int64_t T = m->tet_count, V = m->vertex_count;
    for (int64_t t = 0; t < T; t++) {
        const int32_t *v = m->tets + 4 * t;
        for (int k = 0; k < 4; k++) {
            if (v[k] < 0 || v[k] >= V)
                return tpk_inv_fail(msg, cap, "tet %lld: vertex %d out of range", (long long)t, v[k]);
            for (int j = 0; j < k; j++)
                if (v[j] == v[k])
                    return tpk_inv_fail(msg, cap, "tet %lld repeats vertex %d", (long long)t, v[k]);
        }
        if (tpk_inv_orient(m, v) <= 0)
            return tpk_inv_fail(msg, cap, "tet %lld (%d %d %d %d) is not positive", (long long)t, v[0],
                                v[1], v[2], v[3]);
        for (int k = 0; k < 4; k++) {
            int32_t u = nb[4 * t + k];
            if (u == -1)
                continue;
            if (u < 0 || u >= T || u == t)
                return tpk_inv_fail(msg, cap, "tet %lld: neighbor %d invalid", (long long)t, u);
            const int32_t *w = m->tets + 4 * (int64_t)u;
            int32_t f[3] = {v[tpk_tet_faces[k][0]], v[tpk_tet_faces[k][1]], v[tpk_tet_faces[k][2]]};
            int apex = -1, shared = 0;
            for (int j = 0; j < 4; j++) {
                int in = w[j] == f[0] || w[j] == f[1] || w[j] == f[2];
                shared += in;
                if (!in)
                    apex = j;
            }
            if (shared != 3)
                return tpk_inv_fail(msg, cap, "tets %lld and %d are neighbors but share %d vertices",
                                    (long long)t, u, shared);
            if (nb[4 * (int64_t)u + apex] != t)
                return tpk_inv_fail(msg, cap, "tet %lld -> %d across face %d, but %d -> %d", (long long)t,
                                    u, k, u, nb[4 * (int64_t)u + apex]);
            int32_t q[4] = {f[0], f[1], f[2], w[apex]};
            if (!(flags & TPK_INV_ALLOW_SAME_SIDE) && tpk_inv_orient(m, q) <= 0)
                return tpk_inv_fail(msg, cap, "tets %lld and %d lie on the same side of their face",
                                    (long long)t, u);
        }
    }
    tpk_inv_face *faces = malloc(sizeof *faces * (size_t)(4 * T + 1));
    if (!faces)
        return tpk_inv_fail(msg, cap, "out of memory");
    for (int64_t t = 0; t < T; t++)
        for (int k = 0; k < 4; k++) {
            tpk_inv_face *f = &faces[4 * t + k];
            int n = 0;
            for (int j = 0; j < 4; j++)
                if (j != k)
                    f->v[n++] = m->tets[4 * t + j];
            for (int a = 0; a < 3; a++)
                for (int b = a + 1; b < 3; b++)
                    if (f->v[b] < f->v[a]) {
                        int32_t s = f->v[a];
                        f->v[a] = f->v[b];
                        f->v[b] = s;
                    }
            f->tet = (int32_t)t;
            f->k = k;
        }
    qsort(faces, (size_t)(4 * T), sizeof *faces, tpk_inv_face_cmp);
    int rc = 0;
    for (int64_t i = 0; i < 4 * T && !rc;) {
        int64_t run = 1;
        while (i + run < 4 * T && !memcmp(faces[i].v, faces[i + run].v, sizeof faces[i].v))
            run++;
        if (run > 2)
            rc = tpk_inv_fail(msg, cap, "face (%d %d %d) in %lld tets", faces[i].v[0], faces[i].v[1],
                              faces[i].v[2], (long long)run);
        else if (run == 2 && (nb[4 * (int64_t)faces[i].tet + faces[i].k] != faces[i + 1].tet))
            rc = tpk_inv_fail(msg, cap, "face (%d %d %d) of tets %d and %d not matched", faces[i].v[0],
                              faces[i].v[1], faces[i].v[2], faces[i].tet, faces[i + 1].tet);
        else if (run == 1 && nb[4 * (int64_t)faces[i].tet + faces[i].k] != -1)
            rc = tpk_inv_fail(msg, cap, "face (%d %d %d) of tet %d alone but has a neighbor",
                              faces[i].v[0], faces[i].v[1], faces[i].v[2], faces[i].tet);
        i += run;
    }
    free(faces);
    if (rc)
        return rc;

    int64_t S = tpk_count_shell_faces(nb, T), boundary = 0;
    for (int64_t i = 0; i < 4 * T; i++)
        boundary += nb[i] == -1;
    if (S != boundary)
        return tpk_inv_fail(msg, cap, "shell count %lld, boundary faces %lld", (long long)S,
                            (long long)boundary);
    tpk_shell_face *shell = malloc(sizeof *shell * (size_t)(S + 1));
    if (!shell)
        return tpk_inv_fail(msg, cap, "out of memory");
    tpk_build_shell(m->tets, nb, T, shell);
    int64_t s = 0;
    for (int64_t t = 0; t < T && !rc; t++)
        for (int k = 0; k < 4 && !rc; k++) {
            if (nb[4 * t + k] != -1)
                continue;
            const tpk_shell_face *f = &shell[s++];
            const int32_t *v = m->tets + 4 * t;
            int32_t fv[3] = {f->a, f->b, f->c};
            int in = 0;
            for (int j = 0; j < 3; j++)
                in += (fv[j] != v[k]) && (fv[j] == v[0] || fv[j] == v[1] || fv[j] == v[2] || fv[j] == v[3]);
            int32_t q[4] = {f->a, f->b, f->c, v[k]};
            if (f->t != t || in != 3 || f->a == f->b || f->b == f->c || f->a == f->c)
                rc = tpk_inv_fail(msg, cap, "shell face %lld is not face %d of tet %lld", (long long)(s - 1),
                                  k, (long long)t);
            else if (tpk_inv_orient(m, q) >= 0) /* the opposite vertex must be behind the face */
                rc = tpk_inv_fail(msg, cap, "shell face %lld (%d %d %d) of tet %lld is not outward",
                                  (long long)(s - 1), f->a, f->b, f->c, (long long)t);
        }
    free(shell);
    return rc;
}

static inline int tpk_check_invariants(const tpk_tetmesh *m, const int32_t *nb, char *msg, size_t cap)
{
    return tpk_check_invariants_flags(m, nb, 0, msg, cap);
}

/* Neighbor pairs whose apexes lie on the same side of (or on) their shared face, i.e. overlapping
 * tets; each pair counted once. *first gets the lower tet of the first pair (or -1). */
static inline int64_t tpk_count_same_side_pairs(const tpk_tetmesh *m, const int32_t *nb, int64_t *first)
{
    int64_t count = 0;
    *first = -1;
    for (int64_t t = 0; t < m->tet_count; t++)
        for (int k = 0; k < 4; k++) {
            int32_t u = nb[4 * t + k];
            if (u <= t)
                continue;
            const int32_t *v = m->tets + 4 * t, *w = m->tets + 4 * (int64_t)u;
            int32_t apex = -1;
            for (int j = 0; j < 4; j++)
                if (w[j] != v[0] && w[j] != v[1] && w[j] != v[2] && w[j] != v[3])
                    apex = w[j];
            int32_t q[4] = {v[tpk_tet_faces[k][0]], v[tpk_tet_faces[k][1]], v[tpk_tet_faces[k][2]], apex};
            if (apex < 0 || tpk_inv_orient(m, q) <= 0) {
                if (*first < 0)
                    *first = t;
                count++;
            }
        }
    return count;
}

/* Rank of v[k] among the 4 (distinct) ids. */
static inline int tpk_inv_rank(const int32_t *v, int k)
{
    return (v[0] < v[k]) + (v[1] < v[k]) + (v[2] < v[k]) + (v[3] < v[k]);
}

static inline int tpk_inv_same_set(const int32_t *a, const int32_t *b)
{
    for (int i = 0; i < 4; i++)
        if (a[i] != b[0] && a[i] != b[1] && a[i] != b[2] && a[i] != b[3])
            return 0;
    return 1;
}

/* Builds Tet32/20/16 and the shell, checks each against tets/neighbors (Tet16 decoded from every
 * possible entry neighbor), and checks tpk_recover_tets on all three layouts: same vertex sets,
 * positive (exact). */
static inline int tpk_check_layouts(const tpk_tetmesh *m, const int32_t *nb, char *msg, size_t cap)
{
    int64_t T = m->tet_count, S = tpk_count_shell_faces(nb, T);
    tpk_tet32 *t32 = malloc(sizeof *t32 * (size_t)(T + 1));
    tpk_tet20 *t20 = malloc(sizeof *t20 * (size_t)(T + 1));
    tpk_tet16 *t16 = malloc(sizeof *t16 * (size_t)(T + 1));
    tpk_shell_face *shell = malloc(sizeof *shell * (size_t)(S + 1));
    int32_t *rec = malloc(sizeof *rec * 4 * (size_t)(T + 1));
    int rc = 0;
    if (!t32 || !t20 || !t16 || !shell || !rec) {
        rc = tpk_inv_fail(msg, cap, "out of memory");
        goto done;
    }
    tpk_build_tet32(m->tets, nb, T, t32);
    tpk_build_tet20(m->tets, nb, T, t20);
    tpk_build_tet16(m->tets, nb, T, t16);
    tpk_build_shell(m->tets, nb, T, shell);
    for (int64_t t = 0; t < T && !rc; t++) {
        const int32_t *v = m->tets + 4 * t, *n = nb + 4 * t;
        int32_t vx = v[0] ^ v[1] ^ v[2] ^ v[3];
        if (t32[t].v[0] != v[0] || t32[t].v[1] != v[1] || t32[t].v[2] != v[2] || t32[t].vx != vx ||
            (t32[t].vx ^ t32[t].v[0] ^ t32[t].v[1] ^ t32[t].v[2]) != v[3] || memcmp(t32[t].n, n, 16))
            rc = tpk_inv_fail(msg, cap, "Tet32 record %lld wrong", (long long)t);
        if (!rc && t20[t].vx != vx)
            rc = tpk_inv_fail(msg, cap, "Tet20 vx of %lld wrong", (long long)t);
        for (int k = 0; k < 4 && !rc; k++)
            if (t20[t].n[tpk_inv_rank(v, k)] != n[k])
                rc = tpk_inv_fail(msg, cap, "Tet20 %lld: n[rank %d] is %d, the neighbor opposite %d is %d",
                                  (long long)t, tpk_inv_rank(v, k), t20[t].n[tpk_inv_rank(v, k)], v[k], n[k]);
        /* Every entry: arriving from neighbor of rank r_e (or the shell where it is -1). */
        for (int re = 0; re < 4 && !rc; re++) {
            int32_t from = t20[t].n[re];
            int32_t n3 = re == 3 ? from : t16[t].nx[re] ^ from;
            int32_t dec[4] = {t16[t].nx[0] ^ n3, t16[t].nx[1] ^ n3, t16[t].nx[2] ^ n3, n3};
            if (t16[t].vx != vx || memcmp(dec, t20[t].n, 16))
                rc = tpk_inv_fail(msg, cap, "Tet16 %lld decoded from entry rank %d differs from Tet20",
                                  (long long)t, re);
        }
    }
    for (int layout = 0; layout < 3 && !rc; layout++) {
        tpk_mesh_arrays arrays;
        memset(&arrays, 0, sizeof arrays);
        arrays.vertex_count = (uint64_t)m->vertex_count;
        arrays.tet_count = (uint64_t)T;
        arrays.shell_face_count = (uint64_t)S;
        arrays.shell = shell;
        arrays.layout = layout == 0 ? TPK_LAYOUT_TET32 : layout == 1 ? TPK_LAYOUT_TET20 : TPK_LAYOUT_TET16;
        arrays.tet32 = t32;
        arrays.tet20 = t20;
        arrays.tet16 = t16;
        tpk_result r = tpk_recover_tets(&arrays, rec);
        if (r != TPK_OK) {
            rc = tpk_inv_fail(msg, cap, "tpk_recover_tets(Tet%d) failed: %s", (int)arrays.layout,
                              tpk_result_string(r));
            break;
        }
        for (int64_t t = 0; t < T && !rc; t++) {
            if (!tpk_inv_same_set(rec + 4 * t, m->tets + 4 * t) || !tpk_inv_same_set(m->tets + 4 * t, rec + 4 * t))
                rc = tpk_inv_fail(msg, cap, "Tet%d recovery: tet %lld has other vertices", (int)arrays.layout,
                                  (long long)t);
            else if (tpk_inv_orient(m, rec + 4 * t) <= 0)
                rc = tpk_inv_fail(msg, cap, "Tet%d recovery: tet %lld not positive", (int)arrays.layout,
                                  (long long)t);
        }
    }
done:
    free(t32);
    free(t20);
    free(t16);
    free(shell);
    free(rec);
    return rc;
}

#endif
