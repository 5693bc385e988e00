// Part of render.comp, included once, in the order it lists.
// A ray's state between dispatches (SLICED; vk_layout.h Slices).

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
