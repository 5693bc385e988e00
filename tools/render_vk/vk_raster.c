/* Isosurfaces drawn directly (render.h: tpk_render_iso_raster; render --iso-raster), by one of two paths:
 * - where the device has VK_EXT_mesh_shader (and TETPACK_ISO_MESH_SHADER is not 0): task shaders
 *   (shaders/iso_mesh.task) cull clusters of 32 tets by their value range and classify the rest, and mesh
 *   shaders (iso_mesh.mesh) run marching tets on the active tets and emit their triangles to the
 *   rasterizer: nothing is stored between frames but a range per cluster;
 * - elsewhere (lavapipe): the compute extraction of vk_iso.c writes each value's triangle list and its
 *   indirect draw arguments on the device, and a graphics pipeline (shaders/iso_raster.vert) draws it.
 * Both draw with a depth test into the image, shaded by shaders/iso_raster.frag, with no pass through the
 * host in between; the triangles are the same (corners placed alike, in tet order). The picture is the
 * ray-marched isosurface's up to rasterization (pixel centres, float positions).
 * A third path draws the compute extraction's lists without fixed-function graphics: the compute
 * rasterizer of vk_vis.c (a visibility buffer by atomics, then shaded). --iso-raster-path picks one;
 * auto (the default) draws the first MEASURES frames at a size (render draws one) with both the graphics
 * path and the compute rasterizer, timed on the device, and keeps the one with the least time: what the
 * device measures decides, not its name (on chips with few graphics units, as the H100/H200, compute is
 * expected to win; on lavapipe the graphics path does). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "base/clock.h"
#include "render/transfer_function.h"
#include "render_vk.h"
#include "render_vk_internal.h"

extern const uint32_t tpk_vk_iso_raster_vert_spv[], tpk_vk_iso_raster_frag_spv[];
extern const size_t tpk_vk_iso_raster_vert_spv_size, tpk_vk_iso_raster_frag_spv_size;
extern const uint32_t tpk_vk_iso_mesh_task_spv[], tpk_vk_iso_mesh_mesh_spv[];
extern const size_t tpk_vk_iso_mesh_task_spv_size, tpk_vk_iso_mesh_mesh_spv_size;

/* The shaders' push constants (iso_raster.vert; the mesh path's iso_mesh.glsl adds mesh_push's tail). */
typedef struct raster_push {
    float eye[4], forward[4], right[4], up[4], light[4], color[4], clip_lo[4], clip_hi[4];
} raster_push;

typedef struct mesh_push {
    raster_push camera;
    float threshold, value;
    uint32_t tet_count, base;
} mesh_push;

enum { MESH_BINDINGS = 5 }; /* tets, scalars, positions, case table, cluster ranges; then the probes */
enum { PROBE_BINDING = 5 };

/* iso_raster.frag's Probes block: tpk_probe_keeps's probes, relative to the mesh's origin. */
typedef struct probe_block {
    int32_t count[4];
    int32_t kind[TPK_RENDER_MAX_PROBES][4]; /* shape, cut */
    float a[TPK_RENDER_MAX_PROBES][4];      /* xyz; w: radius */
    float b[TPK_RENDER_MAX_PROBES][4];
} probe_block;

#define RASTER_VALUES TPK_RENDER_MAX_ISO
enum { MEASURES = 2 }; /* frames that draw both paths (auto) */

struct tpk_iso_raster {
    tpk_iso_vk *iso;   /* the extractor, on its device; the mesh's tets, scalars, positions uploaded */
    const tpk_mesh_arrays *mesh;
    double diagonal;   /* of its positions' box (tpk_positions_diagonal), once rather than each frame */
    VkImage images[2]; /* colour, depth: at the last frame's size */
    VkDeviceMemory memory[2];
    VkImageView views[2];
    VkRenderPass pass;
    VkFramebuffer framebuffer;
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkShaderModule shaders[2];
    VkPipeline pipeline;
    VkDescriptorPool pool;
    VkDescriptorSet sets[RASTER_VALUES];
    tpk_vk_buffer readback;
    tpk_vk_buffer probes; /* the frame's probes (probe_block), host-visible, read by the fragment shader */
    int width, height;
    /* the triangle lists drawn, one per value, kept across frames until the values change */
    int value_count;
    double values[RASTER_VALUES];
    tpk_vk_buffer corners[RASTER_VALUES], args[RASTER_VALUES];
    uint64_t triangles[RASTER_VALUES];
    /* one frame's */
    float clear[4];
    raster_push push[RASTER_VALUES];
    /* the mesh-shader path, when mesh_path */
    int mesh_path;
    int mesh_state;          /* render.h iso_mesh_shader: 1 used, 0 the device lacks it, 2 it has it, unused */
    const char *mesh_reason; /* why not, when the device has the extension */
    char mesh_failure[192];  /* mesh_reason when setting the path up failed */
    VkDescriptorSetLayout mesh_set_layout;
    VkPipelineLayout mesh_layout;
    VkShaderModule mesh_shaders[2]; /* task, mesh */
    VkPipeline mesh_pipeline;
    VkDescriptorPool mesh_pool;
    VkDescriptorSet mesh_set;
    tpk_vk_buffer ranges; /* per cluster of 32 tets: min and max of its corners' values (floats) */
    uint32_t clusters;
    PFN_vkCmdDrawMeshTasksEXT draw_mesh_tasks;
    /* the compute rasterizer (vk_vis.c), made on the first frame that may use it */
    tpk_iso_vis *vis;
    tpk_iso_vis_frame vis_frame;
    int listed[RASTER_VALUES]; /* value i's triangle list is in corners[i] (the mesh path needs none) */
    int samples;               /* --iso-raster-path auto: frames at this size that drew both paths; the
                                  first MEASURES do, so that one stall of the device does not decide */
    int choice;                /* --iso-raster-path auto: -1 not measured at this size, else the faster
                                  path, TPK_ISO_RASTER_COMPUTE or _GRAPHICS */
    double measured[2];        /* the least device time of each path's draw so far: graphics, compute */
    int vis_failed;            /* auto: the compute rasterizer could not draw (at this size): graphics */
};
typedef struct tpk_iso_raster raster;

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

