// Part of render.comp, included once, in the order it lists.
// Normals, the lighting factor and iso crossings (render/render_light.c; render.h NORMAL, ISOSURFACES).

// ---- Effects (render.h: ISOSURFACES, NORMAL, LIGHTING FACTOR) -------------------------------------

vec3 eye_dir_point(float t)
{
    return P.eye.xyz + t * ray_dir;
}

// m at x with normal n (has_n false: no normal), shadow transmittance S and AO factor A (rl_factor).
float lighting_factor(vec3 x, bool has_n, vec3 n, float S, float A)
{
    float d = 1.0;
    vec3 to_light = P.light.xyz - x;
    float len = length(to_light);
    if (SHADING && has_n && len > 0.0 && !isinf(len))
        d = abs(dot(n, to_light / len));
    return A * (0.3 + 0.7 * d * S); // TPK_RENDER_AMBIENT
}

bool unit_or_none(vec3 v, out vec3 n)
{
    float len = length(v);
    n = v / len;
    return len > 0.0 && !isinf(len) && !isnan(len);
}

// The unit gradient of the point scalar over the tet v[0..3] (false where it is zero).
bool tet_normal(ivec4 v, out vec3 n)
{
    vec4 p0 = fetch_verts(uint(v.x)), p1 = fetch_verts(uint(v.y)), p2 = fetch_verts(uint(v.z)),
         p3 = fetch_verts(uint(v.w));
    vec3 e1 = p1.xyz - p0.xyz, e2 = p2.xyz - p0.xyz, e3 = p3.xyz - p0.xyz;
    vec3 c23 = cross(e2, e3), c31 = cross(e3, e1), c12 = cross(e1, e2);
    float det = dot(e1, c23);
    vec3 g = ((p1.w - p0.w) * c23 + (p2.w - p0.w) * c31 + (p3.w - p0.w) * c12) / det;
    return unit_or_none(g, n);
}

// render_light.c's rl_vertex_lookup: S and A at x (eye-relative world, as eye_dir_point gives it) from the
// per-vertex cache, linear in the tet v[0..3] (barycentric from its edges; the mean of the four where
// the tet is flat), clamped to [0, 1].
vec2 vertex_lookup(ivec4 v, vec3 x)
{
    vec4 p0 = fetch_verts(uint(v.x)), p1 = fetch_verts(uint(v.y)), p2 = fetch_verts(uint(v.z)),
         p3 = fetch_verts(uint(v.w));
    vec3 e1 = p1.xyz - p0.xyz, e2 = p2.xyz - p0.xyz, e3 = p3.xyz - p0.xyz;
    vec3 c1 = cross(e2, e3), c2 = cross(e3, e1), c3 = cross(e1, e2);
    float det = dot(e1, c1);
    vec3 q = x - p0.xyz;
    vec4 l = vec4(0.25);
    if (det != 0.0 && !isinf(det) && !isnan(det)) {
        l.yzw = vec3(dot(q, c1), dot(q, c2), dot(q, c3)) / det;
        l.x = 1.0 - l.y - l.z - l.w;
    }
    vec2 sa = l.x * fetch_vertex_sa(uint(v.x)).xy + l.y * fetch_vertex_sa(uint(v.y)).xy +
              l.z * fetch_vertex_sa(uint(v.z)).xy + l.w * fetch_vertex_sa(uint(v.w)).xy;
    return clamp(sa, 0.0, 1.0);
}

bool face_normal(ivec4 v, out vec3 n)
{
    vec3 p0 = fetch_verts(uint(v.x)).xyz, p1 = fetch_verts(uint(v.y)).xyz, p2 = fetch_verts(uint(v.z)).xyz;
    return unit_or_none(cross(p1 - p0, p2 - p0), n);
}

// Iso crossings of one piece, in increasing t (equal t: increasing j).
int crossing_j[4];
float crossing_t[4];

int add_crossing(int n, float t, int j)
{
    int k = n;
    while (k > 0 && (crossing_t[k - 1] > t || (crossing_t[k - 1] == t && crossing_j[k - 1] > j))) {
        crossing_t[k] = crossing_t[k - 1];
        crossing_j[k] = crossing_j[k - 1];
        k--;
    }
    crossing_t[k] = t;
    crossing_j[k] = j;
    return n + 1;
}

// Point field: where the linear scalar crosses each value (half-open, so a face counts once).
int point_crossings(float t_in, float t_out, float s_in, float s_out)
{
    int n = 0;
    for (int j = 0; j < P.shell_info.y; j++) {
        float v = P.iso[j];
        if ((s_in < v && v <= s_out) || (s_in > v && v >= s_out))
            n = add_crossing(n, clamp(t_in + (v - s_in) / (s_out - s_in) * (t_out - t_in), t_in, t_out), j);
    }
    return n;
}

// Tet field: the jump between two consecutive pieces, at t.
int jump_crossings(float t, float s_prev, float s)
{
    int n = 0;
    for (int j = 0; j < P.shell_info.y; j++) {
        float v = P.iso[j];
        if ((s_prev < v && v <= s) || (s_prev > v && v >= s))
            n = add_crossing(n, t, j);
    }
    return n;
}
