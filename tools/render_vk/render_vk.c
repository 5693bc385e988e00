/* The Vulkan renderer's entry: checks the options as the CPU reference does, uploads the file's arrays
 * and the marcher's shell BVH, renders the image in bands of rows (one submission each, so that no
 * single submission runs long enough to trip a GPU watchdog), and reads pixels and tet steps back. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/parallel.h"
#include "render/render_backend.h"
#include "render_vk.h"
#include "render_vk_internal.h"

#define BAND_PIXELS (1u << 20) /* pixels per submission; TPK_VK_BAND_PIXELS overrides it (tests) */

/* Everything a renderer owns; zero means not created. */
struct tpk_vk_renderer {
    tpk_vk_context ctx;
    tpk_vk_array arrays[TPK_VK_ARRAY_COUNT];
    tpk_vk_buffer params;   /* device memory, written by each band's commands (vkCmdUpdateBuffer) */
    tpk_vk_buffer pixels;   /* the band's image: device memory, or host-visible on unified memory */
    tpk_vk_buffer counters; /* the band's statistics (TPK_VK_COUNT_*), as pixels */
    tpk_vk_buffer readback; /* staged: pixels then counters copied out, HOST_CACHED; else unused */
    tpk_vk_buffer state;    /* sliced: each pixel's ray between slices (a stand-in of 16 bytes else) */
    int sliced;             /* rays run in slices (tpk_vk_sliced) */
    tpk_vk_pipeline pipeline;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool timestamps; /* two per band; VK_NULL_HANDLE when the queue has none */
    uint32_t band_pixels;
    tpk_marcher *marcher; /* owns the shell BVH that was uploaded */
    tpk_shell_bvh bvh;
    tpk_mesh_arrays mesh; /* the caller's arrays (not copied) */
    double diagonal;      /* of the positions' box (tpk_positions_diagonal), once: a pass over every vertex
                           * took most of a frame's host time (bench/README, figures) */
    tpk_range_bvh *range; /* culled iso-only frames (render.h ISO-ONLY RAYS): made and uploaded on the
                             first (range_leaf_base > 0 from then on) */
    int64_t range_leaf_base;
    int tet_scalars;      /* tet scalars were uploaded */
    double device_seconds, upload_seconds, pipeline_seconds; /* setup, pipelines compiled so far included */
    double frame_compile_seconds; /* of the last frame, the pipeline compiled in it */
    const tpk_vk_band_target *target; /* during a presenting frame: where the bands go, not the host */
    /* --occlusion vertex: the cache kept across frames (render.h tpk_vertex_cache), uploaded when it changes */
    tpk_vertex_cache *cache;
};
typedef struct tpk_vk_renderer vk_render;

void tpk_vk_renderer_destroy(tpk_vk_renderer *v)
{
    if (!v)
        return;
    tpk_range_bvh_destroy(v->range);
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
    if (v->timestamps)
        vkDestroyQueryPool(v->ctx.device, v->timestamps, NULL);
    tpk_vk_pipeline_destroy(&v->ctx, &v->pipeline);
    tpk_vk_buffer_destroy(&v->ctx, &v->params);
    tpk_vk_buffer_destroy(&v->ctx, &v->pixels);
    tpk_vk_buffer_destroy(&v->ctx, &v->counters);
    tpk_vk_buffer_destroy(&v->ctx, &v->readback);
    tpk_vk_buffer_destroy(&v->ctx, &v->state);
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++)
        tpk_vk_array_destroy(&v->ctx, &v->arrays[a]);
    tpk_vk_context_destroy(&v->ctx);
    tpk_vertex_cache_destroy(v->cache);
    free(v);
}

/* ---- Upload ------------------------------------------------------------------------------------- */

/* Positions and the point scalar, one float4 per vertex (the scalar slot is 0 without point scalars),
 * made piece by piece into the staging slot or the mapped buffer. */
static void fill_vertices(void *dst, uint64_t first, uint64_t count, const void *user)
{
    const tpk_mesh_arrays *mesh = user;
    float *v = dst;
    for (uint64_t i = 0; i < count; i++) {
        memcpy(&v[4 * i], &mesh->positions[3 * (first + i)], 3 * sizeof *v);
        v[4 * i + 3] = mesh->scalars ? mesh->scalars[first + i] : 0.0f;
    }
}

/* BVH nodes as two uint4 texels each: lo and first, hi and count (a piece may start at either). */
static void fill_nodes(void *dst, uint64_t first, uint64_t count, const void *user)
{
    const tpk_shell_bvh *bvh = user;
    uint32_t *t = dst;
    for (uint64_t k = 0; k < count; k++) {
        const tpk_shell_bvh_node *n = &bvh->nodes[(first + k) / 2];
        int hi = (int)((first + k) & 1);
        memcpy(&t[4 * k], hi ? n->hi : n->lo, 3 * sizeof *t);
        memcpy(&t[4 * k + 3], hi ? (const void *)&n->count : (const void *)&n->first, sizeof *t);
    }
}

typedef struct upload_item {
    const char *what;
    VkFormat format;
    tpk_vk_source src;
    uint64_t texels;
} upload_item;

