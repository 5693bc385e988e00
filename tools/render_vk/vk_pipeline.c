/* The compute pipeline of the renderer: its descriptor layout (shaders/vk_layout.h's bindings), the
 * SPIR-V embedded at build time, and the specialization constants that pick the marcher (Tet16, Tet20,
 * Tet32) and tell the shader how each array is split. */
#include <stdlib.h>
#include <string.h>

#include "render_vk_internal.h"

static int fail(tpk_diag *diag, const char *step, VkResult r)
{
    return tpk_diag_fail(diag, "vulkan: %s failed: %s", step, tpk_vk_result_name(r));
}

static int create_set_layout(const tpk_vk_context *ctx, tpk_vk_pipeline *p, tpk_diag *diag)
{
    VkDescriptorSetLayoutBinding b[TPK_VK_BIND_COUNT];
    memset(b, 0, sizeof b);
    for (uint32_t i = 0; i < TPK_VK_BIND_COUNT; i++) {
        b[i].binding = i;
        b[i].descriptorCount = 1;
        b[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
        b[i].descriptorType = i == TPK_VK_BIND_PARAMS ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
                              : i < TPK_VK_BIND_ARRAY(0) ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
                                                         : VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    }
    VkDescriptorSetLayoutCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
        .bindingCount = TPK_VK_BIND_COUNT,
        .pBindings = b,
    };
    VkResult r = vkCreateDescriptorSetLayout(ctx->device, &info, NULL, &p->set_layout);
    if (r != VK_SUCCESS)
        return fail(diag, "creating the descriptor set layout", r);
    VkPipelineLayoutCreateInfo pl = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
        .setLayoutCount = 1,
        .pSetLayouts = &p->set_layout,
    };
    r = vkCreatePipelineLayout(ctx->device, &pl, NULL, &p->layout);
    return r == VK_SUCCESS ? 0 : fail(diag, "creating the pipeline layout", r);
}

/* CPU devices run both sides of every branch, so the always-double edge test is cheaper there than a
 * filter with a rarely taken slow path (vk_layout.h). TPK_VK_EXACT=1|2 overrides, for tests. */
int tpk_vk_exact_mode(const tpk_vk_context *ctx)
{
    const char *env = getenv("TPK_VK_EXACT");
    if (env && (!strcmp(env, "1") || !strcmp(env, "2")))
        return atoi(env);
    return ctx->props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU ? TPK_VK_EXACT_ALWAYS : TPK_VK_EXACT_FILTER;
}

int tpk_vk_sliced(const tpk_vk_context *ctx)
{
    const char *env = getenv("TPK_VK_SLICED");
    if (env && (!strcmp(env, "0") || !strcmp(env, "1")))
        return atoi(env);
    return ctx->props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
}

/* The module for arrays in one part each (TPK_VK_ONE_PART: no parts' switch, less for the driver to
 * compile) or for split ones, with its pipeline cache, in place of the one `p` had. Pipelines made from
 * the old module stay valid. */
static int load_module(const tpk_vk_context *ctx, int one_part, tpk_vk_pipeline *p, tpk_diag *diag)
{
    VkShaderModuleCreateInfo sm = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    if (ctx->fp64) {
        sm.codeSize = one_part ? tpk_vk_render_spv_fp64_one_size : tpk_vk_render_spv_fp64_size;
        sm.pCode = one_part ? tpk_vk_render_spv_fp64_one : tpk_vk_render_spv_fp64;
    } else {
        sm.codeSize = one_part ? tpk_vk_render_spv_fp32_one_size : tpk_vk_render_spv_fp32_size;
        sm.pCode = one_part ? tpk_vk_render_spv_fp32_one : tpk_vk_render_spv_fp32;
    }
    VkShaderModule shader;
    VkResult r = vkCreateShaderModule(ctx->device, &sm, NULL, &shader);
    if (r != VK_SUCCESS)
        return fail(diag, "loading the shader", r);
    if (p->shader) {
        vkDestroyShaderModule(ctx->device, p->shader, NULL);
        tpk_vk_cache_close(ctx, &p->cache);
    }
    p->shader = shader;
    p->one_part = one_part;
    tpk_vk_cache_open(ctx, sm.pCode, sm.codeSize, &p->cache);
    return 0;
}

