/* The CPU volume renderer: one primary ray per pixel through the reference marcher, emission-absorption
 * integrated per tet piece, rows shared between pthreads through an atomic counter. Iso-only rays by
 * range culling go in packets of 4x4 pixels (tpk_march_packet_values), each pixel the same as alone. */
#include "render_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

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

tpk_result tpk_render_use_cull(tpk_file *file, tpk_cull *cull, tpk_render_options *opt)
{
    tpk_result r = tpk_load_cull(file, cull);
    opt->cull = r == TPK_OK ? cull : NULL;
    return r == TPK_ERR_NOT_FOUND ? TPK_OK : r;
}

/* ---- One primary ray: pieces, iso hits, lighting ----------------------------------------------- */

static void point_at(const ray_state *ray, double t, double x[3])
{
    for (int k = 0; k < 3; k++)
        x[k] = ray->job->eye[k] + t * ray->dir[k];
}

/* Composite the hit of iso value v at t in seg's tet (render.h: ISOSURFACES); n is the hit's normal or
 * NULL. */
static void composite_iso(ray_state *ray, const tpk_segment *seg, double t, double v, const double *n)
{
    const render_job *job = ray->job;
    double m = 1.0;
    if (job->setup.lighting) {
        double x[3], s = 1.0, a = 1.0;
        point_at(ray, t, x);
        if (job->vertex_s)
            rl_vertex_lookup(job, seg, x, &s, &a);
        else if (job->opt->occlusion == TPK_OCCLUSION_SURFACE) { /* the first hit is the ray's surface */
            if (job->setup.cast && !ray->cast_done) {
                rl_cast(ray, x, n, &ray->shade_s, &ray->shade_a);
                ray->cast_done = 1;
            }
            s = ray->shade_s, a = ray->shade_a;
        } else if (job->setup.cast)
            rl_cast(ray, x, n, &s, &a);
        m = rl_factor(ray, x, n, s, a);
    }
    double c[4];
    tpk_tf_eval(job->opt->tf, ri_normalized(job, v), c);
    double alpha = job->setup.iso_opacity;
    for (int k = 0; k < 3; k++)
        ray->color[k] += ray->transmittance * alpha * m * c[k];
    ray->transmittance *= 1.0 - alpha;
}

/* The lighting factor of a volume piece (render.h: SHADE POINTS, LIGHTING FACTOR; OCCLUSION AT THE
 * SURFACE: without iso values, the first volume shade point alone) into ray->m. */
static void light_piece(ray_state *ray, const tpk_segment *seg, const double *n, double u_in, double u_out)
{
    const render_job *job = ray->job;
    double length = seg->t_out - seg->t_in, mid[3];
    const int surface = job->opt->occlusion == TPK_OCCLUSION_SURFACE;
    point_at(ray, 0.5 * (seg->t_in + seg->t_out), mid);
    if (job->vertex_s)
        rl_vertex_lookup(job, seg, mid, &ray->shade_s, &ray->shade_a);
    else if (job->setup.cast && !(surface && (job->opt->iso_count > 0 || ray->cast_done)) &&
             ri_optical_depth(job, length, u_in, u_out) > 0 &&
             (!ray->cast_done || ray->t_cast - ray->transmittance >= TPK_RENDER_SHADE_STEP)) {
        rl_cast(ray, mid, n, &ray->shade_s, &ray->shade_a);
        ray->cast_done = 1;
        ray->t_cast = ray->transmittance;
    }
    ray->m = rl_factor(ray, mid, n, ray->shade_s, ray->shade_a);
}

