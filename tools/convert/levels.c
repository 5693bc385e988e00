/* Levels of detail by half-edge collapse (levels.h).
 *
 * A collapse moves vertex u onto a neighbour v: the tets around both u and v vanish, the other tets
 * around u get v instead of u. It is taken only when every changed tet stays positive, exactly
 * (tpk_orient3d_exact), and keeps a fair shape (volume over its longest edge cubed at least the smaller of
 * TPK_LEVEL_QUALITY and half the worst of the tets it replaces): then the changed tets tile what u's tets
 * tiled, v being in the kernel of that star, so the mesh stays conforming and covers the same domain.
 *
 * A vertex on the shell moves too, where its shell faces form one ring around it (a manifold shell
 * there; no shell vertex moves in a mesh with cut folds), onto a vertex v of that ring whose tets do not
 * hold a face of the ring that v is not on (the shell would tear), and only
 * - within flat pieces: every face of the ring lies in a plane through v, exactly (orient3d = 0), so u
 *   moves within a flat piece of the shell or along a straight crease where two meet, never off a corner.
 *   The cone from v over u's shell faces has no volume, the changed tets tile u's star as above, and the
 *   shell covers the same surface exactly (each level is checked for the same volume and shell area);
 * - or inward, with a tolerance (convert's level_shell_error times the bounding box diagonal): v on the
 *   inner side of, or on, the plane of every face of the ring, so the level's domain lies inside the
 *   full mesh's (it never meets another block of a mesh whose blocks only touch), and every shell vertex
 *   removed so far keeps a face of the shell within the tolerance: u and each removed vertex that may
 *   have lost its witness face (needs_witness) must find one among the new faces. The level's shell
 *   distance is then measured at every removed shell vertex (shell_distance()).
 * Without that the coarsest level of a large mesh would keep every shell face (a 48M-tet grid's 480k).
 *
 * Among the valid targets v the one whose field value is closest to u's is taken (the nearest without a field): the field at the kept vertices is the full
 * mesh's, exactly, and the error is what interpolation over the coarser tets makes of it at the removed
 * vertices, which is where it is measured.
 *
 * Passes: every vertex that may move, in id order, skipping the targets of this pass's collapses (the only
 * stars a collapse grows; the others only lose the tets it kills, which a star read leaves out), inside
 * fixed blocks of ids side by side first, until the level has a sixth of the tets of the last
 * (TPK_LEVEL_RATIO) or a pass removes almost nothing. The result does not depend on the thread count. */
#define _GNU_SOURCE /* memfd_create */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/clock.h"
#include "base/parallel.h"
#include "base/predicates.h"
#include "levels.h"
#include "pipeline.h"
#include "tetpack_format.h"
#include "write_tpk.h"

#define TPK_LEVEL_QUALITY 0.02 /* 6 V / L^3 of a new tet (a regular tet: 0.707) */
/* Each level aims at a sixth of the tets of the one before. A level costs more bytes per tet than its
 * file (its TMAP and the shell it keeps whole; grid 55: 27 B against 24 B), so a fifth made the levels
 * 31% of the file; a sixth makes them 28%, for an RMS error 13% higher on level 1 (0.0774 against
 * 0.0683) and a frame time that tets^(1/3) predicts 6% lower. */
#define TPK_LEVEL_RATIO 6
#define STAR_MAX 512
#define NEIGHBOURS_MAX 128
#define RING_MAX 64 /* shell faces around one vertex; past it the vertex stays */

/* What a collapse reads of each vertex it meets, side by side: its position, field value and mark
 * (star_neighbours), so that a neighbour costs one cache line, not three. */
typedef struct level_vertex {
    double p[3];
    float field;  /* s->field's value, or 0 */
    int32_t seen; /* -1, or the vertex whose neighbours star_neighbours is listing */
} level_vertex;

typedef struct simplifier {
    const tpk_tetmesh *mesh;
    int threads;
    const float *field;  /* the first point field at its step of widest range (field_step), or NULL */
    int field_step;
    uint8_t *boundary;   /* per vertex: on the shell */
    uint8_t *pinned;     /* per vertex: never moves (on the shell of a mesh with cut folds) */
    double shell_tolerance; /* how far the shell may move from the full mesh's, stored frame units */
    int32_t *chain_head, *chain_next; /* per live shell vertex (with a tolerance): the removed shell
                            vertices it owns (needs_witness), linked through chain_next; -1 ends */
    uint8_t *removed;    /* per vertex */
    int32_t *onto;       /* per removed vertex: the vertex it was moved onto (measure() follows these) */
    int32_t *tets;       /* 4 per live tet, full mesh vertex ids, positive */
    int32_t *origin;     /* per live tet: the full mesh tet it descends from */
    int64_t tet_count;
    int64_t *star_start, *star_end; /* per live vertex: its tets in star, [start, end) (-1, -1: not kept) */
    int32_t *alive;      /* the vertices not removed, in id order, as of the last build_stars */
    int64_t alive_count;
    int32_t *alive_next; /* build_stars writes the new list here, then swaps it with alive */
    int32_t *star;
    uint8_t *locked, *dead;
    uint8_t *stuck;      /* per vertex: no valid target, and its star has not changed since */
    level_vertex *vert;  /* per vertex */
    int32_t *active;     /* the vertices this pass may collapse, in id order (build_stars) */
    int64_t active_count;
    float *tet_quality;  /* per live tet: its shape (quality(); a moved tet's from its test in choose_target) */
} simplifier;

static const double *point(const simplifier *s, int32_t v)
{
    return s->vert[v].p;
}

/* a[0..n) = value, on all threads (the per-vertex maps each level sets up: 32 MB each on grid 200). */
typedef struct fill_job {
    int32_t *a;
    int32_t value;
} fill_job;

static void fill_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const fill_job *j = ctx;
    (void)worker;
    for (int64_t i = begin; i < end; i++)
        j->a[i] = j->value;
}

static void fill_i32(int32_t *a, int64_t n, int32_t value, int threads)
{
    fill_job job = {a, value};
    tpk_parallel_for(n, tpk_threads_for(n, threads, 1 << 18), fill_range, &job);
}

/* a[0..n) = 0, bytes, on all threads. */
static void zero_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    (void)worker;
    memset((uint8_t *)ctx + begin, 0, (size_t)(end - begin));
}

static void zero_bytes(uint8_t *a, int64_t n, int threads)
{
    tpk_parallel_for(n, tpk_threads_for(n, threads, 1 << 22), zero_range, a);
}

/* The bounds of n points (each origin + point, origin NULL: 0), on all threads: each worker's, then the
 * least and greatest of those, which are the ones one thread finds. */
typedef struct bounds_job {
    const double *points, *origin;
    double lo[TPK_MAX_THREADS][3], hi[TPK_MAX_THREADS][3];
} bounds_job;

static void bounds_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    bounds_job *j = ctx;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t v = begin; v < end; v++)
        for (int a = 0; a < 3; a++) {
            double w = j->origin ? j->origin[a] + j->points[3 * v + a] : j->points[3 * v + a];
            lo[a] = w < lo[a] ? w : lo[a];
            hi[a] = w > hi[a] ? w : hi[a];
        }
    memcpy(j->lo[worker], lo, sizeof lo);
    memcpy(j->hi[worker], hi, sizeof hi);
}

static void bounds_of(const double *points, const double *origin, int64_t n, int threads, double lo[3], double hi[3])
{
    bounds_job j; /* 3 KB */
    j.points = points, j.origin = origin;
    int parts = tpk_threads_for(n, threads, 1 << 16);
    tpk_parallel_for(n, parts, bounds_range, &j);
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY, hi[a] = -INFINITY;
        for (int w = 0; w < parts; w++) {
            lo[a] = j.lo[w][a] < lo[a] ? j.lo[w][a] : lo[a];
            hi[a] = j.hi[w][a] > hi[a] ? j.hi[w][a] : hi[a];
        }
    }
}

/* The squared length of b - a, and b - a in e. */
static double edge(const double *a, const double *b, double e[3])
{
    e[0] = b[0] - a[0], e[1] = b[1] - a[1], e[2] = b[2] - a[2];
    return e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
}

/* 6 V / L^3 of the tet (a, b, c, d): 0 flat, 0.707 regular; negative when inverted. */
static double quality(const double *a, const double *b, const double *c, const double *d)
{
    double ab[3], ac[3], ad[3], e[3];
    double l2 = edge(a, b, ab), x;
    l2 = (x = edge(a, c, ac)) > l2 ? x : l2;
    l2 = (x = edge(a, d, ad)) > l2 ? x : l2;
    l2 = (x = edge(b, c, e)) > l2 ? x : l2;
    l2 = (x = edge(b, d, e)) > l2 ? x : l2;
    l2 = (x = edge(c, d, e)) > l2 ? x : l2;
    double det = ab[0] * (ac[1] * ad[2] - ac[2] * ad[1]) - ab[1] * (ac[0] * ad[2] - ac[2] * ad[0]) +
                 ab[2] * (ac[0] * ad[1] - ac[1] * ad[0]);
    return l2 > 0 ? det / (l2 * sqrt(l2)) : 0;
}

