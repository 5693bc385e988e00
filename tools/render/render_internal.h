/* Private declarations of the CPU reference renderer, shared by its files. The effect definitions they
 * implement are in render.h. Owners, top to bottom (a file calls only files below it):
 *   render_cpu.c        tpk_render_cpu, tpk_render_options_default, tpk_camera_default: setup, threads,
 *                       primary rays, pieces, iso hits
 *   render_light.c      rl_*: normals, clip slab test, secondary rays (shadow, AO), the lighting factor
 *   render_integrate.c  ri_*: emission-absorption of one piece, optical depth, iso crossings */
#ifndef TPK_RENDER_INTERNAL_H
#define TPK_RENDER_INTERNAL_H

#include <stdatomic.h>
#include <pthread.h>

#include "render.h"

/* What the CPU reference keeps across frames for one mesh and field (render.h: tpk_vertex_cache holds
 * one): the marcher and the range culling's trees (made on the marcher), made again only when the
 * arrays change (by pointer); another field (by pointer) is read into them, the selected tree made again. */
typedef struct render_keep {
    tpk_mesh_arrays mesh;   /* the arrays they were made for (a copy of the struct) */
    tpk_marcher *marcher;
    tpk_range_bvh *range;   /* NULL: not made */
    int range_new_field;    /* range has read a new field since the last frame: the automatic culling
                               choice counts its set-up as unpaid, as for that field alone */
    double values[TPK_RENDER_MAX_ISO]; /* the values the range trees were selected for */
    int value_count;        /* 0: none selected */
    int frames;             /* the frames a field is drawn with (tpk_vertex_cache_frames_per_field);
                               0: TPK_RENDER_KEPT_FRAMES */
} render_keep;

/* Free what `keep` holds and zero it, but for `frames` (a choice of the caller's, not set-up). */
void render_keep_free(render_keep *keep);
/* tpk_render_cpu_given_cache, keeping the marcher and range trees in `keep` (NULL: made for the frame). */
int render_cpu_keeping(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba, const float *s,
                       const float *a, render_keep *keep, tpk_render_stats *stats, tpk_diag *diag);

typedef struct render_job {
    const tpk_render_options *opt;
    const tpk_mesh_arrays *mesh;
    const tpk_marcher *marcher;
    const tpk_set_marcher *set; /* a part set instead (spec §15): no lighting, no tet field */
    const tpk_range_bvh *range; /* iso-only (render.h: ISO-ONLY RAYS): primary rays find their pieces by
                                   range culling, not by marching every tet */
    const float *tet_scalars;  /* opt->tet_scalars (a tet field) or NULL */
    int has_scalars;           /* a point or a tet field */
    int clear_volume;          /* exact integration of a TF with opacity 0 everywhere: a stretch adds nothing */
    tpk_render_setup setup;    /* what every backend derives from the options (render.h) */
    const float *vertex_s, *vertex_a; /* TPK_OCCLUSION_VERTEX: S_v and A_v per vertex (NULL: ray) */
    double eye[3], forward[3], right[3], up[3];
    double tan_half_y, tan_half_x;
    uint8_t *rgba;
    atomic_int next_row;
    atomic_int failed;
    pthread_mutex_t error_lock;
    tpk_result error;
    int error_x, error_y;
    atomic_uint_least64_t tet_steps, secondary_rays;
    atomic_uint_least64_t ray_cpu_ns; /* CPU time of the workers, summed */
} render_job;

/* The accumulators of one primary ray. */
typedef struct ray_state {
    const render_job *job;
    int px, py;                /* the pixel, for the AO rotation */
    double dir[3];             /* unit direction of the primary ray */
    double color[3];           /* accumulated, premultiplied */
    double transmittance;
    double m;                  /* lighting factor of the piece being integrated */
    int cast_done;             /* a volume shade point was taken */
    double t_cast;             /* transmittance when it was taken */
    double shade_s, shade_a;   /* its S and A */
    int have_prev;             /* tet field iso: the previous piece of the run */
    double prev_t_out, prev_s;
    uint64_t steps, secondary; /* marcher steps (all rays) and secondary rays of this pixel */
    tpk_result error;          /* a secondary ray's marcher failure */
} ray_state;