static int on_segment(void *user, const tpk_segment *seg)
{
    ray_state *ray = user;
    const render_job *job = ray->job;
    const tpk_render_options *opt = job->opt;
    const int tet_field = job->tet_scalars != NULL;
    double s_in = tet_field ? job->tet_scalars[seg->tet] : seg->scalar_in;
    double s_out = tet_field ? s_in : seg->scalar_out;
    ri_crossing hits[TPK_RENDER_MAX_ISO];
    int nh = 0;
    if (opt->iso_count > 0 && !tet_field)
        nh = ri_point_crossings(opt, seg->t_in, seg->t_out, s_in, s_out, hits);
    else if (opt->iso_count > 0 && ray->have_prev && ray->prev_t_out == seg->t_in)
        nh = ri_jump_crossings(opt, seg->t_in, ray->prev_s, s_in, hits);
    ray->have_prev = 1;
    ray->prev_t_out = seg->t_out;
    ray->prev_s = s_in;

    double n[3], fn[3];
    const double *np = job->setup.lighting && rl_tet_normal(job, seg, n) ? n : NULL;
    const double u_in = ri_normalized(job, s_in), u_out = ri_normalized(job, s_out);
    ray->m = 1.0;
    if (job->setup.lighting && seg->t_out > seg->t_in)
        light_piece(ray, seg, np, u_in, u_out);
    /* the volume up to each hit, the hit, then the rest of the piece */
    double cur_t = seg->t_in, cur_u = u_in;
    for (int i = 0; i < nh && ray->transmittance > TPK_RENDER_OPAQUE_T; i++) {
        double v = opt->iso[hits[i].j];
        double hit_u = tet_field ? u_in : ri_normalized(job, v);
        ri_integrate(ray, hits[i].t - cur_t, cur_u, hit_u);
        const double *hn = np;
        if (tet_field)
            hn = job->setup.lighting && rl_face_normal(job, seg, fn) ? fn : NULL;
        double m = ray->m;
        composite_iso(ray, seg, hits[i].t, v, hn);
        ray->m = m;
        cur_t = hits[i].t;
        cur_u = hit_u;
    }
    if (ray->transmittance > TPK_RENDER_OPAQUE_T)
        ri_integrate(ray, seg->t_out - cur_t, cur_u, u_out);
    return ray->transmittance <= TPK_RENDER_OPAQUE_T || ray->error != TPK_OK;
}

static uint8_t to_byte(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    return (uint8_t)(v * 255.0 + 0.5);
}

/* A primary ray: its state, the span to march and the callback (render_light.c's rl_ray_spans, which
 * may wrap the callback in sp); 0 when nothing of it is left to march. */
static int ray_begin(const render_job *job, int x, int y, ray_state *ray, double *lo, double *hi, rl_spans *sp,
                     tpk_segment_fn *fn, void **user)
{
    const tpk_render_options *opt = job->opt;
    double px = (2.0 * (x + 0.5) / opt->width - 1.0) * job->tan_half_x;
    double py = (1.0 - 2.0 * (y + 0.5) / opt->height) * job->tan_half_y;
    memset(ray, 0, sizeof *ray);
    ray->job = job;
    ray->px = x;
    ray->py = y;
    ray->transmittance = 1.0;
    ray->shade_s = ray->shade_a = 1.0;
    double len2 = 0;
    for (int k = 0; k < 3; k++) {
        ray->dir[k] = job->forward[k] + px * job->right[k] + py * job->up[k];
        len2 += ray->dir[k] * ray->dir[k];
    }
    double inv_len = 1.0 / sqrt(len2);
    for (int k = 0; k < 3; k++)
        ray->dir[k] *= inv_len; /* unit direction: t is the distance from the eye */
    *lo = 0.0, *hi = INFINITY;
    *fn = on_segment;
    *user = ray;
    return rl_ray_spans(opt, job->eye, ray->dir, lo, hi, sp, fn, user);
}

/* Write the pixel of a marched (or skipped) ray; returns r, else the ray's own error. */
static tpk_result ray_finish(const render_job *job, const ray_state *ray, tpk_result r, uint64_t counts[2])
{
    const tpk_render_options *opt = job->opt;
    counts[0] += ray->steps;
    counts[1] += ray->secondary;
    const float *bg = opt->background;
    double alpha = (1.0 - ray->transmittance) + ray->transmittance * bg[3];
    uint8_t *out = &job->rgba[4 * ((size_t)ray->py * (size_t)opt->width + (size_t)ray->px)];
    for (int k = 0; k < 3; k++) {
        double premult = ray->color[k] + ray->transmittance * bg[3] * bg[k];
        out[k] = to_byte(alpha > 0 ? premult / alpha : 0.0);
    }
    out[3] = to_byte(alpha);
    return r != TPK_OK ? r : ray->error;
}

