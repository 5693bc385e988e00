/* Isosurfaces drawn directly (render.h: tpk_render_iso_raster; render --iso-raster): the compute extraction
 * of vk_iso.c writes each value's triangle list and its indirect draw arguments on the device, and a
 * graphics pipeline (shaders/iso_raster.vert, .frag) draws it with a depth test into the image, with no
 * pass through the host in between. This is the path for devices without VK_EXT_mesh_shader (lavapipe);
 * the picture is the ray-marched isosurface's up to rasterization (pixel centres, float positions). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "render/transfer_function.h"
#include "render_vk.h"
#include "render_vk_internal.h"

extern const uint32_t tpk_vk_iso_raster_vert_spv[], tpk_vk_iso_raster_frag_spv[];
extern const size_t tpk_vk_iso_raster_vert_spv_size, tpk_vk_iso_raster_frag_spv_size;

/* The shaders' push constants (iso_raster.vert). */
typedef struct raster_push {
    float eye[4], forward[4], right[4], up[4], light[4], color[4], clip_lo[4], clip_hi[4];
} raster_push;

typedef struct raster {
    tpk_iso_vk *iso;
    VkImage images[2]; /* colour, depth */
    VkDeviceMemory memory[2];
    VkImageView views[2];
    VkRenderPass pass[2]; /* the first value's (clears), the next values' (keeps what is drawn) */
    VkFramebuffer framebuffer;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkShaderModule shaders[2];
    VkPipeline pipeline;
    VkDescriptorPool pool;
    VkDescriptorSet set;
    tpk_vk_buffer readback;
    int width, height;
    float clear[4];
    raster_push push;
} raster;

/* Does the device offer VK_EXT_mesh_shader? (Said in --json; the path that uses it is not written yet.) */
static int has_mesh_shader(VkPhysicalDevice physical)
{
    uint32_t n = 0;
    if (vkEnumerateDeviceExtensionProperties(physical, NULL, &n, NULL) != VK_SUCCESS || n == 0)
        return 0;
    VkExtensionProperties *ext = malloc(sizeof *ext * n);
    int found = 0;
    if (ext && vkEnumerateDeviceExtensionProperties(physical, NULL, &n, ext) == VK_SUCCESS)
        for (uint32_t i = 0; i < n && !found; i++)
            found = !strcmp(ext[i].extensionName, "VK_EXT_mesh_shader");
    free(ext);
    return found;
}

static int ok(VkResult r, const char *step, tpk_diag *diag)
{
    return r == VK_SUCCESS ? 0 : tpk_diag_fail(diag, "vulkan iso raster: %s failed: %s", step, tpk_vk_result_name(r));
}

static int image(raster *ra, int i, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect,
                 tpk_diag *diag)
{
    const tpk_vk_context *ctx = &ra->iso->ctx;
    VkImageCreateInfo info = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO, .imageType = VK_IMAGE_TYPE_2D,
                              .format = format, .extent = {(uint32_t)ra->width, (uint32_t)ra->height, 1},
                              .mipLevels = 1, .arrayLayers = 1, .samples = VK_SAMPLE_COUNT_1_BIT,
                              .tiling = VK_IMAGE_TILING_OPTIMAL, .usage = usage,
                              .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED};
    if (ok(vkCreateImage(ctx->device, &info, NULL, &ra->images[i]), "creating an image", diag))
        return -1;
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(ctx->device, ra->images[i], &req);
    uint32_t order[VK_MAX_MEMORY_TYPES];
    int n = tpk_vk_memory_rank(&ctx->memory, ctx->unified, req.memoryTypeBits, TPK_VK_MEMORY_DEVICE, order);
    VkResult r = VK_ERROR_OUT_OF_DEVICE_MEMORY;
    for (int k = 0; k < n && r != VK_SUCCESS; k++) {
        VkMemoryAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, .allocationSize = req.size,
                                      .memoryTypeIndex = order[k]};
        r = vkAllocateMemory(ctx->device, &alloc, NULL, &ra->memory[i]);
    }
    if (ok(r, "allocating image memory", diag) ||
        ok(vkBindImageMemory(ctx->device, ra->images[i], ra->memory[i], 0), "binding image memory", diag))
        return -1;
    VkImageViewCreateInfo view = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO, .image = ra->images[i],
                                  .viewType = VK_IMAGE_VIEW_TYPE_2D, .format = format,
                                  .subresourceRange = {aspect, 0, 1, 0, 1}};
    return ok(vkCreateImageView(ctx->device, &view, NULL, &ra->views[i]), "creating an image view", diag);
}

