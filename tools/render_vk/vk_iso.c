/* Marching tetrahedra in Vulkan compute (render_vk.h: tpk_iso_vk_*): the mesh's tets, scalars and
 * positions uploaded once, then per value three passes of shaders/iso.comp (classify and scan per group
 * of 256 tets, scan of the groups, emit) give every tet's triangles as edge keys, in tet order,
 * and as float positions (a triangle list a GPU can draw as it is). The keys come back to the host,
 * where tools/iso/ shares vertices by edge and computes positions and normals as it does for its own
 * keys: the surface is the CPU's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "iso/iso.h"
#include "render_vk.h"
#include "render_vk_internal.h"

extern const uint32_t tpk_vk_iso_spv[];
extern const size_t tpk_vk_iso_spv_size;

#define B_COUNT TPK_ISO_VK_BUFFERS

static int vk_ok(VkResult r, const char *step, tpk_diag *diag)
{
    if (r == VK_SUCCESS)
        return 0;
    return tpk_diag_fail(diag, "vulkan iso: %s failed: %s", step, tpk_vk_result_name(r));
}

/* The device's view of a buffer: written in place where mapped, else through a host buffer and a copy. */
static int run_commands(tpk_iso_vk *v, void (*record)(tpk_iso_vk *v, const void *arg), const void *arg,
                        tpk_diag *diag)
{
    VkCommandBufferBeginInfo begin = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                      .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    if (vk_ok(vkResetCommandBuffer(v->cmd, 0), "resetting the command buffer", diag) ||
        vk_ok(vkBeginCommandBuffer(v->cmd, &begin), "beginning commands", diag))
        return -1;
    v->timed = 0;
    if (v->timestamps)
        vkCmdResetQueryPool(v->cmd, v->timestamps, 0, 2);
    record(v, arg);
    VkSubmitInfo submit = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &v->cmd};
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (vk_ok(vkEndCommandBuffer(v->cmd), "ending commands", diag) ||
        vk_ok(vkResetFences(v->ctx.device, 1, &v->fence), "resetting the fence", diag) ||
        vk_ok(vkQueueSubmit(v->ctx.queue, 1, &submit, v->fence), "submitting", diag) ||
        vk_ok(vkWaitForFences(v->ctx.device, 1, &v->fence, VK_TRUE, UINT64_MAX), "waiting for the device", diag))
        return -1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    v->wall_seconds += (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    double elapsed = v->timed ? tpk_vk_timestamp_seconds(&v->ctx, v->timestamps) : -1.0;
    if (elapsed > 0)
        v->timed_seconds += elapsed;
    return 0;
}

void tpk_iso_vk_time(tpk_iso_vk *v, int end)
{
    if (!v->timestamps)
        return;
    vkCmdWriteTimestamp(v->cmd, end ? VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT : VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                        v->timestamps, end ? 1 : 0);
    v->timed |= end;
}

double tpk_iso_vk_gpu_seconds(const tpk_iso_vk *v)
{
    return v->timestamps ? v->timed_seconds : -1.0;
}

typedef struct copy_arg {
    VkBuffer src, dst;
    VkDeviceSize bytes, src_offset;
} copy_arg;

static void record_copy(tpk_iso_vk *v, const void *arg)
{
    const copy_arg *c = arg;
    VkBufferCopy region = {c->src_offset, 0, c->bytes};
    vkCmdCopyBuffer(v->cmd, c->src, c->dst, 1, &region);
}

/* bytes of data into the device buffer b (at its start). */
static int upload(tpk_iso_vk *v, tpk_vk_buffer *b, const void *data, size_t bytes, tpk_diag *diag)
{
    if (b->mapped) {
        memcpy(b->mapped, data, bytes);
        return tpk_vk_buffer_flush(&v->ctx, b, diag);
    }
    tpk_vk_buffer host;
    memset(&host, 0, sizeof host);
    if (tpk_vk_buffer_create(&v->ctx, bytes ? bytes : 4, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, TPK_VK_MEMORY_UPLOAD,
                             "iso upload", &host, diag))
        return -1;
    int rc = -1;
    if (host.mapped) {
        memcpy(host.mapped, data, bytes);
        copy_arg c = {host.buffer, b->buffer, bytes ? bytes : 4, 0};
        rc = tpk_vk_buffer_flush(&v->ctx, &host, diag) || run_commands(v, record_copy, &c, diag) ? -1 : 0;
    } else {
        tpk_diag_fail(diag, "vulkan iso: no host-visible memory for uploads");
    }
    tpk_vk_buffer_destroy(&v->ctx, &host);
    return rc;
}

