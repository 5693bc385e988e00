/* render --iso-raster's compute rasterizer (render_vk_internal.h: tpk_iso_vis_*): the triangle lists the
 * compute extraction made (vk_iso.c) rasterized by shaders/iso_vis.comp into a visibility buffer of 64
 * bits a pixel (depth key and triangle id, kept by atomicMin), then shaded by shaders/iso_resolve.comp
 * into packed RGBA8. Where the device lacks 64-bit buffer atomics, the same buffer is filled in two
 * passes of 32-bit ones (the depth, then the id of the triangle at that depth). No fixed-function
 * graphics: on chips with few graphics units (H100/H200) this is the fast path; vk_raster.c measures
 * both and keeps the faster. */
#include <stdlib.h>
#include <string.h>

#include "render_vk_internal.h"

extern const uint32_t tpk_vk_iso_vis64_spv[], tpk_vk_iso_vis32_spv[], tpk_vk_iso_resolve_spv[];
extern const size_t tpk_vk_iso_vis64_spv_size, tpk_vk_iso_vis32_spv_size, tpk_vk_iso_resolve_spv_size;

enum { BINDINGS = 5 };       /* corners, visibility, large triangles, probes, image */
enum { LARGE_GROUPS = 1024 }; /* workgroups of iso_vis.comp's mode 1, each a large triangle at a time */
enum { GROUP = 64 };          /* its local size */

/* iso_vis.comp's push constants */
typedef struct vis_push {
    float eye[4], forward[4], right[4], up[4], clip_lo[4], clip_hi[4];
    uint32_t frame[4]; /* width, height, first id, triangles */
    uint32_t pass[4];  /* pass (32-bit: 0 depth, 1 id), first triangle of the dispatch, mode */
} vis_push;

/* iso_resolve.comp's */
typedef struct resolve_push {
    float eye[4], forward[4], right[4], up[4], light[4], color[4], background[4];
    uint32_t frame[4];
} resolve_push;

struct tpk_iso_vis {
    const tpk_vk_context *ctx;
    VkBuffer probes;
    int bits; /* 64 or 32 */
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkShaderModule shaders[2]; /* visibility, resolve */
    VkPipeline pipelines[2];
    VkDescriptorPool pool;
    VkDescriptorSet sets[TPK_RENDER_MAX_ISO];
    tpk_vk_buffer vis, large, image;
    int width, height;
    uint32_t large_capacity; /* triangles the list holds */
};

static int ok(VkResult r, const char *step, tpk_diag *diag)
{
    return r == VK_SUCCESS ? 0 : tpk_diag_fail(diag, "vulkan iso raster (compute): %s failed: %s", step,
                                               tpk_vk_result_name(r));
}

static int make_pipeline(tpk_iso_vis *vis, int i, const uint32_t *code, size_t size, tpk_diag *diag)
{
    VkShaderModuleCreateInfo shader = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, .codeSize = size,
                                       .pCode = code};
    if (ok(vkCreateShaderModule(vis->ctx->device, &shader, NULL, &vis->shaders[i]), "a shader", diag))
        return -1;
    VkComputePipelineCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = vis->shaders[i], .pName = "main"},
        .layout = vis->layout};
    return ok(vkCreateComputePipelines(vis->ctx->device, VK_NULL_HANDLE, 1, &info, NULL, &vis->pipelines[i]),
              i ? "the resolve pipeline" : "the visibility pipeline", diag);
}

int tpk_iso_vis_create(tpk_iso_vis **out, const tpk_vk_context *ctx, VkBuffer probes, tpk_diag *diag)
{
    *out = NULL;
    if (ctx->props.limits.maxPushConstantsSize < sizeof(vis_push))
        return tpk_diag_fail(diag, "vulkan iso raster (compute): the device's push constants are under %u bytes",
                             (unsigned)sizeof(vis_push));
    tpk_iso_vis *vis = calloc(1, sizeof *vis);
    if (!vis)
        return tpk_diag_fail(diag, "vulkan iso raster (compute): out of memory");
    vis->ctx = ctx;
    vis->probes = probes;
    vis->bits = ctx->int64_atomics ? 64 : 32;
    VkDevice dev = ctx->device;
    VkDescriptorSetLayoutBinding bindings[BINDINGS];
    for (uint32_t i = 0; i < BINDINGS; i++)
        bindings[i] = (VkDescriptorSetLayoutBinding){i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
                                                     VK_SHADER_STAGE_COMPUTE_BIT, NULL};
    VkDescriptorSetLayoutCreateInfo set_info = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                                .bindingCount = BINDINGS, .pBindings = bindings};
    VkPushConstantRange range = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(vis_push)};
    VkPipelineLayoutCreateInfo layout = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
                                         .pSetLayouts = &vis->set_layout, .pushConstantRangeCount = 1,
                                         .pPushConstantRanges = &range};
    VkDescriptorPoolSize size = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, BINDINGS * TPK_RENDER_MAX_ISO};
    VkDescriptorPoolCreateInfo pool = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
                                       .maxSets = TPK_RENDER_MAX_ISO, .poolSizeCount = 1, .pPoolSizes = &size};
    VkDescriptorSetLayout layouts[TPK_RENDER_MAX_ISO];
    int rc = ok(vkCreateDescriptorSetLayout(dev, &set_info, NULL, &vis->set_layout), "a descriptor layout", diag) ||
             ok(vkCreatePipelineLayout(dev, &layout, NULL, &vis->layout), "a pipeline layout", diag) ||
             (vis->bits == 64 ? make_pipeline(vis, 0, tpk_vk_iso_vis64_spv, tpk_vk_iso_vis64_spv_size, diag)
                              : make_pipeline(vis, 0, tpk_vk_iso_vis32_spv, tpk_vk_iso_vis32_spv_size, diag)) ||
             make_pipeline(vis, 1, tpk_vk_iso_resolve_spv, tpk_vk_iso_resolve_spv_size, diag) ||
             ok(vkCreateDescriptorPool(dev, &pool, NULL, &vis->pool), "a descriptor pool", diag);
    for (int i = 0; i < TPK_RENDER_MAX_ISO; i++)
        layouts[i] = vis->set_layout;
    VkDescriptorSetAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                         .descriptorPool = vis->pool, .descriptorSetCount = TPK_RENDER_MAX_ISO,
                                         .pSetLayouts = layouts};
    if (rc == 0)
        rc = ok(vkAllocateDescriptorSets(dev, &alloc, vis->sets), "descriptor sets", diag);
    if (rc != 0) {
        tpk_iso_vis_destroy(vis);
        return -1;
    }
    *out = vis;
    return 0;
}

