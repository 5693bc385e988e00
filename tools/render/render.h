/* The CPU volume renderer (emission-absorption over the reference marcher, all cores) and PNG output.
 * The image origin is the top-left pixel; pixels are RGBA 8-bit, straight (not premultiplied) alpha. */
#ifndef TPK_RENDER_H
#define TPK_RENDER_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "tetpack.h"
#include "render_options.h"
#include "transfer_function.h"

typedef struct tpk_camera {
    double eye[3], at[3], up[3]; /* world coordinates */
    double fovy_deg;             /* vertical field of view */
} tpk_camera;

/* A camera that frames the box from a 3/4 view: eye along (1, 0.6, 0.8) from the box center, far
 * enough that the bounding sphere fits the view with a margin, up = +z, fovy 35. */
void tpk_camera_default(const double bounds_min[3], const double bounds_max[3], tpk_camera *out);

/* The view basis of a camera: unit forward (eye to at), right and up (up from the camera's up, made
 * perpendicular; any perpendicular where up is along the view), and tan of half the field of view in y
 * and in x for a width x height image. Both backends take their rays from this one function. Returns 0,
 * or -1 with a message (a coordinate that is not finite, eye == at, fovy outside (0, 180)). */
typedef struct tpk_camera_basis {
    double forward[3], right[3], up[3];
    double tan_half_x, tan_half_y;
} tpk_camera_basis;
int tpk_camera_basis_of(const tpk_camera *cam, int width, int height, tpk_camera_basis *out, tpk_diag *diag);

/* A CSG probe (PROBES below): a sphere (center a, radius), a half-space (the side of the plane through a
 * that its normal b points away from) or a box [a, b]; `cut` 0 keeps only what is inside it, 1 cuts
 * what is inside it away. */
#define TPK_RENDER_MAX_PROBES_ 4
#define TPK_PROBE_SPHERE 1
#define TPK_PROBE_PLANE 2
#define TPK_PROBE_BOX 3
typedef struct tpk_probe {
    int shape; /* TPK_PROBE_* */
    int cut;   /* 0: keep inside, 1: cut inside away */
    double a[3], b[3];
    double radius;
} tpk_probe;

/* Render options. tpk_render_options_default fills friendly defaults; a zero-initialised struct
 * (plus width, height, camera and tf) also works: then the background is transparent black. The fields
 * of the rows of render_options.def with R = 1 come from that table; for them zero is the default:
 * unit_distance (TF alpha is opacity per this distance; <= 0: bbox diagonal / 100), threads (<= 0: all
 * cores), integration (TPK_INTEGRATION_EXACT 0; _SAMPLED 1: samples at the midpoints of equal steps of
 * at most unit_distance / 2, at least 1 per piece; _MIDPOINT 2: one sample per piece at its midpoint),
 * iso_opacity (of an isosurface hit; <= 0: 1, opaque), shading (gradient Lambert, two-sided), shadows
 * (transmittance toward the point light), ao_rays (ambient occlusion with this many hemisphere rays, at
 * most TPK_RENDER_MAX_AO_RAYS; 0: off), ao_radius (AO ray length; <= 0: bounds diagonal / 10) and
 * occlusion (where shadow and AO rays start: TPK_OCCLUSION_RAY 0 at the shade points of every primary
 * ray, TPK_OCCLUSION_VERTEX 1 at the mesh vertices, once per frame, interpolated, TPK_OCCLUSION_SURFACE 2
 * at one surface point per primary ray; below). */
typedef struct tpk_render_options {
    int width, height;             /* pixels, 1 .. TPK_RENDER_MAX_SIZE each */
    tpk_camera camera;
    const tpk_transfer_function *tf;
    double range_min, range_max;   /* scalar range mapped to TF s in [0,1]; equal: every scalar -> 0.5 */
    float background[4];           /* RGBA, straight alpha, composited behind the volume */
    /* ---- Effects (zero: off). Both backends (CPU reference, Vulkan) implement each one with the
     * same definition, so their pictures agree; the definitions live in render.h's comments and in
     * docs/ARCHITECTURE.md "Render effects". */
    const float *tet_scalars;      /* per tet (a tet field): constant in each tet, replaces the
                                      point scalars of the mesh for colour, opacity and iso */
    const tpk_cull *cull;          /* the file's culling blocks (spec §17) or NULL: the CPU reference's culled
                                      iso rays then walk only the blocks that may hold a value
                                      (tpk_range_bvh_create_cull); the same picture */
    int iso_count;                 /* 0..TPK_RENDER_MAX_ISO exact isosurfaces of the linear scalar */
    double iso[4];                 /* iso values (in scalar units, not TF units) */
    int clip;                      /* nonzero: only the volume inside [clip_min, clip_max] shows */
    double clip_min[3], clip_max[3];
    int have_light;                /* zero: a headlight at the camera eye */
    double light[3];               /* point light position, world coordinates */
    int probe_count;               /* 0..TPK_RENDER_MAX_PROBES CSG probes (PROBES below) */
    tpk_probe probes[TPK_RENDER_MAX_PROBES_];
    /* The table's options (render_options.def, R = 1). */
#define TPK_OPTION TPK_OPTION_FIELD_R
#include "render_options.def"
#undef TPK_OPTION
} tpk_render_options;

