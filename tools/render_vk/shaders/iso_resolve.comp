#version 450
// The compute rasterizer's resolve (tools/render_vk/vk_vis.c): each pixel of the visibility buffer
// (iso_vis.comp) shaded from its triangle as shaders/iso_raster.frag shades a fragment: the TF at the
// value, times 0.3 + 0.7 |n . l| with shading, n the triangle's plane normal, l toward the light from the
// point where the pixel's ray meets the triangle's plane. Run once per value: a dispatch writes the pixels
// whose triangle is among its value's, and the first value's also the empty ones (the background).
// Colours go out as packed RGBA8 (byte 0 red), rounded as the graphics path's UNORM attachment.
layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push {
    vec4 eye;        // xyz: the eye relative to the mesh's origin
    vec4 forward;    // xyz
    vec4 right;      // xyz; w: tan_half_x
    vec4 up;         // xyz; w: tan_half_y
    vec4 light;      // xyz: the light relative to the origin; w: 1 with shading
    vec4 color;      // rgb: the TF at the value
    vec4 background; // premultiplied, as the graphics path's clear colour
    uvec4 frame;     // width, height, the id of this value's first triangle, its triangle count
} pc;

layout(std430, binding = 0) readonly buffer Corners { float corners[]; };
layout(std430, binding = 1) readonly buffer Vis { uint vis[]; }; // per pixel: id, depth key
layout(std430, binding = 4) writeonly buffer Image { uint rgba[]; };

vec3 corner(uint i)
{
    return vec3(corners[3u * i], corners[3u * i + 1u], corners[3u * i + 2u]);
}

void main()
{
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= pc.frame.x || px.y >= pc.frame.y)
        return;
    uint p = px.y * pc.frame.x + px.x, id = vis[2u * p];
    if (id == 0xffffffffu) {
        if (pc.frame.z == 0u)
            rgba[p] = packUnorm4x8(pc.background);
        return;
    }
    uint t = id - pc.frame.z;
    if (t >= pc.frame.w)
        return; // another value's
    vec3 p0 = corner(3u * t), p1 = corner(3u * t + 1u), p2 = corner(3u * t + 2u);
    vec3 n = cross(p1 - p0, p2 - p0);
    vec3 normal = length(n) > 0.0 ? normalize(n) : vec3(0.0);
    vec2 ndc = (vec2(px) + 0.5) / vec2(pc.frame.xy) * 2.0 - 1.0;
    vec3 dir = pc.forward.xyz + ndc.x * pc.right.w * pc.right.xyz - ndc.y * pc.up.w * pc.up.xyz;
    float den = dot(dir, normal);
    vec3 world = den != 0.0 ? pc.eye.xyz + dot(p0 - pc.eye.xyz, normal) / den * dir : p0;
    float m = 1.0;
    vec3 to_light = pc.light.xyz - world;
    float len = length(to_light);
    if (pc.light.w > 0.5 && len > 0.0 && length(normal) > 0.0)
        m = 0.3 + 0.7 * abs(dot(normal, to_light / len));
    rgba[p] = packUnorm4x8(vec4(clamp(pc.color.rgb * m, 0.0, 1.0), 1.0));
}