/* b at least `bytes` large (device memory, storage and transfer), made again only when it grows. */
static int ensure(tpk_iso_vis *vis, tpk_vk_buffer *b, VkDeviceSize bytes, const char *what, tpk_diag *diag)
{
    if (b->buffer && b->size >= bytes)
        return 0;
    if (bytes > vis->ctx->props.limits.maxStorageBufferRange)
        return tpk_diag_fail(diag, "vulkan iso raster (compute): the %s need %llu bytes; this device binds at most "
                             "%u bytes (Vulkan limit maxStorageBufferRange): use a smaller --size or "
                             "--iso-raster-path graphics", what, (unsigned long long)bytes,
                             vis->ctx->props.limits.maxStorageBufferRange);
    vkDeviceWaitIdle(vis->ctx->device);
    tpk_vk_buffer_destroy(vis->ctx, b);
    memset(b, 0, sizeof *b);
    return tpk_vk_buffer_create(vis->ctx, bytes,
                                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                    VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                TPK_VK_MEMORY_DEVICE, what, b, diag);
}

int tpk_iso_vis_prepare(tpk_iso_vis *vis, const tpk_iso_vis_frame *f, tpk_diag *diag)
{
    VkDeviceSize pixels = (VkDeviceSize)f->width * (VkDeviceSize)f->height;
    uint32_t most = 0;
    for (int i = 0; i < f->count; i++)
        most = f->values[i].triangles > most ? f->values[i].triangles : most;
    if (ensure(vis, &vis->vis, 8 * pixels, "visibility buffer's pixels", diag) ||
        ensure(vis, &vis->image, 4 * pixels, "image's pixels", diag) ||
        ensure(vis, &vis->large, 4 * ((VkDeviceSize)most + 1), "large triangles' list", diag))
        return -1;
    vis->width = f->width, vis->height = f->height;
    for (int i = 0; i < f->count; i++) {
        VkBuffer buffers[BINDINGS] = {f->values[i].corners, vis->vis.buffer, vis->large.buffer, vis->probes,
                                      vis->image.buffer};
        VkDescriptorBufferInfo info[BINDINGS];
        VkWriteDescriptorSet write[BINDINGS];
        for (uint32_t k = 0; k < BINDINGS; k++) {
            info[k] = (VkDescriptorBufferInfo){buffers[k], 0, VK_WHOLE_SIZE};
            write[k] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = vis->sets[i],
                                              .dstBinding = k, .descriptorCount = 1,
                                              .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                              .pBufferInfo = &info[k]};
        }
        vkUpdateDescriptorSets(vis->ctx->device, BINDINGS, write, 0, NULL);
    }
    return 0;
}

/* Shader writes (and transfer writes) before the next compute or transfer step. */
static void barrier(VkCommandBuffer cmd)
{
    VkMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                         .srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                         .dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                                          VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT};
    const VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    vkCmdPipelineBarrier(cmd, stages, stages, 0, 1, &b, 0, NULL, 0, NULL);
}

/* One pass of iso_vis.comp over value i's triangles (ids from `first` on): each triangle alone, then
 * the large ones a workgroup each. */
