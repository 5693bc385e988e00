#version 450
// Isosurface triangles rasterized in compute into a visibility buffer (render --iso-raster-path compute,
// tools/render_vk/vk_vis.c): per pixel the nearest triangle's depth and id, packed into 64 bits (high: the
// depth key, low: the id), so that one atomicMin keeps the nearest, and of equal depths the first
// triangle, as the graphics path's depth test (GREATER) keeps the first drawn. iso_resolve.comp then
// shades each pixel from its triangle.
// Built twice: TPK_VIS64=1 with 64-bit buffer atomics (shaderBufferInt64Atomics), TPK_VIS64=0 with 32-bit
// ones only, in two passes over the triangles (pass.x 0: atomicMin of the depth key; 1: where a pixel's
// depth key is the triangle's own, atomicMin of the id). The buffer is the same: words 2p (id) and
// 2p + 1 (depth key) of pixel p, all ones where nothing was drawn.
// The picture is the graphics path's (shaders/iso_raster.vert): the same projection, pixel centres,
// depth near / d interpolated linearly in screen space, triangles clipped at the near distance, a
// top-left fill rule whose edge functions are evaluated alike for both triangles of a shared edge (so
// no pixel of a closed surface is missed or hit twice), and the clip box and probes cutting the
// surface per pixel (the fragment shader's discard).
// One invocation per triangle (mode 0); a triangle whose box covers more than LARGE pixels is put in a
// list instead, and mode 1 rasterizes the list with a workgroup of 64 per triangle, each invocation
// pixel of each 8 x 8 tile of its box, so that no invocation walks a huge box alone.
#if TPK_VIS64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#endif
layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    vec4 eye;      // xyz: the eye relative to the mesh's origin; w: the near distance
    vec4 forward;  // xyz
    vec4 right;    // xyz; w: tan_half_x
    vec4 up;       // xyz; w: tan_half_y
    vec4 clip_lo;  // xyz; w: 1 with a clip box
    vec4 clip_hi;  // xyz
    uvec4 frame;   // width, height, the id of this value's first triangle, its triangle count
    uvec4 pass;    // x: 0 depth, 1 id (TPK_VIS64=0 only); y: first triangle of this dispatch; z: mode
} pc;

layout(std430, binding = 0) readonly buffer Corners { float corners[]; }; // 3 floats per corner
#if TPK_VIS64
layout(std430, binding = 1) buffer Vis { uint64_t vis[]; };
#else
layout(std430, binding = 1) buffer Vis { uint vis[]; };
#endif
layout(std430, binding = 2) buffer Large { uint large[]; }; // [0]: count, then the triangles
// tpk_probe_keeps' probes, as shaders/iso_raster.frag reads them
layout(std430, binding = 3) readonly buffer Probes {
    ivec4 probe_count; // x
    ivec4 kind[4];
    vec4 a[4];
    vec4 b[4];
} probes;

const uint LARGE = 256u; // pixels in a triangle's box above which mode 1 draws it

bool probes_keep(vec3 x)
{
    for (int i = 0; i < probes.probe_count.x; i++) {
        vec3 a = probes.a[i].xyz, b = probes.b[i].xyz;
        bool inside;
        if (probes.kind[i].x == 1)
            inside = dot(x - a, x - a) <= probes.a[i].w * probes.a[i].w;
        else if (probes.kind[i].x == 2)
            inside = dot(x - a, b) <= 0.0;
        else
            inside = all(greaterThanEqual(x, a)) && all(lessThanEqual(x, b));
        if (inside == (probes.kind[i].y != 0))
            return false;
    }
    return true;
}

bool kept(vec3 world)
{
    if (pc.clip_lo.w > 0.5 && (any(lessThan(world, pc.clip_lo.xyz)) || any(greaterThan(world, pc.clip_hi.xyz))))
        return false;
    return probes_keep(world);
}

