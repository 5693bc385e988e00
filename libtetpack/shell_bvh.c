/* The BVH over shell faces (binned SAH) and the search for the shell faces where a ray's line enters
 * the volume: the starting points of the marcher's inside-runs (docs/ARCHITECTURE.md §6). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_march.h"

int tpki_shell_face_entry(const float *positions, const tpk_ray_frame *frame, const tpk_shell_face *face,
                         tpk_face_hit *hit)
{
    hit->v[0] = face->a;
    hit->v[1] = face->b;
    hit->v[2] = face->c;
    hit->p[0] = tpk_project(positions, frame, face->a);
    hit->p[1] = tpk_project(positions, frame, face->b);
    /* Outward winding: the line enters where all three edge functions are negative. */
    if (tpk_edge_sign(face->a, &hit->p[0], face->b, &hit->p[1], &hit->e[0]) > 0)
        return 0;
    hit->p[2] = tpk_project(positions, frame, face->c);
    if (tpk_edge_sign(face->b, &hit->p[1], face->c, &hit->p[2], &hit->e[1]) > 0)
        return 0;
    if (tpk_edge_sign(face->c, &hit->p[2], face->a, &hit->p[0], &hit->e[2]) > 0)
        return 0;
    double w[3];
    int first = tpk_face_first(hit);
    tpk_face_weights(hit, first, w);
    hit->t = tpk_face_sum(first, w, (const double[3]){hit->p[0].z, hit->p[1].z, hit->p[2].z});
    return 1;
}

/* ---- Build --------------------------------------------------------------------------------------- */

/* Bounds of a face in float, rounded outward and padded by `pad`. */
static void face_bounds(const float *pos, const tpk_shell_face *f, double pad, tpki_bvh_item *it)
{
    const int32_t v[3] = {f->a, f->b, f->c};
    for (int k = 0; k < 3; k++) {
        double lo = DBL_MAX, hi = -DBL_MAX, sum = 0.0;
        for (int i = 0; i < 3; i++) {
            double x = pos[3 * (int64_t)v[i] + k];
            lo = fmin(lo, x);
            hi = fmax(hi, x);
            sum += x;
        }
        it->lo[k] = nextafterf((float)(lo - pad), -FLT_MAX);
        it->hi[k] = nextafterf((float)(hi + pad), FLT_MAX);
        it->centroid[k] = (float)(sum / 3.0);
    }
}

/* Box padding: the edge tests use 2-D coordinates rounded relative to the ray origin, so a crossing may be
 * reported a few ulps of the coordinates outside the exact triangle; the boxes are padded far beyond
 * that (1e-6 of the mesh extent plus the positions' magnitude), and never culled by the box test. */
static double positions_extent(const float *pos, int64_t vertex_count)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (int64_t i = 0; i < vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = pos[3 * i + k];
            if (isfinite(x)) {
                lo[k] = fmin(lo[k], x);
                hi[k] = fmax(hi[k], x);
            }
        }
    double size = 0.0;
    for (int k = 0; k < 3; k++)
        if (hi[k] >= lo[k])
            size = fmax(size, fmax(hi[k] - lo[k], fmax(fabs(lo[k]), fabs(hi[k]))));
    return size;
}

void tpki_shell_prepare(tpk_marcher *m)
{
    m->face_count = (int64_t)m->mesh.shell_face_count;
    m->extent = positions_extent(m->mesh.positions, (int64_t)m->mesh.vertex_count);
}

