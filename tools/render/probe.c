/* CSG probes (render.h PROBES): a ray's spans through them, the point and tet tests extract uses, and
 * their text form (--probe).
 * The Vulkan shader (render.comp, probe_spans) follows the same definition in float. Pure. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render.h"

/* The inside of probe p on the ray org + t dir: [*t0, *t1]; 0 when the ray misses it. */
static int probe_interval(const tpk_probe *p, const double org[3], const double dir[3], double *t0, double *t1)
{
    if (p->shape == TPK_PROBE_SPHERE) {
        double q = 0, c = -p->radius * p->radius;
        for (int k = 0; k < 3; k++) {
            double e = org[k] - p->a[k];
            q += dir[k] * e;
            c += e * e;
        }
        double disc = q * q - c;
        if (disc < 0)
            return 0;
        double r = sqrt(disc);
        *t0 = -q - r;
        *t1 = -q + r;
        return 1;
    }
    if (p->shape == TPK_PROBE_PLANE) {
        double e = 0, f = 0;
        for (int k = 0; k < 3; k++) {
            e += (org[k] - p->a[k]) * p->b[k];
            f += dir[k] * p->b[k];
        }
        if (f == 0) {
            *t0 = -INFINITY;
            *t1 = INFINITY;
            return e <= 0;
        }
        double t = -e / f;
        *t0 = f > 0 ? -INFINITY : t;
        *t1 = f > 0 ? t : INFINITY;
        return 1;
    }
    *t0 = -INFINITY; /* box: the clip box's slab test */
    *t1 = INFINITY;
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0) {
            if (org[k] < p->a[k] || org[k] > p->b[k])
                return 0;
            continue;
        }
        double ta = (p->a[k] - org[k]) / dir[k], tb = (p->b[k] - org[k]) / dir[k];
        double near = ta < tb ? ta : tb, far = ta < tb ? tb : ta;
        *t0 = near > *t0 ? near : *t0;
        *t1 = far < *t1 ? far : *t1;
    }
    return *t0 <= *t1;
}

int tpk_probe_spans(const tpk_probe *probes, int count, const double org[3], const double dir[3], double lo,
                    double hi, double span[][2])
{
    if (!(lo < hi))
        return 0;
    int n = 1;
    span[0][0] = lo;
    span[0][1] = hi;
    for (int i = 0; i < count && n > 0; i++) {
        double t0, t1;
        int meets = probe_interval(&probes[i], org, dir, &t0, &t1);
        if (!probes[i].cut && !meets)
            return 0;
        if (probes[i].cut && !meets)
            continue;
        double next[TPK_RENDER_MAX_PROBES + 1][2];
        int m = 0;
        for (int j = 0; j < n; j++) {
            double p = span[j][0], q = span[j][1];
            if (!probes[i].cut) {
                double a = p > t0 ? p : t0, b = q < t1 ? q : t1;
                if (a < b) {
                    next[m][0] = a;
                    next[m++][1] = b;
                }
                continue;
            }
            double b = q < t0 ? q : t0, a = p > t1 ? p : t1;
            if (p < b && m <= TPK_RENDER_MAX_PROBES) {
                next[m][0] = p;
                next[m++][1] = b;
            }
            if (a < q && m <= TPK_RENDER_MAX_PROBES) {
                next[m][0] = a;
                next[m++][1] = q;
            }
        }
        for (int j = 0; j < m; j++) {
            span[j][0] = next[j][0];
            span[j][1] = next[j][1];
        }
        n = m;
    }
    return n;
}

static int inside(const tpk_probe *p, const double x[3])
{
    double d = 0;
    switch (p->shape) {
    case TPK_PROBE_SPHERE:
        for (int k = 0; k < 3; k++)
            d += (x[k] - p->a[k]) * (x[k] - p->a[k]);
        return d <= p->radius * p->radius;
    case TPK_PROBE_PLANE:
        for (int k = 0; k < 3; k++)
            d += (x[k] - p->a[k]) * p->b[k];
        return d <= 0;
    default:
        for (int k = 0; k < 3; k++)
            if (x[k] < p->a[k] || x[k] > p->b[k])
                return 0;
        return 1;
    }
}

