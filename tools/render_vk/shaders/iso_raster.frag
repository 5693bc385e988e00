#version 450
// The colour of an isosurface point as the marcher composites an opaque iso hit (render.h: ISOSURFACES,
// LIGHTING FACTOR without shadows or AO): the TF at the value, times 0.3 + 0.7 |n . l| with shading.
// A point the clip box or the probes (render.h: PROBES) leave out is discarded, so the depth test shows
// the next surface behind it, as a ray that passes the cut part reaches it.
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

// The probes (tpk_probe, relative to the mesh's origin): kind = (shape: 1 sphere, 2 half-space, 3 box;
// cut; 0; 0), a = (centre, point on the plane or box corner; radius), b = (the plane's normal or the
// box's other corner; 0). Binding 5 in both paths' descriptor sets.
layout(std430, set = 0, binding = 5) readonly buffer Probes {
    ivec4 probe_count; // x
    ivec4 kind[4];
    vec4 a[4];
    vec4 b[4];
} probes;

layout(location = 0) in vec3 world;
layout(location = 1) flat in vec3 normal;
layout(location = 0) out vec4 out_color;

// tpk_probe_keeps: every probe keeps x (inside a keep probe, outside a cut probe).
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

void main()
{
    if (pc.clip_lo.w > 0.5 && (any(lessThan(world, pc.clip_lo.xyz)) || any(greaterThan(world, pc.clip_hi.xyz))))
        discard;
    if (!probes_keep(world))
        discard;
    float m = 1.0;
    vec3 to_light = pc.light.xyz - world;
    float len = length(to_light);
    if (pc.light.w > 0.5 && len > 0.0 && length(normal) > 0.0)
        m = 0.3 + 0.7 * abs(dot(normal, to_light / len));
    out_color = vec4(clamp(pc.color.rgb * m, 0.0, 1.0), 1.0);
}