/* A graphics pipeline of `stages` (vertex or task and mesh, then iso_raster.frag) in the render pass,
 * with the state both paths share: triangles, no culling (both sides shade), reversed depth. */
static int graphics_pipeline(raster *ra, const VkPipelineShaderStageCreateInfo *stages, uint32_t count,
                             VkPipelineLayout layout, VkPipeline *out, tpk_diag *diag)
{
    int mesh = stages[0].stage != VK_SHADER_STAGE_VERTEX_BIT;
    VkPipelineVertexInputStateCreateInfo input = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo assembly = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO,
        .topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST};
    VkPipelineViewportStateCreateInfo vp = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO,
                                            .viewportCount = 1, .scissorCount = 1};
    VkDynamicState dynamic[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dyn = {.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
                                            .dynamicStateCount = 2, .pDynamicStates = dynamic};
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
    VkGraphicsPipelineCreateInfo info = {.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
                                         .stageCount = count, .pStages = stages,
                                         /* a mesh pipeline has neither (the spec: ignored, may be NULL) */
                                         .pVertexInputState = mesh ? NULL : &input,
                                         .pInputAssemblyState = mesh ? NULL : &assembly, .pViewportState = &vp,
                                         .pRasterizationState = &rs, .pMultisampleState = &ms,
                                         .pDepthStencilState = &ds, .pColorBlendState = &cb, .pDynamicState = &dyn,
                                         .layout = layout, .renderPass = ra->pass};
    return ok(vkCreateGraphicsPipelines(ra->iso->ctx.device, VK_NULL_HANDLE, 1, &info, NULL, out),
              mesh ? "the iso mesh-shader pipeline" : "the iso raster pipeline", diag);
}

/* Render pass, pipeline (viewport and scissor dynamic: the size may change between frames), descriptor
 * sets (one per value). Once per rasterizer. */
static int make_pipeline(raster *ra, tpk_diag *diag)
{
    VkDevice dev = ra->iso->ctx.device;
    VkAttachmentDescription att[2] = {
        {0, VK_FORMAT_R8G8B8A8_UNORM, VK_SAMPLE_COUNT_1_BIT, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_STORE,
         VK_ATTACHMENT_LOAD_OP_DONT_CARE, VK_ATTACHMENT_STORE_OP_DONT_CARE, VK_IMAGE_LAYOUT_UNDEFINED,
         VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL},
        {0, VK_FORMAT_D32_SFLOAT, VK_SAMPLE_COUNT_1_BIT, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_DONT_CARE,
         VK_ATTACHMENT_LOAD_OP_DONT_CARE, VK_ATTACHMENT_STORE_OP_DONT_CARE, VK_IMAGE_LAYOUT_UNDEFINED,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL}};
    VkAttachmentReference color = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub = {.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS, .colorAttachmentCount = 1,
                                .pColorAttachments = &color, .pDepthStencilAttachment = &depth};
    VkSubpassDependency dep = {VK_SUBPASS_EXTERNAL, 0, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                               VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT |
                                   (ra->iso->ctx.mesh_shader ? VK_PIPELINE_STAGE_TASK_SHADER_BIT_EXT | VK_PIPELINE_STAGE_MESH_SHADER_BIT_EXT
                                             : 0),
                               VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                               VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT, 0};
    VkRenderPassCreateInfo pass = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO, .attachmentCount = 2,
                                   .pAttachments = att, .subpassCount = 1, .pSubpasses = &sub,
                                   .dependencyCount = 1, .pDependencies = &dep};
    if (ok(vkCreateRenderPass(dev, &pass, NULL, &ra->pass), "creating the render pass", diag))
        return -1;
    VkDescriptorSetLayoutBinding binding[2] = {
        {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, NULL},
        {PROBE_BINDING, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, NULL}};
    VkDescriptorSetLayoutCreateInfo set_info = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                                .bindingCount = 2, .pBindings = binding};
    VkPushConstantRange range = {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(raster_push)};
    if (ok(vkCreateDescriptorSetLayout(dev, &set_info, NULL, &ra->set_layout), "a descriptor layout", diag))
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
    VkDescriptorPoolSize size = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 2 * RASTER_VALUES};
    VkDescriptorPoolCreateInfo pool = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = RASTER_VALUES,
                                       .poolSizeCount = 1, .pPoolSizes = &size};
    if (graphics_pipeline(ra, stages, 2, ra->layout, &ra->pipeline, diag) ||
        ok(vkCreateDescriptorPool(dev, &pool, NULL, &ra->pool), "a descriptor pool", diag))
        return -1;
    VkDescriptorSetLayout layouts[RASTER_VALUES];
    for (int i = 0; i < RASTER_VALUES; i++)
        layouts[i] = ra->set_layout;
    VkDescriptorSetAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                         .descriptorPool = ra->pool, .descriptorSetCount = RASTER_VALUES,
                                         .pSetLayouts = layouts};
    if (ok(vkAllocateDescriptorSets(dev, &alloc, ra->sets), "descriptor sets", diag))
        return -1;
    VkDescriptorBufferInfo info = {ra->probes.buffer, 0, VK_WHOLE_SIZE};
    for (int i = 0; i < RASTER_VALUES; i++) {
        VkWriteDescriptorSet write = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = ra->sets[i],
                                      .dstBinding = PROBE_BINDING, .descriptorCount = 1,
                                      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &info};
        vkUpdateDescriptorSets(dev, 1, &write, 0, NULL);
    }
    return 0;
}

/* The mesh-shader path's pipeline and its one descriptor set (the extractor's tets, scalars, positions and
 * case table, and the cluster ranges); the fragment shader module is the other path's. */
