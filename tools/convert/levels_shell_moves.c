/* Levels of detail (levels_internal.h): the collapse rules for a vertex on the shell: its ring of shell
 * faces, whether it may move onto a vertex of the ring (flat, or inward within the tolerance), and the
 * witnesses (a shell face within the tolerance) of the shell vertices removed so far. */
#include <math.h>

#include "base/predicates.h"
#include "levels_internal.h"

/* A face through u, as the sorted pair of its other two ids, and the fourth corner of the tet that has it. */
typedef struct ring_key {
    uint64_t pair;
    int32_t fourth;
} ring_key;

/* The shell faces (u, a, b) around shell vertex u, as ring[i] = {a, b, c} with c the fourth corner of
 * the tet that has the face: the faces through u that only one tet of its star has (two tets share each
 * of the others). Their count when they form one ring around u (each a and b in exactly two of them,
 * and one walk meets them all); -1 when they do not (the shell is not a disc there) or past RING_MAX:
 * then u stays. */
int levels_shell_ring(const simplifier *s, int32_t u, const int32_t *star, int n, int32_t ring[RING_MAX][3])
{
    ring_key keys[3 * STAR_MAX];
    int k = 0, m = 0;
    for (int i = 0; i < n; i++) {
        const int32_t *t = s->tets + 4 * (size_t)star[i];
        int32_t o[3];
        for (int c = 0, j = 0; c < 4; c++)
            if (t[c] != u)
                o[j++] = t[c];
        for (int a = 0; a < 2; a++)
            for (int b = a + 1; b < 3; b++) {
                uint32_t x = (uint32_t)o[a], y = (uint32_t)o[b];
                keys[k].pair = x < y ? (uint64_t)x << 32 | y : (uint64_t)y << 32 | x;
                keys[k++].fourth = o[3 - a - b];
            }
    }
    for (int i = 1; i < k; i++) { /* a few dozen: insertion sort (qsort's calls cost more) */
        ring_key x = keys[i];
        int j = i;
        for (; j > 0 && keys[j - 1].pair > x.pair; j--)
            keys[j] = keys[j - 1];
        keys[j] = x;
    }
    for (int i = 0; i < k;) {
        int j = i + 1;
        while (j < k && keys[j].pair == keys[i].pair)
            j++;
        if (j - i > 2)
            return -1; /* three tets of the star on one face through u: not a mesh of a domain there */
        if (j - i == 1) {
            if (m == RING_MAX)
                return -1;
            ring[m][0] = (int32_t)(keys[i].pair >> 32);
            ring[m][1] = (int32_t)(keys[i].pair & 0xffffffffu);
            ring[m][2] = keys[i].fourth;
            m++;
        }
        i = j;
    }
    if (m < 3)
        return -1;
    /* one ring: from ring[0], each next face is the only other one with the current end */
    int32_t start = ring[0][0], at = ring[0][1];
    int prev = 0, steps = 1;
    while (at != start) {
        int next = -1;
        for (int i = 0; i < m; i++)
            if (i != prev && (ring[i][0] == at || ring[i][1] == at)) {
                if (next >= 0)
                    return -1; /* a third face at this vertex */
                next = i;
            }
        if (next < 0 || ++steps > m)
            return -1;
        at = ring[next][0] == at ? ring[next][1] : ring[next][0];
        prev = next;
    }
    return steps == m ? m : -1;
}

/* The distance from p to the nearest of the fan of faces (w, a, b) over u's ring, those without v. */
static double fan_distance(const simplifier *s, const double *p, int32_t w, int32_t v, const int32_t ring[][3], int m)
{
    double best = INFINITY;
    for (int i = 0; i < m; i++)
        if (ring[i][0] != v && ring[i][1] != v) {
            double d = levels_point_triangle(p, point(s, w), point(s, ring[i][0]), point(s, ring[i][1]));
            best = d < best ? d : best;
        }
    return best;
}

/* Each removed shell vertex p is chained at a live shell vertex x, its owner, one of whose shell faces
 * lies within the tolerance of p (p's witness). A collapse of u onto v changes only the faces at u (the
 * old fan, (u, a, b) over u's ring), which become (v, a, b) (the new fan): the faces at any other vertex
 * than u, v and the ring's stay, and so do their witnesses. Whether p, owned by x (u, v or on the ring),
 * needs a new witness: x is u, or an old face at x lies within the tolerance of p (then it may have been
 * the witness; else the witness is a face at x that stays). */
static int needs_witness(const simplifier *s, const double *p, int32_t x, int32_t u, const int32_t ring[][3], int m)
{
    if (x == u)
        return 1;
    for (int i = 0; i < m; i++)
        if ((ring[i][0] == x || ring[i][1] == x) &&
            levels_point_triangle(p, point(s, u), point(s, ring[i][0]), point(s, ring[i][1])) <= s->shell_tolerance)
            return 1;
    return 0;
}

