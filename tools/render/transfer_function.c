/* Transfer functions: built-in presets (perceptual color maps with opacity ramps) and the `s r g b a`
 * text format. */
#include "transfer_function.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/text_scan.h"

typedef struct tf_preset {
    const char *name;
    int count;
    const float (*rgb)[3]; /* colors at evenly spaced s */
    float alpha_lo, alpha_mid, alpha_hi; /* opacity at s = 0, 0.5, 1, piecewise linear */
} tf_preset;

/* Color maps sampled at 11 evenly spaced points: matplotlib's viridis and inferno (van der Walt and
 * Smith), Moreland's diverging cool-warm, and a gray ramp. */
static const float viridis_rgb[11][3] = {
    {0.267f, 0.005f, 0.329f}, {0.283f, 0.141f, 0.458f}, {0.254f, 0.265f, 0.530f}, {0.207f, 0.372f, 0.553f},
    {0.164f, 0.471f, 0.558f}, {0.128f, 0.567f, 0.551f}, {0.135f, 0.659f, 0.518f}, {0.267f, 0.749f, 0.441f},
    {0.478f, 0.821f, 0.318f}, {0.741f, 0.873f, 0.150f}, {0.993f, 0.906f, 0.144f}};
static const float inferno_rgb[11][3] = {
    {0.001f, 0.000f, 0.014f}, {0.087f, 0.045f, 0.224f}, {0.258f, 0.039f, 0.406f}, {0.416f, 0.090f, 0.433f},
    {0.578f, 0.148f, 0.404f}, {0.736f, 0.216f, 0.330f}, {0.865f, 0.317f, 0.226f}, {0.954f, 0.469f, 0.098f},
    {0.988f, 0.645f, 0.040f}, {0.964f, 0.843f, 0.273f}, {0.988f, 0.998f, 0.645f}};
static const float cool_warm_rgb[9][3] = {
    {0.230f, 0.299f, 0.754f}, {0.384f, 0.510f, 0.918f}, {0.553f, 0.690f, 0.996f}, {0.722f, 0.816f, 0.976f},
    {0.867f, 0.867f, 0.867f}, {0.961f, 0.769f, 0.678f}, {0.957f, 0.604f, 0.482f}, {0.871f, 0.376f, 0.302f},
    {0.706f, 0.016f, 0.150f}};
static const float grayscale_rgb[2][3] = {{0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}};

static const tf_preset presets[] = {
    {"viridis", 11, viridis_rgb, 0.0f, 0.08f, 0.3f},
    {"cool-warm", 9, cool_warm_rgb, 0.3f, 0.01f, 0.3f}, /* diverging: both ends stand out */
    {"inferno", 11, inferno_rgb, 0.0f, 0.08f, 0.3f},
    {"grayscale", 2, grayscale_rgb, 0.0f, 0.1f, 0.2f},
};

/* The names joined from the table (the one list of presets), made once. */
static char preset_names[128];
static pthread_once_t preset_names_once = PTHREAD_ONCE_INIT;

static void join_preset_names(void)
{
    size_t at = 0;
    for (size_t i = 0; i < sizeof presets / sizeof presets[0]; i++)
        at += (size_t)snprintf(preset_names + at, sizeof preset_names - at, "%s%s", i ? ", " : "", presets[i].name);
}

const char *tpk_tf_preset_names(void)
{
    pthread_once(&preset_names_once, join_preset_names);
    return preset_names;
}

const char *tpk_tf_preset(int i)
{
    return i >= 0 && (size_t)i < sizeof presets / sizeof presets[0] ? presets[i].name : NULL;
}

int tpk_tf_is_preset(const char *name)
{
    for (int i = 0; name && tpk_tf_preset(i); i++)
        if (!strcmp(name, tpk_tf_preset(i)))
            return 1;
    return 0;
}

static double preset_alpha(const tf_preset *p, double s)
{
    return s < 0.5 ? p->alpha_lo + (p->alpha_mid - p->alpha_lo) * (s / 0.5)
                   : p->alpha_mid + (p->alpha_hi - p->alpha_mid) * ((s - 0.5) / 0.5);
}

/* Control points at the color samples plus s = 0.5 (the opacity's knee) when it falls between. */
static void build_preset(const tf_preset *p, tpk_transfer_function *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->name, sizeof out->name, "%s", p->name);
    for (int i = 0; i < p->count; i++) {
        double s = (double)i / (p->count - 1);
        if (i > 0 && (double)(i - 1) / (p->count - 1) < 0.5 && s > 0.5) {
            tpk_tf_point mid = {0.5, 0, 0, 0, preset_alpha(p, 0.5)};
            double u = (0.5 - (double)(i - 1) / (p->count - 1)) * (p->count - 1);
            mid.r = p->rgb[i - 1][0] + u * (p->rgb[i][0] - p->rgb[i - 1][0]);
            mid.g = p->rgb[i - 1][1] + u * (p->rgb[i][1] - p->rgb[i - 1][1]);
            mid.b = p->rgb[i - 1][2] + u * (p->rgb[i][2] - p->rgb[i - 1][2]);
            out->points[out->count++] = mid;
        }
        out->points[out->count++] = (tpk_tf_point){s, p->rgb[i][0], p->rgb[i][1], p->rgb[i][2], preset_alpha(p, s)};
    }
}

