/* The one check of tpk_render_options that every backend makes before it renders: the values a renderer
 * cannot use are refused, not clamped, with the same message whichever backend is asked. Pure. */
#include <math.h>

#include "render.h"

static int finite3(const double v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

/* The image, the transfer function and the scalar mapping. */
static int check_image(const tpk_render_options *opt, tpk_diag *diag)
{
    if (opt->width < 1 || opt->height < 1 || opt->width > TPK_RENDER_MAX_SIZE || opt->height > TPK_RENDER_MAX_SIZE)
        return tpk_diag_fail(diag, "render: expected width and height in 1..%d, found %dx%d", TPK_RENDER_MAX_SIZE,
                             opt->width, opt->height);
    if (!opt->tf || opt->tf->count < 1 || opt->tf->count > TPK_TF_MAX_POINTS)
        return tpk_diag_fail(diag, "render: a transfer function with at least one point is required");
    if (opt->integration < TPK_INTEGRATION_EXACT || opt->integration > TPK_INTEGRATION_MIDPOINT)
        return tpk_diag_fail(diag, "render: expected integration 0 (exact), 1 (sampled) or 2 (midpoint), found %d",
                             opt->integration);
    if (!isfinite(opt->range_min) || !isfinite(opt->range_max))
        return tpk_diag_fail(diag, "render: the scalar range must be finite");
    return 0;
}

int tpk_probe_check(const tpk_probe *p, int number, tpk_diag *diag)
{
    if (p->cut != 0 && p->cut != 1)
        return tpk_diag_fail(diag, "render: probe %d: expected keep (0) or cut (1), found %d", number, p->cut);
    if (!finite3(p->a) || (p->shape != TPK_PROBE_SPHERE && !finite3(p->b)))
        return tpk_diag_fail(diag, "render: probe %d: its coordinates must be finite", number);
    switch (p->shape) {
    case TPK_PROBE_SPHERE:
        if (!(isfinite(p->radius) && p->radius > 0))
            return tpk_diag_fail(diag, "render: probe %d: expected a sphere radius > 0, found %g", number, p->radius);
        return 0;
    case TPK_PROBE_PLANE:
        if (p->b[0] == 0 && p->b[1] == 0 && p->b[2] == 0)
            return tpk_diag_fail(diag, "render: probe %d: the plane's normal is zero", number);
        return 0;
    case TPK_PROBE_BOX:
        for (int k = 0; k < 3; k++)
            if (p->a[k] > p->b[k])
                return tpk_diag_fail(diag, "render: probe %d: box min %g above max %g on axis %c", number, p->a[k],
                                     p->b[k], "xyz"[k]);
        return 0;
    default:
        return tpk_diag_fail(diag, "render: probe %d: expected shape sphere (1), plane (2) or box (3), found %d",
                             number, p->shape);
    }
}

/* The effects (render.h): each one off when zero. */
static int check_effects(const tpk_render_options *opt, tpk_diag *diag)
{
    if (opt->iso_count < 0 || opt->iso_count > TPK_RENDER_MAX_ISO)
        return tpk_diag_fail(diag, "render: expected 0..%d iso values, found %d", TPK_RENDER_MAX_ISO, opt->iso_count);
    for (int j = 0; j < opt->iso_count; j++)
        if (!isfinite(opt->iso[j]))
            return tpk_diag_fail(diag, "render: iso value %d is not finite", j + 1);
    if (!isfinite(opt->iso_opacity) || opt->iso_opacity > 1)
        return tpk_diag_fail(diag, "render: expected an iso opacity <= 1, found %g", opt->iso_opacity);
    if (opt->clip && (!finite3(opt->clip_min) || !finite3(opt->clip_max)))
        return tpk_diag_fail(diag, "render: the clip box must be finite");
    for (int k = 0; opt->clip && k < 3; k++)
        if (opt->clip_min[k] > opt->clip_max[k])
            return tpk_diag_fail(diag, "render: clip box min %g above max %g on axis %c", opt->clip_min[k],
                                 opt->clip_max[k], "xyz"[k]);
    if (opt->probe_count < 0 || opt->probe_count > TPK_RENDER_MAX_PROBES)
        return tpk_diag_fail(diag, "render: expected 0..%d probes, found %d", TPK_RENDER_MAX_PROBES, opt->probe_count);
    for (int i = 0; i < opt->probe_count; i++)
        if (tpk_probe_check(&opt->probes[i], i + 1, diag) != 0)
            return -1;
    if (opt->have_light && !finite3(opt->light))
        return tpk_diag_fail(diag, "render: the light position must be finite");
    if (opt->ao_rays < 0 || opt->ao_rays > TPK_RENDER_MAX_AO_RAYS)
        return tpk_diag_fail(diag, "render: expected 0..%d AO rays, found %d", TPK_RENDER_MAX_AO_RAYS, opt->ao_rays);
    if (opt->occlusion != TPK_OCCLUSION_RAY && opt->occlusion != TPK_OCCLUSION_VERTEX)
        return tpk_diag_fail(diag, "render: expected occlusion ray (0) or vertex (1), found %d", opt->occlusion);
    if (!isfinite(opt->ao_radius))
        return tpk_diag_fail(diag, "render: the AO radius must be finite");
    return 0;
}

int tpk_render_check_options(const tpk_render_options *opt, tpk_diag *diag)
{
    if (!opt)
        return tpk_diag_fail(diag, "render: options are required");
    tpk_camera_basis basis;
    if (check_image(opt, diag) != 0 || check_effects(opt, diag) != 0)
        return -1;
    return tpk_camera_basis_of(&opt->camera, opt->width, opt->height, &basis, diag);
}
