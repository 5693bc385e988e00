// The Vulkan renderer's compute shader: one invocation per pixel. Finds the ray's shell entries in
// order with the shell BVH, marches tets through neighbor links with watertight face tests, and
// integrates emission-absorption per tet piece exactly as tools/render/render_cpu.c does. The marcher
// follows libtetpack/march.c, ray.c and shell_bvh.c step for step (same entry order, same exit-face
// rule, same tie-breaks), in float instead of double. Watertightness does not need double: every edge
// decision is a deterministic function of its two vertex ids and their projections (computed by one
// `precise` function, so no call site fuses differently), evaluated in the canonical (lower id first)
// order, with an exact sign (Dekker products) on the slow path.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "vk_layout.h"

layout(local_size_x = TPK_VK_GROUP, local_size_y = TPK_VK_GROUP) in;

layout(constant_id = TPK_VK_SPEC_LAYOUT) const int LAYOUT = TPK_VK_LAYOUT_TET16;
layout(constant_id = TPK_VK_SPEC_EXACT) const int EXACT = TPK_VK_EXACT_FILTER;
// Effects compiled in (TPK_VK_EFFECT_* bits): code for an effect that is off is not there at all, as
// a CPU device would otherwise run it under a mask on every step.
layout(constant_id = TPK_VK_SPEC_EFFECTS) const int EFFECTS = 0;
// Rays run in slices of bounded work, their state kept between dispatches (vk_layout.h: a CPU device).
layout(constant_id = TPK_VK_SPEC_SLICED) const bool SLICED = false;
const bool ISO = (EFFECTS & TPK_VK_EFFECT_ISO) != 0;
const bool SHADING = (EFFECTS & TPK_VK_EFFECT_SHADING) != 0;
const bool SHADOWS = (EFFECTS & TPK_VK_EFFECT_SHADOWS) != 0;
const bool AO = (EFFECTS & TPK_VK_EFFECT_AO) != 0;
// --occlusion vertex: S and A interpolated from the per-vertex cache (render.h OCCLUSION AT VERTICES)
const bool VERTEX_OCC = (EFFECTS & TPK_VK_EFFECT_VERTEX) != 0;
const bool CAST = (SHADOWS || AO) && !VERTEX_OCC;
const bool LIGHTING = SHADING || SHADOWS || AO;
// iso-only primary rays take their pieces from the range BVH (render.h ISO-ONLY RAYS), not the marcher
const bool CULL = (EFFECTS & TPK_VK_EFFECT_CULL) != 0;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_VERTS)) const int PARTS_VERTS = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_VERTS)) const int SHIFT_VERTS = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_TETS)) const int PARTS_TETS = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_TETS)) const int SHIFT_TETS = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_SHELL)) const int PARTS_SHELL = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_SHELL)) const int SHIFT_SHELL = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_NODES)) const int PARTS_NODES = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_NODES)) const int SHIFT_NODES = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_TET_SCALARS)) const int PARTS_TET_SCALARS = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_TET_SCALARS)) const int SHIFT_TET_SCALARS = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_VERTEX_SA)) const int PARTS_VERTEX_SA = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_VERTEX_SA)) const int SHIFT_VERTEX_SA = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_RANGE_NODES)) const int PARTS_RANGE_NODES = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_RANGE_NODES)) const int SHIFT_RANGE_NODES = 27;
layout(constant_id = TPK_VK_SPEC_PARTS(TPK_VK_ARRAY_RANGE_TETS)) const int PARTS_RANGE_TETS = 1;
layout(constant_id = TPK_VK_SPEC_SHIFT(TPK_VK_ARRAY_RANGE_TETS)) const int SHIFT_RANGE_TETS = 27;

// Mirrors tpk_vk_params in render_vk_internal.h (std140).
layout(std140, set = 0, binding = TPK_VK_BIND_PARAMS) uniform Params {
    vec4 eye;        // xyz: the eye relative to the mesh origin
    vec4 forward;    // xyz: unit view direction; w: tan(fovy/2) * width / height
    vec4 right;      // xyz; w: tan(fovy/2)
    vec4 up;         // xyz; w: extra box padding for the float box test
    vec4 background; // straight RGBA
    vec4 scalar_map; // x: range_min, y: 1 / (range_max - range_min) or 0, z: 1 / unit_distance
    ivec4 dims;      // width, height, first row of this dispatch, TF point count
    ivec4 mode;      // x: tet count, y: vertex count, z: integration (0 exact, 1 sampled),
                     // w: scalars (0 none, 1 per point, 2 per tet)
    vec4 clip_lo;    // xyz: clip box (relative to the origin); w: 1 when clipping
    vec4 clip_hi;
    ivec4 shell_info; // x: shell face count, y: iso value count, z: CULL: the range BVH's first leaf node
    vec4 iso;         // iso values (scalar units)
    vec4 light;       // xyz: point light (relative to the origin; the eye without one); w: iso opacity
    vec4 cast_info;   // x: AO ray length, y: TPK_RENDER_SELF_EPS * unit distance, z: unit distance
    ivec4 cast_count; // x: AO rays; y: the row after this dispatch's rows (a band need not be whole groups);
                      // z: the slice (SLICED: 0 starts the band's rays, later ones resume them)
    ivec4 probe_info;   // x: probe count; y: bit i set when probe i cuts
    vec4 probe_a[TPK_VK_MAX_PROBES]; // xyz: center, point or min (relative to the origin); w: shape
    vec4 probe_b[TPK_VK_MAX_PROBES]; // xyz: the plane's normal or the box's max; w: the sphere's radius
    vec4 tf_s[TPK_VK_TF_MAX / 4];
    vec4 tf_rgba[TPK_VK_TF_MAX];
} P;

layout(std430, set = 0, binding = TPK_VK_BIND_PIXELS) writeonly buffer Pixels { uint pixels[]; };
layout(std430, set = 0, binding = TPK_VK_BIND_COUNTERS) buffer Counters { uint counters[TPK_VK_COUNT_WORDS]; };
layout(std430, set = 0, binding = TPK_VK_BIND_STATE) buffer State { vec4 state[]; }; // sliced: rays between slices

uint work = 0u; // this dispatch's iterations of the loops that can run long (sliced: TPK_VK_SLICE_WORK)

// Split texel arrays: TPK_VK_MAX_PARTS bindings each; with one part the switch folds away.
#define DECLARE_ARRAY(SAMPLER, NAME, ARRAY)                                                   \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 0) uniform SAMPLER NAME##0;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 1) uniform SAMPLER NAME##1;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 2) uniform SAMPLER NAME##2;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 3) uniform SAMPLER NAME##3;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 4) uniform SAMPLER NAME##4;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 5) uniform SAMPLER NAME##5;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 6) uniform SAMPLER NAME##6;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 7) uniform SAMPLER NAME##7;

