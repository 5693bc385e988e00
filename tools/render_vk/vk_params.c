/* The Vulkan renderer's parameters for one frame: the options checked as the CPU reference checks
 * them, and the camera basis, scalar mapping, clip box and transfer function in the shader's uniform
 * block (render.comp's Params). No Vulkan call here. */
#include <math.h>
#include <string.h>

#include "render_vk_internal.h"

/* ---- Options and camera (as tpk_render_cpu) ----------------------------------------------------- */

int tpk_vk_check_options(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, const uint8_t *rgba,
                         tpk_diag *diag)
{
    if (!mesh || !opt || !rgba)
        return tpk_diag_fail(diag, "render: mesh, options and image buffer are required");
    if (opt->width < 1 || opt->height < 1 || opt->width > 32768 || opt->height > 32768)
        return tpk_diag_fail(diag, "render: expected width and height in 1..32768, found %dx%d", opt->width,
                             opt->height);
    if (!opt->tf || opt->tf->count < 1 || opt->tf->count > TPK_TF_MAX_POINTS)
        return tpk_diag_fail(diag, "render: a transfer function with at least one point is required");
    if (opt->integration < 0 || opt->integration > 2)
        return tpk_diag_fail(diag, "render: expected integration 0 (exact), 1 (sampled) or 2 (midpoint), found %d",
                             opt->integration);
    if (!isfinite(opt->range_min) || !isfinite(opt->range_max))
        return tpk_diag_fail(diag, "render: the scalar range must be finite");
    for (int k = 0; opt->clip && k < 3; k++) {
        if (!isfinite(opt->clip_min[k]) || !isfinite(opt->clip_max[k]))
            return tpk_diag_fail(diag, "render: the clip box must be finite");
        if (opt->clip_min[k] > opt->clip_max[k])
            return tpk_diag_fail(diag, "render: clip box min %g above max %g on axis %c", opt->clip_min[k],
                                 opt->clip_max[k], "xyz"[k]);
    }
    if (opt->iso_count < 0 || opt->iso_count > TPK_RENDER_MAX_ISO)
        return tpk_diag_fail(diag, "render: expected 0..%d iso values, found %d", TPK_RENDER_MAX_ISO, opt->iso_count);
    for (int j = 0; j < opt->iso_count; j++)
        if (!isfinite(opt->iso[j]))
            return tpk_diag_fail(diag, "render: iso values must be finite");
    if (opt->ao_rays < 0 || opt->ao_rays > 1024 || !isfinite(opt->ao_radius))
        return tpk_diag_fail(diag, "render: expected 0..1024 AO rays and a finite AO radius");
    if (mesh->vertex_count > 0x7fffffffu || mesh->tet_count > 0x7fffffffu || mesh->shell_face_count > 0x7fffffffu)
        return tpk_diag_fail(diag, "render: more than 2^31 - 1 vertices, tets or shell faces");
    return 0;
}

/* The camera basis of both backends (tpk_camera_basis_of), into the shader's parameters. */
static int set_camera(const tpk_render_options *opt, const double origin[3], tpk_vk_params *p, tpk_diag *diag)
{
    const tpk_camera *cam = &opt->camera;
    tpk_camera_basis basis;
    if (tpk_camera_basis_of(cam, opt->width, opt->height, &basis, diag) != 0)
        return -1;
    for (int k = 0; k < 3; k++) {
        p->eye[k] = (float)(cam->eye[k] - origin[k]);
        p->forward[k] = (float)basis.forward[k];
        p->right[k] = (float)basis.right[k];
        p->up[k] = (float)basis.up[k];
    }
    p->forward[3] = (float)basis.tan_half_x;
    p->right[3] = (float)basis.tan_half_y;
    return 0;
}

int tpk_vk_params_fill(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, double extent, int64_t face_count,
                       tpk_vk_params *p, tpk_diag *diag)
{
    memset(p, 0, sizeof *p);
    if (set_camera(opt, mesh->origin, p, diag) != 0)
        return -1;
    /* Boxes get 1e-5 of the reach on top of the builder's 1e-6 of the extent: the float slab test and
     * the float edge tests err by a few ulps of coordinates relative to the eye. */
    double reach = extent + fabs(p->eye[0]) + fabs(p->eye[1]) + fabs(p->eye[2]);
    p->up[3] = (float)(1e-5 * reach);
    memcpy(p->background, opt->background, sizeof p->background);
    p->scalar_map[0] = (float)opt->range_min;
    p->scalar_map[1] = opt->range_max != opt->range_min ? (float)(1.0 / (opt->range_max - opt->range_min)) : 0.0f;
    double unit, ao_radius;
    tpk_render_lengths(opt, tpk_positions_diagonal(mesh), &unit, &ao_radius);
    p->scalar_map[2] = (float)(1.0 / unit);
    p->cast_info[0] = (float)ao_radius;
    p->cast_info[1] = (float)(1e-3 * unit); /* TPK_RENDER_SELF_EPS */
    p->cast_info[2] = (float)unit;
    p->cast_count[0] = opt->ao_rays;
    p->dims[0] = opt->width;
    p->dims[1] = opt->height;
    p->dims[3] = opt->tf->count;
    p->mode[0] = (int32_t)mesh->tet_count;
    p->mode[1] = (int32_t)mesh->vertex_count;
    p->mode[2] = opt->integration;
    p->mode[3] = opt->tet_scalars ? 2 : mesh->scalars ? 1 : 0;
    if (opt->clip) {
        for (int k = 0; k < 3; k++) {
            p->clip_lo[k] = (float)(opt->clip_min[k] - mesh->origin[k]);
            p->clip_hi[k] = (float)(opt->clip_max[k] - mesh->origin[k]);
        }
        p->clip_lo[3] = 1.0f;
    }
    p->shell_info[0] = (int32_t)face_count;
    p->shell_info[1] = opt->iso_count;
    for (int j = 0; j < opt->iso_count; j++)
        p->iso[j] = (float)opt->iso[j];
    for (int k = 0; k < 3; k++) /* render.h: LIGHT, the eye without a light */
        p->light[k] = opt->have_light ? (float)(opt->light[k] - mesh->origin[k]) : p->eye[k];
    p->light[3] = opt->iso_opacity > 0 ? (float)opt->iso_opacity : 1.0f;
    for (int i = 0; i < opt->tf->count; i++) {
        const tpk_tf_point *t = &opt->tf->points[i];
        p->tf_s[i] = (float)t->s;
        p->tf_rgba[i][0] = (float)t->r;
        p->tf_rgba[i][1] = (float)t->g;
        p->tf_rgba[i][2] = (float)t->b;
        p->tf_rgba[i][3] = (float)t->a;
    }
    return 0;
}


int tpk_vk_effects(const tpk_render_options *opt)
{
    return (opt->iso_count > 0 ? TPK_VK_EFFECT_ISO : 0) | (opt->shading ? TPK_VK_EFFECT_SHADING : 0) |
           (opt->shadows ? TPK_VK_EFFECT_SHADOWS : 0) | (opt->ao_rays > 0 ? TPK_VK_EFFECT_AO : 0);
}

/* render.comp's Params block, std140: 15 vec4 rows, then the TF's 256 s values and 256 colours. */
_Static_assert(sizeof(tpk_vk_params) == 15 * 16 + TPK_VK_TF_MAX * 4 + TPK_VK_TF_MAX * 16,
               "tpk_vk_params as render.comp's Params");
