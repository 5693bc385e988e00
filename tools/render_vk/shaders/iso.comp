#version 450
// Marching tetrahedra in compute (tools/render_vk/vk_iso.c, `tetpack iso --backend vulkan`): one value at a
// time, in four dispatches that push constant `mode` selects:
//   0 classify   per tet: its case (bit k: corner k at or above the value) and triangle count, and per
//                group of 256 tets the exclusive prefix sum of the counts: counts[t] = offset << 4 | case,
//                groups[group] = the group's total
//   1 groups     one workgroup: the exclusive prefix sum of the group totals, 1024 at a time, and the
//                grand total after them
//   2 emit       per tet with triangles: its triangles' corners as edge keys (a < b) and float
//                positions, from triangle group offset + offset in the group on (the tets without any
//                read 4 bytes and leave)
//   3 draw args  one invocation: the VkDrawIndirectCommand of the triangle list (render --iso-raster)
// The case table comes from the host (tpk_iso_case_table), so the CPU and this shader share one table.
// "At or above" compares the float scalar with `threshold`, the smallest float >= the double value:
// for a float s, s >= value exactly when s >= threshold, so the cases are the CPU's.
layout(local_size_x = 256) in;

layout(push_constant) uniform Push {
    uint mode;
    uint tet_count;
    uint group_count;
    float threshold; // smallest float >= value
    float value;     // the value rounded to float, for the positions
    uint base;       // the first tet (and group * 256) of this dispatch: dispatches are at most 65535 groups
} pc;

layout(std430, binding = 0) readonly buffer Tets { ivec4 tets[]; };
layout(std430, binding = 1) readonly buffer Scalars { float scalars[]; };
layout(std430, binding = 2) readonly buffer Positions { float positions[]; };
layout(std430, binding = 3) readonly buffer Cases { int cases[]; }; // 16 x (count, 6 edges, 1 unused)
layout(std430, binding = 4) buffer Counts { uint counts[]; };       // per tet: count, then first triangle
layout(std430, binding = 5) buffer Groups { uint groups[]; };       // per group: total, then offset; + total
layout(std430, binding = 6) writeonly buffer Keys { uvec2 keys[]; };          // 3 per triangle: (b, a)
layout(std430, binding = 7) writeonly buffer Corners { float corners[]; };    // 3 floats per corner
layout(std430, binding = 8) writeonly buffer DrawArgs { uint draw_args[]; };  // vertexCount, instances, 0, 0

const ivec2 EDGES[6] = ivec2[6](ivec2(0, 1), ivec2(0, 2), ivec2(0, 3), ivec2(1, 2), ivec2(1, 3), ivec2(2, 3));

shared uint scan[256];

// The case of tet t, -1 when a corner's value is NaN.
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

// Hillis-Steele inclusive scan of scan[0..255] in place (every invocation of the group calls it).
void scan_group(uint local)
{
    for (uint step = 1u; step < 256u; step <<= 1) {
        uint add = local >= step ? scan[local - step] : 0u;
        barrier();
        scan[local] += add;
        barrier();
    }
}

void main()
{
    uint t = pc.base + gl_GlobalInvocationID.x;
    uint local = gl_LocalInvocationID.x;
    uint group = pc.base / 256u + gl_WorkGroupID.x;
    if (pc.mode == 0u) {
        int c = t < pc.tet_count ? tet_case(t) : -1;
        uint own = c < 0 ? 0u : uint(cases[8 * c]);
        scan[local] = own;
        barrier();
        scan_group(local);
        if (t < pc.tet_count)
            counts[t] = (scan[local] - own) << 4 | (own > 0u ? uint(c) : 0u);
        if (local == 255u)
            groups[group] = scan[255];
    } else if (pc.mode == 1u) {
        // one workgroup: tiles of 1024 group totals, 4 consecutive ones per invocation
        uint carry = 0u;
        for (uint tile = 0u; tile < pc.group_count; tile += 1024u) {
            uint i = tile + 4u * local;
            uint a = i < pc.group_count ? groups[i] : 0u;
            uint b = i + 1u < pc.group_count ? groups[i + 1u] : 0u;
            uint c = i + 2u < pc.group_count ? groups[i + 2u] : 0u;
            uint d = i + 3u < pc.group_count ? groups[i + 3u] : 0u;
            uint own = a + b + c + d;
            scan[local] = own;
            barrier();
            scan_group(local);
            uint first = carry + scan[local] - own;
            if (i < pc.group_count)
                groups[i] = first;
            if (i + 1u < pc.group_count)
                groups[i + 1u] = first + a;
            if (i + 2u < pc.group_count)
                groups[i + 2u] = first + a + b;
            if (i + 3u < pc.group_count)
                groups[i + 3u] = first + a + b + c;
            carry += scan[255];
            barrier(); // every invocation has read scan[255] before the next tile writes scan
        }
        if (local == 0u)
            groups[pc.group_count] = carry;
    } else if (pc.mode == 3u) {
        if (gl_GlobalInvocationID.x == 0u) {
            draw_args[0] = 3u * groups[pc.group_count];
            draw_args[1] = 1u;
            draw_args[2] = 0u;
            draw_args[3] = 0u;
        }
    } else if (t < pc.tet_count) {
        uint packed = counts[t];
        int c = int(packed & 15u);
        if (c == 0 || c == 15)
            return;
        ivec4 v = tets[t];
        uint first = (packed >> 4) + groups[group];
        int n = cases[8 * c];
        for (int k = 0; k < 3 * n; k++) {
            ivec2 e = EDGES[cases[8 * c + 1 + k]];
            int a = v[e.x], b = v[e.y];
            if (a > b) {
                int x = a;
                a = b;
                b = x;
            }
            uint corner = 3u * first + uint(k);
            keys[corner] = uvec2(uint(b), uint(a));
            float sa = scalars[a], sb = scalars[b];
            float w = (pc.value - sa) / (sb - sa);
            for (int i = 0; i < 3; i++) {
                float pa = positions[3 * a + i], pb = positions[3 * b + i];
                corners[3u * corner + uint(i)] = pa + w * (pb - pa);
            }
        }
    }
}
