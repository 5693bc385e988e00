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
 *   distance is then measured at every removed shell vertex (levels_shell_distance()).
 * Without that the coarsest level of a large mesh would keep every shell face (a 48M-tet grid's 480k).
 *
 * Among the valid targets v the one whose field value is closest to u's is taken (the nearest without a
 * field): the field at the kept vertices is the full mesh's, exactly, and the error is what interpolation
 * over the coarser tets makes of it at the removed vertices, which is where it is measured.
 *
 * Passes: every vertex that may move, in id order, skipping the targets of this pass's collapses (the only
 * stars a collapse grows; the others only lose the tets it kills, which a star read leaves out), inside
 * fixed blocks of ids side by side first, until the level has a sixth of the tets of the last
 * (TPK_LEVEL_RATIO) or a pass removes almost nothing. The result does not depend on the thread count.
 *
 * This file is the driver: the set-up, the levels one by one, each extracted, checked, written and
 * measured. Each algorithm has a file of its own below it (levels_internal.h lists them). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/parallel.h"
#include "levels_internal.h"
#include "tetpack_format.h"
#include "pipeline.h"

/* Level k out of the simplifier's live tets: its tetmesh and neighbours (the folds the full mesh had cut,
 * cut again), its domain checked against the full mesh's, its file written (levels_memfd.c), and its
 * shell distance and field error measured. */
static int make_level(const tpk_convert_options *o, const simplifier *s, domain_size full, int k,
                      const char *source_format, const tpk_convert_report *source, tpk_level *r, tpk_diag *diag)
{
    tpk_tetmesh lvl;
    int32_t *vertex_old = NULL, *neighbors = NULL;
    int rc = levels_mesh(s, &lvl, &vertex_old, diag);
    if (rc == 0 && !(neighbors = malloc(sizeof *neighbors * 4 * (size_t)(lvl.tet_count ? lvl.tet_count : 1))))
        rc = tpk_diag_fail(diag, "levels: out of memory");
    /* The folds the full mesh had cut (--cut-folds: both faces are shell faces there) pair up again in
     * face matching: cut them again, as extract does. No collapse makes a new one (every changed tet is
     * positive inside the star it replaces, and no shell vertex moves in a mesh with folds);
     * levels_same_size below shows the domain is the full mesh's. The face matching finds them as it
     * pairs the faces (only pairs whose orders agree get the exact test). */
    int64_t *slots = NULL, folds = 0;
    if (rc == 0)
        rc = tpk_connect_folds(lvl.tets, lvl.tet_count, lvl.vertex_count, lvl.points, neighbors, o->threads, &slots,
                               &folds, diag);
    if (rc == 0 && folds > 0)
        tpk_cut_folds(lvl.tets, neighbors, slots, folds);
    free(slots);
    if (rc == 0) {
        domain_size d = levels_size_of(lvl.points, lvl.tets, neighbors, lvl.tet_count, s->threads);
        if (!levels_same_size(full, d, s->shell_tolerance))
            rc = tpk_diag_fail(diag, "level %d: its volume %.17g and shell area %.17g are not the full mesh's %.17g and %.17g "
                               "(a bug in levels.c)", k, d.volume / 6, d.area / 2, full.volume / 6, full.area / 2);
    }
    if (rc == 0)
        rc = levels_write_file(o, &lvl, neighbors, s->threads, k, source_format, source, r, diag);
    if (rc == 0) {
        r->vertices = lvl.vertex_count;
        r->tets = lvl.tet_count;
        int32_t *near_tet = malloc(sizeof *near_tet * (size_t)(s->mesh->vertex_count ? s->mesh->vertex_count : 1));
        if (near_tet)
            levels_fill_i32(near_tet, s->mesh->vertex_count, -1, s->threads);
        r->shell_tolerance = s->shell_tolerance;
        /* Without a tolerance only flat pieces moved: the same surface, and every removed shell vertex on it */
        r->shell_distance = !(s->shell_tolerance > 0) ? 0
                            : near_tet ? levels_shell_distance(s, &lvl, vertex_old, neighbors, near_tet) : INFINITY;
        levels_measure(s, &lvl, vertex_old, neighbors, near_tet, r);
        free(near_tet);
    }
    free(neighbors);
    free(vertex_old);
    levels_mesh_free(&lvl);
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
        s->tet_quality[t] = (float)levels_quality(point(s, v[0]), point(s, v[1]), point(s, v[2]), point(s, v[3]));
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
    /* the arrays of the tets (fresh pages cost a first touch: bench/README "Figures behind code comments"):
     * the mesh's own tets become the working tets, and its neighbors, once read below, the stars */
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
    domain_size full = rc == 0 ? levels_size_of(mesh->points, mesh->tets, neighbors, T, s.threads) : (domain_size){0, 0};
    if (o->level_shell_error > 0 && V > 0) { /* a fraction of the bounding box diagonal */
        double lo[3], hi[3], diag = 0;
        levels_bounds_of(mesh->points, NULL, V, s.threads, lo, hi);
        for (int a = 0; a < 3; a++)
            diag += (hi[a] - lo[a]) * (hi[a] - lo[a]);
        s.shell_tolerance = o->level_shell_error * sqrt(diag);
    }
    for (int k = 1; rc == 0 && k <= count; k++) {
        double t0 = tpk_now_seconds();
        int64_t before = s.tet_count;
        levels_simplify_to(&s, before / TPK_LEVEL_RATIO);
        if (s.tet_count > before - before * 15 / 100) /* not coarser enough to be worth a level */
            break;
        tpk_level *r = &out->level[out->count];
        snprintf(r->field, sizeof r->field, "%s", field_name);
        r->field_step = s.field_step;
        rc = make_level(o, &s, full, k, source_format, source, r, diag);
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
