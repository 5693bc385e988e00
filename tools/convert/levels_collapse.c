/* Levels of detail (levels_internal.h): one half-edge collapse: the rules for the tets it changes
 * (positive, exactly, and of fair shape), the choice of a target among u's neighbours, and the collapse. */
#include <math.h>

#include "base/predicates.h"
#include "levels_internal.h"
#include "tetpack_format.h"

/* A tet of u's star seen from its face opposite u: moving u to v makes the tet (face, v), whose 6V is
 * normal . (v - a) (the face's inward normal, scaled) and whose longest edge is the face's or one to v. */
typedef struct star_face {
    const int32_t *tet; /* its 4 ids (u among them) */
    int index;          /* in the star */
    const double *a, *b, *c;
    double normal[3], face_l2;
    double six_v, l2;   /* of the moved tet that last passed moved_tet_ok: its shape is 6V / L^3 */
} star_face;

static void star_face_of(const simplifier *s, const int32_t *t, int32_t u, star_face *f)
{
    int k = (t[1] == u) + 2 * (t[2] == u) + 3 * (t[3] == u); /* u is one corner: no branch to mispredict */
    f->tet = t;
    f->a = point(s, t[tpk_tet_faces[k][0]]);
    f->b = point(s, t[tpk_tet_faces[k][1]]);
    f->c = point(s, t[tpk_tet_faces[k][2]]);
    double ab[3], ac[3], bc[3];
    double lab = edge(f->a, f->b, ab), lac = edge(f->a, f->c, ac), lbc = edge(f->b, f->c, bc);
    /* tpk_tet_faces turns each face outward, so 6V = -(ab x ac) . (corner - a) */
    f->normal[0] = ac[1] * ab[2] - ac[2] * ab[1];
    f->normal[1] = ac[2] * ab[0] - ac[0] * ab[2];
    f->normal[2] = ac[0] * ab[1] - ac[1] * ab[0];
    double l2 = lab > lac ? lab : lac;
    f->face_l2 = lbc > l2 ? lbc : l2;
}

/* Whether the tet of face f with u moved to v (at q) is positive, exactly, and of shape 6V/L^3 >= floor
 * (floor >= 0). The shape in double first, as 6V^2 >= floor^2 L^6 without a root: it rejects most. */
static int moved_tet_ok(const simplifier *s, star_face *f, int32_t u, int32_t v, const double *q, double floor)
{
    double da[3], db[3], dc[3], l2 = f->face_l2;
    double la = edge(f->a, q, da), six_v = f->normal[0] * da[0] + f->normal[1] * da[1] + f->normal[2] * da[2];
    if (!(six_v > 0))
        return 0;
    double lb = edge(f->b, q, db), lc = edge(f->c, q, dc);
    l2 = la > l2 ? la : l2;
    l2 = lb > l2 ? lb : l2;
    l2 = lc > l2 ? lc : l2;
    if (six_v * six_v < floor * floor * l2 * l2 * l2)
        return 0;
    f->six_v = six_v;
    f->l2 = l2;
    /* Then 6V >= floor L^3, while the rounding of six_v (the expansion tpk_orient3d_filter bounds: rows
     * v - a, c - a, b - a) is at most (7 + 56 eps) eps times a permanent <= 6 L^3, 5e-15 L^3: past a floor
     * of 1e-12 the sign is certain, and the exact test would only say so again. */
    if (floor >= 1e-12 && l2 > 1e-180 && l2 < 1e180)
        return 1;
    const double *p[4];
    for (int k = 0; k < 4; k++)
        p[k] = point(s, f->tet[k] == u ? v : f->tet[k]);
    int sign = tpk_orient3d_filter(p[0], p[1], p[2], p[3]);
    return (sign ? sign : tpk_orient3d_exact(p[0], p[1], p[2], p[3])) > 0;
}

/* The best valid target of vertex u among its m neighbours nb (with their costs, reordered
 * here), or -1: by ascending cost (then id), the first whose moved tets are all positive and of fair
 * shape, and, for a shell vertex (ring_count >= 0, its shell ring), that keeps the domain. With a target,
 * shape[i] is the shape of star[i] moved onto it (0 for the tets that vanish). */
