/* Private declarations of the Vulkan renderer (tools/render_vk/). Owners, top to bottom (a file calls
 * only files below it):
 *   vk_iso.c       render_vk.h: tpk_iso_vk_* (marching tetrahedra in compute, shaders/iso.comp), on
 *                  vk_context.c only
 *   vk_present.c   render_vk_present.h: the window's swapchain, each frame's bands copied into it
 *   render_vk.c    render_vk.h: the renderer (upload, dispatch in bands, read back), tpk_render_vulkan,
 *                  tpk_vulkan_available
 *   vk_params.c    tpk_vk_check_options, tpk_vk_params_fill: one frame's uniform block
 *   vk_pipeline.c  tpk_vk_pipeline_*: descriptor layout, the embedded shader, one pipeline per layout
 *   vk_pipeline_cache.c  tpk_vk_cache_*: the pipeline cache on disk
 *   vk_arrays.c    tpk_vk_array_*: texel arrays split over bindings; the record-layout checks
 *   vk_staging.c   tpk_vk_stager_*, tpk_vk_source_fill: uploads in pieces through a bounded buffer
 *   vk_context.c   tpk_vk_context_*, tpk_vk_buffer_*, tpk_vk_result_name: instance, device, buffers
 *   vk_memory.c    vk_memory.h: the memory-type choice (pure)
 * The shader and this side share shaders/vk_layout.h. */
#ifndef TPK_RENDER_VK_INTERNAL_H
#define TPK_RENDER_VK_INTERNAL_H

#include <stdint.h>
#include <vulkan/vulkan.h>

#include "base/diag.h"
#include "render/render.h"
#include "render_vk_present.h"
#include "shaders/vk_layout.h"
#include "vk_memory.h"

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
    int unified;                 /* tpk_vk_memory_unified: device memory is the host's */
    int staged;                  /* arrays go through staging, the image through a readback copy: a
                                    discrete GPU, or TPK_VK_MEMORY=staged (tests, on lavapipe) */
    uint32_t timestamp_bits;     /* the queue's timestampValidBits; 0: no timestamps */
    int creation_feedback;       /* VK_EXT_pipeline_creation_feedback enabled */
    VkSurfaceKHR surface;        /* the window's, the queue can present to it and VK_KHR_swapchain is
                                    enabled; VK_NULL_HANDLE: no window */
    int mesh_shader;             /* VK_EXT_mesh_shader enabled with its task and mesh shaders (asked for
                                    by tpk_vk_context_create_mesh, where the device has them) */
    VkPhysicalDeviceMeshShaderPropertiesEXT mesh; /* its limits, when mesh_shader */
    int int64_atomics;           /* shaderBufferInt64Atomics and shaderInt64 enabled (vk_vis.c) */
} tpk_vk_context;

/* Create instance, device and a compute queue. Returns 0, or -1 with a message naming the step and the
 * VkResult; the context is then empty (destroy is still safe). */
int tpk_vk_context_create(tpk_vk_context *ctx, tpk_diag *diag);
/* The same with the window's surface made on the instance (its extensions enabled), a queue family that
 * has compute and can present to it, and VK_KHR_swapchain; NULL: as tpk_vk_context_create. */
int tpk_vk_context_create_presenting(tpk_vk_context *ctx, const tpk_vk_surface_source *surface, tpk_diag *diag);
/* The same with VK_EXT_mesh_shader's task and mesh shaders enabled where the device offers them and
 * TETPACK_ISO_MESH_SHADER is not 0 (ctx->mesh_shader says whether they are); a device without them is
 * no error. */
int tpk_vk_context_create_mesh(tpk_vk_context *ctx, tpk_diag *diag);
/* Does the device offer VK_EXT_mesh_shader with task and mesh shaders? */
int tpk_vk_has_mesh_shader(VkPhysicalDevice physical);
void tpk_vk_context_destroy(tpk_vk_context *ctx);
const char *tpk_vk_result_name(VkResult r);
/* A pool of two timestamp queries on ctx's device (0 written before the work to time, 1 after), or
 * VK_NULL_HANDLE where its queue has no timestamps or the pool cannot be made. */
VkQueryPool tpk_vk_timestamp_pool(const tpk_vk_context *ctx);
/* The device time between the pool's two timestamps (once the submission that wrote them finished), or
 * -1 when they cannot be read. A wrap of the counter between them is taken into account. */
double tpk_vk_timestamp_seconds(const tpk_vk_context *ctx, VkQueryPool pool);