/* One pixel: returns the marcher's result. */
static tpk_result render_pixel(const render_job *job, int x, int y, uint64_t counts[2])
{
    const tpk_render_options *opt = job->opt;
    ray_state ray;
    double lo, hi;
    rl_spans sp;
    tpk_segment_fn fn;
    void *user;
    tpk_result r = TPK_OK;
    if (ray_begin(job, x, y, &ray, &lo, &hi, &sp, &fn, &user)) {
        tpk_march_stats st;
        if (job->set)
            r = tpk_set_march_ray(job->set, job->eye, ray.dir, lo, hi, fn, user, NULL, &st);
        else if (job->range)
            r = tpk_march_ray_values(job->range, job->eye, ray.dir, lo, hi, opt->iso, opt->iso_count, fn, user, &st);
        else
            r = tpk_march_ray(job->marcher, job->eye, ray.dir, lo, hi, fn, user, &st);
        ray.steps += st.tet_steps;
    }
    return ray_finish(job, &ray, r, counts);
}

/* Iso-only rays by range culling go PACKET x PACKET pixels at a time (tpk_march_packet_values): neighbours
 * meet the same nodes and tets, which the packet tests once for all of them. */
#define PACKET 4

/* The pixels [x0, x0 + PACKET) x [y0, y0 + PACKET) that lie in the picture, as one packet; the first
 * failure, and its pixel in *fail_x, *fail_y. */
static tpk_result render_packet(const render_job *job, int x0, int y0, uint64_t counts[2], int *fail_x, int *fail_y)
{
    const tpk_render_options *opt = job->opt;
    ray_state rays[PACKET * PACKET];
    rl_spans sp[PACKET * PACKET];
    /* zeroed: only the first `marched` are read, which GCC cannot see under the sanitizers */
    double dirs[PACKET * PACKET][3], lo[PACKET * PACKET] = {0}, hi[PACKET * PACKET] = {0};
    tpk_segment_fn fns[PACKET * PACKET] = {0};
    void *users[PACKET * PACKET] = {0};
    tpk_march_stats st[PACKET * PACKET];
    int walks[PACKET * PACKET], count = 0, marched = 0;
    for (int y = y0; y < y0 + PACKET && y < opt->height; y++)
        for (int x = x0; x < x0 + PACKET && x < opt->width; x++, count++)
            if ((walks[count] = ray_begin(job, x, y, &rays[count], &lo[marched], &hi[marched], &sp[count],
                                          &fns[marched], &users[marched])))
                memcpy(dirs[marched++], rays[count].dir, sizeof dirs[0]);
    tpk_result r = tpk_march_packet_values(job->range, job->eye, marched, (const double(*)[3])dirs, lo, hi, opt->iso,
                                           opt->iso_count, fns, users, st);
    tpk_result first = TPK_OK;
    for (int i = 0, m = 0; i < count; i++) {
        if (walks[i])
            rays[i].steps += st[m++].tet_steps;
        tpk_result ri = ray_finish(job, &rays[i], r, counts);
        if (ri != TPK_OK && first == TPK_OK)
            first = ri, *fail_x = rays[i].px, *fail_y = rays[i].py;
    }
    return first;
}

/* Pixels go in tiles of TILE x TILE, a band of TILE rows at a time per thread: neighbouring rays meet
 * the same tets and BVH nodes, so a tile's rays find them in cache (a whole row spans the mesh). */
#define TILE 8

/* The frame's first failure, kept with its pixel. */
static void note_failure(render_job *job, tpk_result r, int x, int y)
{
    pthread_mutex_lock(&job->error_lock);
    if (!atomic_load(&job->failed)) {
        job->error = r;
        job->error_x = x;
        job->error_y = y;
        atomic_store(&job->failed, 1);
    }
    pthread_mutex_unlock(&job->error_lock);
}