/* bytes from byte `offset` of device buffer b into data. */
static int download_at(tpk_iso_vk *v, const tpk_vk_buffer *b, VkDeviceSize offset, void *data, size_t bytes,
                       tpk_diag *diag)
{
    if (bytes == 0)
        return 0;
    if (b->mapped) {
        if (tpk_vk_buffer_invalidate(&v->ctx, b, diag))
            return -1;
        memcpy(data, (const char *)b->mapped + offset, bytes);
        return 0;
    }
    tpk_vk_buffer host;
    memset(&host, 0, sizeof host);
    if (tpk_vk_buffer_create(&v->ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, TPK_VK_MEMORY_READBACK, "iso readback",
                             &host, diag))
        return -1;
    copy_arg c = {b->buffer, host.buffer, bytes, offset};
    int rc = -1;
    if (!host.mapped)
        tpk_diag_fail(diag, "vulkan iso: no host-visible memory for the read-back");
    else if (run_commands(v, record_copy, &c, diag) == 0 && tpk_vk_buffer_invalidate(&v->ctx, &host, diag) == 0) {
        memcpy(data, host.mapped, bytes);
        rc = 0;
    }
    tpk_vk_buffer_destroy(&v->ctx, &host);
    return rc;
}

static int download(tpk_iso_vk *v, const tpk_vk_buffer *b, void *data, size_t bytes, tpk_diag *diag)
{
    return download_at(v, b, 0, data, bytes, diag);
}

static int make_buffer(tpk_iso_vk *v, int which, VkDeviceSize bytes, const char *what, tpk_diag *diag)
{
    tpk_vk_buffer_destroy(&v->ctx, &v->buf[which]);
    memset(&v->buf[which], 0, sizeof v->buf[which]);
    if (bytes > v->ctx.props.limits.maxStorageBufferRange)
        return tpk_diag_fail(diag, "vulkan iso: the %s need %llu bytes; this device binds at most %u bytes "
                             "(Vulkan limit maxStorageBufferRange): use the CPU backend",
                             what, (unsigned long long)bytes, v->ctx.props.limits.maxStorageBufferRange);
    return tpk_vk_buffer_create(&v->ctx, bytes ? bytes : 16,
                                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                    VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                                TPK_VK_MEMORY_DEVICE, what, &v->buf[which], diag);
}

static void write_descriptors(tpk_iso_vk *v)
{
    VkDescriptorBufferInfo info[B_COUNT];
    VkWriteDescriptorSet write[B_COUNT];
    for (int i = 0; i < B_COUNT; i++) {
        info[i] = (VkDescriptorBufferInfo){v->buf[i].buffer, 0, VK_WHOLE_SIZE};
        write[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
                                          .dstSet = v->set,
                                          .dstBinding = (uint32_t)i,
                                          .descriptorCount = 1,
                                          .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                          .pBufferInfo = &info[i]};
    }
    vkUpdateDescriptorSets(v->ctx.device, B_COUNT, write, 0, NULL);
}

