/* Lighting of the CPU reference: tet normals, the clip box slab test, shadow and ambient-occlusion rays
 * (transmittance marched through the volume with the same marcher), and the lighting factor m. The
 * definitions, which the Vulkan renderer follows too, are in render.h. */
#include <math.h>
#include <string.h>

#include "base/parallel.h"
#include "render_internal.h"

int rl_clip(const tpk_render_options *opt, const double org[3], const double dir[3], double *lo, double *hi)
{
    if (!opt->clip)
        return *lo <= *hi;
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0) {
            if (org[k] < opt->clip_min[k] || org[k] > opt->clip_max[k])
                return 0;
            continue;
        }
        double ta = (opt->clip_min[k] - org[k]) / dir[k], tb = (opt->clip_max[k] - org[k]) / dir[k];
        double near = ta < tb ? ta : tb, far = ta < tb ? tb : ta;
        *lo = near > *lo ? near : *lo;
        *hi = far < *hi ? far : *hi;
    }
    return *lo <= *hi;
}

/* A piece cut to the spans: each part inside one is a piece of its own, scalars interpolated. */
static int span_segment(void *user, const tpk_segment *seg)
{
    const rl_spans *sp = user;
    double len = seg->t_out - seg->t_in;
    for (int i = 0; i < sp->n; i++) {
        double a = seg->t_in > sp->span[i][0] ? seg->t_in : sp->span[i][0];
        double b = seg->t_out < sp->span[i][1] ? seg->t_out : sp->span[i][1];
        if (!(a < b))
            continue;
        tpk_segment part = *seg;
        part.t_in = a;
        part.t_out = b;
        part.scalar_in = seg->scalar_in + (seg->scalar_out - seg->scalar_in) * ((a - seg->t_in) / len);
        part.scalar_out = seg->scalar_in + (seg->scalar_out - seg->scalar_in) * ((b - seg->t_in) / len);
        if (sp->fn(sp->user, &part))
            return 1;
    }
    return 0;
}

