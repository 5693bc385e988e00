/* Private to the VTK legacy importer (import_vtk*.c): the reader state, the big-endian readers, and the
 * functions the pieces share. import_vtk_tokens.c: tokens and value blocks; import_vtk_cells.c: POINTS,
 * CELLS, CELL_TYPES; import_vtk_data.c: POINT_DATA/CELL_DATA; import_vtk.c: the section loop and the
 * final mesh. Not installed. Every function that can fail returns 0, or -1 with the message in r->s. */
#ifndef TPK_IMPORT_VTK_INTERNAL_H
#define TPK_IMPORT_VTK_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "import/importers.h"
#include "tetpack_format.h"
#include "base/text_scan.h"

typedef enum vtk_type {
    VT_BIT, VT_U8, VT_I8, VT_U16, VT_I16, VT_U32, VT_I32, VT_U64, VT_I64, VT_F32, VT_F64
} vtk_type;

typedef struct vtk_reader {
    tpk_scan s;
    int binary;
    size_t kw_pos;          /* the current section keyword, for messages about the whole block */
    int64_t kw_line;
    int64_t point_count;    /* -1 until POINTS */
    double *points;
    int64_t cell_count;     /* -1 until CELLS */
    int64_t *offsets;       /* cell_count + 1 */
    int32_t *conn;          /* ids checked to be in [0, INT32_MAX]; against point_count at the end */
    size_t cells_pos;
    int64_t cells_line;
    int offsets_form;       /* CELLS came as OFFSETS/CONNECTIVITY (VTK 5.1) */
    int64_t each_size;      /* >= 0: the binary passes found every cell with this many ids, none above
                               max_id; -1: not known (finish_mesh then checks cell by cell) */
    int64_t max_id;
    int64_t type_count;     /* -1 until CELL_TYPES */
    uint8_t *types;
    int type_lo, type_hi;   /* the smallest and largest cell type (-1: not known) */
    size_t types_pos;
    int64_t types_line;
    int assoc;              /* -1 before POINT_DATA/CELL_DATA */
    int64_t assoc_count;
    int64_t assoc_expected; /* points or cells the section should have: differs from assoc_count only in a
                               section of the wrong size read leniently (its arrays are dropped) */
    tpk_mesh fields;        /* collected fields; cell fields per source cell until filtered */
} vtk_reader;

/* ---- Big-endian values (BINARY files) ----------------------------------------------------------- */

static inline uint16_t be16(const unsigned char *p)
{
    return (uint16_t)((unsigned)p[0] << 8 | p[1]);
}
static inline uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}
static inline uint64_t be64(const unsigned char *p)
{
    return (uint64_t)be32(p) << 32 | be32(p + 4);
}

static inline double be_real(const unsigned char *p, vtk_type type, uint64_t i)
{
    switch (type) {
    case VT_BIT: return (p[i >> 3] >> (7 - (i & 7))) & 1;
    case VT_U8: return p[i];
    case VT_I8: return (int8_t)p[i];
    case VT_U16: return be16(p + 2 * i);
    case VT_I16: return (int16_t)be16(p + 2 * i);
    case VT_U32: return be32(p + 4 * i);
    case VT_I32: return (int32_t)be32(p + 4 * i);
    case VT_U64: return (double)be64(p + 8 * i);
    case VT_I64: return (double)(int64_t)be64(p + 8 * i);
    case VT_F32: {
        uint32_t u = be32(p + 4 * i);
        float f;
        memcpy(&f, &u, 4);
        return f;
    }
    case VT_F64: {
        uint64_t u = be64(p + 8 * i);
        double d;
        memcpy(&d, &u, 8);
        return d;
    }
    }
    return 0;
}

/* ---- Tokens and value blocks (import_vtk_tokens.c) ---------------------------------------------- */

/* A failure placed at the current section keyword (r->kw_pos, r->kw_line). */
int vtk_fail_kw(vtk_reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
const char *vtk_quote(const char *tok, size_t len, char *buf, size_t cap);
/* Next token on the keyword's line, or an error saying what was expected after which keyword. */
int vtk_arg_token(vtk_reader *r, const char *keyword, const char *what, const char **tok, size_t *len);
/* A count >= 0 on the keyword's line. */
int vtk_arg_count(vtk_reader *r, const char *keyword, const char *what, int64_t *out);
/* A data type name (float, double, int, vtktypeint64, ...) on the keyword's line. */
int vtk_arg_type(vtk_reader *r, const char *keyword, vtk_type *out);
/* Array and field names: %XX decoded, TPK_NAME_MAX bytes at most, "unnamed" when empty. */
void vtk_decode_name(const char *tok, size_t len, char *name);
int vtk_arg_name(vtk_reader *r, const char *keyword, char *name);
/* Peek: is the next token `word`? Leaves the position unchanged when it is not. */
int vtk_next_is(vtk_reader *r, const char *word);
/* Bytes that `count` binary values of `type` take (bit: packed). */
uint64_t vtk_bytes_for(vtk_type type, uint64_t count);
/* Before allocating for `count` values: do they fit in what is left of the file? */
int vtk_check_room(vtk_reader *r, vtk_type type, uint64_t count, const char *block);
/* The message for ASCII value i of count that is missing (len 0) or not a number. */
int vtk_ascii_value_error(vtk_reader *r, const char *tok, size_t len, const char *block, uint64_t i,
                          uint64_t count);
/* Threads for a pass over `count` binary values: those of tpk_thread_count(0), one per 64k values at most. */
int vtk_threads_for(uint64_t count);
/* `count` values of `type` into doubles (d64) or floats (f32); room already checked. Binary blocks are
 * converted on vtk_threads_for(count) threads, the same values for any count. */
int vtk_read_reals(vtk_reader *r, vtk_type type, uint64_t count, double *d64, float *f32, const char *block);
int vtk_is_integer_type(vtk_type t);
/* `count` integers into int64 (offsets, cell types); room already checked. */
int vtk_read_ints(vtk_reader *r, vtk_type type, uint64_t count, int64_t *dst, const char *block);

/* ---- Sections (import_vtk_cells.c, import_vtk_data.c) ------------------------------------------- */

/* Each reads its section from just after its keyword (r->kw_pos, r->kw_line at the keyword). */
int vtk_read_points(vtk_reader *r);
int vtk_read_cells(vtk_reader *r);
int vtk_read_cell_types(vtk_reader *r);
int vtk_read_data_header(vtk_reader *r, int assoc);
int vtk_read_scalars(vtk_reader *r);
int vtk_read_fixed_attribute(vtk_reader *r, const char *kw, int comps);
int vtk_read_texture_coordinates(vtk_reader *r);
int vtk_read_color_scalars(vtk_reader *r);
int vtk_skip_lookup_table(vtk_reader *r);
void vtk_skip_metadata(vtk_reader *r);
int vtk_read_field(vtk_reader *r);

#endif