static int make_pipeline(tpk_iso_vk *v, tpk_diag *diag)
{
    VkDescriptorSetLayoutBinding bindings[B_COUNT];
    for (int i = 0; i < B_COUNT; i++)
        bindings[i] = (VkDescriptorSetLayoutBinding){(uint32_t)i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
                                                     VK_SHADER_STAGE_COMPUTE_BIT, NULL};
    VkDescriptorSetLayoutCreateInfo set_info = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                                .bindingCount = B_COUNT, .pBindings = bindings};
    VkPushConstantRange push = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(iso_push)};
    VkShaderModuleCreateInfo shader = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
                                       .codeSize = tpk_vk_iso_spv_size, .pCode = tpk_vk_iso_spv};
    if (vk_ok(vkCreateDescriptorSetLayout(v->ctx.device, &set_info, NULL, &v->set_layout), "a descriptor layout", diag))
        return -1;
    VkPipelineLayoutCreateInfo layout = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
                                         .pSetLayouts = &v->set_layout, .pushConstantRangeCount = 1,
                                         .pPushConstantRanges = &push};
    if (vk_ok(vkCreatePipelineLayout(v->ctx.device, &layout, NULL, &v->layout), "a pipeline layout", diag) ||
        vk_ok(vkCreateShaderModule(v->ctx.device, &shader, NULL, &v->shader), "the iso shader", diag))
        return -1;
    VkComputePipelineCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = v->shader, .pName = "main"},
        .layout = v->layout};
    VkDescriptorPoolSize size = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, B_COUNT};
    VkDescriptorPoolCreateInfo pool = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
                                       .poolSizeCount = 1, .pPoolSizes = &size};
    if (vk_ok(vkCreateComputePipelines(v->ctx.device, VK_NULL_HANDLE, 1, &info, NULL, &v->pipeline), "the iso pipeline",
              diag) ||
        vk_ok(vkCreateDescriptorPool(v->ctx.device, &pool, NULL, &v->pool), "a descriptor pool", diag))
        return -1;
    VkDescriptorSetAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                         .descriptorPool = v->pool, .descriptorSetCount = 1, .pSetLayouts = &v->set_layout};
    VkCommandPoolCreateInfo commands = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
                                        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
                                        .queueFamilyIndex = v->ctx.queue_family};
    if (vk_ok(vkAllocateDescriptorSets(v->ctx.device, &alloc, &v->set), "a descriptor set", diag) ||
        vk_ok(vkCreateCommandPool(v->ctx.device, &commands, NULL, &v->commands), "a command pool", diag))
        return -1;
    VkCommandBufferAllocateInfo cmd = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                       .commandPool = v->commands, .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                       .commandBufferCount = 1};
    VkFenceCreateInfo fence = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if (vk_ok(vkAllocateCommandBuffers(v->ctx.device, &cmd, &v->cmd), "a command buffer", diag) ||
        vk_ok(vkCreateFence(v->ctx.device, &fence, NULL, &v->fence), "a fence", diag))
        return -1;
    v->timestamps = tpk_vk_timestamp_pool(&v->ctx); /* without one, no device time is reported */
    return 0;
}

int tpk_iso_vk_create(tpk_iso_vk **out, const tpk_iso_input *in, tpk_diag *diag)
{
    return tpk_iso_vk_create_with(out, in, 0, diag);
}

int tpk_iso_vk_upload(tpk_iso_vk *v, tpk_vk_buffer *b, const void *data, size_t bytes, tpk_diag *diag)
{
    return upload(v, b, data, bytes, diag);
}

int tpk_iso_vk_create_with(tpk_iso_vk **out, const tpk_iso_input *in, int mesh_shader, tpk_diag *diag)
{
    *out = NULL;
    if (in->tet_count > UINT32_MAX / 4 || in->vertex_count > INT32_MAX)
        return tpk_diag_fail(diag, "vulkan iso: %lld tets and %lld vertices: at most 2^30 tets", (long long)in->tet_count,
                             (long long)in->vertex_count);
    tpk_iso_vk *v = calloc(1, sizeof *v);
    if (!v)
        return tpk_diag_fail(diag, "vulkan iso: out of memory");
    v->tet_count = in->tet_count;
    v->group_count = (uint32_t)((in->tet_count + 255) / 256);
    int cases[16 * 8];
    memset(cases, 0, sizeof cases);
    for (int c = 0; c < 16; c++) {
        int count, edges[6], corners[6][2];
        tpk_iso_case_table(c, &count, edges, corners);
        cases[8 * c] = count;
        for (int k = 0; k < 6; k++)
            cases[8 * c + 1 + k] = edges[k];
    }
    size_t tets = 16 * (size_t)in->tet_count, verts = (size_t)in->vertex_count;
    int rc = mesh_shader ? tpk_vk_context_create_mesh(&v->ctx, diag) : tpk_vk_context_create(&v->ctx, diag);
    if (rc == 0)
        rc = make_buffer(v, B_TETS, tets, "tets", diag) || make_buffer(v, B_SCALARS, 4 * verts, "scalars", diag) ||
             make_buffer(v, B_POSITIONS, 12 * verts, "positions", diag) ||
             make_buffer(v, B_CASES, sizeof cases, "case table", diag) ||
             make_buffer(v, B_COUNTS, 4 * (size_t)in->tet_count, "triangle counts", diag) ||
             make_buffer(v, B_GROUPS, 4 * ((size_t)v->group_count + 1), "group sums", diag) ||
             make_buffer(v, B_KEYS, 0, "corner keys", diag) || make_buffer(v, B_CORNERS, 0, "corner positions", diag) ||
             make_buffer(v, B_DRAW_ARGS, 16, "draw arguments", diag);
    if (rc == 0)
        rc = make_pipeline(v, diag);
    if (rc == 0)
        rc = upload(v, &v->buf[B_TETS], in->tets, tets, diag) ||
             upload(v, &v->buf[B_SCALARS], in->scalars, 4 * verts, diag) ||
             upload(v, &v->buf[B_POSITIONS], in->positions, 12 * verts, diag) ||
             upload(v, &v->buf[B_CASES], cases, sizeof cases, diag);
    if (rc != 0) {
        tpk_iso_vk_destroy(v);
        return -1;
    }
    write_descriptors(v);
    v->wall_seconds = 0;
    *out = v;
    return 0;
}

