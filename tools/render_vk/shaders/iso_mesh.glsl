// What the mesh-shader isosurface path (iso_mesh.task, iso_mesh.mesh; tools/render_vk/vk_raster.c) shares:
// its push constants, its buffers and the tet's marching case. The push constants begin with
// iso_raster.frag's block (the camera, light, colour and clip box of one value), so one fragment shader
// serves both paths; the rest say which clusters of 32 tets (file order) this draw covers.
// MESH_TETS (a divisor of 32): the live tets one mesh workgroup takes, so that it declares at most
// 6 MESH_TETS vertices and 2 MESH_TETS triangles; a task launches as many as its cluster needs. 8, not
// 32: faster on an H200 at both sizes measured (bench/README, "Figures behind code comments").
#define MESH_TETS 8
layout(push_constant) uniform Push {
    vec4 eye;       // xyz: the eye relative to the origin; w: the near distance
    vec4 forward;   // xyz
    vec4 right;     // xyz; w: tan_half_x
    vec4 up;        // xyz; w: tan_half_y
    vec4 light;     // (fragment shader)
    vec4 color;     // (fragment shader)
    vec4 clip_lo;   // (fragment shader)
    vec4 clip_hi;   // (fragment shader)
    float threshold; // the smallest float >= the value: a float s is at or above the value when s >= it
    float value;     // the value rounded to float, for the positions (as iso.comp)
    uint tet_count;
    uint base;       // the first cluster of this draw (a draw covers at most the device's task group count)
} pc;

layout(std430, binding = 0) readonly buffer Tets { ivec4 tets[]; };
layout(std430, binding = 1) readonly buffer Scalars { float scalars[]; };
layout(std430, binding = 2) readonly buffer Positions { float positions[]; };
layout(std430, binding = 3) readonly buffer Cases { int cases[]; }; // 16 x (count, 6 edges, 1 unused)
layout(std430, binding = 4) readonly buffer Ranges { vec2 ranges[]; }; // per cluster: min, max corner value

// A task's hand-over to its mesh shader: the cluster's tets that have triangles, in tet order, and
// where each one's triangles start among the cluster's.
struct Task {
    uint count;     // tets with triangles
    uint triangles; // their triangles
    uint tets[32];
    uint first[32];
};

// The case of tet t (bit k: corner k at or above the value), -1 when a corner's value is NaN: iso.comp's.
int tet_case(uint t)
{
    ivec4 v = tets[t];
    int mask = 0;
    for (int k = 0; k < 4; k++) {
        float s = scalars[v[k]];
        if (isnan(s))
            return -1;
        if (s >= pc.threshold)
            mask |= 1 << k;
    }
    return mask;
}
