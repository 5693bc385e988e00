/* The Vulkan renderer's entry: checks the options as the CPU reference does, uploads the file's arrays
 * and the marcher's shell BVH, renders the image in bands of rows (one submission each, so that no
 * single submission runs long enough to trip a GPU watchdog), and reads pixels and tet steps back. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render_vk.h"
#include "render_vk_internal.h"

#define BAND_PIXELS (1u << 20) /* pixels per submission */

/* Everything one render owns on the device; zero means not created. */
typedef struct vk_render {
    tpk_vk_context ctx;
    tpk_vk_array arrays[TPK_VK_ARRAY_COUNT];
    tpk_vk_buffer params, pixels, steps;
    tpk_vk_pipeline pipeline;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
} vk_render;

static void vk_render_destroy(vk_render *v)
{
    if (!v->ctx.device) {
        tpk_vk_context_destroy(&v->ctx);
        return;
    }
    vkDeviceWaitIdle(v->ctx.device);
    if (v->fence)
        vkDestroyFence(v->ctx.device, v->fence, NULL);
    if (v->pool)
        vkDestroyCommandPool(v->ctx.device, v->pool, NULL);
    tpk_vk_pipeline_destroy(&v->ctx, &v->pipeline);
    tpk_vk_buffer_destroy(&v->ctx, &v->params);
    tpk_vk_buffer_destroy(&v->ctx, &v->pixels);
    tpk_vk_buffer_destroy(&v->ctx, &v->steps);
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++)
        tpk_vk_array_destroy(&v->ctx, &v->arrays[a]);
    tpk_vk_context_destroy(&v->ctx);
}

/* ---- Options and camera (as tpk_render_cpu) ----------------------------------------------------- */

static int check_options(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, const uint8_t *rgba,
                         tpk_diag *diag)
{
    if (!mesh || !opt || !rgba)
        return tpk_diag_fail(diag, "render: mesh, options and image buffer are required");
    if (opt->width < 1 || opt->height < 1 || opt->width > 32768 || opt->height > 32768)
        return tpk_diag_fail(diag, "render: expected width and height in 1..32768, found %dx%d", opt->width,
                             opt->height);
    if (!opt->tf || opt->tf->count < 1 || opt->tf->count > TPK_TF_MAX_POINTS)
        return tpk_diag_fail(diag, "render: a transfer function with at least one point is required");
    if (opt->integration != 0 && opt->integration != 1)
        return tpk_diag_fail(diag, "render: expected integration 0 (exact) or 1 (sampling), found %d",
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
    if (mesh->vertex_count > 0x7fffffffu || mesh->tet_count > 0x7fffffffu || mesh->shell_face_count > 0x7fffffffu)
        return tpk_diag_fail(diag, "render: more than 2^31 - 1 vertices, tets or shell faces");
    return 0;
}

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

/* The camera basis exactly as render_cpu.c's setup_camera, into the shader's parameters. */
static int set_camera(const tpk_render_options *opt, const double origin[3], tpk_vk_params *p, tpk_diag *diag)
{
    const tpk_camera *cam = &opt->camera;
    double forward[3], right[3], up[3];
    for (int k = 0; k < 3; k++) {
        if (!isfinite(cam->eye[k]) || !isfinite(cam->at[k]) || !isfinite(cam->up[k]))
            return tpk_diag_fail(diag, "render: camera eye, at and up must be finite");
        forward[k] = cam->at[k] - cam->eye[k];
        up[k] = cam->up[k];
    }
    normalize3(forward);
    if (forward[0] == 0 && forward[1] == 0 && forward[2] == 0)
        return tpk_diag_fail(diag, "render: camera eye and at are the same point");
    if (!(cam->fovy_deg > 0 && cam->fovy_deg < 180))
        return tpk_diag_fail(diag, "render: expected a field of view in (0, 180) degrees, found %g", cam->fovy_deg);
    cross3(forward, up, right);
    normalize3(right);
    if (right[0] == 0 && right[1] == 0 && right[2] == 0) {
        const double other[3] = {fabs(forward[0]) < 0.9 ? 1.0 : 0.0, fabs(forward[0]) < 0.9 ? 0.0 : 1.0, 0};
        cross3(forward, other, right);
        normalize3(right);
    }
    double true_up[3];
    cross3(right, forward, true_up);
    double tan_half_y = tan(0.5 * cam->fovy_deg * M_PI / 180.0);
    for (int k = 0; k < 3; k++) {
        p->eye[k] = (float)(cam->eye[k] - origin[k]);
        p->forward[k] = (float)forward[k];
        p->right[k] = (float)right[k];
        p->up[k] = (float)true_up[k];
    }
    p->forward[3] = (float)(tan_half_y * opt->width / opt->height);
    p->right[3] = (float)tan_half_y;
    return 0;
}

static double bbox_diagonal(const tpk_mesh_arrays *mesh)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < mesh->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->positions[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        if (hi[k] > lo[k])
            d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d2);
}