/* The distance from p to the triangle (a, b, c): to its closest point, found by the region of the
 * triangle's plane (corner, edge or inside) that p projects into. */
static double point_triangle(const double *p, const double *a, const double *b, const double *c)
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
    edge(a, b, ab), edge(a, c, ac), edge(a, p, ap), edge(b, p, bp), edge(c, p, cp);
    double d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2], d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2];
    double d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2], d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2];
    double d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2], d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2];
    double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
    const double *from = a, *dir = ab;
    double x = 0, y = 0, bc[3];
    if (d1 <= 0 && d2 <= 0)
        from = a;
    else if (d3 >= 0 && d4 <= d3)
        from = b;
    else if (d6 >= 0 && d5 <= d6)
        from = c;
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        x = d1 / (d1 - d3);
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        dir = ac, x = d2 / (d2 - d6);
    else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
        from = b, dir = bc, x = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    else {
        double den = 1 / (va + vb + vc);
        x = vb * den, y = vc * den;
    }
    edge(b, c, bc);
    for (int k = 0; k < 3; k++)
        q[k] = from[k] + x * dir[k] + y * ac[k];
    double e[3];
    return sqrt(edge(p, q, e));
}

/* build_stars' counting and filling, side by side: worker w takes the corners whose vertex lies in its
 * range of ids [cut[w], cut[w + 1]) and reads every tet in order, so each star is filled in tet order, as
 * one thread would fill it. */
typedef struct star_job {
    simplifier *s;
    int32_t cut[TPK_MAX_THREADS + 1];
    int fill; /* 0: count, 1: fill */
} star_job;

static void star_ranges(void *ctx, int64_t begin, int64_t end, int worker)
{
    star_job *j = ctx;
    simplifier *s = j->s;
    const int32_t *tets = s->tets;
    int64_t *star_start = s->star_start, *star_end = s->star_end;
    int32_t *star = s->star;
    int64_t corners = 4 * s->tet_count;
    (void)worker;
    for (int64_t w = begin; w < end; w++) {
        uint32_t lo = (uint32_t)j->cut[w], span = (uint32_t)j->cut[w + 1] - lo;
        if (!j->fill) {
            for (int64_t i = 0; i < corners; i++)
                if ((uint32_t)tets[i] - lo < span)
                    star_end[tets[i]]++;
        } else {
            for (int64_t i = 0; i < corners; i++) {
                int32_t v = tets[i];
                if ((uint32_t)v - lo < span && star_start[v] >= 0)
                    star[star_end[v]++] = (int32_t)(i / 4);
            }
        }
    }
}

/* build_stars' lists, on all threads: each worker takes a range of the vertices that were alive and
 * counts (phase 0), then writes at the offsets the counts before it make (phase 1: the live and the
 * active vertices; phase 2: the stars' starts, after the counting of the stars). The same lists and
 * starts as one thread makes. */
typedef struct list_job {
    simplifier *s;
    int phase;
    int64_t live[TPK_MAX_THREADS + 1], act[TPK_MAX_THREADS + 1], entries[TPK_MAX_THREADS + 1];
} list_job;

static void list_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    list_job *j = ctx;
    simplifier *s = j->s;
    const uint8_t *removed = s->removed, *pinned = s->pinned, *stuck = s->stuck;
    if (j->phase == 0) { /* over the old list: the live, the active, and each live star's count cleared */
        int64_t live = 0, act = 0;
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            if (removed[v])
                continue;
            live++;
            act += !(pinned[v] | stuck[v]);
            s->star_end[v] = 0;
        }
        j->live[worker] = live, j->act[worker] = act;
    } else if (j->phase == 1) {
        int64_t live = j->live[worker], act = j->act[worker];
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            if (removed[v])
                continue;
            s->alive_next[live++] = v;
            if (!(pinned[v] | stuck[v]))
                s->active[act++] = v;
        }
    } else if (j->phase == 2) { /* over the new list: the entries of the stars kept */
        int64_t entries = 0;
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            entries += !(pinned[v] | stuck[v]) ? s->star_end[v] : 0;
        }
        j->entries[worker] = entries;
    } else { /* only the active vertices' stars are kept; the others' are empty (-1, -1) */
        int64_t at = j->entries[worker];
        for (int64_t i = begin; i < end; i++) {
            int32_t v = s->alive[i];
            int keep = !(pinned[v] | stuck[v]);
            s->star_start[v] = keep ? at : -1;
            at += keep ? s->star_end[v] : 0;
            s->star_end[v] = s->star_start[v]; /* the fill's cursor, its end once filled */
        }
    }
}

/* Counts per worker into offsets: c[w] becomes the sum of c[0..w). */
static void offsets(int64_t *c, int parts)
{
    int64_t at = 0;
    for (int w = 0; w < parts; w++) {
        int64_t n = c[w];
        c[w] = at;
        at += n;
    }
    c[parts] = at;
}

/* The vertices a pass may collapse (not pinned, not removed, not stuck), in id order, and their stars:
 * the tets that hold them, in tet order. */
static void build_stars(simplifier *s)
{
    /* over the vertices still there (the live tets use no other), not all of the full mesh's: a coarse
     * level's passes would spend most of their time on vertices long gone */
    list_job list;
    list.s = s;
    int lists = tpk_threads_for(s->alive_count, s->threads, 1 << 16);
    for (list.phase = 0; list.phase < 2; list.phase++) {
        tpk_parallel_for(s->alive_count, lists, list_range, &list);
        if (list.phase == 0)
            offsets(list.live, lists), offsets(list.act, lists);
    }
    int32_t *old = s->alive;
    s->alive = s->alive_next, s->alive_next = old;
    int64_t live = s->alive_count = list.live[lists];
    s->active_count = list.act[lists];
    /* each worker reads all the corners but writes only its own vertices' counts and stars: the
     * writes, scattered, are the cost */
    star_job job = {s, {0}, 0};
    int parts = tpk_threads_for(4 * s->tet_count, s->threads, 1 << 20);
    for (int w = 0; w <= parts; w++)
        job.cut[w] = w == 0 ? 0 : w == parts ? (int32_t)s->mesh->vertex_count : s->alive[live * w / parts];
    tpk_parallel_for(parts, parts, star_ranges, &job);
    lists = tpk_threads_for(live, s->threads, 1 << 16);
    list.phase = 2;
    tpk_parallel_for(live, lists, list_range, &list);
    offsets(list.entries, lists);
    list.phase = 3;
    tpk_parallel_for(live, lists, list_range, &list);
    job.fill = 1;
    tpk_parallel_for(parts, parts, star_ranges, &job);
}

/* u's neighbours (each once, in the order the star first meets them) with their costs: the field
 * difference, or the squared distance without a field. The ones met are marked (s->vert[].seen), and
 * cleared again.
 * The count; -1 past NEIGHBOURS_MAX; -2 when lo < hi and one lies outside [lo, hi) (then none is marked,
 * so blocks side by side touch only their own marks). */
static int star_neighbours(simplifier *s, int32_t u, const int32_t *star, int n, int32_t lo, int32_t hi,
                           int32_t *nb, double *cost)
{
    /* Every entry is stored at nb[m] and m only grows for a new one (not u, not seen): which corner is u
     * and whether a vertex is new are as random as the mesh, and branches on them mispredict (this loop
     * was a fifth of the simplification). u lies in [lo, hi) (run_blocks), and its mark is cleared with the
     * others. */
    const int32_t *tets = s->tets;
    level_vertex *vert = s->vert;
    const float *field = s->field;
    uint32_t first = lo < hi ? (uint32_t)lo : 0, span = lo < hi ? (uint32_t)hi - (uint32_t)lo : UINT32_MAX;
    double field_u = vert[u].field;
    const double *p = point(s, u);
    int m = 0, over = 0;
    for (int i = 0; i < n; i++) {
        const int32_t *t = tets + 4 * (size_t)star[i];
        for (int k = 0; k < 4; k++) {
            int32_t w = t[k];
            if ((uint32_t)w - first >= span) {
                for (int j = 0; j < m; j++)
                    vert[nb[j]].seen = -1;
                vert[u].seen = -1;
                return -2;
            }
            if (m == NEIGHBOURS_MAX) {
                over |= (vert[w].seen != u) & (w != u);
                continue;
            }
            int fresh = (vert[w].seen != u) & (w != u);
            vert[w].seen = u;
            double c = 0;
            if (field)
                c = fabs((double)vert[w].field - field_u);
            else
                for (int a = 0; a < 3; a++)
                    c += (point(s, w)[a] - p[a]) * (point(s, w)[a] - p[a]);
            nb[m] = w;
            cost[m] = c;
            m += fresh;
        }
    }
    for (int j = 0; j < m; j++)
        vert[nb[j]].seen = -1;
    vert[u].seen = -1;
    return over ? -1 : m;
}

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
static int shell_ring(const simplifier *s, int32_t u, const int32_t *star, int n, int32_t ring[RING_MAX][3])
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
            double d = point_triangle(p, point(s, w), point(s, ring[i][0]), point(s, ring[i][1]));
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
            point_triangle(p, point(s, u), point(s, ring[i][0]), point(s, ring[i][1])) <= s->shell_tolerance)
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
static void move_chains(simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m)
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
 * tolerance) v is on or inside each face's plane; witnesses_kept() then asks the rest. */
