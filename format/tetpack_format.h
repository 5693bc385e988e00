/* tetpack on-disk definitions: magic, version, chunk tags, record structs.
 * Shared by the writer, the reader, the tools and (via tetpack_format.glsl) the shaders.
 * Everything on disk is little-endian. spec/tetpack-format.md is normative; this header mirrors it. */
#ifndef TETPACK_FORMAT_H
#define TETPACK_FORMAT_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* 0x89 catches 7-bit transfers, CR LF catches text-mode line-ending conversion, 0x1A stops `type` on
 * DOS, the final LF catches LF->CRLF conversion (same idea as PNG). */
#define TPK_MAGIC_0 0x89u
#define TPK_MAGIC "\x89TPK\r\n\x1a\n"
#define TPK_MAGIC_SIZE 8

#define TPK_VERSION_MAJOR 1
#define TPK_VERSION_MINOR 4
/* A file without a chunk of 1.2 (PART, LINK), 1.3 (LEVL) or 1.4 (CULL) is written as 1.1: its bytes stay
 * those of 1.1 writers; one with PART or LINK as 1.2, one with LEVL as 1.3, one with CULL as 1.4. */
#define TPK_VERSION_MINOR_PLAIN 1
#define TPK_VERSION_MINOR_PARTS 2
#define TPK_VERSION_MINOR_LEVELS 3
#define TPK_VERSION_MINOR_CULL 4

#define TPK_HEADER_SIZE 192u
#define TPK_DIR_ENTRY_SIZE 64u
#define TPK_CHUNK_ALIGN 64u        /* every chunk offset, and the directory offset */
#define TPK_LARGE_CHUNK_ALIGN 4096u /* uncompressed chunks of at least TPK_LARGE_CHUNK_BYTES */
#define TPK_LARGE_CHUNK_BYTES 65536u

/* FourCC tags, first character in the lowest byte. */
#define TPK_FOURCC(a, b, c, d) \
    ((uint32_t)(uint8_t)(a) | ((uint32_t)(uint8_t)(b) << 8) | ((uint32_t)(uint8_t)(c) << 16) | \
     ((uint32_t)(uint8_t)(d) << 24))

#define TPK_TAG_META TPK_FOURCC('M', 'E', 'T', 'A') /* UTF-8 JSON: provenance, summary (optional) */
#define TPK_TAG_POS3 TPK_FOURCC('P', 'O', 'S', '3') /* float32 x,y,z per vertex, relative to origin */
#define TPK_TAG_TT16 TPK_FOURCC('T', 'T', '1', '6') /* tpk_tet16 per tet */
#define TPK_TAG_TT20 TPK_FOURCC('T', 'T', '2', '0') /* tpk_tet20 per tet */
#define TPK_TAG_TT32 TPK_FOURCC('T', 'T', '3', '2') /* tpk_tet32 per tet */
#define TPK_TAG_SHEL TPK_FOURCC('S', 'H', 'E', 'L') /* tpk_shell_face per boundary face */
#define TPK_TAG_FDSC TPK_FOURCC('F', 'D', 'S', 'C') /* tpk_field_desc per field */
#define TPK_TAG_FDAT TPK_FOURCC('F', 'D', 'A', 'T') /* float32 values; entry.index = field, entry.step = step */
#define TPK_TAG_TIME TPK_FOURCC('T', 'I', 'M', 'E') /* float64 time value per step */
#define TPK_TAG_TMAP TPK_FOURCC('T', 'M', 'A', 'P') /* int32 source cell id per tet */
#define TPK_TAG_VMAP TPK_FOURCC('V', 'M', 'A', 'P') /* int32 source vertex id per vertex */
/* Format 1.2, part sets (spec §15): */
#define TPK_TAG_PART TPK_FOURCC('P', 'A', 'R', 'T') /* manifest: tpk_part_record per part, as BYTE */
#define TPK_TAG_LINK TPK_FOURCC('L', 'I', 'N', 'K') /* part: tpk_link per cut shell face, as 4 I32 */
/* Format 1.3, levels of detail (spec §16): */
#define TPK_TAG_LEVL TPK_FOURCC('L', 'E', 'V', 'L') /* a complete .tpk of level `index` (1..), as BYTE, codec none */
/* Format 1.4, culling blocks (spec §17): per block of tets in file order, seeds of a walk inside the block
 * and the vertex id intervals its tets use, as I32 (tpk_cull_* below). */