static int make_mesh_pipeline(raster *ra, tpk_diag *diag)
{
    VkDevice dev = ra->iso->ctx.device;
    VkDescriptorSetLayoutBinding bindings[MESH_BINDINGS + 1];
    for (uint32_t i = 0; i < MESH_BINDINGS; i++)
        bindings[i] = (VkDescriptorSetLayoutBinding){i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
                                                     VK_SHADER_STAGE_TASK_BIT_EXT | VK_SHADER_STAGE_MESH_BIT_EXT, NULL};
    bindings[MESH_BINDINGS] = (VkDescriptorSetLayoutBinding){PROBE_BINDING, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1,
                                                             VK_SHADER_STAGE_FRAGMENT_BIT, NULL};
    VkDescriptorSetLayoutCreateInfo set_info = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                                .bindingCount = MESH_BINDINGS + 1, .pBindings = bindings};
    VkPushConstantRange range = {VK_SHADER_STAGE_TASK_BIT_EXT | VK_SHADER_STAGE_MESH_BIT_EXT | VK_SHADER_STAGE_FRAGMENT_BIT,
                                 0, sizeof(mesh_push)};
    if (ok(vkCreateDescriptorSetLayout(dev, &set_info, NULL, &ra->mesh_set_layout), "a descriptor layout", diag))
        return -1;
    VkPipelineLayoutCreateInfo layout = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
                                         .pSetLayouts = &ra->mesh_set_layout, .pushConstantRangeCount = 1,
                                         .pPushConstantRanges = &range};
    VkShaderModuleCreateInfo task = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
                                     .codeSize = tpk_vk_iso_mesh_task_spv_size, .pCode = tpk_vk_iso_mesh_task_spv};
    VkShaderModuleCreateInfo mesh = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
                                     .codeSize = tpk_vk_iso_mesh_mesh_spv_size, .pCode = tpk_vk_iso_mesh_mesh_spv};
    if (ok(vkCreatePipelineLayout(dev, &layout, NULL, &ra->mesh_layout), "a pipeline layout", diag) ||
        ok(vkCreateShaderModule(dev, &task, NULL, &ra->mesh_shaders[0]), "the iso task shader", diag) ||
        ok(vkCreateShaderModule(dev, &mesh, NULL, &ra->mesh_shaders[1]), "the iso mesh shader", diag))
        return -1;
    VkPipelineShaderStageCreateInfo stages[3] = {
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_TASK_BIT_EXT,
         .module = ra->mesh_shaders[0], .pName = "main"},
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_MESH_BIT_EXT,
         .module = ra->mesh_shaders[1], .pName = "main"},
        {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_FRAGMENT_BIT,
         .module = ra->shaders[1], .pName = "main"}};
    VkDescriptorPoolSize size = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, MESH_BINDINGS + 1};
    VkDescriptorPoolCreateInfo pool = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
                                       .poolSizeCount = 1, .pPoolSizes = &size};
    VkDescriptorSetAllocateInfo alloc = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                         .descriptorSetCount = 1, .pSetLayouts = &ra->mesh_set_layout};
    if (graphics_pipeline(ra, stages, 3, ra->mesh_layout, &ra->mesh_pipeline, diag) ||
        ok(vkCreateDescriptorPool(dev, &pool, NULL, &ra->mesh_pool), "a descriptor pool", diag))
        return -1;
    alloc.descriptorPool = ra->mesh_pool;
    if (ok(vkAllocateDescriptorSets(dev, &alloc, &ra->mesh_set), "a descriptor set", diag))
        return -1;
    const tpk_vk_buffer *buffers[MESH_BINDINGS + 1] = {&ra->iso->buf[B_TETS], &ra->iso->buf[B_SCALARS],
                                                       &ra->iso->buf[B_POSITIONS], &ra->iso->buf[B_CASES], &ra->ranges,
                                                       &ra->probes};
    VkDescriptorBufferInfo info[MESH_BINDINGS + 1];
    VkWriteDescriptorSet write[MESH_BINDINGS + 1];
    for (uint32_t i = 0; i <= MESH_BINDINGS; i++) {
        info[i] = (VkDescriptorBufferInfo){buffers[i]->buffer, 0, VK_WHOLE_SIZE};
        write[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = ra->mesh_set,
                                          .dstBinding = i < MESH_BINDINGS ? i : PROBE_BINDING, .descriptorCount = 1,
                                          .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &info[i]};
    }
    vkUpdateDescriptorSets(dev, MESH_BINDINGS + 1, write, 0, NULL);
    ra->draw_mesh_tasks = (PFN_vkCmdDrawMeshTasksEXT)vkGetDeviceProcAddr(dev, "vkCmdDrawMeshTasksEXT");
    return ra->draw_mesh_tasks ? 0 : tpk_diag_fail(diag, "vulkan iso raster: the device has no vkCmdDrawMeshTasksEXT");
}

/* Per cluster of 32 tets (file order), the min and max of its corners' values, NaN left out (a tet with
 * a NaN corner has no triangles); a cluster of NaNs only gets (+inf, -inf), which no value lies within. */
static float *cluster_ranges(const int32_t *tets, const float *scalars, uint64_t tet_count, uint32_t clusters)
{
    float *r = malloc(8 * (size_t)(clusters ? clusters : 1));
    if (!r)
        return NULL;
    for (uint32_t c = 0; c < clusters; c++) {
        float lo = INFINITY, hi = -INFINITY;
        for (uint64_t t = 32 * (uint64_t)c; t < tet_count && t < 32 * (uint64_t)c + 32; t++)
            for (int k = 0; k < 4; k++) {
                float x = scalars[tets[4 * t + (uint64_t)k]];
                if (!isnan(x)) {
                    lo = x < lo ? x : lo;
                    hi = x > hi ? x : hi;
                }
            }
        r[2 * c] = lo, r[2 * c + 1] = hi;
    }
    return r;
}