/* ---- render_integrate.c ---- */

/* u(s): the scalar mapped onto the TF's [0, 1], 0.5 without a field or range. */
double ri_normalized(const render_job *job, double scalar);
/* Composite a stretch of `length` over which the scalar goes linearly from u0 to u1 (TF units), with
 * the job's integration mode; ray->m multiplies its colour. */
void ri_integrate(ray_state *ray, double length, double u0, double u1);
/* Optical depth of that stretch, exact for the piecewise linear TF alpha. */
double ri_optical_depth(const render_job *job, double length, double u0, double u1);

/* An iso crossing inside a piece: distance and iso index. */
typedef struct ri_crossing {
    double t;
    int j;
} ri_crossing;
/* The crossings of the point-field piece [t_in, t_out], scalar s_in -> s_out, in increasing t (then
 * j), half-open as render.h defines; returns how many (<= TPK_RENDER_MAX_ISO). */
int ri_point_crossings(const tpk_render_options *opt, double t_in, double t_out, double s_in, double s_out,
                       ri_crossing out[TPK_RENDER_MAX_ISO]);
/* Crossings of a tet-field jump from s_prev to s at t: same order. */
int ri_jump_crossings(const tpk_render_options *opt, double t, double s_prev, double s,
                      ri_crossing out[TPK_RENDER_MAX_ISO]);

/* ---- render_light.c ---- */

/* Clip [*lo, *hi] of the ray org + t dir to the clip box (when opt->clip); 0 when nothing is left. */
int rl_clip(const tpk_render_options *opt, const double org[3], const double dir[3], double *lo, double *hi);
/* The probes' spans of one ray (render.h PROBES) and the callback it is marched with. */
typedef struct rl_spans {
    double span[TPK_RENDER_MAX_PROBES + 1][2];
    int n;
    tpk_segment_fn fn;
    void *user;
} rl_spans;
/* rl_clip, then the probes: [*lo, *hi] becomes the range to march and, with probes, *fn and *user the
 * callback that cuts each piece to the spans before it calls the given one (kept in sp). 0 when
 * nothing of the ray is left. */
int rl_ray_spans(const tpk_render_options *opt, const double org[3], const double dir[3], double *lo, double *hi,
                 rl_spans *sp, tpk_segment_fn *fn, void **user);
/* Unit normal of the segment's tet for shading: the point field's gradient direction; 0 when none. */
int rl_tet_normal(const render_job *job, const tpk_segment *seg, double n[3]);
/* Unit normal of the segment's entry face v[0..2]; 0 when degenerate. */
int rl_face_normal(const render_job *job, const tpk_segment *seg, double n[3]);
/* Shadow transmittance S and AO factor A at world point x with normal n (NULL: none); 1 when that
 * effect is off. Adds the secondary marcher steps to ray->steps; a marcher failure goes to ray->error. */
void rl_cast(ray_state *ray, const double x[3], const double *n, double *s, double *a);
/* The vertex cache (render.h: OCCLUSION AT VERTICES) on `threads` workers into s[] and a[] (vertex_count
 * floats each; an effect that is off gives 1); adds its steps and rays to *steps and *secondary.
 * Returns the first marcher failure, or TPK_OK. */
tpk_result rl_vertex_cache(const render_job *job, int threads, float *s, float *a, uint64_t *steps,
                           uint64_t *secondary);
/* S and A of the vertex cache interpolated at world point x in the segment's tet. */
void rl_vertex_lookup(const render_job *job, const tpk_segment *seg, const double x[3], double *s, double *a);
/* The lighting factor m = A * (K_AMB + (1 - K_AMB) * D * S) at x with normal n (NULL: none). */
double rl_factor(const ray_state *ray, const double x[3], const double *n, double s, double a);

#endif