static int fill_params(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, const tpk_shell_bvh *bvh,
                       tpk_vk_params *p, tpk_diag *diag)
{
    memset(p, 0, sizeof *p);
    if (set_camera(opt, mesh->origin, p, diag) != 0)
        return -1;
    /* Boxes get 1e-5 of the reach on top of the builder's 1e-6 of the extent: the float slab test and
     * the float edge tests err by a few ulps of coordinates relative to the eye. */
    double reach = bvh->extent + fabs(p->eye[0]) + fabs(p->eye[1]) + fabs(p->eye[2]);
    p->up[3] = (float)(1e-5 * reach);
    memcpy(p->background, opt->background, sizeof p->background);
    p->scalar_map[0] = (float)opt->range_min;
    p->scalar_map[1] = opt->range_max != opt->range_min ? (float)(1.0 / (opt->range_max - opt->range_min)) : 0.0f;
    double unit = opt->unit_distance;
    if (!(unit > 0) || !isfinite(unit))
        unit = bbox_diagonal(mesh) / 100.0;
    p->scalar_map[2] = unit > 0 ? (float)(1.0 / unit) : 1.0f;
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
    p->shell_info[0] = (int32_t)bvh->face_count;
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

/* ---- Upload ------------------------------------------------------------------------------------- */

/* Positions and the point scalar, one float4 per vertex (the scalar slot is 0 without point scalars). */
static float *vertex_texels(const tpk_mesh_arrays *mesh)
{
    float *v = malloc((mesh->vertex_count ? mesh->vertex_count : 1) * 4 * sizeof *v);
    if (!v)
        return NULL;
    for (uint64_t i = 0; i < mesh->vertex_count; i++) {
        memcpy(&v[4 * i], &mesh->positions[3 * i], 3 * sizeof *v);
        v[4 * i + 3] = mesh->scalars ? mesh->scalars[i] : 0.0f;
    }
    return v;
}

/* BVH nodes as two uint4 texels each: lo and first, hi and count. */
static uint32_t *node_texels(const tpk_shell_bvh *bvh)
{
    uint32_t *t = malloc((bvh->node_count ? (size_t)bvh->node_count : 1) * 8 * sizeof *t);
    if (!t)
        return NULL;
    for (int64_t i = 0; i < bvh->node_count; i++) {
        const tpk_shell_bvh_node *n = &bvh->nodes[i];
        memcpy(&t[8 * i], n->lo, 3 * sizeof *t);
        memcpy(&t[8 * i + 3], &n->first, sizeof *t);
        memcpy(&t[8 * i + 4], n->hi, 3 * sizeof *t);
        memcpy(&t[8 * i + 7], &n->count, sizeof *t);
    }
    return t;
}

static int upload_tets(vk_render *v, const tpk_mesh_arrays *mesh, tpk_diag *diag)
{
    tpk_vk_array *a = &v->arrays[TPK_VK_ARRAY_TETS];
    switch (mesh->layout) {
    case TPK_LAYOUT_TET16:
        return tpk_vk_array_upload(&v->ctx, "Tet16 records", VK_FORMAT_R32G32B32A32_SINT, 16, mesh->tet16,
                                   mesh->tet_count, a, diag);
    case TPK_LAYOUT_TET20:
        return tpk_vk_array_upload(&v->ctx, "Tet20 records", VK_FORMAT_R32_SINT, 4, mesh->tet20,
                                   mesh->tet_count * TPK_VK_TET20_WORDS, a, diag);
    case TPK_LAYOUT_TET32:
        return tpk_vk_array_upload(&v->ctx, "Tet32 records", VK_FORMAT_R32G32B32A32_SINT, 16, mesh->tet32,
                                   mesh->tet_count * 2, a, diag);
    }
    return tpk_diag_fail(diag, "render: expected layout tet16, tet20 or tet32");
}

static int upload(vk_render *v, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                  const tpk_shell_bvh *bvh, tpk_diag *diag)
{
    float *verts = vertex_texels(mesh);
    uint32_t *nodes = node_texels(bvh);
    int rc = -1;
    if (!verts || !nodes) {
        tpk_diag_fail(diag, "render: out of memory");
        goto done;
    }
    if (tpk_vk_array_upload(&v->ctx, "positions and scalars", VK_FORMAT_R32G32B32A32_SFLOAT, 16, verts,
                            mesh->vertex_count, &v->arrays[TPK_VK_ARRAY_VERTS], diag) != 0 ||
        upload_tets(v, mesh, diag) != 0 ||
        tpk_vk_array_upload(&v->ctx, "shell faces", VK_FORMAT_R32G32B32A32_SINT, 16, bvh->faces,
                            (uint64_t)bvh->face_count, &v->arrays[TPK_VK_ARRAY_SHELL], diag) != 0 ||
        tpk_vk_array_upload(&v->ctx, "shell BVH", VK_FORMAT_R32G32B32A32_UINT, 16, nodes,
                            2 * (uint64_t)bvh->node_count, &v->arrays[TPK_VK_ARRAY_NODES], diag) != 0 ||
        tpk_vk_array_upload(&v->ctx, "tet scalars", VK_FORMAT_R32_SFLOAT, 4, opt->tet_scalars,
                            opt->tet_scalars ? mesh->tet_count : 0, &v->arrays[TPK_VK_ARRAY_TET_SCALARS], diag) != 0)
        goto done;
    rc = 0;
done:
    free(verts);
    free(nodes);
    return rc;
}

/* ---- Dispatch ----------------------------------------------------------------------------------- */

static int vk_check(VkResult r, const char *step, tpk_diag *diag)
{
    if (r == VK_SUCCESS)
        return 0;
    return tpk_diag_fail(diag, "vulkan: %s failed: %s", step, tpk_vk_result_name(r));
}

static int create_commands(vk_render *v, tpk_diag *diag)
{
    VkCommandPoolCreateInfo pool = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
        .queueFamilyIndex = v->ctx.queue_family,
    };
    if (vk_check(vkCreateCommandPool(v->ctx.device, &pool, NULL, &v->pool), "creating a command pool", diag))
        return -1;
    VkCommandBufferAllocateInfo alloc = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = v->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    VkFenceCreateInfo fence = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if (vk_check(vkAllocateCommandBuffers(v->ctx.device, &alloc, &v->cmd), "allocating a command buffer", diag) ||
        vk_check(vkCreateFence(v->ctx.device, &fence, NULL, &v->fence), "creating a fence", diag))
        return -1;
    return 0;
}