/* A buffer in the memory type tpk_vk_memory_rank puts first for its use (the next when that heap is
 * full), mapped for its lifetime when that type is host-visible. */
typedef struct tpk_vk_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size;
    void *mapped;  /* NULL: not host-visible */
    int coherent;  /* HOST_COHERENT: no flush or invalidate needed */
} tpk_vk_buffer;

/* `what` names the buffer in messages ("tet records, part 2"). Returns 0 or -1 with a message. */
int tpk_vk_buffer_create(const tpk_vk_context *ctx, VkDeviceSize size, VkBufferUsageFlags usage,
                         tpk_vk_memory_use use, const char *what, tpk_vk_buffer *out, tpk_diag *diag);
void tpk_vk_buffer_destroy(const tpk_vk_context *ctx, tpk_vk_buffer *b);
/* Make CPU writes visible to the device (flush) or device writes to the CPU (invalidate), for memory
 * that is not coherent; no-ops otherwise. 0 or -1 with a message. */
int tpk_vk_buffer_flush(const tpk_vk_context *ctx, const tpk_vk_buffer *b, tpk_diag *diag);
int tpk_vk_buffer_invalidate(const tpk_vk_context *ctx, const tpk_vk_buffer *b, tpk_diag *diag);

/* Where an array's texels come from: `data` (texel_size bytes each; NULL: zeros), or `fill`, which
 * writes texels [first, first + count) into dst (arrays built on the fly: no host copy of them). */
typedef struct tpk_vk_source {
    const void *data;
    uint32_t texel_size;
    void (*fill)(void *dst, uint64_t first, uint64_t count, const void *user);
    const void *user;
} tpk_vk_source;
void tpk_vk_source_fill(const tpk_vk_source *src, void *dst, uint64_t first, uint64_t count);

/* Uploads through two staging slots of TPK_VK_STAGING_BYTES / 2 each (the environment variable of
 * that name overrides it, for tests): the GPU copies one while the CPU fills the other. */
#define TPK_VK_STAGING_BYTES ((uint64_t)64 << 20)
typedef struct tpk_vk_stager {
    tpk_vk_buffer slots[2];
    VkCommandPool pool;
    VkCommandBuffer cmd[2];
    VkFence fence[2];
    VkDeviceSize slot_bytes;
    int next;
    uint64_t bytes, pieces; /* uploaded so far */
} tpk_vk_stager;
/* Slots no larger than `largest` (the largest array part, in bytes) needs. 0 or -1 with a message. */
int tpk_vk_stager_create(const tpk_vk_context *ctx, uint64_t largest, tpk_vk_stager *s, tpk_diag *diag);
/* Copy texels [first, first + count) of src to the start of dst, piece by piece. 0 or -1. */
int tpk_vk_stager_copy(const tpk_vk_context *ctx, tpk_vk_stager *s, const tpk_vk_source *src, uint64_t first,
                       uint64_t count, VkBuffer dst, tpk_diag *diag);
/* Wait for every copy. 0 or -1. */
int tpk_vk_stager_finish(const tpk_vk_context *ctx, tpk_vk_stager *s, tpk_diag *diag);
void tpk_vk_stager_destroy(const tpk_vk_context *ctx, tpk_vk_stager *s);

/* One array of the file as texel buffers: part k holds texels [k << shift, (k + 1) << shift). */
typedef struct tpk_vk_array {
    tpk_vk_buffer parts[TPK_VK_MAX_PARTS];
    VkBufferView views[TPK_VK_MAX_PARTS];
    int part_count;
    int shift;
} tpk_vk_array;

/* shaders/vk_layout.h's TPK_VK_TET_FACES is tpk_tet_faces (format/tetpack_format.h): 1, else 0. */
int tpk_vk_tet_faces_match(void);

/* The largest texel count a binding may hold on this device for texels of `texel_size` bytes: a power
 * of two within maxTexelBufferElements and maxMemoryAllocationSize, lowered by TPK_VK_SPLIT_BYTES. */
uint64_t tpk_vk_part_texels(const tpk_vk_context *ctx, uint32_t texel_size);

/* Upload texel_count texels of src (texel_count 0: one zero texel is made so every binding has a view)
 * into device memory: in place on unified memory, else through `stager`. Returns 0, or -1 with a
 * message (too many parts for the device, out of device memory) naming `what`. */
int tpk_vk_array_upload(const tpk_vk_context *ctx, tpk_vk_stager *stager, const char *what, VkFormat format,
                        const tpk_vk_source *src, uint64_t texel_count, tpk_vk_array *out, tpk_diag *diag);