int rl_ray_spans(const tpk_render_options *opt, const double org[3], const double dir[3], double *lo, double *hi,
                 rl_spans *sp, tpk_segment_fn *fn, void **user)
{
    if (!rl_clip(opt, org, dir, lo, hi))
        return 0;
    if (opt->probe_count == 0)
        return 1;
    sp->n = tpk_probe_spans(opt->probes, opt->probe_count, org, dir, *lo, *hi, sp->span);
    if (sp->n == 0)
        return 0;
    sp->fn = *fn;
    sp->user = *user;
    *fn = span_segment;
    *user = sp;
    *lo = sp->span[0][0];
    *hi = sp->span[sp->n - 1][1];
    return 1;
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* v / |v| into n; 0 when v is zero or not finite. */
static int unit_or_none(const double v[3], double n[3])
{
    double len = sqrt(dot3(v, v));
    if (!(len > 0) || !isfinite(len))
        return 0;
    for (int k = 0; k < 3; k++)
        n[k] = v[k] / len;
    return 1;
}

/* Edge vectors e_i = p_i - p0 of the segment's vertices (positions are relative to the mesh origin,
 * which differences do not need). */
static void tet_edges(const render_job *job, const tpk_segment *seg, double e[3][3])
{
    const float *pos = job->mesh->positions;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            e[i][k] = (double)pos[3 * (size_t)seg->v[i + 1] + k] - (double)pos[3 * (size_t)seg->v[0] + k];
}

int rl_tet_normal(const render_job *job, const tpk_segment *seg, double n[3])
{
    const float *sc = job->mesh->scalars;
    if (job->tet_scalars || !sc)
        return 0; /* a tet field is constant inside a tet: no gradient */
    double e[3][3], c23[3], c31[3], c12[3];
    tet_edges(job, seg, e);
    cross3(e[1], e[2], c23);
    cross3(e[2], e[0], c31);
    cross3(e[0], e[1], c12);
    double det = dot3(e[0], c23);
    double s0 = sc[seg->v[0]];
    double d1 = sc[seg->v[1]] - s0, d2 = sc[seg->v[2]] - s0, d3 = sc[seg->v[3]] - s0;
    double g[3];
    for (int k = 0; k < 3; k++)
        g[k] = (d1 * c23[k] + d2 * c31[k] + d3 * c12[k]) / det;
    return unit_or_none(g, n);
}

int rl_face_normal(const render_job *job, const tpk_segment *seg, double n[3])
{
    double e[3][3], c[3];
    tet_edges(job, seg, e);
    cross3(e[0], e[1], c);
    return unit_or_none(c, n);
}

/* ---- Secondary rays ------------------------------------------------------------------------------ */

typedef struct trans_ray {
    const render_job *job;
    double tau;       /* optical depth so far */
    double iso;       /* product of (1 - iso_opacity) over the iso crossings so far */
    double eps;       /* crossings at t <= eps are the start point's own surface */
    int have_prev;    /* tet field: the previous piece of the run */
    double prev_t_out, prev_s;
} trans_ray;

static int on_trans_segment(void *user, const tpk_segment *seg)
{
    trans_ray *tr = user;
    const render_job *job = tr->job;
    const tpk_render_options *opt = job->opt;
    double len = seg->t_out - seg->t_in;
    ri_crossing hits[TPK_RENDER_MAX_ISO];
    int n = 0;
    if (job->tet_scalars) {
        double s = job->tet_scalars[seg->tet];
        if (tr->have_prev && tr->prev_t_out == seg->t_in && seg->t_in > tr->eps)
            n = ri_jump_crossings(opt, seg->t_in, tr->prev_s, s, hits);
        tr->have_prev = 1;
        tr->prev_t_out = seg->t_out;
        tr->prev_s = s;
        double u = ri_normalized(job, s);
        tr->tau += ri_optical_depth(job, len, u, u);
    } else {
        int all = ri_point_crossings(opt, seg->t_in, seg->t_out, seg->scalar_in, seg->scalar_out, hits);
        for (int i = 0; i < all; i++)
            n += hits[i].t > tr->eps;
        tr->tau += ri_optical_depth(job, len, ri_normalized(job, seg->scalar_in), ri_normalized(job, seg->scalar_out));
    }
    for (int i = 0; i < n; i++)
        tr->iso *= 1.0 - job->setup.iso_opacity;
    return exp(-tr->tau) * tr->iso <= TPK_RENDER_OPAQUE_T;
}

/* Transmittance from x along unit w over [0, len], clipped to the box. */
static double transmittance(ray_state *ray, const double x[3], const double w[3], double len)
{
    const render_job *job = ray->job;
    double lo = 0.0, hi = len;
    trans_ray tr = {job, 0.0, 1.0, TPK_RENDER_SELF_EPS * job->setup.unit, 0, 0.0, 0.0};
    rl_spans sp;
    tpk_segment_fn fn = on_trans_segment;
    void *user = &tr;
    if (!rl_ray_spans(job->opt, x, w, &lo, &hi, &sp, &fn, &user))
        return 1.0;
    tpk_march_stats st;
    tpk_result r = tpk_march_ray(job->marcher, x, w, lo, hi, fn, user, &st);
    ray->steps += st.tet_steps;
    ray->secondary++;
    if (r != TPK_OK && ray->error == TPK_OK)
        ray->error = r;
    return exp(-tr.tau) * tr.iso;
}

static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* Mean transmittance of the AO rays around axis a (unit). */
static double ambient(ray_state *ray, const double x[3], const double a[3])
{
    const render_job *job = ray->job;
    const int count = job->opt->ao_rays;
    double sgn = a[2] >= 0 ? 1.0 : -1.0;
    double p = -1.0 / (sgn + a[2]), q = a[0] * a[1] * p;
    const double b1[3] = {1.0 + sgn * a[0] * a[0] * p, sgn * q, -sgn * a[0]};
    const double b2[3] = {q, sgn + a[1] * a[1] * p, -a[1]};
    uint32_t h = hash32((uint32_t)ray->py * 65536u + (uint32_t)ray->px);
    double rot = (double)h * (1.0 / 4294967296.0), sum = 0.0;
    for (int i = 0; i < count; i++) {
        double z = 1.0 - (i + 0.5) / count, r = sqrt(1.0 - z * z);
        double f = i * 0.6180339887498949 + rot;
        double phi = 2.0 * M_PI * (f - floor(f));
        double w[3];
        for (int k = 0; k < 3; k++)
            w[k] = r * cos(phi) * b1[k] + r * sin(phi) * b2[k] + z * a[k];
        sum += transmittance(ray, x, w, job->setup.ao_radius);
    }
    return sum / count;
}

void rl_cast(ray_state *ray, const double x[3], const double *n, double *s, double *a)
{
    const render_job *job = ray->job;
    *s = 1.0;
    *a = 1.0;
    if (job->opt->shadows) {
        double w[3] = {job->setup.light[0] - x[0], job->setup.light[1] - x[1], job->setup.light[2] - x[2]};
        double len = sqrt(dot3(w, w));
        if (len > 0) {
            for (int k = 0; k < 3; k++)
                w[k] /= len;
            *s = transmittance(ray, x, w, len);
        }
    }
    if (job->opt->ao_rays > 0) {
        double axis[3];
        int flip = n && dot3(n, ray->dir) > 0;
        for (int k = 0; k < 3; k++)
            axis[k] = n ? (flip ? -n[k] : n[k]) : -ray->dir[k];
        *a = ambient(ray, x, axis);
    }
}

/* ---- The vertex cache (render.h: OCCLUSION AT VERTICES) ---------------------------------------- */

typedef struct cache_work {
    const render_job *job;
    float *s, *a;
    uint64_t steps[TPK_MAX_THREADS], secondary[TPK_MAX_THREADS];
    tpk_result error[TPK_MAX_THREADS];
} cache_work;

/* S_v and A_v of one vertex at world point p. */
static void cache_vertex(ray_state *ray, uint32_t v, const double p[3], float *s, float *a)
{
    const render_job *job = ray->job;
    double sv = 1.0, av = 1.0;
    if (job->opt->shadows) {
        double w[3] = {job->setup.light[0] - p[0], job->setup.light[1] - p[1], job->setup.light[2] - p[2]};
        double len = sqrt(dot3(w, w));
        if (len > 0) {
            for (int k = 0; k < 3; k++)
                w[k] /= len;
            sv = transmittance(ray, p, w, len);
        }
    }
    const int count = job->opt->ao_rays;
    if (count > 0) {
        double rot = (double)hash32(v) * (1.0 / 4294967296.0), sum = 0.0;
        for (int i = 0; i < count; i++) {
            double z = 1.0 - 2.0 * (i + 0.5) / count, r = sqrt(1.0 - z * z);
            double f = i * 0.6180339887498949 + rot;
            double phi = 2.0 * M_PI * (f - floor(f));
            const double w[3] = {r * cos(phi), r * sin(phi), z};
            sum += transmittance(ray, p, w, job->setup.ao_radius);
        }
        av = sum / count;
    }
    *s = (float)sv;
    *a = (float)av;
}

static void cache_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    cache_work *cw = ctx;
    const render_job *job = cw->job;
    ray_state ray;
    memset(&ray, 0, sizeof ray);
    ray.job = job;
    for (int64_t v = begin; v < end; v++) {
        double p[3];
        for (int k = 0; k < 3; k++)
            p[k] = job->mesh->origin[k] + (double)job->mesh->positions[3 * v + k];
        cache_vertex(&ray, (uint32_t)v, p, &cw->s[v], &cw->a[v]);
    }
    cw->steps[worker] = ray.steps;
    cw->secondary[worker] = ray.secondary;
    cw->error[worker] = ray.error;
}

