// Part of render.comp, included once, in the order it lists.
// A ray's set-up, the clip box and the CSG probes' spans (render/probe.c; render.h CLIP BOX, PROBES).


// The ray's frame (ray.c, tpki_ray_frame_init); false for a degenerate direction.
bool frame_init(vec3 org, vec3 dir)
{
    int kz = 0;
    if (abs(dir[1]) > abs(dir[kz]))
        kz = 1;
    if (abs(dir[2]) > abs(dir[kz]))
        kz = 2;
    if (dir[kz] == 0.0)
        return false;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (dir[kz] < 0.0) {
        int swap = kx;
        kx = ky;
        ky = swap;
    }
    frame.org = org;
    frame.kx = kx;
    frame.ky = ky;
    frame.kz = kz;
    frame.sx = dir[kx] / dir[kz];
    frame.sy = dir[ky] / dir[kz];
    frame.sz = 1.0 / dir[kz];
    return true;
}

// render.h's CLIP BOX: cut [lo, hi] of the ray org + t dir to the box; false when it misses.
bool clip_ray(vec3 org, vec3 dir, inout float lo, inout float hi)
{
    bool meets = true;
    for (int k = 0; P.clip_lo.w != 0.0 && k < 3; k++) {
        if (dir[k] == 0.0) {
            meets = meets && org[k] >= P.clip_lo[k] && org[k] <= P.clip_hi[k];
            continue;
        }
        float t0 = (P.clip_lo[k] - org[k]) / dir[k], t1 = (P.clip_hi[k] - org[k]) / dir[k];
        lo = max(lo, min(t0, t1));
        hi = min(hi, max(t0, t1));
    }
    return meets && lo <= hi;
}

// render.h PROBES (probe.c): the inside of probe i on the ray org + t dir as [t0, t1]; false: missed.
bool probe_interval(int i, vec3 org, vec3 dir, out float t0, out float t1)
{
    const vec4 a = P.probe_a[i], b = P.probe_b[i];
    t0 = -INF;
    t1 = INF;
    if (a.w == float(TPK_VK_PROBE_SPHERE)) {
        const vec3 e = org - a.xyz;
        const float q = dot(dir, e), disc = q * q - (dot(e, e) - b.w * b.w);
        if (disc < 0.0)
            return false;
        const float r = sqrt(disc);
        t0 = -q - r;
        t1 = -q + r;
        return true;
    }
    if (a.w == float(TPK_VK_PROBE_PLANE)) {
        const float e = dot(org - a.xyz, b.xyz), f = dot(dir, b.xyz);
        if (f == 0.0)
            return e <= 0.0;
        if (f > 0.0)
            t1 = -e / f;
        else
            t0 = -e / f;
        return true;
    }
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0.0) {
            if (org[k] < a[k] || org[k] > b[k])
                return false;
            continue;
        }
        const float ta = (a[k] - org[k]) / dir[k], tb = (b[k] - org[k]) / dir[k];
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
    return t0 <= t1;
}

#define MAX_SPANS (TPK_VK_MAX_PROBES + 1)

// The spans of [lo, hi] that the probes keep, in order (tpk_probe_spans); their count.
int probe_spans(vec3 org, vec3 dir, float lo, float hi, out float sa[MAX_SPANS], out float sb[MAX_SPANS])
{
    if (!(lo < hi))
        return 0;
    int n = 1;
    sa[0] = lo;
    sb[0] = hi;
    for (int i = 0; i < P.probe_info.x && n > 0; i++) {
        float t0, t1;
        const bool meets = probe_interval(i, org, dir, t0, t1), cut = (P.probe_info.y & (1 << i)) != 0;
        if (!meets) {
            if (!cut)
                return 0;
            continue;
        }
        float na[MAX_SPANS], nb[MAX_SPANS];
        int m = 0;
        for (int j = 0; j < n; j++) {
            const float p = sa[j], q = sb[j];
            if (!cut) {
                const float x = max(p, t0), y = min(q, t1);
                if (x < y) {
                    na[m] = x;
                    nb[m] = y;
                    m++;
                }
                continue;
            }
            const float y = min(q, t0), x = max(p, t1);
            if (p < y && m < MAX_SPANS) {
                na[m] = p;
                nb[m] = y;
                m++;
            }
            if (x < q && m < MAX_SPANS) {
                na[m] = x;
                nb[m] = q;
                m++;
            }
        }
        for (int j = 0; j < m; j++) {
            sa[j] = na[j];
            sb[j] = nb[j];
        }
        n = m;
    }
    return n;
}
