#version 450
// The colour of an isosurface point as the marcher composites an opaque iso hit (render.h: ISOSURFACES,
// LIGHTING FACTOR without shadows or AO): the TF at the value, times 0.3 + 0.7 |n . l| with shading.
layout(push_constant) uniform Push {
    vec4 eye;
    vec4 forward;
    vec4 right;
    vec4 up;
    vec4 light;
    vec4 color;
    vec4 clip_lo;
    vec4 clip_hi;
} pc;

layout(location = 0) in vec3 world;
layout(location = 1) flat in vec3 normal;
layout(location = 0) out vec4 out_color;

void main()
{
    if (pc.clip_lo.w > 0.5 && (any(lessThan(world, pc.clip_lo.xyz)) || any(greaterThan(world, pc.clip_hi.xyz))))
        discard;
    float m = 1.0;
    vec3 to_light = pc.light.xyz - world;
    float len = length(to_light);
    if (pc.light.w > 0.5 && len > 0.0 && length(normal) > 0.0)
        m = 0.3 + 0.7 * abs(dot(normal, to_light / len));
    out_color = vec4(clamp(pc.color.rgb * m, 0.0, 1.0), 1.0);
}
