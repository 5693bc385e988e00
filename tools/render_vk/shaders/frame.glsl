// Part of render.comp, included once, in the order it lists.
// The ray frame, the watertight edge test and shell-face hits (libtetpack/ray.c, internal_ray.h).

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
