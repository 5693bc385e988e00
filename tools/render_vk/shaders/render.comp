// The Vulkan renderer's compute shader: one invocation per pixel. Finds the ray's shell entries in
// order with the shell BVH, marches tets through neighbor links with watertight face tests, and
// integrates emission-absorption per tet piece exactly as tools/render/render_cpu.c does. The marcher
// follows libtetpack/march.c, ray.c and shell_bvh.c step for step (same entry order, same exit-face
// rule, same tie-breaks), in float instead of double. Watertightness does not need double: every edge
// decision is a deterministic function of its two vertex ids and their projections (computed by one
// `precise` function, so no call site fuses differently), evaluated in the canonical (lower id first)
// order, with an exact sign (Dekker products) on the slow path.
//
// The parts, included in this order, each mirroring its CPU twin: frame.glsl (ray frame, edge test),
// shell_bvh.glsl, transfer_function.glsl (TF, emission-absorption), probes.glsl (clip box, probes),
// march.glsl (run state), effects.glsl (normals, lighting, iso crossings), occlusion.glsl (shadow and
// AO rays, shade points), primary.glsl (a primary ray's pieces and march), culling.glsl (iso-only
// rays), slices.glsl (state between dispatches). march_run.glsl, the run loop, is included twice (by
// occlusion.glsl and primary.glsl): GLSL has no function pointers, and one copy that branches on the
// kind of ray would change the code every ray runs.
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
// --occlusion surface: one cast per ray, at its first iso hit or first volume shade point (render.h
// OCCLUSION AT THE SURFACE); set only with CAST (tpk_vk_effects)
const bool SURFACE_OCC = (EFFECTS & TPK_VK_EFFECT_SURFACE) != 0;
// not a frame: the vertex cache's casts on the device (vertex_cast below)
const bool CACHE_CAST = (EFFECTS & TPK_VK_EFFECT_CACHE) != 0;
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
    ivec4 mode;      // x: tet count, y: vertex count, z: TPK_VK_INTEGRATION (0 exact, 1 sampled, 2 midpoint),
                     // w: scalars (0 none, 1 per point, 2 per tet)
    vec4 clip_lo;    // xyz: clip box (relative to the origin); w: 1 when clipping
    vec4 clip_hi;
    ivec4 shell_info; // x: shell face count, y: iso value count, z: CULL: the range BVH's first leaf node
    vec4 iso;         // iso values (scalar units)
    vec4 light;       // xyz: point light (relative to the origin; the eye without one); w: TPK_VK_ISO_OPACITY
    vec4 cast_info;   // x: TPK_VK_AO_RADIUS, y: TPK_RENDER_SELF_EPS * unit distance, z: unit distance
    ivec4 cast_count; // x: TPK_VK_AO_RAYS; y: the row after this dispatch's rows (a band need not be whole groups);
                      // z: the slice (SLICED: 0 starts the band's rays, later ones resume them)
    ivec4 probe_info;   // x: probe count; y: bit i set when probe i cuts
    vec4 probe_a[TPK_VK_MAX_PROBES]; // xyz: center, point or min (relative to the origin); w: shape
    vec4 probe_b[TPK_VK_MAX_PROBES]; // xyz: the plane's normal or the box's max; w: the sphere's radius
    vec4 tf_s[TPK_VK_TF_MAX / 4];
    vec4 tf_rgba[TPK_VK_TF_MAX];
} P;
// TPK_VK_<ID>: where Params holds an option of render/render_options.def (generated at build time).
#include "render_options.glsl"

layout(std430, set = 0, binding = TPK_VK_BIND_PIXELS) writeonly buffer Pixels { uint pixels[]; };
layout(std430, set = 0, binding = TPK_VK_BIND_COUNTERS) buffer Counters { uint counters[TPK_VK_COUNT_WORDS]; };
layout(std430, set = 0, binding = TPK_VK_BIND_STATE) buffer State { vec4 state[]; }; // sliced: rays between slices

uint work = 0u; // this dispatch's iterations of the loops that can run long (sliced: TPK_VK_SLICE_WORK)

