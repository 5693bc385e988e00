/* The CPU volume renderer: one primary ray per pixel through the reference marcher, emission-absorption
 * integrated per tet piece, rows shared between pthreads through an atomic counter. */
#include "render.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define OPAQUE_TRANSMITTANCE 0.02 /* stop at 98% opacity */
#define MAX_PIECE_DEPTH 0.05      /* optical depth of one quadrature step of the exact integration */
#define MAX_PIECE_STEPS 256

void tpk_camera_default(const double bounds_min[3], const double bounds_max[3], tpk_camera *out)
{
    double center[3], diag2 = 0;
    for (int k = 0; k < 3; k++) {
        center[k] = 0.5 * (bounds_min[k] + bounds_max[k]);
        double e = bounds_max[k] - bounds_min[k];
        diag2 += e * e;
    }
    double radius = diag2 > 0 ? 0.5 * sqrt(diag2) : 1.0;
    const double fovy = 35.0;
    double dist = 1.05 * radius / sin(0.5 * fovy * M_PI / 180.0);
    const double view[3] = {1.0, 0.6, 0.8};
    double len = sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
    for (int k = 0; k < 3; k++) {
        out->eye[k] = center[k] + view[k] / len * dist;
        out->at[k] = center[k];
        out->up[k] = k == 2 ? 1.0 : 0.0;
    }
    out->fovy_deg = fovy;
}

void tpk_render_options_default(tpk_render_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->width = 800;
    opt->height = 600;
    opt->background[0] = opt->background[1] = opt->background[2] = 0.1f;
    opt->background[3] = 1.0f;
}

/* ---- Shared state of one render ----------------------------------------------------------------- */

typedef struct render_job {
    const tpk_render_options *opt;
    const tpk_marcher *marcher;
    const tpk_set_marcher *set; /* a part set instead (spec §15) */
    int has_scalars;
    double inv_range;          /* 1 / (range_max - range_min), 0 when the range is empty */
    double inv_unit;           /* 1 / unit_distance */
    double eye[3], forward[3], right[3], up[3];
    double tan_half_y, tan_half_x;
    uint8_t *rgba;
    atomic_int next_row;
    atomic_int failed;
    pthread_mutex_t error_lock;
    tpk_result error;
    int error_x, error_y;
    atomic_uint_least64_t tet_steps;
} render_job;

typedef struct ray_state {
    const render_job *job;
    double color[3];       /* accumulated, premultiplied */
    double transmittance;
} ray_state;

static inline double normalized(const render_job *job, double scalar)
{
    if (!job->has_scalars || job->inv_range == 0)
        return 0.5;
    return (scalar - job->opt->range_min) * job->inv_range;
}

/* Add a stretch of length h over which color and extinction go linearly from (c0,k0) to (c1,k1), in
 * steps of optical depth at most MAX_PIECE_DEPTH. */
static void integrate_linear(ray_state *ray, double h, const double c0[4], const double c1[4])
{
    const double inv_unit = ray->job->inv_unit;
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
        double weight = ray->transmittance * alpha / (k0 + k1);
        for (int c = 0; c < 3; c++) {
            double e0 = c0[c] + u0 * (c1[c] - c0[c]), e1 = c0[c] + u1 * (c1[c] - c0[c]);
            ray->color[c] += weight * (e0 * k0 + e1 * k1); /* extinction-weighted mean color */
        }
        ray->transmittance *= 1.0 - alpha;
    }
}

/* Exact integration of one piece: split where the scalar crosses a TF control point, so that color and
 * opacity are linear in distance on every part. */
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

/* Sampling: midpoints of equal steps no longer than unit_distance / 2. */
static void integrate_sampled(ray_state *ray, double length, double s0, double s1)
{
    const render_job *job = ray->job;
    double max_step = 0.5 / job->inv_unit;
    int n = (int)ceil(length / max_step);
    n = n < 1 ? 1 : n > 4096 ? 4096 : n;
    double step = length / n;
    for (int j = 0; j < n && ray->transmittance > OPAQUE_TRANSMITTANCE; j++) {
        double c[4];
        tpk_tf_eval(job->opt->tf, s0 + (s1 - s0) * ((j + 0.5) / n), c);
        double alpha = 1.0 - exp(-step * c[3] * job->inv_unit);
        for (int k = 0; k < 3; k++)
            ray->color[k] += ray->transmittance * alpha * c[k];
        ray->transmittance *= 1.0 - alpha;
    }
}