/* The mesh-shader path where the device's context enabled it and its limits allow; else mesh_path stays 0
 * with the reason. Task and mesh workgroups of 32, a mesh workgroup's output (192 vertices, 64 triangles,
 * 264 payload bytes) is within every device's guaranteed limits; the push constants (144 bytes) are not. */
static int setup_mesh_path(raster *ra, const int32_t *tets, tpk_diag *diag)
{
    const tpk_vk_context *ctx = &ra->iso->ctx;
    if (!ctx->mesh_shader) { /* the device lacks it, or tpk_vk_context_create_mesh was told not to */
        ra->mesh_state = tpk_vk_has_mesh_shader(ctx->physical) ? 2 : 0;
        ra->mesh_reason = ra->mesh_state ? "TETPACK_ISO_MESH_SHADER=0" : NULL;
        return 0;
    }
    ra->mesh_state = 2;
    if (ctx->props.limits.maxPushConstantsSize < sizeof(mesh_push)) {
        ra->mesh_reason = "the device's push constants are under 144 bytes";
        return 0;
    }
    ra->clusters = (uint32_t)((ra->mesh->tet_count + 31) / 32);
    float *ranges = cluster_ranges(tets, ra->mesh->scalars, ra->mesh->tet_count, ra->clusters);
    if (!ranges)
        return tpk_diag_fail(diag, "render: out of memory for the cluster ranges");
    int rc = tpk_vk_buffer_create(ctx, 8 * (VkDeviceSize)(ra->clusters ? ra->clusters : 1),
                                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                  TPK_VK_MEMORY_DEVICE, "iso cluster ranges", &ra->ranges, diag) ||
                     tpk_iso_vk_upload(ra->iso, &ra->ranges, ranges, 8 * (size_t)ra->clusters, diag) ||
                     make_mesh_pipeline(ra, diag)
                 ? -1
                 : 0;
    free(ranges);
    ra->mesh_path = rc == 0;
    ra->mesh_state = rc == 0 ? 1 : 2;
    if (rc != 0) { /* the compute path draws instead, and --json says why */
        snprintf(ra->mesh_failure, sizeof ra->mesh_failure, "setting it up failed: %.160s", diag->message);
        ra->mesh_reason = ra->mesh_failure;
        diag->message[0] = 0;
    }
    return 0;
}

static void destroy_targets(raster *ra)
{
    VkDevice dev = ra->iso->ctx.device;
    tpk_vk_buffer_destroy(&ra->iso->ctx, &ra->readback);
    memset(&ra->readback, 0, sizeof ra->readback);
    if (ra->framebuffer)
        vkDestroyFramebuffer(dev, ra->framebuffer, NULL);
    ra->framebuffer = VK_NULL_HANDLE;
    for (int i = 0; i < 2; i++) {
        if (ra->views[i])
            vkDestroyImageView(dev, ra->views[i], NULL);
        if (ra->images[i])
            vkDestroyImage(dev, ra->images[i], NULL);
        if (ra->memory[i])
            vkFreeMemory(dev, ra->memory[i], NULL);
        ra->views[i] = VK_NULL_HANDLE, ra->images[i] = VK_NULL_HANDLE, ra->memory[i] = VK_NULL_HANDLE;
    }
    ra->width = ra->height = 0;
}

/* Images, framebuffer and read-back buffer at width x height (kept while the size stays). */
static int make_targets(raster *ra, int width, int height, tpk_diag *diag)
{
    if (ra->width == width && ra->height == height)
        return 0;
    vkDeviceWaitIdle(ra->iso->ctx.device);
    destroy_targets(ra);
    ra->choice = -1; /* the paths' speeds depend on the size: measured again */
    ra->samples = 0;
    ra->vis_failed = 0;
    ra->width = width;
    ra->height = height;
    VkFramebufferCreateInfo fb = {.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO, .renderPass = ra->pass,
                                  .attachmentCount = 2, .pAttachments = ra->views, .width = (uint32_t)width,
                                  .height = (uint32_t)height, .layers = 1};
    int rc = image(ra, 0, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT, diag) ||
             image(ra, 1, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                   diag) ||
             ok(vkCreateFramebuffer(ra->iso->ctx.device, &fb, NULL, &ra->framebuffer), "creating the framebuffer", diag) ||
             tpk_vk_buffer_create(&ra->iso->ctx, 4 * (VkDeviceSize)width * (VkDeviceSize)height,
                                  VK_BUFFER_USAGE_TRANSFER_DST_BIT, TPK_VK_MEMORY_READBACK, "iso raster image",
                                  &ra->readback, diag)
                 ? -1
                 : 0;
    if (rc == 0 && !ra->readback.mapped)
        rc = tpk_diag_fail(diag, "render: --iso-raster: no host-visible memory for the image");
    if (rc != 0)
        destroy_targets(ra);
    return rc;
}

void tpk_iso_raster_destroy(raster *ra)
{
    if (!ra)
        return;
    if (ra->iso && ra->iso->ctx.device) {
        VkDevice dev = ra->iso->ctx.device;
        vkDeviceWaitIdle(dev);
        destroy_targets(ra);
        for (int i = 0; i < RASTER_VALUES; i++) {
            tpk_vk_buffer_destroy(&ra->iso->ctx, &ra->corners[i]);
            tpk_vk_buffer_destroy(&ra->iso->ctx, &ra->args[i]);
        }
        if (ra->pipeline)
            vkDestroyPipeline(dev, ra->pipeline, NULL);
        if (ra->mesh_pipeline)
            vkDestroyPipeline(dev, ra->mesh_pipeline, NULL);
        for (int i = 0; i < 2; i++) {
            if (ra->shaders[i])
                vkDestroyShaderModule(dev, ra->shaders[i], NULL);
            if (ra->mesh_shaders[i])
                vkDestroyShaderModule(dev, ra->mesh_shaders[i], NULL);
        }
        tpk_vk_buffer_destroy(&ra->iso->ctx, &ra->ranges);
        tpk_iso_vis_destroy(ra->vis);
        tpk_vk_buffer_destroy(&ra->iso->ctx, &ra->probes);
        if (ra->mesh_pool)
            vkDestroyDescriptorPool(dev, ra->mesh_pool, NULL);
        if (ra->mesh_layout)
            vkDestroyPipelineLayout(dev, ra->mesh_layout, NULL);
        if (ra->mesh_set_layout)
            vkDestroyDescriptorSetLayout(dev, ra->mesh_set_layout, NULL);
        if (ra->pool)
            vkDestroyDescriptorPool(dev, ra->pool, NULL);
        if (ra->layout)
            vkDestroyPipelineLayout(dev, ra->layout, NULL);
        if (ra->set_layout)
            vkDestroyDescriptorSetLayout(dev, ra->set_layout, NULL);
        if (ra->pass)
            vkDestroyRenderPass(dev, ra->pass, NULL);
    }
    tpk_iso_vk_destroy(ra->iso);
    free(ra);
}