static int shader(raster *ra, int i, const uint32_t *code, size_t size, tpk_diag *diag)
{
    VkShaderModuleCreateInfo info = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, .codeSize = size,
                                     .pCode = code};
    return ok(vkCreateShaderModule(ra->iso->ctx.device, &info, NULL, &ra->shaders[i]), "an iso raster shader", diag);
}

/* Render pass (colour and depth kept across the values' draws), framebuffer, pipeline, descriptor set. */
static int make_pipeline(raster *ra, tpk_diag *diag)
{
    VkDevice dev = ra->iso->ctx.device;
    VkAttachmentDescription att[2] = {
        {0, VK_FORMAT_R8G8B8A8_UNORM, VK_SAMPLE_COUNT_1_BIT, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_STORE,
         VK_ATTACHMENT_LOAD_OP_DONT_CARE, VK_ATTACHMENT_STORE_OP_DONT_CARE, VK_IMAGE_LAYOUT_UNDEFINED,
         VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL},
        {0, VK_FORMAT_D32_SFLOAT, VK_SAMPLE_COUNT_1_BIT, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_STORE,
         VK_ATTACHMENT_LOAD_OP_DONT_CARE, VK_ATTACHMENT_STORE_OP_DONT_CARE, VK_IMAGE_LAYOUT_UNDEFINED,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL}};
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS, .colorAttachmentCount = 1,
                                .pColorAttachments = &color, .pDepthStencilAttachment = &depth};
    VkSubpassDependency dep = {VK_SUBPASS_EXTERNAL, 0, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                               VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                               VK_ACCESS_SHADER_WRITE_BIT,
                               VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT, 0};
    VkRenderPassCreateInfo pass = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO, .attachmentCount = 2,
                                   .pAttachments = att, .subpassCount = 1, .pSubpasses = &sub,
                                   .dependencyCount = 1, .pDependencies = &dep};
    if (ok(vkCreateRenderPass(dev, &pass, NULL, &ra->pass[0]), "creating the render pass", diag))
        return -1;
    att[0].loadOp = att[1].loadOp = VK_ATTACHMENT_LOAD_OP_LOAD; /* the next values draw over the first's */
    att[0].initialLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    att[1].initialLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    if (ok(vkCreateRenderPass(dev, &pass, NULL, &ra->pass[1]), "creating the render pass", diag))
        return -1;
    VkFramebufferCreateInfo fb = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO, .renderPass = ra->pass[0],
                                  .attachmentCount = 2, .pAttachments = ra->views, .width = (uint32_t)ra->width,
                                  .height = (uint32_t)ra->height, .layers = 1};
    VkDescriptorSetLayoutBinding binding = {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, NULL};
    VkDescriptorSetLayoutCreateInfo set_info = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                                .bindingCount = 1, .pBindings = &binding};
    VkPushConstantRange range = {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(raster_push)};
    if (ok(vkCreateFramebuffer(dev, &fb, NULL, &ra->framebuffer), "creating the framebuffer", diag) ||
        ok(vkCreateDescriptorSetLayout(dev, &set_info, NULL, &ra->set_layout), "a descriptor layout", diag))
        return -1;
    VkPipelineLayoutCreateInfo layout = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
                                         .pSetLayouts = &ra->set_layout, .pushConstantRangeCount = 1,
                                         .pPushConstantRanges = &range};
    if (ok(vkCreatePipelineLayout(dev, &layout, NULL, &ra->layout), "a pipeline layout", diag) ||
        shader(ra, 0, tpk_vk_iso_raster_vert_spv, tpk_vk_iso_raster_vert_spv_size, diag) ||
        shader(ra, 1, tpk_vk_iso_raster_frag_spv, tpk_vk_iso_raster_frag_spv_size, diag))
        return -1;
    VkPipelineShaderStageCreateInfo stages[2] = {
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_VERTEX_BIT,
         .module = ra->shaders[0], .pName = "main"},
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_FRAGMENT_BIT,
         .module = ra->shaders[1], .pName = "main"}};
    VkPipelineVertexInputStateCreateInfo input = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo assembly = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO,
        .topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST};
    VkViewport viewport = {0, 0, (float)ra->width, (float)ra->height, 0, 1};
    VkRect2D scissor = {{0, 0}, {(uint32_t)ra->width, (uint32_t)ra->height}};
    VkPipelineViewportStateCreateInfo vp = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO,
                                            .viewportCount = 1, .pViewports = &viewport, .scissorCount = 1,
                                            .pScissors = &scissor};
    VkPipelineRasterizationStateCreateInfo rs = {.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO,
                                                 .polygonMode = VK_POLYGON_MODE_FILL, .cullMode = VK_CULL_MODE_NONE,
                                                 .frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE, .lineWidth = 1};
    VkPipelineMultisampleStateCreateInfo ms = {.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO,
                                               .rasterizationSamples = VK_SAMPLE_COUNT_1_BIT};
    VkPipelineDepthStencilStateCreateInfo ds = {.sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO,
                                                .depthTestEnable = VK_TRUE, .depthWriteEnable = VK_TRUE,
                                                .depthCompareOp = VK_COMPARE_OP_GREATER}; /* reversed depth */
    VkPipelineColorBlendAttachmentState blend = {.colorWriteMask = 0xf};
    VkPipelineColorBlendStateCreateInfo cb = {.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO,
                                              .attachmentCount = 1, .pAttachments = &blend};
    VkGraphicsPipelineCreateInfo info = {.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, .stageCount = 2,
                                         .pStages = stages, .pVertexInputState = &input,
                                         .pInputAssemblyState = &assembly, .pViewportState = &vp,
                                         .pRasterizationState = &rs, .pMultisampleState = &ms,
                                         .pDepthStencilState = &ds, .pColorBlendState = &cb, .layout = ra->layout,
                                         .renderPass = ra->pass[0]}; /* compatible with pass[1] */
    VkDescriptorPoolSize size = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1};
    VkDescriptorPoolCreateInfo pool = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
                                       .poolSizeCount = 1, .pPoolSizes = &size};
    if (ok(vkCreateGraphicsPipelines(dev, VK_NULL_HANDLE, 1, &info, NULL, &ra->pipeline), "the iso raster pipeline",
           diag) ||
        ok(vkCreateDescriptorPool(dev, &pool, NULL, &ra->pool), "a descriptor pool", diag))
        return -1;
    VkDescriptorSetAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                         .descriptorPool = ra->pool, .descriptorSetCount = 1,
                                         .pSetLayouts = &ra->set_layout};
    return ok(vkAllocateDescriptorSets(dev, &alloc, &ra->set), "a descriptor set", diag);
}