void write_pixel(uint p, float z, uint id)
{
    uint key = ~floatBitsToUint(z); // z > 0: nearer, larger z, smaller key
#if TPK_VIS64
    atomicMin(vis[p], uint64_t(key) << 32 | uint64_t(id));
#else
    if (pc.pass.x == 0u)
        atomicMin(vis[2u * p + 1u], key);
    else if (vis[2u * p + 1u] == key)
        atomicMin(vis[2u * p], id);
#endif
}

// The edge function of the edge from u along d at p: the same bits for both triangles of a shared edge,
// since both order its ends alike (u the lesser by x, then y).
float edge(vec2 u, vec2 d, vec2 p)
{
    precise float e = d.x * (p.y - u.y) - d.y * (p.x - u.x);
    return e;
}

// A screen triangle ready to test pixels against: per edge (k: the one opposite corner k) its lesser end
// u, its direction d, the side its triangle lies on (sigma) and whether a centre on it is the triangle's.
struct Setup {
    vec2 u[3], d[3];
    float sigma[3];
    bool own[3];
    vec3 z;    // the corners' depths
    vec3 w[3]; // the corners in the world, for the clip box and probes
    uint id;
    bool cut;  // a clip box or probes
};

void pixel(Setup t, uint px, uint py)
{
    vec2 c = vec2(float(px) + 0.5, float(py) + 0.5);
    vec3 e;
    for (int k = 0; k < 3; k++) {
        float v = t.sigma[k] * edge(t.u[k], t.d[k], c);
        if (!(v > 0.0 || (v == 0.0 && t.own[k])))
            return;
        e[k] = v;
    }
    e /= e.x + e.y + e.z; // screen-space barycentric weights
    float z = dot(e, t.z);
    if (t.cut) { // perspective-correct: weights over depth (z is near / d)
        vec3 q = e * t.z;
        if (!kept((q.x * t.w[0] + q.y * t.w[1] + q.z * t.w[2]) / (q.x + q.y + q.z)))
            return;
    }
    write_pixel(py * pc.frame.x + px, z, t.id);
}

// The pixels of the screen triangle s (x, y in pixels, z the depth) whose centres it covers: all of its
// box (lanes 1), or with lanes 64 the lane-th pixel of each 8 x 8 tile of the box; w: its corners in
// the world.
void raster(vec3 s[3], vec3 w[3], uint id, uint lane, uint lanes)
{
    Setup t;
    for (int k = 0; k < 3; k++) {
        vec2 a = s[(k + 1) % 3].xy, b = s[(k + 2) % 3].xy;
        bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
        t.u[k] = swap ? b : a;
        t.d[k] = (swap ? a : b) - t.u[k];
        float opposite = edge(t.u[k], t.d[k], s[k].xy);
        if (!(opposite != 0.0))
            return; // no area (or NaN)
        t.sigma[k] = opposite > 0.0 ? 1.0 : -1.0;
        // top-left: a pixel centre on the edge belongs to the triangle right of it (left edge) or below
        // it (top edge, y down); the triangle is on the edge function's positive side when sigma > 0
        t.own[k] = (t.sigma[k] > 0.0) == (t.d[k].y <= 0.0);
        t.w[k] = w[k];
    }
    t.z = vec3(s[0].z, s[1].z, s[2].z);
    t.id = id;
    t.cut = pc.clip_lo.w > 0.5 || probes.probe_count.x > 0;
    float width = float(pc.frame.x), height = float(pc.frame.y);
    vec2 lo = min(min(s[0].xy, s[1].xy), s[2].xy), hi = max(max(s[0].xy, s[1].xy), s[2].xy);
    int x0 = int(clamp(ceil(lo.x - 0.5), 0.0, width)), x1 = int(clamp(floor(hi.x - 0.5), -1.0, width - 1.0));
    int y0 = int(clamp(ceil(lo.y - 0.5), 0.0, height)), y1 = int(clamp(floor(hi.y - 0.5), -1.0, height - 1.0));
    if (x1 < x0 || y1 < y0)
        return;
    if (lanes == 1u) {
        for (int py = y0; py <= y1; py++)
            for (int px = x0; px <= x1; px++)
                pixel(t, uint(px), uint(py));
        return;
    }
    uint tw = uint(x1 - x0 + 8) / 8u, tiles = tw * (uint(y1 - y0 + 8) / 8u);
    for (uint k = 0u; k < tiles; k++) {
        uint px = uint(x0) + k % tw * 8u + lane % 8u, py = uint(y0) + k / tw * 8u + lane / 8u;
        if (px <= uint(x1) && py <= uint(y1))
            pixel(t, px, py);
    }
}