/* Render rows [row0, row0 + rows) into the band buffers and wait for them. */
static int run_band(vk_render *v, tpk_vk_params *params, int row0, int rows, tpk_diag *diag)
{
    params->dims[2] = row0;
    memcpy(v->params.mapped, params, sizeof *params);
    VkCommandBufferBeginInfo begin = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    if (vk_check(vkResetCommandBuffer(v->cmd, 0), "resetting the command buffer", diag) ||
        vk_check(vkBeginCommandBuffer(v->cmd, &begin), "recording commands", diag))
        return -1;
    vkCmdBindPipeline(v->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, v->pipeline.pipeline);
    vkCmdBindDescriptorSets(v->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, v->pipeline.layout, 0, 1, &v->pipeline.set, 0,
                            NULL);
    vkCmdDispatch(v->cmd, ((uint32_t)params->dims[0] + TPK_VK_GROUP - 1) / TPK_VK_GROUP,
                  ((uint32_t)rows + TPK_VK_GROUP - 1) / TPK_VK_GROUP, 1);
    VkMemoryBarrier to_host = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
        .srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT,
        .dstAccessMask = VK_ACCESS_HOST_READ_BIT,
    };
    vkCmdPipelineBarrier(v->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0,
                         NULL, 0, NULL);
    if (vk_check(vkEndCommandBuffer(v->cmd), "recording commands", diag))
        return -1;
    VkSubmitInfo submit = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &v->cmd};
    if (vk_check(vkResetFences(v->ctx.device, 1, &v->fence), "resetting a fence", diag) ||
        vk_check(vkQueueSubmit(v->ctx.queue, 1, &submit, v->fence), "submitting the render", diag) ||
        vk_check(vkWaitForFences(v->ctx.device, 1, &v->fence, VK_TRUE, UINT64_MAX), "waiting for the render", diag))
        return -1;
    return 0;
}

