/* Emission-absorption along one stretch of a tet piece (exact, sampled or midpoint), the optical depth of
 * a stretch for secondary rays, and where a piece crosses the iso values (definitions: render.h). */
#include <math.h>
#include <string.h>

#include "render_internal.h"

#define MAX_PIECE_DEPTH 0.05 /* optical depth of one quadrature step of the exact integration */
#define MAX_PIECE_STEPS 256

double ri_normalized(const render_job *job, double scalar)
{
    if (!job->has_scalars || job->setup.inv_range == 0)
        return 0.5;
    return (scalar - job->setup.range_min) * job->setup.inv_range;
}

/* Add a stretch of length h over which color and extinction go linearly from (c0,k0) to (c1,k1), in
 * steps of optical depth at most MAX_PIECE_DEPTH. */
static void integrate_linear(ray_state *ray, double h, const double c0[4], const double c1[4])
{
    const double inv_unit = ray->job->setup.inv_unit;
    double depth = h * 0.5 * (c0[3] + c1[3]) * inv_unit;
    if (!(depth > 0))
        return;
    int n = (int)ceil(depth / MAX_PIECE_DEPTH);
    n = n < 1 ? 1 : n > MAX_PIECE_STEPS ? MAX_PIECE_STEPS : n;
    double step = h / n;
    for (int j = 0; j < n; j++) {
        double u0 = (double)j / n, u1 = (double)(j + 1) / n;
        double k0 = c0[3] + u0 * (c1[3] - c0[3]), k1 = c0[3] + u1 * (c1[3] - c0[3]);
        if (k0 + k1 <= 0)
            continue;
        double tau = step * 0.5 * (k0 + k1) * inv_unit;
        double alpha = 1.0 - exp(-tau);
        double weight = ray->m * ray->transmittance * alpha / (k0 + k1);
        for (int c = 0; c < 3; c++) {
            double e0 = c0[c] + u0 * (c1[c] - c0[c]), e1 = c0[c] + u1 * (c1[c] - c0[c]);
            ray->color[c] += weight * (e0 * k0 + e1 * k1); /* extinction-weighted mean color */
        }
        ray->transmittance *= 1.0 - alpha;
    }
}

/* Exact integration: split where the scalar crosses a TF control point, so that color and opacity are
 * linear in distance on every part. */
static void integrate_exact(ray_state *ray, double length, double s0, double s1)
{
    const tpk_transfer_function *tf = ray->job->opt->tf;
    double ca[4], cb[4];
    tpk_tf_eval(tf, s0, ca);
    if (s0 == s1) {
        integrate_linear(ray, length, ca, ca);
        return;
    }
    const double ds = s1 - s0;
    double prev_s = s0;
    int n = tf->count;
    for (int i = 0; i < n; i++) {
        int k = ds > 0 ? i : n - 1 - i;
        double cs = tf->points[k].s;
        if (ds > 0 ? (cs <= s0 || cs >= s1) : (cs >= s0 || cs <= s1))
            continue;
        tpk_tf_eval(tf, cs, cb);
        integrate_linear(ray, length * ((cs - prev_s) / ds), ca, cb);
        memcpy(ca, cb, sizeof ca);
        prev_s = cs;
    }
    tpk_tf_eval(tf, s1, cb);
    integrate_linear(ray, length * ((s1 - prev_s) / ds), ca, cb);
}

/* One point sample of `step` length at TF coordinate u. */
static void composite_sample(ray_state *ray, double step, double u)
{
    double c[4];
    tpk_tf_eval(ray->job->opt->tf, u, c);
    double alpha = 1.0 - exp(-step * c[3] * ray->job->setup.inv_unit);
    for (int k = 0; k < 3; k++)
        ray->color[k] += ray->m * ray->transmittance * alpha * c[k];
    ray->transmittance *= 1.0 - alpha;
}

/* Sampling: midpoints of equal steps no longer than unit_distance / 2. */
static void integrate_sampled(ray_state *ray, double length, double s0, double s1)
{
    double max_step = 0.5 * ray->job->setup.unit;
    int n = (int)ceil(length / max_step);
    n = n < 1 ? 1 : n > 4096 ? 4096 : n;
    double step = length / n;
    for (int j = 0; j < n && ray->transmittance > TPK_RENDER_OPAQUE_T; j++)
        composite_sample(ray, step, s0 + (s1 - s0) * ((j + 0.5) / n));
}

void ri_integrate(ray_state *ray, double length, double u0, double u1)
{
    /* a clear volume: integrate_exact's every stretch has depth 0 (or NaN) and returns untouched */
    if (!(length > 0) || ray->job->clear_volume)
        return;
    switch (ray->job->opt->integration) {
    case TPK_INTEGRATION_SAMPLED: integrate_sampled(ray, length, u0, u1); break;
    case TPK_INTEGRATION_MIDPOINT: composite_sample(ray, length, 0.5 * (u0 + u1)); break;
    default: integrate_exact(ray, length, u0, u1); break;
    }
}

double ri_optical_depth(const render_job *job, double length, double u0, double u1)
{
    if (!(length > 0))
        return 0.0;
    const tpk_transfer_function *tf = job->opt->tf;
    double c[4];
    tpk_tf_eval(tf, u0, c);
    if (u0 == u1)
        return length * c[3] * job->setup.inv_unit;
    const double du = u1 - u0;
    double prev_u = u0, prev_a = c[3], sum = 0.0; /* integral of alpha over u, trapezoids between points */
    for (int i = 0; i < tf->count; i++) {
        int k = du > 0 ? i : tf->count - 1 - i;
        double cu = tf->points[k].s;
        if (du > 0 ? (cu <= u0 || cu >= u1) : (cu >= u0 || cu <= u1))
            continue;
        tpk_tf_eval(tf, cu, c);
        sum += 0.5 * (prev_a + c[3]) * (cu - prev_u);
        prev_u = cu;
        prev_a = c[3];
    }
    tpk_tf_eval(tf, u1, c);
    sum += 0.5 * (prev_a + c[3]) * (u1 - prev_u);
    return length * (sum / du) * job->setup.inv_unit;
}

/* Insert (t, j) keeping increasing t, then j. */
static int add_crossing(ri_crossing *out, int n, double t, int j)
{
    int k = n;
    while (k > 0 && (out[k - 1].t > t || (out[k - 1].t == t && out[k - 1].j > j))) {
        out[k] = out[k - 1];
        k--;
    }
    out[k] = (ri_crossing){t, j};
    return n + 1;
}

int ri_point_crossings(const tpk_render_options *opt, double t_in, double t_out, double s_in, double s_out,
                       ri_crossing out[TPK_RENDER_MAX_ISO])
{
    int n = 0;
    for (int j = 0; j < opt->iso_count && j < TPK_RENDER_MAX_ISO; j++) {
        double v = opt->iso[j];
        if ((s_in < v && v <= s_out) || (s_in > v && v >= s_out)) {
            double t = t_in + (v - s_in) / (s_out - s_in) * (t_out - t_in);
            t = t < t_in ? t_in : t > t_out ? t_out : t;
            n = add_crossing(out, n, t, j);
        }
    }
    return n;
}

int ri_jump_crossings(const tpk_render_options *opt, double t, double s_prev, double s,
                      ri_crossing out[TPK_RENDER_MAX_ISO])
{
    int n = 0;
    for (int j = 0; j < opt->iso_count && j < TPK_RENDER_MAX_ISO; j++) {
        double v = opt->iso[j];
        if ((s_prev < v && v <= s) || (s_prev > v && v >= s))
            n = add_crossing(out, n, t, j);
    }
    return n;
}