#define TPK_TAG_CULL TPK_FOURCC('C', 'U', 'L', 'L')
#define TPK_CULL_HEADER_WORDS 4 /* block_tets, block_count, seed_count, interval_count */
#define TPK_CULL_SEED_WORDS 6   /* tet, its vertices a, b, c, d in positive order, n3 */
#define TPK_CULL_MIN_BLOCK 16
#define TPK_CULL_MAX_BLOCK 65536

/* Directory entry flags. Bits other than these are reserved and must be zero. */
#define TPK_CHUNK_REQUIRED 0x0001u

typedef enum tpk_codec {
    TPK_CODEC_NONE = 0,
    TPK_CODEC_ZSTD = 1
} tpk_codec;

/* Element types: what one element of a chunk is. elem_size in the entry must match. */
typedef enum tpk_elem_type {
    TPK_ELEM_BYTE = 0,       /* 1: opaque bytes / UTF-8 text */
    TPK_ELEM_I32 = 1,        /* 4 */
    TPK_ELEM_F32 = 2,        /* 4 */
    TPK_ELEM_F64 = 3,        /* 8 */
    TPK_ELEM_VEC3_F32 = 4,   /* 12 */
    TPK_ELEM_TET16 = 5,      /* 16 */
    TPK_ELEM_TET20 = 6,      /* 20 */
    TPK_ELEM_TET32 = 7,      /* 32 */
    TPK_ELEM_SHELL_FACE = 8, /* 16 */
    TPK_ELEM_FIELD_DESC = 9, /* 128 */
    TPK_ELEM_TYPE_COUNT = 10
} tpk_elem_type;

typedef enum tpk_field_association {
    TPK_ASSOC_POINT = 0, /* one value per vertex */
    TPK_ASSOC_TET = 1    /* one value per tet */
} tpk_field_association;

/* The fixed file header at offset 0. */
typedef struct tpk_header {
    uint8_t magic[8];              /* TPK_MAGIC */
    uint16_t version_major;        /* TPK_VERSION_MAJOR */
    uint16_t version_minor;        /* TPK_VERSION_MINOR */
    uint32_t header_size;          /* TPK_HEADER_SIZE */
    uint32_t flags;                /* reserved, 0 */
    uint32_t dir_entry_size;       /* TPK_DIR_ENTRY_SIZE */
    uint64_t file_size;            /* total bytes */
    uint64_t directory_offset;     /* multiple of TPK_CHUNK_ALIGN */
    uint64_t chunk_count;          /* directory entries */
    uint64_t vertex_count;         /* <= 2^31-1 */
    uint64_t tet_count;            /* <= 2^31-1 */
    uint64_t shell_face_count;     /* <= 4 * tet_count */
    uint64_t directory_checksum;   /* XXH64(seed 0) of the chunk_count * 64 directory bytes */
    double origin[3];              /* positions are stored relative to this */
    double bounds_min[3];          /* bounding box of origin + (double)pos */
    double bounds_max[3];
    uint8_t reserved[32];          /* 0 */
    uint64_t header_checksum;      /* XXH64(seed 0) of bytes [0, 184) */
} tpk_header;

typedef struct tpk_dir_entry {
    uint32_t tag;          /* FourCC */
    uint16_t flags;        /* TPK_CHUNK_REQUIRED; other bits 0 */
    uint8_t codec;         /* tpk_codec */
    uint8_t elem_type;     /* tpk_elem_type */
    uint32_t elem_size;    /* bytes per element */
    uint32_t index;        /* FDAT: field index; else 0 */
    uint64_t elem_count;
    uint64_t offset;       /* from file start; multiple of TPK_CHUNK_ALIGN */
    uint64_t stored_size;  /* bytes in the file */
    uint64_t raw_size;     /* elem_count * elem_size, after decoding */
    uint64_t checksum;     /* XXH64(seed 0) of the raw (decoded) bytes */
    uint32_t step;         /* FDAT: time step; else 0 */
    uint32_t reserved;     /* 0 */
} tpk_dir_entry;

/* Tet records. Vertex order is positive: det[p1-p0, p2-p0, p3-p0] > 0. Ids are int32, -1 = none. */
typedef struct tpk_tet32 {
    int32_t v[3];  /* first three stored vertices; v3 = vx ^ v0 ^ v1 ^ v2 */
    int32_t vx;    /* v0 ^ v1 ^ v2 ^ v3 */
    int32_t n[4];  /* n[k]: tet across the face opposite stored vertex k, or -1 */
} tpk_tet32;

typedef struct tpk_tet20 {
    int32_t vx;
    int32_t n[4];  /* n[r]: neighbor opposite the vertex whose id has rank r (ascending) */
} tpk_tet20;

