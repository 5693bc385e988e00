/* The Vulkan renderer's parameters for one frame: the options checked by the one check of every backend
 * (tpk_render_check_options) and the limits of this renderer's own buffers, then the camera basis,
 * scalar mapping, clip box, probes and transfer function in the shader's uniform block (render.comp's Params),
 * derived as every backend derives them (tpk_render_setup_of). No Vulkan call here. */
#include <math.h>
#include <string.h>

#include "render_vk_internal.h"

_Static_assert(TPK_VK_MAX_PROBES == TPK_RENDER_MAX_PROBES && TPK_VK_PROBE_SPHERE == TPK_PROBE_SPHERE &&
                   TPK_VK_PROBE_PLANE == TPK_PROBE_PLANE && TPK_VK_PROBE_BOX == TPK_PROBE_BOX,
               "the shader's probes are render.h's");

/* ---- Options: the shared check, then what only this renderer limits ------------------------------ */

int tpk_vk_check_options(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, const uint8_t *rgba,
                         tpk_diag *diag)
{
    if (!mesh || !opt || !rgba)
        return tpk_diag_fail(diag, "render: mesh, options and image buffer are required");
    if (tpk_render_check_options(opt, diag) != 0)
        return -1;
    /* Vulkan limit: the Params block holds the TF in arrays of TPK_VK_TF_MAX points. */
    if (opt->tf->count > TPK_VK_TF_MAX)
        return tpk_diag_fail(diag, "render: the Vulkan renderer takes at most %d transfer function points, found %d",
                             TPK_VK_TF_MAX, opt->tf->count);
    /* Vulkan limit: the Params block and the shader index vertices, tets and shell faces with int32. */
    if (mesh->vertex_count > 0x7fffffffu || mesh->tet_count > 0x7fffffffu || mesh->shell_face_count > 0x7fffffffu)
        return tpk_diag_fail(diag, "render: more than 2^31 - 1 vertices, tets or shell faces");
    return 0;
}

/* The camera basis of both backends, into the shader's parameters. */
static void set_camera(const tpk_render_options *opt, const tpk_camera_basis *basis, const double origin[3],
                       tpk_vk_params *p)
{
    for (int k = 0; k < 3; k++) {
        p->eye[k] = (float)(opt->camera.eye[k] - origin[k]);
        p->forward[k] = (float)basis->forward[k];
        p->right[k] = (float)basis->right[k];
        p->up[k] = (float)basis->up[k];
    }
    p->forward[3] = (float)basis->tan_half_x;
    p->right[3] = (float)basis->tan_half_y;
}

int tpk_vk_params_fill(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, double diagonal, double extent,
                       int64_t face_count, tpk_vk_params *p, tpk_diag *diag)
{
    memset(p, 0, sizeof *p);
    tpk_render_setup setup;
    if (tpk_render_setup_of(opt, diagonal, &setup, diag) != 0)
        return -1;
    set_camera(opt, &setup.basis, mesh->origin, p);
    /* Boxes get 1e-5 of the reach on top of the builder's 1e-6 of the extent: the float slab test and
     * the float edge tests err by a few ulps of coordinates relative to the eye. */
    double reach = extent + fabs(p->eye[0]) + fabs(p->eye[1]) + fabs(p->eye[2]);
    p->up[3] = (float)(1e-5 * reach);
    memcpy(p->background, opt->background, sizeof p->background);
    p->scalar_map[0] = (float)setup.range_min;
    p->scalar_map[1] = (float)setup.inv_range;
    p->scalar_map[2] = (float)setup.inv_unit;
    p->cast_info[1] = (float)(TPK_RENDER_SELF_EPS * setup.unit);
    p->cast_info[2] = (float)setup.unit;
    p->dims[0] = opt->width;
    p->dims[1] = opt->height;
    p->dims[3] = opt->tf->count;
    p->mode[0] = (int32_t)mesh->tet_count;
    p->mode[1] = (int32_t)mesh->vertex_count;
    p->mode[3] = opt->tet_scalars ? 2 : mesh->scalars ? 1 : 0;
    if (opt->clip) {
        for (int k = 0; k < 3; k++) {
            p->clip_lo[k] = (float)(opt->clip_min[k] - mesh->origin[k]);
            p->clip_hi[k] = (float)(opt->clip_max[k] - mesh->origin[k]);
        }
        p->clip_lo[3] = 1.0f;
    }
    p->probe_info[0] = opt->probe_count;
    for (int i = 0; i < opt->probe_count; i++) {
        const tpk_probe *q = &opt->probes[i];
        p->probe_info[1] |= q->cut ? 1 << i : 0;
        for (int k = 0; k < 3; k++) {
            p->probe_a[i][k] = (float)(q->a[k] - mesh->origin[k]);
            p->probe_b[i][k] = (float)(q->shape == TPK_PROBE_BOX ? q->b[k] - mesh->origin[k] : q->b[k]);
        }
        p->probe_a[i][3] = (float)q->shape;
        p->probe_b[i][3] = (float)q->radius;
    }
    p->shell_info[0] = (int32_t)face_count;
    p->shell_info[1] = opt->iso_count;
    for (int j = 0; j < opt->iso_count; j++)
        p->iso[j] = (float)opt->iso[j];
    for (int k = 0; k < 3; k++) /* render.h: LIGHT, the eye without a light */
        p->light[k] = opt->have_light ? (float)(setup.light[k] - mesh->origin[k]) : p->eye[k];
    /* The table's options (render/render_options.def, TPK_VK): the AO rays and length, the iso opacity,
     * the integration, where the shader reads them (TPK_VK_<ID>, render_options.glsl). */
#define TPK_VK(member, index, value) p->member[index] = (value);
#define TPK_VK_NONE
#define TPK_OPTION(ID, name, kind, R, A, S, rule, cli, key, use, vk) TPK_IF(R, vk)
#include "render/render_options.def"
#undef TPK_OPTION
#undef TPK_VK
#undef TPK_VK_NONE
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
           (opt->shadows ? TPK_VK_EFFECT_SHADOWS : 0) | (opt->ao_rays > 0 ? TPK_VK_EFFECT_AO : 0) |
           (opt->occlusion == TPK_OCCLUSION_VERTEX && (opt->shadows || opt->ao_rays > 0) ? TPK_VK_EFFECT_VERTEX : 0) |
           (opt->occlusion == TPK_OCCLUSION_SURFACE && (opt->shadows || opt->ao_rays > 0) ? TPK_VK_EFFECT_SURFACE : 0);
}

/* render.comp's Params block, std140: 16 vec4 rows, the probes' 2 x 4, then the TF's 256 s values and 256
 * colours. */
_Static_assert(sizeof(tpk_vk_params) == (16 + 2 * TPK_VK_MAX_PROBES) * 16 + TPK_VK_TF_MAX * 4 + TPK_VK_TF_MAX * 16,
               "tpk_vk_params as render.comp's Params");