int tpk_iso_raster_create(raster **out, const tpk_mesh_arrays *mesh, tpk_diag *diag)
{
    *out = NULL;
    if (!mesh->scalars)
        return tpk_diag_fail(diag, "render: --iso-raster draws the isosurfaces of a point field: the file has none");
    int32_t *tets = malloc(16 * (size_t)(mesh->tet_count ? mesh->tet_count : 1));
    if (!tets)
        return tpk_diag_fail(diag, "render: out of memory for the tets");
    tpk_result r = tpk_recover_tets_threads(mesh, tets, tpk_thread_count(0));
    if (r != TPK_OK) {
        free(tets);
        return tpk_diag_fail(diag, "render: --iso-raster: the tets' vertex order: %s", tpk_result_string(r));
    }
    tpk_iso_input in = {(int64_t)mesh->vertex_count, (int64_t)mesh->tet_count, {0, 0, 0}, mesh->positions, tets,
                        mesh->scalars, NULL};
    memcpy(in.origin, mesh->origin, sizeof in.origin);
    raster *ra = calloc(1, sizeof *ra);
    if (!ra) {
        free(tets);
        return tpk_diag_fail(diag, "render: out of memory");
    }
    ra->mesh = mesh;
    ra->diagonal = tpk_positions_diagonal(mesh);
    ra->choice = -1;
    ra->measured[0] = ra->measured[1] = -1;
    int rc = tpk_iso_vk_create_with(&ra->iso, &in, 1, diag); /* the arrays are copied to the device */
    if (rc == 0 && !(ra->iso->ctx.props.limits.maxPushConstantsSize >= sizeof(raster_push)))
        rc = tpk_diag_fail(diag, "render: --iso-raster: the device's push constants are too small");
    if (rc == 0)
        rc = tpk_vk_buffer_create(&ra->iso->ctx, sizeof(probe_block), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                  TPK_VK_MEMORY_UPLOAD, "iso raster probes", &ra->probes, diag);
    if (rc == 0 && !ra->probes.mapped)
        rc = tpk_diag_fail(diag, "render: --iso-raster: no host-visible memory for the probes");
    if (rc == 0)
        rc = make_pipeline(ra, diag);
    if (rc == 0)
        rc = setup_mesh_path(ra, tets, diag);
    free(tets);
    if (rc != 0) {
        tpk_iso_raster_destroy(ra);
        return -1;
    }
    *out = ra;
    return 0;
}

const char *tpk_iso_raster_device(const raster *ra)
{
    return tpk_iso_vk_device(ra->iso);
}

/* Value i's triangle list and draw arguments copied out of the extractor's buffers into its own. */
typedef struct keep_arg {
    raster *ra;
    int i;
    double value;
    VkDeviceSize bytes;
} keep_arg;

static void record_keep(tpk_iso_vk *v, const void *arg)
{
    const keep_arg *k = arg;
    tpk_iso_vk_time(v, 0);
    tpk_iso_vk_record(v, 2, 3, k->value);
    tpk_iso_vk_time(v, 1);
    VkBufferCopy corners = {0, 0, k->bytes}, args = {0, 0, 16};
    if (k->bytes)
        vkCmdCopyBuffer(v->cmd, v->buf[B_CORNERS].buffer, k->ra->corners[k->i].buffer, 1, &corners);
    vkCmdCopyBuffer(v->cmd, v->buf[B_DRAW_ARGS].buffer, k->ra->args[k->i].buffer, 1, &args);
}

/* Value i's triangle list and draw arguments on the compute path, *total its triangles. 0 or -1. */
static int extract_value(raster *ra, int i, double value, uint32_t *total, tpk_diag *diag)
{
    if (tpk_iso_vk_count(ra->iso, value, total, diag))
        return -1;
    VkDeviceSize bytes = (VkDeviceSize)*total * 36;
    tpk_vk_context *ctx = &ra->iso->ctx;
    if (ra->corners[i].size < (bytes ? bytes : 16)) {
        tpk_vk_buffer_destroy(ctx, &ra->corners[i]);
        memset(&ra->corners[i], 0, sizeof ra->corners[i]);
        if (tpk_vk_buffer_create(ctx, bytes ? bytes : 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                 VK_BUFFER_USAGE_TRANSFER_DST_BIT, TPK_VK_MEMORY_DEVICE, "iso raster triangles",
                                 &ra->corners[i], diag))
            return -1;
    }
    if (!ra->args[i].buffer &&
        tpk_vk_buffer_create(ctx, 16, VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             TPK_VK_MEMORY_DEVICE, "iso raster draw arguments", &ra->args[i], diag))
        return -1;
    keep_arg k = {ra, i, value, bytes};
    if (tpk_iso_vk_submit(ra->iso, record_keep, &k, diag))
        return -1;
    VkDescriptorBufferInfo info = {ra->corners[i].buffer, 0, VK_WHOLE_SIZE};
    VkWriteDescriptorSet write = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = ra->sets[i],
                                  .dstBinding = 0, .descriptorCount = 1,
                                  .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &info};
    vkUpdateDescriptorSets(ctx->device, 1, &write, 0, NULL);
    return 0;
}