static void raster_destroy(raster *ra)
{
    if (!ra->iso)
        return;
    VkDevice dev = ra->iso->ctx.device;
    if (dev) {
        vkDeviceWaitIdle(dev);
        tpk_vk_buffer_destroy(&ra->iso->ctx, &ra->readback);
        if (ra->pipeline)
            vkDestroyPipeline(dev, ra->pipeline, NULL);
        for (int i = 0; i < 2; i++) {
            if (ra->shaders[i])
                vkDestroyShaderModule(dev, ra->shaders[i], NULL);
            if (ra->views[i])
                vkDestroyImageView(dev, ra->views[i], NULL);
            if (ra->images[i])
                vkDestroyImage(dev, ra->images[i], NULL);
            if (ra->memory[i])
                vkFreeMemory(dev, ra->memory[i], NULL);
        }
        if (ra->pool)
            vkDestroyDescriptorPool(dev, ra->pool, NULL);
        if (ra->layout)
            vkDestroyPipelineLayout(dev, ra->layout, NULL);
        if (ra->set_layout)
            vkDestroyDescriptorSetLayout(dev, ra->set_layout, NULL);
        if (ra->framebuffer)
            vkDestroyFramebuffer(dev, ra->framebuffer, NULL);
        for (int i = 0; i < 2; i++)
            if (ra->pass[i])
                vkDestroyRenderPass(dev, ra->pass[i], NULL);
    }
    tpk_iso_vk_destroy(ra->iso);
}

