#version 450
// Isosurface triangles drawn directly (render --iso-raster, tools/render_vk/vk_raster.c): the triangle
// list iso.comp emitted (3 float positions per corner, relative to the mesh's origin), projected with
// the renderers' pinhole camera (render.h: camera basis; pixel centres are where the CPU casts its rays).
// The normal of each triangle is its plane's, which in a tet is the field's gradient direction (the
// isosurface of a linear field is a plane normal to the gradient): the marcher's shading normal.
layout(std430, binding = 0) readonly buffer Corners { float corners[]; };

layout(push_constant) uniform Push {
    vec4 eye;      // xyz: the eye relative to the origin; w: the near distance
    vec4 forward;  // xyz
    vec4 right;    // xyz; w: tan_half_x
    vec4 up;       // xyz; w: tan_half_y
    vec4 light;    // xyz: the light relative to the origin; w: 1 with shading
    vec4 color;    // rgb: the TF at the value
    vec4 clip_lo;  // xyz; w: 1 with a clip box
    vec4 clip_hi;
} pc;

layout(location = 0) out vec3 world;
layout(location = 1) flat out vec3 normal;

vec3 corner(uint i)
{
    return vec3(corners[3u * i], corners[3u * i + 1u], corners[3u * i + 2u]);
}

void main()
{
    uint i = uint(gl_VertexIndex);
    uint first = i - i % 3u;
    vec3 p = corner(i);
    vec3 n = cross(corner(first + 1u) - corner(first), corner(first + 2u) - corner(first));
    normal = length(n) > 0.0 ? normalize(n) : vec3(0.0);
    world = p;
    vec3 q = p - pc.eye.xyz;
    float d = dot(q, pc.forward.xyz);
    float x = dot(q, pc.right.xyz) / pc.right.w;
    float y = -dot(q, pc.up.xyz) / pc.up.w;
    // reversed depth (near / d: 1 at the near plane, toward 0 far away) in a float buffer: the same
    // relative precision at every distance
    gl_Position = vec4(x, y, pc.eye.w, d);
}