#define TPK_RENDER_MAX_ISO 4
#define TPK_RENDER_MAX_PROBES TPK_RENDER_MAX_PROBES_
#define TPK_RENDER_MAX_SIZE 32768
#define TPK_RENDER_MAX_AO_RAYS 1024
#define TPK_INTEGRATION_EXACT 0
#define TPK_INTEGRATION_SAMPLED 1
#define TPK_INTEGRATION_MIDPOINT 2
#define TPK_OCCLUSION_RAY 0
#define TPK_OCCLUSION_VERTEX 1
#define TPK_OCCLUSION_SURFACE 2
#define TPK_ISO_RASTER_AUTO 0
#define TPK_ISO_RASTER_COMPUTE 1
#define TPK_ISO_RASTER_GRAPHICS 2

/* ---- Effect definitions (the contract between the CPU reference and the Vulkan renderer) ----------
 * Notation. Primary ray x(t) = eye + t d, d unit, t = distance. The marcher reports pieces
 * [t_in, t_out] of one tet (tpk_segment: v[0..2] the face it entered through, v[3] the fourth vertex).
 * Scalar s: point field: linear on the piece from scalar_in to scalar_out; tet field: tet_scalars[tet]
 * on the whole piece. u(s) = (s - range_min) / (range_max - range_min), u = 0.5 when the range is empty
 * or there is no field. TF(u) = (r, g, b, a); extinction k(u) = a / unit_distance. Colour is composited
 * front to back: C += T * alpha * m * rgb, T *= 1 - alpha, starting at C = 0, T = 1.
 *
 * CLIP BOX (clip != 0). Slab test of every ray (primary, shadow, AO) against [clip_min, clip_max]:
 * per axis k, with d_k != 0, ta = (clip_min_k - o_k) / d_k, tb = (clip_max_k - o_k) / d_k,
 * lo = max(lo, min(ta, tb)), hi = min(hi, max(ta, tb)); with d_k == 0 the ray misses when o_k is
 * outside [clip_min_k, clip_max_k]. Start lo = tmin of the ray, hi = its tmax; the ray is marched over
 * [lo, hi] (the marcher's tmin/tmax) and nothing when lo > hi: outside the box there is no volume and
 * no isosurface, for every ray. Primary rays: tmin = 0, tmax = infinity.
 *
 * PROBES (probe_count > 0). Each probe has an inside: sphere |x - a| <= radius (radius > 0); half-space
 * (x - a) . b <= 0 (b != 0, any length); box a <= x <= b on every axis (a <= b). On a ray (origin o, unit d,
 * after the clip box has cut it to [lo, hi]) the inside is one interval [t0, t1] or none: sphere with
 * q = d . (o - a), c = |o - a|^2 - radius^2, disc = q^2 - c: none when disc < 0, else -q -+ sqrt(disc);
 * half-space with e = (o - a) . b, f = d . b: f = 0: all t when e <= 0, none otherwise; f > 0: (-inf, -e/f];
 * f < 0: [-e/f, inf); box: the clip box's slab test. The ray is kept where every keep probe (cut 0) holds
 * it inside and no cut probe (cut 1) does: starting from the one span [lo, hi] (none when lo >= hi), a keep
 * probe intersects every span with [t0, t1] (none: no span is left); a cut probe replaces every span
 * [p, q] by [p, min(q, t0)] and [max(p, t1), q] (none: spans unchanged); after each probe, spans of zero or
 * negative length are dropped. At most probe_count + 1 spans remain, in order. The ray is marched over
 * [first span's start, last span's end] and each piece is cut to the spans: each part [a, b] of a piece
 * inside a span is a piece of its own (scalars interpolated linearly to a and b), in order; parts outside
 * every span contribute nothing. This holds for every ray (primary, shadow, AO, vertex occlusion).
 * Without probes the spans are the clip box's [lo, hi] alone, as above.
 *
 * EARLY TERMINATION. A primary ray stops after the piece (or iso hit) that brings T <= 0.02.
 *
 * NORMAL. Point field: the tet's gradient g = [(s1-s0)(e2 x e3) + (s2-s0)(e3 x e1) + (s3-s0)(e1 x e2)] /
 * (e1 . (e2 x e3)), e_i = p_i - p0, p_i and s_i the positions and scalars of v[0..3] of the segment;
 * n = g / |g|, and no normal when g = 0 (or not finite). Tet field: no normal inside a tet; at a tet-field
 * iso hit n is the unit normal (p1 - p0) x (p2 - p0) of the entry face v[0..2].
 *
 * LIGHT. Position light[] (have_light) or the eye. For a point x: L = (light - x) / |light - x|.
 *
 * LIGHTING FACTOR m of a shade point x (multiplies rgb; opacity is never changed):
 *   m = A * (K_AMB + (1 - K_AMB) * D * S),   K_AMB = TPK_RENDER_AMBIENT = 0.3
 *   D = |n . L| (two-sided Lambert) with shading on and a normal, else 1;
 *   S = shadow transmittance from x (shadows on), else 1;  A = AO factor at x (ao_rays > 0), else 1.
 *   With shading, shadows and AO all off, m = 1 (plain emission-absorption).
 *   A volume piece uses x = its midpoint (t_in + t_out) / 2 for D, each piece its own normal.
 *
 * SHADE POINTS (where shadow and AO rays start; bounds their cost). Iso hits: every hit is one. Volume:
 * before integrating a piece of optical depth tau > 0 (tau = length * mean k over the piece, exact for
 * the piecewise linear TF), it becomes a shade point, at its midpoint, when no volume piece of this ray
 * has been one yet or when T_cast - T >= TPK_RENDER_SHADE_STEP (= 1/32), T_cast being T when the last
 * volume shade point was taken. Pieces in between reuse S and A of the last volume shade point. So a
 * pixel casts at most ~32 volume shade points (T falls from 1 to 0.02).
 *
 * TRANSMITTANCE of a secondary ray from x along unit w over [0, len] (clipped by the box as above):
 * T2 = exp(-sum over pieces of length * mean k) (exact mean of the piecewise linear TF alpha for a point
 * field, constant for a tet field, whatever `integration` says), times (1 - iso_opacity) for every iso
 * crossing at t > TPK_RENDER_SELF_EPS * unit_distance (an isosurface hides what is behind it; the
 * epsilon keeps a hit from shadowing itself). Marching stops once T2 <= 0.02 (T2 keeps its value).
 *   Shadow: w = L at x, len = |light - x|.  S = T2.
 *   AO: len = ao_radius (<= 0: bounds diagonal / 10). A = mean of T2 over the ao_rays directions.
 *
 * AO DIRECTIONS. Axis a = n oriented toward the viewer (a = n if n . d <= 0 else -n); a = -d where there
 * is no normal. Ray i of N (i = 0..N-1), pixel (px, py):
 *   h = hash32((uint32)py * 65536u + (uint32)px)  with hash32(x): x ^= x >> 16; x *= 0x7feb352du;
 *       x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16   (uint32 arithmetic, wrapping)
 *   rot = h * 2^-32;  z = 1 - (i + 0.5) / N;  r = sqrt(1 - z*z);
 *   phi = 2 pi * fract(i * 0.6180339887498949 + rot);   w = r cos(phi) b1 + r sin(phi) b2 + z a
 *   basis (Duff et al. 2017): sgn = a.z >= 0 ? 1 : -1; p = -1 / (sgn + a.z); q = a.x a.y p;
 *   b1 = (1 + sgn a.x a.x p, sgn q, -sgn a.x), b2 = (q, sgn + a.y a.y p, -a.y).
 *
 * OCCLUSION AT VERTICES (occlusion == TPK_OCCLUSION_VERTEX; the two sections above are then not used).
 * The secondary rays start at the mesh vertices, not at shade points. Cache: for every vertex v, at
 * p_v = origin + its stored position (double), with the light and transmittance defined above,
 *   S_v = shadow transmittance from p_v: w = L at p_v, len = |light - p_v| (1 when len = 0; shadows off: 1);
 *   A_v = mean T2 over N = ao_rays directions on the whole sphere (view-independent: no axis, no pixel):
 *       h = hash32((uint32)v), rot = h * 2^-32, z = 1 - 2 (i + 0.5) / N, r = sqrt(1 - z*z),
 *       phi = 2 pi * fract(i * 0.6180339887498949 + rot), w = (r cos(phi), r sin(phi), z) in world axes,
 *       len = ao_radius (AO off: 1).
 * S_v and A_v are stored as float. The cache depends on the mesh and field, light, TF, range, unit
 * distance, iso values and opacity, clip box, probes, AO rays and radius; not on the camera except through a
 * headlight (then once per frame: N + 1 rays per vertex instead of per shade point).
 * Use: every volume piece (x = its midpoint) and every iso hit (x = the hit point) takes S and A
 * interpolated linearly in the piece's tet v[0..3] (no shade-point schedule, no casts): with e_i and
 * c1 = e2 x e3, c2 = e3 x e1, c3 = e1 x e2, det = e1 . c1 as for the NORMAL and q = x - origin - p0,
 * l_i = (q . c_i) / det (i = 1..3), l_0 = 1 - l_1 - l_2 - l_3; S = clamp(sum l_i S_v[i], 0, 1) and A
 * likewise; where det is 0 or not finite, the mean of the four. m is then as in LIGHTING FACTOR.
 * secondary_rays and tet_steps count the cache's rays.
 *
 * OCCLUSION AT THE SURFACE (occlusion == TPK_OCCLUSION_SURFACE: the seed paper's effects, Sahistan et al.
 * 2021 §6, shadows and AO where a primary ray meets a surface, the volume's opacity the occluder). A
 * primary ray has at most one shade point, its surface: with iso values its first iso hit (the hit point
 * and normal, as ISOSURFACES), without them its first volume shade point of SHADE POINTS (the midpoint of
 * its first piece of optical depth tau > 0, just inside where it enters the shell, the clip box or a
 * probe; that piece's normal). S and A there are cast as TRANSMITTANCE and AO DIRECTIONS say (the
 * secondary rays see the volume's opacity and the isosurfaces). Every lighting factor after it takes
 * them, before it S = A = 1; a volume piece takes S and A as they stand where it starts (its m is made
 * before its hits). So a pixel casts at most 1 + ao_rays secondary rays, against up to ~32 (1 + ao_rays)
 * with `ray`.
 *
 * ISOSURFACES (iso_count values v_j, scalar units). Point field: the piece crosses v_j where
 * (s_in < v_j <= s_out) or (s_in > v_j >= s_out), at t = t_in + (v_j - s_in) / (s_out - s_in) * length
 * (half-open, so a crossing exactly on a face counts once). Tet field: between two consecutive pieces
 * of one marcher run (previous t_out == this t_in) whose constants s_prev, s cross v_j the same way,
 * at t = t_in. Crossings in a piece are taken in increasing t (equal t: increasing j); the volume is
 * integrated up to each one, then the hit composites rgb = TF(u(v_j)).rgb, alpha = iso_opacity (<= 0:
 * 1), m at the hit point with the normal above (the hit is a shade point; the volume schedule is not
 * changed by it).
 *
 * ISO-ONLY RAYS. With iso values, a point field and a TF whose opacity is 0 at every control point, the
 * volume adds nothing and only the pieces that hold a crossing matter: the CPU renderer finds those by
 * range culling (libtetpack's tpk_march_ray_values: a BVH over the tets whose nodes carry the field's
 * range; 4x4 pixels at a time through tpk_march_packet_values), the same pieces, bit for bit, in the
 * same order, so the picture is the same. The CPU walks a
 * second tree made for the frame's iso values (tpk_range_bvh_select: only the tets that hold one, four
 * children a node), which tests fewer tets per ray than marching steps through on any surface; but its
 * set-up (recovering the tets' vertices from Tet16, the file-order tree, the selected tree) costs about
 * CPU time per tet, which only enough rays pay back. Once the trees are built, culling beats marching
 * up to about half of the leaves holding a value with many rays, and less with few (the figures behind
 * this: bench/README, "Figures behind code comments"). So the CPU renderer culls where at most TPK_RENDER_CULL_ACTIVE_MANY of those leaves hold a value with at
 * least as many rays as tets; with fewer, at most TPK_RENDER_CULL_ACTIVE_CPU from a quarter as many
 * rays as tets, less below (linearly down to TPK_RENDER_CULL_ACTIVE with no rays); else it marches.
 * Building the trees
 * to count the leaves costs more than a small frame on a large mesh (10.4M tets: several
 * CPU-seconds), so with fewer rays than tets a glance at the field comes first: where more than
 * TPK_RENDER_DENSE_RUNS of the runs of 8 consecutive vertices (spatially compact along the file's
 * Hilbert order) hold an iso value, the surface is dense beyond doubt (on grid 55 such runs hold a value
 * about 0.8 times as often as leaves do) and the renderer marches without building them. The --json
 * output says which (iso_culling). TETPACK_ISO_CULLING in the environment: 0 always marches, 1 always culls (benchmarks
 * compare the two), unset decides as above. The Vulkan renderer culls only when TETPACK_ISO_CULLING=1
 * asks, walking the file-order tree in its shader (render.comp's cull_trace), with the same pieces as its
 * own marcher; unset, it marches on every device, as the walk cost more than it saved wherever it was
 * measured (bench/README).
 *
 * INTEGRATION of each stretch of volume (a piece, or its part before, between or after its iso hits),
 * the piece's m multiplying its rgb, as `integration` says. Exact: split where u crosses a TF control
 * point, then steps of optical depth <= 0.05 with colour weighted by extinction. Sampled: equal steps of
 * at most unit_distance / 2, sampled at their middles, none once T <= 0.02. Midpoint: one sample at the
 * middle of the stretch, alpha = 1 - exp(-length * k(u(s_mid))). */
