/* The one check of tpk_render_options that every backend makes before it renders: the values a renderer
 * cannot use are refused, not clamped, with the same message whichever backend is asked. Pure. */
#include <math.h>
#include <stddef.h>

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
    return 0;
}

/* The range every renderer accepts for each option of the table (render_options.def, TPK_USE's check
 * columns; a double must also be finite), in the table's order. */
typedef struct table_check {
    size_t at; /* the field's offset in tpk_render_options */
    int real;  /* a double, else an int */
    double lo, hi;
    const char *message; /* printf form of the value; NULL: no check */
} table_check;

#define TPK_USE(init, when, always, cache, lo, hi, message) lo, hi, message
#define TPK_OPTION(ID, name, kind, R, A, S, rule, cli, key, use, vk) \
    TPK_IF(R, {offsetof(tpk_render_options, name), TPK_OPTION_REAL_##kind, use},)
static const table_check table_checks[] = {
#include "render_options.def"
};
#undef TPK_OPTION
#undef TPK_USE

static int check_table(const tpk_render_options *opt, tpk_diag *diag)
{
    for (size_t i = 0; i < sizeof table_checks / sizeof table_checks[0]; i++) {
        const table_check *c = &table_checks[i];
        const char *field = (const char *)opt + c->at;
        if (!c->message)
            continue;
        if (c->real) {
            double v = *(const double *)field;
            if (!isfinite(v) || v < c->lo || v > c->hi)
                return tpk_diag_fail(diag, c->message, v);
        } else {
            int v = *(const int *)field;
            if (v < c->lo || v > c->hi)
                return tpk_diag_fail(diag, c->message, v);
        }
    }
    return 0;
}

int tpk_render_check_options(const tpk_render_options *opt, tpk_diag *diag)
{
    if (!opt)
        return tpk_diag_fail(diag, "render: options are required");
    tpk_camera_basis basis;
    if (check_image(opt, diag) != 0 || check_effects(opt, diag) != 0 || check_table(opt, diag) != 0)
        return -1;
    return tpk_camera_basis_of(&opt->camera, opt->width, opt->height, &basis, diag);
}