int tpk_probe_keeps(const tpk_probe *probes, int count, const double x[3])
{
    for (int i = 0; i < count; i++)
        if (inside(&probes[i], x) == probes[i].cut)
            return 0;
    return 1;
}

/* Whether the box [lo, hi] meets the inside of keep probe p. */
static int box_meets(const tpk_probe *p, const double lo[3], const double hi[3])
{
    double d = 0;
    switch (p->shape) {
    case TPK_PROBE_SPHERE: /* distance from the center to the box */
        for (int k = 0; k < 3; k++) {
            double e = p->a[k] < lo[k] ? lo[k] - p->a[k] : p->a[k] > hi[k] ? p->a[k] - hi[k] : 0;
            d += e * e;
        }
        return d <= p->radius * p->radius;
    case TPK_PROBE_PLANE: /* the box corner lowest along the normal */
        for (int k = 0; k < 3; k++)
            d += ((p->b[k] > 0 ? lo[k] : hi[k]) - p->a[k]) * p->b[k];
        return d <= 0;
    default:
        for (int k = 0; k < 3; k++)
            if (hi[k] < p->a[k] || lo[k] > p->b[k])
                return 0;
        return 1;
    }
}

int tpk_probe_may_show(const tpk_probe *probes, int count, const double corner[4][3])
{
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = hi[k] = corner[0][k];
        for (int c = 1; c < 4; c++) {
            lo[k] = corner[c][k] < lo[k] ? corner[c][k] : lo[k];
            hi[k] = corner[c][k] > hi[k] ? corner[c][k] : hi[k];
        }
    }
    for (int i = 0; i < count; i++) {
        const tpk_probe *p = &probes[i];
        if (!p->cut && !box_meets(p, lo, hi))
            return 0;
        if (p->cut && inside(p, corner[0]) && inside(p, corner[1]) && inside(p, corner[2]) && inside(p, corner[3]))
            return 0;
    }
    return 1;
}

static const char *const shape_names[] = {[TPK_PROBE_SPHERE] = "sphere", [TPK_PROBE_PLANE] = "plane",
                                          [TPK_PROBE_BOX] = "box"};

const char *tpk_probe_shape_name(int shape)
{
    return shape >= TPK_PROBE_SPHERE && shape <= TPK_PROBE_BOX ? shape_names[shape] : "?";
}

int tpk_probe_shape_of(const char *name, size_t length)
{
    for (int s = TPK_PROBE_SPHERE; s <= TPK_PROBE_BOX; s++)
        if (strlen(shape_names[s]) == length && !strncmp(name, shape_names[s], length))
            return s;
    return 0;
}

int tpk_probe_parse(const char *text, tpk_probe *out)
{
    memset(out, 0, sizeof *out);
    const char *colon = strchr(text, ':');
    if (!colon || !(out->shape = tpk_probe_shape_of(text, (size_t)(colon - text))))
        return -1;
    const int want = out->shape == TPK_PROBE_SPHERE ? 4 : 6;
    double v[6];
    const char *s = colon + 1;
    for (int i = 0; i < want; i++) {
        char *end;
        errno = 0;
        v[i] = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(v[i]) || (i + 1 < want && *end != ','))
            return -1;
        s = i + 1 < want ? end + 1 : end;
    }
    if (*s == ':') {
        if (!strcmp(s + 1, "cut"))
            out->cut = 1;
        else if (strcmp(s + 1, "keep"))
            return -1;
    } else if (*s) {
        return -1;
    }
    memcpy(out->a, v, sizeof out->a);
    if (out->shape == TPK_PROBE_SPHERE)
        out->radius = v[3];
    else
        memcpy(out->b, v + 3, sizeof out->b);
    return 0;
}

int tpk_probe_format(const tpk_probe *p, char *buf, size_t size)
{
    if (p->shape == TPK_PROBE_SPHERE)
        return snprintf(buf, size, "sphere:%.17g,%.17g,%.17g,%.17g:%s", p->a[0], p->a[1], p->a[2], p->radius,
                        p->cut ? "cut" : "keep");
    return snprintf(buf, size, "%s:%.17g,%.17g,%.17g,%.17g,%.17g,%.17g:%s", tpk_probe_shape_name(p->shape), p->a[0],
                    p->a[1], p->a[2], p->b[0], p->b[1], p->b[2], p->cut ? "cut" : "keep");
}