/* The file's arrays, the BVH and the tet scalars as texel arrays (TPK_VK_ARRAY_* order). */
static int upload_items(const tpk_mesh_arrays *mesh, const float *tet_scalars, const tpk_shell_bvh *bvh,
                        upload_item items[TPK_VK_ARRAY_COUNT], tpk_diag *diag)
{
    items[TPK_VK_ARRAY_VERTS] = (upload_item){"positions and scalars", VK_FORMAT_R32G32B32A32_SFLOAT,
                                              {NULL, 16, fill_vertices, mesh}, mesh->vertex_count};
    switch (mesh->layout) {
    case TPK_LAYOUT_TET16:
        items[TPK_VK_ARRAY_TETS] = (upload_item){"Tet16 records", VK_FORMAT_R32G32B32A32_SINT, {mesh->tet16, 16, NULL, NULL},
                                                 mesh->tet_count};
        break;
    case TPK_LAYOUT_TET20:
        items[TPK_VK_ARRAY_TETS] = (upload_item){"Tet20 records", VK_FORMAT_R32_SINT, {mesh->tet20, 4, NULL, NULL},
                                                 mesh->tet_count * TPK_VK_TET20_WORDS};
        break;
    case TPK_LAYOUT_TET32:
        items[TPK_VK_ARRAY_TETS] = (upload_item){"Tet32 records", VK_FORMAT_R32G32B32A32_SINT, {mesh->tet32, 16, NULL, NULL},
                                                 mesh->tet_count * 2};
        break;
    default:
        return tpk_diag_fail(diag, "render: expected layout tet16, tet20 or tet32");
    }
    items[TPK_VK_ARRAY_SHELL] = (upload_item){"shell faces", VK_FORMAT_R32G32B32A32_SINT, {bvh->faces, 16, NULL, NULL},
                                              (uint64_t)bvh->face_count};
    items[TPK_VK_ARRAY_NODES] = (upload_item){"shell BVH", VK_FORMAT_R32G32B32A32_UINT, {NULL, 16, fill_nodes, bvh},
                                              2 * (uint64_t)bvh->node_count};
    items[TPK_VK_ARRAY_TET_SCALARS] = (upload_item){"tet scalars", VK_FORMAT_R32_SFLOAT, {tet_scalars, 4, NULL, NULL},
                                                    tet_scalars ? mesh->tet_count : 0};
    /* zeros until a frame with --occlusion vertex fills it (vertex_cache below) */
    items[TPK_VK_ARRAY_VERTEX_SA] = (upload_item){"vertex occlusion cache", VK_FORMAT_R32G32_SFLOAT, {NULL, 8, NULL, NULL},
                                                  mesh->vertex_count};
    /* one zero texel each until a frame culls (range_upload below) */
    items[TPK_VK_ARRAY_RANGE_NODES] = (upload_item){"range BVH", VK_FORMAT_R32G32B32A32_SFLOAT, {NULL, 16, NULL, NULL}, 0};
    items[TPK_VK_ARRAY_RANGE_TETS] = (upload_item){"range BVH tets", VK_FORMAT_R32G32B32A32_SINT, {NULL, 16, NULL, NULL}, 0};
    return 0;
}

/* Every array to device memory: in place on unified memory, else through one bounded stager. */
static int upload(vk_render *v, const tpk_mesh_arrays *mesh, const float *tet_scalars, const tpk_shell_bvh *bvh,
                  tpk_diag *diag)
{
    upload_item items[TPK_VK_ARRAY_COUNT];
    if (upload_items(mesh, tet_scalars, bvh, items, diag) != 0)
        return -1;
    tpk_vk_stager stager;
    memset(&stager, 0, sizeof stager);
    uint64_t largest = 0;
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++) {
        uint64_t bytes = (items[a].texels ? items[a].texels : 1) * items[a].src.texel_size;
        largest = bytes > largest ? bytes : largest;
    }
    if (v->ctx.staged && tpk_vk_stager_create(&v->ctx, largest, &stager, diag) != 0)
        return -1;
    int rc = 0;
    for (int a = 0; a < TPK_VK_ARRAY_COUNT && rc == 0; a++)
        rc = tpk_vk_array_upload(&v->ctx, v->ctx.staged ? &stager : NULL, items[a].what, items[a].format, &items[a].src,
                                 items[a].texels, &v->arrays[a], diag);
    if (rc == 0 && v->ctx.staged)
        rc = tpk_vk_stager_finish(&v->ctx, &stager, diag);
    tpk_vk_stager_destroy(&v->ctx, &stager);
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
    v->timestamps = tpk_vk_timestamp_pool(&v->ctx); /* without one, frames report no GPU time */
    return 0;
}

static void barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stage, VkAccessFlags src,
                    VkPipelineStageFlags dst_stage, VkAccessFlags dst)
{
    VkMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER, .srcAccessMask = src, .dstAccessMask = dst};
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 1, &b, 0, NULL, 0, NULL);
}

/* A presenting frame's band: the pixels copied by the target's commands on the device, only the
 * counters to the host (copied into the readback buffer on a discrete GPU, read in place otherwise). */
static void record_band_to_target(vk_render *v, const tpk_vk_params *params, int rows)
{
    VkCommandBuffer cmd = v->cmd;
    barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
            VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_HOST_BIT,
            VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_HOST_READ_BIT);
    v->target->record(cmd, v->pixels.buffer, params->dims[0], params->dims[2], rows, v->target->user);
    if (!v->ctx.staged)
        return;
    VkBufferCopy counts = {0, (VkDeviceSize)v->band_pixels * 4, TPK_VK_COUNT_WORDS * 4};
    vkCmdCopyBuffer(cmd, v->counters.buffer, v->readback.buffer, 1, &counts);
    barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
            VK_ACCESS_HOST_READ_BIT);
}

/* The commands of one band: parameters and zeroed counters written by the queue itself (so the
 * uniform block lives in device memory), the dispatch between two timestamps, and on a discrete GPU the
 * band's pixels and counters copied into the HOST_CACHED readback buffer. */