#define TPK_RENDER_AMBIENT 0.3
#define TPK_RENDER_SHADE_STEP (1.0 / 32.0)
#define TPK_RENDER_SELF_EPS 1e-3
#define TPK_RENDER_OPAQUE_T 0.02

/* ISO-ONLY RAYS: iso values, a point field (has_point_scalars, no tet field) and a TF with opacity 0 at
 * every control point. */
int tpk_render_iso_only(const tpk_render_options *opt, int has_point_scalars);
/* The same mesh arrays (by identity: counts, origin, positions, layout records, shell), whatever the
 * point field: what a renderer kept from frame to frame was made for (a time step changes the field only). */
int tpk_render_same_mesh(const tpk_mesh_arrays *x, const tpk_mesh_arrays *y);
/* TETPACK_ISO_CULLING: -1 unset (decide by TPK_RENDER_CULL_ACTIVE), 0 never, 1 always. */
int tpk_render_culling_wanted(void);
/* The ISO-ONLY RAYS glance: 1 when more than TPK_RENDER_DENSE_RUNS of the runs of 8 consecutive vertices
 * of mesh's point field hold one of the values (a dense surface: march without building the tree). */
int tpk_render_iso_dense(const tpk_mesh_arrays *mesh, const double *values, int count);
#define TPK_RENDER_CULL_ACTIVE 0.1       /* the CPU's with no rays */
#define TPK_RENDER_CULL_ACTIVE_CPU 0.35  /* the CPU's, from a quarter as many rays as tets */
#define TPK_RENDER_CULL_ACTIVE_MANY 0.55
#define TPK_RENDER_DENSE_RUNS 0.2