/* One data line: five finite numbers, ranges checked. */
static int parse_point(const char *name, int line, const char *text, tpk_tf_point *pt, tpk_diag *diag)
{
    double v[5];
    const char *p = text;
    static const char *const labels[5] = {"s", "r", "g", "b", "a"};
    for (int i = 0; i < 5; i++) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            p++;
        char *end;
        errno = 0;
        v[i] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(v[i]) ||
            (*end && *end != ' ' && *end != '\t' && *end != '\r')) {
            char found[32];
            size_t n = strcspn(p, " \t\r");
            snprintf(found, sizeof found, "%.*s", (int)(n > 24 ? 24 : n), p);
            return tpk_diag_fail(diag, "%s:%d: expected 5 numbers 's r g b a', found %s where %s should be",
                                 name, line, *found ? found : "end of line", labels[i]);
        }
        if (v[i] < 0 || v[i] > 1)
            return tpk_diag_fail(diag, "%s:%d: expected %s in [0,1], found %g", name, line, labels[i], v[i]);
        p = end;
    }
    while (*p == ' ' || *p == '\t' || *p == '\r')
        p++;
    if (*p)
        return tpk_diag_fail(diag, "%s:%d: expected 5 numbers 's r g b a', found extra text '%.24s'", name,
                             line, p);
    *pt = (tpk_tf_point){v[0], v[1], v[2], v[3], v[4]};
    return 0;
}

int tpk_tf_parse(const char *name, const char *text, tpk_transfer_function *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    snprintf(out->name, sizeof out->name, "%s", name);
    char buf[512];
    int line = 0;
    const char *p = text;
    while (*p) {
        line++;
        size_t n = strcspn(p, "\n");
        if (n >= sizeof buf)
            return tpk_diag_fail(diag, "%s:%d: expected a line of at most %zu characters, found %zu", name, line,
                                 sizeof buf - 1, n);
        memcpy(buf, p, n);
        buf[n] = 0;
        p += n + (p[n] == '\n');
        char *hash = strchr(buf, '#');
        if (hash)
            *hash = 0;
        if (buf[strspn(buf, " \t\r")] == 0)
            continue;
        tpk_tf_point pt;
        if (parse_point(name, line, buf, &pt, diag) != 0)
            return -1;
        if (out->count > 0 && !(pt.s > out->points[out->count - 1].s))
            return tpk_diag_fail(diag, "%s:%d: expected s greater than %g (s must increase strictly), found %g",
                                 name, line, out->points[out->count - 1].s, pt.s);
        if (out->count == TPK_TF_MAX_POINTS)
            return tpk_diag_fail(diag, "%s:%d: expected at most %d points, found more", name, line,
                                 TPK_TF_MAX_POINTS);
        out->points[out->count++] = pt;
    }
    if (out->count < 2)
        return tpk_diag_fail(diag, "%s: expected at least 2 points 's r g b a', found %d", name, out->count);
    return 0;
}

int tpk_tf_load(const char *preset_or_path, tpk_transfer_function *out, tpk_diag *diag)
{
    if (!preset_or_path || !out)
        return tpk_diag_fail(diag, "transfer function: no name given");
    for (size_t i = 0; i < sizeof presets / sizeof presets[0]; i++)
        if (!strcmp(preset_or_path, presets[i].name)) {
            build_preset(&presets[i], out);
            return 0;
        }
    /* The file is mapped, so a FIFO or a directory is refused with a message instead of blocking. */
    if (access(preset_or_path, F_OK) != 0)
        return tpk_diag_fail(diag, "%s: not a transfer function preset (%s) and cannot open it as a file: %s",
                             preset_or_path, tpk_tf_preset_names(), strerror(errno));
    const char *data;
    size_t n;
    if (tpk_map_file(preset_or_path, &data, &n, diag) != 0)
        return -1;
    enum { MAX_BYTES = 1 << 20 };
    char *text = n <= MAX_BYTES ? malloc(n + 1) : NULL;
    int rc;
    if (n > MAX_BYTES)
        rc = tpk_diag_fail(diag, "%s: expected a transfer function file under 1 MiB, found a larger file",
                           preset_or_path);
    else if (!text)
        rc = tpk_diag_fail(diag, "%s: out of memory", preset_or_path);
    else if (memchr(data, 0, n))
        rc = tpk_diag_fail(diag, "%s: expected text 's r g b a' lines, found a NUL byte", preset_or_path);
    else {
        memcpy(text, data, n);
        text[n] = 0;
        rc = tpk_tf_parse(preset_or_path, text, out, diag);
    }
    tpk_unmap_file(data, n);
    free(text);
    return rc;
}

void tpk_tf_eval(const tpk_transfer_function *tf, double s, double rgba[4])
{
    const tpk_tf_point *p = tf->points;
    int n = tf->count;
    const tpk_tf_point *lo = &p[0], *hi = &p[0];
    double u = 0;
    if (n <= 0) {
        rgba[0] = rgba[1] = rgba[2] = rgba[3] = 0;
        return;
    }
    if (s <= p[0].s || n == 1) {
        lo = hi = &p[0];
    } else if (s >= p[n - 1].s) {
        lo = hi = &p[n - 1];
    } else {
        int a = 0, b = n - 1; /* p[a].s <= s < p[b].s */
        while (b - a > 1) {
            int mid = (a + b) / 2;
            if (p[mid].s <= s)
                a = mid;
            else
                b = mid;
        }
        lo = &p[a];
        hi = &p[b];
        u = (s - lo->s) / (hi->s - lo->s);
    }
    rgba[0] = lo->r + u * (hi->r - lo->r);
    rgba[1] = lo->g + u * (hi->g - lo->g);
    rgba[2] = lo->b + u * (hi->b - lo->b);
    rgba[3] = lo->a + u * (hi->a - lo->a);
}