/* The triangle lists of opt's values, extracted again only where a value changed; on the mesh-shader
 * path only their triangle counts (for the statistics), since the mesh shaders make the triangles,
 * unless `lists` (the compute rasterizer draws them). */
static int extract_values(raster *ra, const tpk_render_options *opt, int lists, tpk_diag *diag)
{
    for (int i = 0; i < opt->iso_count; i++) {
        lists |= !ra->mesh_path;
        if (i < ra->value_count && ra->values[i] == opt->iso[i] && (ra->listed[i] || !lists))
            continue;
        uint32_t total;
        if (lists ? extract_value(ra, i, opt->iso[i], &total, diag)
                  : tpk_iso_vk_triangles(ra->iso, opt->iso[i], &total, diag))
            return -1;
        ra->listed[i] = lists;
        ra->values[i] = opt->iso[i];
        ra->triangles[i] = total;
        if (ra->value_count <= i)
            ra->value_count = i + 1;
    }
    return 0;
}

/* The mesh-shader path's draws of `count` values: each value's push constants, then every cluster in
 * draws of at most the device's task workgroup counts (a grid of x by y groups; the task shader skips
 * the clusters past the last). */
static void record_mesh_draws(tpk_iso_vk *v, raster *ra, int count)
{
    const VkPhysicalDeviceMeshShaderPropertiesEXT *lim = &ra->iso->ctx.mesh;
    const VkShaderStageFlags stages = VK_SHADER_STAGE_TASK_BIT_EXT | VK_SHADER_STAGE_MESH_BIT_EXT |
                                      VK_SHADER_STAGE_FRAGMENT_BIT;
    vkCmdBindPipeline(v->cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, ra->mesh_pipeline);
    vkCmdBindDescriptorSets(v->cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, ra->mesh_layout, 0, 1, &ra->mesh_set, 0, NULL);
    uint32_t max_x = lim->maxTaskWorkGroupCount[0] ? lim->maxTaskWorkGroupCount[0] : 65535;
    uint32_t max_y = lim->maxTaskWorkGroupCount[1] ? lim->maxTaskWorkGroupCount[1] : 65535;
    uint32_t max_total = lim->maxTaskWorkGroupTotalCount ? lim->maxTaskWorkGroupTotalCount : 1u << 22;
    for (int i = 0; i < count; i++) {
        mesh_push p = {ra->push[i], tpk_iso_vk_threshold(ra->values[i]), (float)ra->values[i],
                       (uint32_t)ra->mesh->tet_count, 0};
        vkCmdPushConstants(v->cmd, ra->mesh_layout, stages, 0, sizeof p, &p);
        for (uint32_t base = 0; base < ra->clusters;) {
            uint32_t left = ra->clusters - base;
            uint32_t x = left < max_x ? left : max_x;
            uint32_t y = left / x < max_y ? left / x : max_y;
            y = y > max_total / x ? max_total / x : y;
            y = y ? y : 1;
            vkCmdPushConstants(v->cmd, ra->mesh_layout, stages, offsetof(mesh_push, base), 4, &base);
            ra->draw_mesh_tasks(v->cmd, x, y, 1);
            base += x * y;
        }
    }
}

/* Every value's draw in one render pass, then the image out to the read-back buffer. */
typedef struct draw_arg {
    raster *ra;
    int count;
} draw_arg;

static void record_draw(tpk_iso_vk *v, const void *arg)
{
    const draw_arg *d = arg;
    raster *ra = d->ra;
    VkClearValue clears[2] = {{.color = {{ra->clear[0], ra->clear[1], ra->clear[2], ra->clear[3]}}},
                              {.depthStencil = {0.0f, 0}}}; /* reversed depth: 0 is infinitely far */
    tpk_iso_vk_time(v, 0); /* the draw's device time: the render pass alone, without the image's copy out */
    VkRenderPassBeginInfo begin = {.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO, .renderPass = ra->pass,
                                   .framebuffer = ra->framebuffer,
                                   .renderArea = {{0, 0}, {(uint32_t)ra->width, (uint32_t)ra->height}},
                                   .clearValueCount = 2, .pClearValues = clears};
    vkCmdBeginRenderPass(v->cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(v->cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, ra->pipeline);
    VkViewport viewport = {0, 0, (float)ra->width, (float)ra->height, 0, 1};
    VkRect2D scissor = {{0, 0}, {(uint32_t)ra->width, (uint32_t)ra->height}};
    vkCmdSetViewport(v->cmd, 0, 1, &viewport);
    vkCmdSetScissor(v->cmd, 0, 1, &scissor);
    if (ra->mesh_path)
        record_mesh_draws(v, ra, d->count);
    for (int i = 0; !ra->mesh_path && i < d->count; i++) {
        vkCmdBindDescriptorSets(v->cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, ra->layout, 0, 1, &ra->sets[i], 0, NULL);
        vkCmdPushConstants(v->cmd, ra->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                           sizeof ra->push[i], &ra->push[i]);
        vkCmdDrawIndirect(v->cmd, ra->args[i].buffer, 0, 1, 16);
    }
    vkCmdEndRenderPass(v->cmd);
    tpk_iso_vk_time(v, 1);
    VkBufferImageCopy region = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                                .imageExtent = {(uint32_t)ra->width, (uint32_t)ra->height, 1}};
    vkCmdCopyImageToBuffer(v->cmd, ra->images[0], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, ra->readback.buffer, 1, &region);
}

