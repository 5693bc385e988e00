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

/* Everything a renderer owns; zero means not created. */
struct tpk_vk_renderer {
    tpk_vk_context ctx;
    tpk_vk_array arrays[TPK_VK_ARRAY_COUNT];
    tpk_vk_buffer params, pixels, steps;
    tpk_vk_pipeline pipeline;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    tpk_marcher *marcher; /* owns the shell BVH that was uploaded */
    tpk_shell_bvh bvh;
    tpk_mesh_arrays mesh; /* the caller's arrays (not copied) */
    int tet_scalars;      /* tet scalars were uploaded */
};
typedef struct tpk_vk_renderer vk_render;

void tpk_vk_renderer_destroy(tpk_vk_renderer *v)
{
    if (!v)
        return;
    tpk_marcher_destroy(v->marcher);
    if (!v->ctx.device) {
        tpk_vk_context_destroy(&v->ctx);
        free(v);
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
    free(v);
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

static int upload(vk_render *v, const tpk_mesh_arrays *mesh, const float *tet_scalars, const tpk_shell_bvh *bvh,
                  tpk_diag *diag)
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
        tpk_vk_array_upload(&v->ctx, "tet scalars", VK_FORMAT_R32_SFLOAT, 4, tet_scalars,
                            tet_scalars ? mesh->tet_count : 0, &v->arrays[TPK_VK_ARRAY_TET_SCALARS], diag) != 0)
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
static int run_band(vk_render *v, VkPipeline pipeline, tpk_vk_params *params, int row0, int rows, tpk_diag *diag)
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
    vkCmdBindPipeline(v->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
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

/* Copy a finished band out: pixels into rgba, tet steps (counts[0]) and secondary rays (counts[1])
 * summed; the first failed ray is an error. */
static int read_band(const vk_render *v, int width, int row0, int rows, uint8_t *rgba, uint64_t counts[2],
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
        counts[0] += st[4 * i];
        counts[1] += st[4 * i + 2];
        if (st[4 * i + 1] != TPK_VK_STATUS_OK)
            return tpk_diag_fail(diag, "render: ray of pixel (%d, %d): %s", (int)(i % (size_t)width),
                                 row0 + (int)(i / (size_t)width), tpk_result_string(TPK_ERR_MESH));
    }
    return 0;
}

static int render_bands(vk_render *v, VkPipeline pipeline, tpk_vk_params *params, uint8_t *rgba,
                        uint64_t counts[2], tpk_diag *diag)
{
    const int width = params->dims[0], height = params->dims[1];
    int band = (int)(BAND_PIXELS / (uint32_t)width); /* width <= 32768: at least 32 rows */
    band = band < 1 ? 1 : band > height ? height : band;
    for (int row0 = 0; row0 < height; row0 += band) {
        int rows = height - row0 < band ? height - row0 : band;
        if (run_band(v, pipeline, params, row0, rows, diag) != 0 || read_band(v, width, row0, rows, rgba, counts, diag) != 0)
            return -1;
    }
    return 0;
}

/* What the renderer holds on the device: every array part and buffer it created (sizes as requested;
 * the driver may round each allocation up to its alignment). */
static uint64_t device_bytes(const vk_render *v)
{
    uint64_t total = (uint64_t)v->params.size + (uint64_t)v->pixels.size + (uint64_t)v->steps.size;
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++)
        for (int p = 0; p < v->arrays[a].part_count; p++)
            total += (uint64_t)v->arrays[a].parts[p].size;
    return total;
}

/* ---- Entry points ------------------------------------------------------------------------------- */

