/* Camera navigation of the viewer: orbit, tilt, zoom and pan of a tpk_camera around its look-at point. */
#include <math.h>

#include "view.h"

static const double deg_to_rad = 3.14159265358979323846 / 180.0;

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static int normalize3(double v[3])
{
    double n = sqrt(dot3(v, v));
    if (!(n > 0) || !isfinite(n))
        return -1;
    for (int k = 0; k < 3; k++)
        v[k] /= n;
    return 0;
}

/* v turned by `rad` around unit axis k (Rodrigues). */
static void rotate3(double v[3], const double k[3], double rad)
{
    double kxv[3], c = cos(rad), s = sin(rad), kv = dot3(k, v);
    cross3(k, v, kxv);
    for (int i = 0; i < 3; i++)
        v[i] = v[i] * c + kxv[i] * s + k[i] * kv * (1 - c);
}

void tpk_view_orbit(tpk_camera *camera, double deg)
{
    double up[3] = {camera->up[0], camera->up[1], camera->up[2]}, offset[3];
    if (normalize3(up) != 0)
        return;
    for (int k = 0; k < 3; k++)
        offset[k] = camera->eye[k] - camera->at[k];
    rotate3(offset, up, deg * deg_to_rad);
    for (int k = 0; k < 3; k++)
        camera->eye[k] = camera->at[k] + offset[k];
}

void tpk_view_tilt(tpk_camera *camera, double deg)
{
    double up[3] = {camera->up[0], camera->up[1], camera->up[2]}, offset[3], right[3];
    for (int k = 0; k < 3; k++)
        offset[k] = camera->eye[k] - camera->at[k];
    double distance = sqrt(dot3(offset, offset));
    if (normalize3(up) != 0 || !(distance > 0))
        return;
    /* the angle between the view offset and up, kept within [1, 179] degrees so up never flips */
    double now = acos(fmax(-1.0, fmin(1.0, dot3(offset, up) / distance))) / deg_to_rad;
    double to = fmax(1.0, fmin(179.0, now - deg));
    cross3(up, offset, right);
    if (normalize3(right) != 0)
        return;
    rotate3(offset, right, (to - now) * deg_to_rad); /* around up x offset: + turns away from up */
    for (int k = 0; k < 3; k++)
        camera->eye[k] = camera->at[k] + offset[k];
}

void tpk_view_zoom(tpk_camera *camera, double factor)
{
    if (!(factor > 0) || !isfinite(factor))
        return;
    for (int k = 0; k < 3; k++)
        camera->eye[k] = camera->at[k] + (camera->eye[k] - camera->at[k]) * factor;
}

void tpk_view_pan(tpk_camera *camera, double dx, double dy, int height)
{
    double forward[3], right[3], up[3];
    for (int k = 0; k < 3; k++)
        forward[k] = camera->at[k] - camera->eye[k];
    double distance = sqrt(dot3(forward, forward));
    cross3(forward, camera->up, right);
    if (height < 1 || normalize3(forward) != 0 || normalize3(right) != 0)
        return;
    cross3(right, forward, up);
    /* world units per pixel at the look-at depth: the view's height there over the image's */
    double per_pixel = 2.0 * distance * tan(0.5 * camera->fovy_deg * deg_to_rad) / height;
    for (int k = 0; k < 3; k++) {
        double shift = (-dx * right[k] + dy * up[k]) * per_pixel;
        camera->eye[k] += shift;
        camera->at[k] += shift;
    }
}
