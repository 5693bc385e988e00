/* The shell checks: 303 nonconforming_face and 406 shell_self_intersection from the exact face pairs of
 * check_shell_cgal.cpp, then the combinatorial 401..405 (check_topo_shell_edges.c).
 *
 * The shell is every face of exactly one cell. Geometric tests cut quads into the two triangles of the
 * diagonal through their smallest id (as the converter does); combinatorial tests keep quads as quads.
 * A nonconforming interface (hanging nodes, a quad against two triangles) leaves its faces in the shell:
 * they are counted once, as 303, and the cells on either side are joined for the component count. */
#include <stdlib.h>
#include <string.h>

#include "check_topo.h"
#include "base/parallel.h"

static void shell_face_as_topo(const tpk_bface *s, tpk_topo_face *f)
{
    f->n = tpk_bface_n(s);
    memcpy(f->v, s->v, sizeof f->v);
}

static void face_centre(const tpk_mesh *mesh, const tpk_bface *s, double out[3])
{
    tpk_topo_face f;
    shell_face_as_topo(s, &f);
    tpk_topo_face_centre(mesh, &f, out);
}

/* 303: every shell face that lies against a face of another cell, in shell order. */
static void report_nonconforming(const tpk_mesh *mesh, tpk_topo_match *m, const tpk_shell_pair *pairs,
                                 int64_t pair_count, tpk_check_report *report, int64_t *partner)
{
    for (int64_t f = 0; f < m->shell_count; f++)
        partner[f] = -1;
    for (int64_t i = 0; i < pair_count; i++) {
        if (pairs[i].kind != TPK_PAIR_NONCONFORMING)
            continue;
        const tpk_shell_pair *p = &pairs[i];
        tpk_uf_union(m->parent, m->shell[p->a].cell, m->shell[p->b].cell);
        if (partner[p->a] < 0)
            partner[p->a] = p->b;
        if (partner[p->b] < 0)
            partner[p->b] = p->a;
    }
    for (int64_t f = 0; f < m->shell_count; f++) {
        if (partner[f] < 0)
            continue;
        const tpk_bface *s = &m->shell[f], *o = &m->shell[partner[f]];
        tpk_example *ex = tpk_check_hit(report, 303, "face");
        int64_t ids[TPK_CHECK_MAX_IDS];
        int n = tpk_bface_n(s);
        for (int i = 0; i < n; i++)
            ids[i] = s->v[i];
        ids[n] = s->cell;
        ids[n + 1] = o->cell;
        tpk_example_ids(ex, n + 2, ids);
        double centre[3];
        face_centre(mesh, s, centre);
        tpk_example_point(ex, centre);
        tpk_example_note(ex, "boundary face of cell %u lies against a face of cell %u with other vertices "
                         "(coplanar, facing it, overlapping); ids: the face, then the two cells",
                         s->cell, o->cell);
    }
}

/* 406: pairs of faces that share no vertex and intersect; a pair that is also 303 counts there only. */
static void report_intersections(const tpk_mesh *mesh, const tpk_topo_match *m, const tpk_shell_pair *pairs,
                                 int64_t pair_count, tpk_check_report *report)
{
    for (int64_t i = 0; i < pair_count; i++) {
        const tpk_shell_pair *p = &pairs[i];
        if (p->kind != TPK_PAIR_INTERSECTING ||
            (i > 0 && pairs[i - 1].a == p->a && pairs[i - 1].b == p->b))
            continue;
        const tpk_bface *s = &m->shell[p->a], *o = &m->shell[p->b];
        tpk_example *ex = tpk_check_hit(report, 406, "face");
        int64_t ids[TPK_CHECK_MAX_IDS];
        int n = 0;
        for (int i2 = 0; i2 < tpk_bface_n(s); i2++)
            ids[n++] = s->v[i2];
        for (int i2 = 0; i2 < tpk_bface_n(o); i2++)
            ids[n++] = o->v[i2];
        tpk_example_ids(ex, n, ids);
        double centre[3];
        face_centre(mesh, s, centre);
        tpk_example_point(ex, centre);
        tpk_example_note(ex, "shell faces of cells %u and %u intersect and share no vertex; ids: the two "
                         "faces' vertices", s->cell, o->cell);
    }
}

int tpk_check_shell(const tpk_mesh *mesh, tpk_topo_match *m, tpk_check_report *report, tpk_diag *diag)
{
    tpk_shell_pair *pairs = NULL;
    int64_t pair_count = 0;
    int64_t *partner = malloc(sizeof *partner * (size_t)(m->shell_count ? m->shell_count : 1));
    int threads = tpk_thread_count(report->options.threads);
    if (!partner || tpk_shell_face_pairs(mesh->points, m->shell, m->shell_count,
                                         !report->options.skip_shell_intersections, threads, &pairs, &pair_count)) {
        free(partner);
        return tpk_diag_fail(diag, "check: out of memory (shell intersections, %lld faces)",
                             (long long)m->shell_count);
    }
    tpk_check_progress(report, "shell", 0.5);
    report_nonconforming(mesh, m, pairs, pair_count, report, partner);
    report_intersections(mesh, m, pairs, pair_count, report);
    free(pairs);
    free(partner);
    int rc = tpk_check_shell_edges(mesh, m, report, diag);
    tpk_check_progress(report, "shell", 1.0);
    return rc;
}
