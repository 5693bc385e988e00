/* libtetpack: read, verify and write tetpack (.tpk) files, and march rays through their tets.
 * C11; depends on zstd and xxHash only. No global state. Every function that can fail returns a
 * tpk_result (0 = TPK_OK); details go to the handle's error text and the optional message callback.
 * Functions marked "untrusted input: safe" check every offset, size and count before use. */
#ifndef TETPACK_H
#define TETPACK_H

#include <stddef.h>
#include <stdint.h>

#include "tetpack_format.h"

#ifdef __cplusplus
extern "C" {
#endif
/* The library is built with -fvisibility=hidden: what this header declares is all that the shared
 * libtetpack exports (internal_*.h stays hidden). */
#if defined(__GNUC__)
#pragma GCC visibility push(default)
#endif

#define TPK_LIBRARY_VERSION "1.4.0"

typedef enum tpk_result {
    TPK_OK = 0,
    TPK_ERR_INVALID_ARGUMENT = 1, /* a NULL or out-of-range argument from the caller */
    TPK_ERR_IO = 2,               /* open/read/write/rename/mmap failed (errno in the message) */
    TPK_ERR_OUT_OF_MEMORY = 3,
    TPK_ERR_NOT_TETPACK = 4,      /* magic does not match: not a tetpack file, or text-mode damage */
    TPK_ERR_TRUNCATED = 5,        /* shorter than the header or than header.file_size */
    TPK_ERR_VERSION = 6,          /* a newer major version than this library reads */
    TPK_ERR_HEADER_CHECKSUM = 7,
    TPK_ERR_DIRECTORY_CHECKSUM = 8,
    TPK_ERR_CHUNK_CHECKSUM = 9,   /* a chunk's decoded bytes do not match its checksum */
    TPK_ERR_UNSUPPORTED_CHUNK = 10, /* an unknown chunk marked required, or an unknown codec */
    TPK_ERR_OUT_OF_BOUNDS = 11,   /* an offset or size points past the end of the file */
    TPK_ERR_OVERLAP = 12,         /* two chunks, or a chunk and the header/directory, overlap */
    TPK_ERR_MISALIGNED = 13,      /* an offset that is not a multiple of the required alignment */
    TPK_ERR_CORRUPT = 14,         /* any other broken rule: reserved bits set, counts disagree, ... */
    TPK_ERR_LIMIT = 15,           /* exceeds a caller-set limit for untrusted input */
    TPK_ERR_NOT_FOUND = 16,       /* no such chunk / field / layout */
    TPK_ERR_DECOMPRESS = 17,      /* zstd failed or produced the wrong size */
    TPK_ERR_BAD_STATE = 18,       /* the handle saw a corruption error earlier and refuses reads */
    TPK_ERR_MESH = 19,            /* the marcher met inconsistent connectivity (cycle, dead end) */
    TPK_RESULT_COUNT = 20
} tpk_result;

/* A static English name for a result code ("checksum mismatch in a chunk", ...). Never NULL. */
const char *tpk_result_string(tpk_result result);

typedef struct tpk_allocator {
    void *(*alloc)(void *user, size_t size); /* NULL: malloc */
    void (*free)(void *user, void *ptr);     /* NULL: free */
    void *user;
} tpk_allocator;

/* Limits for untrusted input (spec §9.1): a file within them that breaks no rule is read, one beyond
 * them gets TPK_ERR_LIMIT. 0 means the default given in brackets, the largest a valid file needs.
 * Whatever the limits, a chunk never costs more memory than its stored bytes can decode to: an
 * uncompressed chunk is its stored bytes, a zstd chunk's claim is checked against its stored size and
 * frame header before anything is allocated (TPK_ERR_CORRUPT / TPK_ERR_DECOMPRESS). */
typedef struct tpk_limits {
    uint64_t max_chunks;         /* [65536] */
    uint64_t max_chunk_bytes;    /* raw size of one chunk [64 GiB] */
    uint64_t max_total_bytes;    /* sum of raw sizes [256 GiB] */
} tpk_limits;

/* Checksums of chunk contents: by default each chunk is checked the first time it is read or viewed
 * (header and directory checksums are always checked at open). */
#define TPK_OPEN_VERIFY_ALL 0x1u  /* check every chunk's checksum during open */
#define TPK_OPEN_TRUSTED 0x2u     /* never check chunk checksums (header/directory still checked) */

typedef void (*tpk_message_fn)(void *user, tpk_result code, const char *text);

/* Zero-initialised means defaults. `size` is sizeof(tpk_open_options) or 0. */
typedef struct tpk_open_options {
    size_t size;
    uint32_t flags;
    tpk_allocator allocator;
    tpk_limits limits;
    tpk_message_fn message; /* called once per error with a detailed text; may be NULL */
    void *message_user;
} tpk_open_options;

typedef struct tpk_file tpk_file;

/* Open a file by path and map it read-only. On success *out owns the mapping; tpk_close frees it.
 * On failure *out is NULL and, if err_text/err_cap are given, a detailed message is copied there.
 * Untrusted input: safe. Thread safety: a tpk_file may be read from several threads at once. */
tpk_result tpk_open_path(tpk_file **out, const char *path, const tpk_open_options *options,
                         char *err_text, size_t err_cap);
/* Same, over bytes the caller owns and keeps alive and unchanged until tpk_close. */
tpk_result tpk_open_memory(tpk_file **out, const void *data, size_t size,
                           const tpk_open_options *options, char *err_text, size_t err_cap);
void tpk_close(tpk_file *file);

/* The detailed text of the last error on this handle ("" if none). Thread safety: safe while other
 * threads use the handle; the text is a copy taken under the handle's lock into storage owned by the
 * calling thread, valid until that thread's next tpk_error_text call (on any handle). */
const char *tpk_error_text(const tpk_file *file);

typedef struct tpk_file_info {
    uint16_t version_major, version_minor;
    uint64_t file_size;
    uint64_t vertex_count, tet_count, shell_face_count;
    uint64_t chunk_count;
    double origin[3];
    double bounds_min[3], bounds_max[3];
} tpk_file_info;
tpk_result tpk_get_info(const tpk_file *file, tpk_file_info *out);

/* Chunk directory: a copy of entry `i` (0 <= i < chunk_count), already validated. */
tpk_result tpk_get_chunk(const tpk_file *file, uint64_t i, tpk_dir_entry *out);
/* Index of the first chunk with this tag, index and step; TPK_ERR_NOT_FOUND if none. */
tpk_result tpk_find_chunk(const tpk_file *file, uint32_t tag, uint32_t index, uint32_t step,
                          uint64_t *out_i);
/* Zero-copy view of an uncompressed chunk (codec none); checks its checksum on first use unless
 * opened TRUSTED. *out_data is valid until tpk_close and is aligned as the spec promises.
 * A zstd chunk gives TPK_ERR_UNSUPPORTED_CHUNK: use tpk_read_chunk. */
tpk_result tpk_view_chunk(tpk_file *file, uint64_t i, const void **out_data, uint64_t *out_size);
/* Decode chunk `i` into dst (dst_size >= entry.raw_size), decompressing if needed, and check it. */
tpk_result tpk_read_chunk(tpk_file *file, uint64_t i, void *dst, uint64_t dst_size);
/* What this handle has done with chunk i so far, as TPK_CHUNK_USE_* bits. Chunks are read lazily:
 * opening reads only the header, the directory and FDSC; tpk_load_arrays then reads POS3, one layout,
 * SHEL and one FDAT step, and nothing else. For tools and tests that check a reader touches only what
 * it needs. Thread safety: safe while other threads read the handle. */
#define TPK_CHUNK_USE_READ 0x1u     /* its bytes were read: viewed, decoded, or checksummed */
#define TPK_CHUNK_USE_VERIFIED 0x2u /* its checksum was checked */
tpk_result tpk_get_chunk_use(const tpk_file *file, uint64_t i, uint32_t *out_bits);
/* Check every chunk's checksum and the cross-chunk rules of the spec that need no geometry
 * (counts agree with the header, field descriptors valid, ids in range). */
tpk_result tpk_verify(tpk_file *file);

/* Fields, from the FDSC chunk (0 fields if absent). */
uint32_t tpk_field_count(const tpk_file *file);
tpk_result tpk_get_field(const tpk_file *file, uint32_t i, tpk_field_desc *out);
tpk_result tpk_find_field(const tpk_file *file, const char *name, uint32_t *out_i);
/* Time value of a step (TIME chunk); TPK_ERR_NOT_FOUND when the file stores none. */
tpk_result tpk_get_time(tpk_file *file, uint32_t step, double *out_time);

/* ---- Arrays ready for a renderer ------------------------------------------------------------------ */

typedef enum tpk_layout {
    TPK_LAYOUT_TET32 = 32,
    TPK_LAYOUT_TET20 = 20,
    TPK_LAYOUT_TET16 = 16
} tpk_layout;

/* Plain arrays of one mesh, the input of the marcher. Either views into a mapped file or caller data.
 * Exactly one of tet16/tet20/tet32 is used, chosen by `layout`. scalars may be NULL (no field). */
typedef struct tpk_mesh_arrays {
    uint64_t vertex_count, tet_count, shell_face_count;
    double origin[3];
    const float *positions;          /* 3 * vertex_count, relative to origin */
    tpk_layout layout;
    const tpk_tet16 *tet16;
    const tpk_tet20 *tet20;
    const tpk_tet32 *tet32;
    const tpk_shell_face *shell;
    const float *scalars;            /* per vertex; NULL for none */
} tpk_mesh_arrays;

/* Fill `out` from a file: zero-copy views where chunks are uncompressed, otherwise decoded into memory
 * owned by the file handle (freed by tpk_close). field_name NULL: first point field, or none if the
 * file has none. Untrusted input: safe (all chunks verified, ids checked in range). */
tpk_result tpk_load_arrays(tpk_file *file, tpk_layout layout, const char *field_name, uint32_t step,
                           tpk_mesh_arrays *out);

/* The values of tet field `field_name` (association 1, spec §7.2) at `step`: tet_count floats, element
 * i the constant value in tet i; zero-copy or decoded into handle-owned memory like tpk_load_arrays.
 * TPK_ERR_NOT_FOUND (with a message) for a missing field, a point field or a step past its count.
 * Untrusted input: safe (checksum and element count checked). */
tpk_result tpk_load_tet_field(tpk_file *file, const char *field_name, uint32_t step, const float **out);

/* Recover positively oriented vertex quadruples (4 per tet) from any layout: direct for Tet32, by a
 * walk from the shell through neighbors for Tet20/Tet16. dst holds 4 * tet_count int32. Tet20/Tet16
 * give each tet as the even permutation of its vertices with the smallest id first, then the smallest
 * of the other three (spec §6.6). One thread. */
tpk_result tpk_recover_tets(const tpk_mesh_arrays *mesh, int32_t *dst);

/* tpk_recover_tets on `threads` threads for Tet20/Tet16 (threads <= 0: all cores); the same bytes and
 * the same result code whatever the thread count (on an error the one-thread walk is rerun). Since 1.3.0. */
tpk_result tpk_recover_tets_threads(const tpk_mesh_arrays *mesh, int32_t *dst, int threads);

/* ---- Culling blocks (format 1.4, spec §17) -------------------------------------------------------- */

/* A file's CULL chunk: its tets in file order cut into blocks of block_tets; per block, seeds from which a
 * walk inside the block reaches all its tets, and intervals of vertex ids that hold every vertex of its
 * tets (so the scalars over the intervals bound the block's). Views into the file handle. Since 1.4.0. */
typedef struct tpk_cull {
    uint32_t block_tets;
    uint64_t block_count, seed_count, interval_count;
    const int32_t *seed_start;     /* block_count + 1: block k's seeds are [seed_start[k], seed_start[k + 1]) */
    const int32_t *interval_start; /* block_count + 1, likewise for its intervals */
    const int32_t *seeds;          /* TPK_CULL_SEED_WORDS per seed: tet, its vertices in positive order, n3 */
    const int32_t *intervals;      /* 2 per interval: first id, end id (exclusive) */
} tpk_cull;

/* The file's CULL chunk into out, its structure checked (spec rule 17: CORRUPT with a message);
 * TPK_ERR_NOT_FOUND when the file has none. */
tpk_result tpk_load_cull(tpk_file *file, tpk_cull *out);

/* The tets of block `block` of `cull` by a walk from its seeds inside the block: 4 per tet into
 * dst[4 * (t - block * block_tets) ...], each in the canonical rotation tpk_recover_tets gives, so the
 * same ids as tpk_recover_tets returns for them. Every decoded id and visit is checked as the walk from
 * the shell checks them, and every vertex against the block's intervals: TPK_ERR_CORRUPT or TPK_ERR_MESH
 * (a tet not reached, a vertex outside the intervals). Any layout (Tet32: read directly, then checked
 * against the intervals). Safe to call for different blocks from several threads. */
tpk_result tpk_recover_block(const tpk_mesh_arrays *mesh, const tpk_cull *cull, uint64_t block, int32_t *dst);

/* ---- Writer ------------------------------------------------------------------------------------- */

typedef struct tpk_writer tpk_writer;

typedef struct tpk_write_options {
    size_t size;
    tpk_allocator allocator;
    tpk_message_fn message; /* called once per error with a detailed text (the only way to see why
                               tpk_writer_finish failed, since it frees the writer); may be NULL */
    void *message_user;
    int threads; /* 2 or more: a large uncompressed append is hashed on a second thread while the calling
                    thread writes it (the same bytes; the append returns when both are done); else one.
                    A zstd chunk over 8 MiB is compressed on up to this many of zstd's worker threads
                    (at least one, beside the calling thread): the bytes are the same for any value */
} tpk_write_options;

/* Start a file at `path`: data goes to a temporary file in the same directory, which tpk_writer_finish
 * renames over `path`. Nothing appears at `path` until finish succeeds; a process killed before that
 * leaves the temporary file (the library installs no signal handlers): callers that must leave nothing
 * write into an unnamed file with tpk_writer_open_fd instead. */
tpk_result tpk_writer_open(tpk_writer **out, const char *path, const tpk_write_options *options,
                           char *err_text, size_t err_cap);
/* Write into `fd`, a file the caller created (empty, writable and seekable, at offset 0), for callers
 * that make and place the file themselves (an unnamed O_TMPFILE linked in at the end, a file that must
 * not be left behind by a killed process). `name` appears in messages. The fd stays the caller's:
 * tpk_writer_finish flushes it to disk (fsync) and tpk_writer_abort leaves its bytes; neither closes it. */
tpk_result tpk_writer_open_fd(tpk_writer **out, int fd, const char *name, const tpk_write_options *options,
                              char *err_text, size_t err_cap);

typedef struct tpk_chunk_desc {
    uint32_t tag;
    uint16_t flags;      /* TPK_CHUNK_REQUIRED */
    uint8_t codec;       /* tpk_codec */
    uint8_t elem_type;   /* tpk_elem_type */
    uint32_t elem_size;
    uint32_t index;
    uint32_t step;
    uint64_t elem_count;
    int zstd_level;      /* for TPK_CODEC_ZSTD; 0 means zstd's default */
} tpk_chunk_desc;

/* Append one chunk (data: elem_count * elem_size bytes). Aligns it as the spec says. */
tpk_result tpk_writer_add_chunk(tpk_writer *writer, const tpk_chunk_desc *desc, const void *data);

/* The same chunk in pieces, so a large array never has to exist whole in memory: begin with the full
 * description (elem_count announces the total), append the bytes in any number of calls, end. The
 * appended total must be elem_count * elem_size. One streamed chunk at a time; the result is the same
 * file tpk_writer_add_chunk would write. */
tpk_result tpk_writer_begin_chunk(tpk_writer *writer, const tpk_chunk_desc *desc);
tpk_result tpk_writer_append(tpk_writer *writer, const void *data, uint64_t size);
tpk_result tpk_writer_end_chunk(tpk_writer *writer);

typedef struct tpk_header_fields {
    uint64_t vertex_count, tet_count, shell_face_count;
    double origin[3];
    double bounds_min[3], bounds_max[3];
} tpk_header_fields;

/* Write directory and header, flush, and rename into place (with tpk_writer_open_fd: flush only).
 * Frees the writer in every case. */
tpk_result tpk_writer_finish(tpk_writer *writer, const tpk_header_fields *header);
/* Drop everything written so far (removes the temporary file) and free the writer. */
void tpk_writer_abort(tpk_writer *writer);
/* Detailed text of the writer's last error. */
const char *tpk_writer_error_text(const tpk_writer *writer);

/* ---- Reference CPU marcher (double precision) ----------------------------------------------------- */

typedef struct tpk_marcher tpk_marcher;

/* Build the marcher (a BVH over shell faces, made on its first use: rays that never enter from the
 * shell, as range-culled iso rays, pay for none; since 1.4.0). `mesh` arrays must outlive the marcher.
 * Thread safety: tpk_march_ray may be called from many threads on one marcher. */
tpk_result tpk_marcher_create(tpk_marcher **out, const tpk_mesh_arrays *mesh);
void tpk_marcher_destroy(tpk_marcher *marcher);
/* Another point field for the marcher to read from now on (vertex_count floats, outliving the marcher
 * like the other arrays; NULL: none), as tpk_marcher_create would give for the same arrays with these
 * scalars, without building the shell BVH again: for time steps of one mesh. Not while rays are marched
 * on it; trees made on the marcher (tpk_range_bvh) hold the old field's ranges: tpk_range_bvh_set_scalars.
 * TPK_ERR_INVALID_ARGUMENT for a NULL marcher. */
tpk_result tpk_marcher_set_scalars(tpk_marcher *marcher, const float *scalars);

/* A node of the marcher's shell BVH. Leaves (count > 0) hold faces [first, first + count) of the
 * reordered face array; inner nodes (count == 0) have children first and first + 1. Boxes are padded
 * (by 1e-6 of `extent`) so that a face the watertight test reports as crossed is not culled. */
typedef struct tpk_shell_bvh_node {
    float lo[3], hi[3];
    int32_t first;
    int32_t count;
} tpk_shell_bvh_node;

/* The marcher's shell BVH (built here when no ray has built it yet), for renderers that upload it
 * instead of building their own (the Vulkan renderer): nodes (root first), the shell records in leaf
 * order (copies of the file's records), and the largest extent or coordinate magnitude of the positions.
 * Owned by the marcher, valid while it lives. A traversal stack of TPK_SHELL_BVH_STACK entries always
 * suffices. All zero when the BVH could not be built (out of memory). */
typedef struct tpk_shell_bvh {
    const tpk_shell_bvh_node *nodes;
    int64_t node_count;
    const tpk_shell_face *faces;
    int64_t face_count;
    double extent;
} tpk_shell_bvh;

#define TPK_SHELL_BVH_STACK 96

void tpk_marcher_shell_bvh(const tpk_marcher *marcher, tpk_shell_bvh *out);

typedef struct tpk_segment {
    int32_t tet;
    double t_in, t_out;       /* ray parameters, clipped to [tmin, tmax] */
    double scalar_in, scalar_out; /* interpolated at t_in/t_out (0 when the mesh has no scalars) */
    int32_t v[4];             /* the tet's vertices: v[0..2] the face the ray entered through (before
                                 any clipping to tmin), from its smallest id on, v[3] the fourth; for
                                 gradients and face normals */
} tpk_segment;

/* Return nonzero to stop the ray early (e.g. opacity reached). */
typedef int (*tpk_segment_fn)(void *user, const tpk_segment *segment);

typedef struct tpk_march_stats {
    uint64_t tet_steps;      /* tets visited, including those before tmin */
    uint64_t shell_entries;  /* segments of the ray inside the volume */
} tpk_march_stats;

/* March the ray org + t*dir (world coordinates; dir need not be unit) through the mesh, calling `fn`
 * for every tet piece within [tmin, tmax], in increasing t. The ray may start inside the volume and
 * leave and re-enter a non-convex shell. Watertight: decisions depend only on vertex ids and
 * positions, so every ray that enters leaves and no tet repeats within one segment run.
 * stats may be NULL. Returns TPK_ERR_MESH if the connectivity is inconsistent. */
tpk_result tpk_march_ray(const tpk_marcher *marcher, const double org[3], const double dir[3],
                         double tmin, double tmax, tpk_segment_fn fn, void *user,
                         tpk_march_stats *stats);

/* ---- Range culling for iso rays ------------------------------------------------------------------- */

/* A BVH over the tets of a marcher's mesh whose nodes carry the range of its scalars (mesh.scalars,
 * which must be set), for rays that look for isosurfaces only: subtrees whose range holds none of the
 * values are skipped. Built from the tets in file order (runs of 8 consecutive tets, then pairs of
 * neighbours), about 24 bytes per tet. The marcher (and its arrays) must outlive it. Thread safety: as
 * the marcher's. TPK_ERR_INVALID_ARGUMENT without scalars; the errors of tpk_recover_tets. */
typedef struct tpk_range_bvh tpk_range_bvh;
tpk_result tpk_range_bvh_create(tpk_range_bvh **out, const tpk_marcher *marcher);
/* tpk_range_bvh_create with the walk of a Tet20 or Tet16 file on `threads` (tpk_recover_tets_threads;
 * <= 1: the caller's alone), then as tpk_range_bvh_set_threads(bvh, threads). The same bvh for any count.
 * Since 1.3.0. */
tpk_result tpk_range_bvh_create_threads(tpk_range_bvh **out, const tpk_marcher *marcher, int threads);
/* A bvh over a file's culling blocks (tpk_load_cull, spec §17) instead of all its tets: each block's
 * scalar range is read over its vertex intervals, and tpk_range_bvh_select walks only the blocks whose
 * range holds a value (tpk_recover_block: its errors). The selected tree is the one
 * tpk_range_bvh_create_threads would select, so rays give the same pieces. It has no file-order tree:
 * tpk_march_ray_values answers only the selected values (TPK_ERR_INVALID_ARGUMENT otherwise),
 * tpk_range_bvh_heap gives 0 and tpk_range_bvh_tets NULL; tpk_range_bvh_active gives the share of blocks.
 * `cull` must stay valid while the bvh lives. Since 1.4.0. */
tpk_result tpk_range_bvh_create_cull(tpk_range_bvh **out, const tpk_marcher *marcher, const tpk_cull *cull,
                                     int threads);
void tpk_range_bvh_destroy(tpk_range_bvh *bvh);
/* The share (0..1) of its leaves (runs of 8 tets) whose range holds one of values[0 .. count): where it is
 * large, the isosurface is near every ray's entry and marching finds it sooner than culling does. */
double tpk_range_bvh_active(const tpk_range_bvh *bvh, const double *values, int count);
/* Build a second tree over just the tets whose range holds one of values[0 .. count) (clustered
 * bottom-up over them in file order, in time linear in their count, leaves of up to 6 tets; about 100
 * bytes per such tet; the same bytes whatever tpk_range_bvh_set_threads gave), which tpk_march_ray_values then walks
 * whenever it is given the same values (the same count and the same doubles, in the same order), with
 * the same pieces; other values walk the file-order tree. count 0 drops it. Call it before the rays,
 * not while any ray of this bvh runs. TPK_ERR_INVALID_ARGUMENT, TPK_ERR_OUT_OF_MEMORY (then no tree is
 * selected), or TPK_OK. */
tpk_result tpk_range_bvh_select(tpk_range_bvh *bvh, const double *values, int count);
/* The marcher's field changed (tpk_marcher_set_scalars, a time step): the ranges are read again from
 * it, what depends on the positions alone (the tets' vertices, the boxes) is kept, and the selected
 * tree is dropped (tpk_range_bvh_select makes it for the new field). The bvh is then the one
 * tpk_range_bvh_create would make, for a fraction of its time on a Tet20 or Tet16 file (no walk).
 * TPK_ERR_INVALID_ARGUMENT for a NULL bvh or a marcher without scalars. Not while rays run on it. */
tpk_result tpk_range_bvh_set_scalars(tpk_range_bvh *bvh);
/* Threads the builds of this bvh may use (tpk_range_bvh_select; <= 1: the caller's alone). The trees
 * are the same for any count. TPK_ERR_INVALID_ARGUMENT for a NULL bvh. */
tpk_result tpk_range_bvh_set_threads(tpk_range_bvh *bvh, int threads);
/* Tets per leaf: leaf j holds tets [TPK_RANGE_BVH_LEAF * j, TPK_RANGE_BVH_LEAF * (j + 1)). */
#define TPK_RANGE_BVH_LEAF 8
/* The same tree for a renderer that walks it elsewhere (a GPU), as a complete binary tree in heap order:
 * node 1 is the root, node n's children are 2n and 2n + 1, leaf j is node L + j, where L, the power of
 * two returned, is at least the leaf count. Each node is 8 floats: lo[3], the scalar min, hi[3], the
 * scalar max, as the BVH holds them (boxes and ranges rounded outward; the ray's box test adds 1e-6 of
 * the mesh's extent, tpk_marcher_shell_bvh's extent, around them); node 0 and the nodes the tree does not
 * have (past the last leaf) are empty: lo and min +inf, hi and max -inf. nodes: 16 * L floats, or NULL
 * to ask for L. Returns 0 for NULL bvh. */
int64_t tpk_range_bvh_heap(const tpk_range_bvh *bvh, float *nodes);
/* The vertices of every tet, 4 per tet in positive order (tpk_recover_tets), as the BVH's candidate tests
 * read them; owned by bvh. */
const int32_t *tpk_range_bvh_tets(const tpk_range_bvh *bvh);

/* The pieces of tpk_march_ray(marcher, org, dir, tmin, tmax) that cross one of values[0 .. count) by
 * the renderers' rule (scalar_in < v <= scalar_out, or scalar_in > v >= scalar_out), in increasing t
 * (pieces of one t_in, where the ray meets a vertex or an edge, by t_out, then by tet), and no others: the same segments, bit for bit (both compute a tet's faces from their smallest ids on),
 * except in a tet where rounding put the exit before the entry, which the marcher resolves along its
 * path. stats->tet_steps counts the tets tested. fn may stop the ray as in tpk_march_ray. */
tpk_result tpk_march_ray_values(const tpk_range_bvh *bvh, const double org[3], const double dir[3], double tmin,
                                double tmax, const double *values, int count, tpk_segment_fn fn, void *user,
                                tpk_march_stats *stats);

/* The most rays tpk_march_packet_values takes at once. */
#define TPK_MARCH_PACKET 16
/* tpk_march_ray_values for ray_count (<= TPK_MARCH_PACKET) rays from one origin, such as a camera's
 * primary rays through a few neighbouring pixels: ray i runs along dirs[i] over [tmin[i], tmax[i]] and
 * gets exactly the calls fns[i](users[i], ...) that tpk_march_ray_values would make for it alone, in the
 * same order; the calls of different rays interleave. Rays close together walk the selected tree as one
 * (its nodes tested once for all of them); rays whose directions differ too much in kind (dominant axis,
 * signs) walk in halves of the packet, down to one by one; other values walk one by one. stats: ray_count
 * of them, or NULL; tet_steps counts the tets tested exactly, which here are fewer than alone. Returns
 * TPK_ERR_INVALID_ARGUMENT for a NULL array or a count out of range, else the first ray's error, as
 * tpk_march_ray_values gives them. */
tpk_result tpk_march_packet_values(const tpk_range_bvh *bvh, const double org[3], int ray_count,
                                   const double (*dirs)[3], const double *tmin, const double *tmax,
                                   const double *values, int count, const tpk_segment_fn *fns, void *const *users,
                                   tpk_march_stats *stats);

/* ---- Levels of detail (format 1.3, spec §16) ----------------------------------------------------- */

/* How many levels of detail the file holds (its LEVL chunks; levels 1..n, each coarser than the last,
 * level 0 being the file itself). */
uint32_t tpk_level_count(const tpk_file *file);
/* Open level `level` (1..tpk_level_count) as a file of its own: every function of this header reads it
 * as it reads any file. It is a view of the parent's bytes: close it before the parent. On failure *out
 * is NULL and err_text says why (no such level; a LEVL chunk that is not a valid file). */
tpk_result tpk_open_level(tpk_file *file, uint32_t level, const tpk_open_options *options, tpk_file **out,
                          char *err_text, size_t err_cap);

/* ---- Part sets (format 1.2, spec §15) ------------------------------------------------------------ */

/* A part set: a manifest (a .tpk with a PART chunk, conventionally .tpkset) listing part files, each
 * a complete .tpk, whose LINK chunks tie the shell faces on a cut to the same face in another part. */
typedef struct tpk_partset tpk_partset;

/* Open the manifest at `path` and the parts it lists: all of them when box_min and box_max are NULL,
 * else those whose bounds meet the box [box_min, box_max] (closed; the others stay unopened). Each part
 * is opened with `options` and must match its record (file size, header checksum, counts, bounds) and
 * the manifest's origin, else the whole open fails (TPK_ERR_CORRUPT, naming the part). A manifest that
 * is a valid .tpk without a PART chunk gives TPK_ERR_NOT_FOUND. Part file names are plain names in the
 * manifest's folder (no separators, spec §15.2). Untrusted input: safe. On failure *out is NULL. */
tpk_result tpk_partset_open(tpk_partset **out, const char *path, const tpk_open_options *options,
                            const double *box_min, const double *box_max, char *err_text, size_t err_cap);
void tpk_partset_close(tpk_partset *set);
/* Parts listed in the manifest (opened or not). */
uint32_t tpk_partset_part_count(const tpk_partset *set);
/* The manifest's record of part i (a copy). */
tpk_result tpk_partset_get_part(const tpk_partset *set, uint32_t i, tpk_part_record *out);
/* The open handle of part i (owned by the set, closed by tpk_partset_close), or NULL when the box left
 * it out. */
tpk_file *tpk_partset_file(const tpk_partset *set, uint32_t i);
/* The origin every part shares (the manifest's). */
void tpk_partset_origin(const tpk_partset *set, double out[3]);
/* Part i's links, decoded and checked against the set (other part in range; when that part is open,
 * other_face in its SHEL and other_tet its record's t). *out is owned by the set; count 0 without a
 * LINK chunk. Not for a part that is not open (TPK_ERR_INVALID_ARGUMENT). */
tpk_result tpk_partset_links(tpk_partset *set, uint32_t i, const tpk_link **out, uint64_t *out_count);

/* ---- A part set as one mesh ------------------------------------------------------------------------ */

/* The open parts of a set as the arrays of one mesh, for renderers that take one file's (spec §15):
 * a vertex on a cut stored once, the vertices numbered in an order that keeps every part's own (so the
 * vertices of each tet and face compare as in the file the set was cut from), the tets part after part
 * (tet t of part i is tpk_set_mesh_tet_base(i) + t), a linked face made the neighbor across it, and the
 * shell the outer faces alone. The tets are written in `layout` whatever layouts the parts hold. Every
 * array is a copy: the set must stay open only for tpk_set_mesh_arrays and tpk_set_mesh_tet_field.
 * Untrusted input: safe; TPK_ERR_MESH (with a message in err_text) when a link does not join the same
 * face both ways or the parts order their shared vertices differently, TPK_ERR_LIMIT past 2^31 - 1
 * vertices, tets or shell faces. */
typedef struct tpk_set_mesh tpk_set_mesh;
tpk_result tpk_set_mesh_create(tpk_set_mesh **out, tpk_partset *set, tpk_layout layout, char *err_text,
                               size_t err_cap);
void tpk_set_mesh_destroy(tpk_set_mesh *mesh);
/* The arrays, with point field `field_name` at `step` gathered from every part (NULL: each part's first
 * point field, as tpk_load_arrays; scalars NULL when a part has none). The arrays live as long as the
 * set mesh (each call's field too). */
tpk_result tpk_set_mesh_arrays(tpk_set_mesh *mesh, const char *field_name, uint32_t step, tpk_mesh_arrays *out,
                               char *err_text, size_t err_cap);
/* Tet field `field_name` at `step`, part after part as the tets (tet_count floats, living as long as the
 * set mesh). */
tpk_result tpk_set_mesh_tet_field(tpk_set_mesh *mesh, const char *field_name, uint32_t step, const float **out,
                                  char *err_text, size_t err_cap);
/* The first tet of part i in the arrays (the total tet count for i = the part count). */
uint64_t tpk_set_mesh_tet_base(const tpk_set_mesh *mesh, uint32_t i);

/* ---- Marching a part set ---------------------------------------------------------------------------- */

typedef struct tpk_set_marcher tpk_set_marcher;

/* A marcher over several parts that share one origin: parts[i] are part i's arrays (tet_count 0 for a
 * part not loaded) and links[i], link_counts[i] its links. A BVH per part over the shell faces on no
 * cut (or linked to a part not loaded) finds where rays enter; a ray that leaves a part through a
 * linked face continues in the other part at the linked face, without a search. All arrays must outlive
 * the marcher. TPK_ERR_INVALID_ARGUMENT when the origins differ; TPK_ERR_MESH when a link names a face
 * or tet outside the other part. */
tpk_result tpk_set_marcher_create(tpk_set_marcher **out, uint32_t part_count, const tpk_mesh_arrays *parts,
                                  const tpk_link *const *links, const uint64_t *link_counts);
void tpk_set_marcher_destroy(tpk_set_marcher *marcher);

/* As tpk_march_ray, over the whole set: segments in increasing t; segment.tet is a tet of the part
 * given in *segment_part while fn runs (may be NULL). Same pieces as one file of the same tets, when
 * the parts keep the vertex order of that file on every cut (spec §15.4). */
tpk_result tpk_set_march_ray(const tpk_set_marcher *marcher, const double org[3], const double dir[3],
                             double tmin, double tmax, tpk_segment_fn fn, void *user, uint32_t *segment_part,
                             tpk_march_stats *stats);

#if defined(__GNUC__)
#pragma GCC visibility pop
#endif
#ifdef __cplusplus
}
#endif
#endif