static int shell_move_ok(const simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m)
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
static int witnesses_kept(const simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m)
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
        if (ring_count >= 0 && !shell_move_ok(s, u, v, ring, ring_count))
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
        if (ok && ring_count >= 0 && !witnesses_kept(s, u, v, ring, ring_count))
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
static int64_t try_collapse(simplifier *s, int32_t u, int32_t lo, int32_t hi)
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
    int m = star_neighbours(s, u, star, n, lo, hi, nb, cost);
    if (m == -2)
        return -1; /* not in this block */
    int32_t ring[RING_MAX][3];
    int ring_count = s->boundary[u] ? shell_ring(s, u, star, n, ring) : -1;
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
        s->tet_quality[star[i]] = shape[i]; /* as quality() measures it, up to rounding; 0 if gone */
    }
    if (ring_count >= 0 && s->shell_tolerance > 0)
        move_chains(s, u, v, ring, ring_count);
    s->removed[u] = 1;
    s->onto[u] = v;
    s->locked[u] = 1;
    s->locked[v] = 1;
    return killed;
}

/* Blocks of vertex ids that a pass works on side by side: each of a fixed number of the vertices still
 * there (s->alive), so that the levels do not depend on the thread count, and a coarse level's blocks are
 * as large as the full mesh's (counted in ids, they would hold a sixth as many vertices a level, and
 * more stars would cross them). Vertices are in Hilbert order, so a block is a compact region and most
 * stars lie inside one. */
#define BLOCK_IDS ((int64_t)1 << 14)

typedef struct block_pass {
    simplifier *s;
    int64_t shift, size;    /* block b > 0 starts at alive[shift + (b - (shift > 0)) * size], block 0 at 0 */
    int64_t blocks;
    int64_t quota;          /* the tets a block may kill: its share of what the level still needs */
    int64_t *killed, *done; /* per block */
} block_pass;

static void block_range(const block_pass *p, int64_t b, int32_t *lo, int32_t *hi)
{
    const simplifier *s = p->s;
    int64_t n = s->alive_count, first = p->shift > 0;
    int64_t a = b == 0 ? 0 : p->shift + (b - first) * p->size, z = p->shift + (b + 1 - first) * p->size;
    *lo = a == 0 ? 0 : a < n ? s->alive[a] : (int32_t)s->mesh->vertex_count;
    *hi = z < n ? s->alive[z] : (int32_t)s->mesh->vertex_count;
}

/* The first active vertex at or after id lo. */
static int64_t first_active(const simplifier *s, int32_t lo)
{
    int64_t a = 0, z = s->active_count;
    while (a < z) {
        int64_t mid = a + (z - a) / 2;
        if (s->active[mid] < lo)
            a = mid + 1;
        else
            z = mid;
    }
    return a;
}

/* The collapses ahead of active[i], fetched in stages so that each stage reads what the one before
 * brought into cache: a star's bounds (12 ahead), its entries (8), its tets with their shape and mark
 * (4), their corners' vertices (2). A collapse reads these scattered lines and little else, so without
 * this it waits on memory (grid 120: a third of try_collapse's samples on the loads of tets and
 * vertices). Only what is read changes no result. Up to active[n - 1]: a block's thread reads no tet of
 * the next block, which another thread may be changing. */
#define PREFETCH_TETS 48 /* of a star; a typical interior star has 20-30 */

static void prefetch_ahead(const simplifier *s, int64_t i, int64_t n)
{
    const int32_t *active = s->active;
    if (i + 12 < n)
        __builtin_prefetch(s->star_start + active[i + 12]), __builtin_prefetch(s->star_end + active[i + 12]);
    if (i + 8 < n) {
        int64_t a = s->star_start[active[i + 8]];
        __builtin_prefetch(s->star + a), __builtin_prefetch(s->star + a + 16);
    }
    if (i + 4 < n) {
        int32_t a = active[i + 4];
        int64_t b = s->star_start[a], e = s->star_end[a];
        e = e - b > PREFETCH_TETS ? b + PREFETCH_TETS : e;
        for (int64_t j = b; j < e; j++) {
            int32_t t = s->star[j];
            __builtin_prefetch(s->tets + 4 * (size_t)t);
            __builtin_prefetch(s->tet_quality + t);
            __builtin_prefetch(s->dead + t);
        }
    }
    if (i + 2 < n) {
        int32_t a = active[i + 2];
        int64_t b = s->star_start[a], e = s->star_end[a];
        e = e - b > PREFETCH_TETS ? b + PREFETCH_TETS : e;
        for (int64_t j = b; j < e; j++) {
            const int32_t *t = s->tets + 4 * (size_t)s->star[j];
            for (int k = 0; k < 4; k++)
                __builtin_prefetch(s->vert + t[k]);
        }
    }
}

static void run_blocks(void *ctx, int64_t begin, int64_t end, int worker)
{
    block_pass *p = ctx;
    (void)worker;
    for (int64_t b = begin; b < end; b++) {
        int32_t lo, hi;
        block_range(p, b, &lo, &hi);
        p->killed[b] = p->done[b] = 0;
        for (int64_t i = first_active(p->s, lo), n = first_active(p->s, hi); i < n && p->killed[b] < p->quota; i++) {
            int32_t u = p->s->active[i];
            prefetch_ahead(p->s, i, n);
            int64_t k = try_collapse(p->s, u, lo, hi);
            if (k >= 0)
                p->killed[b] += k, p->done[b]++;
        }
    }
}

/* The collapses whose stars lie inside one block, the blocks side by side: no two touch the same tet or
 * vertex, and each reads only its own, so the result is that of the blocks one after the other. */
static int64_t blocks_pass(simplifier *s, int64_t shift, int64_t size, int64_t target, int64_t *live)
{
    int64_t n = s->alive_count, need = *live - target;
    if (need <= 0)
        return 0;
    /* with fewer than shift vertices, one block of them all (first > 0 counts it) */
    block_pass p = {s, shift, size, (n > shift ? (n - shift + size - 1) / size : 0) + (shift > 0), 0, NULL, NULL};
    p.killed = malloc(sizeof *p.killed * 2 * (size_t)p.blocks);
    if (!p.killed)
        return 0; /* the sweep one by one does it all */
    p.done = p.killed + p.blocks;
    p.quota = (need + p.blocks - 1) / p.blocks;
    tpk_parallel_for(p.blocks, tpk_threads_for(p.blocks, s->threads, 1), run_blocks, &p);
    int64_t done = 0;
    for (int64_t b = 0; b < p.blocks; b++)
        *live -= p.killed[b], done += p.done[b];
    free(p.killed);
    return done;
}

/* One pass; the number of collapses. Vertices in id order, skipping the targets of this pass's
 * collapses (the stars it began with, less the tets killed since, are the others'): first inside the
 * blocks, side by side, then inside the blocks shifted by half a block, then inside blocks 16 times as
 * large, shifted so that no boundary is one of the first two's (a star that crosses both of those spans
 * thousands of ids, where the Hilbert order jumps: grid 120's first pass left 221k collapses to the
 * sweep, now 88k), then one by one the rest, which stops at the target exactly. */