/* width 800, height 600, integration 0, threads all, background opaque dark gray (0.1, 0.1, 0.1, 1);
 * the camera, tf and range are left zero for the caller. */
void tpk_render_options_default(tpk_render_options *opt);
/* The file's culling blocks (spec §17) into *cull, and opt->cull = cull; opt->cull NULL when the file has
 * none. TPK_OK, or tpk_load_cull's error for a CULL chunk it refuses (its message in the file). */
tpk_result tpk_render_use_cull(tpk_file *file, tpk_cull *cull, tpk_render_options *opt);

/* The lengths the effects use, as every backend resolves them from the options and the diagonal of the
 * stored positions' box (tpk_positions_diagonal): the unit distance (opt->unit_distance when positive
 * and finite, else diagonal / 100, else 1) and the AO ray length (opt->ao_radius when positive, else
 * diagonal / 10). */
void tpk_render_lengths(const tpk_render_options *opt, double diagonal, double *unit, double *ao_radius);

/* The one validation of render options (render_check.c), which every backend calls before anything
 * else: a size in 1..TPK_RENDER_MAX_SIZE, a transfer function of 1..TPK_TF_MAX_POINTS points, a known
 * integration, a finite range, 0..TPK_RENDER_MAX_ISO finite iso values, a finite iso opacity <= 1, a
 * finite clip box with min <= max, 0..TPK_RENDER_MAX_PROBES valid probes (tpk_probe_check), a finite light, 0..TPK_RENDER_MAX_AO_RAYS AO rays, a finite AO radius,
 * a known occlusion and a camera tpk_camera_basis_of accepts. Values a renderer cannot use are refused, not clamped.
 * Returns 0, or -1 with a message starting "render: " (the same whichever backend asks). Pure. */
