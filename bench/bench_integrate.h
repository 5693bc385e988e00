/* Emission-absorption integrators over the marcher's segments, for the speed-against-error and storage
 * benchmarks (bench_render_error.c, bench_storage.c): the render's model (colour c and extinction
 * a / unit_distance from a piecewise-linear TF of the scalar, which is linear along each tet piece),
 * integrated four ways into float RGBA (premultiplied, transparent background), so that errors are not
 * hidden by 8-bit output:
 *   BI_MIDPOINT   one sample per tet piece at its midpoint (the paper's choice);
 *   BI_EXACT      what `tetpack render` does by default: split at TF control points, then steps of
 *                 optical depth <= 0.05 (the same scheme as tools/render/render_cpu.c);
 *   BI_STEP       fixed-step sampling: samples at t = (i + 1/2) h along the ray, wherever they fall;
 *   BI_REFERENCE  split at TF control points, sub-intervals of optical depth <= depth_limit, each by
 *                 5-point Gauss-Legendre with the transmittance exact (the optical depth is quadratic
 *                 in t there): converged to about 1e-10, no early termination.
 * Header-only (static functions): each benchmark is one executable. */
#ifndef TPK_BENCH_INTEGRATE_H
#define TPK_BENCH_INTEGRATE_H

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <string.h>

#include "render/render.h"
#include "tetpack.h"

enum { BI_MIDPOINT, BI_EXACT, BI_STEP, BI_REFERENCE };

typedef struct bi_method {
    int kind;
    double step;        /* BI_STEP: sample spacing, world units */
    double depth_limit; /* BI_EXACT: 0.05; BI_REFERENCE: optical depth per Gauss-Legendre interval */
    double stop_transmittance; /* stop the ray below this (render: 0.02); 0: never */
    int min_intervals;  /* BI_REFERENCE: at least this many intervals per part (0: 1), for its own check */
} bi_method;

typedef struct bi_scene {
    const tpk_marcher *marcher;
    const tpk_transfer_function *tf;
    double range_min, inv_range, inv_unit;
    double eye[3], forward[3], right[3], up[3], tan_half_x, tan_half_y;
    int width, height;
} bi_scene;

typedef struct bi_ray {
    const bi_scene *scene;
    const bi_method *method;
    double color[3], transmittance;
    double next_sample; /* BI_STEP: ray parameter of the next sample */
} bi_ray;

static inline void bi_tf(const bi_ray *ray, double s, double c[4])
{
    tpk_tf_eval(ray->scene->tf, (s - ray->scene->range_min) * ray->scene->inv_range, c);
}

/* Render's quadrature over a stretch of length h with colour and extinction linear from c0 to c1. */
static inline void bi_linear_steps(bi_ray *ray, double h, const double c0[4], const double c1[4])
{
    double inv_unit = ray->scene->inv_unit, depth = h * 0.5 * (c0[3] + c1[3]) * inv_unit;
    if (!(depth > 0))
        return;
    int n = (int)ceil(depth / ray->method->depth_limit);
    n = n < 1 ? 1 : n > 256 ? 256 : n;
    double step = h / n;
    for (int j = 0; j < n; j++) {
        double u0 = (double)j / n, u1 = (double)(j + 1) / n;
        double k0 = c0[3] + u0 * (c1[3] - c0[3]), k1 = c0[3] + u1 * (c1[3] - c0[3]);
        if (k0 + k1 <= 0)
            continue;
        double alpha = 1.0 - exp(-step * 0.5 * (k0 + k1) * inv_unit);
        double weight = ray->transmittance * alpha / (k0 + k1);
        for (int c = 0; c < 3; c++)
            ray->color[c] += weight * ((c0[c] + u0 * (c1[c] - c0[c])) * k0 + (c0[c] + u1 * (c1[c] - c0[c])) * k1);
        ray->transmittance *= 1.0 - alpha;
    }
}