static int64_t collapse_pass(simplifier *s, int64_t target, int64_t *live)
{
    int64_t V = s->mesh->vertex_count, done = 0;
    if (V <= 0 || s->tet_count <= 0)
        return 0;
    zero_bytes(s->locked, V, s->threads);
    zero_bytes(s->dead, s->tet_count, s->threads);
    done += blocks_pass(s, 0, BLOCK_IDS, target, live);
    done += blocks_pass(s, BLOCK_IDS / 2, BLOCK_IDS, target, live);
    if (s->alive_count > 8 * BLOCK_IDS + BLOCK_IDS / 4) /* else one block of them all: the sweep's work, */
        done += blocks_pass(s, 8 * BLOCK_IDS + BLOCK_IDS / 4, 16 * BLOCK_IDS, target, live); /* on one thread */
    for (int64_t i = 0; i < s->active_count && *live > target; i++) {
        prefetch_ahead(s, i, s->active_count);
        int64_t k = try_collapse(s, s->active[i], 0, 0);
        if (k >= 0)
            *live -= k, done++;
    }
    int64_t w = 0; /* compact, in order */
    for (int64_t t = 0; t < s->tet_count; t++) { /* each copied, kept only if live: no branch */
        for (int k = 0; k < 4; k++)
            s->tets[4 * w + k] = s->tets[4 * t + k];
        s->tet_quality[w] = s->tet_quality[t];
        s->origin[w] = s->origin[t];
        w += !s->dead[t];
    }
    s->tet_count = w;
    return done;
}

/* Simplify to about `target` live tets (or as far as passes go). */
static void simplify_to(simplifier *s, int64_t target)
{
    int64_t live = s->tet_count;
    for (;;) {
        build_stars(s);
        int64_t before = live, done = collapse_pass(s, target, &live);
        if (live <= target || done == 0 || before - live < before / 200)
            return;
    }
}

/* ---- one level as a file -------------------------------------------------------------------------- */

/* level_mesh's copies, over the level's vertices (one job) or tets (the other), side by side. */
typedef struct level_fill {
    const simplifier *s;
    tpk_tetmesh *out;
    const int32_t *renum, *vertex_old;
} level_fill;

static void fill_vertices(void *ctx, int64_t begin, int64_t end, int worker)
{
    const level_fill *f = ctx;
    const tpk_tetmesh *m = f->s->mesh;
    tpk_tetmesh *out = f->out;
    (void)worker;
    for (int64_t i = begin; i < end; i++) {
        int32_t v = f->vertex_old[i];
        memcpy(out->points + 3 * (size_t)i, m->points + 3 * (size_t)v, 3 * sizeof(double));
        out->vertex_source[i] = m->vertex_source ? m->vertex_source[v] : v;
        for (int fi = 0; fi < m->field_count; fi++)
            if (m->fields[fi].association == TPK_ASSOC_POINT)
                for (int st = 0; st < m->fields[fi].step_count; st++)
                    out->fields[fi].values[(size_t)st * (size_t)out->vertex_count + (size_t)i] =
                        m->fields[fi].values[(size_t)st * (size_t)m->vertex_count + (size_t)v];
    }
}

static void fill_tets(void *ctx, int64_t begin, int64_t end, int worker)
{
    const level_fill *f = ctx;
    const simplifier *s = f->s;
    const tpk_tetmesh *m = s->mesh;
    tpk_tetmesh *out = f->out;
    (void)worker;
    for (int64_t t = begin; t < end; t++) {
        for (int k = 0; k < 4; k++)
            out->tets[4 * t + k] = f->renum[s->tets[4 * t + k]];
        out->tet_source[t] = m->tet_source ? m->tet_source[s->origin[t]] : s->origin[t];
        for (int fi = 0; fi < m->field_count; fi++)
            if (m->fields[fi].association != TPK_ASSOC_POINT)
                for (int st = 0; st < m->fields[fi].step_count; st++)
                    out->fields[fi].values[(size_t)st * (size_t)out->tet_count + (size_t)t] =
                        m->fields[fi].values[(size_t)st * (size_t)m->tet_count + (size_t)s->origin[t]];
    }
}

/* level_mesh's numbering on all threads: phase 0 over the live tets marks the vertices they use (renum 0;
 * two workers may mark one, both with 0: relaxed atomic stores); phase 1 over the full mesh's vertices
 * counts the marked; phase 2 numbers them from the offsets the counts before make, in id order as one
 * thread does, and fills vertex_old. */
typedef struct level_numbers {
    const simplifier *s;
    int32_t *renum, *vertex_old;
    int phase;
    int64_t count[TPK_MAX_THREADS + 1];
} level_numbers;

static void number_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    level_numbers *j = ctx;
    int32_t *renum = j->renum;
    if (j->phase == 0) {
        for (int64_t i = 4 * begin; i < 4 * end; i++)
            __atomic_store_n(&renum[j->s->tets[i]], 0, __ATOMIC_RELAXED);
    } else if (j->phase == 1) {
        int64_t n = 0;
        for (int64_t v = begin; v < end; v++)
            n += renum[v] == 0;
        j->count[worker] = n;
    } else {
        int64_t n = j->count[worker];
        for (int64_t v = begin; v < end; v++)
            if (renum[v] == 0) {
                j->vertex_old[n] = (int32_t)v;
                renum[v] = (int32_t)n++;
            }
    }
}

/* The level's tetmesh: kept vertices (those its tets use) in their full-mesh order, the tets renumbered,
 * the fields gathered (tet fields through the tet each level tet descends from), maps through. */
static int level_mesh(const simplifier *s, tpk_tetmesh *out, int32_t **vertex_old, tpk_diag *diag)
{
    const tpk_tetmesh *m = s->mesh;
    memset(out, 0, sizeof *out);
    int32_t *renum = malloc(sizeof *renum * (size_t)(m->vertex_count ? m->vertex_count : 1));
    if (!renum)
        return tpk_diag_fail(diag, "levels: out of memory");
    fill_i32(renum, m->vertex_count, -1, s->threads);
    level_numbers num = {s, renum, NULL, 0, {0}};
    tpk_parallel_for(s->tet_count, tpk_threads_for(s->tet_count, s->threads, 1 << 16), number_range, &num);
    int parts = tpk_threads_for(m->vertex_count, s->threads, 1 << 16);
    num.phase = 1;
    tpk_parallel_for(m->vertex_count, parts, number_range, &num);
    offsets(num.count, parts);
    int64_t n = num.count[parts];
    out->vertex_count = n;
    out->tet_count = s->tet_count;
    memcpy(out->origin, m->origin, sizeof out->origin);
    out->points = malloc(sizeof *out->points * 3 * (size_t)(n ? n : 1));
    out->vertex_source = malloc(sizeof(int32_t) * (size_t)(n ? n : 1));
    *vertex_old = malloc(sizeof(int32_t) * (size_t)(n ? n : 1));
    out->tets = malloc(sizeof *out->tets * 4 * (size_t)(s->tet_count ? s->tet_count : 1));
    out->tet_source = malloc(sizeof *out->tet_source * (size_t)(s->tet_count ? s->tet_count : 1));
    out->field_count = m->field_count;
    out->fields = m->field_count ? calloc((size_t)m->field_count, sizeof *out->fields) : NULL;
    int rc = out->points && out->vertex_source && *vertex_old && out->tets && out->tet_source &&
                     (!m->field_count || out->fields) ? 0 : -1;
    if (rc == 0) { /* the numbers, and vertex_old */
        num.vertex_old = *vertex_old;
        num.phase = 2;
        tpk_parallel_for(m->vertex_count, parts, number_range, &num);
    }
    for (int f = 0; rc == 0 && f < m->field_count; f++) {
        const tpk_src_field *src = &m->fields[f];
        tpk_src_field *dst = &out->fields[f];
        *dst = *src;
        size_t per = (size_t)(src->association == TPK_ASSOC_POINT ? n : s->tet_count);
        if (!(dst->values = malloc(sizeof *dst->values * (per ? per : 1) * (size_t)src->step_count)))
            rc = -1;
    }
    if (rc == 0) { /* the copies, on all threads: level 1 of grid 200 spent 0.2-0.4 s here on one */
        level_fill fill = {s, out, renum, *vertex_old};
        tpk_parallel_for(n, tpk_threads_for(n, s->threads, 1 << 14), fill_vertices, &fill);
        tpk_parallel_for(s->tet_count, tpk_threads_for(s->tet_count, s->threads, 1 << 16), fill_tets, &fill);
    }
    out->step_count = m->step_count;
    out->times = m->times; /* borrowed */
    free(renum);
    return rc == 0 ? 0 : tpk_diag_fail(diag, "levels: out of memory for a level of %lld tets", (long long)s->tet_count);
}

static void level_mesh_free(tpk_tetmesh *m)
{
    free(m->points);
    free(m->vertex_source);
    free(m->tets);
    free(m->tet_source);
    for (int f = 0; m->fields && f < m->field_count; f++)
        free(m->fields[f].values);
    free(m->fields);
    memset(m, 0, sizeof *m);
}

/* The level vertex a removed vertex ended on, at the end of the chain of the vertices it was moved onto. */
static int32_t survivor(const simplifier *s, int32_t u)
{
    while (s->removed[u])
        u = s->onto[u];
    return u;
}