static void record_band(vk_render *v, VkPipeline pipeline, const tpk_vk_params *params, int rows)
{
    static const uint32_t zero_counts[TPK_VK_COUNT_WORDS] = {[TPK_VK_COUNT_FIRST] = 0xffffffffu};
    VkCommandBuffer cmd = v->cmd;
    vkCmdUpdateBuffer(cmd, v->params.buffer, 0, sizeof *params, params);
    if (params->cast_count[2] == 0) /* a later slice adds to the band's sums: only its pending count starts at 0 */
        vkCmdUpdateBuffer(cmd, v->counters.buffer, 0, sizeof zero_counts, zero_counts);
    else
        vkCmdUpdateBuffer(cmd, v->counters.buffer, 4 * TPK_VK_COUNT_PENDING, 4, &zero_counts[TPK_VK_COUNT_PENDING]);
    /* also orders the uploads' copies (earlier submissions) before the shader's reads */
    barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
            VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    if (v->timestamps) {
        vkCmdResetQueryPool(cmd, v->timestamps, 0, 2);
        vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, v->timestamps, 0);
    }
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, v->pipeline.layout, 0, 1, &v->pipeline.set, 0, NULL);
    vkCmdDispatch(cmd, ((uint32_t)params->dims[0] + TPK_VK_GROUP - 1) / TPK_VK_GROUP,
                  ((uint32_t)rows + TPK_VK_GROUP - 1) / TPK_VK_GROUP, 1);
    if (v->timestamps)
        vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, v->timestamps, 1);
    if (v->target) {
        record_band_to_target(v, params, rows);
        return;
    }
    if (!v->ctx.staged) { /* the host reads pixels and counters where the shader wrote them */
        barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                VK_ACCESS_HOST_READ_BIT);
        return;
    }
    barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
            VK_ACCESS_TRANSFER_READ_BIT);
    VkBufferCopy image = {0, 0, (VkDeviceSize)params->dims[0] * (VkDeviceSize)rows * 4};
    VkBufferCopy counts = {0, (VkDeviceSize)v->band_pixels * 4, TPK_VK_COUNT_WORDS * 4};
    vkCmdCopyBuffer(cmd, v->pixels.buffer, v->readback.buffer, 1, &image);
    vkCmdCopyBuffer(cmd, v->counters.buffer, v->readback.buffer, 1, &counts);
    barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
            VK_ACCESS_HOST_READ_BIT);
}

/* The band's statistics as the host reads them (after tpk_vk_buffer_invalidate of band_counters_buffer). */
static const tpk_vk_buffer *band_counters_buffer(const vk_render *v)
{
    return v->ctx.staged ? &v->readback : &v->counters;
}

static const uint32_t *band_counters(const vk_render *v)
{
    return v->ctx.staged ? (const uint32_t *)((const char *)v->readback.mapped + (size_t)v->band_pixels * 4)
                         : (const uint32_t *)v->counters.mapped;
}

static int run_slice(vk_render *v, VkPipeline pipeline, tpk_vk_params *params, int rows, double *gpu_seconds,
                     tpk_diag *diag);

/* Render rows [row0, row0 + rows) and wait for them, in slices until no ray is pending (sliced) or in
 * one dispatch; *gpu_seconds += the dispatches' device time. */
static int run_band(vk_render *v, VkPipeline pipeline, tpk_vk_params *params, int row0, int rows, double *gpu_seconds,
                    tpk_diag *diag)
{
    params->dims[2] = row0;
    params->cast_count[1] = row0 + rows;
    for (int slice = 0;; slice++) {
        params->cast_count[2] = slice;
        if (run_slice(v, pipeline, params, rows, gpu_seconds, diag) != 0)
            return -1;
        if (!v->sliced)
            return 0;
        if (tpk_vk_buffer_invalidate(&v->ctx, band_counters_buffer(v), diag) != 0)
            return -1;
        if (band_counters(v)[TPK_VK_COUNT_PENDING] == 0)
            return 0;
    }
}

static int run_slice(vk_render *v, VkPipeline pipeline, tpk_vk_params *params, int rows, double *gpu_seconds,
                     tpk_diag *diag)
{
    VkCommandBufferBeginInfo begin = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    if (vk_check(vkResetCommandBuffer(v->cmd, 0), "resetting the command buffer", diag) ||
        vk_check(vkBeginCommandBuffer(v->cmd, &begin), "recording commands", diag))
        return -1;
    record_band(v, pipeline, params, rows);
    if (vk_check(vkEndCommandBuffer(v->cmd), "recording commands", diag))
        return -1;
    VkSubmitInfo submit = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &v->cmd};
    if (vk_check(vkResetFences(v->ctx.device, 1, &v->fence), "resetting a fence", diag) ||
        vk_check(vkQueueSubmit(v->ctx.queue, 1, &submit, v->fence), "submitting the render", diag) ||
        vk_check(vkWaitForFences(v->ctx.device, 1, &v->fence, VK_TRUE, UINT64_MAX), "waiting for the render", diag))
        return -1;
    double elapsed = tpk_vk_timestamp_seconds(&v->ctx, v->timestamps);
    if (elapsed >= 0)
        *gpu_seconds += elapsed;
    else
        *gpu_seconds = -1.0;
    return 0;
}

/* Copy a finished band out: pixels into rgba (none when NULL: a presenting frame), tet steps
 * (counts[0]) and secondary rays (counts[1]) added; a failed ray is an error naming the first such pixel. */