static int create_shader(const tpk_vk_context *ctx, int layout_id, const tpk_vk_array arrays[], tpk_vk_pipeline *p,
                         tpk_diag *diag)
{
    int one_part = 1;
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++)
        one_part &= arrays[a].part_count <= 1;
    if (load_module(ctx, one_part, p, diag) != 0)
        return -1;
    int32_t *values = p->spec;
    values[TPK_VK_SPEC_LAYOUT] = layout_id;
    values[TPK_VK_SPEC_EXACT] = tpk_vk_exact_mode(ctx);
    values[TPK_VK_SPEC_SLICED] = tpk_vk_sliced(ctx);
    for (int a = 0; a < TPK_VK_ARRAY_COUNT; a++) {
        values[TPK_VK_SPEC_PARTS(a)] = arrays[a].part_count;
        values[TPK_VK_SPEC_SHIFT(a)] = arrays[a].shift;
    }
    return 0;
}

VkPipeline tpk_vk_pipeline_get(const tpk_vk_context *ctx, tpk_vk_pipeline *p, int effects, tpk_diag *diag)
{
    if (effects < 0 || effects >= TPK_VK_EFFECT_MASKS) {
        tpk_diag_fail(diag, "vulkan: no pipeline for effects %d", effects);
        return VK_NULL_HANDLE;
    }
    if (p->pipelines[effects])
        return p->pipelines[effects];
    int32_t values[TPK_VK_SPEC_COUNT];
    memcpy(values, p->spec, sizeof values);
    values[TPK_VK_SPEC_EFFECTS] = effects;
    VkSpecializationMapEntry entries[TPK_VK_SPEC_COUNT];
    for (uint32_t i = 0; i < TPK_VK_SPEC_COUNT; i++)
        entries[i] = (VkSpecializationMapEntry){i, i * (uint32_t)sizeof(int32_t), sizeof(int32_t)};
    VkSpecializationInfo spec = {TPK_VK_SPEC_COUNT, entries, sizeof values, values};
    VkComputePipelineCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                  .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = p->shader,
                  .pName = "main",
                  .pSpecializationInfo = &spec},
        .layout = p->layout,
    };
    VkPipelineCreationFeedbackEXT feedback = {0}, stage_feedback = {0};
    VkPipelineCreationFeedbackCreateInfoEXT feedback_info = {
        .sType = VK_STRUCTURE_TYPE_PIPELINE_CREATION_FEEDBACK_CREATE_INFO_EXT,
        .pPipelineCreationFeedback = &feedback,
        .pipelineStageCreationFeedbackCount = 1,
        .pPipelineStageCreationFeedbacks = &stage_feedback,
    };
    if (ctx->creation_feedback)
        info.pNext = &feedback_info;
    VkResult r = vkCreateComputePipelines(ctx->device, p->cache.cache, 1, &info, NULL, &p->pipelines[effects]);
    if (r != VK_SUCCESS) {
        p->pipelines[effects] = VK_NULL_HANDLE;
        fail(diag, "compiling the compute pipeline", r);
        return VK_NULL_HANDLE;
    }
    p->cache.compiled++;
    if (!ctx->creation_feedback || !(feedback.flags & VK_PIPELINE_CREATION_FEEDBACK_VALID_BIT_EXT))
        p->cache.hits = -1;
    else if (p->cache.hits >= 0 &&
             (feedback.flags & VK_PIPELINE_CREATION_FEEDBACK_APPLICATION_PIPELINE_CACHE_HIT_BIT_EXT))
        p->cache.hits++;
    return p->pipelines[effects];
}