int tpk_render_check_options(const tpk_render_options *opt, tpk_diag *diag);
/* The part of that check for one probe (numbered from 1 in messages): 0, or -1 with a message. */
int tpk_probe_check(const tpk_probe *probe, int number, tpk_diag *diag);
/* render.h PROBES: the spans of [lo, hi] of the ray org + t dir (unit dir) that the probes keep, into
 * span[0..n-1] in order (at most TPK_RENDER_MAX_PROBES + 1); returns n (0: nothing of the ray shows). */
int tpk_probe_spans(const tpk_probe *probes, int count, const double org[3], const double dir[3], double lo,
                    double hi, double span[][2]);
/* Whether the point x is in what the probes keep (inside every keep probe, outside every cut probe). */
int tpk_probe_keeps(const tpk_probe *probes, int count, const double x[3]);
/* Whether a tet of these corners may show through the probes: 0 only when it is surely outside what
 * they keep (its bounding box misses a keep probe, or all its corners are inside one cut probe: every
 * probe is convex). Conservative: extract keeps the tets for which it is nonzero. */
int tpk_probe_may_show(const tpk_probe *probes, int count, const double corner[4][3]);
/* The text form of a probe (--probe): "sphere:cx,cy,cz,r", "plane:px,py,pz,nx,ny,nz" or
 * "box:x0,y0,z0,x1,y1,z1", then ":keep" (the default) or ":cut". tpk_probe_parse reads it (0, or -1 when
 * it is not that form; tpk_probe_check then judges the values); tpk_probe_format writes it (snprintf's
 * return), exactly. */