static int read_band(const vk_render *v, int width, int row0, int rows, uint8_t *rgba, uint64_t counts[2],
                     tpk_diag *diag)
{
    const tpk_vk_buffer *image = v->ctx.staged ? &v->readback : &v->pixels;
    if ((rgba && tpk_vk_buffer_invalidate(&v->ctx, image, diag) != 0) ||
        ((!rgba || !v->ctx.staged) && tpk_vk_buffer_invalidate(&v->ctx, band_counters_buffer(v), diag) != 0))
        return -1;
    size_t n = rgba ? (size_t)width * (size_t)rows : 0;
    const uint32_t *px = image->mapped;
    uint8_t *dst = rgba ? rgba + 4 * (size_t)width * (size_t)row0 : NULL;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    if (n)
        memcpy(dst, px, 4 * n); /* r | g << 8 | b << 16 | a << 24 is r, g, b, a in memory */
#else
    for (size_t i = 0; i < n; i++) {
        dst[4 * i + 0] = (uint8_t)(px[i] & 0xff);
        dst[4 * i + 1] = (uint8_t)((px[i] >> 8) & 0xff);
        dst[4 * i + 2] = (uint8_t)((px[i] >> 16) & 0xff);
        dst[4 * i + 3] = (uint8_t)(px[i] >> 24);
    }
#endif
    const uint32_t *c = band_counters(v);
    counts[0] += (uint64_t)c[TPK_VK_COUNT_STEPS] | (uint64_t)c[TPK_VK_COUNT_STEPS + 1] << 32;
    counts[1] += (uint64_t)c[TPK_VK_COUNT_SECONDARY] | (uint64_t)c[TPK_VK_COUNT_SECONDARY + 1] << 32;
    if (c[TPK_VK_COUNT_FAILED] != 0) {
        uint32_t first = c[TPK_VK_COUNT_FIRST];
        return tpk_diag_fail(diag, "render: ray of pixel (%d, %d): %s", (int)(first % (uint32_t)width),
                             row0 + (int)(first / (uint32_t)width), tpk_result_string(TPK_ERR_MESH));
    }
    return 0;
}

static int render_bands(vk_render *v, VkPipeline pipeline, tpk_vk_params *params, uint8_t *rgba, uint64_t counts[2],
                        double *gpu_seconds, tpk_diag *diag)
{
    const int width = params->dims[0], height = params->dims[1];
    int band = (int)(v->band_pixels / (uint32_t)width); /* width <= 32768: at least 32 rows by default */
    band = band < 1 ? 1 : band > height ? height : band;
    *gpu_seconds = v->timestamps ? 0.0 : -1.0;
    for (int row0 = 0; row0 < height; row0 += band) {
        int rows = height - row0 < band ? height - row0 : band;
        double gpu = 0.0;
        if (run_band(v, pipeline, params, row0, rows, &gpu, diag) != 0 ||
            read_band(v, width, row0, rows, rgba, counts, diag) != 0)
            return -1;
        *gpu_seconds = *gpu_seconds < 0 || gpu < 0 ? -1.0 : *gpu_seconds + gpu;
    }
    return 0;
}

/* What the renderer holds in device memory: every array part, the image band, counters and
 * parameters (sizes as requested; the driver may round each allocation up to its alignment). The
 * readback buffer is host memory and not counted. */
static uint64_t device_bytes(const vk_render *v)
{
    uint64_t total =
        (uint64_t)v->params.size + (uint64_t)v->pixels.size + (uint64_t)v->counters.size + (uint64_t)v->state.size;
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++)
        for (int p = 0; p < v->arrays[a].part_count; p++)
            total += (uint64_t)v->arrays[a].parts[p].size;
    return total;
}

/* ---- Entry points ------------------------------------------------------------------------------- */

/* The band buffers: in device memory with a HOST_CACHED readback buffer beside them on a discrete GPU;
 * host-visible (cached where the device has it) and read in place on unified memory. */
static int create_band_buffers(vk_render *v, tpk_diag *diag)
{
    const char *env = getenv("TPK_VK_BAND_PIXELS");
    v->sliced = tpk_vk_sliced(&v->ctx);
    v->band_pixels = env && atoi(env) > 0 ? (uint32_t)atoi(env) : v->sliced ? TPK_VK_SLICED_BAND_PIXELS : BAND_PIXELS;
    const VkBufferUsageFlags storage =
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    const tpk_vk_memory_use band_use = v->ctx.staged ? TPK_VK_MEMORY_DEVICE : TPK_VK_MEMORY_READBACK;
    if (tpk_vk_buffer_create(&v->ctx, sizeof(tpk_vk_params),
                             VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             TPK_VK_MEMORY_DEVICE, "render parameters", &v->params, diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, (VkDeviceSize)v->band_pixels * 4, storage, band_use, "the image", &v->pixels,
                             diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, TPK_VK_COUNT_WORDS * 4, storage, band_use, "render statistics", &v->counters,
                             diag) != 0 ||
        tpk_vk_buffer_create(&v->ctx, v->sliced ? (VkDeviceSize)v->band_pixels * TPK_VK_STATE_VEC4 * 16 : 16,
                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, TPK_VK_MEMORY_DEVICE, "the rays between slices",
                             &v->state, diag) != 0)
        return -1;
    if (v->ctx.staged)
        return tpk_vk_buffer_create(&v->ctx, (VkDeviceSize)v->band_pixels * 4 + TPK_VK_COUNT_WORDS * 4,
                                    VK_BUFFER_USAGE_TRANSFER_DST_BIT, TPK_VK_MEMORY_READBACK, "the image read-back",
                                    &v->readback, diag) != 0 || !v->readback.mapped
                   ? tpk_diag_fail(diag, "vulkan: no host-visible memory for the image read-back")
                   : 0;
    if (!v->pixels.mapped || !v->counters.mapped)
        return tpk_diag_fail(diag, "vulkan: the image memory is not host-visible");
    return 0;
}

static int device_setup(vk_render *v, const tpk_mesh_arrays *mesh, const float *tet_scalars,
                        const tpk_vk_surface_source *surface, tpk_diag *diag)
{
    double t0 = tpk_now_seconds();
    if (tpk_vk_context_create_presenting(&v->ctx, surface, diag) != 0)
        return -1;
    double t1 = tpk_now_seconds();
    v->device_seconds = t1 - t0;
    if (upload(v, mesh, tet_scalars, &v->bvh, diag) != 0 || create_band_buffers(v, diag) != 0)
        return -1;
    double t2 = tpk_now_seconds();
    v->upload_seconds = t2 - t1;
    if (tpk_vk_pipeline_create(&v->ctx, (int)mesh->layout, v->arrays, &v->params, &v->pixels, &v->counters,
                               &v->state, &v->pipeline, diag) != 0)
        return -1;
    v->pipeline_seconds = tpk_now_seconds() - t2;
    return create_commands(v, diag);
}

