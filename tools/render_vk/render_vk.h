/* The Vulkan renderer: the same pictures as the CPU reference (tools/render/render.h), from compute
 * shaders on any Vulkan 1.2 device (lavapipe included). The file's arrays are uploaded as they are
 * (texel buffers, split over several bindings when larger than one), plus the shell BVH the CPU
 * marcher builds at load; no connectivity is rebuilt. */
#ifndef TPK_RENDER_VK_H
#define TPK_RENDER_VK_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "iso/iso.h"
#include "render/render.h"

/* Render `mesh` into rgba (width * height * 4 bytes, caller-owned) with the options and definitions of
 * tpk_render_cpu (opt->threads is ignored). stats->tet_steps counts tets stepped through as the CPU
 * reference does. Every Vulkan failure (no loader or device, out of device memory, a file larger than
 * the device's limits, a lost device) returns -1 with a message saying which; never aborts.
 * Environment: TPK_VK_DEVICE=N picks the N-th physical device (default: the first discrete, else
 * integrated, else any); TPK_VK_SPLIT_BYTES=N caps every binding at N bytes (rounded down to a
 * power-of-two texel count), so that the split path can be tested on a small mesh; TPK_VK_NO_FP64=1
 * takes the shader variant without doubles and TPK_VK_EXACT=1|2 the edge test of the FP64 variant
 * (shaders/vk_layout.h), for tests; TPK_VK_MEMORY=staged takes the discrete GPU's memory path (staging
 * upload, readback copy) on any device, TPK_VK_STAGING_BYTES=N and TPK_VK_BAND_PIXELS=N shrink the
 * staging buffer and the bands, for tests; TPK_VK_NO_PRESENT=1 finds no queue that can present to a
 * window (render_vk_present.h), for the viewer's fallback tests. Pipelines are cached on disk under
 * $XDG_CACHE_HOME/tetpack (else ~/.cache/tetpack; TPK_VK_PIPELINE_CACHE=0: not). stats also get
 * gpu_seconds (timestamp queries) and the setup apart (render.h). Not thread-safe with itself (one device each). */
int tpk_render_vulkan(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                      tpk_render_stats *stats, tpk_diag *diag);

/* A renderer kept across frames (the window, benchmarks): the device set up and the arrays uploaded
 * once, then one frame per call with any camera, TF and effect options. `mesh` (and tet_scalars, per
 * tet, or NULL) must outlive the renderer; frames must pass the same tet_scalars (NULL or not) as
 * creation. Create returns 0, or -1 with a message (as tpk_render_vulkan). */
typedef struct tpk_vk_renderer tpk_vk_renderer;
int tpk_vk_renderer_create(tpk_vk_renderer **out, const tpk_mesh_arrays *mesh, const float *tet_scalars,
                           tpk_diag *diag);
/* stats->seconds is the frame alone: parameters, dispatch, wait and read-back (and the pipeline of new
 * effects, compiled on first use); stats->gpu_seconds the dispatches' device time; the setup fields
 * are the renderer's so far. */
int tpk_vk_renderer_frame(tpk_vk_renderer *renderer, const tpk_render_options *opt, uint8_t *rgba,
                          tpk_render_stats *stats, tpk_diag *diag);
const char *tpk_vk_renderer_device(const tpk_vk_renderer *renderer);
/* render.h OCCLUSION AT VERTICES cast on the device, as a frame with --occlusion vertex does (whatever
 * opt->occlusion says): S_v into s[v], A_v into a[v], vertex_count floats each, what tpk_render_vertex_cache
 * gives on the CPU up to the device's float marching (render_vk_effects.vertex_casts_on_device). stats
 * (may be NULL): tet steps, secondary rays, seconds and gpu_seconds of the casts. 0, or -1 with a message. */
int tpk_vk_renderer_vertex_cache(tpk_vk_renderer *renderer, const tpk_render_options *opt, float *s, float *a,
                                 tpk_render_stats *stats, tpk_diag *diag);
void tpk_vk_renderer_destroy(tpk_vk_renderer *renderer);
/* Another field of the same kind for the next frames (a time step): point scalars (vertex_count floats)
 * or tet scalars (tet_count), each NULL or not as at creation, outliving the renderer like the mesh.
 * Only the field goes to the device again (the point field with the positions it is interleaved with);
 * the shell BVH stays, the range culling's tree is made again on the next iso-only frame, and the
 * vertex occlusion cache follows the field. 0, or -1 with a message. */