void tpk_iso_vk_destroy(tpk_iso_vk *v)
{
    if (!v)
        return;
    if (v->ctx.device) {
        vkDeviceWaitIdle(v->ctx.device);
        for (int i = 0; i < B_COUNT; i++)
            tpk_vk_buffer_destroy(&v->ctx, &v->buf[i]);
        if (v->fence)
            vkDestroyFence(v->ctx.device, v->fence, NULL);
        if (v->timestamps)
            vkDestroyQueryPool(v->ctx.device, v->timestamps, NULL);
        if (v->commands)
            vkDestroyCommandPool(v->ctx.device, v->commands, NULL);
        if (v->pool)
            vkDestroyDescriptorPool(v->ctx.device, v->pool, NULL);
        if (v->pipeline)
            vkDestroyPipeline(v->ctx.device, v->pipeline, NULL);
        if (v->shader)
            vkDestroyShaderModule(v->ctx.device, v->shader, NULL);
        if (v->layout)
            vkDestroyPipelineLayout(v->ctx.device, v->layout, NULL);
        if (v->set_layout)
            vkDestroyDescriptorSetLayout(v->ctx.device, v->set_layout, NULL);
    }
    tpk_vk_context_destroy(&v->ctx);
    free(v);
}

const char *tpk_iso_vk_device(const tpk_iso_vk *v)
{
    return v->ctx.props.deviceName;
}

double tpk_iso_vk_seconds(const tpk_iso_vk *v)
{
    return v->wall_seconds;
}

float tpk_iso_vk_threshold(double x)
{
    float f = (float)x;
    if ((double)f < x)
        f = nextafterf(f, INFINITY);
    return f;
}

void tpk_iso_vk_record(tpk_iso_vk *v, int first, int last, double value)
{
    const float threshold = tpk_iso_vk_threshold(value), fvalue = (float)value;
    vkCmdBindPipeline(v->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, v->pipeline);
    vkCmdBindDescriptorSets(v->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, v->layout, 0, 1, &v->set, 0, NULL);
    for (int mode = first; mode <= last; mode++) {
        uint32_t groups = mode == 1 || mode == 3 ? 1 : v->group_count; /* each pass over every tet, */
        for (uint32_t g = 0; g < groups; g += 65535) {                   /* in dispatches of <= 65535 groups */
            uint32_t n = groups - g < 65535 ? groups - g : 65535;
            iso_push p = {(uint32_t)mode, (uint32_t)v->tet_count, v->group_count, threshold, fvalue, g * 256};
            vkCmdPushConstants(v->cmd, v->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof p, &p);
            vkCmdDispatch(v->cmd, n, 1, 1);
        }
        VkMemoryBarrier barrier = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                                   .srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT,
                                   .dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                                                    VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT};
        vkCmdPipelineBarrier(v->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                                 VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                             0, 1, &barrier, 0, NULL, 0, NULL);
    }
}

