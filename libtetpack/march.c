/* The reference CPU marcher: watertight tet-to-tet marching in double precision over Tet32, Tet20 or
 * Tet16 records, started from the shell entry faces the BVH finds (docs/ARCHITECTURE.md §5, §6). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_march.h"

/* ---- Marcher lifetime -------------------------------------------------------------------------- */

static int shell_face_ok(const tpk_shell_face *s, int64_t vertex_count, int64_t tet_count)
{
    return s->a >= 0 && s->a < vertex_count && s->b >= 0 && s->b < vertex_count && s->c >= 0 &&
           s->c < vertex_count && s->a != s->b && s->b != s->c && s->a != s->c && s->t >= 0 &&
           s->t < tet_count;
}

tpk_result tpk_marcher_create(tpk_marcher **out, const tpk_mesh_arrays *mesh)
{
    if (!out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!mesh)
        return TPK_ERR_INVALID_ARGUMENT;
    if (mesh->vertex_count > 0x7fffffffu || mesh->tet_count > 0x7fffffffu ||
        mesh->shell_face_count > 0x7fffffffu)
        return TPK_ERR_LIMIT;
    const void *records = mesh->layout == TPK_LAYOUT_TET32   ? (const void *)mesh->tet32
                          : mesh->layout == TPK_LAYOUT_TET20 ? (const void *)mesh->tet20
                          : mesh->layout == TPK_LAYOUT_TET16 ? (const void *)mesh->tet16
                                                             : NULL;
    if ((mesh->tet_count > 0 && !records) || (mesh->vertex_count > 0 && !mesh->positions) ||
        (mesh->shell_face_count > 0 && !mesh->shell))
        return TPK_ERR_INVALID_ARGUMENT;
    if (mesh->layout != TPK_LAYOUT_TET32 && mesh->layout != TPK_LAYOUT_TET20 &&
        mesh->layout != TPK_LAYOUT_TET16)
        return TPK_ERR_INVALID_ARGUMENT;
    for (uint64_t i = 0; i < mesh->shell_face_count; i++)
        if (!shell_face_ok(&mesh->shell[i], (int64_t)mesh->vertex_count, (int64_t)mesh->tet_count))
            return TPK_ERR_MESH;

    tpk_marcher *m = calloc(1, sizeof *m);
    if (!m)
        return TPK_ERR_OUT_OF_MEMORY;
    m->mesh = *mesh;
    if (pthread_mutex_init(&m->shell_lock, NULL) != 0) {
        free(m);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    tpki_shell_prepare(m); /* the BVH itself on its first use */
    *out = m;
    return TPK_OK;
}

void tpk_marcher_destroy(tpk_marcher *m)
{
    if (!m)
        return;
    free(m->nodes);
    free(m->faces);
    pthread_mutex_destroy(&m->shell_lock);
    free(m);
}

tpk_result tpk_marcher_set_scalars(tpk_marcher *m, const float *scalars)
{
    if (!m)
        return TPK_ERR_INVALID_ARGUMENT;
    m->mesh.scalars = scalars; /* the shell BVH and extent depend on positions and shell alone */
    return TPK_OK;
}

void tpk_marcher_shell_bvh(const tpk_marcher *m, tpk_shell_bvh *out)
{
    memset(out, 0, sizeof *out);
    if (!m || tpki_shell_ready(m) != TPK_OK)
        return;
    out->nodes = m->nodes;
    out->node_count = m->node_count;
    out->faces = m->faces;
    out->face_count = m->face_count;
    out->extent = m->extent;
}

/* ---- One inside-run: from a shell entry face to a face with neighbor -1 -------------------------- */

static inline double face_scalar(const float *scalars, const tpk_face_hit *h, int first, const double w[3])
{
    if (!scalars)
        return 0.0;
    return tpk_face_sum(first, w, (const double[3]){scalars[h->v[0]], scalars[h->v[1]], scalars[h->v[2]]});
}

static inline int rank4(int32_t x, int32_t a, int32_t b, int32_t c, int32_t d)
{
    return (a < x) + (b < x) + (c < x) + (d < x);
}

/* Report the piece [t_in, t_out] of `tet` clipped to [tmin, tmax]; sets p->stop when done. */
static inline void report(march_params *p, int32_t tet, const int32_t v[4], double t_in, double t_out,
                          double s_in, double s_out)
{
    if (t_out < p->tmin)
        return;
    tpk_segment seg = {tet, t_in, t_out, s_in, s_out, {v[0], v[1], v[2], v[3]}};
    double len = t_out - t_in;
    if (t_in < p->tmin) {
        seg.t_in = p->tmin;
        seg.scalar_in = s_in + (s_out - s_in) * ((p->tmin - t_in) / len);
    }
    if (t_out > p->tmax) {
        seg.t_out = p->tmax;
        seg.scalar_out = s_in + (s_out - s_in) * ((p->tmax - t_in) / len);
    }
    if (p->fn && p->fn(p->user, &seg))
        p->stop = 1;
    if (t_out >= p->tmax)
        p->stop = 1;
}

/* `layout` is a constant at each call site, so each layout gets its own specialised loop. */
static inline __attribute__((always_inline)) tpk_result march_run(march_params *p, tpk_face_hit in,
                                                                  int32_t tet, const int layout)
{
    const tpk_mesh_arrays *mesh = &p->m->mesh;
    const float *pos = mesh->positions;
    const int64_t tet_count = (int64_t)mesh->tet_count, vertex_count = (int64_t)mesh->vertex_count;
    const int s = -1; /* entry and exit faces are ordered so that all their edge functions are < 0 */
    double w[3];
    int first = tpk_face_first(&in);
    tpk_face_weights(&in, first, w);
    double s_in = face_scalar(mesh->scalars, &in, first, w);
    int32_t prev = -1;

    for (int64_t step = 0;; step++) {
        if (step >= tet_count)
            return TPK_ERR_MESH; /* a cycle: watertight marching never revisits a tet */
        p->steps++;
        if (in.t > p->tmax) {
            p->stop = 1;
            return TPK_OK;
        }
        const int32_t a = in.v[0], b = in.v[1], c = in.v[2];
        int32_t vx;
        if (layout == TPK_LAYOUT_TET32)
            vx = mesh->tet32[tet].vx;
        else if (layout == TPK_LAYOUT_TET20)
            vx = mesh->tet20[tet].vx;
        else
            vx = mesh->tet16[tet].vx;
        const int32_t d = vx ^ a ^ b ^ c;
        if (d < 0 || d >= vertex_count || d == a || d == b || d == c)
            return TPK_ERR_MESH;
        int32_t n3 = 0;
        if (layout == TPK_LAYOUT_TET16) {
            /* n[rank of d] is the tet we came from; that gives n[3], hence every n[r]. */
            int rp = (a < d) + (b < d) + (c < d);
            n3 = rp == 3 ? prev : (mesh->tet16[tet].nx[rp] ^ prev);
        }

        const tpk_proj pd = tpk_project(pos, p->frame, d);
        double va, vb, vc;
        const int sa = tpk_edge_sign(a, &in.p[0], d, &pd, &va);
        const int sb = tpk_edge_sign(b, &in.p[1], d, &pd, &vb);
        const int sc = tpk_edge_sign(c, &in.p[2], d, &pd, &vc);
        tpk_face_hit out;
        int32_t opposite;
        if (sb == s && sa == -s) {
            out = (tpk_face_hit){{a, b, d}, {in.p[0], in.p[1], pd}, {in.e[0], vb, -va}, 0.0};
            opposite = c;
        } else if (sc == s && sb == -s) {
            out = (tpk_face_hit){{b, c, d}, {in.p[1], in.p[2], pd}, {in.e[1], vc, -vb}, 0.0};
            opposite = a;
        } else if (sa == s && sc == -s) {
            out = (tpk_face_hit){{c, a, d}, {in.p[2], in.p[0], pd}, {in.e[2], va, -vc}, 0.0};
            opposite = b;
        } else {
            return TPK_ERR_MESH; /* impossible with exact signs; kept as a guard */
        }
        const int in_first = first;
        first = tpk_face_first(&out);
        tpk_face_weights(&out, first, w);
        double t_out = tpk_face_sum(first, w, (const double[3]){out.p[0].z, out.p[1].z, out.p[2].z});
        if (!(t_out >= in.t))
            t_out = in.t; /* rounding (or NaN from hostile positions): keep the chain monotone */
        out.t = t_out;
        const double s_out = face_scalar(mesh->scalars, &out, first, w);

        int32_t next;
        if (layout == TPK_LAYOUT_TET32) {
            const tpk_tet32 *r = &mesh->tet32[tet];
            int32_t v3 = r->vx ^ r->v[0] ^ r->v[1] ^ r->v[2];
            int k = opposite == r->v[0] ? 0 : opposite == r->v[1] ? 1 : opposite == r->v[2] ? 2
                  : opposite == v3      ? 3
                                        : -1;
            if (k < 0)
                return TPK_ERR_MESH;
            next = r->n[k];
        } else {
            int r = rank4(opposite, a, b, c, d);
            if (layout == TPK_LAYOUT_TET20)
                next = mesh->tet20[tet].n[r];
            else
                next = r == 3 ? n3 : (mesh->tet16[tet].nx[r] ^ n3);
        }
        if (next < -1 || next >= tet_count)
            return TPK_ERR_MESH;

        /* the entry face from its smallest id on (the segment's v[0..2], for gradients: path-independent) */
        const int32_t verts[4] = {in.v[in_first], in.v[tpk_face_corner[in_first + 1]],
                                  in.v[tpk_face_corner[in_first + 2]], d};
        report(p, tet, verts, in.t, t_out, s_in, s_out);
        if (next < 0) {
            p->exit_t = t_out;
            p->exit_tet = tet;
            p->exit_face = out;
        }
        if (p->stop || next < 0)
            return TPK_OK;
        prev = tet;
        tet = next;
        in = out;
        s_in = s_out;
    }
}

tpk_result tpki_march_run(march_params *p, const tpk_face_hit *in, int32_t tet)
{
    switch (p->m->mesh.layout) {
    case TPK_LAYOUT_TET32: return march_run(p, *in, tet, TPK_LAYOUT_TET32);
    case TPK_LAYOUT_TET20: return march_run(p, *in, tet, TPK_LAYOUT_TET20);
    case TPK_LAYOUT_TET16: return march_run(p, *in, tet, TPK_LAYOUT_TET16);
    }
    return TPK_ERR_INVALID_ARGUMENT;
}

/* ---- A whole ray --------------------------------------------------------------------------------- */

#define ENTRY_STACK 64

/* March the run that starts at entries[k]. */
static tpk_result run_entry(march_params *p, const tpk_entry *entry)
{
    const tpk_marcher *m = p->m;
    const tpk_shell_face *face = &m->faces[entry->face];
    tpk_face_hit hit;
    if (!tpki_shell_face_entry(m->mesh.positions, p->frame, face, &hit))
        return TPK_ERR_MESH; /* the same test said yes a moment ago: cannot happen */
    return tpki_march_run(p, &hit, face->t);
}

/* Several runs entering at (nearly) the same t meet at one shell vertex or edge, where rounding may
 * sort their entries in either order. In the perturbed geometry at most one of them has positive
 * length and the others are points before it, so they are marched (without reporting) to learn where
 * they leave, and reported in order of exit t: pieces stay in increasing t up to rounding. */
typedef struct tie_run {
    double exit_t;
    int64_t index;
} tie_run;

static int tie_run_compare(const void *x, const void *y)
{
    const tie_run *a = x, *b = y;
    if (a->exit_t != b->exit_t)
        return a->exit_t < b->exit_t ? -1 : 1;
    return (a->index > b->index) - (a->index < b->index);
}

static tpk_result run_tie_group(march_params *p, const tpk_entry *group, int64_t n, uint64_t *runs)
{
    tie_run small[16];
    tie_run *order = n <= 16 ? small : malloc((size_t)n * sizeof *order);
    if (!order)
        return TPK_ERR_OUT_OF_MEMORY;
    tpk_result r = TPK_OK;
    for (int64_t i = 0; i < n && r == TPK_OK; i++) {
        march_params dry = {.m = p->m, .frame = p->frame, .tmin = -INFINITY, .tmax = INFINITY, .exit_t = group[i].t,
                            .exit_tet = -1};
        r = run_entry(&dry, &group[i]);
        p->steps += dry.steps;
        order[i] = (tie_run){dry.exit_t, i};
    }
    if (r == TPK_OK)
        qsort(order, (size_t)n, sizeof *order, tie_run_compare);
    for (int64_t i = 0; i < n && r == TPK_OK && !p->stop; i++) {
        (*runs)++;
        r = run_entry(p, &group[order[i].index]);
    }
    if (order != small)
        free(order);
    return r;
}

tpk_result tpk_march_ray(const tpk_marcher *m, const double org[3], const double dir[3], double tmin,
                         double tmax, tpk_segment_fn fn, void *user, tpk_march_stats *stats)
{
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!m || !org || !dir || isnan(tmin) || isnan(tmax))
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_ray_frame frame;
    if (tpki_ray_frame_init(&frame, m->mesh.origin, org, dir) != 0)
        return TPK_ERR_INVALID_ARGUMENT;
    if (tmax < tmin || m->face_count == 0)
        return TPK_OK;

    tpk_entry stack_entries[ENTRY_STACK];
    tpk_entry *entries = NULL;
    int64_t entry_count = 0;
    tpk_result r = tpki_shell_entries(m, &frame, dir, tmin, tmax, stack_entries, ENTRY_STACK, &entries,
                                     &entry_count);
    if (r != TPK_OK)
        return r;

    march_params p = {.m = m, .frame = &frame, .tmin = tmin, .tmax = tmax, .fn = fn, .user = user, .exit_tet = -1};
    uint64_t runs = 0;
    /* Entries closer than rounding of t can order wrongly; see run_tie_group. */
    double dir_len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double reach = m->extent + fabs(frame.org[0]) + fabs(frame.org[1]) + fabs(frame.org[2]);
    double tie_tol = 1e-12 * reach / dir_len;
    for (int64_t k = 0; k < entry_count && !p.stop && r == TPK_OK; k++) {
        if (entries[k].t > tmax)
            break;
        int64_t end = k + 1;
        while (end < entry_count && entries[end].t - entries[end - 1].t <= tie_tol)
            end++;
        if (end - k > 1) {
            r = run_tie_group(&p, &entries[k], end - k, &runs);
            k = end - 1;
        } else {
            runs++;
            r = run_entry(&p, &entries[k]);
        }
    }
    if (entries != stack_entries)
        free(entries);
    if (stats) {
        stats->tet_steps = p.steps;
        stats->shell_entries = runs;
    }
    return r;
}