void tpk_vk_array_destroy(const tpk_vk_context *ctx, tpk_vk_array *a);
/* New contents for texels [0, texel_count) of an uploaded array (the same count or fewer): in place on
 * unified memory, else through `stager`. 0 or -1 with a message. */
int tpk_vk_array_refill(const tpk_vk_context *ctx, tpk_vk_stager *stager, const tpk_vk_source *src,
                        uint64_t texel_count, tpk_vk_array *a, tpk_diag *diag);

/* The marching-tetrahedra extractor (vk_iso.c), here so that the isosurface rasterizer (vk_raster.c) draws
 * from its buffers on its device. */
enum { B_TETS, B_SCALARS, B_POSITIONS, B_CASES, B_COUNTS, B_GROUPS, B_KEYS, B_CORNERS, B_DRAW_ARGS,
       TPK_ISO_VK_BUFFERS };

typedef struct iso_push {
    uint32_t mode, tet_count, group_count;
    float threshold, value;
    uint32_t base;
} iso_push;

struct tpk_iso_vk {
    tpk_vk_context ctx;
    tpk_vk_buffer buf[TPK_ISO_VK_BUFFERS];
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkShaderModule shader;
    VkPipeline pipeline;
    VkDescriptorPool pool;
    VkDescriptorSet set;
    VkCommandPool commands;
    VkCommandBuffer cmd;
    VkFence fence;
    int64_t tet_count;
    uint32_t group_count;
    double wall_seconds; /* submit to fence: the dispatches and copies, so far (tpk_iso_vk_seconds) */
    VkQueryPool timestamps; /* two, written by tpk_iso_vk_time; VK_NULL_HANDLE when the queue has none */
    int timed;              /* this submission wrote both */
    double timed_seconds;   /* device time between the pairs of timestamps, so far */
    int64_t triangles;  /* so far */
};

/* Run the passes `first`..`last` of shaders/iso.comp for `value` into the current command buffer (bound
 * pipeline and set, a barrier after each): 0 classify and scan per group, 1 scan of the groups, 2 emit,
 * 3 draw arguments. */
void tpk_iso_vk_record(tpk_iso_vk *v, int first, int last, double value);
/* A timestamp into the current command buffer: end 0 before the work to time (top of pipe), 1 after it
 * (bottom of pipe); the submission adds the time between them to timed_seconds (tpk_iso_vk_gpu_seconds).
 * Nothing without timestamps. */
void tpk_iso_vk_time(tpk_iso_vk *v, int end);
/* Passes 0..1 for `value` (submitted, waited for), the triangle count into *total, and the corner
 * buffers grown to hold them. 0 or -1 with a message. */
int tpk_iso_vk_count(tpk_iso_vk *v, double value, uint32_t *total, tpk_diag *diag);
/* Passes 0..1 for `value`: the triangle count alone into *total (no buffer grows). 0 or -1. */
int tpk_iso_vk_triangles(tpk_iso_vk *v, double value, uint32_t *total, tpk_diag *diag);
/* The smallest float >= x (x finite): a float s is >= x exactly when s >= this. The shaders' threshold. */
float tpk_iso_vk_threshold(double x);
/* tpk_iso_vk_create on a context made by tpk_vk_context_create_mesh when mesh_shader is 1 (the
 * rasterizer's), so that ctx.mesh_shader says whether task and mesh shaders are enabled. */
int tpk_iso_vk_create_with(tpk_iso_vk **out, const tpk_iso_input *in, int mesh_shader, tpk_diag *diag);
/* bytes of data into the start of device buffer b on v's device (in place where mapped, else through
 * a host buffer and a copy). 0 or -1 with a message. */
int tpk_iso_vk_upload(tpk_iso_vk *v, tpk_vk_buffer *b, const void *data, size_t bytes, tpk_diag *diag);
/* Submit the commands `record` writes (with `arg`) and wait. 0 or -1 with a message. */
int tpk_iso_vk_submit(tpk_iso_vk *v, void (*record)(tpk_iso_vk *v, const void *arg), const void *arg, tpk_diag *diag);

/* render --iso-raster's compute rasterizer (vk_vis.c; shaders/iso_vis.comp, iso_resolve.comp): the
 * extracted triangle lists rasterized into a visibility buffer by atomics (64-bit where ctx->int64_atomics,
 * else 32-bit in two passes), then each pixel shaded from its triangle into packed RGBA8, as the graphics
 * path draws them (vk_raster.c). */