/* The level tet that holds point p, by a walk from tet t across a face p is beyond (exactly; one with a
 * neighbour first, so that a walk near a non-convex shell stays inside), with p's barycentric weights
 * (unnormalised: each a 6V, summing to *total); -1 when the walk leaves the mesh or takes 4096 steps. */
/* p's barycentric weights in level tet t (unnormalised: each a 6V, summing to *total). */
static void weights(const tpk_tetmesh *lvl, int64_t t, const double *p, double lambda[4], double *total)
{
    const int32_t *v = lvl->tets + 4 * t;
    /* The corners from p: lambda[k] is the 6V of the tet with p in place of corner k, a triple
     * product of the other three, two cross products for the four */
    const double *c0 = lvl->points + 3 * (size_t)v[0], *c1 = lvl->points + 3 * (size_t)v[1];
    const double *c2 = lvl->points + 3 * (size_t)v[2], *c3 = lvl->points + 3 * (size_t)v[3];
    double x0 = c0[0] - p[0], y0 = c0[1] - p[1], z0 = c0[2] - p[2];
    double x1 = c1[0] - p[0], y1 = c1[1] - p[1], z1 = c1[2] - p[2];
    double x2 = c2[0] - p[0], y2 = c2[1] - p[1], z2 = c2[2] - p[2];
    double x3 = c3[0] - p[0], y3 = c3[1] - p[1], z3 = c3[2] - p[2];
    double abx = y0 * z1 - z0 * y1, aby = z0 * x1 - x0 * z1, abz = x0 * y1 - y0 * x1;
    double cdx = y2 * z3 - z2 * y3, cdy = z2 * x3 - x2 * z3, cdz = x2 * y3 - y2 * x3;
    lambda[0] = x1 * cdx + y1 * cdy + z1 * cdz;
    lambda[1] = -(x0 * cdx + y0 * cdy + z0 * cdz);
    lambda[2] = abx * x3 + aby * y3 + abz * z3;
    lambda[3] = -(abx * x2 + aby * y2 + abz * z2);
    *total = lambda[0] + lambda[1] + lambda[2] + lambda[3];
}

static int64_t locate(const tpk_tetmesh *lvl, const int32_t *neighbors, const double *p, int64_t t, double lambda[4],
                      double *total)
{
    for (int steps = 0; steps < 4096 && t >= 0; steps++) {
        const int32_t *v = lvl->tets + 4 * t;
        weights(lvl, t, p, lambda, total);
        int beyond = -1, outside = 0;
        for (int k = 0; k < 4 && beyond < 0; k++) {
            if (!(lambda[k] < 0))
                continue;
            const double *q[4];
            for (int j = 0; j < 4; j++)
                q[j] = j == k ? p : lvl->points + 3 * (size_t)v[j];
            if (tpk_orient3d_exact(q[0], q[1], q[2], q[3]) < 0) {
                if (neighbors[4 * t + k] >= 0)
                    beyond = k;
                else
                    outside = 1;
            }
        }
        if (beyond < 0)
            return outside ? -1 : t;
        t = neighbors[4 * t + beyond];
    }
    return -1;
}

/* The error sampling's vertices go in chunks of fixed size, side by side, each walk starting from the tet
 * of the chunk's first kept vertex: the sums do not depend on the thread count. */
#define MEASURE_CHUNK ((int64_t)1 << 15)

typedef struct measure_job {
    const simplifier *s;
    const tpk_tetmesh *lvl;
    const int32_t *vertex_old, *neighbors, *near_tet, *tet_of;
    double *sum, *worst; /* per chunk */
    int64_t *count;
} measure_job;

static void measure_chunks(void *ctx, int64_t begin, int64_t end, int worker)
{
    const measure_job *j = ctx;
    const simplifier *s = j->s;
    const tpk_tetmesh *m = s->mesh, *lvl = j->lvl;
    const int32_t *vertex_old = j->vertex_old, *tet_of = j->tet_of, *near_tet = j->near_tet;
    (void)worker;
    for (int64_t c = begin; c < end; c++) {
        int64_t first = c * MEASURE_CHUNK, last = first + MEASURE_CHUNK;
        last = last < m->vertex_count ? last : m->vertex_count;
        double sum = 0, worst = 0;
        int64_t count = 0, hint = 0;
        for (int64_t u = first; u < last; u++)
            if (tet_of[u] >= 0) {
                hint = tet_of[u];
                break;
            }
        for (int64_t u = first; u < last; u++) {
            if (tet_of[u] >= 0)
                continue;
            const double *p = m->points + 3 * (size_t)u;
            double lambda[4], total = 0;
            int64_t t = locate(lvl, j->neighbors, p, hint, lambda, &total);
            int32_t w = t < 0 && s->removed[u] ? survivor(s, (int32_t)u) : -1;
            if (w >= 0 && tet_of[w] >= 0 && tet_of[w] != hint)
                t = locate(lvl, j->neighbors, p, tet_of[w], lambda, &total);
            int outside = t < 0 && near_tet && near_tet[u] >= 0;
            if (outside) { /* a shell vertex the level's shell moved past: the weights of the nearest shell face's tet */
                t = near_tet[u];
                weights(lvl, t, p, lambda, &total);
            }
            if (t < 0)
                continue;
            const int32_t *v = lvl->tets + 4 * t;
            double value = 0, sum_w = 0;
            for (int k = 0; k < 4 && outside; k++) /* clamped to the tet: its nearest value to p, about */
                sum_w += (lambda[k] = lambda[k] > 0 ? lambda[k] : 0);
            total = outside ? sum_w : total;
            for (int k = 0; k < 4 && total > 0; k++)
                value += lambda[k] / total * (double)s->field[vertex_old[v[k]]];
            double d = fabs(value - (double)s->field[u]);
            worst = d > worst ? d : worst;
            sum += d * d;
            count++;
            hint = t;
        }
        j->sum[c] = sum, j->worst[c] = worst, j->count[c] = count;
    }
}

/* The field of the full mesh at the vertices this level removed against the level's value there (linear
 * in the level tet that holds the point, found by locate(): from the tet found for the removed vertex
 * before, vertices being in Hilbert order, else from a tet of the vertex it ended on, which is in the
 * same part of the mesh: a walk does not cross from one block of a mesh to another that only lies
 * against it). A point neither walk reaches is not sampled; a shell vertex the level's shell moved past is
 * sampled in the tet of its nearest shell face. */
static void measure(const simplifier *s, const tpk_tetmesh *lvl, const int32_t *vertex_old, const int32_t *neighbors,
                    const int32_t *near_tet, tpk_level *r)
{
    const tpk_tetmesh *m = s->mesh;
    int64_t chunks = (m->vertex_count + MEASURE_CHUNK - 1) / MEASURE_CHUNK;
    /* per full mesh vertex: a level tet that holds it, or -1 (not kept) */
    int32_t *tet_of = s->field ? malloc(sizeof *tet_of * (size_t)(m->vertex_count ? m->vertex_count : 1)) : NULL;
    double *sums = tet_of ? malloc(sizeof *sums * 2 * (size_t)(chunks ? chunks : 1)) : NULL;
    int64_t *counts = sums ? malloc(sizeof *counts * (size_t)(chunks ? chunks : 1)) : NULL;
    if (!counts) {
        free(tet_of);
        free(sums);
        return;
    }
    fill_i32(tet_of, m->vertex_count, -1, s->threads);
    for (int64_t i = 0; i < 4 * lvl->tet_count; i++)
        tet_of[vertex_old[lvl->tets[i]]] = (int32_t)(i / 4);
    measure_job job = {s, lvl, vertex_old, neighbors, near_tet, tet_of, sums, sums + chunks, counts};
    tpk_parallel_for(chunks, tpk_threads_for(chunks, s->threads, 1), measure_chunks, &job);
    double sum = 0, worst = 0;
    int64_t count = 0;
    for (int64_t c = 0; c < chunks; c++) { /* in chunk order */
        sum += sums[c];
        worst = job.worst[c] > worst ? job.worst[c] : worst;
        count += counts[c];
    }
    r->error_samples = count;
    r->error_max = worst;
    r->error_rms = count ? sqrt(sum / (double)count) : 0;
    free(tet_of);
    free(sums);
    free(counts);
}

/* What a level must keep of the full mesh: its volume and its shell's area (sums of 6V and of twice the
 * face areas, in the stored frame). Equal up to rounding when the domain is the same; a bug that lost
 * or doubled a piece would show. */
typedef struct domain_size {
    double volume, area;
} domain_size;

/* size_of's sums in chunks of a number of tets that depends on the count alone (at least SIZE_CHUNK, at
 * most SIZE_CHUNKS of them), side by side, added in chunk order: the same sums whatever the thread count. */
