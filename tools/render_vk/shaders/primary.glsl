// Part of render.comp, included once, in the order it lists.
// A primary ray's pieces: effects, spans and its march (render/render_cpu.c's on_segment).

// One tet piece [t_in, t_out] of tet vertices v (entry face, fourth) with scalars s_in, s_out
// (render_cpu.c's on_segment). Returns MARCH_STOP when the ray is opaque, MARCH_PAUSE (before changing
// anything) when the piece needs casts that are not ready.
int segment(float t_in, float t_out, float s_in, float s_out, ivec4 v)
{
    const bool tet_field = P.mode.w == 2;
    int nh = 0;
    if (ISO) {
        if (!tet_field)
            nh = point_crossings(t_in, t_out, s_in, s_out);
        else if (have_prev && prev_t_out == t_in)
            nh = jump_crossings(t_in, prev_s, s_in);
    }
    vec3 n = vec3(0.0);
    bool has_n = false;
    float u_in = normalized(s_in), u_out = normalized(s_out), cur_t = t_in, cur_u = u_in;
    bool volume_cast = false;
    if (LIGHTING) {
        has_n = P.mode.w == 1 && tet_normal(v, n);
        // render.h SHADE POINTS: cast from this piece's middle when the ray has lost 1/32 of
        // transmittance since the last cast; pieces in between reuse its S and A. OCCLUSION AT THE
        // SURFACE: without iso values the first such cast alone, with them none (the first hit casts).
        volume_cast = CAST && !(SURFACE_OCC && (ISO || cast_done)) && t_out > t_in &&
                      optical_depth(t_out - t_in, u_in, u_out) > 0.0 &&
                      (!cast_done || t_cast - transmittance >= 1.0 / 32.0);
    }
    // the hits that cast: every one, or (OCCLUSION AT THE SURFACE) the ray's first alone
    const int nh_cast = SURFACE_OCC ? (cast_done ? 0 : min(nh, 1)) : nh;
    int said = MARCH_GO;
    if (CAST && !casts_ready && (volume_cast || nh_cast > 0)) {
        if (volume_cast)
            ask_cast(eye_dir_point(0.5 * (t_in + t_out)), has_n, n);
        for (int i = 0; i < nh_cast; i++) {
            vec3 hn = n;
            bool has_hn = has_n;
            if (tet_field)
                has_hn = face_normal(v, hn);
            ask_cast(eye_dir_point(crossing_t[i]), has_hn, hn);
        }
        said = MARCH_PAUSE;
    } else {
        if (ISO) {
            have_prev = true;
            prev_t_out = t_out;
            prev_s = s_in;
        }
        shade_m = 1.0;
        if (LIGHTING && t_out > t_in) {
            vec3 mid = eye_dir_point(0.5 * (t_in + t_out));
            if (VERTEX_OCC) {
                vec2 sa = vertex_lookup(v, mid);
                shade_s = sa.x;
                shade_a = sa.y;
            }
            if (volume_cast) {
                take_cast(shade_s, shade_a);
                cast_done = true;
                t_cast = transmittance;
            }
            shade_m = lighting_factor(mid, has_n, n, shade_s, shade_a);
        }
        for (int i = 0; ISO && i < nh && transmittance > OPAQUE_TRANSMITTANCE; i++) {
            float value = P.iso[crossing_j[i]];
            float hit_u = tet_field ? u_in : normalized(value);
            integrate(crossing_t[i] - cur_t, cur_u, hit_u);
            vec3 hn = n;
            bool has_hn = has_n;
            if (LIGHTING && tet_field)
                has_hn = face_normal(v, hn);
            float m = shade_m;
            composite_iso(crossing_t[i], value, has_hn, hn, v);
            shade_m = m;
            cur_t = crossing_t[i];
            cur_u = hit_u;
        }
        if (transmittance > OPAQUE_TRANSMITTANCE)
            integrate(t_out - cur_t, cur_u, u_out);
        casts_ready = false;
        said = transmittance <= OPAQUE_TRANSMITTANCE || status != TPK_VK_STATUS_OK ? MARCH_STOP : MARCH_GO;
    }
    return said;
}

// The range of t a piece may contribute: [0, inf), cut to the clip box when there is one.
float t_min_clip, t_max_clip;
// With probes: the primary ray's spans (made again when a slice resumes the ray), and the end of the
// last part of a piece integrated (a piece redone after MARCH_PAUSE skips the parts already done).
float span_a[MAX_SPANS], span_b[MAX_SPANS], span_done;
int span_n;

// [t_min_clip, t_max_clip] cut by the clip box, then by the probes (their first and last span);
// false when nothing of the primary ray is left.
bool primary_range()
{
    t_min_clip = 0.0;
    t_max_clip = INF;
    if (!clip_ray(P.eye.xyz, ray_dir, t_min_clip, t_max_clip))
        return false;
    if (P.probe_info.x == 0)
        return true;
    span_n = probe_spans(P.eye.xyz, ray_dir, t_min_clip, t_max_clip, span_a, span_b);
    if (span_n == 0)
        return false;
    t_min_clip = span_a[0];
    t_max_clip = span_b[span_n - 1];
    return true;
}

// report() with probes: each part of the piece inside a span goes to segment() as a piece of its own.
int report_spans(float t_in, float t_out, float s_in, float s_out, ivec4 v)
{
    const float len = t_out - t_in;
    for (int i = 0; i < span_n; i++) {
        const float a = max(t_in, span_a[i]), b = min(t_out, span_b[i]);
        if (!(a < b) || b <= span_done)
            continue;
        const int said = segment(a, b, s_in + (s_out - s_in) * ((a - t_in) / len),
                                 s_in + (s_out - s_in) * ((b - t_in) / len), v);
        if (said == MARCH_PAUSE)
            return MARCH_PAUSE;
        span_done = b;
        if (said == MARCH_STOP)
            return MARCH_STOP;
    }
    return t_out >= t_max_clip ? MARCH_STOP : MARCH_GO;
}

// report(): clip the piece to [t_min_clip, t_max_clip] and integrate it (MARCH_GO, MARCH_STOP or
// MARCH_PAUSE, see segment).
int report(float t_in, float t_out, float s_in, float s_out, ivec4 v)
{
    if (P.probe_info.x > 0)
        return report_spans(t_in, t_out, s_in, s_out, v);
    int said = MARCH_GO;
    float a, b, sa, sb;
    if (clip_piece(t_in, t_out, s_in, s_out, t_min_clip, t_max_clip, a, b, sa, sb)) {
        said = segment(a, b, sa, sb, v);
        if (said == MARCH_GO && t_out >= t_max_clip)
            said = MARCH_STOP;
    }
    return said;
}

#define MARCH_RUN_START march_run_start
#undef MARCH_OUT_OF_WORK
#define MARCH_OUT_OF_WORK (SLICED && work >= TPK_VK_SLICE_WORK)
#define MARCH_RUN march_run
#define MARCH_TRACE_START trace_start
#define MARCH_TRACE trace
#define MARCH_TMAX t_max_clip
#define MARCH_REPORT(t_in, t_out, s_in, s_out, v) report(t_in, t_out, s_in, s_out, v)
#include "march_run.glsl"
#undef MARCH_RUN_START
#undef MARCH_RUN
#undef MARCH_TRACE_START
#undef MARCH_TRACE
#undef MARCH_TMAX
#undef MARCH_REPORT