int tpk_vk_renderer_set_field(tpk_vk_renderer *renderer, const float *scalars, const float *tet_scalars,
                              tpk_diag *diag);

/* Marching tetrahedra in compute (vk_iso.c, shaders/iso.comp), for tetpack iso --backend vulkan: the
 * mesh of `in` (its tets, scalars and positions, copied to the device at creation; `in` need not
 * outlive it), then any number of values. Limits: each array within one storage binding of the device
 * (maxStorageBufferRange), else an error that says so and suggests the CPU. */
typedef struct tpk_iso_vk tpk_iso_vk;
int tpk_iso_vk_create(tpk_iso_vk **out, const tpk_iso_input *in, tpk_diag *diag);
void tpk_iso_vk_destroy(tpk_iso_vk *v);
const char *tpk_iso_vk_device(const tpk_iso_vk *v);
/* Wall time of the device's work so far (submit to fence: dispatches and copies). */
double tpk_iso_vk_seconds(const tpk_iso_vk *v);
/* Device time of the extraction passes so far (timestamp queries: classify to emit, without the copies
 * to the host; on the rasterizer's extractor its draws too), or -1 where the device has no timestamps. */
double tpk_iso_vk_gpu_seconds(const tpk_iso_vk *v);
/* The triangles of `value` as tpk_iso_corners defines them (keys: malloc'ed, 3 per triangle, tet order),
 * and with `positions` (may be NULL) the float positions the shader computed per corner (3 floats each:
 * the triangle list as a GPU would draw it, relative to the mesh's origin). 0 or -1 with a message. */
int tpk_iso_vk_emit(tpk_iso_vk *v, double value, uint64_t **keys, float **positions, int64_t *triangles,
                    tpk_diag *diag);
/* The corner source for tpk_iso_extract_from / tpk_iso_options.corners. */
tpk_iso_corners tpk_iso_vk_corners(tpk_iso_vk *v);

/* render --iso-raster (vk_raster.c): the isosurfaces of opt->iso drawn as triangles (the compute
 * extraction above and an indirect draw per value, depth-tested, two-sided), shaded as the marcher shades
 * an opaque iso hit (the TF at the value; with shading, 0.3 + 0.7 |n . l|, n the triangle's normal, which
 * in its tet is the field's gradient); the clip box discards outside points; the volume is not drawn.
 * Refuses shadows, AO, a partial iso opacity and tet fields (the marcher draws those). The path for
 * devices without VK_EXT_mesh_shader; stats: seconds, gpu_seconds, iso_triangles, and tet_steps the tets
 * classified. 0 or -1 with a message. */
int tpk_render_iso_raster(const tpk_mesh_arrays *mesh, const tpk_render_options *opt, uint8_t *rgba,
                          tpk_render_stats *stats, tpk_diag *diag);
/* The same kept across frames (view): the mesh's arrays on the device and each value's triangle list
 * extracted once, drawn again for every camera; a value that changes is extracted again. `mesh` must
 * outlive it (a new field or step: a new rasterizer). */
typedef struct tpk_iso_raster tpk_iso_raster;
int tpk_iso_raster_create(tpk_iso_raster **out, const tpk_mesh_arrays *mesh, tpk_diag *diag);
int tpk_iso_raster_frame(tpk_iso_raster *raster, const tpk_render_options *opt, uint8_t *rgba,
                         tpk_render_stats *stats, tpk_diag *diag);
const char *tpk_iso_raster_device(const tpk_iso_raster *raster);
void tpk_iso_raster_destroy(tpk_iso_raster *raster);

/* Is a Vulkan 1.2 device with a compute queue present? Returns 1 and writes the device's name into
 * `why` (n bytes), or 0 and writes the reason (no loader, no device, too old). */
int tpk_vulkan_available(char *why, size_t n);

/* The same probe, and what the device is: *kind gets TPK_VK_DEVICE_HARDWARE, TPK_VK_DEVICE_SOFTWARE
 * (VK_PHYSICAL_DEVICE_TYPE_CPU: lavapipe) or TPK_VK_DEVICE_NONE (render/render_backend.h; an int here so
 * that this header needs no other). Returns 1 when there is a device. */
int tpk_vulkan_probe(char *why, size_t n, int *kind);

#endif