#define SIZE_CHUNK ((int64_t)1 << 16)
#define SIZE_CHUNKS 2048

typedef struct size_job {
    const double *points;
    const int32_t *tets, *neighbors;
    int64_t tet_count, chunk;
    domain_size part[SIZE_CHUNKS];
} size_job;

static void size_chunks(void *ctx, int64_t begin, int64_t end, int worker)
{
    size_job *j = ctx;
    const double *points = j->points;
    (void)worker;
    for (int64_t c = begin; c < end; c++) {
        domain_size d = {0, 0};
        int64_t last = (c + 1) * j->chunk < j->tet_count ? (c + 1) * j->chunk : j->tet_count;
        for (int64_t t = c * j->chunk; t < last; t++) {
            const int32_t *v = j->tets + 4 * t;
            const double *a = points + 3 * (size_t)v[0];
            double ab[3], ac[3], ad[3];
            edge(a, points + 3 * (size_t)v[1], ab);
            edge(a, points + 3 * (size_t)v[2], ac);
            edge(a, points + 3 * (size_t)v[3], ad);
            d.volume += ab[0] * (ac[1] * ad[2] - ac[2] * ad[1]) - ab[1] * (ac[0] * ad[2] - ac[2] * ad[0]) +
                        ab[2] * (ac[0] * ad[1] - ac[1] * ad[0]);
            for (int k = 0; k < 4; k++)
                if (j->neighbors[4 * t + k] < 0) {
                    const double *p = points + 3 * (size_t)v[tpk_tet_faces[k][0]];
                    double e1[3], e2[3];
                    edge(p, points + 3 * (size_t)v[tpk_tet_faces[k][1]], e1);
                    edge(p, points + 3 * (size_t)v[tpk_tet_faces[k][2]], e2);
                    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
                           z = e1[0] * e2[1] - e1[1] * e2[0];
                    d.area += sqrt(x * x + y * y + z * z);
                }
        }
        j->part[c] = d;
    }
}

static domain_size size_of(const double *points, const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                           int threads)
{
    size_job job = {points, tets, neighbors, tet_count, SIZE_CHUNK, {{0, 0}}}; /* 32 KB */
    if (tet_count > SIZE_CHUNK * SIZE_CHUNKS)
        job.chunk = (tet_count + SIZE_CHUNKS - 1) / SIZE_CHUNKS;
    int64_t chunks = (tet_count + job.chunk - 1) / job.chunk;
    tpk_parallel_for(chunks, tpk_threads_for(chunks, threads, 1), size_chunks, &job);
    domain_size d = {0, 0};
    for (int64_t c = 0; c < chunks; c++)
        d.volume += job.part[c].volume, d.area += job.part[c].area;
    return d;
}

/* With the shell kept (tolerance 0), the same volume and area up to rounding; else the volume changed by
 * at most the shell's area times how far it moved. */
static int same_size(domain_size full, domain_size level, double tolerance)
{
    if (tolerance > 0)
        return fabs(level.volume - full.volume) / 6 <= tolerance * full.area / 2 + 1e-9 * fabs(full.volume) / 6;
    return fabs(level.volume - full.volume) <= 1e-9 * fabs(full.volume) &&
           fabs(level.area - full.area) <= 1e-9 * fabs(full.area);
}

/* shell_distance's search, for the removed shell vertices of [begin, end) (tpk_parallel_for): each
 * one's distance to its owner's level faces, and the tet of the nearest in near_tet. */
typedef struct shell_job {
    const simplifier *s;
    const tpk_tetmesh *lvl;
    const int64_t *start;
    const int32_t *tri, *at, *tet, *level_of, *owner;
    int32_t *near_tet;
    double worst[TPK_MAX_THREADS]; /* per worker */
} shell_job;

static void shell_vertices(void *ctx, int64_t begin, int64_t end, int worker)
{
    shell_job *j = ctx;
    const simplifier *s = j->s;
    const tpk_tetmesh *lvl = j->lvl;
    const int64_t *start = j->start;
    const int32_t *tri = j->tri, *at = j->at, *owner = j->owner;
    double worst = 0;
    for (int64_t u = begin; u < end; u++) {
        if (!(s->boundary[u] && s->removed[u]))
            continue;
        const double *p = point(s, (int32_t)u);
        int32_t from = owner && owner[u] >= 0 ? owner[u] : survivor(s, (int32_t)u);
        int32_t around[3] = {j->level_of[from], -1, -1}, face = -1;
        double best = INFINITY;
        /* the owner's faces hold a witness: they alone give the bound (a descent would make it
         * tighter, at twice the cost, and the bound is what the tolerance is about) */
        int rounds = owner && owner[u] >= 0 ? 1 : 256;
        for (int steps = 0, nearer = 1; nearer && steps < rounds; steps++) {
            nearer = 0;
            for (int k = 0; k < 3 && around[k] >= 0; k++)
                for (int64_t i = start[around[k]]; i < start[around[k] + 1]; i++) {
                    const int32_t *c = tri + 3 * at[i];
                    double d = point_triangle(p, lvl->points + 3 * (size_t)c[0], lvl->points + 3 * (size_t)c[1],
                                              lvl->points + 3 * (size_t)c[2]);
                    if (d < best)
                        best = d, face = at[i], nearer = 1;
                }
            if (face >= 0)
                memcpy(around, tri + 3 * face, sizeof around);
        }
        j->near_tet[u] = face >= 0 ? j->tet[face] : -1;
        worst = best > worst ? best : worst;
    }
    j->worst[worker] = worst;
}

/* shell_distance's preparation on all threads, in phases over ranges that depend on the counts alone:
 * 0, over the full mesh's vertices: the removed shell vertices, counted; 1, over the level's tets: their
 * shell faces, counted; 2, the same: the faces written at the offsets the counts before make (in tet
 * order, as one thread writes them); 3, over the full mesh's vertices: each live one's chain of removed
 * shell vertices (disjoint chains) gives them their owner; 4, over the level's vertices: level_of. */
typedef struct shell_prep {
    const simplifier *s;
    const tpk_tetmesh *lvl;
    const int32_t *neighbors, *vertex_old;
    int32_t *tri, *tet, *owner, *level_of;
    int phase;
    int64_t count[TPK_MAX_THREADS + 1];
} shell_prep;

static void shell_prep_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    shell_prep *j = ctx;
    const simplifier *s = j->s;
    const int32_t *neighbors = j->neighbors;
    int64_t count = 0;
    if (j->phase == 0) {
        for (int64_t v = begin; v < end; v++)
            count += s->boundary[v] & s->removed[v];
    } else if (j->phase == 1) {
        for (int64_t i = 4 * begin; i < 4 * end; i++)
            count += neighbors[i] < 0;
    } else if (j->phase == 2) {
        int64_t f = j->count[worker];
        for (int64_t t = begin; t < end; t++)
            for (int k = 0; k < 4; k++)
                if (neighbors[4 * t + k] < 0) {
                    for (int c = 0; c < 3; c++)
                        j->tri[3 * f + c] = j->lvl->tets[4 * t + tpk_tet_faces[k][c]];
                    j->tet[f++] = (int32_t)t;
                }
    } else if (j->phase == 3) {
        for (int64_t x = begin; x < end; x++)
            for (int32_t p = s->removed[x] ? -1 : s->chain_head[x]; p >= 0; p = s->chain_next[p])
                j->owner[p] = (int32_t)x;
    } else {
        for (int64_t v = begin; v < end; v++)
            j->level_of[j->vertex_old[v]] = (int32_t)v;
    }
    j->count[worker] = count;
}

static int64_t shell_prep_run(shell_prep *j, int phase, int64_t n)
{
    int parts = tpk_threads_for(n, j->s->threads, 1 << 16);
    j->phase = phase;
    tpk_parallel_for(n, parts, shell_prep_range, j);
    offsets(j->count, parts);
    return j->count[parts];
}

/* How far the full mesh's shell lies from the level's, measured at the shell vertices the level removed:
 * each one's distance to the nearest level shell face at its owner (one of them is within the tolerance:
 * needs_witness), or without an owner by a descent from the vertex it ended on (the faces at that
 * vertex, then at the corners of the nearest so far, while one comes nearer). That
 * face may not be the nearest of all, so the figure is at most too large. near_tet[u] gets the level
 * tet of u's face (measure() evaluates the field there when u lies outside the level). */