typedef struct tpk_iso_vis tpk_iso_vis;
typedef struct tpk_iso_vis_value {
    VkBuffer corners;   /* iso.comp's triangle list: 9 floats a triangle, relative to the mesh's origin */
    uint32_t triangles; /* how many */
    float color[4];     /* rgb: the TF at the value */
} tpk_iso_vis_value;
/* One frame: the camera and light relative to the mesh's origin, as shaders/iso_raster.vert takes them. */
typedef struct tpk_iso_vis_frame {
    float eye[4];     /* w: the near distance */
    float forward[4];
    float right[4];   /* w: tan_half_x */
    float up[4];      /* w: tan_half_y */
    float light[4];   /* w: 1 with shading */
    float clip_lo[4]; /* w: 1 with a clip box */
    float clip_hi[4];
    float background[4]; /* premultiplied */
    int width, height, count;
    tpk_iso_vis_value values[TPK_RENDER_MAX_ISO];
} tpk_iso_vis_frame;
/* Pipelines on ctx's device; `probes` is the buffer of iso_raster.frag's Probes block. 0 or -1. */
int tpk_iso_vis_create(tpk_iso_vis **out, const tpk_vk_context *ctx, VkBuffer probes, tpk_diag *diag);
/* The buffers for frame (its size, its triangle counts) and the descriptors of its lists; before
 * recording it, while the device does not use them. 0 or -1 with a message. */
int tpk_iso_vis_prepare(tpk_iso_vis *vis, const tpk_iso_vis_frame *frame, tpk_diag *diag);
/* Clear, rasterize and resolve frame into cmd, ending with a barrier before transfers read the image. */
void tpk_iso_vis_record(tpk_iso_vis *vis, VkCommandBuffer cmd, const tpk_iso_vis_frame *frame);
/* The image the last recorded frame writes: width x height packed RGBA8, row by row (a transfer source). */
VkBuffer tpk_iso_vis_image(const tpk_iso_vis *vis);
/* 64 or 32: the width of the atomics it rasterizes with. */
int tpk_iso_vis_atomic_bits(const tpk_iso_vis *vis);
void tpk_iso_vis_destroy(tpk_iso_vis *vis);

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
    int32_t cast_count[4]; /* AO rays, the row after the band, the slice */
    int32_t probe_info[4]; /* probe count, bit i: probe i cuts */
    float probe_a[TPK_VK_MAX_PROBES][4]; /* xyz: center, point or min (relative to the origin); w: shape */
    float probe_b[TPK_VK_MAX_PROBES][4]; /* xyz: the plane's normal or the box's max; w: the radius */
    float tf_s[TPK_VK_TF_MAX];
    float tf_rgba[TPK_VK_TF_MAX][4];
} tpk_vk_params;

/* The arguments given, tpk_render_check_options (the check of every backend, so the same options are
 * refused with the same message), then the limits of this renderer's own buffers (each named "Vulkan
 * limit"). Returns 0 or -1 with a message. */
int tpk_vk_check_options(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, const uint8_t *rgba,
                         tpk_diag *diag);
/* Fill the uniform block for one frame: diagonal is the positions' (tpk_positions_diagonal, kept by the
 * caller: a pass over the vertices), extent the marcher's (box padding), face_count the shell's.
 * Returns 0, or -1 with a message (a bad camera). */
int tpk_vk_params_fill(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, double diagonal, double extent,
                       int64_t face_count, tpk_vk_params *p, tpk_diag *diag);
/* The TPK_VK_EFFECT_* bits the options ask for. */
int tpk_vk_effects(const tpk_render_options *opt);

/* The pipeline cache (vk_pipeline_cache.c): loaded from the cache file of this device, driver and
 * shader when one is valid, written back (atomically) at close when pipelines were compiled into it.
 * Never an error: without a cache directory or a valid file it starts empty or is VK_NULL_HANDLE. */
typedef struct tpk_vk_cache {
    VkPipelineCache cache; /* VK_NULL_HANDLE: none */
    char *path;            /* NULL: no cache file (TPK_VK_PIPELINE_CACHE=0, no home) */
    uint64_t shader_hash;
    size_t loaded_bytes; /* driver data taken from the file; 0: none */
    int compiled;        /* pipelines created through it */
    int hits;            /* of those, found in it; -1: the driver does not say (no creation feedback) */
} tpk_vk_cache;
void tpk_vk_cache_open(const tpk_vk_context *ctx, const void *spirv, size_t spirv_size, tpk_vk_cache *c);
void tpk_vk_cache_close(const tpk_vk_context *ctx, tpk_vk_cache *c);

