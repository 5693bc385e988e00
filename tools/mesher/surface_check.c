/* Is a surface closed, manifold and consistently oriented? Every edge must lie in exactly two faces
 * that run along it in opposite directions; otherwise TetGen cannot tell inside from outside. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesher.h"

typedef struct edge_use {
    int32_t lo, hi;  /* vertex ids, lo < hi */
    int32_t face;
    int8_t forward;  /* the face runs lo -> hi */
} edge_use;

static int edge_cmp(const void *pa, const void *pb)
{
    const edge_use *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->face < b->face ? -1 : a->face > b->face;
}

static const char *point_text(const tpk_mesh *m, int32_t v, char *buf, size_t cap)
{
    const double *p = m->points + 3 * (int64_t)v;
    snprintf(buf, cap, "(%.17g, %.17g, %.17g)", p[0], p[1], p[2]);
    return buf;
}

/* Faces: at least 3 corners, ids in range, no corner twice. */
static int check_faces(const char *name, const tpk_mesh *m, tpk_diag *diag)
{
    for (int64_t f = 0; f < m->cell_count; f++) {
        int64_t b = m->cell_offsets[f], n = m->cell_offsets[f + 1] - b;
        if (n < 3)
            return tpk_diag_fail(diag, "%s: face %lld has %lld corners; a face needs at least 3", name, (long long)f, (long long)n);
        for (int64_t i = 0; i < n; i++) {
            int32_t v = m->cell_conn[b + i];
            if (v < 0 || v >= m->point_count)
                return tpk_diag_fail(diag, "%s: face %lld names vertex %d, out of range", name, (long long)f, v);
            for (int64_t j = 0; j < i; j++)
                if (m->cell_conn[b + j] == v) {
                    char at[128];
                    return tpk_diag_fail(diag, "%s: face %lld uses vertex %d %s twice (a degenerate face)", name,
                                         (long long)f, v, point_text(m, v, at, sizeof at));
                }
        }
    }
    return 0;
}

/* What is wrong with the uses of one edge (count n, sorted by face), or NULL. */
static const char *edge_problem(const edge_use *u, int64_t n)
{
    if (n == 1)
        return "lies in only one face: the surface is open there";
    if (n > 2)
        return "lies in more than two faces: the surface is not manifold there";
    if (u[0].forward == u[1].forward)
        return "runs the same way in both of its faces: the faces are not consistently oriented";
    return NULL;
}

static int report_edge(const char *name, const tpk_mesh *m, const edge_use *u, int64_t n, const char *why,
                       tpk_diag *diag)
{
    char a[128], b[128], faces[64];
    if (n == 1)
        snprintf(faces, sizeof faces, "face %d", u[0].face);
    else
        snprintf(faces, sizeof faces, "faces %d, %d%s", u[0].face, u[1].face, n > 2 ? ", ..." : "");
    return tpk_diag_fail(diag, "%s: edge (%d, %d) from %s to %s %s (%s); a closed surface has every edge in "
                         "exactly two faces, running opposite ways", name, u[0].lo, u[0].hi,
                         point_text(m, u[0].lo, a, sizeof a), point_text(m, u[0].hi, b, sizeof b), why, faces);
}

static int check_edges(const char *name, const tpk_mesh *m, tpk_diag *diag)
{
    int64_t count = m->cell_offsets[m->cell_count];
    edge_use *uses = malloc(sizeof *uses * (size_t)(count ? count : 1));
    if (!uses)
        return tpk_diag_fail(diag, "%s: out of memory for %lld edges", name, (long long)count);
    for (int64_t f = 0, k = 0; f < m->cell_count; f++) {
        int64_t b = m->cell_offsets[f], n = m->cell_offsets[f + 1] - b;
        for (int64_t i = 0; i < n; i++, k++) {
            int32_t from = m->cell_conn[b + i], to = m->cell_conn[b + (i + 1) % n];
            uses[k] = (edge_use){from < to ? from : to, from < to ? to : from, (int32_t)f, (int8_t)(from < to)};
        }
    }
    qsort(uses, (size_t)count, sizeof *uses, edge_cmp);
    /* Report the bad edge whose first face comes first in the file. */
    int64_t bad = -1, bad_n = 0;
    const char *bad_why = NULL;
    for (int64_t i = 0, j; i < count; i = j) {
        for (j = i + 1; j < count && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi;)
            j++;
        const char *why = edge_problem(uses + i, j - i);
        if (why && (bad < 0 || uses[i].face < uses[bad].face))
            bad = i, bad_n = j - i, bad_why = why;
    }
    int rc = bad >= 0 ? report_edge(name, m, uses + bad, bad_n, bad_why, diag) : 0;
    free(uses);
    return rc;
}

int tpk_surface_check_closed(const char *name, const tpk_mesh *surface, tpk_diag *diag)
{
    if (surface->cell_count < 4)
        return tpk_diag_fail(diag, "%s: %lld faces cannot close a volume (at least 4 are needed)", name,
                             (long long)surface->cell_count);
    if (check_faces(name, surface, diag) || check_edges(name, surface, diag))
        return -1;
    return 0;
}