/* Write every binding; parts an array does not use repeat its first view (the shader never reads them). */
static int write_set(const tpk_vk_context *ctx, const tpk_vk_array arrays[], const tpk_vk_buffer *params,
                     const tpk_vk_buffer *pixels, const tpk_vk_buffer *counters, const tpk_vk_buffer *state,
                     tpk_vk_pipeline *p, tpk_diag *diag)
{
    VkDescriptorPoolSize sizes[3] = {
        {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
        {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 3},
        {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, TPK_VK_ARRAY_COUNT * TPK_VK_MAX_PARTS},
    };
    VkDescriptorPoolCreateInfo pool = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
        .maxSets = 1,
        .poolSizeCount = 3,
        .pPoolSizes = sizes,
    };
    VkResult r = vkCreateDescriptorPool(ctx->device, &pool, NULL, &p->pool);
    if (r != VK_SUCCESS)
        return fail(diag, "creating the descriptor pool", r);
    VkDescriptorSetAllocateInfo alloc = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
        .descriptorPool = p->pool,
        .descriptorSetCount = 1,
        .pSetLayouts = &p->set_layout,
    };
    if ((r = vkAllocateDescriptorSets(ctx->device, &alloc, &p->set)) != VK_SUCCESS)
        return fail(diag, "allocating the descriptor set", r);
    VkDescriptorBufferInfo buffers[4] = {{params->buffer, 0, VK_WHOLE_SIZE},
                                         {pixels->buffer, 0, VK_WHOLE_SIZE},
                                         {counters->buffer, 0, VK_WHOLE_SIZE},
                                         {state->buffer, 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet w[TPK_VK_BIND_COUNT];
    memset(w, 0, sizeof w);
    for (uint32_t i = 0; i < TPK_VK_BIND_COUNT; i++) {
        w[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        w[i].dstSet = p->set;
        w[i].dstBinding = i;
        w[i].descriptorCount = 1;
        if (i < TPK_VK_BIND_ARRAY(0)) {
            w[i].descriptorType = i == TPK_VK_BIND_PARAMS ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
                                                          : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
            w[i].pBufferInfo = &buffers[i];
        } else {
            const tpk_vk_array *a = &arrays[(i - TPK_VK_BIND_ARRAY(0)) / TPK_VK_MAX_PARTS];
            int part = (int)((i - TPK_VK_BIND_ARRAY(0)) % TPK_VK_MAX_PARTS);
            w[i].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
            w[i].pTexelBufferView = &a->views[part < a->part_count ? part : 0];
        }
    }
    vkUpdateDescriptorSets(ctx->device, TPK_VK_BIND_COUNT, w, 0, NULL);
    return 0;
}

int tpk_vk_pipeline_rebind(const tpk_vk_context *ctx, tpk_vk_pipeline *p, int array, const tpk_vk_array *a,
                           tpk_diag *diag)
{
    for (int e = 0; e < TPK_VK_EFFECT_MASKS; e++)
        if (p->pipelines[e] && (e & TPK_VK_EFFECT_CULL))
            return tpk_diag_fail(diag, "vulkan: array %d replaced after a pipeline that reads it was made", array);
    /* a split array needs the module with the parts' switch; the pipelines made so far do not read it */
    if (a->part_count > 1 && p->one_part && load_module(ctx, 0, p, diag) != 0)
        return -1;
    VkWriteDescriptorSet w[TPK_VK_MAX_PARTS];
    memset(w, 0, sizeof w);
    for (int part = 0; part < TPK_VK_MAX_PARTS; part++) {
        w[part].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        w[part].dstSet = p->set;
        w[part].dstBinding = (uint32_t)(TPK_VK_BIND_ARRAY(array) + part);
        w[part].descriptorCount = 1;
        w[part].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
        w[part].pTexelBufferView = &a->views[part < a->part_count ? part : 0];
    }
    vkUpdateDescriptorSets(ctx->device, TPK_VK_MAX_PARTS, w, 0, NULL);
    p->spec[TPK_VK_SPEC_PARTS(array)] = a->part_count;
    p->spec[TPK_VK_SPEC_SHIFT(array)] = a->shift;
    return 0;
}

int tpk_vk_pipeline_create(const tpk_vk_context *ctx, int layout_id, const tpk_vk_array arrays[],
                           const tpk_vk_buffer *params, const tpk_vk_buffer *pixels,
                           const tpk_vk_buffer *counters, const tpk_vk_buffer *state, tpk_vk_pipeline *out,
                           tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    if (create_set_layout(ctx, out, diag) != 0 || create_shader(ctx, layout_id, arrays, out, diag) != 0 ||
        write_set(ctx, arrays, params, pixels, counters, state, out, diag) != 0) {
        tpk_vk_pipeline_destroy(ctx, out);
        return -1;
    }
    return 0;
}

void tpk_vk_pipeline_destroy(const tpk_vk_context *ctx, tpk_vk_pipeline *p)
{
    if (p->pool)
        vkDestroyDescriptorPool(ctx->device, p->pool, NULL);
    for (int e = 0; e < TPK_VK_EFFECT_MASKS; e++)
        if (p->pipelines[e])
            vkDestroyPipeline(ctx->device, p->pipelines[e], NULL);
    if (p->shader)
        vkDestroyShaderModule(ctx->device, p->shader, NULL);
    tpk_vk_cache_close(ctx, &p->cache);
    if (p->layout)
        vkDestroyPipelineLayout(ctx->device, p->layout, NULL);
    if (p->set_layout)
        vkDestroyDescriptorSetLayout(ctx->device, p->set_layout, NULL);
    memset(p, 0, sizeof *p);
}