typedef struct pass_arg {
    int first, last;
    double value;
} pass_arg;

static void record_passes(tpk_iso_vk *v, const void *arg)
{
    const pass_arg *a = arg;
    tpk_iso_vk_time(v, 0);
    tpk_iso_vk_record(v, a->first, a->last, a->value);
    tpk_iso_vk_time(v, 1);
}

int tpk_iso_vk_submit(tpk_iso_vk *v, void (*record)(tpk_iso_vk *v, const void *arg), const void *arg, tpk_diag *diag)
{
    return run_commands(v, record, arg, diag);
}

/* Passes 0..last for `value`, then the grand total the groups pass left after the group sums. */
static int run_and_total(tpk_iso_vk *v, double value, int last, uint32_t *total, tpk_diag *diag)
{
    *total = 0;
    pass_arg passes = {0, last, value};
    if (run_commands(v, record_passes, &passes, diag))
        return -1;
    return download_at(v, &v->buf[B_GROUPS], 4 * (VkDeviceSize)v->group_count, total, 4, diag);
}

int tpk_iso_vk_triangles(tpk_iso_vk *v, double value, uint32_t *total, tpk_diag *diag)
{
    return run_and_total(v, value, 1, total, diag);
}

int tpk_iso_vk_count(tpk_iso_vk *v, double value, uint32_t *total, tpk_diag *diag)
{
    if (run_and_total(v, value, 1, total, diag))
        return -1;
    if ((uint64_t)*total * 3 * 12 > v->ctx.props.limits.maxStorageBufferRange)
        return tpk_diag_fail(diag, "vulkan iso: the surface of %g has %u triangles; their corners do not fit one "
                             "binding of this device (Vulkan limit maxStorageBufferRange): use the CPU backend",
                             value, *total);
    if (v->buf[B_KEYS].size < (VkDeviceSize)*total * 24 || v->buf[B_CORNERS].size < (VkDeviceSize)*total * 36) {
        if (make_buffer(v, B_KEYS, (VkDeviceSize)*total * 24, "corner keys", diag) ||
            make_buffer(v, B_CORNERS, (VkDeviceSize)*total * 36, "corner positions", diag))
            return -1;
        write_descriptors(v);
    }
    return 0;
}

int tpk_iso_vk_emit(tpk_iso_vk *v, double value, uint64_t **keys, float **positions, int64_t *triangles,
                    tpk_diag *diag)
{
    *keys = NULL;
    if (positions)
        *positions = NULL;
    *triangles = 0;
    if (v->tet_count == 0)
        return (*keys = malloc(8)) ? 0 : tpk_diag_fail(diag, "vulkan iso: out of memory");
    uint32_t total;
    if (tpk_iso_vk_count(v, value, &total, diag))
        return -1;
    pass_arg emit = {2, 2, value};
    size_t corners = 3 * (size_t)total;
    /* each key is the shader's uvec2 (b, a): little-endian, the uint64 (a << 32) | b */
    uint64_t *k = malloc(8 * (corners ? corners : 1));
    if (!k)
        return tpk_diag_fail(diag, "vulkan iso: out of memory");
    if (run_commands(v, record_passes, &emit, diag) || download(v, &v->buf[B_KEYS], k, 8 * corners, diag)) {
        free(k);
        return -1;
    }
    if (positions) {
        float *p = malloc(12 * (corners ? corners : 1));
        if (!p || download(v, &v->buf[B_CORNERS], p, 12 * corners, diag)) {
            free(k);
            free(p);
            return p ? -1 : tpk_diag_fail(diag, "vulkan iso: out of memory");
        }
        *positions = p;
    }
    *keys = k;
    *triangles = total;
    v->triangles += total;
    return 0;
}

static int emit_corners(void *user, const tpk_iso_input *in, double value, uint64_t **keys, int64_t *triangles,
                        tpk_diag *diag)
{
    (void)in;
    return tpk_iso_vk_emit(user, value, keys, NULL, triangles, diag);
}

tpk_iso_corners tpk_iso_vk_corners(tpk_iso_vk *v)
{
    return (tpk_iso_corners){emit_corners, v};
}
