// Part of render.comp, included once, in the order it lists.
// The transfer function and emission-absorption of a piece (render/transfer_function.c,
// render_integrate.c).

// ---- Transfer function and emission-absorption (render_cpu.c) -------------------------------------

// The TF, copied from the uniform block into shared memory once per workgroup (tf_to_shared): lavapipe
// reads a uniform block at a per-lane index lane by lane, and shared memory faster.
shared float tf_s_shared[TPK_VK_TF_MAX];
shared vec4 tf_rgba_shared[TPK_VK_TF_MAX];

void tf_to_shared()
{
    const uint group_size = gl_WorkGroupSize.x * gl_WorkGroupSize.y;
    for (uint i = gl_LocalInvocationIndex; i < uint(P.dims.w); i += group_size) {
        tf_s_shared[i] = P.tf_s[i >> 2][i & 3];
        tf_rgba_shared[i] = P.tf_rgba[i];
    }
    barrier();
}

#define TF_RGBA(i) tf_rgba_shared[i]

float tf_point_s(int i)
{
    return tf_s_shared[i];
}

vec4 tf_eval(float s)
{
    int n = P.dims.w;
    if (s <= tf_point_s(0) || n == 1)
        return TF_RGBA(0);
    if (s >= tf_point_s(n - 1))
        return TF_RGBA(n - 1);
    int a = 0, b = n - 1;
    while (b - a > 1) {
        int mid = (a + b) / 2;
        if (tf_point_s(mid) <= s)
            a = mid;
        else
            b = mid;
    }
    float u = (s - tf_point_s(a)) / (tf_point_s(b) - tf_point_s(a));
    return mix(TF_RGBA(a), TF_RGBA(b), u);
}

#define OPAQUE_TRANSMITTANCE 0.02
#define MAX_PIECE_DEPTH 0.05
#define MAX_PIECE_STEPS 256

vec3 color;
float transmittance;
float shade_m = 1.0; // lighting factor m of the stretch being integrated (render.h: LIGHTING FACTOR)

void integrate_linear(float h, vec4 c0, vec4 c1)
{
    float inv_unit = P.scalar_map.z;
    float depth = h * 0.5 * (c0.a + c1.a) * inv_unit;
    if (!(depth > 0.0))
        return;
    int n = clamp(int(ceil(depth / MAX_PIECE_DEPTH)), 1, MAX_PIECE_STEPS);
    float step = h / float(n);
    for (int j = 0; j < n; j++) {
        work++;
        float u0 = float(j) / float(n), u1 = float(j + 1) / float(n);
        vec4 e0 = mix(c0, c1, u0), e1 = mix(c0, c1, u1);
        float k = e0.a + e1.a;
        if (k <= 0.0)
            continue;
        float alpha = 1.0 - exp(-step * 0.5 * k * inv_unit);
        float weight = shade_m * transmittance * alpha / k;
        color += weight * (e0.rgb * e0.a + e1.rgb * e1.a);
        transmittance *= 1.0 - alpha;
    }
}

// The first TF control point with s > x (the count when none): the pieces below visit only the
// points a piece crosses, not all of them (render_cpu.c skips the others; here a loop that no lane
// needs costs nothing, while an `if` inside a loop costs on every iteration on a CPU device).
int tf_first_above(float x)
{
    int a = 0, b = P.dims.w;
    while (a < b) {
        int mid = (a + b) / 2;
        if (tf_point_s(mid) <= x)
            a = mid + 1;
        else
            b = mid;
    }
    return a;
}

// The TF at the last scalar integrate_exact looked up: a piece starts at the scalar the one before
// ended at, so its tf_eval is skipped (IF_ANY) in the common case.
float tf_last_s = uintBitsToFloat(0x7fc00000u); // NaN: equal to nothing
vec4 tf_last_c;

vec4 tf_eval_cached(float s)
{
    vec4 c = tf_last_c;
    IF_ANY(!(s == tf_last_s))
        c = tf_eval(s);
    tf_last_s = s;
    tf_last_c = c;
    return c;
}

// render_cpu.c's integrate_exact: split where the scalar crosses a TF control point.
void integrate_exact(float len, float s0, float s1)
{
    vec4 ca = tf_eval_cached(s0);
    if (s0 == s1) {
        integrate_linear(len, ca, ca);
        return;
    }
    float ds = s1 - s0, prev_s = s0;
    int n = P.dims.w;
    if (ds > 0.0) {
        for (int k = tf_first_above(s0); k < n && tf_point_s(k) < s1; k++) {
            work++;
            float cs = tf_point_s(k);
            vec4 cb = TF_RGBA(k);
            integrate_linear(len * ((cs - prev_s) / ds), ca, cb);
            ca = cb;
            prev_s = cs;
        }
    } else {
        // points below s0 (those equal to it are not crossed), downwards while above s1
        int k = tf_first_above(s0) - 1;
        while (k >= 0 && tf_point_s(k) >= s0)
            k--;
        for (; k >= 0 && tf_point_s(k) > s1; k--) {
            work++;
            float cs = tf_point_s(k);
            vec4 cb = TF_RGBA(k);
            integrate_linear(len * ((cs - prev_s) / ds), ca, cb);
            ca = cb;
            prev_s = cs;
        }
    }
    integrate_linear(len * ((s1 - prev_s) / ds), ca, tf_eval_cached(s1));
}

// One point sample of `step` length at TF coordinate u.
void composite_sample(float step, float u)
{
    vec4 c = tf_eval(u);
    float alpha = 1.0 - exp(-step * c.a * P.scalar_map.z);
    color += shade_m * transmittance * alpha * c.rgb;
    transmittance *= 1.0 - alpha;
}

void integrate_sampled(float len, float s0, float s1)
{
    float max_step = 0.5 / P.scalar_map.z;
    int n = clamp(int(ceil(len / max_step)), 1, 4096);
    float step = len / float(n);
    for (int j = 0; j < n && transmittance > OPAQUE_TRANSMITTANCE; j++)
        composite_sample(step, s0 + (s1 - s0) * ((float(j) + 0.5) / float(n)));
}

// ri_integrate: one stretch of volume, as `integration` says.
void integrate(float len, float u0, float u1)
{
    if (!(len > 0.0))
        return;
    if (TPK_VK_INTEGRATION == 1)
        integrate_sampled(len, u0, u1);
    else if (TPK_VK_INTEGRATION == 2)
        composite_sample(len, 0.5 * (u0 + u1));
    else
        integrate_exact(len, u0, u1);
}

float normalized(float scalar)
{
    if (P.mode.w == 0 || P.scalar_map.y == 0.0)
        return 0.5;
    return (scalar - P.scalar_map.x) * P.scalar_map.y;
}