/* One value: its triangle list and draw arguments (iso.comp passes 4 and 5), then the draw, in one
 * submission; the first value's render pass clears, the others' keep what is drawn. */
typedef struct draw_arg {
    raster *ra;
    double value;
    int first, last;
} draw_arg;

static void record_draw(tpk_iso_vk *v, const void *arg)
{
    const draw_arg *d = arg;
    raster *ra = d->ra;
    tpk_iso_vk_record(v, 4, 5, d->value);
    VkClearValue clears[2] = {{.color = {{ra->clear[0], ra->clear[1], ra->clear[2], ra->clear[3]}}},
                              {.depthStencil = {0.0f, 0}}}; /* reversed depth: 0 is infinitely far */
    VkRenderPassBeginInfo begin = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO, .renderPass = ra->pass[d->first ? 0 : 1],
                                   .framebuffer = ra->framebuffer,
                                   .renderArea = {{0, 0}, {(uint32_t)ra->width, (uint32_t)ra->height}},
                                   .clearValueCount = 2, .pClearValues = clears};
    vkCmdBeginRenderPass(v->cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(v->cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, ra->pipeline);
    vkCmdBindDescriptorSets(v->cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, ra->layout, 0, 1, &ra->set, 0, NULL);
    vkCmdPushConstants(v->cmd, ra->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                       sizeof ra->push, &ra->push);
    vkCmdDrawIndirect(v->cmd, v->buf[B_DRAW_ARGS].buffer, 0, 1, 16);
    vkCmdEndRenderPass(v->cmd);
    if (d->last) { /* the image out to the read-back buffer */
        VkBufferImageCopy region = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                                    .imageExtent = {(uint32_t)ra->width, (uint32_t)ra->height, 1}};
        vkCmdCopyImageToBuffer(v->cmd, ra->images[0], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, ra->readback.buffer, 1,
                               &region);
    }
}