int tpk_probe_parse(const char *text, tpk_probe *out);
int tpk_probe_format(const tpk_probe *probe, char *buf, size_t size);
/* "sphere", "plane", "box" ("?" for another value), and back (0: none of them). */
const char *tpk_probe_shape_name(int shape);
int tpk_probe_shape_of(const char *name, size_t length);

/* What every backend derives from checked options in the same way (render_setup.c), so that they cast
 * the same rays and weigh them alike. */
typedef struct tpk_render_setup {
    tpk_camera_basis basis; /* tpk_camera_basis_of the camera for the image size */
    double range_min;
    double inv_range;       /* 1 / (range_max - range_min); 0 when the range is empty */
    double unit, inv_unit;  /* tpk_render_lengths' unit distance and its inverse */
    double ao_radius;       /* tpk_render_lengths' AO ray length */
    double iso_opacity;     /* opt->iso_opacity, or 1 where it is <= 0 (render.h: ISOSURFACES) */
    double light[3];        /* the point light, or the eye without one (render.h: LIGHT) */
    int cast;               /* shadows or AO: shade points cast secondary rays */
    int lighting;           /* shading, shadows or AO: the lighting factor m is computed */
} tpk_render_setup;

/* Fill `out` from options that tpk_render_check_options accepted and the diagonal of the stored
 * positions' box (tpk_positions_diagonal). Returns 0, or -1 with the camera's message. Pure. */
int tpk_render_setup_of(const tpk_render_options *opt, double diagonal, tpk_render_setup *out, tpk_diag *diag);