static int on_segment(void *user, const tpk_segment *seg)
{
    ray_state *ray = user;
    double length = seg->t_out - seg->t_in;
    if (length > 0) {
        double s0 = normalized(ray->job, seg->scalar_in), s1 = normalized(ray->job, seg->scalar_out);
        if (ray->job->opt->integration == 1)
            integrate_sampled(ray, length, s0, s1);
        else
            integrate_exact(ray, length, s0, s1);
    }
    return ray->transmittance <= OPAQUE_TRANSMITTANCE;
}

static uint8_t to_byte(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    return (uint8_t)(v * 255.0 + 0.5);
}

/* One pixel: returns the marcher's result. */
static tpk_result render_pixel(const render_job *job, int x, int y, uint64_t *steps)
{
    const tpk_render_options *opt = job->opt;
    double px = (2.0 * (x + 0.5) / opt->width - 1.0) * job->tan_half_x;
    double py = (1.0 - 2.0 * (y + 0.5) / opt->height) * job->tan_half_y;
    double dir[3], len2 = 0;
    for (int k = 0; k < 3; k++) {
        dir[k] = job->forward[k] + px * job->right[k] + py * job->up[k];
        len2 += dir[k] * dir[k];
    }
    double inv_len = 1.0 / sqrt(len2);
    for (int k = 0; k < 3; k++)
        dir[k] *= inv_len; /* unit direction: t is the distance from the eye */
    ray_state ray = {job, {0, 0, 0}, 1.0};
    tpk_march_stats st;
    tpk_result r = job->set ? tpk_set_march_ray(job->set, job->eye, dir, 0.0, INFINITY, on_segment, &ray, NULL, &st)
                            : tpk_march_ray(job->marcher, job->eye, dir, 0.0, INFINITY, on_segment, &ray, &st);
    *steps += st.tet_steps;
    const float *bg = opt->background;
    double alpha = (1.0 - ray.transmittance) + ray.transmittance * bg[3];
    uint8_t *out = &job->rgba[4 * ((size_t)y * (size_t)opt->width + (size_t)x)];
    for (int k = 0; k < 3; k++) {
        double premult = ray.color[k] + ray.transmittance * bg[3] * bg[k];
        out[k] = to_byte(alpha > 0 ? premult / alpha : 0.0);
    }
    out[3] = to_byte(alpha);
    return r;
}

static void *render_worker(void *arg)
{
    render_job *job = arg;
    uint64_t steps = 0;
    for (;;) {
        int y = atomic_fetch_add(&job->next_row, 1);
        if (y >= job->opt->height || atomic_load(&job->failed))
            break;
        for (int x = 0; x < job->opt->width; x++) {
            tpk_result r = render_pixel(job, x, y, &steps);
            if (r != TPK_OK) {
                pthread_mutex_lock(&job->error_lock);
                if (!atomic_load(&job->failed)) {
                    job->error = r;
                    job->error_x = x;
                    job->error_y = y;
                    atomic_store(&job->failed, 1);
                }
                pthread_mutex_unlock(&job->error_lock);
                break;
            }
        }
    }
    atomic_fetch_add(&job->tet_steps, steps);
    return NULL;
}

/* ---- Setup -------------------------------------------------------------------------------------- */

static void normalize3(double v[3])
{
    double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len > 0)
        for (int k = 0; k < 3; k++)
            v[k] /= len;
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static int setup_camera(render_job *job, const tpk_camera *cam, tpk_diag *diag)
{
    double up[3];
    for (int k = 0; k < 3; k++) {
        job->eye[k] = cam->eye[k];
        job->forward[k] = cam->at[k] - cam->eye[k];
        up[k] = cam->up[k];
        if (!isfinite(cam->eye[k]) || !isfinite(cam->at[k]) || !isfinite(cam->up[k]))
            return tpk_diag_fail(diag, "render: camera eye, at and up must be finite");
    }
    normalize3(job->forward);
    if (job->forward[0] == 0 && job->forward[1] == 0 && job->forward[2] == 0)
        return tpk_diag_fail(diag, "render: camera eye and at are the same point");
    if (!(cam->fovy_deg > 0 && cam->fovy_deg < 180))
        return tpk_diag_fail(diag, "render: expected a field of view in (0, 180) degrees, found %g", cam->fovy_deg);
    cross3(job->forward, up, job->right);
    normalize3(job->right);
    if (job->right[0] == 0 && job->right[1] == 0 && job->right[2] == 0) {
        /* up along the view direction: pick any perpendicular */
        const double other[3] = {fabs(job->forward[0]) < 0.9 ? 1.0 : 0.0, fabs(job->forward[0]) < 0.9 ? 0.0 : 1.0, 0};
        cross3(job->forward, other, job->right);
        normalize3(job->right);
    }
    cross3(job->right, job->forward, job->up);
    job->tan_half_y = tan(0.5 * cam->fovy_deg * M_PI / 180.0);
    job->tan_half_x = job->tan_half_y * job->opt->width / job->opt->height;
    return 0;
}

