/* Private to the VTU importer (import_vtu*.c): the reader state shared by the XML handlers
 * (import_vtu_xml.c), the DataArray decoding (import_vtu_decode.c) and the mesh building
 * (import_vtu_mesh.c). Who owns what, top to bottom (a file calls only files below it, never back up):
 *   import_vtu.c         tpk_import_vtu, tpk_import_vtu_memory (calls xml, decode, mesh in turn)
 *   import_vtu_xml.c     vtu_parse_xml
 *   import_vtu_mesh.c    vtu_build_mesh
 *   import_vtu_decode.c  vtu_type_from_name, vtu_type_name, vtu_is_int_type,
 *                        vtu_decode_binary, vtu_decode_ascii, vtu_decode_appended
 *   import_vtu_inflate.c vtu_inflate_blocks
 *   import_vtu_source.c  vtu_is_space, vtu_src_read, vtu_src_left, vtu_src_fail
 *   import_vtu_fail.c    vtu_fail_line, vtu_fail_array
 * Not installed. */
#ifndef TPK_IMPORT_VTU_INTERNAL_H
#define TPK_IMPORT_VTU_INTERNAL_H

#include <expat.h>
#include <stddef.h>
#include <stdint.h>

#include "import/importers.h"
#include "tetpack_format.h"

/* zlib's deflate never packs more than this many bytes into one compressed byte (plus a small constant). */
#define ZLIB_MAX_RATIO 1032u

typedef enum vtu_type { T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64, T_NONE } vtu_type;

enum { SEC_NONE, SEC_POINTS, SEC_CELLS, SEC_POINT_DATA, SEC_CELL_DATA, SEC_OTHER };
enum { ROLE_POINTS, ROLE_CONN, ROLE_OFFSETS, ROLE_TYPES, ROLE_FACES, ROLE_FACEOFFSETS, ROLE_POINT_FIELD,
       ROLE_CELL_FIELD, ROLE_COUNT };

typedef struct vtu_array {
    int role;
    char name[TPK_NAME_MAX];
    vtu_type type;
    int components;
    int format;            /* 0 ascii, 1 binary, 2 appended */
    uint64_t offset;       /* appended */
    long line;
    double *values;        /* decoded */
    uint64_t count;
} vtu_array;

typedef struct vtu_reader {
    const char *name;
    const unsigned char *data;
    size_t size;
    tpk_diag *diag;
    XML_Parser parser;
    int failed;
    int depth;
    int root_seen;
    int grid_depth, piece_depth, section_depth;
    int section;
    int piece_seen;
    int big_endian;
    unsigned header_size;  /* 4 or 8 */
    int compressed;
    int64_t point_count, cell_count;
    /* The DataArray being read. */
    int in_array, array_depth, collect;
    int64_t array_fed_offset; /* where its start tag began in what expat was given */
    vtu_array cur;
    char *text;
    size_t text_len, text_cap;
    /* The long base64 run take_base64 took, left where it is in the input (no copy): it stands at
     * text[borrowed_at] in the array's text. NULL when none. */
    const char *borrowed;
    size_t borrowed_len, borrowed_at;
    /* Every DataArray kept, in file order. */
    vtu_array *arrays;
    int array_count, array_cap;
    /* Appended data. */
    int appended_seen;     /* the AppendedData start tag was parsed */
    int appended_base64;
    size_t app_start, app_end;
} vtu_reader;

/* Byte sources: raw bytes, or base64 text decoded as it is read. */
typedef struct bsrc {
    const unsigned char *p;
    size_t len, pos;
    int b64;
    unsigned char pend[3];
    int npend, ipend;
    int in_file;           /* p points into the file at `base` (appended data): places are file offsets */
    size_t base;           /* else: p is the array's text from character `base` on (a run taken alone) */
    const char *error;     /* why a read failed, with the place */
    char error_buf[160];
} bsrc;

/* The zlib header of compressed data: block count, block size, last block size, then each block's
 * compressed size. */
typedef struct zlib_blocks {
    uint64_t count, size, last, total; /* last: the last block's size (never 0); total: all bytes */
    uint64_t *csizes, cmax;            /* compressed sizes, and the largest */
} zlib_blocks;

/* ---- Messages (import_vtu_fail.c) ----------------------------------------------------------------
 * Both set the diag message once (the first failure wins), stop the XML parser when it runs, and
 * return -1. line <= 0: no line in the message. */
int vtu_fail_line(vtu_reader *r, long line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
int vtu_fail_array(vtu_reader *r, const vtu_array *a, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* ---- XML (import_vtu_xml.c) ----------------------------------------------------------------------
 * Parse the XML part of the file (all of it, or up to the AppendedData start tag), keeping every
 * DataArray of the Piece in r->arrays; ascii and binary arrays are decoded as they end. 0 or -1. */
int vtu_parse_xml(vtu_reader *r);

/* ---- DataArray contents (import_vtu_decode.c) ---------------------------------------------------- */
/* The type named by a DataArray's type attribute (Int8 .. Float64, Char, UChar), or T_NONE. */
vtu_type vtu_type_from_name(const char *name);
const char *vtu_type_name(vtu_type t);
int vtu_is_int_type(vtu_type t);
/* Decode a's values (header, then plain or zlib-compressed data) from s into a->values. 0 or -1. */
int vtu_decode_binary(vtu_reader *r, vtu_array *a, bsrc *s);
/* Decode a's whitespace-separated ascii values from text[0 .. len) into a->values. 0 or -1. */
int vtu_decode_ascii(vtu_reader *r, vtu_array *a, const char *text, size_t len);
/* Decode every format="appended" array from the appended data, by its offset. 0 or -1. */
int vtu_decode_appended(vtu_reader *r);

/* ---- Compressed blocks (import_vtu_inflate.c) ----------------------------------------------------
 * Read z's blocks from s (in order) and inflate them into out (z->total bytes), on all cores. On a
 * failure, the message names the first block that failed, as a block-by-block reader would. 0 or -1. */
int vtu_inflate_blocks(vtu_reader *r, const vtu_array *a, bsrc *s, const zlib_blocks *z, unsigned char *out);

/* ---- Byte sources (import_vtu_source.c) ----------------------------------------------------------- */
int vtu_is_space(unsigned char c);
/* n bytes from s into out; 0, or -1 with s->error saying what was found where. */
int vtu_src_read(bsrc *s, unsigned char *out, size_t n);
/* An upper bound on the bytes s can still give. */
uint64_t vtu_src_left(const bsrc *s);
/* Sets s->error to `what` at the current place; returns -1. */
int vtu_src_fail(bsrc *s, const char *what);

/* ---- The mesh (import_vtu_mesh.c) ----------------------------------------------------------------
 * Check the decoded arrays against each other and fill `out` (cells kept or dropped by
 * cell_types.h, polyhedra by their face streams, point and cell fields). 0 or -1. */
int vtu_build_mesh(vtu_reader *r, tpk_mesh *out);

#endif