/* Copy a finished band out: pixels into rgba, steps summed; the first failed ray is an error. */
static int read_band(const vk_render *v, int width, int row0, int rows, uint8_t *rgba, uint64_t *steps,
                     tpk_diag *diag)
{
    size_t n = (size_t)width * (size_t)rows;
    const uint32_t *px = v->pixels.mapped;
    uint8_t *dst = rgba + 4 * (size_t)width * (size_t)row0;
    for (size_t i = 0; i < n; i++) {
        dst[4 * i + 0] = (uint8_t)(px[i] & 0xff);
        dst[4 * i + 1] = (uint8_t)((px[i] >> 8) & 0xff);
        dst[4 * i + 2] = (uint8_t)((px[i] >> 16) & 0xff);
        dst[4 * i + 3] = (uint8_t)(px[i] >> 24);
    }
    const uint32_t *st = v->steps.mapped;
    for (size_t i = 0; i < n; i++) {
        *steps += st[2 * i];
        if (st[2 * i + 1] != TPK_VK_STATUS_OK)
            return tpk_diag_fail(diag, "render: ray of pixel (%d, %d): %s", (int)(i % (size_t)width),
                                 row0 + (int)(i / (size_t)width), tpk_result_string(TPK_ERR_MESH));
    }
    return 0;
}

static int render_bands(vk_render *v, tpk_vk_params *params, uint8_t *rgba, uint64_t *steps, tpk_diag *diag)
{
    const int width = params->dims[0], height = params->dims[1];
    int band = (int)(BAND_PIXELS / (uint32_t)width);
    band = band < 1 ? 1 : band > height ? height : band;
    for (int row0 = 0; row0 < height; row0 += band) {
        int rows = height - row0 < band ? height - row0 : band;
        if (run_band(v, params, row0, rows, diag) != 0 || read_band(v, width, row0, rows, rgba, steps, diag) != 0)
            return -1;
    }
    return 0;
}

/* ---- Entry points ------------------------------------------------------------------------------- */

static int device_setup(vk_render *v, const tpk_mesh_arrays *mesh, const tpk_render_options *opt,
                        const tpk_shell_bvh *bvh, tpk_diag *diag)
{
    if (tpk_vk_context_create(&v->ctx, diag) != 0 || upload(v, mesh, opt, bvh, diag) != 0)
        return -1;
    uint32_t band = BAND_PIXELS / (uint32_t)opt->width;
    band = band < 1 ? 1 : band > (uint32_t)opt->height ? (uint32_t)opt->height : band;
    VkDeviceSize band_pixels = (VkDeviceSize)band * (VkDeviceSize)opt->width;
    if (tpk_vk_buffer_create(&v->ctx, sizeof(tpk_vk_params), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "render parameters",
                             &v->params, diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, band_pixels * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "the image",
                             &v->pixels, diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, band_pixels * 8, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "per-pixel statistics",
                             &v->steps, diag) != 0)
        return -1;
    if (tpk_vk_pipeline_create(&v->ctx, (int)mesh->layout, v->arrays, &v->params, &v->pixels, &v->steps,
                               &v->pipeline, diag) != 0)
        return -1;
    return create_commands(v, diag);
}

int tpk_render_vulkan(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                      tpk_render_stats *stats, tpk_diag *diag)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (check_options(mesh, opt, rgba, diag) != 0)
        return -1;
    tpk_marcher *marcher = NULL;
    tpk_result r = tpk_marcher_create(&marcher, mesh); /* validates the shell and builds its BVH */
    if (r != TPK_OK)
        return tpk_diag_fail(diag, "render: cannot set up the marcher: %s", tpk_result_string(r));
    tpk_shell_bvh bvh;
    tpk_marcher_shell_bvh(marcher, &bvh);
    tpk_vk_params *params = malloc(sizeof *params);
    vk_render *v = calloc(1, sizeof *v);
    uint64_t steps = 0;
    int rc = -1;
    if (!params || !v)
        tpk_diag_fail(diag, "render: out of memory");
    else if (fill_params(mesh, opt, &bvh, params, diag) == 0 && device_setup(v, mesh, opt, &bvh, diag) == 0)
        rc = render_bands(v, params, rgba, &steps, diag);
    if (v)
        vk_render_destroy(v);
    free(v);
    free(params);
    tpk_marcher_destroy(marcher);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (stats) {
        stats->rays = (uint64_t)opt->width * (uint64_t)opt->height;
        stats->tet_steps = steps;
        stats->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    }
    return rc;
}

int tpk_vulkan_available(char *why, size_t n)
{
    tpk_vk_context ctx;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int ok = tpk_vk_context_create(&ctx, &diag) == 0;
    if (why && n)
        snprintf(why, n, "%s", ok ? ctx.props.deviceName : diag.message);
    if (ok)
        tpk_vk_context_destroy(&ctx);
    return ok;
}
