// Part of render.comp, included once, in the order it lists.
// Secondary rays (shadows, AO) and the shade points that cast them (render/render_light.c;
// render.h TRANSMITTANCE, AO DIRECTIONS, SHADE POINTS).

// ---- Secondary rays: shadows and ambient occlusion (render.h: TRANSMITTANCE, AO DIRECTIONS) -------

// Optical depth of a stretch of length len from TF coordinate u0 to u1: the exact mean of the TF's
// alpha (trapezoids between the control points crossed) times length / unit (ri_optical_depth).
float optical_depth(float len, float u0, float u1)
{
    if (!(len > 0.0))
        return 0.0;
    float a0 = tf_eval(u0).a;
    if (u0 == u1)
        return len * a0 * P.scalar_map.z;
    float du = u1 - u0, prev_u = u0, prev_a = a0, sum = 0.0;
    int n = P.dims.w;
    if (du > 0.0) {
        for (int k = tf_first_above(u0); k < n && tf_point_s(k) < u1; k++) {
            work++;
            float cu = tf_point_s(k), ca = TF_RGBA(k).a;
            sum += 0.5 * (prev_a + ca) * (cu - prev_u);
            prev_u = cu;
            prev_a = ca;
        }
    } else {
        int k = tf_first_above(u0) - 1;
        while (k >= 0 && tf_point_s(k) >= u0)
            k--;
        for (; k >= 0 && tf_point_s(k) > u1; k--) {
            work++;
            float cu = tf_point_s(k), ca = TF_RGBA(k).a;
            sum += 0.5 * (prev_a + ca) * (cu - prev_u);
            prev_u = cu;
            prev_a = ca;
        }
    }
    sum += 0.5 * (prev_a + tf_eval(u1).a) * (u1 - prev_u);
    return len * (sum / du) * P.scalar_map.z;
}

float trans_tau, trans_iso, trans_lo, trans_hi; // the secondary ray being marched (trans_ray)
float trans_span_a[MAX_SPANS], trans_span_b[MAX_SPANS]; // its spans through the probes
int trans_span_n;
uint secondary_rays = 0u;
bool trans_have_prev;
float trans_prev_t_out, trans_prev_s;

// One piece of a secondary ray, already within [trans_lo, trans_hi] (on_trans_segment).
bool trans_piece(float t_in, float t_out, float s_in, float s_out)
{
    float len = t_out - t_in, eps = P.cast_info.y;
    int hits = 0;
    if (P.mode.w == 2) {
        for (int j = 0; ISO && trans_have_prev && trans_prev_t_out == t_in && t_in > eps && j < P.shell_info.y; j++) {
            float v = P.iso[j];
            hits += int((trans_prev_s < v && v <= s_in) || (trans_prev_s > v && v >= s_in));
        }
        trans_have_prev = true;
        trans_prev_t_out = t_out;
        trans_prev_s = s_in;
        float u = normalized(s_in);
        trans_tau += optical_depth(len, u, u);
    } else {
        for (int j = 0; ISO && j < P.shell_info.y; j++) {
            float v = P.iso[j];
            if ((s_in < v && v <= s_out) || (s_in > v && v >= s_out)) {
                float t = clamp(t_in + (v - s_in) / (s_out - s_in) * len, t_in, t_out);
                hits += int(t > eps);
            }
        }
        trans_tau += optical_depth(len, normalized(s_in), normalized(s_out));
    }
    for (int i = 0; i < hits; i++)
        trans_iso *= 1.0 - TPK_VK_ISO_OPACITY;
    return exp(-trans_tau) * trans_iso <= OPAQUE_TRANSMITTANCE || status != TPK_VK_STATUS_OK;
}

// report() for secondary rays: clip to [trans_lo, trans_hi] as the marcher does. Never pauses.
int trans_report(float t_in, float t_out, float s_in, float s_out)
{
    int said = MARCH_GO;
    if (P.probe_info.x > 0) { // render.h PROBES: each part of the piece inside a span is a piece
        const float len = t_out - t_in;
        for (int i = 0; i < trans_span_n; i++) {
            const float a = max(t_in, trans_span_a[i]), b = min(t_out, trans_span_b[i]);
            if (a < b && trans_piece(a, b, s_in + (s_out - s_in) * ((a - t_in) / len),
                                     s_in + (s_out - s_in) * ((b - t_in) / len)))
                return MARCH_STOP;
        }
        return t_out >= trans_hi ? MARCH_STOP : MARCH_GO;
    }
    float a, b, sa, sb;
    if (clip_piece(t_in, t_out, s_in, s_out, trans_lo, trans_hi, a, b, sa, sb))
        said = trans_piece(a, b, sa, sb) || t_out >= trans_hi ? MARCH_STOP : MARCH_GO;
    return said;
}