typedef struct tpk_render_stats {
    uint64_t rays;      /* primary rays (one per pixel) */
    uint64_t tet_steps; /* tets the marcher stepped through, all rays (secondary ones included) */
    uint64_t secondary_rays; /* shadow and AO rays */
    int iso_culling;    /* the primary rays were iso-only and range-culled (ISO-ONLY RAYS) */
    uint64_t iso_triangles; /* --iso-raster: the triangles drawn */
    int iso_mesh_shader;    /* --iso-raster: 1 drawn by task and mesh shaders (VK_EXT_mesh_shader); 0 the device
                               lacks them (compute extraction + indirect draw); 2 it has them, not used */
    const char *iso_mesh_reason; /* when 2: why (a static string, or a copy kept until the thread's next
                                    tpk_render_iso_raster), or NULL */
    double iso_draw_gpu_seconds; /* --iso-raster: device time of the draw alone (its render pass: on the
                                    mesh-shader path the tets' classification too); -1: no timestamps */
    int iso_raster_compute;      /* --iso-raster: 1 drawn by the compute rasterizer (visibility buffer) */
    int iso_raster_atomics;      /* its atomics' width: 64, or 32 where the device lacks 64-bit ones */
    int iso_raster_measured;     /* 1: this frame drew both paths and chose (--iso-raster-path auto) */
    double iso_raster_seconds[2]; /* the device time of each path's draw, graphics and compute, as this
                                     raster measured them (auto; -1: not measured) */
    const char *iso_raster_note; /* auto: why the compute rasterizer did not draw (a static string), or NULL */
    double seconds;     /* wall time of the render (marcher creation included) */
    double seconds_rays; /* CPU reference: wall time of the primary rays alone, after the marcher, the range
                            culling's trees and the vertex cache were set up (what a second frame with them
                            kept would take); 0 for Vulkan */
    double cpu_seconds_rays; /* CPU reference: the CPU time of those rays, all threads (rays per core-second
                                on a shared machine) */
    uint64_t device_bytes; /* Vulkan: device memory of the renderer's buffers (mesh arrays, BVH, image
                              band, parameters); 0 for the CPU reference */
    /* Vulkan only (0 for the CPU reference): */
    double gpu_seconds; /* device time of the frame's dispatches (timestamp queries); -1: no timestamps */
    double setup_device_seconds;   /* instance and device */
    double setup_upload_seconds;   /* arrays and BVH into device memory, image buffers */
    double setup_pipeline_seconds; /* shader, pipeline cache and the pipelines compiled so far */
    double first_frame_seconds;    /* tpk_render_vulkan: its one frame, without the pipeline it compiled */
    double vertex_cache_seconds;   /* --occlusion vertex: the time this frame spent casting the vertex cache (a
                                      part of `seconds`): the CPU's wall time, or Vulkan's device time of its
                                      casts (also a part of gpu_seconds; the wall time without timestamps); 0
                                      when nothing was cast */
    uint64_t pipeline_cache_bytes; /* pipeline cache data loaded from disk; 0: none */
    int pipeline_cache_hits;       /* pipelines found in that cache; -1: the driver does not say */
} tpk_render_stats;

/* Render `mesh` into rgba (width * height * 4 bytes, caller-owned). Emission-absorption front to back
 * in world units (ray parameter = distance from the eye); the scalar is linear along each tet piece and
 * the TF piecewise linear, so `integration` 0 integrates each piece between the TF's control points
 * with an optical-depth-limited quadrature (converges to the exact integral); rays stop at 98% opacity.
 * With mesh->scalars NULL the volume has constant density: every point takes the TF at s = 0.5.
 * Deterministic: the image does not depend on the thread count. Returns 0, or -1 with a message
 * (invalid options, out of memory, TPK_ERR_MESH from the marcher with the pixel it happened at). */
int tpk_render_cpu(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                   tpk_render_stats *stats, tpk_diag *diag);

/* The same over a part set (spec §15) through its link-following marcher: the picture of the one file
 * the parts were cut from. has_scalars: the parts' arrays carry a point field; diagonal: of the box of
 * all parts' positions (tpk_positions_diagonal), for the default unit distance. Emission-absorption,
 * isosurfaces, the clip box and probes; shading, shadows, AO and tet fields are refused here (the CLI
 * renders those frames through the set as one mesh, tpk_set_mesh, with tpk_render_cpu). */
int tpk_render_cpu_set(const tpk_set_marcher *marcher, int has_scalars, double diagonal,
                       const tpk_render_options *opt, uint8_t *rgba, tpk_render_stats *stats, tpk_diag *diag);
/* The vertex cache of render.h's OCCLUSION AT VERTICES for `mesh` and `opt` (whatever opt->occlusion
 * says), on all cores (opt->threads): S_v into s[v] and A_v into a[v], vertex_count floats each. stats
 * (may be NULL) gets the cache's tet steps, secondary rays and time. For tests and other backends to
 * compare with. Returns 0, or -1 with a message. */
int tpk_render_vertex_cache(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, float *s, float *a,
                            tpk_render_stats *stats, tpk_diag *diag);