/* The compute rasterizer's frame (ra->vis_frame), then its image out to the read-back buffer. */
static void record_vis(tpk_iso_vk *v, const void *arg)
{
    raster *ra = (raster *)arg;
    tpk_iso_vk_time(v, 0); /* as the graphics draw's: the image's copy out left out */
    tpk_iso_vis_record(ra->vis, v->cmd, &ra->vis_frame);
    tpk_iso_vk_time(v, 1);
    VkBufferCopy region = {0, 0, 4 * (VkDeviceSize)ra->width * (VkDeviceSize)ra->height};
    vkCmdCopyBuffer(v->cmd, tpk_iso_vis_image(ra->vis), ra->readback.buffer, 1, &region);
}

/* The frame drawn by one path (compute 1: the compute rasterizer, 0: the graphics pipeline) into the
 * read-back buffer, *seconds its draw's device time (the submission's wall time without timestamps). */
static int draw_path(raster *ra, int compute, int count, double *seconds, tpk_diag *diag)
{
    double gpu0 = tpk_iso_vk_gpu_seconds(ra->iso), wall0 = tpk_iso_vk_seconds(ra->iso);
    draw_arg d = {ra, count};
    if (compute) {
        tpk_iso_vis_frame *f = &ra->vis_frame;
        f->width = ra->width, f->height = ra->height, f->count = count;
        for (int i = 0; i < count; i++) {
            f->values[i].corners = ra->corners[i].buffer;
            f->values[i].triangles = (uint32_t)ra->triangles[i];
            memcpy(f->values[i].color, ra->push[i].color, sizeof f->values[i].color);
        }
        if (tpk_iso_vis_prepare(ra->vis, f, diag) || tpk_iso_vk_submit(ra->iso, record_vis, ra, diag))
            return -1;
    } else if (tpk_iso_vk_submit(ra->iso, record_draw, &d, diag)) {
        return -1;
    }
    double gpu = tpk_iso_vk_gpu_seconds(ra->iso);
    *seconds = gpu >= 0 ? gpu - gpu0 : tpk_iso_vk_seconds(ra->iso) - wall0;
    return 0;
}

/* --iso-raster-path auto where the compute rasterizer cannot draw (its set-up failed, or its buffers
 * exceed a device limit at this size): the graphics path draws, measured no further. */
static void vis_unusable(raster *ra, tpk_diag *diag)
{
    ra->vis_failed = 1;
    ra->samples = MEASURES;
    ra->choice = TPK_ISO_RASTER_GRAPHICS;
    ra->measured[1] = -1;
    diag->message[0] = 0;
}

/* The camera, light and background of the compute rasterizer's frame, from value 0's push constants. */
static void vis_camera(raster *ra)
{
    tpk_iso_vis_frame *f = &ra->vis_frame;
    const raster_push *p = &ra->push[0];
    memcpy(f->eye, p->eye, sizeof f->eye);
    memcpy(f->forward, p->forward, sizeof f->forward);
    memcpy(f->right, p->right, sizeof f->right);
    memcpy(f->up, p->up, sizeof f->up);
    memcpy(f->light, p->light, sizeof f->light);
    memcpy(f->clip_lo, p->clip_lo, sizeof f->clip_lo);
    memcpy(f->clip_hi, p->clip_hi, sizeof f->clip_hi);
    memcpy(f->background, ra->clear, sizeof f->background);
}

