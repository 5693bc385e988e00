/* The Vulkan renderer's data layout, shared by its C side and its GLSL shader (both include this file;
 * only #defines, so it is valid in both languages). vk_arrays.c asserts every record number below
 * against the structs of format/tetpack_format.h, so the shader reads what the format defines.
 *
 * Each array of the file is uploaded unchanged as a texel buffer of 16-byte (or 4-byte) texels:
 *   positions + point scalar   RGBA32F, one texel per vertex: x, y, z (relative to the origin), scalar
 *   Tet16                      RGBA32I, one texel per tet: vx, nx[0], nx[1], nx[2]
 *   Tet32                      RGBA32I, two texels per tet: v[0], v[1], v[2], vx | n[0..3]
 *   Tet20                      R32I, five texels per tet: vx, n[0..3]
 *   shell faces (BVH order)    RGBA32I, one texel per face: a, b, c, t
 *   shell BVH nodes            RGBA32UI, two texels per node: lo xyz (float bits), first | hi xyz, count
 *   tet scalars (tet field)    R32F, one texel per tet
 *   range BVH nodes            RGBA32F, two texels per node in heap order: lo xyz, scalar min | hi xyz,
 *                              scalar max (tpk_range_bvh_heap; iso-only frames that cull, else one texel)
 *   range BVH tets             RGBA32I, one texel per tet: its vertices in positive order
 * An array larger than one binding is split into TPK_VK_MAX_PARTS bindings at most, each holding
 * 2^shift texels (the shift is a specialization constant), so texel i is texel i & (2^shift - 1) of
 * binding i >> shift. */
#ifndef TPK_VK_LAYOUT_H
#define TPK_VK_LAYOUT_H

/* Record geometry in 32-bit words (checked against format/tetpack_format.h in vk_arrays.c). */
#define TPK_VK_TET16_WORDS 4
#define TPK_VK_TET16_VX 0    /* then nx[0..2] at words 1..3 */
#define TPK_VK_TET20_WORDS 5
#define TPK_VK_TET20_VX 0    /* then n[0..3] at words 1..4 */
#define TPK_VK_TET32_WORDS 8
#define TPK_VK_TET32_V 0     /* v[0..2] at words 0..2 */
#define TPK_VK_TET32_VX 3
#define TPK_VK_TET32_N 4     /* n[0..3] at words 4..7 */
#define TPK_VK_SHELL_WORDS 4 /* a, b, c, t */
#define TPK_VK_NODE_WORDS 8  /* lo[3], hi[3], first, count as stored; uploaded as lo, first | hi, count */

/* Layout ids: the specialization constant that selects the marcher (same values as tpk_layout). */
#define TPK_VK_LAYOUT_TET32 32
#define TPK_VK_LAYOUT_TET20 20
#define TPK_VK_LAYOUT_TET16 16

/* The texel arrays, each with TPK_VK_MAX_PARTS consecutive bindings starting at its base. */
#define TPK_VK_MAX_PARTS 8
#define TPK_VK_ARRAY_VERTS 0
#define TPK_VK_ARRAY_TETS 1
#define TPK_VK_ARRAY_SHELL 2
#define TPK_VK_ARRAY_NODES 3
#define TPK_VK_ARRAY_TET_SCALARS 4
#define TPK_VK_ARRAY_VERTEX_SA 5 /* --occlusion vertex: S_v and A_v per vertex (render.h OCCLUSION AT VERTICES) */
#define TPK_VK_ARRAY_RANGE_NODES 6 /* range culling of iso-only rays (render.h ISO-ONLY RAYS) */
#define TPK_VK_ARRAY_RANGE_TETS 7
#define TPK_VK_ARRAY_COUNT 8

#define TPK_VK_BIND_PARAMS 0 /* uniform block */
#define TPK_VK_BIND_PIXELS 1 /* storage buffer: packed RGBA8 per pixel */
#define TPK_VK_BIND_COUNTERS 2 /* storage buffer: the dispatch's statistics, TPK_VK_COUNT_* below */
#define TPK_VK_BIND_STATE 3 /* storage buffer: each pixel's ray between slices (TPK_VK_SPEC_SLICED, below) */
#define TPK_VK_BIND_ARRAY(a) (4 + (a) * TPK_VK_MAX_PARTS)
#define TPK_VK_BIND_COUNT TPK_VK_BIND_ARRAY(TPK_VK_ARRAY_COUNT)