/* Converged integral over length h with colour and extinction linear from c0 to c1. */
static inline void bi_linear_gauss(bi_ray *ray, double h, const double c0[4], const double c1[4])
{
    static const double x[5] = {0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
                                0.95308992296933200};
    static const double w[5] = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                0.23931433524968324, 0.11846344252809454};
    double inv_unit = ray->scene->inv_unit, depth = h * 0.5 * (c0[3] + c1[3]) * inv_unit;
    if (!(depth > 0))
        return;
    long n = (long)ceil(depth / ray->method->depth_limit);
    n = n < 1 ? 1 : n;
    n = n < ray->method->min_intervals ? ray->method->min_intervals : n;
    double len = h / (double)n;
    for (long j = 0; j < n; j++) {
        double ua = (double)j / (double)n, ub = (double)(j + 1) / (double)n;
        double ka = c0[3] + ua * (c1[3] - c0[3]), kb = c0[3] + ub * (c1[3] - c0[3]);
        for (int q = 0; q < 5; q++) {
            double u = x[q], k = ka + u * (kb - ka);
            double tau = len * inv_unit * (ka * u + 0.5 * (kb - ka) * u * u);
            double weight = w[q] * len * k * inv_unit * ray->transmittance * exp(-tau);
            double uu = ua + u * (ub - ua);
            for (int c = 0; c < 3; c++)
                ray->color[c] += weight * (c0[c] + uu * (c1[c] - c0[c]));
        }
        ray->transmittance *= exp(-len * inv_unit * 0.5 * (ka + kb));
    }
}

/* Split a piece where the scalar crosses a TF control point; each part is linear in colour and k. */
static inline void bi_piecewise(bi_ray *ray, double length, double s0, double s1)
{
    const tpk_transfer_function *tf = ray->scene->tf;
    void (*part)(bi_ray *, double, const double *, const double *) =
        ray->method->kind == BI_REFERENCE ? bi_linear_gauss : bi_linear_steps;
    double a = (s0 - ray->scene->range_min) * ray->scene->inv_range;
    double b = (s1 - ray->scene->range_min) * ray->scene->inv_range;
    double ca[4], cb[4], prev = a;
    tpk_tf_eval(tf, a, ca);
    if (a != b)
        for (int i = 0; i < tf->count; i++) {
            double cs = tf->points[b > a ? i : tf->count - 1 - i].s;
            if (b > a ? (cs <= a || cs >= b) : (cs >= a || cs <= b))
                continue;
            tpk_tf_eval(tf, cs, cb);
            part(ray, length * ((cs - prev) / (b - a)), ca, cb);
            memcpy(ca, cb, sizeof ca);
            prev = cs;
        }
    tpk_tf_eval(tf, b, cb);
    part(ray, a == b ? length : length * ((b - prev) / (b - a)), ca, cb);
}

static inline void bi_sample(bi_ray *ray, double h, double s)
{
    double c[4];
    bi_tf(ray, s, c);
    double alpha = 1.0 - exp(-h * c[3] * ray->scene->inv_unit);
    for (int k = 0; k < 3; k++)
        ray->color[k] += ray->transmittance * alpha * c[k];
    ray->transmittance *= 1.0 - alpha;
}

static inline int bi_on_segment(void *user, const tpk_segment *seg)
{
    bi_ray *ray = user;
    double length = seg->t_out - seg->t_in;
    if (length > 0) {
        switch (ray->method->kind) {
        case BI_MIDPOINT:
            bi_sample(ray, length, 0.5 * (seg->scalar_in + seg->scalar_out));
            break;
        case BI_STEP: {
            double h = ray->method->step;
            if (ray->next_sample < seg->t_in) /* the grid of samples is global along the ray */
                ray->next_sample = (ceil(seg->t_in / h - 0.5) + 0.5) * h;
            for (; ray->next_sample < seg->t_out; ray->next_sample += h) {
                double u = (ray->next_sample - seg->t_in) / length;
                bi_sample(ray, h, seg->scalar_in + u * (seg->scalar_out - seg->scalar_in));
            }
            break;
        }
        default:
            bi_piecewise(ray, length, seg->scalar_in, seg->scalar_out);
        }
    }
    return ray->transmittance < ray->method->stop_transmittance;
}