/* Whether every point owned by x keeps a witness when u moves onto v: the new one is a face of the new
 * fan (all hold v, which then owns the point: move_chains). */
static int chain_keeps(const simplifier *s, int32_t x, int32_t u, int32_t v, const int32_t ring[][3], int m)
{
    for (int32_t p = s->chain_head[x]; p >= 0; p = s->chain_next[p]) {
        const double *q = point(s, p);
        if (needs_witness(s, q, x, u, ring, m) && fan_distance(s, q, v, v, ring, m) > s->shell_tolerance)
            return 0;
    }
    return 1;
}

/* The vertices of u's ring, each once (a ring of m faces has m). */
static int ring_vertices(const int32_t ring[][3], int m, int32_t *out)
{
    int n = 0;
    for (int i = 0; i < m; i++)
        for (int k = 0; k < 2; k++) {
            int again = 0;
            for (int j = 0; j < n && !again; j++)
                again = out[j] == ring[i][k];
            if (!again)
                out[n++] = ring[i][k];
        }
    return n;
}

/* After u moved onto v: u and the points it owned, and the points of the ring's vertices that needed a
 * new witness (chain_keeps found it in the new fan), go to v's chain. */
void levels_move_chains(simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m)
{
    int32_t verts[RING_MAX];
    int n = ring_vertices(ring, m, verts);
    for (int j = 0; j < n; j++) {
        int32_t x = verts[j];
        if (x == v)
            continue;
        for (int32_t p = s->chain_head[x], prev = -1, next; p >= 0; p = next) {
            next = s->chain_next[p];
            if (!needs_witness(s, point(s, p), x, u, ring, m)) {
                prev = p;
                continue;
            }
            if (prev < 0)
                s->chain_head[x] = next;
            else
                s->chain_next[prev] = next;
            s->chain_next[p] = s->chain_head[v];
            s->chain_head[v] = p;
        }
    }
    int32_t last = u;
    s->chain_next[u] = s->chain_head[u];
    while (s->chain_next[last] >= 0)
        last = s->chain_next[last];
    s->chain_next[last] = s->chain_head[v];
    s->chain_head[v] = u;
    s->chain_head[u] = -1;
}

/* Whether shell vertex u may move onto v: v is on u's ring, and the ring's faces (u, a, b), which
 * become (v, a, b), either all lie in a plane through v, exactly (the shell does not move), or (with a
 * tolerance) v is on or inside each face's plane; levels_witnesses_kept() then asks the rest. */
int levels_shell_move_ok(const simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m)
{
    /* v on the ring, and no face (u, a, b) of it in a tet with v (that tet vanishes, and takes the face
     * (v, a, b) it should become with it: the shell would tear there) */
    int on_ring = 0;
    for (int i = 0; i < m; i++) {
        on_ring |= (ring[i][0] == v) | (ring[i][1] == v);
        if (ring[i][2] == v && ring[i][0] != v && ring[i][1] != v)
            return 0;
    }
    if (!on_ring)
        return 0;
    /* v on every face's plane (flat), or else on its inner side (the side of the tet that has it) */
    const double *pu = point(s, u), *pv = point(s, v);
    for (int i = 0; i < m; i++) {
        if (ring[i][0] == v || ring[i][1] == v)
            continue;
        const double *a = point(s, ring[i][0]), *b = point(s, ring[i][1]);
        int side = tpk_orient3d_filter(a, b, pu, pv);
        side = side ? side : tpk_orient3d_exact(a, b, pu, pv);
        if (side == 0)
            continue;
        if (!(s->shell_tolerance > 0))
            return 0;
        const double *c = point(s, ring[i][2]);
        int inner = tpk_orient3d_filter(a, b, pu, c);
        if (side != (inner ? inner : tpk_orient3d_exact(a, b, pu, c)))
            return 0;
    }
    return 1;
}

/* With a tolerance, after shell_move_ok and the moved tets' tests (cheaper, and they reject more): every
 * removed shell vertex keeps a witness within the tolerance, u itself in the new fan, and the points
 * owned by u, v and the ring (chain_keeps). */
int levels_witnesses_kept(const simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m)
{
    if (!(s->shell_tolerance > 0))
        return 1; /* flat */
    const double *pu = point(s, u);
    if (fan_distance(s, pu, v, v, ring, m) > s->shell_tolerance || !chain_keeps(s, u, u, v, ring, m))
        return 0;
    int32_t verts[RING_MAX];
    int n = ring_vertices(ring, m, verts);
    for (int j = 0; j < n; j++)
        if (!chain_keeps(s, verts[j], u, v, ring, m))
            return 0;
    return 1;
}