static double shell_distance(const simplifier *s, const tpk_tetmesh *lvl, const int32_t *vertex_old,
                             const int32_t *neighbors, int32_t *near_tet)
{
    const tpk_tetmesh *m = s->mesh;
    shell_prep prep = {s, lvl, neighbors, vertex_old, NULL, NULL, NULL, NULL, 0, {0}};
    int64_t n = lvl->vertex_count;
    if (shell_prep_run(&prep, 0, m->vertex_count) == 0)
        return 0; /* no shell vertex removed */
    int64_t faces = shell_prep_run(&prep, 1, lvl->tet_count);
    size_t fn = (size_t)(faces ? faces : 1);
    int32_t *level_of = malloc(sizeof *level_of * (size_t)m->vertex_count);
    int64_t *start = calloc((size_t)n + 1, sizeof *start), *fill = malloc(sizeof *fill * (size_t)(n ? n : 1));
    int32_t *tri = malloc(sizeof *tri * 3 * fn), *at = malloc(sizeof *at * 3 * fn), *tet = malloc(sizeof *tet * fn);
    double worst = INFINITY;
    if (level_of && start && fill && tri && at && tet) {
        prep.tri = tri, prep.tet = tet;
        prep.phase = 2; /* at the offsets phase 1 left */
        tpk_parallel_for(lvl->tet_count, tpk_threads_for(lvl->tet_count, s->threads, 1 << 16), shell_prep_range,
                         &prep);
        for (int64_t i = 0; i < 3 * faces; i++)
            start[tri[i] + 1]++;
        for (int64_t v = 0; v < n; v++)
            start[v + 1] += start[v];
        memcpy(fill, start, sizeof *fill * (size_t)n);
        for (int64_t i = 0; i < 3 * faces; i++)
            at[fill[tri[i]]++] = (int32_t)(i / 3);
        fill_i32(level_of, m->vertex_count, -1, s->threads);
        prep.level_of = level_of;
        shell_prep_run(&prep, 4, n);
        worst = 0;
        /* from the owner (one of whose faces is p's witness), or without a tolerance the vertex p ended on */
        int32_t *owner = malloc(sizeof *owner * (size_t)m->vertex_count);
        if (owner) {
            fill_i32(owner, m->vertex_count, -1, s->threads);
            prep.owner = owner;
            shell_prep_run(&prep, 3, m->vertex_count);
        }
        shell_job job = {s, lvl, start, tri, at, tet, level_of, owner, near_tet, {0}};
        int threads = tpk_threads_for(m->vertex_count, s->threads, 1 << 14);
        tpk_parallel_for(m->vertex_count, threads, shell_vertices, &job);
        for (int w = 0; w < threads; w++) /* a maximum: the same whatever the split */
            worst = job.worst[w] > worst ? job.worst[w] : worst;
        free(owner);
    }
    free(level_of);
    free(start);
    free(fill);
    free(tri);
    free(at);
    free(tet);
    return worst;
}

/* The level's bytes from the file it was written into: mapped (r->mapped), else read into memory. 0 or -1. */
static int take_level_bytes(int fd, tpk_level *r)
{
    struct stat st;
    if (fstat(fd, &st) != 0 || st.st_size <= 0)
        return -1;
    r->size = (size_t)st.st_size;
    void *map = mmap(NULL, r->size, PROT_READ, MAP_SHARED, fd, 0);
    if (map != MAP_FAILED) {
        r->data = map;
        r->mapped = 1;
        return 0;
    }
    if ((r->data = malloc(r->size)) && pread(fd, r->data, r->size, 0) == (ssize_t)r->size)
        return 0;
    free(r->data);
    r->data = NULL;
    return -1;
}

/* Write the level through the converter's own writer into an unnamed file in memory (a memfd; a
 * temporary file where there is none), and take its bytes. A file on disk cost grid 200's first level
 * 0.4-0.65 s: the writer flushes what it writes (fsync), and the bytes were then copied into memory. */
static int write_level(const tpk_convert_options *o, const simplifier *s, domain_size full, int k,
                       const char *source_format, const tpk_convert_report *source, tpk_level *r, tpk_diag *diag)
{
    tpk_tetmesh lvl;
    int32_t *vertex_old = NULL, *neighbors = NULL;
    int rc = level_mesh(s, &lvl, &vertex_old, diag);
    if (rc == 0 && !(neighbors = malloc(sizeof *neighbors * 4 * (size_t)(lvl.tet_count ? lvl.tet_count : 1))))
        rc = tpk_diag_fail(diag, "levels: out of memory");
    /* The folds the full mesh had cut (--cut-folds: both faces are shell faces there) pair up again in
     * face matching: cut them again, as extract does. No collapse makes a new one (every changed tet is
     * positive inside the star it replaces, and no shell vertex moves in a mesh with folds); same_size below shows the
     * domain is the full mesh's. The face matching finds them as it pairs the faces (only pairs whose
     * orders agree get the exact test). */
    int64_t *slots = NULL, folds = 0;
    if (rc == 0)
        rc = tpk_connect_folds(lvl.tets, lvl.tet_count, lvl.vertex_count, lvl.points, neighbors, o->threads, &slots,
                               &folds, diag);
    if (rc == 0 && folds > 0)
        tpk_cut_folds(lvl.tets, neighbors, slots, folds);
    free(slots);
    if (rc == 0) {
        domain_size d = size_of(lvl.points, lvl.tets, neighbors, lvl.tet_count, s->threads);
        if (!same_size(full, d, s->shell_tolerance))
            rc = tpk_diag_fail(diag, "level %d: its volume %.17g and shell area %.17g are not the full mesh's %.17g and %.17g "
                               "(a bug in levels.c)", k, d.volume / 6, d.area / 2, full.volume / 6, full.area / 2);
    }
    FILE *tmp = NULL;
    int fd = -1;
#ifdef MFD_CLOEXEC
    if (rc == 0)
        fd = memfd_create("tetpack-level", MFD_CLOEXEC);
#endif
    if (rc == 0 && fd < 0 && (tmp = tmpfile()) != NULL)
        fd = fileno(tmp);
    if (rc == 0 && fd < 0)
        rc = tpk_diag_fail(diag, "level %d: cannot make a temporary file", k);
    if (rc == 0) {
        tpk_convert_options lo = *o;
        char name[64];
        snprintf(name, sizeof name, "level %d", k);
        lo.output = name;
        lo.output_fd = fd;
        tpk_header_fields hdr;
        memset(&hdr, 0, sizeof hdr);
        memcpy(hdr.origin, lvl.origin, sizeof hdr.origin);
        bounds_of(lvl.points, lvl.origin, lvl.vertex_count, s->threads, hdr.bounds_min, hdr.bounds_max);
        /* The file's report: its TMAP and VMAP number the file's source cells and points (spec §16.1),
         * and the pipeline and repairs that made the file made the mesh it was coarsened from; META
         * names them all, as a part's does */
        tpk_convert_report lrep = *source;
        lrep.vertices = lvl.vertex_count;
        lrep.tets = lvl.tet_count;
        rc = tpk_write_tpk(&lo, &lvl, neighbors, &hdr, &lrep, source_format, NULL, NULL, diag);
        if (rc == 0 && take_level_bytes(fd, r) != 0)
            rc = tpk_diag_fail(diag, "level %d: cannot read back its file", k);
    }
    if (tmp)
        fclose(tmp);
    else if (fd >= 0)
        close(fd);
    if (rc == 0) {
        r->vertices = lvl.vertex_count;
        r->tets = lvl.tet_count;
        int32_t *near_tet = malloc(sizeof *near_tet * (size_t)(s->mesh->vertex_count ? s->mesh->vertex_count : 1));
        if (near_tet)
            fill_i32(near_tet, s->mesh->vertex_count, -1, s->threads);
        r->shell_tolerance = s->shell_tolerance;
        /* Without a tolerance only flat pieces moved: the same surface, and every removed shell vertex on it */
        r->shell_distance = !(s->shell_tolerance > 0) ? 0
                            : near_tet ? shell_distance(s, &lvl, vertex_old, neighbors, near_tet) : INFINITY;
        measure(s, &lvl, vertex_old, neighbors, near_tet, r);
        free(near_tet);
    }
    free(neighbors);
    free(vertex_old);
    level_mesh_free(&lvl);
    return rc;
}

/* Each vertex's level_vertex, no chain, and the list of those alive (tpk_parallel_for: the first touch of
 * fresh pages on all threads too). */
static void set_up_vertices(void *ctx, int64_t begin, int64_t end, int worker)
{
    simplifier *s = ctx;
    (void)worker;
    for (int64_t v = begin; v < end; v++) {
        level_vertex *x = &s->vert[v];
        memcpy(x->p, s->mesh->points + 3 * (size_t)v, sizeof x->p);
        x->field = s->field ? s->field[v] : 0;
        x->seen = -1;
        s->chain_head[v] = s->chain_next[v] = -1;
        s->alive[v] = (int32_t)v;
    }
}

/* Each tet's corners, shape and origin, at the start (tpk_parallel_for over the tets: the first touch of
 * fresh pages, a third of the set-up on grid 200, goes on all threads too). */