// Split texel arrays: TPK_VK_MAX_PARTS bindings each; with one part the switch folds away. The module
// built with TPK_VK_ONE_PART 1 (every array in one part) has no switch at all: specialization folds it
// only after a driver has inlined each fetch's eight cases at every call site, a large share of the
// compile on lavapipe (bench/README, figures behind code comments).
#define DECLARE_ARRAY(SAMPLER, NAME, ARRAY)                                                   \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 0) uniform SAMPLER NAME##0;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 1) uniform SAMPLER NAME##1;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 2) uniform SAMPLER NAME##2;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 3) uniform SAMPLER NAME##3;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 4) uniform SAMPLER NAME##4;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 5) uniform SAMPLER NAME##5;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 6) uniform SAMPLER NAME##6;         \
    layout(set = 0, binding = TPK_VK_BIND_ARRAY(ARRAY) + 7) uniform SAMPLER NAME##7;

#if TPK_VK_ONE_PART
#define FETCH_FUNCTION(RET, NAME, PARTS, SHIFT)                                               \
    RET fetch_##NAME(uint i)                                                                  \
    {                                                                                         \
        return texelFetch(NAME##0, int(i));                                                   \
    }
#else
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
#endif

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

#include "frame.glsl"
#include "shell_bvh.glsl"
#include "transfer_function.glsl"
#include "probes.glsl"
#include "march.glsl"
#include "effects.glsl"
#include "occlusion.glsl"
#include "primary.glsl"
#include "culling.glsl"

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

#include "slices.glsl"

// CACHE_CAST (vk_layout.h TPK_VK_EFFECT_CACHE): S_v and A_v of one vertex (render.h OCCLUSION AT VERTICES,
// render_light.c's cache_vertex) by the frame's casts of one shade point at the vertex, in slices as a
// pixel's; written as float bits to words 2i and 2i + 1 of the band, i its place there.
void vertex_cast(int x, int y)
{
    const int per_row = P.dims.x / 2;
    cache_v = uint(y) * uint(per_row) + uint(x);
    if (x >= per_row || y >= P.cast_count.y || cache_v >= uint(P.mode.y))
        return;
    const uint slot = gl_GlobalInvocationID.y * uint(P.dims.x) + uint(x); // its state between slices
    MarchTrace none; // no primary ray
    int k = 0, rays = 0;
    if (!SLICED || P.cast_count.z == 0) {
        steps_taken = 0u;
        secondary_rays = 0u;
        status = TPK_VK_STATUS_OK;
        cast_asked = 0;
        ask_cast(fetch_verts(cache_v).xyz, false, vec3(0.0));
        rays = cast_ray_count();
    } else if (!load_state(slot, none, k, rays)) {
        return;
    }
    while (k < rays && !(SLICED && work >= TPK_VK_SLICE_WORK)) {
        cast_one(k);
        k++;
    }
    if (k < rays) {
        save_state(slot, none, k, rays, 0);
        atomicAdd(counters[TPK_VK_COUNT_PENDING], 1u);
        return;
    }
    if (SLICED)
        state[slot * uint(TPK_VK_STATE_VEC4) + 6u].w = intBitsToFloat(STATE_FINISHED);
    float S = 1.0, A = 1.0;
    if (rays > 0) {
        casts_cast();
        take_cast(S, A);
    }
    const uint word = gl_GlobalInvocationID.y * uint(P.dims.x) + 2u * uint(x);
    pixels[word] = floatBitsToUint(S);
    pixels[word + 1u] = floatBitsToUint(A);
    group_add64(TPK_VK_COUNT_STEPS, steps_taken);
    group_add64(TPK_VK_COUNT_SECONDARY, secondary_rays);
    if (status != TPK_VK_STATUS_OK) {
        atomicAdd(group_counts[TPK_VK_COUNT_FAILED], 1u);
        atomicMin(group_counts[TPK_VK_COUNT_FIRST], cache_v);
    }
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
    if (CACHE_CAST) {
        vertex_cast(x, y);
    } else if (x < P.dims.x && y < P.cast_count.y) {
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