/* The pinhole camera of render_cpu.c: rows top to bottom, unit directions (t = distance). */
static inline void bi_scene_camera(bi_scene *scene, const tpk_camera *cam)
{
    double len = 0;
    for (int k = 0; k < 3; k++) {
        scene->eye[k] = cam->eye[k];
        scene->forward[k] = cam->at[k] - cam->eye[k];
        len += scene->forward[k] * scene->forward[k];
    }
    for (int k = 0; k < 3; k++)
        scene->forward[k] /= sqrt(len);
    const double *f = scene->forward, *u = cam->up;
    double r[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
    len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int k = 0; k < 3; k++)
        scene->right[k] = r[k] / len;
    r[0] = scene->right[1] * f[2] - scene->right[2] * f[1];
    r[1] = scene->right[2] * f[0] - scene->right[0] * f[2];
    r[2] = scene->right[0] * f[1] - scene->right[1] * f[0];
    memcpy(scene->up, r, sizeof r);
    scene->tan_half_y = tan(0.5 * cam->fovy_deg * M_PI / 180.0);
    scene->tan_half_x = scene->tan_half_y * scene->width / scene->height;
}

static inline void bi_ray_dir(const bi_scene *scene, int x, int y, double dir[3])
{
    double px = (2.0 * (x + 0.5) / scene->width - 1.0) * scene->tan_half_x;
    double py = (1.0 - 2.0 * (y + 0.5) / scene->height) * scene->tan_half_y;
    double len2 = 0;
    for (int k = 0; k < 3; k++) {
        dir[k] = scene->forward[k] + px * scene->right[k] + py * scene->up[k];
        len2 += dir[k] * dir[k];
    }
    for (int k = 0; k < 3; k++)
        dir[k] /= sqrt(len2);
}

/* ---- One image on all threads ------------------------------------------------------------------- */

typedef struct bi_job {
    const bi_scene *scene;
    const bi_method *method;
    float *rgba; /* width * height * 4, premultiplied */
    atomic_int next_row, failed_rays;
    atomic_uint_least64_t tet_steps;
} bi_job;

static inline void *bi_worker(void *arg)
{
    bi_job *job = arg;
    const bi_scene *sc = job->scene;
    uint64_t steps = 0;
    int failed = 0;
    for (int y; (y = atomic_fetch_add(&job->next_row, 1)) < sc->height;)
        for (int x = 0; x < sc->width; x++) {
            double dir[3];
            bi_ray_dir(sc, x, y, dir);
            bi_ray ray = {sc, job->method, {0, 0, 0}, 1.0, -INFINITY};
            tpk_march_stats st;
            failed += tpk_march_ray(sc->marcher, sc->eye, dir, 0.0, INFINITY, bi_on_segment, &ray, &st) != TPK_OK;
            steps += st.tet_steps;
            float *px = &job->rgba[4 * ((size_t)y * (size_t)sc->width + (size_t)x)];
            for (int k = 0; k < 3; k++)
                px[k] = (float)ray.color[k];
            px[3] = (float)(1.0 - ray.transmittance);
        }
    atomic_fetch_add(&job->tet_steps, steps);
    atomic_fetch_add(&job->failed_rays, failed);
    return NULL;
}

/* Render into rgba with `threads` threads; returns the failed rays (marcher errors). */
static inline int bi_render(const bi_scene *scene, const bi_method *method, int threads, float *rgba,
                            uint64_t *tet_steps)
{
    bi_job job = {.scene = scene, .method = method, .rgba = rgba};
    atomic_init(&job.next_row, 0);
    atomic_init(&job.failed_rays, 0);
    atomic_init(&job.tet_steps, 0);
    pthread_t tids[64];
    threads = threads < 1 ? 1 : threads > 64 ? 64 : threads;
    int started = 0;
    for (int i = 0; i < threads - 1; i++)
        started += pthread_create(&tids[started], NULL, bi_worker, &job) == 0;
    bi_worker(&job);
    for (int i = 0; i < started; i++)
        pthread_join(tids[i], NULL);
    if (tet_steps)
        *tet_steps = atomic_load(&job.tet_steps);
    return atomic_load(&job.failed_rays);
}

/* RMSE over all channels (premultiplied RGBA in [0,1]) and the largest absolute difference. */
static inline double bi_rmse(const float *a, const float *b, size_t pixels, double *max_abs)
{
    double sum = 0, mx = 0;
    for (size_t i = 0; i < 4 * pixels; i++) {
        double d = fabs((double)a[i] - (double)b[i]);
        sum += d * d;
        mx = d > mx ? d : mx;
    }
    if (max_abs)
        *max_abs = mx;
    return sqrt(sum / (double)(4 * pixels));
}

static inline double bi_psnr(double rmse)
{
    return rmse > 0 ? 20.0 * log10(1.0 / rmse) : INFINITY;
}

#endif