int tpk_render_iso_raster(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                          tpk_render_stats *stats, tpk_diag *diag)
{
    double t0 = tpk_now_seconds();
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (tpk_render_check_options(opt, diag) != 0)
        return -1;
    if (opt->iso_count < 1 || !mesh->scalars || opt->tet_scalars)
        return tpk_diag_fail(diag, "render: --iso-raster draws the isosurfaces of a point field: give --iso V and a "
                                   "point field");
    if (opt->shadows || opt->ao_rays > 0 || (opt->iso_opacity > 0 && opt->iso_opacity < 1))
        return tpk_diag_fail(diag, "render: --iso-raster draws opaque isosurfaces with shading at most: without "
                                   "--shadows, --ao and --iso-opacity (the ray marcher draws those)");
    tpk_render_setup setup;
    if (tpk_render_setup_of(opt, tpk_positions_diagonal(mesh), &setup, diag) != 0)
        return -1;
    int32_t *tets = malloc(16 * (size_t)(mesh->tet_count ? mesh->tet_count : 1));
    if (!tets)
        return tpk_diag_fail(diag, "render: out of memory for the tets");
    tpk_result r = tpk_recover_tets(mesh, tets);
    if (r != TPK_OK) {
        free(tets);
        return tpk_diag_fail(diag, "render: --iso-raster: the tets' vertex order: %s", tpk_result_string(r));
    }
    tpk_iso_input in = {(int64_t)mesh->vertex_count, (int64_t)mesh->tet_count, {0, 0, 0}, mesh->positions, tets,
                        mesh->scalars, NULL};
    memcpy(in.origin, mesh->origin, sizeof in.origin);
    raster ra;
    memset(&ra, 0, sizeof ra);
    ra.width = opt->width;
    ra.height = opt->height;
    int rc = tpk_iso_vk_create(&ra.iso, &in, diag);
    free(tets);
    if (rc != 0)
        return -1;
    if (!(ra.iso->ctx.props.limits.maxPushConstantsSize >= sizeof(raster_push)))
        rc = tpk_diag_fail(diag, "render: --iso-raster: the device's push constants are too small");
    /* near and far: the mesh's box seen from the eye */
    double far = 0, eye[3];
    for (int k = 0; k < 3; k++)
        eye[k] = opt->camera.eye[k] - mesh->origin[k];
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < mesh->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            float x = mesh->positions[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    for (int c = 0; c < 8; c++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double x = ((c >> k) & 1 ? hi[k] : lo[k]) - eye[k];
            d2 += x * x;
        }
        far = sqrt(d2) > far ? sqrt(d2) : far;
    }
    far = 1.01 * far + 1e-6;
    raster_push *p = &ra.push;
    for (int k = 0; k < 3; k++) {
        p->eye[k] = (float)eye[k];
        p->forward[k] = (float)setup.basis.forward[k];
        p->right[k] = (float)setup.basis.right[k];
        p->up[k] = (float)setup.basis.up[k];
        p->light[k] = (float)(setup.light[k] - mesh->origin[k]);
        p->clip_lo[k] = (float)(opt->clip_min[k] - mesh->origin[k]);
        p->clip_hi[k] = (float)(opt->clip_max[k] - mesh->origin[k]);
    }
    p->eye[3] = (float)(far * 1e-6); /* the near distance; depth is near / distance */
    p->right[3] = (float)setup.basis.tan_half_x;
    p->up[3] = (float)setup.basis.tan_half_y;
    p->light[3] = opt->shading ? 1.0f : 0.0f;
    p->clip_lo[3] = opt->clip ? 1.0f : 0.0f;
    for (int k = 0; k < 4; k++)
        ra.clear[k] = k < 3 ? opt->background[k] * opt->background[3] : opt->background[3];
    if (rc == 0)
        rc = image(&ra, 0, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT, diag) ||
             image(&ra, 1, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                   diag) ||
             make_pipeline(&ra, diag) ||
             tpk_vk_buffer_create(&ra.iso->ctx, 4 * (VkDeviceSize)ra.width * (VkDeviceSize)ra.height,
                                  VK_BUFFER_USAGE_TRANSFER_DST_BIT, TPK_VK_MEMORY_READBACK, "iso raster image",
                                  &ra.readback, diag);
    if (rc == 0 && !ra.readback.mapped)
        rc = tpk_diag_fail(diag, "render: --iso-raster: no host-visible memory for the image");
    uint64_t triangles = 0;
    for (int i = 0; rc == 0 && i < opt->iso_count; i++) {
        uint32_t total;
        rc = tpk_iso_vk_count(ra.iso, opt->iso[i], &total, diag);
        if (rc)
            break;
        triangles += total;
        VkDescriptorBufferInfo corners = {ra.iso->buf[B_CORNERS].buffer, 0, VK_WHOLE_SIZE};
        VkWriteDescriptorSet write = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = ra.set,
                                      .dstBinding = 0, .descriptorCount = 1,
                                      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &corners};
        vkUpdateDescriptorSets(ra.iso->ctx.device, 1, &write, 0, NULL);
        double c[4], u = setup.inv_range == 0 ? 0.5 : (opt->iso[i] - setup.range_min) * setup.inv_range;
        tpk_tf_eval(opt->tf, u, c);
        for (int k = 0; k < 3; k++)
            p->color[k] = (float)c[k];
        draw_arg d = {&ra, opt->iso[i], i == 0, i == opt->iso_count - 1};
        rc = tpk_iso_vk_submit(ra.iso, record_draw, &d, diag);
    }
    if (rc == 0 && tpk_vk_buffer_invalidate(&ra.iso->ctx, &ra.readback, diag) == 0)
        memcpy(rgba, ra.readback.mapped, 4 * (size_t)ra.width * (size_t)ra.height);
    if (stats && rc == 0) {
        stats->rays = 0;
        stats->tet_steps = (uint64_t)mesh->tet_count * (uint64_t)opt->iso_count; /* tets classified */
        stats->seconds = tpk_now_seconds() - t0;
        stats->gpu_seconds = tpk_iso_vk_seconds(ra.iso);
        stats->iso_triangles = triangles;
        stats->iso_mesh_shader = has_mesh_shader(ra.iso->ctx.physical);
    }
    raster_destroy(&ra);
    return rc;
}