/* Specialization constants: the layout, then per array its part count and shift. */
#define TPK_VK_SPEC_LAYOUT 0
#define TPK_VK_SPEC_PARTS(a) (1 + 2 * (a))
#define TPK_VK_SPEC_SHIFT(a) (2 + 2 * (a))
#define TPK_VK_SPEC_EXACT (1 + 2 * TPK_VK_ARRAY_COUNT) /* the FP64 variant's edge test, below */
#define TPK_VK_SPEC_EFFECTS (2 + 2 * TPK_VK_ARRAY_COUNT) /* TPK_VK_EFFECT_* bits */
#define TPK_VK_SPEC_SLICED (3 + 2 * TPK_VK_ARRAY_COUNT) /* 1: rays run in slices of bounded work */
#define TPK_VK_SPEC_COUNT (4 + 2 * TPK_VK_ARRAY_COUNT)
#define TPK_VK_EFFECT_ISO 1
#define TPK_VK_EFFECT_SHADING 2
#define TPK_VK_EFFECT_SHADOWS 4
#define TPK_VK_EFFECT_AO 8
#define TPK_VK_EFFECT_VERTEX 16 /* shadows and AO from the per-vertex cache: no secondary rays in the shader */
#define TPK_VK_EFFECT_CULL 32 /* iso-only primary rays find their pieces in the range BVH, not by marching */
#define TPK_VK_EFFECT_SURFACE 64 /* shadows and AO cast once per ray, at its surface (render.h OCCLUSION AT THE SURFACE) */
/* Not a frame: the vertex cache's casts (render.h OCCLUSION AT VERTICES), invocation x < width / 2 of row y
 * for vertex y * (width / 2) + x, S_v and A_v as float bits into words 2i and 2i + 1 of the band (render.comp
 * vertex_cast) */
#define TPK_VK_EFFECT_CACHE 128
#define TPK_VK_EFFECT_MASKS 256 /* pipelines per renderer, one per combination */

/* The faces of a positive tet in outward order (tpk_tet_faces of format/tetpack_format.h, checked in
 * vk_arrays.c): face k, opposite corner k, is corners [3k, 3k + 3). */
#define TPK_VK_TET_FACES 1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1
#define TPK_VK_RANGE_LEAF 8 /* tets per leaf of the range BVH (TPK_RANGE_BVH_LEAF) */

/* The shader is built twice: with TPK_VK_FP64 1 (for devices with shaderFloat64) and 0. The exact
 * sign of an edge function of float coordinates is the sign of one double expression (the products
 * are exact in double); without doubles it takes Dekker's error-free products. In the FP64 variant,
 * TPK_VK_SPEC_EXACT picks: TPK_VK_EXACT_FILTER, a float filter with the double test only near zero
 * (GPUs, which branch), or TPK_VK_EXACT_ALWAYS, the double test every time (CPU devices such as
 * lavapipe, which run both sides of a branch under a mask, so that a rare slow path costs always). */
#define TPK_VK_EXACT_FILTER 1
#define TPK_VK_EXACT_ALWAYS 2

/* The statistics of one dispatch, reduced on the device: each workgroup sums its pixels in shared
 * memory, then adds its sums to these words with one atomic each. 64-bit sums are two words (low, high)
 * added with carry. The host resets them before each dispatch. */
#define TPK_VK_COUNT_STEPS 0     /* tet steps, 64-bit: words 0 (low) and 1 (high) */
#define TPK_VK_COUNT_SECONDARY 2 /* shadow and AO rays, 64-bit: words 2 and 3 */
#define TPK_VK_COUNT_FAILED 4    /* pixels whose ray failed (TPK_VK_STATUS_MESH) */
#define TPK_VK_COUNT_FIRST 5     /* the smallest failed pixel index in the dispatch (0xffffffff: none) */
#define TPK_VK_COUNT_PENDING 6   /* sliced: pixels whose ray goes on in the next slice */
#define TPK_VK_COUNT_WORDS 8

/* Slices (TPK_VK_SPEC_SLICED, for CPU devices). llvmpipe ends every loop of a shader once the loops
 * have run 65535 iterations in all (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS, counted per SIMD group,
 * silently): a long ray, or one with shadow and AO rays, was cut short there. Sliced, a ray stops at
 * a safe point once it has done TPK_VK_SLICE_WORK units of work (a tet step or a BVH node visited) in
 * a dispatch, keeps its state in TPK_VK_STATE_VEC4 vec4s of the state buffer, and the host dispatches
 * the band again (the slice number in cast_count.z) until no pixel is pending. */
#define TPK_VK_SLICE_WORK 512
#define TPK_VK_STATE_VEC4 28
#define TPK_VK_SLICED_BAND_PIXELS (1u << 16) /* a sliced band's pixels: 28 MiB of state */

/* Per-pixel status of the shader. */
#define TPK_VK_STATUS_OK 0
#define TPK_VK_STATUS_MESH 1 /* inconsistent connectivity (TPK_ERR_MESH on the CPU) */

#define TPK_VK_TF_MAX 256   /* == TPK_TF_MAX_POINTS */
#define TPK_VK_MAX_PROBES 4 /* == TPK_RENDER_MAX_PROBES */
#define TPK_VK_PROBE_SPHERE 1 /* == TPK_PROBE_SPHERE, _PLANE, _BOX */
#define TPK_VK_PROBE_PLANE 2
#define TPK_VK_PROBE_BOX 3
#define TPK_VK_GROUP 8      /* workgroup: 8 x 8 pixels */

#endif
