/* The shell checks: 303 nonconforming_face and 406 shell_self_intersection from the exact face pairs of
 * check_shell_cgal.cpp, then the combinatorial 401..405 (check_topo_shell_edges.c).
 *
 * The shell is every face of exactly one cell. Geometric tests cut quads into the two triangles of the
 * diagonal through their smallest id (as the converter does), and the faces of polyhedra and polygons
 * of more than 4 vertices about their centre (as OpenFOAM does: check_topo_match.c's centre_cut);
 * findings name the source face, and two source faces with a common vertex never make a 406.
 * Combinatorial tests keep quads as quads.
 * A nonconforming interface (hanging nodes, a quad against two triangles) leaves its faces in the shell:
 * they are counted once, as 303; the components (304) stay face-connected, as checkMesh's regions, and
 * its summary says how many the interface joins. */
#include <stdlib.h>
#include <string.h>

#include "check_topo.h"
#include "base/parallel.h"

static void shell_face_as_topo(const tpk_bface *s, tpk_topo_face *f)
{
    f->n = tpk_bface_n(s);
    memcpy(f->v, s->v, sizeof s->v);
}

static void face_centre(const tpk_topo_match *m, const tpk_bface *s, double out[3])
{
    tpk_topo_face f;
    shell_face_as_topo(s, &f);
    tpk_topo_face_centre(m->points, &f, out);
}

/* The mesh's own face behind a shell face: itself, or the polygon a centre cut made it from (its
 * triangles hold the centre, an id past the mesh's points). */
static void source_face(const tpk_mesh *mesh, const tpk_bface *s, tpk_topo_face *f)
{
    if (s->v[0] >= mesh->point_count)
        tpk_topo_cell_face(mesh, s->cell, (int)s->local, f);
    else
        shell_face_as_topo(s, f);
}

static int share_vertex(const tpk_topo_face *a, const tpk_topo_face *b)
{
    for (int i = 0; i < a->n; i++)
        for (int j = 0; j < b->n; j++)
            if (a->v[i] == b->v[j])
                return 1;
    return 0;
}

/* first[f]: the first shell face of the same source face (a centre cut's triangles are consecutive). */
static void source_starts(const tpk_topo_match *m, int64_t *first)
{
    for (int64_t f = 0; f < m->shell_count; f++) {
        const tpk_bface *s = &m->shell[f], *p = f ? &m->shell[f - 1] : NULL;
        first[f] = p && p->cell == s->cell && p->local == s->local ? first[f - 1] : f;
    }
}

/* Up to `cap` ids: the source face's vertices. */
static int face_ids(const tpk_mesh *mesh, const tpk_bface *s, int64_t *ids, int cap)
{
    tpk_topo_face f;
    source_face(mesh, s, &f);
    int n = 0;
    for (int i = 0; i < f.n && n < cap; i++)
        ids[n++] = f.v[i];
    return n;
}

/* 303: every source face of the shell that lies against a face of another cell, in shell order. */
static void report_nonconforming(const tpk_mesh *mesh, tpk_topo_match *m, const tpk_shell_pair *pairs,
                                 int64_t pair_count, tpk_check_report *report, int64_t *partner,
                                 const int64_t *first)
{
    for (int64_t f = 0; f < m->shell_count; f++)
        partner[f] = -1;
    for (int64_t i = 0; i < pair_count; i++) {
        if (pairs[i].kind != TPK_PAIR_NONCONFORMING)
            continue;
        const tpk_shell_pair *p = &pairs[i];
        tpk_uf_union(m->parent, m->shell[p->a].cell, m->shell[p->b].cell);
        if (partner[first[p->a]] < 0)
            partner[first[p->a]] = p->b;
        if (partner[first[p->b]] < 0)
            partner[first[p->b]] = p->a;
    }
    for (int64_t f = 0; f < m->shell_count; f++) {
        if (partner[f] < 0)
            continue;
        const tpk_bface *s = &m->shell[f], *o = &m->shell[partner[f]];
        tpk_example *ex = tpk_check_hit(report, 303, "face");
        int64_t ids[TPK_CHECK_MAX_IDS];
        int n = face_ids(mesh, s, ids, TPK_CHECK_MAX_IDS - 2);
        ids[n] = s->cell;
        ids[n + 1] = o->cell;
        tpk_example_ids(ex, n + 2, ids);
        double centre[3];
        face_centre(m, s, centre);
        tpk_example_point(ex, centre);
        tpk_example_note(ex, "boundary face of cell %u lies against a face of cell %u with other vertices "
                         "(coplanar, facing it, overlapping); ids: the face, then the two cells",
                         s->cell, o->cell);
    }
}