static int32_t choose_target(const simplifier *s, int32_t u, const int32_t *star, int n, int32_t *nb, double *cost,
                             int m, const int32_t ring[][3], int ring_count, float *shape)
{
    star_face faces[STAR_MAX];
    double worst = INFINITY;
    for (int i = 0; i < n; i++) {
        double q = s->tet_quality[star[i]];
        worst = q < worst ? q : worst;
        faces[i].tet = s->tets + 4 * (size_t)star[i];
        faces[i].index = i;
        faces[i].a = NULL; /* the rest when first needed: a target that fails tests few */
        shape[i] = 0;      /* stays for the tets that vanish: dead, their quality is not read again */
    }
    double floor = worst * 0.5 < TPK_LEVEL_QUALITY ? worst * 0.5 : TPK_LEVEL_QUALITY;
    floor = floor > 0 ? floor : 0;
    for (int j = 1; j < m; j++) { /* by cost, then id: an insertion sort (m is small) */
        int32_t v = nb[j];
        double c = cost[j];
        int i = j;
        for (; i > 0 && (cost[i - 1] > c || (cost[i - 1] == c && nb[i - 1] > v)); i--)
            nb[i] = nb[i - 1], cost[i] = cost[i - 1];
        nb[i] = v, cost[i] = c;
    }
    for (int tried = 0; tried < m; tried++) {
        int32_t v = nb[tried];
        if (ring_count >= 0 && !levels_shell_move_ok(s, u, v, ring, ring_count))
            continue;
        const double *q = point(s, v);
        int ok = 1, i = 0;
        for (; i < n && ok; i++) {
            const int32_t *t = faces[i].tet;
            if (t[0] == v || t[1] == v || t[2] == v || t[3] == v)
                continue; /* it vanishes */
            if (!faces[i].a)
                star_face_of(s, t, u, &faces[i]);
            ok = moved_tet_ok(s, &faces[i], u, v, q, floor);
        }
        if (ok && ring_count >= 0 && !levels_witnesses_kept(s, u, v, ring, ring_count))
            continue; /* the shell would move too far: the next target (the moved tets passed) */
        if (ok) {
            for (i = 0; i < n; i++)
                if (faces[i].a && faces[i].tet[0] != v && faces[i].tet[1] != v && faces[i].tet[2] != v &&
                    faces[i].tet[3] != v)
                    shape[faces[i].index] = (float)(faces[i].six_v / (faces[i].l2 * sqrt(faces[i].l2)));
            return v;
        }
        /* The face that turned this target down is tried first for the next: targets of close cost often
         * fail on the same one. All must pass, so the order changes the time, not the answer. */
        star_face f = faces[i - 1];
        faces[i - 1] = faces[0];
        faces[0] = f;
    }
    return -1;
}

/* Collapse u if it may go and has a valid target; with lo < hi, only when every vertex of its star lies
 * in [lo, hi) (then it reads and writes only tets and vertices of that block). The tets it kills, or -1
 * when it stays. */
int64_t levels_try_collapse(simplifier *s, int32_t u, int32_t lo, int32_t hi)
{
    int n = (int)(s->star_end[u] - s->star_start[u]);
    if (s->pinned[u] || s->removed[u] || s->locked[u] || s->stuck[u] || n == 0 || n > STAR_MAX)
        return -1;
    /* Its tets: those of its star that no collapse of this pass killed. A collapse onto v changes the
     * stars of u's other neighbours only by the tets it kills, so only v (whose star grows) waits for the
     * next pass. */
    int32_t star[STAR_MAX];
    const int32_t *built = s->star + s->star_start[u];
    int live = 0;
    for (int i = 0; i < n; i++) { /* which are dead is as random as the mesh: no branch on it */
        star[live] = built[i];
        live += !s->dead[built[i]];
    }
    n = live;
    if (n == 0)
        return -1;
    int32_t nb[NEIGHBOURS_MAX];
    double cost[NEIGHBOURS_MAX];
    int m = levels_star_neighbours(s, u, star, n, lo, hi, nb, cost);
    if (m == -2)
        return -1; /* not in this block */
    int32_t ring[RING_MAX][3];
    int ring_count = s->boundary[u] ? levels_shell_ring(s, u, star, n, ring) : -1;
    float shape[STAR_MAX];
    int32_t v = m < 0 || (s->boundary[u] && ring_count < 0)
                    ? -1
                    : choose_target(s, u, star, n, nb, cost, m, ring, ring_count, shape);
    if (v < 0) {
        s->stuck[u] = 1; /* until a collapse next to it changes its star */
        return -1;
    }
    int64_t killed = 0;
    for (int i = 0; i < n; i++) {
        /* without branches on which tets vanish and which corner is u: they mispredict */
        int32_t *t = s->tets + 4 * (size_t)star[i];
        int gone = (t[0] == v) | (t[1] == v) | (t[2] == v) | (t[3] == v);
        s->dead[star[i]] = (uint8_t)gone;
        killed += gone;
        for (int k = 0; k < 4; k++) {
            s->stuck[t[k]] = 0;
            t[k] ^= (t[k] ^ v) & -((t[k] == u) & !gone);
        }
        s->tet_quality[star[i]] = shape[i]; /* as levels_quality() measures it, up to rounding; 0 if gone */
    }
    if (ring_count >= 0 && s->shell_tolerance > 0)
        levels_move_chains(s, u, v, ring, ring_count);
    s->removed[u] = 1;
    s->onto[u] = v;
    s->locked[u] = 1;
    s->locked[v] = 1;
    return killed;
}