static tpk_result shell_bvh_build(tpk_marcher *m)
{
    const tpk_mesh_arrays *mesh = &m->mesh;
    const int32_t n = (int32_t)mesh->shell_face_count;
    if (n == 0)
        return TPK_OK;
    tpki_bvh_item *items = malloc((size_t)n * sizeof *items);
    m->nodes = malloc((size_t)(2 * (int64_t)n) * sizeof *m->nodes);
    m->faces = malloc((size_t)n * sizeof *m->faces);
    if (!items || !m->nodes || !m->faces) {
        free(items);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    const double pad = m->extent > 0 ? m->extent * 1e-6 : 1e-30;
    for (int32_t i = 0; i < n; i++) {
        face_bounds(mesh->positions, &mesh->shell[i], pad, &items[i]);
        items[i].id = i;
    }

    int32_t node_count = 0;
    tpk_result r = tpki_bvh_build(items, n, TPK_BVH_LEAF_SIZE, m->nodes, &node_count);
    if (r != TPK_OK) {
        free(items);
        return r;
    }
    m->node_count = node_count;
    for (int32_t i = 0; i < n; i++)
        m->faces[i] = mesh->shell[items[i].id];
    free(items);
    return TPK_OK;
}

tpk_result tpki_shell_ready(const tpk_marcher *marcher)
{
    tpk_marcher *m = (tpk_marcher *)marcher; /* the BVH is a cache of what the shell holds */
    if (__atomic_load_n(&m->shell_built, __ATOMIC_ACQUIRE))
        return m->shell_result;
    pthread_mutex_lock(&m->shell_lock);
    if (!m->shell_built) {
        m->shell_result = shell_bvh_build(m);
        __atomic_store_n(&m->shell_built, 1, __ATOMIC_RELEASE);
    }
    pthread_mutex_unlock(&m->shell_lock);
    return m->shell_result;
}

/* ---- Query --------------------------------------------------------------------------------------- */

/* Does the line org + t dir meet the box for some t in [t_low, tmax]? */
static inline int box_hit(const tpk_bvh_node *node, const double org[3], const double dir[3],
                          const double inv[3], double t_low, double tmax)
{
    double tn = -INFINITY, tf = tmax;
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0.0) {
            if (org[k] < node->lo[k] || org[k] > node->hi[k])
                return 0;
            continue;
        }
        double t0 = (node->lo[k] - org[k]) * inv[k];
        double t1 = (node->hi[k] - org[k]) * inv[k];
        if (t0 > t1) {
            double s = t0;
            t0 = t1;
            t1 = s;
        }
        tn = t0 > tn ? t0 : tn; /* not fmin/fmax: those are libm calls at -O2 */
        tf = t1 < tf ? t1 : tf;
    }
    return tn <= tf && tf >= t_low;
}

static int entry_less(const tpk_entry *x, const tpk_entry *y)
{
    return x->t < y->t || (x->t == y->t && x->face < y->face);
}

static int entry_compare(const void *x, const void *y)
{
    return entry_less(x, y) ? -1 : entry_less(y, x) ? 1 : 0;
}

tpk_result tpki_shell_entries(const tpk_marcher *m, const tpk_ray_frame *frame, const double dir[3],
                             double tmin, double tmax, tpk_entry *stack_buf, int64_t stack_cap,
                             tpk_entry **out, int64_t *out_count)
{
    *out = stack_buf;
    *out_count = 0;
    if (m->face_count == 0)
        return TPK_OK;
    tpk_result ready = tpki_shell_ready(m);
    if (ready != TPK_OK)
        return ready;
    const double inv[3] = {1.0 / dir[0], 1.0 / dir[1], 1.0 / dir[2]};
    tpk_entry *list = stack_buf;
    int64_t count = 0, cap = stack_cap;
    /* Runs that start before the last entry before tmin end before it, hence before tmin. */
    double t_low = -INFINITY;
    int32_t stack[TPK_BVH_STACK];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const tpk_bvh_node *node = &m->nodes[stack[--top]];
        if (!box_hit(node, frame->org, dir, inv, t_low, tmax))
            continue;
        if (node->count == 0) {
            stack[top++] = node->first + 1;
            stack[top++] = node->first;
            continue;
        }
        for (int32_t i = node->first; i < node->first + node->count; i++) {
            tpk_face_hit hit;
            if (!tpki_shell_face_entry(m->mesh.positions, frame, &m->faces[i], &hit) || hit.t > tmax)
                continue;
            if (hit.t < tmin && hit.t > t_low)
                t_low = hit.t;
            if (hit.t < t_low)
                continue;
            if (count == cap) {
                tpk_entry *bigger = malloc((size_t)(2 * cap) * sizeof *bigger);
                if (!bigger) {
                    if (list != stack_buf)
                        free(list);
                    return TPK_ERR_OUT_OF_MEMORY;
                }
                memcpy(bigger, list, (size_t)count * sizeof *list);
                if (list != stack_buf)
                    free(list);
                list = bigger;
                cap *= 2;
            }
            list[count++] = (tpk_entry){hit.t, i};
        }
    }
    int64_t kept = 0;
    for (int64_t i = 0; i < count; i++)
        if (list[i].t >= t_low)
            list[kept++] = list[i];
    if (kept < 32) {
        for (int64_t i = 1; i < kept; i++)
            for (int64_t j = i; j > 0 && entry_less(&list[j], &list[j - 1]); j--) {
                tpk_entry s = list[j];
                list[j] = list[j - 1];
                list[j - 1] = s;
            }
    } else {
        qsort(list, (size_t)kept, sizeof *list, entry_compare);
    }
    *out = list;
    *out_count = kept;
    return TPK_OK;
}