static void record_value(tpk_iso_vis *vis, VkCommandBuffer cmd, const tpk_iso_vis_frame *f, int i, uint32_t first,
                         uint32_t pass)
{
    uint32_t n = f->values[i].triangles;
    if (n == 0)
        return;
    vis_push p;
    memcpy(p.eye, f->eye, sizeof p.eye);
    memcpy(p.forward, f->forward, sizeof p.forward);
    memcpy(p.right, f->right, sizeof p.right);
    memcpy(p.up, f->up, sizeof p.up);
    memcpy(p.clip_lo, f->clip_lo, sizeof p.clip_lo);
    memcpy(p.clip_hi, f->clip_hi, sizeof p.clip_hi);
    p.frame[0] = (uint32_t)f->width, p.frame[1] = (uint32_t)f->height, p.frame[2] = first, p.frame[3] = n;
    vkCmdFillBuffer(cmd, vis->large.buffer, 0, 4, 0);
    barrier(cmd);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, vis->layout, 0, 1, &vis->sets[i], 0, NULL);
    uint32_t groups = (n + GROUP - 1) / GROUP;
    for (uint32_t g = 0; g < groups; g += 65535) { /* dispatches of at most 65535 groups */
        uint32_t k = groups - g < 65535 ? groups - g : 65535;
        p.pass[0] = pass, p.pass[1] = g * GROUP, p.pass[2] = 0, p.pass[3] = 0;
        vkCmdPushConstants(cmd, vis->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof p, &p);
        vkCmdDispatch(cmd, k, 1, 1);
    }
    barrier(cmd);
    p.pass[1] = 0, p.pass[2] = 1;
    vkCmdPushConstants(cmd, vis->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof p, &p);
    vkCmdDispatch(cmd, n < LARGE_GROUPS ? n : LARGE_GROUPS, 1, 1); /* at most a group a triangle */
    barrier(cmd);
}

void tpk_iso_vis_record(tpk_iso_vis *vis, VkCommandBuffer cmd, const tpk_iso_vis_frame *f)
{
    VkDeviceSize pixels = (VkDeviceSize)f->width * (VkDeviceSize)f->height;
    if (f->count == 0) { /* the background alone */
        uint32_t rgba = 0;
        for (int k = 0; k < 4; k++) {
            float c = f->background[k] < 0 ? 0 : f->background[k] > 1 ? 1 : f->background[k];
            rgba |= (uint32_t)(c * 255.0f + 0.5f) << (8 * k);
        }
        vkCmdFillBuffer(cmd, vis->image.buffer, 0, 4 * pixels, rgba);
        barrier(cmd);
        return;
    }
    vkCmdFillBuffer(cmd, vis->vis.buffer, 0, 8 * pixels, 0xffffffffu); /* nothing drawn: all ones */
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, vis->pipelines[0]);
    for (uint32_t pass = 0; pass < (vis->bits == 64 ? 1u : 2u); pass++) {
        uint32_t first = 0;
        for (int i = 0; i < f->count; i++) {
            record_value(vis, cmd, f, i, first, pass);
            first += f->values[i].triangles;
        }
    }
    barrier(cmd);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, vis->pipelines[1]);
    resolve_push r;
    memcpy(r.eye, f->eye, sizeof r.eye);
    memcpy(r.forward, f->forward, sizeof r.forward);
    memcpy(r.right, f->right, sizeof r.right);
    memcpy(r.up, f->up, sizeof r.up);
    memcpy(r.light, f->light, sizeof r.light);
    memcpy(r.background, f->background, sizeof r.background);
    uint32_t first = 0;
    for (int i = 0; i < f->count; i++) { /* disjoint pixels: no barrier between the values */
        memcpy(r.color, f->values[i].color, sizeof r.color);
        r.frame[0] = (uint32_t)f->width, r.frame[1] = (uint32_t)f->height, r.frame[2] = first;
        r.frame[3] = f->values[i].triangles;
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, vis->layout, 0, 1, &vis->sets[i], 0, NULL);
        vkCmdPushConstants(cmd, vis->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof r, &r);
        vkCmdDispatch(cmd, ((uint32_t)f->width + 7) / 8, ((uint32_t)f->height + 7) / 8, 1);
        first += f->values[i].triangles;
    }
    barrier(cmd);
}

VkBuffer tpk_iso_vis_image(const tpk_iso_vis *vis)
{
    return vis->image.buffer;
}

int tpk_iso_vis_atomic_bits(const tpk_iso_vis *vis)
{
    return vis->bits;
}

void tpk_iso_vis_destroy(tpk_iso_vis *vis)
{
    if (!vis)
        return;
    VkDevice dev = vis->ctx->device;
    vkDeviceWaitIdle(dev);
    tpk_vk_buffer_destroy(vis->ctx, &vis->vis);
    tpk_vk_buffer_destroy(vis->ctx, &vis->large);
    tpk_vk_buffer_destroy(vis->ctx, &vis->image);
    for (int i = 0; i < 2; i++) {
        if (vis->pipelines[i])
            vkDestroyPipeline(dev, vis->pipelines[i], NULL);
        if (vis->shaders[i])
            vkDestroyShaderModule(dev, vis->shaders[i], NULL);
    }
    if (vis->pool)
        vkDestroyDescriptorPool(dev, vis->pool, NULL);
    if (vis->layout)
        vkDestroyPipelineLayout(dev, vis->layout, NULL);
    if (vis->set_layout)
        vkDestroyDescriptorSetLayout(dev, vis->set_layout, NULL);
    free(vis);
}