#define MARCH_RUN_START march_run_start_secondary
#define MARCH_OUT_OF_WORK false // a secondary ray runs to its end
#define MARCH_RUN march_run_secondary
#define MARCH_TRACE_START trace_start_secondary
#define MARCH_TRACE trace_secondary
#define MARCH_TMAX trans_hi
#define MARCH_REPORT(t_in, t_out, s_in, s_out, v) trans_report(t_in, t_out, s_in, s_out)
#include "march_run.glsl"
#undef MARCH_RUN_START
#undef MARCH_RUN
#undef MARCH_TRACE_START
#undef MARCH_TRACE
#undef MARCH_TMAX
#undef MARCH_REPORT

// Transmittance from x along unit w over [0, len], clipped to the box; the primary ray's frame is kept.
float transmittance_ray(vec3 x, vec3 w, float len)
{
    float lo = 0.0, hi = len;
    if (!clip_ray(x, w, lo, hi))
        lo = hi = -1.0; // misses the box: marches nothing, T2 = 1 (one exit, see march_run.glsl)
    else if (P.probe_info.x > 0) {
        trans_span_n = probe_spans(x, w, lo, hi, trans_span_a, trans_span_b);
        lo = trans_span_n > 0 ? trans_span_a[0] : -1.0;
        hi = trans_span_n > 0 ? trans_span_b[trans_span_n - 1] : -1.0;
    }
    Frame primary = frame;
    vec3 primary_dir = ray_dir, primary_inv = inv_dir;
    float primary_exit = run_exit_t;
    trans_tau = 0.0;
    trans_iso = 1.0;
    trans_lo = lo;
    trans_hi = hi;
    trans_have_prev = false;
    secondary_rays += lo >= 0.0 ? 1u : 0u;
    if (lo >= 0.0 && frame_init(x, w)) {
        ray_dir = w;
        inv_dir = 1.0 / w;
        MarchTrace ts = trace_start_secondary(lo, hi);
        trace_secondary(ts); // a secondary ray never pauses
    }
    frame = primary;
    ray_dir = primary_dir;
    inv_dir = primary_inv;
    run_exit_t = primary_exit;
    return exp(-trans_tau) * trans_iso;
}