static void *render_worker(void *arg)
{
    render_job *job = arg;
    const int width = job->opt->width, height = job->opt->height;
    struct timespec c0, c1;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    uint64_t counts[2] = {0, 0}; /* marcher steps, secondary rays */
    for (;;) {
        int band = atomic_fetch_add(&job->next_row, 1);
        if (band * TILE >= height || atomic_load(&job->failed))
            break;
        int failed = 0;
        for (int x0 = 0; x0 < width && !failed; x0 += TILE) {
            if (job->range && !job->set) {
                for (int y = band * TILE; y < band * TILE + TILE && y < height && !failed; y += PACKET)
                    for (int x = x0; x < x0 + TILE && x < width && !failed; x += PACKET) {
                        int fail_x = x, fail_y = y;
                        tpk_result r = render_packet(job, x, y, counts, &fail_x, &fail_y);
                        if (r != TPK_OK)
                            note_failure(job, r, fail_x, fail_y), failed = 1;
                    }
                continue;
            }
            for (int y = band * TILE; y < band * TILE + TILE && y < height && !failed; y++)
                for (int x = x0; x < x0 + TILE && x < width; x++) {
                    tpk_result r = render_pixel(job, x, y, counts);
                    if (r != TPK_OK) {
                        note_failure(job, r, x, y), failed = 1;
                        break;
                    }
                }
        }
    }
    atomic_fetch_add(&job->tet_steps, counts[0]);
    atomic_fetch_add(&job->secondary_rays, counts[1]);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    atomic_fetch_add(&job->ray_cpu_ns, (uint64_t)((c1.tv_sec - c0.tv_sec) * 1000000000LL + (c1.tv_nsec - c0.tv_nsec)));
    return NULL;
}

/* ---- Setup -------------------------------------------------------------------------------------- */

int tpk_render_iso_only(const tpk_render_options *opt, int has_point_scalars)
{
    if (!opt || opt->iso_count <= 0 || opt->tet_scalars || !has_point_scalars || !opt->tf)
        return 0;
    for (int i = 0; i < opt->tf->count; i++)
        if (opt->tf->points[i].a != 0.0)
            return 0;
    return 1;
}