int tpk_vk_renderer_create(tpk_vk_renderer **out, const tpk_mesh_arrays *mesh, const float *tet_scalars,
                           tpk_diag *diag)
{
    return tpk_vk_renderer_create_presenting(out, mesh, tet_scalars, NULL, diag);
}

int tpk_vk_renderer_create_presenting(tpk_vk_renderer **out, const tpk_mesh_arrays *mesh, const float *tet_scalars,
                                      const tpk_vk_surface_source *surface, tpk_diag *diag)
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
    v->diagonal = tpk_positions_diagonal(mesh);
    v->tet_scalars = tet_scalars != NULL;
    if (device_setup(v, mesh, tet_scalars, surface, diag) != 0) {
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

const tpk_vk_context *tpk_vk_renderer_context(const tpk_vk_renderer *v)
{
    return &v->ctx;
}

/* The pipeline of these effects; its compile time (when made now) counts as pipeline setup. */
static VkPipeline frame_pipeline(vk_render *v, int effects, tpk_diag *diag)
{
    double t0 = tpk_now_seconds();
    VkPipeline pipeline = tpk_vk_pipeline_get(&v->ctx, &v->pipeline, effects, diag);
    v->frame_compile_seconds = tpk_now_seconds() - t0;
    v->pipeline_seconds += v->frame_compile_seconds;
    return pipeline;
}

#define CAST_ROW 1024 /* vertices per row of the vertex casts' bands (2 words each) */

/* render.h OCCLUSION AT VERTICES on the device (a tpk_vertex_caster): S_v and A_v of every vertex by the
 * shader's vertex_cast (TPK_VK_EFFECT_CACHE), CAST_ROW vertices a row, in bands (and slices) as a frame's
 * rows, read back into s and a. The casts are the frame's shade-point casts started at the vertex, in float:
 * render_vk_effects.vertex_casts_on_device says how near the CPU's double they come. */
static int device_vertex_casts(void *user, const tpk_mesh_arrays *mesh, const tpk_render_options *opt, float *s,
                               float *a, tpk_render_stats *stats, tpk_diag *diag)
{
    vk_render *v = user;
    double t0 = tpk_now_seconds();
    memset(stats, 0, sizeof *stats);
    const int64_t n = (int64_t)mesh->vertex_count;
    const int effects = TPK_VK_EFFECT_CACHE | (opt->iso_count > 0 ? TPK_VK_EFFECT_ISO : 0) |
                        (opt->shadows ? TPK_VK_EFFECT_SHADOWS : 0) | (opt->ao_rays > 0 ? TPK_VK_EFFECT_AO : 0);
    if (!(effects & (TPK_VK_EFFECT_SHADOWS | TPK_VK_EFFECT_AO))) {
        for (int64_t i = 0; i < n; i++)
            s[i] = a[i] = 1.0f;
        return 0;
    }
    tpk_vk_params *params = malloc(sizeof *params);
    if (!params)
        return tpk_diag_fail(diag, "render: out of memory");
    VkPipeline pipeline = VK_NULL_HANDLE;
    const double compiled = v->frame_compile_seconds; /* the frame's own pipeline, compiled before */
    int rc = tpk_vk_params_fill(mesh, opt, v->diagonal, v->bvh.extent, v->bvh.face_count, params, diag);
    if (rc == 0 && !(pipeline = frame_pipeline(v, effects, diag)))
        rc = -1;
    t0 += v->frame_compile_seconds; /* the compile is the pipeline's setup, not the casts' */
    v->frame_compile_seconds += compiled;
    const int width = 2 * CAST_ROW, height = (int)((n + CAST_ROW - 1) / CAST_ROW);
    int band = (int)(v->band_pixels / (uint32_t)width);
    band = band < 1 ? 1 : band;
    double gpu = v->timestamps ? 0.0 : -1.0;
    uint64_t counts[2] = {0, 0};
    params->dims[0] = width;
    params->dims[1] = height;
    for (int row0 = 0; rc == 0 && row0 < height; row0 += band) {
        const int rows = height - row0 < band ? height - row0 : band;
        double g = 0.0;
        const tpk_vk_buffer *image = v->ctx.staged ? &v->readback : &v->pixels;
        if (run_band(v, pipeline, params, row0, rows, &g, diag) != 0 ||
            tpk_vk_buffer_invalidate(&v->ctx, image, diag) != 0 ||
            (!v->ctx.staged && tpk_vk_buffer_invalidate(&v->ctx, band_counters_buffer(v), diag) != 0)) {
            rc = -1;
            break;
        }
        gpu = gpu < 0 || g < 0 ? -1.0 : gpu + g;
        const uint32_t *words = image->mapped, *c = band_counters(v);
        const int64_t first = (int64_t)row0 * CAST_ROW;
        const int64_t last = first + (int64_t)rows * CAST_ROW < n ? first + (int64_t)rows * CAST_ROW : n;
        for (int64_t i = first; i < last; i++) {
            memcpy(&s[i], &words[2 * (i - first)], 4); /* row r's vertex j at words 2 (r width / 2 + j) */
            memcpy(&a[i], &words[2 * (i - first) + 1], 4);
        }
        counts[0] += (uint64_t)c[TPK_VK_COUNT_STEPS] | (uint64_t)c[TPK_VK_COUNT_STEPS + 1] << 32;
        counts[1] += (uint64_t)c[TPK_VK_COUNT_SECONDARY] | (uint64_t)c[TPK_VK_COUNT_SECONDARY + 1] << 32;
        if (c[TPK_VK_COUNT_FAILED] != 0)
            rc = tpk_diag_fail(diag, "render: vertex cache: a ray from vertex %u: %s", c[TPK_VK_COUNT_FIRST],
                               tpk_result_string(TPK_ERR_MESH));
    }
    free(params);
    stats->tet_steps = counts[0];
    stats->secondary_rays = counts[1];
    stats->seconds = tpk_now_seconds() - t0;
    stats->gpu_seconds = gpu;
    return rc;
}

/* render.h OCCLUSION AT VERTICES: S_v and A_v of every vertex, cast on the device (device_vertex_casts)
 * through the cache kept across frames (tpk_vertex_cache: a half whose inputs did not change is not cast
 * again), uploaded into the VERTEX_SA array when it changed; the shader interpolates them at each shade
 * point as render_light.c does. The rays and steps cast in this frame count into the frame's (all of them
 * the first time, as on the CPU), their device time into *cast_gpu (-1: no timestamps) and their time
 * into *cast_seconds. TPK_VK_VERTEX_CASTS=cpu casts them by the CPU reference's pass instead (on all
 * cores), to compare. */
static int vertex_cache(vk_render *v, const tpk_render_options *opt, uint64_t counts[2], double *cast_gpu,
                        double *cast_seconds, tpk_diag *diag)
{
    size_t n = (size_t)v->mesh.vertex_count;
    *cast_gpu = 0.0;
    *cast_seconds = 0.0;
    if (!v->cache && !(v->cache = tpk_vertex_cache_create()))
        return tpk_diag_fail(diag, "render: out of memory for the vertex cache");
    tpk_render_options cpu = *opt;
    cpu.threads = 0; /* all cores */
    tpk_render_stats st;
    int changed = 0;
    const char *env = getenv("TPK_VK_VERTEX_CASTS");
    const int on_cpu = env && !strcmp(env, "cpu");
    if ((on_cpu ? tpk_vertex_cache_update(v->cache, &v->mesh, &cpu, &changed, &st, diag)
                : tpk_vertex_cache_update_with(v->cache, &v->mesh, &cpu, device_vertex_casts, v, &changed, &st,
                                               diag)) != 0)
        return -1;
    counts[0] += st.tet_steps;
    counts[1] += st.secondary_rays;
    *cast_gpu = on_cpu ? 0.0 : st.gpu_seconds;
    *cast_seconds = st.seconds;
    if (!changed)
        return 0;
    const float *s = tpk_vertex_cache_s(v->cache), *a = tpk_vertex_cache_a(v->cache);
    float *sa = malloc(2 * sizeof *sa * (n ? n : 1)); /* interleaved, as VERTEX_SA holds them */
    if (!sa)
        return tpk_diag_fail(diag, "render: out of memory for the vertex cache");
    for (size_t i = 0; i < n; i++)
        sa[2 * i] = s[i], sa[2 * i + 1] = a[i];
    tpk_vk_source src = {sa, 8, NULL, NULL};
    tpk_vk_stager stager;
    memset(&stager, 0, sizeof stager);
    int rc = 0;
    if (v->ctx.staged && tpk_vk_stager_create(&v->ctx, 8 * (uint64_t)(n ? n : 1), &stager, diag) != 0)
        rc = -1;
    if (rc == 0)
        rc = tpk_vk_array_refill(&v->ctx, v->ctx.staged ? &stager : NULL, &src, n, &v->arrays[TPK_VK_ARRAY_VERTEX_SA],
                                 diag);
    if (rc == 0 && v->ctx.staged)
        rc = tpk_vk_stager_finish(&v->ctx, &stager, diag);
    tpk_vk_stager_destroy(&v->ctx, &stager);
    free(sa);
    if (rc != 0) { /* the device holds neither: cast both again next time */
        tpk_vertex_cache_destroy(v->cache);
        v->cache = NULL;
    }
    return rc;
}

/* The range BVH's heap nodes and tets into the RANGE arrays, bound anew (their placeholders go). */
static int range_upload(vk_render *v, tpk_diag *diag)
{
    if (!tpk_vk_tet_faces_match())
        return tpk_diag_fail(diag, "vulkan: the shader's tet faces are not the format's");
    int64_t base = tpk_range_bvh_heap(v->range, NULL);
    float *nodes = malloc(sizeof *nodes * 16 * (size_t)base);
    if (!nodes)
        return tpk_diag_fail(diag, "render: out of memory for the range BVH");
    tpk_range_bvh_heap(v->range, nodes);
    const tpk_vk_source sources[2] = {{nodes, 16, NULL, NULL}, {tpk_range_bvh_tets(v->range), 16, NULL, NULL}};
    const uint64_t texels[2] = {4 * (uint64_t)base, v->mesh.tet_count}; /* 2 texels per node, nodes 0 .. 2 base */
    const int ids[2] = {TPK_VK_ARRAY_RANGE_NODES, TPK_VK_ARRAY_RANGE_TETS};
    const VkFormat formats[2] = {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SINT};
    const char *what[2] = {"range BVH", "range BVH tets"};
    tpk_vk_stager stager;
    memset(&stager, 0, sizeof stager);
    uint64_t largest = 16 * (texels[0] > texels[1] ? texels[0] : texels[1]);
    int rc = v->ctx.staged ? tpk_vk_stager_create(&v->ctx, largest ? largest : 16, &stager, diag) : 0;
    for (int i = 0; i < 2 && rc == 0; i++) {
        tpk_vk_array fresh;
        memset(&fresh, 0, sizeof fresh);
        rc = tpk_vk_array_upload(&v->ctx, v->ctx.staged ? &stager : NULL, what[i], formats[i], &sources[i], texels[i],
                                 &fresh, diag);
        if (rc == 0 && (rc = tpk_vk_pipeline_rebind(&v->ctx, &v->pipeline, ids[i], &fresh, diag)) == 0) {
            tpk_vk_array_destroy(&v->ctx, &v->arrays[ids[i]]);
            v->arrays[ids[i]] = fresh;
        } else
            tpk_vk_array_destroy(&v->ctx, &fresh);
    }
    if (rc == 0 && v->ctx.staged)
        rc = tpk_vk_stager_finish(&v->ctx, &stager, diag);
    tpk_vk_stager_destroy(&v->ctx, &stager);
    free(nodes);
    if (rc == 0)
        v->range_leaf_base = base;
    return rc;
}

/* Whether this frame's primary rays cull (render.h ISO-ONLY RAYS): only when TETPACK_ISO_CULLING=1 asks
 * (then 1 with the range BVH uploaded, or -1 with a message); else 0, on every device. The walk of the
 * tree in the shader never paid where it was measured, on an NVIDIA H200 and on lavapipe, at dense and
 * sparse values (bench/README "Figures behind code comments", and the first GPU run). */
static int frame_culls(vk_render *v, const tpk_render_options *opt, tpk_diag *diag)
{
    if (tpk_render_culling_wanted() != 1 || !tpk_render_iso_only(opt, v->mesh.scalars != NULL))
        return 0;
    if (!v->range) {
        tpk_result r = tpk_range_bvh_create_threads(&v->range, v->marcher, tpk_thread_count(0));
        if (r != TPK_OK)
            return tpk_diag_fail(diag, "render: cannot set up the range culling of iso rays: %s", tpk_result_string(r));
    }
    if (v->range_leaf_base == 0 && range_upload(v, diag) != 0)
        return -1;
    return 1;
}

/* One frame into rgba, or into `target` (rgba NULL) on the device. */
static int render_frame(vk_render *v, const tpk_render_options *opt, uint8_t *rgba, const tpk_vk_band_target *target,
                        tpk_render_stats *stats, tpk_diag *diag)
{
    static const uint8_t no_image[1]; /* the image goes to the target: the check's buffer argument is moot */
    double t0 = tpk_now_seconds(), gpu_seconds = -1.0;
    v->frame_compile_seconds = 0.0;
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (tpk_vk_check_options(&v->mesh, opt, target ? no_image : rgba, diag) != 0)
        return -1;
    if ((opt->tet_scalars != NULL) != v->tet_scalars)
        return tpk_diag_fail(diag, "render: tet scalars %s at creation but %s for this frame",
                             v->tet_scalars ? "given" : "not given", opt->tet_scalars ? "given" : "not");
    tpk_vk_params *params = malloc(sizeof *params);
    if (!params)
        return tpk_diag_fail(diag, "render: out of memory");
    uint64_t counts[2] = {0, 0};
    int rc = tpk_vk_params_fill(&v->mesh, opt, v->diagonal, v->bvh.extent, v->bvh.face_count, params, diag);
    int culls = rc == 0 ? frame_culls(v, opt, diag) : 0;
    if (culls < 0)
        rc = -1;
    else if (culls)
        params->shell_info[2] = (int32_t)v->range_leaf_base;
    VkPipeline pipeline = VK_NULL_HANDLE;
    if (rc == 0 && !(pipeline = frame_pipeline(v, tpk_vk_effects(opt) | (culls > 0 ? TPK_VK_EFFECT_CULL : 0), diag)))
        rc = -1;
    uint64_t cache_counts[2] = {0, 0};
    double cast_gpu = 0.0, cast_seconds = 0.0;
    if (rc == 0 && (tpk_vk_effects(opt) & TPK_VK_EFFECT_VERTEX))
        rc = vertex_cache(v, opt, cache_counts, &cast_gpu, &cast_seconds, diag);
    v->target = target;
    if (rc == 0)
        rc = render_bands(v, pipeline, params, target ? NULL : rgba, counts, &gpu_seconds, diag);
    gpu_seconds = gpu_seconds < 0 || cast_gpu < 0 ? -1.0 : gpu_seconds + cast_gpu; /* the casts are the frame's */
    counts[0] += cache_counts[0];
    counts[1] += cache_counts[1];
    v->target = NULL;
    free(params);
    if (stats) {
        stats->rays = (uint64_t)opt->width * (uint64_t)opt->height;
        stats->tet_steps = counts[0];
        stats->secondary_rays = counts[1];
        stats->iso_culling = culls > 0;
        stats->seconds = tpk_now_seconds() - t0;
        stats->gpu_seconds = gpu_seconds;
        stats->vertex_cache_seconds = cast_gpu > 0 ? cast_gpu : cast_seconds;
        stats->device_bytes = device_bytes(v);
        stats->setup_device_seconds = v->device_seconds;
        stats->setup_upload_seconds = v->upload_seconds;
        stats->setup_pipeline_seconds = v->pipeline_seconds;
        stats->pipeline_cache_bytes = v->pipeline.cache.loaded_bytes;
        stats->pipeline_cache_hits = v->pipeline.cache.hits;
    }
    return rc;
}

int tpk_vk_renderer_vertex_cache(tpk_vk_renderer *v, const tpk_render_options *opt, float *s, float *a,
                                 tpk_render_stats *stats, tpk_diag *diag)
{
    static const uint8_t no_image[1]; /* no picture: the check's buffer argument is moot */
    tpk_render_stats own;
    if (!v || !s || !a)
        return tpk_diag_fail(diag, "render: a renderer and the cache's arrays are required");
    if (tpk_vk_check_options(&v->mesh, opt, no_image, diag) != 0)
        return -1;
    if ((opt->tet_scalars != NULL) != v->tet_scalars)
        return tpk_diag_fail(diag, "render: tet scalars %s at creation but %s for the cache",
                             v->tet_scalars ? "given" : "not given", opt->tet_scalars ? "given" : "not");
    return device_vertex_casts(v, &v->mesh, opt, s, a, stats ? stats : &own, diag);
}

int tpk_vk_renderer_frame(tpk_vk_renderer *v, const tpk_render_options *opt, uint8_t *rgba, tpk_render_stats *stats,
                          tpk_diag *diag)
{
    return render_frame(v, opt, rgba, NULL, stats, diag);
}

int tpk_vk_renderer_frame_to(tpk_vk_renderer *v, const tpk_render_options *opt, const tpk_vk_band_target *target,
                             tpk_render_stats *stats, tpk_diag *diag)
{
    if (!v || !target)
        return tpk_diag_fail(diag, "render: a renderer and a target are required");
    return render_frame(v, opt, NULL, target, stats, diag);
}

int tpk_vk_renderer_set_field(tpk_vk_renderer *v, const float *scalars, const float *tet_scalars, tpk_diag *diag)
{
    if (!v)
        return tpk_diag_fail(diag, "render: a renderer is required");
    if ((scalars != NULL) != (v->mesh.scalars != NULL) || (tet_scalars != NULL) != v->tet_scalars)
        return tpk_diag_fail(diag, "render: another field must be of the same kind (point or tet) as the renderer's");
    v->mesh.scalars = scalars;
    tpk_marcher_set_scalars(v->marcher, scalars);
    /* The range tree reads the new field's ranges, keeping the tets' vertices and boxes (no walk again).
     * Once uploaded, a culling pipeline reads it: the new ranges go into the same array (the tree's shape
     * depends on the tet count alone). */
    float *nodes = NULL;
    int64_t base = 0;
    if (v->range && (!scalars || tpk_range_bvh_set_scalars(v->range) != TPK_OK)) {
        tpk_range_bvh_destroy(v->range);
        v->range = NULL;
    }
    if (v->range_leaf_base > 0) {
        tpk_result r = v->range ? TPK_OK : tpk_range_bvh_create_threads(&v->range, v->marcher, tpk_thread_count(0));
        if (r != TPK_OK)
            return tpk_diag_fail(diag, "render: cannot set up the range culling of iso rays: %s", tpk_result_string(r));
        base = tpk_range_bvh_heap(v->range, NULL);
        if (base != v->range_leaf_base)
            return tpk_diag_fail(diag, "render: the range tree of the new field has %lld leaves' base, the uploaded "
                                 "one %lld (a bug in render_vk.c)", (long long)base, (long long)v->range_leaf_base);
        if (!(nodes = malloc(sizeof *nodes * 16 * (size_t)base)))
            return tpk_diag_fail(diag, "render: out of memory for the range BVH");
        tpk_range_bvh_heap(v->range, nodes);
    }
    const tpk_vk_source verts = {NULL, 16, fill_vertices, &v->mesh}, tets = {tet_scalars, 4, NULL, NULL},
                        ranges = {nodes, 16, NULL, NULL};
    uint64_t n = (uint64_t)v->mesh.vertex_count, t = tet_scalars ? (uint64_t)v->mesh.tet_count : 0;
    tpk_vk_stager stager;
    memset(&stager, 0, sizeof stager);
    uint64_t largest = 16 * (n > t ? n : t);
    largest = 64 * (uint64_t)base > largest ? 64 * (uint64_t)base : largest;
    int rc = v->ctx.staged ? tpk_vk_stager_create(&v->ctx, largest ? largest : 16, &stager, diag) : 0;
    if (rc == 0 && nodes) /* 2 texels per node, nodes 0 .. 2 base (range_upload) */
        rc = tpk_vk_array_refill(&v->ctx, v->ctx.staged ? &stager : NULL, &ranges, 4 * (uint64_t)base,
                                 &v->arrays[TPK_VK_ARRAY_RANGE_NODES], diag);
    if (rc == 0 && scalars) /* positions and the point field, interleaved */
        rc = tpk_vk_array_refill(&v->ctx, v->ctx.staged ? &stager : NULL, &verts, n, &v->arrays[TPK_VK_ARRAY_VERTS],
                                 diag);
    if (rc == 0 && tet_scalars)
        rc = tpk_vk_array_refill(&v->ctx, v->ctx.staged ? &stager : NULL, &tets, t,
                                 &v->arrays[TPK_VK_ARRAY_TET_SCALARS], diag);
    if (rc == 0 && v->ctx.staged)
        rc = tpk_vk_stager_finish(&v->ctx, &stager, diag);
    tpk_vk_stager_destroy(&v->ctx, &stager);
    free(nodes);
    return rc;
}

int tpk_render_vulkan(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                      tpk_render_stats *stats, tpk_diag *diag)
{
    double t0 = tpk_now_seconds();
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (tpk_vk_check_options(mesh, opt, rgba, diag) != 0)
        return -1;
    tpk_vk_renderer *v = NULL;
    if (tpk_vk_renderer_create(&v, mesh, opt->tet_scalars, diag) != 0)
        return -1;
    int rc = tpk_vk_renderer_frame(v, opt, rgba, stats, diag);
    if (stats) /* the frame apart from the pipeline it compiled */
        stats->first_frame_seconds = stats->seconds - v->frame_compile_seconds;
    tpk_vk_renderer_destroy(v); /* writes the pipeline cache */
    if (stats) /* like the CPU reference's, the time includes the setup */
        stats->seconds = tpk_now_seconds() - t0;
    return rc;
}

int tpk_vulkan_probe(char *why, size_t n, int *kind)
{
    tpk_vk_context ctx;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int ok = tpk_vk_context_create(&ctx, &diag) == 0;
    if (why && n)
        snprintf(why, n, "%s", ok ? ctx.props.deviceName : diag.message);
    if (kind)
        *kind = !ok ? TPK_VK_DEVICE_NONE
                : ctx.props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU ? TPK_VK_DEVICE_SOFTWARE : TPK_VK_DEVICE_HARDWARE;
    if (ok)
        tpk_vk_context_destroy(&ctx);
    return ok;
}

int tpk_vulkan_available(char *why, size_t n)
{
    return tpk_vulkan_probe(why, n, NULL);
}