uint hash32(uint x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

ivec2 pixel; // of this invocation
uint cache_v; // CACHE_CAST: the vertex whose S_v and A_v this invocation casts

// The AO axis: the normal turned toward the viewer, -d without one (render.h: AO DIRECTIONS).
vec3 ao_axis(bool has_n, vec3 n)
{
    return has_n ? (dot(n, ray_dir) > 0.0 ? -n : n) : -ray_dir;
}

// AO ray i of TPK_VK_AO_RAYS around unit axis a (render.h: AO DIRECTIONS).
vec3 ao_direction(vec3 x, vec3 a, int i)
{
    int count = TPK_VK_AO_RAYS;
    if (CACHE_CAST) { // render.h OCCLUSION AT VERTICES: the whole sphere, world axes, hashed by the vertex
        float rot = float(hash32(cache_v)) * (1.0 / 4294967296.0);
        float z = 1.0 - 2.0 * (float(i) + 0.5) / float(count), r = sqrt(1.0 - z * z);
        float phi = 6.283185307179586 * fract(float(i) * 0.6180339887498949 + rot);
        return vec3(r * cos(phi), r * sin(phi), z);
    }
    float sgn = a.z >= 0.0 ? 1.0 : -1.0;
    float p = -1.0 / (sgn + a.z), q = a.x * a.y * p;
    vec3 b1 = vec3(1.0 + sgn * a.x * a.x * p, sgn * q, -sgn * a.x), b2 = vec3(q, sgn + a.y * a.y * p, -a.y);
    uint h = hash32(uint(pixel.y) * 65536u + uint(pixel.x));
    float rot = float(h) * (1.0 / 4294967296.0);
    float z = 1.0 - (float(i) + 0.5) / float(count), r = sqrt(1.0 - z * z);
    float phi = 6.283185307179586 * fract(float(i) * 0.6180339887498949 + rot);
    return r * cos(phi) * b1 + r * sin(phi) * b2 + z * a;
}

bool cast_done = false; // shade points of this ray (render.h: SHADE POINTS)
float t_cast, shade_s = 1.0, shade_a = 1.0;
bool have_prev = false; // the previous piece of this ray (tet-field iso)
float prev_t_out, prev_s;

// The casts of the piece being reported: segment() asks for them and pauses the march, main() casts
// them at the top level (march_run.glsl says why), and the redone piece takes their results in the
// order asked. A result's secondary rays and steps count when it is taken, so an iso hit behind an
// opaque stretch of its piece, asked for but never taken, counts nothing (as on the CPU).
#define MAX_CASTS 5 // a piece's volume shade point and up to 4 iso hits
int cast_asked = 0;
int cast_next = 0;
bool casts_ready = false;
vec3 cast_x[MAX_CASTS], cast_n[MAX_CASTS];
bool cast_has_n[MAX_CASTS];
float cast_S[MAX_CASTS], cast_A[MAX_CASTS];
uint cast_rays_of[MAX_CASTS], cast_steps_of[MAX_CASTS];

void ask_cast(vec3 x, bool has_n, vec3 n)
{
    cast_x[cast_asked] = x;
    cast_has_n[cast_asked] = has_n;
    cast_n[cast_asked] = n;
    cast_asked++;
}

// The secondary rays of the casts asked, one per call, so that main() marches each at the top level:
// k counts the shadow ray (SHADOWS) then the AO rays (AO) of cast 0, then of cast 1, ...
int cast_ray_count()
{
    return cast_asked * ((SHADOWS ? 1 : 0) + (AO ? TPK_VK_AO_RAYS : 0));
}

void cast_one(int k)
{
    const int per = (SHADOWS ? 1 : 0) + (AO ? TPK_VK_AO_RAYS : 0);
    const int i = k / per, j = k - i * per;
    if (j == 0) {
        cast_S[i] = 1.0;
        cast_A[i] = 0.0; // the sum of the AO rays' transmittances until the last one
        cast_rays_of[i] = 0u;
        cast_steps_of[i] = 0u;
    }
    const vec3 x = cast_x[i];
    const bool shadow = SHADOWS && j == 0;
    vec3 w;
    float len;
    if (shadow) {
        w = P.light.xyz - x;
        len = length(w);
        w /= len;
    } else {
        w = ao_direction(x, ao_axis(cast_has_n[i], cast_n[i]), j - (SHADOWS ? 1 : 0));
        len = TPK_VK_AO_RADIUS;
    }
    uint rays = secondary_rays, taken = steps_taken;
    float T = 1.0;
    if (!shadow || len > 0.0)
        T = transmittance_ray(x, w, len);
    cast_rays_of[i] += secondary_rays - rays;
    cast_steps_of[i] += steps_taken - taken;
    secondary_rays = rays;
    steps_taken = taken;
    if (shadow)
        cast_S[i] = T;
    else
        cast_A[i] += T;
    if (AO && j == per - 1)
        cast_A[i] /= float(TPK_VK_AO_RAYS);
    if (!AO)
        cast_A[i] = 1.0;
}

// After the last cast_one: the redone piece takes the results.
void casts_cast()
{
    cast_asked = 0;
    cast_next = 0;
    casts_ready = true;
}

void take_cast(out float S, out float A)
{
    S = cast_S[cast_next];
    A = cast_A[cast_next];
    secondary_rays += cast_rays_of[cast_next];
    steps_taken += cast_steps_of[cast_next];
    cast_next++;
}

void composite_iso(float t, float v, bool has_n, vec3 n, ivec4 tet)
{
    float m = 1.0;
    if (LIGHTING) {
        vec3 x = eye_dir_point(t);
        float S = 1.0, A = 1.0;
        if (VERTEX_OCC) {
            vec2 sa = vertex_lookup(tet, x);
            S = sa.x;
            A = sa.y;
        } else if (SURFACE_OCC) { // the ray's first hit is its surface: it casts, later ones reuse
            if (!cast_done) {
                take_cast(shade_s, shade_a);
                cast_done = true;
            }
            S = shade_s;
            A = shade_a;
        } else if (CAST) {
            take_cast(S, A);
        }
        m = lighting_factor(x, has_n, n, S, A);
    }
    vec4 c = tf_eval(normalized(v));
    float alpha = TPK_VK_ISO_OPACITY;
    color += transmittance * alpha * m * c.rgb;
    transmittance *= 1.0 - alpha;
}