tpk_result rl_vertex_cache(const render_job *job, int threads, float *s, float *a, uint64_t *steps,
                           uint64_t *secondary)
{
    static cache_work cw_zero;
    cache_work cw = cw_zero;
    cw.job = job;
    cw.s = s;
    cw.a = a;
    int64_t count = (int64_t)job->mesh->vertex_count;
    int n = tpk_threads_for(count, tpk_thread_count(threads), 256);
    tpk_parallel_for(count, n, cache_range, &cw);
    tpk_result r = TPK_OK;
    for (int w = 0; w < n; w++) {
        *steps += cw.steps[w];
        *secondary += cw.secondary[w];
        if (r == TPK_OK)
            r = cw.error[w];
    }
    return r;
}

void rl_vertex_lookup(const render_job *job, const tpk_segment *seg, const double x[3], double *s, double *a)
{
    const float *pos = job->mesh->positions;
    double e[3][3], c[3][3], q[3];
    tet_edges(job, seg, e);
    cross3(e[1], e[2], c[0]);
    cross3(e[2], e[0], c[1]);
    cross3(e[0], e[1], c[2]);
    double det = dot3(e[0], c[0]);
    for (int k = 0; k < 3; k++)
        q[k] = x[k] - job->mesh->origin[k] - (double)pos[3 * (size_t)seg->v[0] + k];
    double l[4] = {0.25, 0.25, 0.25, 0.25};
    if (det != 0 && isfinite(det)) {
        for (int i = 0; i < 3; i++)
            l[i + 1] = dot3(q, c[i]) / det;
        l[0] = 1.0 - l[1] - l[2] - l[3];
    }
    double sv = 0.0, av = 0.0;
    for (int i = 0; i < 4; i++) {
        sv += l[i] * job->vertex_s[seg->v[i]];
        av += l[i] * job->vertex_a[seg->v[i]];
    }
    *s = sv < 0 ? 0 : sv > 1 ? 1 : sv;
    *a = av < 0 ? 0 : av > 1 ? 1 : av;
}

double rl_factor(const ray_state *ray, const double x[3], const double *n, double s, double a)
{
    const render_job *job = ray->job;
    double d = 1.0, l[3];
    const double to_light[3] = {job->setup.light[0] - x[0], job->setup.light[1] - x[1], job->setup.light[2] - x[2]};
    if (job->opt->shading && n && unit_or_none(to_light, l))
        d = fabs(dot3(n, l));
    return a * (TPK_RENDER_AMBIENT + (1.0 - TPK_RENDER_AMBIENT) * d * s);
}