int tpk_render_culling_wanted(void)
{
    const char *v = getenv("TETPACK_ISO_CULLING");
    return !v || !*v ? -1 : strcmp(v, "0") == 0 ? 0 : 1;
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

/* The job's view of the options: tpk_render_setup_of, the derivation every backend shares. */
static int setup_job(render_job *job, int has_point_scalars, double diagonal, const tpk_render_options *opt,
                     tpk_diag *diag)
{
    tpk_render_setup setup;
    if (tpk_render_setup_of(opt, diagonal, &setup, diag) != 0)
        return -1;
    job->opt = opt;
    job->tet_scalars = opt->tet_scalars;
    job->has_scalars = has_point_scalars || opt->tet_scalars != NULL;
    job->clear_volume = opt->tf && opt->integration != TPK_INTEGRATION_SAMPLED &&
                        opt->integration != TPK_INTEGRATION_MIDPOINT;
    for (int i = 0; opt->tf && i < opt->tf->count; i++)
        job->clear_volume &= opt->tf->points[i].a == 0.0;
    job->setup = setup;
    memcpy(job->eye, opt->camera.eye, sizeof job->eye);
    memcpy(job->forward, setup.basis.forward, sizeof job->forward);
    memcpy(job->right, setup.basis.right, sizeof job->right);
    memcpy(job->up, setup.basis.up, sizeof job->up);
    job->tan_half_y = setup.basis.tan_half_y;
    job->tan_half_x = setup.basis.tan_half_x;
    return 0;
}

/* ISO-ONLY RAYS' glance (render.h): more than TPK_RENDER_DENSE_RUNS of the runs of 8 consecutive vertices
 * hold one of the values. */
int tpk_render_iso_dense(const tpk_mesh_arrays *mesh, const double *values, int count)
{
    const int64_t n = (int64_t)mesh->vertex_count, run = 8;
    int64_t runs = 0, holding = 0;
    for (int64_t first = 0; first < n; first += run, runs++) {
        float lo = INFINITY, hi = -INFINITY;
        for (int64_t v = first; v < first + run && v < n; v++) {
            float s = mesh->scalars[v];
            lo = s < lo ? s : lo;
            hi = s > hi ? s : hi;
        }
        for (int j = 0; j < count; j++)
            if (values[j] >= lo && values[j] <= hi) {
                holding++;
                break;
            }
    }
    return runs > 0 && (double)holding > TPK_RENDER_DENSE_RUNS * (double)runs;
}

/* The rows on all threads, once the job's marcher (or part set) and options are in place. */
static int run_render(render_job *job, tpk_render_stats *stats, const struct timespec *t0, tpk_diag *diag)
{
    const tpk_render_options *opt = job->opt;
    int rc = 0;
    atomic_init(&job->next_row, 0);
    atomic_init(&job->failed, 0);
    atomic_init(&job->tet_steps, 0);
    atomic_init(&job->secondary_rays, 0);
    atomic_init(&job->ray_cpu_ns, 0);
    pthread_mutex_init(&job->error_lock, NULL);

    struct timespec t_rays;
    clock_gettime(CLOCK_MONOTONIC, &t_rays);
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
        stats->secondary_rays = atomic_load(&job->secondary_rays);
        stats->seconds = (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
        stats->seconds_rays = (double)(t1.tv_sec - t_rays.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t_rays.tv_nsec);
        stats->cpu_seconds_rays = 1e-9 * (double)atomic_load(&job->ray_cpu_ns);
    }
    pthread_mutex_destroy(&job->error_lock);
    return rc;
}

int tpk_render_cpu(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                   tpk_render_stats *stats, tpk_diag *diag)
{
    return tpk_render_cpu_given_cache(mesh, opt, rgba, NULL, NULL, stats, diag);
}

int tpk_render_same_mesh(const tpk_mesh_arrays *x, const tpk_mesh_arrays *y)
{
    return x->vertex_count == y->vertex_count && x->tet_count == y->tet_count &&
           x->shell_face_count == y->shell_face_count && !memcmp(x->origin, y->origin, sizeof x->origin) &&
           x->positions == y->positions && x->layout == y->layout && x->tet16 == y->tet16 && x->tet20 == y->tet20 &&
           x->tet32 == y->tet32 && x->shell == y->shell;
}

void render_keep_free(render_keep *keep)
{
    tpk_range_bvh_destroy(keep->range);
    tpk_marcher_destroy(keep->marcher);
    int frames = keep->frames;
    memset(keep, 0, sizeof *keep);
    keep->frames = frames;
}

/* The range trees for an iso-only frame (render.h ISO-ONLY RAYS), kept in `keep` or made (own: `keep` is
 * the frame's own, freed after it): NULL where the frame marches. *rc -1 (with a message) on failure. */
static tpk_range_bvh *culling_trees(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, render_keep *keep,
                                    int own, int *rc, tpk_diag *diag)
{
    int culling = tpk_render_culling_wanted();
    if (culling == 0 || !tpk_render_iso_only(opt, mesh->scalars != NULL))
        return NULL;
    /* many rays pay for the trees on any surface, few only on a sparse one; trees already kept are paid,
     * and trees to be kept are paid by the frames each field is drawn with (TPK_RENDER_KEPT_FRAMES, or
     * tpk_vertex_cache_frames_per_field's) */
    /* for this marcher, hence these arrays; a field read into kept trees is not paid for by earlier frames,
     * so the choice is that field's alone (tests/cli/render_effects.sh), only its set-up shorter */
    int kept = keep->range != NULL && !keep->range_new_field;
    int frames = own ? 1 : keep->frames > 0 ? keep->frames : TPK_RENDER_KEPT_FRAMES;
    double rays = (double)opt->width * (double)opt->height * frames;
    int many_rays = kept || rays >= (double)mesh->tet_count;
    if (!kept && culling < 0 && !many_rays && tpk_render_iso_dense(mesh, opt->iso, opt->iso_count))
        return NULL;
    tpk_result r = TPK_OK;
    if (!keep->range) {
        keep->value_count = 0;
        r = opt->cull ? tpk_range_bvh_create_cull(&keep->range, keep->marcher, opt->cull, thread_count(opt))
                      : tpk_range_bvh_create_threads(&keep->range, keep->marcher, thread_count(opt));
    }
    keep->range_new_field = 0;
    if (r == TPK_OK) {
        double share = culling < 0 ? tpk_range_bvh_active(keep->range, opt->iso, opt->iso_count) : 0.0;
        /* fewer rays than tets: the share culling pays for grows with the rays, up to a quarter as many */
        double few = TPK_RENDER_CULL_ACTIVE + (TPK_RENDER_CULL_ACTIVE_CPU - TPK_RENDER_CULL_ACTIVE) *
                                                  fmin(1.0, rays / (0.25 * (double)mesh->tet_count));
        if (share > (many_rays ? TPK_RENDER_CULL_ACTIVE_MANY : few))
            return NULL; /* a dense isosurface: marching finds it sooner */
    }
    if (r == TPK_OK)
        r = tpk_range_bvh_set_threads(keep->range, thread_count(opt));
    if (r == TPK_OK && (keep->value_count != opt->iso_count ||
                        memcmp(keep->values, opt->iso, sizeof *opt->iso * (size_t)opt->iso_count) != 0)) {
        keep->value_count = 0;
        r = tpk_range_bvh_select(keep->range, opt->iso, opt->iso_count);
        memcpy(keep->values, opt->iso, sizeof *opt->iso * (size_t)opt->iso_count);
        keep->value_count = r == TPK_OK ? opt->iso_count : 0;
    }
    if (r != TPK_OK) {
        *rc = tpk_diag_fail(diag, "render: cannot set up the range culling of iso rays: %s", tpk_result_string(r));
        return NULL;
    }
    return keep->range;
}

int tpk_render_cpu_given_cache(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                               const float *given_s, const float *given_a, tpk_render_stats *stats, tpk_diag *diag)
{
    return render_cpu_keeping(mesh, opt, rgba, given_s, given_a, NULL, stats, diag);
}

int render_cpu_keeping(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba, const float *given_s,
                       const float *given_a, render_keep *keep, tpk_render_stats *stats, tpk_diag *diag)
{
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!mesh || !opt || !rgba)
        return tpk_diag_fail(diag, "render: mesh, options and image buffer are required");
    if (tpk_render_check_options(opt, diag))
        return -1;
    render_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "render: out of memory");
    job->rgba = rgba;
    job->mesh = mesh;
    if (setup_job(job, mesh->scalars != NULL, tpk_positions_diagonal(mesh), opt, diag) != 0) {
        free(job);
        return -1;
    }
    render_keep own = {0}; /* made for this frame when nothing is kept */
    render_keep *k = keep ? keep : &own;
    if (k->marcher && !(tpk_render_same_mesh(&k->mesh, mesh) && k->mesh.scalars == mesh->scalars)) {
        /* another field of the same mesh (a time step): the marcher and the range trees read it from now
         * on, the trees keeping what depends on the positions alone (the tets' vertices, the boxes: the walk
         * of a Tet16 file is most of their set-up); the selected tree is made again */
        if (tpk_render_same_mesh(&k->mesh, mesh)) {
            tpk_marcher_set_scalars(k->marcher, mesh->scalars);
            if (k->range && (!mesh->scalars || tpk_range_bvh_set_scalars(k->range) != TPK_OK)) {
                tpk_range_bvh_destroy(k->range);
                k->range = NULL;
            }
            k->range_new_field = k->range != NULL;
            k->value_count = 0;
            k->mesh.scalars = mesh->scalars;
        } else {
            render_keep_free(k);
        }
    }
    tpk_result r = TPK_OK;
    if (!k->marcher && (r = tpk_marcher_create(&k->marcher, mesh)) != TPK_OK) {
        free(job);
        return tpk_diag_fail(diag, "render: cannot set up the marcher: %s", tpk_result_string(r));
    }
    job->marcher = k->marcher;
    int rc = 0;
    float *cache = NULL;
    uint64_t cache_counts[2] = {0, 0}; /* steps, secondary rays */
    struct timespec c0 = {0, 0}, c1 = {0, 0}; /* the cache's casts */
    if (job->setup.cast && opt->occlusion == TPK_OCCLUSION_VERTEX && given_s && given_a) {
        job->vertex_s = given_s;
        job->vertex_a = given_a;
    } else if (job->setup.cast && opt->occlusion == TPK_OCCLUSION_VERTEX) {
        clock_gettime(CLOCK_MONOTONIC, &c0);
        cache = malloc(2 * sizeof *cache * (mesh->vertex_count ? mesh->vertex_count : 1));
        if (!cache) {
            rc = tpk_diag_fail(diag, "render: out of memory for the vertex cache");
        } else {
            job->vertex_s = cache;
            job->vertex_a = cache + mesh->vertex_count;
            r = rl_vertex_cache(job, opt->threads, cache, cache + mesh->vertex_count, &cache_counts[0],
                                &cache_counts[1]);
            if (r != TPK_OK)
                rc = tpk_diag_fail(diag, "render: vertex cache: %s", tpk_result_string(r));
        }
        clock_gettime(CLOCK_MONOTONIC, &c1);
    }
    tpk_range_bvh *range = rc == 0 ? culling_trees(mesh, opt, k, keep == NULL, &rc, diag) : NULL;
    k->mesh = *mesh;
    job->range = range;
    if (rc == 0)
        rc = run_render(job, stats, &t0, diag);
    if (rc == 0 && stats) {
        stats->iso_culling = range != NULL;
        stats->tet_steps += cache_counts[0];
        stats->secondary_rays += cache_counts[1];
        stats->vertex_cache_seconds = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
    }
    free(cache);
    if (!keep)
        render_keep_free(&own);
    free(job);
    return rc;
}