vec3 corner(uint i)
{
    return vec3(corners[3u * i], corners[3u * i + 1u], corners[3u * i + 2u]);
}

// Triangle t of this value: projected as iso_raster.vert does, clipped at the near distance (a triangle
// crossing it becomes up to two), rasterized; with `classify`, a large one is listed for mode 1 instead.
void triangle(uint t, uint lane, uint lanes, bool classify)
{
    float near = pc.eye.w;
    vec3 p[4], c[4]; // world, and clip space (x, y, w = d)
    int behind = 0;
    for (int k = 0; k < 3; k++) {
        p[k] = corner(3u * t + uint(k));
        vec3 q = p[k] - pc.eye.xyz;
        c[k] = vec3(dot(q, pc.right.xyz) / pc.right.w, -dot(q, pc.up.xyz) / pc.up.w, dot(q, pc.forward.xyz));
        behind += c[k].z < near ? 1 : 0;
    }
    if (behind == 3)
        return;
    vec3 wp[4], cp[4];
    int n = 0;
    if (behind == 0) {
        for (int k = 0; k < 3; k++)
            wp[k] = p[k], cp[k] = c[k];
        n = 3;
    } else {
        for (int k = 0; k < 3; k++) {
            int j = (k + 1) % 3;
            bool kin = c[k].z >= near, jin = c[j].z >= near;
            if (kin)
                wp[n] = p[k], cp[n] = c[k], n++;
            if (kin != jin) {
                float f = (near - c[k].z) / (c[j].z - c[k].z);
                wp[n] = mix(p[k], p[j], f), cp[n] = vec3(mix(c[k].xy, c[j].xy, f), near), n++;
            }
        }
    }
    float width = float(pc.frame.x), height = float(pc.frame.y);
    vec3 s[4];
    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    for (int k = 0; k < n; k++) {
        s[k] = vec3((cp[k].x / cp[k].z * 0.5 + 0.5) * width, (cp[k].y / cp[k].z * 0.5 + 0.5) * height, near / cp[k].z);
        lo = min(lo, s[k].xy), hi = max(hi, s[k].xy);
    }
    if (classify) {
        vec2 a = clamp(ceil(lo - 0.5), vec2(0.0), vec2(width, height));
        vec2 b = clamp(floor(hi - 0.5), vec2(-1.0), vec2(width - 1.0, height - 1.0));
        if (b.x >= a.x && b.y >= a.y && (b.x - a.x + 1.0) * (b.y - a.y + 1.0) > float(LARGE)) {
            large[1u + atomicAdd(large[0], 1u)] = t;
            return;
        }
    }
    uint id = pc.frame.z + t;
    raster(vec3[3](s[0], s[1], s[2]), vec3[3](wp[0], wp[1], wp[2]), id, lane, lanes);
    if (n == 4)
        raster(vec3[3](s[0], s[2], s[3]), vec3[3](wp[0], wp[2], wp[3]), id, lane, lanes);
}

void main()
{
    if (pc.pass.z == 0u) {
        uint t = pc.pass.y + gl_GlobalInvocationID.x;
        if (t < pc.frame.w)
            triangle(t, 0u, 1u, true);
    } else {
        uint listed = large[0];
        for (uint k = gl_WorkGroupID.x; k < listed; k += gl_NumWorkGroups.x)
            triangle(large[1u + k], gl_LocalInvocationID.x, 64u, false);
    }
}