static int cmp_pair(const void *x, const void *y)
{
    const int64_t *a = x, *b = y;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

/* 406: pairs of source faces that share no vertex and intersect, each once; a pair that is also 303
 * counts there only. Returns -1 when out of memory. */
static int report_intersections(const tpk_mesh *mesh, const tpk_topo_match *m, const tpk_shell_pair *pairs,
                                int64_t pair_count, tpk_check_report *report, const int64_t *first)
{
    int64_t (*found)[2] = malloc(sizeof *found * (size_t)(pair_count ? pair_count : 1));
    if (!found)
        return -1;
    int64_t n_found = 0;
    for (int64_t i = 0; i < pair_count; i++) {
        const tpk_shell_pair *p = &pairs[i];
        if (p->kind != TPK_PAIR_INTERSECTING || (i > 0 && pairs[i - 1].a == p->a && pairs[i - 1].b == p->b))
            continue;
        tpk_topo_face fa, fb;
        source_face(mesh, &m->shell[p->a], &fa);
        source_face(mesh, &m->shell[p->b], &fb);
        if (share_vertex(&fa, &fb)) /* the triangles of two cut faces that meet at a corner or an edge */
            continue;
        found[n_found][0] = first[p->a];
        found[n_found++][1] = first[p->b];
    }
    if (n_found > 1)
        qsort(found, (size_t)n_found, sizeof *found, cmp_pair);
    for (int64_t i = 0; i < n_found; i++) {
        if (i > 0 && found[i][0] == found[i - 1][0] && found[i][1] == found[i - 1][1])
            continue;
        const tpk_bface *s = &m->shell[found[i][0]], *o = &m->shell[found[i][1]];
        tpk_example *ex = tpk_check_hit(report, 406, "face");
        int64_t ids[TPK_CHECK_MAX_IDS];
        int n = face_ids(mesh, s, ids, TPK_CHECK_MAX_IDS / 2);
        n += face_ids(mesh, o, ids + n, TPK_CHECK_MAX_IDS - n);
        tpk_example_ids(ex, n, ids);
        double centre[3];
        face_centre(m, s, centre);
        tpk_example_point(ex, centre);
        tpk_example_note(ex, "shell faces of cells %u and %u intersect and share no vertex; ids: the two "
                         "faces' vertices", s->cell, o->cell);
    }
    free(found);
    return 0;
}

int tpk_check_shell(const tpk_mesh *mesh, tpk_topo_match *m, tpk_check_report *report, tpk_diag *diag)
{
    tpk_shell_pair *pairs = NULL;
    int64_t pair_count = 0;
    size_t faces = (size_t)(m->shell_count ? m->shell_count : 1);
    int64_t *partner = malloc(sizeof *partner * faces), *first = malloc(sizeof *first * faces);
    int threads = tpk_thread_count(report->options.threads);
    if (!partner || !first ||
        tpk_shell_face_pairs(m->points, m->shell, m->shell_count, !report->options.skip_shell_intersections, threads,
                             &pairs, &pair_count)) {
        free(partner);
        free(first);
        return tpk_diag_fail(diag, "check: out of memory (shell intersections, %lld faces)",
                             (long long)m->shell_count);
    }
    tpk_check_progress(report, "shell", 0.5);
    source_starts(m, first);
    report_nonconforming(mesh, m, pairs, pair_count, report, partner, first);
    int rc = report_intersections(mesh, m, pairs, pair_count, report, first);
    free(pairs);
    free(partner);
    free(first);
    if (rc != 0)
        return tpk_diag_fail(diag, "check: out of memory (shell intersections, %lld faces)",
                             (long long)m->shell_count);
    rc = tpk_check_shell_edges(m, report, diag);
    tpk_check_progress(report, "shell", 1.0);
    return rc;
}