/* Descriptor layout, pipeline layout and the compute pipelines of one marcher layout and one set of
 * array splits: one pipeline per combination of effects, made when first needed. */
typedef struct tpk_vk_pipeline {
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkShaderModule shader;
    int one_part; /* shader is the module for arrays in one part each (TPK_VK_ONE_PART) */
    VkPipeline pipelines[TPK_VK_EFFECT_MASKS];
    VkDescriptorPool pool;
    VkDescriptorSet set;
    int layout_id;
    int32_t spec[TPK_VK_SPEC_COUNT];
    tpk_vk_cache cache;
} tpk_vk_pipeline;

/* The pipeline for `effects` (TPK_VK_EFFECT_* bits), compiled on first use. Returns VK_NULL_HANDLE
 * with a message on failure. */
VkPipeline tpk_vk_pipeline_get(const tpk_vk_context *ctx, tpk_vk_pipeline *p, int effects, tpk_diag *diag);

/* layout_id: TPK_VK_LAYOUT_*; arrays: TPK_VK_ARRAY_COUNT uploaded arrays (their splits become
 * specialization constants). Binds params, pixels and counters too. Returns 0 or -1 with a message. */
int tpk_vk_pipeline_create(const tpk_vk_context *ctx, int layout_id, const tpk_vk_array arrays[],
                           const tpk_vk_buffer *params, const tpk_vk_buffer *pixels,
                           const tpk_vk_buffer *counters, const tpk_vk_buffer *state, tpk_vk_pipeline *out,
                           tpk_diag *diag);
void tpk_vk_pipeline_destroy(const tpk_vk_context *ctx, tpk_vk_pipeline *p);
/* Bind array `array` (TPK_VK_ARRAY_*) anew, uploaded after the pipeline was created (the range BVH, on
 * the first frame that culls): its descriptors and its split constants for pipelines made from now on.
 * Only the TPK_VK_EFFECT_CULL pipelines read the range arrays, so none of those may exist yet (-1 with
 * a message). The set must not be in use by a pending submission. */
int tpk_vk_pipeline_rebind(const tpk_vk_context *ctx, tpk_vk_pipeline *p, int array, const tpk_vk_array *a,
                           tpk_diag *diag);
/* The edge test of the FP64 variant for this device: TPK_VK_EXACT_FILTER or TPK_VK_EXACT_ALWAYS. */
int tpk_vk_exact_mode(const tpk_vk_context *ctx);
/* Whether rays run in slices (vk_layout.h, TPK_VK_SPEC_SLICED): on CPU devices, whose llvmpipe cuts
 * loops short past 65535 iterations in all; TPK_VK_SLICED=0|1 overrides, for tests. */
int tpk_vk_sliced(const tpk_vk_context *ctx);

/* Where a presenting frame's bands go instead of the host (vk_present.c): `record` adds, after the
 * band's dispatch and a barrier that makes its pixels readable by transfers, commands that copy rows
 * [row0, row0 + rows) of a `width`-pixel image, packed RGBA8 from the start of `pixels`, into the
 * target. Sliced rays record it after every slice; the last one's copy is the band's final pixels. */
typedef struct tpk_vk_band_target {
    void (*record)(VkCommandBuffer cmd, VkBuffer pixels, int width, int row0, int rows, void *user);
    void *user;
} tpk_vk_band_target;
/* tpk_vk_renderer_frame with the bands going to `target`: only the statistics are read back. */
int tpk_vk_renderer_frame_to(tpk_vk_renderer *renderer, const tpk_render_options *opt,
                             const tpk_vk_band_target *target, tpk_render_stats *stats, tpk_diag *diag);
const tpk_vk_context *tpk_vk_renderer_context(const tpk_vk_renderer *renderer);

/* The SPIR-V of shaders/render.comp with TPK_VK_FP64 1 and 0, and of both with TPK_VK_ONE_PART 1 (_one:
 * for arrays in one part each) (generated at build time by glslc, render_spv.c); sizes in bytes. */
extern const uint32_t tpk_vk_render_spv_fp64[], tpk_vk_render_spv_fp32[];
extern const size_t tpk_vk_render_spv_fp64_size, tpk_vk_render_spv_fp32_size;
extern const uint32_t tpk_vk_render_spv_fp64_one[], tpk_vk_render_spv_fp32_one[];
extern const size_t tpk_vk_render_spv_fp64_one_size, tpk_vk_render_spv_fp32_one_size;

#endif
