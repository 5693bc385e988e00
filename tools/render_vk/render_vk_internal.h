/* Private declarations of the Vulkan renderer (tools/render_vk/). Owners, top to bottom (a file calls
 * only files below it):
 *   render_vk.c    render_vk.h: the renderer (upload, dispatch in bands, read back), tpk_render_vulkan,
 *                  tpk_vulkan_available
 *   vk_params.c    tpk_vk_check_options, tpk_vk_params_fill: one frame's uniform block
 *   vk_pipeline.c  tpk_vk_pipeline_*: descriptor layout, the embedded shader, one pipeline per layout
 *   vk_arrays.c    tpk_vk_array_*: texel arrays split over bindings; the record-layout checks
 *   vk_context.c   tpk_vk_context_*, tpk_vk_buffer_*, tpk_vk_result_name: instance, device, memory
 * The shader and this side share shaders/vk_layout.h. */
#ifndef TPK_RENDER_VK_INTERNAL_H
#define TPK_RENDER_VK_INTERNAL_H

#include <stdint.h>
#include <vulkan/vulkan.h>

#include "base/diag.h"
#include "render/render.h"
#include "shaders/vk_layout.h"

typedef struct tpk_vk_context {
    VkInstance instance;
    VkPhysicalDevice physical;
    VkDevice device;
    VkQueue queue;
    uint32_t queue_family;
    VkPhysicalDeviceProperties props;
    VkPhysicalDeviceMemoryProperties memory;
    VkDeviceSize max_allocation; /* maxMemoryAllocationSize (Vulkan 1.1) */
    int fp64;                    /* shaderFloat64 supported and enabled */
} tpk_vk_context;

/* Create instance, device and a compute queue. Returns 0, or -1 with a message naming the step and the
 * VkResult; the context is then empty (destroy is still safe). */
int tpk_vk_context_create(tpk_vk_context *ctx, tpk_diag *diag);
void tpk_vk_context_destroy(tpk_vk_context *ctx);
const char *tpk_vk_result_name(VkResult r);

/* A buffer in host-visible, coherent memory (device-local too when the device has such memory: every
 * CPU device and GPUs with a resizable BAR), mapped for its lifetime. */
typedef struct tpk_vk_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size;
    void *mapped;
} tpk_vk_buffer;

/* `what` names the buffer in messages ("tet records, part 2"). Returns 0 or -1 with a message. */
int tpk_vk_buffer_create(const tpk_vk_context *ctx, VkDeviceSize size, VkBufferUsageFlags usage,
                         const char *what, tpk_vk_buffer *out, tpk_diag *diag);
void tpk_vk_buffer_destroy(const tpk_vk_context *ctx, tpk_vk_buffer *b);

/* One array of the file as texel buffers: part k holds texels [k << shift, (k + 1) << shift). */
typedef struct tpk_vk_array {
    tpk_vk_buffer parts[TPK_VK_MAX_PARTS];
    VkBufferView views[TPK_VK_MAX_PARTS];
    int part_count;
    int shift;
} tpk_vk_array;

/* The largest texel count a binding may hold on this device for texels of `texel_size` bytes: a power
 * of two within maxTexelBufferElements and maxMemoryAllocationSize, lowered by TPK_VK_SPLIT_BYTES. */
uint64_t tpk_vk_part_texels(const tpk_vk_context *ctx, uint32_t texel_size);

/* Upload texel_count texels of texel_size bytes (data may be NULL when texel_count is 0: one dummy
 * texel is made so every binding has a view). Returns 0, or -1 with a message (too many parts for the
 * device, out of device memory) naming `what`. */
int tpk_vk_array_upload(const tpk_vk_context *ctx, const char *what, VkFormat format, uint32_t texel_size,
                        const void *data, uint64_t texel_count, tpk_vk_array *out, tpk_diag *diag);
void tpk_vk_array_destroy(const tpk_vk_context *ctx, tpk_vk_array *a);

/* The uniform block of the shader (std140; render.comp's Params). */
typedef struct tpk_vk_params {
    float eye[4];
    float forward[4];
    float right[4];
    float up[4];
    float background[4];
    float scalar_map[4];
    int32_t dims[4];
    int32_t mode[4];
    float clip_lo[4];
    float clip_hi[4];
    int32_t shell_info[4];
    float iso[4];
    float light[4];
    float cast_info[4];
    int32_t cast_count[4];
    float tf_s[TPK_VK_TF_MAX];
    float tf_rgba[TPK_VK_TF_MAX][4];
} tpk_vk_params;

/* The options checks of tpk_render_cpu (same messages). Returns 0 or -1 with a message. */
int tpk_vk_check_options(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, const uint8_t *rgba,
                         tpk_diag *diag);
/* Fill the uniform block for one frame: extent is the marcher's (box padding), face_count the shell's.
 * Returns 0, or -1 with a message (a bad camera). */
int tpk_vk_params_fill(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, double extent,
                       int64_t face_count, tpk_vk_params *p, tpk_diag *diag);
/* The TPK_VK_EFFECT_* bits the options ask for. */
int tpk_vk_effects(const tpk_render_options *opt);

/* Descriptor layout, pipeline layout and the compute pipelines of one marcher layout and one set of
 * array splits: one pipeline per combination of effects, made when first needed. */
typedef struct tpk_vk_pipeline {
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkShaderModule shader;
    VkPipeline pipelines[TPK_VK_EFFECT_MASKS];
    VkDescriptorPool pool;
    VkDescriptorSet set;
    int layout_id;
    int32_t spec[TPK_VK_SPEC_COUNT];
} tpk_vk_pipeline;

/* The pipeline for `effects` (TPK_VK_EFFECT_* bits), compiled on first use. Returns VK_NULL_HANDLE
 * with a message on failure. */
VkPipeline tpk_vk_pipeline_get(const tpk_vk_context *ctx, tpk_vk_pipeline *p, int effects, tpk_diag *diag);

/* layout_id: TPK_VK_LAYOUT_*; arrays: TPK_VK_ARRAY_COUNT uploaded arrays (their splits become
 * specialization constants). Binds params, pixels and steps too. Returns 0 or -1 with a message. */
int tpk_vk_pipeline_create(const tpk_vk_context *ctx, int layout_id, const tpk_vk_array arrays[],
                           const tpk_vk_buffer *params, const tpk_vk_buffer *pixels,
                           const tpk_vk_buffer *steps, tpk_vk_pipeline *out, tpk_diag *diag);
void tpk_vk_pipeline_destroy(const tpk_vk_context *ctx, tpk_vk_pipeline *p);
/* The edge test of the FP64 variant for this device: TPK_VK_EXACT_FILTER or TPK_VK_EXACT_ALWAYS. */
int tpk_vk_exact_mode(const tpk_vk_context *ctx);

/* The SPIR-V of shaders/render.comp with TPK_VK_FP64 1 and 0 (generated at build time by glslc,
 * render_spv.c); sizes in bytes. */
extern const uint32_t tpk_vk_render_spv_fp64[], tpk_vk_render_spv_fp32[];
extern const size_t tpk_vk_render_spv_fp64_size, tpk_vk_render_spv_fp32_size;

#endif