static void set_up_tets(void *ctx, int64_t begin, int64_t end, int worker)
{
    simplifier *s = ctx;
    (void)worker;
    if (s->tets != s->mesh->tets) /* else they are the mesh's own (tpk_make_levels) */
        memcpy(s->tets + 4 * begin, s->mesh->tets + 4 * begin, sizeof *s->tets * 4 * (size_t)(end - begin));
    for (int64_t t = begin; t < end; t++) {
        const int32_t *v = s->mesh->tets + 4 * t;
        s->tet_quality[t] = (float)quality(point(s, v[0]), point(s, v[1]), point(s, v[2]), point(s, v[3]));
        s->origin[t] = (int32_t)t;
    }
}

/* The corners of the shell faces marked as on the shell (tpk_parallel_for over the tets; two workers may
 * mark one vertex, both with 1: relaxed atomic stores). */
typedef struct shell_marks {
    simplifier *s;
    const int32_t *neighbors;
} shell_marks;

static void mark_shell(void *ctx, int64_t begin, int64_t end, int worker)
{
    const shell_marks *j = ctx;
    const int32_t *tets = j->s->mesh->tets;
    (void)worker;
    for (int64_t t = begin; t < end; t++)
        for (int k = 0; k < 4; k++)
            if (j->neighbors[4 * t + k] < 0)
                for (int c = 0; c < 3; c++)
                    __atomic_store_n(&j->s->boundary[tets[4 * t + tpk_tet_faces[k][c]]], 1, __ATOMIC_RELAXED);
}

int tpk_make_levels(const tpk_convert_options *o, tpk_tetmesh *mesh, int32_t *neighbors, int count,
                    const char *source_format, const tpk_convert_report *source, tpk_levels *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    count = count > TPK_MAX_LEVELS ? TPK_MAX_LEVELS : count;
    simplifier s;
    memset(&s, 0, sizeof s);
    s.mesh = mesh;
    s.threads = tpk_thread_count(o->threads);
    int64_t V = mesh->vertex_count, T = mesh->tet_count;
    /* The field that steers the collapses and measures the error: the first point field, at its step of
     * widest range (a first step of a transient is often uniform). */
    const char *field_name = "";
    for (int f = 0; f < mesh->field_count && !s.field; f++) {
        const tpk_src_field *src = &mesh->fields[f];
        if (src->association != TPK_ASSOC_POINT || V == 0)
            continue;
        double widest = -1;
        for (int st = 0; st < src->step_count; st++) {
            const float *v = src->values + (size_t)st * (size_t)V;
            float lo = INFINITY, hi = -INFINITY;
            for (int64_t i = 0; i < V; i++)
                if (v[i] == v[i])
                    lo = v[i] < lo ? v[i] : lo, hi = v[i] > hi ? v[i] : hi;
            if (hi >= lo && hi - lo > widest) {
                widest = hi - lo;
                s.field = v;
                s.field_step = st;
            }
        }
        field_name = src->name;
    }
    s.boundary = calloc((size_t)(V ? V : 1), 1);
    s.pinned = calloc((size_t)(V ? V : 1), 1);
    s.chain_head = malloc(sizeof *s.chain_head * 2 * (size_t)(V ? V : 1));
    s.chain_next = s.chain_head ? s.chain_head + V : NULL;
    s.removed = calloc((size_t)(V ? V : 1), 1);
    s.onto = malloc(sizeof *s.onto * (size_t)(V ? V : 1));
    s.locked = calloc((size_t)(V ? V : 1), 1);
    s.dead = tpk_calloc_large((size_t)(T ? T : 1), 1);
    s.stuck = calloc((size_t)(V ? V : 1), 1);
    s.vert = tpk_alloc_large(sizeof *s.vert * (size_t)(V ? V : 1));
    s.active = malloc(sizeof *s.active * (size_t)(V ? V : 1));
    /* the arrays of the tets (a first touch of fresh pages costs about 0.75 ms a MB here): the mesh's
     * own tets become the working tets, and its neighbors, once read below, the stars (same size) */
    int scratch = T > 0 && mesh->tets && neighbors;
    s.tets = scratch ? mesh->tets : tpk_alloc_large(sizeof *s.tets * 4 * (size_t)(T ? T : 1));
    s.origin = tpk_alloc_large(sizeof *s.origin * (size_t)(T ? T : 1));
    s.star_start = tpk_alloc_large(sizeof *s.star_start * 2 * (size_t)(V ? V : 1));
    s.star_end = s.star_start ? s.star_start + V : NULL;
    s.alive = malloc(sizeof *s.alive * 2 * (size_t)(V ? V : 1));
    s.alive_next = s.alive ? s.alive + V : NULL;
    s.star = scratch ? neighbors : tpk_alloc_large(sizeof *s.star * 4 * (size_t)(T ? T : 1));
    s.tet_quality = tpk_alloc_large(sizeof *s.tet_quality * (size_t)(T ? T : 1));
    int rc = s.boundary && s.pinned && s.chain_head && s.removed && s.onto && s.locked && s.dead && s.stuck && s.vert && s.active && s.tets && s.origin && s.star_start && s.alive && s.star &&
                     s.tet_quality
                 ? 0 : tpk_diag_fail(diag, "levels: out of memory for %lld tets", (long long)T);
    if (rc == 0) {
        tpk_parallel_for(V, tpk_threads_for(V, s.threads, 1 << 16), set_up_vertices, &s);
        s.alive_count = V;
        tpk_parallel_for(T, tpk_threads_for(T, s.threads, 1 << 16), set_up_tets, &s);
        shell_marks marks = {&s, neighbors};
        tpk_parallel_for(T, tpk_threads_for(T, s.threads, 1 << 16), mark_shell, &marks);
        s.tet_count = T;
        /* Where a mesh folds (connect cut its folds: source->folds_cut), its tets overlap: it tiles no
         * domain, and a shell vertex that moves near the fold can make faces meet that should not (a
         * gmsh boundary-layer mesh did). Then no shell vertex moves. */
        if (source->folds_cut > 0)
            memcpy(s.pinned, s.boundary, (size_t)V);
    }
    domain_size full = rc == 0 ? size_of(mesh->points, mesh->tets, neighbors, T, s.threads) : (domain_size){0, 0};
    if (o->level_shell_error > 0 && V > 0) { /* a fraction of the bounding box diagonal */
        double lo[3], hi[3], diag = 0;
        bounds_of(mesh->points, NULL, V, s.threads, lo, hi);
        for (int a = 0; a < 3; a++)
            diag += (hi[a] - lo[a]) * (hi[a] - lo[a]);
        s.shell_tolerance = o->level_shell_error * sqrt(diag);
    }
    for (int k = 1; rc == 0 && k <= count; k++) {
        double t0 = tpk_now_seconds();
        int64_t before = s.tet_count;
        simplify_to(&s, before / TPK_LEVEL_RATIO);
        if (s.tet_count > before - before * 15 / 100) /* not coarser enough to be worth a level */
            break;
        tpk_level *r = &out->level[out->count];
        snprintf(r->field, sizeof r->field, "%s", field_name);
        r->field_step = s.field_step;
        rc = write_level(o, &s, full, k, source_format, source, r, diag);
        r->seconds = tpk_now_seconds() - t0;
        if (rc == 0)
            out->count++;
    }
    free(s.boundary);
    free(s.pinned);
    free(s.chain_head);
    free(s.removed);
    free(s.onto);
    free(s.locked);
    tpk_free_large(s.dead, (size_t)(T ? T : 1));
    free(s.stuck);
    tpk_free_large(s.vert, sizeof *s.vert * (size_t)(V ? V : 1));
    free(s.active);
    if (!scratch)
        tpk_free_large(s.tets, sizeof *s.tets * 4 * (size_t)(T ? T : 1));
    tpk_free_large(s.origin, sizeof *s.origin * (size_t)(T ? T : 1));
    tpk_free_large(s.star_start, sizeof *s.star_start * 2 * (size_t)(V ? V : 1));
    free(s.alive < s.alive_next ? s.alive : s.alive_next); /* the block both halves are in (build_stars swaps them) */
    if (!scratch)
        tpk_free_large(s.star, sizeof *s.star * 4 * (size_t)(T ? T : 1));
    tpk_free_large(s.tet_quality, sizeof *s.tet_quality * (size_t)(T ? T : 1));
    if (rc != 0)
        tpk_levels_free(out);
    return rc;
}

void tpk_levels_free(tpk_levels *levels)
{
    for (int i = 0; i < levels->count; i++)
        if (levels->level[i].mapped)
            munmap(levels->level[i].data, levels->level[i].size);
        else
            free(levels->level[i].data);
    memset(levels, 0, sizeof *levels);
}