#define FETCH_FUNCTION(RET, NAME, PARTS, SHIFT)                                               \
    RET fetch_##NAME(uint i)                                                                  \
    {                                                                                         \
        if (PARTS == 1)                                                                       \
            return texelFetch(NAME##0, int(i));                                               \
        int j = int(i & ((1u << SHIFT) - 1u));                                                \
        switch (i >> SHIFT) {                                                                 \
        case 0u: return texelFetch(NAME##0, j);                                               \
        case 1u: return texelFetch(NAME##1, j);                                               \
        case 2u: return texelFetch(NAME##2, j);                                               \
        case 3u: return texelFetch(NAME##3, j);                                               \
        case 4u: return texelFetch(NAME##4, j);                                               \
        case 5u: return texelFetch(NAME##5, j);                                               \
        case 6u: return texelFetch(NAME##6, j);                                               \
        default: return texelFetch(NAME##7, j);                                               \
        }                                                                                     \
    }

DECLARE_ARRAY(samplerBuffer, verts, TPK_VK_ARRAY_VERTS)
DECLARE_ARRAY(isamplerBuffer, tets, TPK_VK_ARRAY_TETS)
DECLARE_ARRAY(isamplerBuffer, shell, TPK_VK_ARRAY_SHELL)
DECLARE_ARRAY(usamplerBuffer, nodes, TPK_VK_ARRAY_NODES)
DECLARE_ARRAY(samplerBuffer, tet_scalars, TPK_VK_ARRAY_TET_SCALARS)
DECLARE_ARRAY(samplerBuffer, vertex_sa, TPK_VK_ARRAY_VERTEX_SA)
DECLARE_ARRAY(samplerBuffer, range_nodes, TPK_VK_ARRAY_RANGE_NODES)
DECLARE_ARRAY(isamplerBuffer, range_tets, TPK_VK_ARRAY_RANGE_TETS)
FETCH_FUNCTION(vec4, verts, PARTS_VERTS, SHIFT_VERTS)
FETCH_FUNCTION(ivec4, tets, PARTS_TETS, SHIFT_TETS)
FETCH_FUNCTION(ivec4, shell, PARTS_SHELL, SHIFT_SHELL)
FETCH_FUNCTION(uvec4, nodes, PARTS_NODES, SHIFT_NODES)
FETCH_FUNCTION(vec4, tet_scalars, PARTS_TET_SCALARS, SHIFT_TET_SCALARS)
FETCH_FUNCTION(vec4, vertex_sa, PARTS_VERTEX_SA, SHIFT_VERTEX_SA)
FETCH_FUNCTION(vec4, range_nodes, PARTS_RANGE_NODES, SHIFT_RANGE_NODES)
FETCH_FUNCTION(ivec4, range_tets, PARTS_RANGE_TETS, SHIFT_RANGE_TETS)

// `IF_ANY(c) { ... }` runs the block once where c holds. On a CPU device (lavapipe) every lane runs
// both sides of an `if` under a mask, whatever the lanes decided; a loop that no lane enters is
// skipped. So a block that is rarely needed costs nothing in the common case. No `return` inside
// (see march_run.glsl).
#define IF_ANY(c) for (bool rare_once = (c); rare_once; rare_once = false)

// ---- The ray frame and the watertight edge test (libtetpack/internal_ray.h, ray.c) --------------

struct Frame {
    vec3 org;
    float sx, sy, sz;
    int kx, ky, kz;
};

Frame frame;       // of this invocation's ray
vec3 ray_dir;

// Projection of vertex v and its scalar (w). The one place positions become 2-D coordinates.
vec4 project(int v, out float scalar)
{
    vec4 p = fetch_verts(uint(v));
    scalar = p.w;
    precise vec3 q = p.xyz - frame.org;
    precise float x = q[frame.kx] - frame.sx * q[frame.kz];
    precise float y = q[frame.ky] - frame.sy * q[frame.kz];
    precise float z = frame.sz * q[frame.kz];
    return vec4(x, y, z, 0.0);
}

#if TPK_VK_FP64
// Exact sign of a*d - b*c for floats: the products are exact in double and the one rounding of their
// difference keeps its sign (and is 0 only when it is exactly 0).
int det2_sign_exact(float a, float b, float c, float d)
{
    precise double ad = double(a) * double(d);
    precise double bc = double(b) * double(c);
    precise double det = ad - bc;
    return det > 0.0LF ? 1 : det < 0.0LF ? -1 : 0;
}
#else
// Error-free product (Dekker): a * b == p + err exactly, no fused multiply-add needed.
float two_prod(float a, float b, out float err)
{
    precise float p = a * b;
    precise float ca = 4097.0 * a;
    precise float ahi = ca - (ca - a);
    precise float alo = a - ahi;
    precise float cb = 4097.0 * b;
    precise float bhi = cb - (cb - b);
    precise float blo = b - bhi;
    precise float e = ((ahi * bhi - p) + ahi * blo + alo * bhi) + alo * blo;
    err = e;
    return p;
}

float two_sum(float a, float b, out float err)
{
    precise float s = a + b;
    precise float bv = s - a;
    precise float av = s - bv;
    precise float e = (a - av) + (b - bv);
    err = e;
    return s;
}

// Exact sign of a*d - b*c (ray.c, tpki_det2_sign_exact, in float).
int det2_sign_exact(float a, float b, float c, float d)
{
    float ad_lo, bc_lo, x0, x1, x2, m0, i0, i1;
    float ad = two_prod(a, d, ad_lo);
    float bc = two_prod(b, c, bc_lo);
    i0 = two_sum(ad_lo, -bc_lo, x0);
    float j = two_sum(ad, i0, m0);
    i1 = two_sum(m0, -bc, x1);
    float x3 = two_sum(j, i1, x2);
    if (x3 != 0.0) return x3 > 0.0 ? 1 : -1;
    if (x2 != 0.0) return x2 > 0.0 ? 1 : -1;
    if (x1 != 0.0) return x1 > 0.0 ? 1 : -1;
    if (x0 != 0.0) return x0 > 0.0 ? 1 : -1;
    return 0;
}
#endif

// Ties (the ray's point exactly on the edge's line) fall to the perturbation of the ray's point.
int tie_sign(vec4 lo, vec4 hi)
{
    float dy = lo.y - hi.y, dx = hi.x - lo.x;
    return dy > 0.0 ? 1 : dy < 0.0 ? -1 : dx > 0.0 ? 1 : dx < 0.0 ? -1 : 1;
}

// tpk_edge_sign: orient(P_i, P_j, o) with o = (0,0) symbolically perturbed; never 0.
int edge_sign(int i, vec4 pi, int j, vec4 pj, out float value)
{
    vec4 lo = pi, hi = pj;
    int flip = 1;
    if (i > j) {
        lo = pj;
        hi = pi;
        flip = -1;
    }
#if TPK_VK_FP64
    if (EXACT == TPK_VK_EXACT_ALWAYS) {
        precise double ad = double(lo.x) * double(hi.y);
        precise double bc = double(lo.y) * double(hi.x);
        precise double dd = ad - bc;
        int sign = dd > 0.0LF ? 1 : dd < 0.0LF ? -1 : 0;
        value = sign == 0 ? 0.0 : float(flip) * float(dd);
        return flip * (sign == 0 ? tie_sign(lo, hi) : sign);
    }
#endif
    precise float p = lo.x * hi.y;
    precise float q = lo.y * hi.x;
    precise float det = p - q;
    float bound = 2.384185791015625e-7 * (abs(p) + abs(q)); // 4 u, u = 2^-24
    int sign = det > bound ? 1 : -1;
    // The exact test near zero, in a loop rather than an `if`: a CPU device runs an `if` under a mask
    // for every lane, but skips a loop that no lane enters, and this one is rarely entered.
    IF_ANY(!(det > bound || det < -bound)) {
        sign = det2_sign_exact(lo.x, lo.y, hi.x, hi.y);
        if (sign == 0 || (det > 0.0 && sign < 0) || (det < 0.0 && sign > 0) || isnan(det))
            det = 0.0;
        if (sign == 0)
            sign = tie_sign(lo, hi);
    }
    value = float(flip) * det;
    return flip * sign;
}

// The face a ray crosses (tpk_face_hit): ids, projections (w unused), edge values, scalars.
struct Hit {
    ivec3 v;
    vec4 p0, p1, p2;
    vec3 e;
    vec3 s; // the vertices' point scalars
    float t;
};

vec3 edge_weights(Hit h, int zero_edge)
{
    // the edge (i, j) = (zero_edge, zero_edge + 1), interpolated from its lower id (ray.c)
    vec4 pi = zero_edge == 0 ? h.p0 : zero_edge == 1 ? h.p1 : h.p2;
    vec4 pj = zero_edge == 0 ? h.p1 : zero_edge == 1 ? h.p2 : h.p0;
    int vi = zero_edge == 0 ? h.v[0] : zero_edge == 1 ? h.v[1] : h.v[2];
    int vj = zero_edge == 0 ? h.v[1] : zero_edge == 1 ? h.v[2] : h.v[0];
    bool i_low = vi < vj;
    vec4 a = i_low ? pi : pj, b = i_low ? pj : pi;
    precise float ex = b.x - a.x;
    precise float ey = b.y - a.y;
    precise float len2 = ex * ex + ey * ey;
    precise float u = len2 > 0.0 ? -(a.x * ex + a.y * ey) / len2 : 0.5;
    u = clamp(u, 0.0, 1.0);
    float wi = i_low ? 1.0 - u : u, wj = i_low ? u : 1.0 - u;
    return zero_edge == 0 ? vec3(wi, wj, 0.0) : zero_edge == 1 ? vec3(0.0, wi, wj) : vec3(wj, 0.0, wi);
}

// The corner (0..2) of the face's smallest id (internal_ray.h, tpk_face_first): every sum over a face's
// corners starts there, so a face gives the same weights, t and scalar, bit for bit, in whatever rotation
// it is held (the marcher holds it as its path gave it; range culling meets the tet without a path).
int face_first(Hit h)
{
    return h.v[1] < h.v[0] ? (h.v[2] < h.v[1] ? 2 : 1) : (h.v[2] < h.v[0] ? 2 : 0);
}

// x[0..2] weighted by w, summed from corner `first` on (tpk_face_sum).
float face_sum(int first, vec3 w, vec3 x)
{
    const int b = first == 2 ? 0 : first + 1, c = first == 0 ? 2 : first - 1;
    precise float s = w[first] * x[first] + w[b] * x[b] + w[c] * x[c];
    return s;
}

vec3 face_weights(Hit h)
{
    const int f = face_first(h);
    precise float sum = h.e[f] + h.e[f == 2 ? 0 : f + 1] + h.e[f == 0 ? 2 : f - 1];
    precise float inv = 1.0 / sum;
    vec3 w = sum != 0.0 && !isnan(sum) ? vec3(h.e[1] * inv, h.e[2] * inv, h.e[0] * inv) : vec3(1.0 / 3.0);
    int zeros = int(h.e[0] == 0.0) + int(h.e[1] == 0.0) + int(h.e[2] == 0.0);
    IF_ANY(zeros == 1) // the ray through an edge: rare, so a loop (see edge_sign)
        w = edge_weights(h, h.e[0] == 0.0 ? 0 : h.e[1] == 0.0 ? 1 : 2);
    return w;
}

float hit_t(Hit h, vec3 w)
{
    return face_sum(face_first(h), w, vec3(h.p0.z, h.p1.z, h.p2.z));
}

// The face's corners from its smallest id on, then `fourth` (tpk_segment.v: for gradients).
ivec4 face_from_first(Hit h, int fourth)
{
    const int f = face_first(h);
    return ivec4(h.v[f], h.v[f == 2 ? 0 : f + 1], h.v[f == 0 ? 2 : f - 1], fourth);
}

// tpki_shell_face_entry: does the line enter the volume through shell face f (outward winding)?
bool shell_face_entry(ivec4 f, out Hit h)
{
    h.v = f.xyz;
    h.p0 = project(f.x, h.s[0]);
    h.p1 = project(f.y, h.s[1]);
    h.p2 = vec4(0.0);
    h.s[2] = 0.0;
    h.e = vec3(0.0);
    h.t = 0.0;
    if (edge_sign(f.x, h.p0, f.y, h.p1, h.e[0]) > 0)
        return false;
    h.p2 = project(f.z, h.s[2]);
    if (edge_sign(f.y, h.p1, f.z, h.p2, h.e[1]) > 0)
        return false;
    if (edge_sign(f.z, h.p2, f.x, h.p0, h.e[2]) > 0)
        return false;
    h.t = hit_t(h, face_weights(h));
    return true;
}

// ---- Shell entries through the BVH (shell_bvh.c): found one at a time, in (t, face) order ----------

vec3 inv_dir;

// The t at which the line enters node n's box, if it meets the box for some t in [t_low, t_high];
// +inf otherwise. Boxes are widened by P.up.w on top of the builder's padding, for the float slab test.
float box_enter(uint n, float t_low, float t_high)
{
    uvec4 a = fetch_nodes(2u * n), b = fetch_nodes(2u * n + 1u);
    vec3 lo = uintBitsToFloat(a.xyz) - P.up.w, hi = uintBitsToFloat(b.xyz) + P.up.w;
    float tn = -1.0 / 0.0, tf = t_high;
    bool meets = true;
    for (int k = 0; k < 3; k++) {
        if (ray_dir[k] == 0.0) {
            meets = meets && frame.org[k] >= lo[k] && frame.org[k] <= hi[k];
            continue;
        }
        float t0 = (lo[k] - frame.org[k]) * inv_dir[k], t1 = (hi[k] - frame.org[k]) * inv_dir[k];
        tn = max(tn, min(t0, t1));
        tf = min(tf, max(t0, t1));
    }
    return meets && tn <= tf && tf >= t_low ? tn : 1.0 / 0.0;
}

#define STACK_SIZE 96 // TPK_SHELL_BVH_STACK
#define INF (1.0 / 0.0)

// Shell BVH traversal, nearer child first, over boxes met within [t_low, t_high]; t_high shrinks as
// the query finds better entries. mode 0: the last entry before t_high (the ray's start); mode 1: the
// first entry after (t_prev, face_prev) in (t, face) order.
int bvh_query(int mode, float t_low, float t_high, float t_prev, int face_prev, out Hit best_hit)
{
    int best = -1;
    float best_t = mode == 0 ? -INF : INF;
    uint stack[STACK_SIZE];
    float stack_t[STACK_SIZE];
    int top = 0;
    float t_root = box_enter(0u, t_low, t_high);
    if (t_root == INF)
        return -1;
    stack[top] = 0u;
    stack_t[top++] = t_root;
    while (top > 0) {
        --top;
        work++;
        uint n = stack[top];
        if (mode == 1 && stack_t[top] > best_t)
            continue; // every face in it is after the best entry found since it was pushed
        uvec4 a = fetch_nodes(2u * n), b = fetch_nodes(2u * n + 1u);
        uint first = a.w, count = b.w;
        if (count == 0u) {
            float hi_t = mode == 1 ? best_t : t_high;
            float lo_t = mode == 0 ? max(t_low, best_t) : t_low;
            float t0 = box_enter(first, lo_t, hi_t), t1 = box_enter(first + 1u, lo_t, hi_t);
            uint near = t0 <= t1 ? first : first + 1u, far = t0 <= t1 ? first + 1u : first;
            float near_t = min(t0, t1), far_t = max(t0, t1);
            if (far_t != INF) {
                stack[top] = far;
                stack_t[top++] = far_t;
            }
            if (near_t != INF) {
                stack[top] = near;
                stack_t[top++] = near_t;
            }
            continue;
        }
        for (uint i = first; i < first + count; i++) {
            Hit h;
            int f = int(i);
            if (!shell_face_entry(fetch_shell(i), h))
                continue;
            if (mode == 0) {
                if (h.t < t_high && h.t > best_t) {
                    best_t = h.t;
                    best = f;
                }
            } else {
                bool after = h.t > t_prev || (h.t == t_prev && f > face_prev);
                bool better = best < 0 || h.t < best_t || (h.t == best_t && f < best);
                if (after && better) {
                    best = f;
                    best_t = h.t;
                    best_hit = h;
                }
            }
        }
    }
    if (mode == 0)
        best_hit.t = best_t;
    return best;
}

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
    if (P.mode.z == 1)
        integrate_sampled(len, u0, u1);
    else if (P.mode.z == 2)
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

// The ray's frame (ray.c, tpki_ray_frame_init); false for a degenerate direction.
bool frame_init(vec3 org, vec3 dir)
{
    int kz = 0;
    if (abs(dir[1]) > abs(dir[kz]))
        kz = 1;
    if (abs(dir[2]) > abs(dir[kz]))
        kz = 2;
    if (dir[kz] == 0.0)
        return false;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (dir[kz] < 0.0) {
        int swap = kx;
        kx = ky;
        ky = swap;
    }
    frame.org = org;
    frame.kx = kx;
    frame.ky = ky;
    frame.kz = kz;
    frame.sx = dir[kx] / dir[kz];
    frame.sy = dir[ky] / dir[kz];
    frame.sz = 1.0 / dir[kz];
    return true;
}

// render.h's CLIP BOX: cut [lo, hi] of the ray org + t dir to the box; false when it misses.
bool clip_ray(vec3 org, vec3 dir, inout float lo, inout float hi)
{
    bool meets = true;
    for (int k = 0; P.clip_lo.w != 0.0 && k < 3; k++) {
        if (dir[k] == 0.0) {
            meets = meets && org[k] >= P.clip_lo[k] && org[k] <= P.clip_hi[k];
            continue;
        }
        float t0 = (P.clip_lo[k] - org[k]) / dir[k], t1 = (P.clip_hi[k] - org[k]) / dir[k];
        lo = max(lo, min(t0, t1));
        hi = min(hi, max(t0, t1));
    }
    return meets && lo <= hi;
}

// render.h PROBES (probe.c): the inside of probe i on the ray org + t dir as [t0, t1]; false: missed.
bool probe_interval(int i, vec3 org, vec3 dir, out float t0, out float t1)
{
    const vec4 a = P.probe_a[i], b = P.probe_b[i];
    t0 = -INF;
    t1 = INF;
    if (a.w == float(TPK_VK_PROBE_SPHERE)) {
        const vec3 e = org - a.xyz;
        const float q = dot(dir, e), disc = q * q - (dot(e, e) - b.w * b.w);
        if (disc < 0.0)
            return false;
        const float r = sqrt(disc);
        t0 = -q - r;
        t1 = -q + r;
        return true;
    }
    if (a.w == float(TPK_VK_PROBE_PLANE)) {
        const float e = dot(org - a.xyz, b.xyz), f = dot(dir, b.xyz);
        if (f == 0.0)
            return e <= 0.0;
        if (f > 0.0)
            t1 = -e / f;
        else
            t0 = -e / f;
        return true;
    }
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0.0) {
            if (org[k] < a[k] || org[k] > b[k])
                return false;
            continue;
        }
        const float ta = (a[k] - org[k]) / dir[k], tb = (b[k] - org[k]) / dir[k];
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
    return t0 <= t1;
}

#define MAX_SPANS (TPK_VK_MAX_PROBES + 1)

// The spans of [lo, hi] that the probes keep, in order (tpk_probe_spans); their count.
int probe_spans(vec3 org, vec3 dir, float lo, float hi, out float sa[MAX_SPANS], out float sb[MAX_SPANS])
{
    if (!(lo < hi))
        return 0;
    int n = 1;
    sa[0] = lo;
    sb[0] = hi;
    for (int i = 0; i < P.probe_info.x && n > 0; i++) {
        float t0, t1;
        const bool meets = probe_interval(i, org, dir, t0, t1), cut = (P.probe_info.y & (1 << i)) != 0;
        if (!meets) {
            if (!cut)
                return 0;
            continue;
        }
        float na[MAX_SPANS], nb[MAX_SPANS];
        int m = 0;
        for (int j = 0; j < n; j++) {
            const float p = sa[j], q = sb[j];
            if (!cut) {
                const float x = max(p, t0), y = min(q, t1);
                if (x < y) {
                    na[m] = x;
                    nb[m] = y;
                    m++;
                }
                continue;
            }
            const float y = min(q, t0), x = max(p, t1);
            if (p < y && m < MAX_SPANS) {
                na[m] = p;
                nb[m] = y;
                m++;
            }
            if (x < q && m < MAX_SPANS) {
                na[m] = x;
                nb[m] = q;
                m++;
            }
        }
        for (int j = 0; j < m; j++) {
            sa[j] = na[j];
            sb[j] = nb[j];
        }
        n = m;
    }
    return n;
}

// ---- One inside-run (march.c, march_run) --------------------------------------------------------

uint steps_taken;
uint status;
float run_exit_t; // t of the shell face the last run left through

// What a piece tells the march (MARCH_REPORT), and how a run ends (march_run.glsl).
#define MARCH_GO 0
#define MARCH_STOP 1
#define MARCH_PAUSE 2
#define MARCH_RAY_DONE 0
#define MARCH_RAY_EXIT 1
#define MARCH_RAY_PAUSED 2

struct MarchRun { // one inside-run, resumable: the tet to step next and how it was entered
    Hit h;
    int tet, prev, step;
    float s_in;
};

struct MarchTrace { // the runs of one ray, resumable
    MarchRun run;
    float t_prev, t_low, tmax;
    int face_prev;
    bool in_run;
};

int rank4(int x, int a, int b, int c, int d)
{
    return int(a < x) + int(b < x) + int(c < x) + int(d < x);
}

float hit_scalar(Hit h, vec3 w)
{
    return face_sum(face_first(h), w, h.s);
}

// ---- Effects (render.h: ISOSURFACES, NORMAL, LIGHTING FACTOR) -------------------------------------

vec3 eye_dir_point(float t)
{
    return P.eye.xyz + t * ray_dir;
}

// m at x with normal n (has_n false: no normal), shadow transmittance S and AO factor A (rl_factor).
float lighting_factor(vec3 x, bool has_n, vec3 n, float S, float A)
{
    float d = 1.0;
    vec3 to_light = P.light.xyz - x;
    float len = length(to_light);
    if (SHADING && has_n && len > 0.0 && !isinf(len))
        d = abs(dot(n, to_light / len));
    return A * (0.3 + 0.7 * d * S); // TPK_RENDER_AMBIENT
}

bool unit_or_none(vec3 v, out vec3 n)
{
    float len = length(v);
    n = v / len;
    return len > 0.0 && !isinf(len) && !isnan(len);
}

// The unit gradient of the point scalar over the tet v[0..3] (false where it is zero).
bool tet_normal(ivec4 v, out vec3 n)
{
    vec4 p0 = fetch_verts(uint(v.x)), p1 = fetch_verts(uint(v.y)), p2 = fetch_verts(uint(v.z)),
         p3 = fetch_verts(uint(v.w));
    vec3 e1 = p1.xyz - p0.xyz, e2 = p2.xyz - p0.xyz, e3 = p3.xyz - p0.xyz;
    vec3 c23 = cross(e2, e3), c31 = cross(e3, e1), c12 = cross(e1, e2);
    float det = dot(e1, c23);
    vec3 g = ((p1.w - p0.w) * c23 + (p2.w - p0.w) * c31 + (p3.w - p0.w) * c12) / det;
    return unit_or_none(g, n);
}

// render_light.c's rl_vertex_lookup: S and A at x (eye-relative world, as eye_dir_point gives it) from the
// per-vertex cache, linear in the tet v[0..3] (barycentric from its edges; the mean of the four where
// the tet is flat), clamped to [0, 1].
vec2 vertex_lookup(ivec4 v, vec3 x)
{
    vec4 p0 = fetch_verts(uint(v.x)), p1 = fetch_verts(uint(v.y)), p2 = fetch_verts(uint(v.z)),
         p3 = fetch_verts(uint(v.w));
    vec3 e1 = p1.xyz - p0.xyz, e2 = p2.xyz - p0.xyz, e3 = p3.xyz - p0.xyz;
    vec3 c1 = cross(e2, e3), c2 = cross(e3, e1), c3 = cross(e1, e2);
    float det = dot(e1, c1);
    vec3 q = x - p0.xyz;
    vec4 l = vec4(0.25);
    if (det != 0.0 && !isinf(det) && !isnan(det)) {
        l.yzw = vec3(dot(q, c1), dot(q, c2), dot(q, c3)) / det;
        l.x = 1.0 - l.y - l.z - l.w;
    }
    vec2 sa = l.x * fetch_vertex_sa(uint(v.x)).xy + l.y * fetch_vertex_sa(uint(v.y)).xy +
              l.z * fetch_vertex_sa(uint(v.z)).xy + l.w * fetch_vertex_sa(uint(v.w)).xy;
    return clamp(sa, 0.0, 1.0);
}

bool face_normal(ivec4 v, out vec3 n)
{
    vec3 p0 = fetch_verts(uint(v.x)).xyz, p1 = fetch_verts(uint(v.y)).xyz, p2 = fetch_verts(uint(v.z)).xyz;
    return unit_or_none(cross(p1 - p0, p2 - p0), n);
}

// Iso crossings of one piece, in increasing t (equal t: increasing j).
int crossing_j[4];
float crossing_t[4];

int add_crossing(int n, float t, int j)
{
    int k = n;
    while (k > 0 && (crossing_t[k - 1] > t || (crossing_t[k - 1] == t && crossing_j[k - 1] > j))) {
        crossing_t[k] = crossing_t[k - 1];
        crossing_j[k] = crossing_j[k - 1];
        k--;
    }
    crossing_t[k] = t;
    crossing_j[k] = j;
    return n + 1;
}

// Point field: where the linear scalar crosses each value (half-open, so a face counts once).
int point_crossings(float t_in, float t_out, float s_in, float s_out)
{
    int n = 0;
    for (int j = 0; j < P.shell_info.y; j++) {
        float v = P.iso[j];
        if ((s_in < v && v <= s_out) || (s_in > v && v >= s_out))
            n = add_crossing(n, clamp(t_in + (v - s_in) / (s_out - s_in) * (t_out - t_in), t_in, t_out), j);
    }
    return n;
}

// Tet field: the jump between two consecutive pieces, at t.
int jump_crossings(float t, float s_prev, float s)
{
    int n = 0;
    for (int j = 0; j < P.shell_info.y; j++) {
        float v = P.iso[j];
        if ((s_prev < v && v <= s) || (s_prev > v && v >= s))
            n = add_crossing(n, t, j);
    }
    return n;
}

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
        trans_iso *= 1.0 - P.light.w;
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
    if (t_out >= trans_lo) {
        float len = t_out - t_in, a = t_in, b = t_out, sa = s_in, sb = s_out;
        if (t_in < trans_lo) {
            a = trans_lo;
            sa = s_in + (s_out - s_in) * ((trans_lo - t_in) / len);
        }
        if (t_out > trans_hi) {
            b = trans_hi;
            sb = s_in + (s_out - s_in) * ((trans_hi - t_in) / len);
        }
        said = trans_piece(a, b, sa, sb) || t_out >= trans_hi ? MARCH_STOP : MARCH_GO;
    }
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

// The AO axis: the normal turned toward the viewer, -d without one (render.h: AO DIRECTIONS).
vec3 ao_axis(bool has_n, vec3 n)
{
    return has_n ? (dot(n, ray_dir) > 0.0 ? -n : n) : -ray_dir;
}

// AO ray i of P.cast_count.x around unit axis a (render.h: AO DIRECTIONS).
vec3 ao_direction(vec3 x, vec3 a, int i)
{
    int count = P.cast_count.x;
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
    return cast_asked * ((SHADOWS ? 1 : 0) + (AO ? P.cast_count.x : 0));
}

void cast_one(int k)
{
    const int per = (SHADOWS ? 1 : 0) + (AO ? P.cast_count.x : 0);
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
        len = P.cast_info.x;
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
        cast_A[i] /= float(P.cast_count.x);
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
        } else if (CAST) {
            take_cast(S, A);
        }
        m = lighting_factor(x, has_n, n, S, A);
    }
    vec4 c = tf_eval(normalized(v));
    float alpha = P.light.w;
    color += transmittance * alpha * m * c.rgb;
    transmittance *= 1.0 - alpha;
}

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
        // transmittance since the last cast; pieces in between reuse its S and A.
        volume_cast = CAST && t_out > t_in && optical_depth(t_out - t_in, u_in, u_out) > 0.0 &&
                      (!cast_done || t_cast - transmittance >= 1.0 / 32.0);
    }
    int said = MARCH_GO;
    if (CAST && !casts_ready && (volume_cast || nh > 0)) {
        if (volume_cast)
            ask_cast(eye_dir_point(0.5 * (t_in + t_out)), has_n, n);
        for (int i = 0; i < nh; i++) {
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
    if (t_out >= t_min_clip) {
        float len = t_out - t_in;
        float a = t_in, b = t_out, sa = s_in, sb = s_out;
        if (t_in < t_min_clip) {
            a = t_min_clip;
            sa = s_in + (s_out - s_in) * ((t_min_clip - t_in) / len);
        }
        if (t_out > t_max_clip) {
            b = t_max_clip;
            sb = s_in + (s_out - s_in) * ((t_max_clip - t_in) / len);
        }
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

// ---- Range culling of iso-only primary rays (libtetpack/range_bvh.c; render.h ISO-ONLY RAYS) -------
// The TF is transparent, so only the pieces that hold an iso crossing change the pixel. They come from
// the range BVH (tpk_range_bvh_heap: heap order, node n's children 2n and 2n + 1, leaves of
// TPK_VK_RANGE_LEAF consecutive tets from node P.shell_info.z on), one query at a time: the first piece
// after the last one handed on in (t_in, t_out, tet) order, over the nodes whose range holds a value and
// whose box the ray meets before the best piece found, nearer child first. The walk needs no stack: the
// parent of n is n / 2 and a bit per depth says which child was entered first, so a query's whole state
// is a node, where it came from and those bits (CullTrace), and a sliced ray stops after any node. Each candidate tet's
// piece is computed as the marcher computes it (face_weights, hit_t, hit_scalar from each face's
// smallest id), so report() gets the same pieces, bit for bit, and the picture is the same.

struct CullTrace {
    float t_prev, t_out_prev; // the last piece handed on (-inf: none yet)
    int tet_prev;
    uint node;     // the query's node
    uint from;     // 0: node was entered from above (the ray meets its box); else the child the walk came up from
    uint trail;    // bit d: at depth d (node n's depth is findMSB(n)) the walk went right first
    int best;      // the best piece of the query so far (tet), -1: none
    float best_in, best_out;
    bool in_query, have_piece; // have_piece: `best` is to be handed on (again, after a pause)
};

const int TET_FACES[12] = int[12](TPK_VK_TET_FACES);

// An iso value in [lo, hi], widened by a few float ulps of the range: the marcher's interpolated
// scalars are float sums of the vertex scalars and may leave their range by that much. Empty: lo > hi.
bool range_holds(float lo, float hi)
{
    const float m = 1e-6 * max(abs(lo), abs(hi));
    bool holds = false;
    for (int j = 0; j < P.shell_info.y; j++)
        holds = holds || (P.iso[j] >= lo - m && P.iso[j] <= hi + m);
    return lo <= hi && holds;
}

// Where the ray enters range node n's box (widened as box_enter widens), if its range holds a value and
// the ray meets it within [t_low, t_high]; +inf otherwise.
float cull_node_enter(uint n, float t_low, float t_high)
{
    const vec4 a = fetch_range_nodes(2u * n), b = fetch_range_nodes(2u * n + 1u);
    if (!range_holds(a.w, b.w))
        return INF;
    const vec3 lo = a.xyz - P.up.w, hi = b.xyz + P.up.w;
    float tn = -INF, tf = t_high;
    bool meets = true;
    for (int k = 0; k < 3; k++) {
        if (ray_dir[k] == 0.0) {
            meets = meets && frame.org[k] >= lo[k] && frame.org[k] <= hi[k];
            continue;
        }
        const float t0 = (lo[k] - frame.org[k]) * inv_dir[k], t1 = (hi[k] - frame.org[k]) * inv_dir[k];
        tn = max(tn, min(t0, t1));
        tf = min(tf, max(t0, t1));
    }
    return meets && tn <= tf && tf >= t_low ? tn : INF;
}

// The piece of tet `tet` (corners q, projected p, scalars s) as the marcher computes it (range_bvh.c's
// tet_piece): entry face the one whose outward edges all read -1, exit the one whose all read +1, each
// held with its edge values <= 0 as the marcher holds the faces it crosses. False: the ray misses it.
bool cull_piece(ivec4 q, vec4 p[4], float s[4], out float t_in, out float t_out, out float s_in,
                out float s_out, out ivec4 v)
{
    t_in = t_out = s_in = s_out = 0.0;
    v = ivec4(0);
    // edge i -> j for i < j at index (i, j): 01 02 03 12 13 23
    int sg[6];
    float val[6];
    sg[0] = edge_sign(q[0], p[0], q[1], p[1], val[0]);
    sg[1] = edge_sign(q[0], p[0], q[2], p[2], val[1]);
    sg[2] = edge_sign(q[0], p[0], q[3], p[3], val[2]);
    sg[3] = edge_sign(q[1], p[1], q[2], p[2], val[3]);
    sg[4] = edge_sign(q[1], p[1], q[3], p[3], val[4]);
    sg[5] = edge_sign(q[2], p[2], q[3], p[3], val[5]);
    Hit entry, exit;
    int opposite = -1;
    bool have_exit = false;
    for (int k = 0; k < 4; k++) {
        int g[3] = int[3](TET_FACES[3 * k], TET_FACES[3 * k + 1], TET_FACES[3 * k + 2]);
        int es[3];
        float ev[3];
        for (int i = 0; i < 3; i++) {
            const int a = g[i], b = g[i == 2 ? 0 : i + 1], lo = min(a, b), hi = max(a, b);
            const int e = lo == 0 ? hi - 1 : lo + hi; // 01 02 03 -> 0 1 2; 12 13 23 -> 3 4 5
            es[i] = a < b ? sg[e] : -sg[e];
            ev[i] = a < b ? val[e] : -val[e];
        }
        if (es[0] != es[1] || es[1] != es[2])
            continue;
        if (es[0] > 0) { // turned over: (g0, g2, g1), whose edges are the negated reversed ones
            g = int[3](g[0], g[2], g[1]);
            ev = float[3](-ev[2], -ev[1], -ev[0]);
        }
        const Hit h = Hit(ivec3(q[g[0]], q[g[1]], q[g[2]]), p[g[0]], p[g[1]], p[g[2]], vec3(ev[0], ev[1], ev[2]),
                          vec3(s[g[0]], s[g[1]], s[g[2]]), 0.0);
        if (es[0] < 0) {
            entry = h;
            opposite = k;
        } else {
            exit = h;
            have_exit = true;
        }
    }
    if (opposite < 0 || !have_exit)
        return false;
    vec3 w = face_weights(entry);
    t_in = hit_t(entry, w);
    s_in = hit_scalar(entry, w);
    v = face_from_first(entry, q[opposite]);
    w = face_weights(exit);
    t_out = hit_t(exit, w);
    if (!(t_out >= t_in))
        t_out = t_in; // rounding: as the marcher keeps its chain monotone
    s_out = hit_scalar(exit, w);
    return true;
}

// Tet `tet`'s corners, projected, and its scalars; false when its scalar range (widened as range_holds
// widens it) holds no iso value or the ray's point (0, 0) is off one side of all four.
bool cull_candidate(int tet, out ivec4 q, out vec4 p[4], out float s[4])
{
    q = fetch_range_tets(uint(tet));
    for (int i = 0; i < 4; i++)
        p[i] = project(q[i], s[i]);
    if (!range_holds(min(min(s[0], s[1]), min(s[2], s[3])), max(max(s[0], s[1]), max(s[2], s[3]))))
        return false;
    steps_taken++; // tets tested (tpk_march_ray_values' tet_steps)
    work++; // a tet tested is a few loops' worth: counted twice towards a slice
    const vec4 xs = vec4(p[0].x, p[1].x, p[2].x, p[3].x), ys = vec4(p[0].y, p[1].y, p[2].y, p[3].y);
    return !(all(greaterThan(xs, vec4(0.0))) || all(lessThan(xs, vec4(0.0))) || all(greaterThan(ys, vec4(0.0))) ||
             all(lessThan(ys, vec4(0.0))));
}

// The piece [t_in, t_out] cut to [t_min_clip, t_max_clip] as report() cuts it, holds an iso crossing.
bool cull_crosses(float t_in, float t_out, float s_in, float s_out)
{
    if (t_out < t_min_clip || t_in > t_max_clip)
        return false;
    const float len = t_out - t_in;
    float sa = s_in, sb = s_out;
    if (t_in < t_min_clip)
        sa = s_in + (s_out - s_in) * ((t_min_clip - t_in) / len);
    if (t_out > t_max_clip)
        sb = s_in + (s_out - s_in) * ((t_max_clip - t_in) / len);
    bool crosses = false;
    for (int j = 0; j < P.shell_info.y; j++) {
        const float value = P.iso[j];
        crosses = crosses || (sa < value && value <= sb) || (sa > value && value >= sb);
    }
    return crosses;
}

// The leaf's tets whose piece crosses a value and comes after the last piece handed on: the first one in
// (t_in, t_out, tet) order becomes the query's best.
void cull_leaf(uint leaf, inout CullTrace c)
{
    const int first = int(leaf - uint(P.shell_info.z)) * TPK_VK_RANGE_LEAF;
    const int end = min(first + TPK_VK_RANGE_LEAF, P.mode.x);
    for (int tet = first; tet < end; tet++) {
        work++;
        ivec4 q, v;
        vec4 p[4];
        float s[4], t_in, t_out, s_in, s_out;
        if (!cull_candidate(tet, q, p, s) || !cull_piece(q, p, s, t_in, t_out, s_in, s_out, v) ||
            !cull_crosses(t_in, t_out, s_in, s_out))
            continue;
        const bool after = t_in > c.t_prev ||
                           (t_in == c.t_prev && (t_out > c.t_out_prev || (t_out == c.t_out_prev && tet > c.tet_prev)));
        const bool better = c.best < 0 || t_in < c.best_in ||
                            (t_in == c.best_in && (t_out < c.best_out || (t_out == c.best_out && tet < c.best)));
        if (after && better) {
            c.best = tet;
            c.best_in = t_in;
            c.best_out = t_out;
        }
    }
}

CullTrace cull_start()
{
    CullTrace c;
    c.t_prev = c.t_out_prev = -INF;
    c.tet_prev = -1;
    c.node = 1u;
    c.from = 0u;
    c.trail = 0u;
    c.best = -1;
    c.best_in = c.best_out = INF;
    c.in_query = false;
    c.have_piece = false;
    return c;
}

// One node of the query, whose box the ray meets: a leaf's tets tested, or the children's boxes tested
// and the one the ray enters first entered (the left on a tie); coming up from the first child, the
// other one tested again (the best piece may have moved closer) and entered, else further up. Returns
// false when the query is over.
bool cull_query_step(inout CullTrace c)
{
    const float margin = P.up.w; // boxes against float t: the box padding again
    const float t_low = max(c.t_prev, t_min_clip) - margin;
    const float t_high = min(t_max_clip, c.best >= 0 ? c.best_in : INF) + margin;
    const uint n = c.node, leaf_base = uint(P.shell_info.z), depth_bit = 1u << uint(findMSB(n));
    bool up = true;
    if (c.from == 0u) {
        if (n >= leaf_base)
            cull_leaf(n, c);
        else {
            const float t0 = cull_node_enter(2u * n, t_low, t_high), t1 = cull_node_enter(2u * n + 1u, t_low, t_high);
            if (min(t0, t1) != INF) {
                const bool right = t1 < t0;
                c.trail = right ? c.trail | depth_bit : c.trail & ~depth_bit;
                c.node = right ? 2u * n + 1u : 2u * n;
                up = false;
            }
        }
    } else if (((c.from & 1u) != 0u) == ((c.trail & depth_bit) != 0u)) { // came up from the first child
        const uint other = c.from ^ 1u;
        if (cull_node_enter(other, t_low, t_high) != INF) {
            c.node = other;
            c.from = 0u;
            up = false;
        }
    }
    if (up) {
        c.from = n;
        c.node = n >> 1;
    }
    return c.node != 0u;
}

// The ray's pieces from where c stands, each to report(). Returns false when paused (casts asked, or a
// sliced ray out of work: call again), true when the ray is done.
bool cull_trace(inout CullTrace c)
{
    bool paused = false;
    for (;;) {
        if (SLICED && work >= TPK_VK_SLICE_WORK) {
            paused = true;
            break;
        }
        if (c.have_piece) {
            ivec4 q, v;
            vec4 p[4];
            float s[4], t_in, t_out, s_in, s_out;
            q = fetch_range_tets(uint(c.best)); // cull_candidate's work, not counted again
            for (int i = 0; i < 4; i++)
                p[i] = project(q[i], s[i]);
            cull_piece(q, p, s, t_in, t_out, s_in, s_out, v);
            const int said = report(t_in, t_out, s_in, s_out, v);
            if (said == MARCH_PAUSE) {
                paused = true;
                break;
            }
            c.have_piece = false;
            c.t_prev = t_in;
            c.t_out_prev = t_out;
            c.tet_prev = c.best;
            if (said == MARCH_STOP)
                break;
            continue;
        }
        work++;
        if (!c.in_query) { // the root first (node 0: the ray misses it, the query is over)
            c.in_query = true;
            c.from = 0u;
            c.best = -1;
            c.node = cull_node_enter(1u, max(c.t_prev, t_min_clip) - P.up.w, t_max_clip + P.up.w) != INF ? 1u : 0u;
            if (c.node != 0u)
                continue;
        }
        if (c.node != 0u && cull_query_step(c))
            continue;
        c.in_query = false;
        if (c.best < 0)
            break; // no piece left
        c.have_piece = true;
    }
    return !paused;
}

// ---- The pixel ----------------------------------------------------------------------------------

uint to_byte(float v)
{
    return uint(clamp(v, 0.0, 1.0) * 255.0 + 0.5);
}

// The workgroup's statistics (vk_layout.h, TPK_VK_COUNT_*), summed in shared memory before one atomic
// per word goes to the counters buffer: no per-pixel statistics leave the device.
shared uint group_counts[TPK_VK_COUNT_WORDS];

// 64-bit add of v to words [at, at + 1] of the group's sums: the carry of the low word goes to the high.
void group_add64(int at, uint v)
{
    uint old = atomicAdd(group_counts[at], v);
    if (old + v < old)
        atomicAdd(group_counts[at + 1], 1u);
}

void counters_add64(int at)
{
    uint lo = group_counts[at], hi = group_counts[at + 1];
    uint old = atomicAdd(counters[at], lo);
    hi += old + lo < old ? 1u : 0u;
    if (hi != 0u)
        atomicAdd(counters[at + 1], hi);
}

// ---- Slices: a ray's state between dispatches (SLICED) ----------------------------------------------

#define STATE_IN_RUN 1
#define STATE_CAST_DONE 2
#define STATE_HAVE_PREV 4
#define STATE_CASTS_READY 8
#define STATE_FINISHED 16

vec4 ibits(int a, int b, int c, int d)
{
    return intBitsToFloat(ivec4(a, b, c, d));
}

void save_state(uint index, MarchTrace ray, int k, int rays, int flags)
{
    const uint at = index * uint(TPK_VK_STATE_VEC4);
    const MarchRun m = ray.run;
    state[at + 0u] = ibits(m.h.v.x, m.h.v.y, m.h.v.z, m.tet);
    state[at + 1u] = m.h.p0;
    state[at + 2u] = m.h.p1;
    state[at + 3u] = m.h.p2;
    state[at + 4u] = vec4(m.h.e, m.h.t);
    state[at + 5u] = vec4(m.h.s, m.s_in);
    state[at + 6u] = ibits(m.prev, m.step, ray.face_prev,
                           flags | (ray.in_run ? STATE_IN_RUN : 0) | (cast_done ? STATE_CAST_DONE : 0) |
                               (have_prev ? STATE_HAVE_PREV : 0) | (casts_ready ? STATE_CASTS_READY : 0));
    state[at + 7u] = vec4(ray.t_prev, ray.t_low, ray.tmax, run_exit_t);
    state[at + 8u] = vec4(color, transmittance);
    state[at + 9u] = ibits(int(steps_taken), int(secondary_rays), int(status), k);
    state[at + 10u] = ibits(rays, cast_asked, cast_next, 0);
    state[at + 11u] = vec4(t_cast, shade_s, shade_a, prev_t_out);
    state[at + 12u] = vec4(prev_s, t_min_clip, t_max_clip, span_done);
    for (int i = 0; i < MAX_CASTS; i++) {
        const uint c = at + 13u + 3u * uint(i);
        state[c] = vec4(cast_x[i], cast_has_n[i] ? 1.0 : 0.0);
        state[c + 1u] = vec4(cast_n[i], cast_S[i]);
        state[c + 2u] = vec4(cast_A[i], uintBitsToFloat(cast_rays_of[i]), uintBitsToFloat(cast_steps_of[i]), 0.0);
    }
}

// CULL: the range query in slots 0..2 (save_state's MarchRun slots, which a culled ray does not use).
void save_cull(uint index, CullTrace c)
{
    const uint at = index * uint(TPK_VK_STATE_VEC4);
    state[at + 0u] = vec4(c.t_prev, c.t_out_prev, c.best_in, c.best_out);
    state[at + 1u] = ibits(c.tet_prev, int(c.node), int(c.from), c.best);
    state[at + 2u] = ibits((c.in_query ? 1 : 0) | (c.have_piece ? 2 : 0), int(c.trail), 0, 0);
}

CullTrace load_cull(uint index)
{
    const uint at = index * uint(TPK_VK_STATE_VEC4);
    const vec4 w0 = state[at + 0u];
    const ivec4 w1 = floatBitsToInt(state[at + 1u]), w2 = floatBitsToInt(state[at + 2u]);
    CullTrace c;
    c.t_prev = w0.x;
    c.t_out_prev = w0.y;
    c.best_in = w0.z;
    c.best_out = w0.w;
    c.tet_prev = w1.x;
    c.node = uint(w1.y);
    c.from = uint(w1.z);
    c.best = w1.w;
    c.in_query = (w2.x & 1) != 0;
    c.have_piece = (w2.x & 2) != 0;
    c.trail = uint(w2.y);
    return c;
}

// The ray as the last slice left it; false when it finished in an earlier slice.
bool load_state(uint index, out MarchTrace ray, out int k, out int rays)
{
    const uint at = index * uint(TPK_VK_STATE_VEC4);
    const ivec4 w0 = floatBitsToInt(state[at + 0u]), w6 = floatBitsToInt(state[at + 6u]),
                w9 = floatBitsToInt(state[at + 9u]), w10 = floatBitsToInt(state[at + 10u]);
    const vec4 w4 = state[at + 4u], w5 = state[at + 5u], w7 = state[at + 7u], w8 = state[at + 8u],
               w11 = state[at + 11u], w12 = state[at + 12u];
    ray.run.h = Hit(w0.xyz, state[at + 1u], state[at + 2u], state[at + 3u], w4.xyz, w5.xyz, w4.w);
    ray.run.tet = w0.w;
    ray.run.s_in = w5.w;
    ray.run.prev = w6.x;
    ray.run.step = w6.y;
    ray.face_prev = w6.z;
    ray.in_run = (w6.w & STATE_IN_RUN) != 0;
    cast_done = (w6.w & STATE_CAST_DONE) != 0;
    have_prev = (w6.w & STATE_HAVE_PREV) != 0;
    casts_ready = (w6.w & STATE_CASTS_READY) != 0;
    ray.t_prev = w7.x;
    ray.t_low = w7.y;
    ray.tmax = w7.z;
    run_exit_t = w7.w;
    color = w8.xyz;
    transmittance = w8.w;
    steps_taken = uint(w9.x);
    secondary_rays = uint(w9.y);
    status = uint(w9.z);
    k = w9.w;
    rays = w10.x;
    cast_asked = w10.y;
    cast_next = w10.z;
    t_cast = w11.x;
    shade_s = w11.y;
    shade_a = w11.z;
    prev_t_out = w11.w;
    prev_s = w12.x;
    t_min_clip = w12.y;
    t_max_clip = w12.z;
    span_done = w12.w;
    for (int i = 0; i < MAX_CASTS; i++) {
        const uint c = at + 13u + 3u * uint(i);
        const vec4 c0 = state[c], c1 = state[c + 1u], c2 = state[c + 2u];
        cast_x[i] = c0.xyz;
        cast_has_n[i] = c0.w != 0.0;
        cast_n[i] = c1.xyz;
        cast_S[i] = c1.w;
        cast_A[i] = c2.x;
        cast_rays_of[i] = floatBitsToUint(c2.y);
        cast_steps_of[i] = floatBitsToUint(c2.z);
    }
    return (w6.w & STATE_FINISHED) == 0;
}

void main()
{
    if (gl_LocalInvocationIndex == 0u) {
        for (int i = 0; i < TPK_VK_COUNT_WORDS; i++)
            group_counts[i] = 0u;
        group_counts[TPK_VK_COUNT_FIRST] = 0xffffffffu;
    }
    tf_to_shared(); // its barrier also publishes group_counts' zeros
    const int x = int(gl_GlobalInvocationID.x), y = P.dims.z + int(gl_GlobalInvocationID.y);
    pixel = ivec2(x, y);
    // every invocation reaches the barrier below, so pixels outside the image do no work but return late
    if (x < P.dims.x && y < P.cast_count.y) {
        const float px = (2.0 * (float(x) + 0.5) / float(P.dims.x) - 1.0) * P.forward.w;
        const float py = (1.0 - 2.0 * (float(y) + 0.5) / float(P.dims.y)) * P.right.w;
        ray_dir = normalize(P.forward.xyz + px * P.right.xyz + py * P.up.xyz);
        inv_dir = 1.0 / ray_dir;
        const uint index = gl_GlobalInvocationID.y * uint(P.dims.x) + uint(x); // within this band of rows
        MarchTrace ray;
        CullTrace culled; // CULL: the primary ray's pieces from the range BVH instead
        int k = 0, rays = 0; // the secondary rays of the casts asked: the next, and how many
        bool done = true, live = true;
        if (!SLICED || P.cast_count.z == 0) {
            color = vec3(0.0);
            transmittance = 1.0;
            steps_taken = 0u;
            status = TPK_VK_STATUS_OK;
            span_done = -INF;
            if (frame_init(P.eye.xyz, ray_dir) && primary_range()) {
                if (CULL)
                    culled = cull_start();
                else
                    ray = trace_start(t_min_clip, t_max_clip);
                done = false;
            }
        } else {
            live = load_state(index, ray, k, rays);
            if (CULL)
                culled = load_cull(index);
            done = !live;
            if (live && P.probe_info.x > 0)
                primary_range(); // the spans the first slice made (the same arithmetic, the same floats)
            frame_init(P.eye.xyz, ray_dir); // the primary ray's frame, as the first slice made it
        }
        // One loop, so that a secondary ray runs at the top level, not inside the primary march
        // (march_run.glsl), and a sliced ray stops between two steps of it.
        while (!done && !(SLICED && work >= TPK_VK_SLICE_WORK)) {
            if (k < rays) {
                cast_one(k);
                k++;
                if (k == rays)
                    casts_cast();
            } else {
                done = CULL ? cull_trace(culled) : trace(ray); // false: paused for casts, or (sliced) out of work
                k = 0;
                rays = !done && cast_asked > 0 ? cast_ray_count() : 0;
                if (!done && cast_asked > 0 && rays == 0)
                    casts_cast(); // no secondary rays to cast (an AO of no rays): S = A = 1
            }
        }
        if (!done) {
            save_state(index, ray, k, rays, 0);
            if (CULL)
                save_cull(index, culled);
            atomicAdd(counters[TPK_VK_COUNT_PENDING], 1u);
        } else if (live) {
            if (SLICED)
                state[index * uint(TPK_VK_STATE_VEC4) + 6u].w = intBitsToFloat(STATE_FINISHED);
            const vec4 bg = P.background;
            float alpha = (1.0 - transmittance) + transmittance * bg.a;
            vec3 premult = color + transmittance * bg.a * bg.rgb;
            vec3 straight = alpha > 0.0 ? premult / alpha : vec3(0.0);
            pixels[index] = to_byte(straight.r) | (to_byte(straight.g) << 8) | (to_byte(straight.b) << 16) |
                            (to_byte(alpha) << 24);
            group_add64(TPK_VK_COUNT_STEPS, steps_taken);
            group_add64(TPK_VK_COUNT_SECONDARY, secondary_rays);
            if (status != TPK_VK_STATUS_OK) {
                atomicAdd(group_counts[TPK_VK_COUNT_FAILED], 1u);
                atomicMin(group_counts[TPK_VK_COUNT_FIRST], index);
            }
        }
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        counters_add64(TPK_VK_COUNT_STEPS);
        counters_add64(TPK_VK_COUNT_SECONDARY);
        if (group_counts[TPK_VK_COUNT_FAILED] != 0u) {
            atomicAdd(counters[TPK_VK_COUNT_FAILED], group_counts[TPK_VK_COUNT_FAILED]);
            atomicMin(counters[TPK_VK_COUNT_FIRST], group_counts[TPK_VK_COUNT_FIRST]);
        }
    }
}