typedef struct tpk_tet16 {
    int32_t vx;
    int32_t nx[3]; /* nx[r] = n[r] ^ n[3], n as in tpk_tet20 */
} tpk_tet16;

/* A boundary face of tet t; (b-a) x (c-a) points out of the volume. */
typedef struct tpk_shell_face {
    int32_t a, b, c, t;
} tpk_shell_face;

/* The faces of a tet (v0, v1, v2, v3): face k is the one opposite v[k] (the face its neighbor k lies
 * across, §3), listed in outward order, the winding of a shell record (§6.6): for a positive tet
 * (det[p1-p0, p2-p0, p3-p0] > 0) the normal (pb-pa) x (pc-pa) of face (a, b, c) points away from p[k].
 * (p0,p1,p2) faces p3, so (p0,p2,p1) faces out; (p1,p2,p3,p0) is an odd permutation of (p0..p3), so
 * (p1,p2,p3) faces away from p0; (p0,p2,p3,p1) is even: (p0,p3,p2); (p0,p1,p3,p2) is odd: (p0,p1,p3).
 * This is the one place the order is written: the marchers' recovery, the converter's shell and face
 * matching, the checker and the tools' cell shapes (tools/mesh/cell_types.c) all read it from here. */
#define TPK_TET_FACE_LIST {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}
static const int tpk_tet_faces[4][3] = TPK_TET_FACE_LIST;

typedef struct tpk_field_desc {
    char name[64];        /* UTF-8, NUL-terminated, NUL-padded, non-empty, unique in the file */
    char units[32];       /* UTF-8, NUL-terminated, NUL-padded; may be empty */
    uint32_t association; /* tpk_field_association */
    uint32_t step_count;  /* >= 1; FDAT chunks with step 0..step_count-1 exist */
    uint32_t components;  /* 1 in format 1.0 */
    uint32_t reserved0;   /* 0 */
    float min_value;      /* over all steps, ignoring NaN */
    float max_value;
    uint64_t reserved1;   /* 0 */
} tpk_field_desc;

/* One part of a part set, in the manifest's PART chunk (stored as 256 BYTE elements per record). */
#define TPK_PART_FILE_MAX 128
typedef struct tpk_part_record {
    char file[TPK_PART_FILE_MAX]; /* the part's file name, in the manifest's folder; UTF-8, NUL-padded */
    uint64_t file_size;           /* the part file's size in bytes */
    uint64_t header_checksum;     /* the part's header_checksum (covers its directory, hence every chunk) */
    uint64_t vertex_count, tet_count, shell_face_count;
    uint64_t link_count;          /* shell faces of the part that lie on a cut (its LINK records) */
    double bounds_min[3], bounds_max[3]; /* the part's header bounds */
    uint8_t reserved[32];         /* 0 */
} tpk_part_record;

/* A shell face on a cut, and the same face seen from the part across it (a part's LINK chunk, stored as
 * 4 I32 elements per record, sorted by face). */
typedef struct tpk_link {
    int32_t face;       /* index into this part's SHEL */
    int32_t part;       /* index of the other part in the manifest's PART table */
    int32_t other_face; /* index into the other part's SHEL of the same face */
    int32_t other_tet;  /* that record's t: the tet across the cut */
} tpk_link;

#if defined(__cplusplus)
#define TPK_STATIC_ASSERT static_assert
#else
#define TPK_STATIC_ASSERT _Static_assert
#endif
TPK_STATIC_ASSERT(sizeof(tpk_header) == TPK_HEADER_SIZE, "tpk_header layout");
TPK_STATIC_ASSERT(sizeof(tpk_dir_entry) == TPK_DIR_ENTRY_SIZE, "tpk_dir_entry layout");
TPK_STATIC_ASSERT(sizeof(tpk_tet32) == 32, "tpk_tet32 layout");
TPK_STATIC_ASSERT(sizeof(tpk_tet20) == 20, "tpk_tet20 layout");
TPK_STATIC_ASSERT(sizeof(tpk_tet16) == 16, "tpk_tet16 layout");
TPK_STATIC_ASSERT(sizeof(tpk_shell_face) == 16, "tpk_shell_face layout");
TPK_STATIC_ASSERT(sizeof(tpk_field_desc) == 128, "tpk_field_desc layout");
TPK_STATIC_ASSERT(sizeof(tpk_part_record) == 256, "tpk_part_record layout");
TPK_STATIC_ASSERT(sizeof(tpk_link) == 16, "tpk_link layout");

#ifdef __cplusplus
}
#endif
#endif