static int device_setup(vk_render *v, const tpk_mesh_arrays *mesh, const float *tet_scalars, tpk_diag *diag)
{
    if (tpk_vk_context_create(&v->ctx, diag) != 0 || upload(v, mesh, tet_scalars, &v->bvh, diag) != 0)
        return -1;
    if (tpk_vk_buffer_create(&v->ctx, sizeof(tpk_vk_params), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "render parameters",
                             &v->params, diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, (VkDeviceSize)BAND_PIXELS * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "the image",
                             &v->pixels, diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, (VkDeviceSize)BAND_PIXELS * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                             "per-pixel statistics", &v->steps, diag) != 0)
        return -1;
    if (tpk_vk_pipeline_create(&v->ctx, (int)mesh->layout, v->arrays, &v->params, &v->pixels, &v->steps,
                               &v->pipeline, diag) != 0)
        return -1;
    return create_commands(v, diag);
}

int tpk_vk_renderer_create(tpk_vk_renderer **out, const tpk_mesh_arrays *mesh, const float *tet_scalars,
                           tpk_diag *diag)
{
    *out = NULL;
    if (!mesh)
        return tpk_diag_fail(diag, "render: a mesh is required");
    if (mesh->vertex_count > 0x7fffffffu || mesh->tet_count > 0x7fffffffu || mesh->shell_face_count > 0x7fffffffu)
        return tpk_diag_fail(diag, "render: more than 2^31 - 1 vertices, tets or shell faces");
    vk_render *v = calloc(1, sizeof *v);
    if (!v)
        return tpk_diag_fail(diag, "render: out of memory");
    tpk_result r = tpk_marcher_create(&v->marcher, mesh); /* validates the shell and builds its BVH */
    if (r != TPK_OK) {
        tpk_vk_renderer_destroy(v);
        return tpk_diag_fail(diag, "render: cannot set up the marcher: %s", tpk_result_string(r));
    }
    tpk_marcher_shell_bvh(v->marcher, &v->bvh);
    v->mesh = *mesh;
    v->tet_scalars = tet_scalars != NULL;
    if (device_setup(v, mesh, tet_scalars, diag) != 0) {
        tpk_vk_renderer_destroy(v);
        return -1;
    }
    *out = v;
    return 0;
}

const char *tpk_vk_renderer_device(const tpk_vk_renderer *v)
{
    return v->ctx.props.deviceName;
}

int tpk_vk_renderer_frame(tpk_vk_renderer *v, const tpk_render_options *opt, uint8_t *rgba, tpk_render_stats *stats,
                          tpk_diag *diag)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (tpk_vk_check_options(&v->mesh, opt, rgba, diag) != 0)
        return -1;
    if ((opt->tet_scalars != NULL) != v->tet_scalars)
        return tpk_diag_fail(diag, "render: tet scalars %s at creation but %s for this frame",
                             v->tet_scalars ? "given" : "not given", opt->tet_scalars ? "given" : "not");
    tpk_vk_params *params = malloc(sizeof *params);
    if (!params)
        return tpk_diag_fail(diag, "render: out of memory");
    uint64_t counts[2] = {0, 0};
    int rc = tpk_vk_params_fill(&v->mesh, opt, v->bvh.extent, v->bvh.face_count, params, diag);
    VkPipeline pipeline = VK_NULL_HANDLE;
    if (rc == 0 && !(pipeline = tpk_vk_pipeline_get(&v->ctx, &v->pipeline, tpk_vk_effects(opt), diag)))
        rc = -1;
    if (rc == 0)
        rc = render_bands(v, pipeline, params, rgba, counts, diag);
    free(params);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (stats) {
        stats->rays = (uint64_t)opt->width * (uint64_t)opt->height;
        stats->tet_steps = counts[0];
        stats->secondary_rays = counts[1];
        stats->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        stats->device_bytes = device_bytes(v);
    }
    return rc;
}

int tpk_render_vulkan(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                      tpk_render_stats *stats, tpk_diag *diag)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (tpk_vk_check_options(mesh, opt, rgba, diag) != 0)
        return -1;
    tpk_vk_renderer *v = NULL;
    if (tpk_vk_renderer_create(&v, mesh, opt->tet_scalars, diag) != 0)
        return -1;
    int rc = tpk_vk_renderer_frame(v, opt, rgba, stats, diag);
    tpk_vk_renderer_destroy(v);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (stats) /* like the CPU reference's, the time includes the setup */
        stats->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
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