double tpk_positions_diagonal(const tpk_mesh_arrays *mesh)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < mesh->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->positions[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        if (hi[k] > lo[k])
            d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d2);
}

static int thread_count(const tpk_render_options *opt)
{
    long n = opt->threads > 0 ? opt->threads : sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1)
        n = 1;
    if (n > 256)
        n = 256;
    if (n > opt->height)
        n = opt->height;
    return (int)n;
}

static int check_options(const tpk_render_options *opt, const void *scene, uint8_t *rgba, tpk_diag *diag)
{
    if (!scene || !opt || !rgba)
        return tpk_diag_fail(diag, "render: mesh, options and image buffer are required");
    if (opt->width < 1 || opt->height < 1 || opt->width > 32768 || opt->height > 32768)
        return tpk_diag_fail(diag, "render: expected width and height in 1..32768, found %dx%d", opt->width,
                             opt->height);
    if (!opt->tf || opt->tf->count < 1 || opt->tf->count > TPK_TF_MAX_POINTS)
        return tpk_diag_fail(diag, "render: a transfer function with at least one point is required");
    if (opt->integration != 0 && opt->integration != 1)
        return tpk_diag_fail(diag, "render: expected integration 0 (exact) or 1 (sampling), found %d",
                             opt->integration);
    if (!isfinite(opt->range_min) || !isfinite(opt->range_max))
        return tpk_diag_fail(diag, "render: the scalar range must be finite");
    return 0;
}

/* The rows on all threads, once job's marcher (or set) is in place. */
static int run_render(render_job *job, double diagonal, tpk_render_stats *stats, const struct timespec *t0,
                      tpk_diag *diag)
{
    const tpk_render_options *opt = job->opt;
    job->inv_range = opt->range_max != opt->range_min ? 1.0 / (opt->range_max - opt->range_min) : 0.0;
    double unit = opt->unit_distance;
    if (!(unit > 0) || !isfinite(unit))
        unit = diagonal / 100.0;
    job->inv_unit = unit > 0 ? 1.0 / unit : 1.0;
    int rc = setup_camera(job, &opt->camera, diag);
    if (rc != 0)
        return rc;
    atomic_init(&job->next_row, 0);
    atomic_init(&job->failed, 0);
    atomic_init(&job->tet_steps, 0);
    pthread_mutex_init(&job->error_lock, NULL);

    int n = thread_count(opt);
    pthread_t threads[256];
    int started = 0;
    for (; started < n - 1; started++)
        if (pthread_create(&threads[started], NULL, render_worker, job) != 0)
            break; /* fewer threads: the rows still all get done */
    render_worker(job);
    for (int i = 0; i < started; i++)
        pthread_join(threads[i], NULL);

    if (atomic_load(&job->failed))
        rc = tpk_diag_fail(diag, "render: ray of pixel (%d, %d): %s", job->error_x, job->error_y,
                           tpk_result_string(job->error));
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (stats) {
        stats->rays = (uint64_t)opt->width * (uint64_t)opt->height;
        stats->tet_steps = atomic_load(&job->tet_steps);
        stats->seconds = (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
    }
    pthread_mutex_destroy(&job->error_lock);
    return rc;
}

int tpk_render_cpu(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                   tpk_render_stats *stats, tpk_diag *diag)
{
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (check_options(opt, mesh, rgba, diag) != 0)
        return -1;
    render_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "render: out of memory");
    job->opt = opt;
    job->rgba = rgba;
    job->has_scalars = mesh->scalars != NULL;
    tpk_marcher *marcher = NULL;
    tpk_result r = tpk_marcher_create(&marcher, mesh);
    if (r != TPK_OK) {
        free(job);
        return tpk_diag_fail(diag, "render: cannot set up the marcher: %s", tpk_result_string(r));
    }
    job->marcher = marcher;
    int rc = run_render(job, tpk_positions_diagonal(mesh), stats, &t0, diag);
    tpk_marcher_destroy(marcher);
    free(job);
    return rc;
}

int tpk_render_cpu_set(const tpk_set_marcher *marcher, int has_scalars, double diagonal,
                       const tpk_render_options *opt, uint8_t *rgba, tpk_render_stats *stats, tpk_diag *diag)
{
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (check_options(opt, marcher, rgba, diag) != 0)
        return -1;
    render_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "render: out of memory");
    job->opt = opt;
    job->rgba = rgba;
    job->has_scalars = has_scalars;
    job->set = marcher;
    int rc = run_render(job, diagonal, stats, &t0, diag);
    free(job);
    return rc;
}