int tpk_iso_raster_frame(raster *ra, const tpk_render_options *opt, uint8_t *rgba, tpk_render_stats *stats,
                         tpk_diag *diag)
{
    double t0 = tpk_now_seconds(), gpu0 = tpk_iso_vk_gpu_seconds(ra->iso);
    const tpk_mesh_arrays *mesh = ra->mesh;
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (tpk_render_check_options(opt, diag) != 0)
        return -1;
    if (opt->tet_scalars) /* no values (view's iso key off): the background alone */
        return tpk_diag_fail(diag, "render: --iso-raster draws the isosurfaces of a point field, not a tet field");
    if (opt->shadows || opt->ao_rays > 0 || (opt->iso_opacity > 0 && opt->iso_opacity < 1))
        return tpk_diag_fail(diag, "render: --iso-raster draws opaque isosurfaces with shading at most: without "
                                   "--shadows, --ao and --iso-opacity (the ray marcher draws those)");
    tpk_render_setup setup;
    if (tpk_render_setup_of(opt, ra->diagonal, &setup, diag) != 0)
        return -1;
    /* the near distance: a millionth of the farthest corner of the mesh's box seen from the eye (depth
     * is near / distance, reversed, in float) */
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
    for (int i = 0; i < opt->iso_count; i++) {
        raster_push *p = &ra->push[i];
        memset(p, 0, sizeof *p);
        for (int k = 0; k < 3; k++) {
            p->eye[k] = (float)eye[k];
            p->forward[k] = (float)setup.basis.forward[k];
            p->right[k] = (float)setup.basis.right[k];
            p->up[k] = (float)setup.basis.up[k];
            p->light[k] = (float)(setup.light[k] - mesh->origin[k]);
            p->clip_lo[k] = (float)(opt->clip_min[k] - mesh->origin[k]);
            p->clip_hi[k] = (float)(opt->clip_max[k] - mesh->origin[k]);
        }
        p->eye[3] = (float)(far * 1e-6);
        p->right[3] = (float)setup.basis.tan_half_x;
        p->up[3] = (float)setup.basis.tan_half_y;
        p->light[3] = opt->shading ? 1.0f : 0.0f;
        p->clip_lo[3] = opt->clip ? 1.0f : 0.0f;
        double c[4], u = setup.inv_range == 0 ? 0.5 : (opt->iso[i] - setup.range_min) * setup.inv_range;
        tpk_tf_eval(opt->tf, u, c);
        for (int k = 0; k < 3; k++)
            p->color[k] = (float)c[k];
    }
    for (int k = 0; k < 4; k++)
        ra->clear[k] = k < 3 ? opt->background[k] * opt->background[3] : opt->background[3];
    probe_block pb;
    memset(&pb, 0, sizeof pb);
    pb.count[0] = opt->probe_count;
    for (int i = 0; i < opt->probe_count && i < TPK_RENDER_MAX_PROBES; i++) {
        const tpk_probe *p = &opt->probes[i];
        pb.kind[i][0] = p->shape, pb.kind[i][1] = p->cut;
        for (int k = 0; k < 3; k++) { /* a half-space's b is a direction, the others' a point */
            pb.a[i][k] = (float)(p->a[k] - mesh->origin[k]);
            pb.b[i][k] = (float)(p->shape == TPK_PROBE_PLANE ? p->b[k] : p->b[k] - mesh->origin[k]);
        }
        pb.a[i][3] = (float)p->radius;
    }
    memcpy(ra->probes.mapped, &pb, sizeof pb);
    if (tpk_vk_buffer_flush(&ra->iso->ctx, &ra->probes, diag))
        return -1;
    if (make_targets(ra, opt->width, opt->height, diag))
        return -1;
    /* which path draws: forced, or measured on the first frame at this size (both drawn, timed on the
     * device) and the faster kept */
    int path = opt->iso_raster_path, measure = path == TPK_ISO_RASTER_AUTO && ra->samples < MEASURES;
    int compute = path == TPK_ISO_RASTER_COMPUTE || (path == TPK_ISO_RASTER_AUTO && ra->choice == TPK_ISO_RASTER_COMPUTE);
    if ((compute || measure) && !ra->vis && tpk_iso_vis_create(&ra->vis, &ra->iso->ctx, ra->probes.buffer, diag)) {
        if (path != TPK_ISO_RASTER_AUTO)
            return -1;
        compute = measure = 0;
        vis_unusable(ra, diag);
    }
    if (extract_values(ra, opt, compute || measure, diag))
        return -1;
    vis_camera(ra);
    size_t bytes = 4 * (size_t)ra->width * (size_t)ra->height;
    double draw = 0;
    if (measure) {
        double t[2];
        if (draw_path(ra, 0, opt->iso_count, &t[0], diag) ||
            tpk_vk_buffer_invalidate(&ra->iso->ctx, &ra->readback, diag))
            return -1;
        memcpy(rgba, ra->readback.mapped, bytes);
        int failed = draw_path(ra, 1, opt->iso_count, &t[1], diag); /* e.g. its buffers over a device limit */
        for (int k = 0; k < 2; k++)
            ra->measured[k] = ra->samples == 0 || t[k] < ra->measured[k] ? t[k] : ra->measured[k];
        ra->samples++;
        if (failed)
            vis_unusable(ra, diag);
        compute = !failed && ra->measured[1] < ra->measured[0];
        ra->choice = compute ? TPK_ISO_RASTER_COMPUTE : TPK_ISO_RASTER_GRAPHICS;
        draw = t[compute];
    } else if (draw_path(ra, compute, opt->iso_count, &draw, diag)) {
        return -1;
    }
    if (compute || !measure) { /* else the graphics draw's picture is in rgba already */
        if (tpk_vk_buffer_invalidate(&ra->iso->ctx, &ra->readback, diag))
            return -1;
        memcpy(rgba, ra->readback.mapped, bytes);
    }
    if (stats) {
        stats->tet_steps = 0;
        for (int i = 0; i < opt->iso_count; i++)
            stats->iso_triangles += ra->triangles[i];
        stats->seconds = tpk_now_seconds() - t0;
        /* device time (timestamps): the extraction passes this frame ran (values that changed) and the
         * draw, without the copies to the host; the draw alone apart */
        double timed = tpk_iso_vk_gpu_seconds(ra->iso);
        stats->gpu_seconds = timed < 0 ? -1.0 : timed - gpu0;
        stats->iso_draw_gpu_seconds = timed < 0 ? -1.0 : draw;
        stats->iso_mesh_shader = ra->mesh_state;
        stats->iso_mesh_reason = ra->mesh_path ? NULL : ra->mesh_reason;
        if (compute && ra->mesh_state == 1) { /* the device has the mesh path; the compute rasterizer drew */
            stats->iso_mesh_shader = 2;
            stats->iso_mesh_reason = "the compute rasterizer drew";
        }
        stats->iso_raster_compute = compute;
        stats->iso_raster_atomics = ra->vis ? tpk_iso_vis_atomic_bits(ra->vis) : 0;
        stats->iso_raster_measured = measure;
        stats->iso_raster_seconds[0] = ra->measured[0], stats->iso_raster_seconds[1] = ra->measured[1];
        stats->iso_raster_note = ra->vis_failed ? "the compute rasterizer could not draw at this size" : NULL;
    }
    return 0;
}

int tpk_render_iso_raster(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                          tpk_render_stats *stats, tpk_diag *diag)
{
    double t0 = tpk_now_seconds();
    raster *ra;
    if (tpk_render_check_options(opt, diag) != 0)
        return -1;
    if (opt->iso_count < 1 || opt->tet_scalars)
        return tpk_diag_fail(diag, "render: --iso-raster draws the isosurfaces of a point field: give --iso V and a "
                                   "point field");
    if (tpk_iso_raster_create(&ra, mesh, diag) != 0)
        return -1;
    int rc = tpk_iso_raster_frame(ra, opt, rgba, stats, diag);
    if (rc == 0 && stats) {
        stats->seconds = tpk_now_seconds() - t0; /* set-up included, as the other renderers' */
        stats->tet_steps = (uint64_t)mesh->tet_count * (uint64_t)opt->iso_count; /* tets classified */
        /* a failed mesh-path set-up's message lives in the raster freed below: keep a copy for the caller
         * (valid until this thread's next one-shot frame) */
        static _Thread_local char reason[sizeof ra->mesh_failure];
        if (stats->iso_mesh_reason == ra->mesh_failure) {
            memcpy(reason, ra->mesh_failure, sizeof reason);
            stats->iso_mesh_reason = reason;
        }
    }
    tpk_iso_raster_destroy(ra);
    return rc;
}
