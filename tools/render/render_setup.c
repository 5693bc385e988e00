/* What every backend derives from the options in the same way, so that the CPU reference and the Vulkan
 * renderer cast the same rays and weigh them alike: the camera's view basis, the effects' lengths and
 * the rest of tpk_render_setup. */
#include <math.h>

#include "render.h"

static void normalize3(double v[3])
{
    double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len > 0)
        for (int k = 0; k < 3; k++)
            v[k] /= len;
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

int tpk_camera_basis_of(const tpk_camera *cam, int width, int height, tpk_camera_basis *out, tpk_diag *diag)
{
    double up[3];
    for (int k = 0; k < 3; k++) {
        if (!isfinite(cam->eye[k]) || !isfinite(cam->at[k]) || !isfinite(cam->up[k]))
            return tpk_diag_fail(diag, "render: camera eye, at and up must be finite");
        out->forward[k] = cam->at[k] - cam->eye[k];
        up[k] = cam->up[k];
    }
    normalize3(out->forward);
    const double *f = out->forward;
    if (f[0] == 0 && f[1] == 0 && f[2] == 0)
        return tpk_diag_fail(diag, "render: camera eye and at are the same point");
    if (!(cam->fovy_deg > 0 && cam->fovy_deg < 180))
        return tpk_diag_fail(diag, "render: expected a field of view in (0, 180) degrees, found %g", cam->fovy_deg);
    cross3(f, up, out->right);
    normalize3(out->right);
    if (out->right[0] == 0 && out->right[1] == 0 && out->right[2] == 0) {
        /* up along the view direction: pick any perpendicular */
        const double other[3] = {fabs(f[0]) < 0.9 ? 1.0 : 0.0, fabs(f[0]) < 0.9 ? 0.0 : 1.0, 0};
        cross3(f, other, out->right);
        normalize3(out->right);
    }
    cross3(out->right, f, out->up);
    out->tan_half_y = tan(0.5 * cam->fovy_deg * M_PI / 180.0);
    out->tan_half_x = out->tan_half_y * width / height;
    return 0;
}

void tpk_render_lengths(const tpk_render_options *opt, double diagonal, double *unit, double *ao_radius)
{
    double u = opt->unit_distance;
    if (!(u > 0) || !isfinite(u))
        u = diagonal / 100.0;
    *unit = u > 0 ? u : 1.0;
    *ao_radius = opt->ao_radius > 0 ? opt->ao_radius : diagonal / 10.0;
}

int tpk_render_setup_of(const tpk_render_options *opt, double diagonal, tpk_render_setup *out, tpk_diag *diag)
{
    if (tpk_camera_basis_of(&opt->camera, opt->width, opt->height, &out->basis, diag) != 0)
        return -1;
    out->range_min = opt->range_min;
    out->inv_range = opt->range_max != opt->range_min ? 1.0 / (opt->range_max - opt->range_min) : 0.0;
    tpk_render_lengths(opt, diagonal, &out->unit, &out->ao_radius);
    out->inv_unit = 1.0 / out->unit;
    out->iso_opacity = opt->iso_opacity > 0 ? opt->iso_opacity : 1.0;
    for (int k = 0; k < 3; k++)
        out->light[k] = opt->have_light ? opt->light[k] : opt->camera.eye[k];
    out->cast = opt->shadows || opt->ao_rays > 0;
    out->lighting = out->cast || opt->shading;
    return 0;
}