int tpk_render_vertex_cache(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, float *s, float *a,
                            tpk_render_stats *stats, tpk_diag *diag)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!mesh || !opt || !s || !a)
        return tpk_diag_fail(diag, "render: mesh, options and cache arrays are required");
    if (tpk_render_check_options(opt, diag))
        return -1;
    render_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "render: out of memory");
    job->mesh = mesh;
    tpk_marcher *marcher = NULL;
    int rc = setup_job(job, mesh->scalars != NULL, tpk_positions_diagonal(mesh), opt, diag);
    tpk_result r = rc == 0 ? tpk_marcher_create(&marcher, mesh) : TPK_OK;
    if (r != TPK_OK)
        rc = tpk_diag_fail(diag, "render: cannot set up the marcher: %s", tpk_result_string(r));
    uint64_t counts[2] = {0, 0};
    if (rc == 0) {
        job->marcher = marcher;
        r = rl_vertex_cache(job, opt->threads, s, a, &counts[0], &counts[1]);
        if (r != TPK_OK)
            rc = tpk_diag_fail(diag, "render: vertex cache: %s", tpk_result_string(r));
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (stats) {
        stats->tet_steps = counts[0];
        stats->secondary_rays = counts[1];
        stats->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    }
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
    if (!marcher || !opt || !rgba)
        return tpk_diag_fail(diag, "render: part set, options and image buffer are required");
    if (tpk_render_check_options(opt, diag))
        return -1;
    /* Normals and tet fields index one mesh's vertices and tets; a set's segments name a part's: those
     * frames go through the set as one mesh (tpk_set_mesh), as render and view do. */
    if (opt->shading || opt->shadows || opt->ao_rays > 0 || opt->tet_scalars)
        return tpk_diag_fail(diag, "render: the link-following marcher of a part set renders emission-absorption, "
                                   "isosurfaces, a clip box and probes; shading, shadows, ambient occlusion and "
                                   "tet fields render the set as one mesh (tpk_set_mesh)");
    render_job *job = calloc(1, sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "render: out of memory");
    job->rgba = rgba;
    job->set = marcher;
    int rc = setup_job(job, has_scalars, diagonal, opt, diag);
    if (rc == 0)
        rc = run_render(job, stats, &t0, diag);
    free(job);
    return rc;
}