/* The vertex cache kept across frames (render_cache.c): each half (S, A) is cast again only when an input
 * of that half (OCCLUSION AT VERTICES: the mesh and field, TF, range, unit distance, integration, iso
 * values and opacity, clip box, probes; the light and shadows for S; the AO rays and radius for A)
 * differs from the last update's, and then alone (S without AO rays, A without shadow rays): a camera
 * move under a fixed light casts nothing, a headlight S alone. The values are those
 * tpk_render_vertex_cache gives, bit for bit. Used by the Vulkan renderer and by view's CPU frames. For
 * tpk_render_cpu_cached it also keeps the marcher and, for iso-only frames, the range culling's trees
 * (ISO-ONLY RAYS), made again only when the mesh's arrays or field change (by pointer: a file's arrays
 * stay put until it closes). Trees to be kept count the rays of TPK_RENDER_KEPT_FRAMES frames (or
 * tpk_vertex_cache_frames_per_field's) against their set-up, and kept trees as paid for: such frames
 * cull up to TPK_RENDER_CULL_ACTIVE_MANY. */
#define TPK_RENDER_KEPT_FRAMES 8
typedef struct tpk_vertex_cache tpk_vertex_cache;
tpk_vertex_cache *tpk_vertex_cache_create(void); /* NULL: out of memory */
void tpk_vertex_cache_destroy(tpk_vertex_cache *cache);
/* How many frames each field is drawn with (frames >= 1; TPK_RENDER_KEPT_FRAMES until set): what trees to
 * be kept are paid by. render --steps draws each field once (1), so its frames choose as one frame alone. */
void tpk_vertex_cache_frames_per_field(tpk_vertex_cache *cache, int frames);
/* Bring the cache up to date for mesh and opt. *changed (may be NULL) = 1 when a half was cast again;
 * cast (may be NULL) gets this update's tet steps and secondary rays (zeros when nothing was cast). The
 * arrays stay valid until the next update or destroy. 0, or -1 with a message (the cache is then empty). */
int tpk_vertex_cache_update(tpk_vertex_cache *cache, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                            int *changed, tpk_render_stats *cast, tpk_diag *diag);
/* The same, the stale halves cast by `caster` (the Vulkan renderer's on its device) instead of
 * tpk_render_vertex_cache: it gets the options with the fresh half's effect off (shadows 0: S alone, ao_rays
 * 0: A alone), fills s and a (vertex_count floats each, 1 for an effect that is off) and stats (its tet steps,
 * secondary rays and seconds, as tpk_render_vertex_cache does; zeroed first), and returns 0 or -1 with a
 * message. */
typedef int (*tpk_vertex_caster)(void *user, const tpk_mesh_arrays *mesh, const tpk_render_options *opt, float *s,
                                 float *a, tpk_render_stats *stats, tpk_diag *diag);
int tpk_vertex_cache_update_with(tpk_vertex_cache *cache, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                                 tpk_vertex_caster caster, void *user, int *changed, tpk_render_stats *cast,
                                 tpk_diag *diag);
const float *tpk_vertex_cache_s(const tpk_vertex_cache *cache); /* vertex_count floats: S_v */
const float *tpk_vertex_cache_a(const tpk_vertex_cache *cache); /* A_v */
/* tpk_render_cpu whose --occlusion vertex takes its cache from `cache` (kept across calls, brought up to
 * date first), not one of its own made for the frame, and whose marcher and range trees are the ones
 * `cache` keeps (any occlusion); cache NULL: tpk_render_cpu. stats counts the rays this frame cast, and
 * its seconds the set-up this frame made. (render_cache.c) */
int tpk_render_cpu_cached(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                          tpk_vertex_cache *cache, tpk_render_stats *stats, tpk_diag *diag);
/* tpk_render_cpu with --occlusion vertex's S_v and A_v given (vertex_count floats each, as
 * tpk_render_vertex_cache makes them), not cast; NULL: cast for this frame. */
int tpk_render_cpu_given_cache(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                               const float *s, const float *a, tpk_render_stats *stats, tpk_diag *diag);
/* The diagonal of the box of mesh->positions (0 for fewer than two distinct points). */
double tpk_positions_diagonal(const tpk_mesh_arrays *mesh);

/* Write an 8-bit RGBA PNG, rows top to bottom, atomically: a temporary file in the same directory,
 * renamed over `path` only when complete. Returns 0, or -1 with a message naming the path. */
int tpk_write_png(const char *path, int width, int height, const uint8_t *rgba, tpk_diag *diag);

#endif
