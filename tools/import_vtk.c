/* VTK legacy UNSTRUCTURED_GRID importer (ASCII and big-endian BINARY, old CELLS lists and the 5.1
 * OFFSETS/CONNECTIVITY form). Parses from one in-memory buffer with explicit bounds: every count is
 * checked against the bytes left in the file before anything is allocated. */
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "importers.h"
#include "tetpack_format.h"
#include "cell_types.h"
#include "polyhedron.h"
#include "text_scan.h"

typedef enum vtk_type {
    VT_BIT, VT_U8, VT_I8, VT_U16, VT_I16, VT_U32, VT_I32, VT_U64, VT_I64, VT_F32, VT_F64
} vtk_type;

static const struct {
    const char *name;
    vtk_type type;
} type_names[] = {
    {"bit", VT_BIT},           {"unsigned_char", VT_U8},    {"char", VT_I8},
    {"signed_char", VT_I8},    {"unsigned_short", VT_U16},  {"short", VT_I16},
    {"unsigned_int", VT_U32},  {"int", VT_I32},             {"unsigned_long", VT_U64},
    {"long", VT_I64},          {"float", VT_F32},           {"double", VT_F64},
    {"vtktypeint8", VT_I8},    {"vtktypeuint8", VT_U8},     {"vtktypeint16", VT_I16},
    {"vtktypeuint16", VT_U16}, {"vtktypeint32", VT_I32},    {"vtktypeuint32", VT_U32},
    {"vtktypeint64", VT_I64},  {"vtktypeuint64", VT_U64},   {"vtkidtype", VT_I32},
    {"vtktypefloat32", VT_F32}, {"vtktypefloat64", VT_F64},
};

static const unsigned type_size[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8}; /* bit: packed, see bytes_for */

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
    int64_t type_count;     /* -1 until CELL_TYPES */
    uint8_t *types;
    size_t types_pos;
    int64_t types_line;
    int assoc;              /* -1 before POINT_DATA/CELL_DATA */
    int64_t assoc_count;
    int64_t assoc_expected; /* points or cells the section should have: differs from assoc_count only in a
                               section of the wrong size read leniently (its arrays are dropped) */
    tpk_mesh fields;        /* collected fields; cell fields per source cell until filtered */
} vtk_reader;

/* ---- Small helpers ------------------------------------------------------------------------------ */

static int fail_kw(vtk_reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int fail_kw(vtk_reader *r, const char *fmt, ...)
{
    char text[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    return tpk_scan_fail_at(&r->s, r->kw_pos, r->kw_line, "%s", text);
}

static const char *quote(const char *tok, size_t len, char *buf, size_t cap)
{
    return tpk_scan_quote(tok, len, buf, cap);
}

/* Next token on the keyword's line, or an error saying what was expected after which keyword. */
static int arg_token(vtk_reader *r, const char *keyword, const char *what, const char **tok, size_t *len)
{
    *len = tpk_scan_line_token(&r->s, tok);
    if (!*len)
        return tpk_scan_fail(&r->s, "%s: expected %s, found end of %s", keyword, what,
                             r->s.pos >= r->s.size ? "file" : "line");
    return 0;
}

static int arg_count(vtk_reader *r, const char *keyword, const char *what, int64_t *out)
{
    const char *tok;
    size_t len;
    if (arg_token(r, keyword, what, &tok, &len))
        return -1;
    char q[64];
    if (tpk_parse_int64(tok, len, out) != 0)
        return tpk_scan_fail(&r->s, "%s: expected %s, found '%s'", keyword, what, quote(tok, len, q, sizeof q));
    if (*out < 0)
        return tpk_scan_fail(&r->s, "%s: expected %s (>= 0), found %lld", keyword, what, (long long)*out);
    return 0;
}

static int arg_type(vtk_reader *r, const char *keyword, vtk_type *out)
{
    const char *tok;
    size_t len;
    if (arg_token(r, keyword, "a data type (float, double, int, ...)", &tok, &len))
        return -1;
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++) {
        if (tpk_token_is(tok, len, type_names[i].name)) {
            *out = type_names[i].type;
            return 0;
        }
    }
    char q[64];
    return tpk_scan_fail(&r->s, "%s: expected a data type (float, double, int, unsigned_char, vtktypeint64, ...), "
                         "found '%s'", keyword, quote(tok, len, q, sizeof q));
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* Array and field names: VTK 5.1 writes spaces and other special characters as %XX. */
static void decode_name(const char *tok, size_t len, char *name)
{
    size_t o = 0;
    for (size_t i = 0; i < len && o + 1 < TPK_NAME_MAX; i++) {
        int hi = i + 2 < len ? hex_digit(tok[i + 1]) : -1, lo = i + 2 < len ? hex_digit(tok[i + 2]) : -1;
        if (tok[i] == '%' && hi >= 0 && lo >= 0) {
            name[o++] = (char)(hi * 16 + lo);
            i += 2;
        } else {
            name[o++] = tok[i];
        }
    }
    name[o] = 0;
    if (!name[0])
        strcpy(name, "unnamed");
}

static int arg_name(vtk_reader *r, const char *keyword, char *name)
{
    const char *tok;
    size_t len;
    if (arg_token(r, keyword, "a name", &tok, &len))
        return -1;
    decode_name(tok, len, name);
    return 0;
}

/* Peek: is the next token `word`? Leaves the position unchanged when it is not. */
static int next_is(vtk_reader *r, const char *word)
{
    size_t pos = r->s.pos;
    int64_t line = r->s.line;
    const char *tok;
    size_t len = tpk_scan_token(&r->s, &tok);
    if (len && tpk_token_is(tok, len, word))
        return 1;
    r->s.pos = pos;
    r->s.line = line;
    return 0;
}

static uint64_t bytes_for(vtk_type type, uint64_t count)
{
    return type == VT_BIT ? (count + 7) / 8 : count * type_size[type];
}

/* Before allocating for `count` values: do they fit in what is left of the file? Binary: exactly;
 * ASCII: every value takes at least one character and a separator. */
static int check_room(vtk_reader *r, vtk_type type, uint64_t count, const char *block)
{
    size_t left = r->s.size - r->s.pos;
    if (r->binary) {
        unsigned size = type == VT_BIT ? 1 : type_size[type];
        uint64_t units = type == VT_BIT ? (count + 7) / 8 : count;
        if (units > left / size) {
            if (units <= UINT64_MAX / size)
                return tpk_scan_fail_at(&r->s, r->s.pos, r->s.line,
                                        "%s block truncated: expected %llu bytes, found %zu", block,
                                        (unsigned long long)(units * size), left);
            return tpk_scan_fail_at(&r->s, r->s.pos, r->s.line,
                                    "%s block truncated: expected %llu values, found %zu bytes", block,
                                    (unsigned long long)count, left);
        }
        return 0;
    }
    if (count > left / 2 + 1)
        return fail_kw(r, "%s: %llu values cannot fit in the %zu bytes left in the file "
                       "(wrong count or truncated file)", block, (unsigned long long)count, left);
    return 0;
}

static int ascii_value_error(vtk_reader *r, const char *tok, size_t len, const char *block, uint64_t i,
                             uint64_t count)
{
    char q[64];
    if (!len)
        return tpk_scan_fail(&r->s, "%s block truncated: expected %llu values, found %llu before end of file",
                             block, (unsigned long long)count, (unsigned long long)i);
    return tpk_scan_fail(&r->s, "%s: expected a number (value %llu of %llu), found '%s'", block,
                         (unsigned long long)i + 1, (unsigned long long)count, quote(tok, len, q, sizeof q));
}

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

/* `count` values of `type` into doubles (d64) or floats (f32); room already checked. */
static int read_reals(vtk_reader *r, vtk_type type, uint64_t count, double *d64, float *f32, const char *block)
{
    if (r->binary) {
        const unsigned char *p = r->s.data + r->s.pos;
        if (type == VT_F64 && d64) {
            for (uint64_t i = 0; i < count; i++)
                d64[i] = be_real(p, VT_F64, i);
        } else if (type == VT_F32 && f32) {
            for (uint64_t i = 0; i < count; i++)
                f32[i] = (float)be_real(p, VT_F32, i);
        } else {
            for (uint64_t i = 0; i < count; i++) {
                double v = be_real(p, type, i);
                if (d64)
                    d64[i] = v;
                else
                    f32[i] = (float)v;
            }
        }
        r->s.pos += bytes_for(type, count);
        return 0;
    }
    for (uint64_t i = 0; i < count; i++) {
        const char *tok;
        size_t len = tpk_scan_token(&r->s, &tok);
        double v;
        if (!len || tpk_parse_double(tok, len, &v) != 0)
            return ascii_value_error(r, tok, len, block, i, count);
        if (d64)
            d64[i] = v;
        else
            f32[i] = (float)v;
    }
    return 0;
}

static int is_integer_type(vtk_type t)
{
    return t != VT_F32 && t != VT_F64;
}

/* `count` integers into int64 (offsets, cell types); room already checked. */
static int read_ints(vtk_reader *r, vtk_type type, uint64_t count, int64_t *dst, const char *block)
{
    if (!is_integer_type(type))
        return tpk_scan_fail(&r->s, "%s: expected an integer data type, found a floating-point one", block);
    if (r->binary) {
        const unsigned char *p = r->s.data + r->s.pos;
        for (uint64_t i = 0; i < count; i++) {
            switch (type) {
            case VT_I32: dst[i] = (int32_t)be32(p + 4 * i); break;
            case VT_I64: dst[i] = (int64_t)be64(p + 8 * i); break;
            case VT_U64: {
                uint64_t u = be64(p + 8 * i);
                dst[i] = u > INT64_MAX ? -1 : (int64_t)u;
                break;
            }
            default: dst[i] = (int64_t)be_real(p, type, i); break;
            }
        }
        r->s.pos += bytes_for(type, count);
        return 0;
    }
    for (uint64_t i = 0; i < count; i++) {
        const char *tok;
        size_t len = tpk_scan_token(&r->s, &tok);
        if (!len || tpk_parse_int64(tok, len, &dst[i]) != 0) {
            char q[64];
            if (!len)
                return ascii_value_error(r, tok, len, block, i, count);
            return tpk_scan_fail(&r->s, "%s: expected an integer (value %llu of %llu), found '%s'", block,
                                 (unsigned long long)i + 1, (unsigned long long)count, quote(tok, len, q, sizeof q));
        }
    }
    return 0;
}

/* Cell index holding connectivity entry k (offsets known and monotone up to there). */
static int64_t cell_of_entry(const int64_t *offsets, int64_t cells, int64_t k)
{
    int64_t lo = 0, hi = cells;
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (offsets[mid] <= k)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* ---- Sections ----------------------------------------------------------------------------------- */

static int read_points(vtk_reader *r)
{
    int64_t n;
    vtk_type type;
    if (r->point_count >= 0)
        return fail_kw(r, "expected one POINTS section, found a second");
    if (arg_count(r, "POINTS", "a point count", &n) || arg_type(r, "POINTS", &type) ||
        tpk_scan_end_line(&r->s, "POINTS n type"))
        return -1;
    if ((uint64_t)n > UINT64_MAX / 3)
        return fail_kw(r, "POINTS %lld: too many points for any file", (long long)n);
    if (check_room(r, type, 3 * (uint64_t)n, "POINTS"))
        return -1;
    if (n > INT32_MAX)
        return fail_kw(r, "POINTS %lld: more than 2^31-1 points (the format's limit; split the mesh)", (long long)n);
    r->points = malloc(sizeof(double) * 3 * (size_t)(n ? n : 1));
    if (!r->points)
        return fail_kw(r, "POINTS %lld: out of memory", (long long)n);
    r->point_count = n;
    return read_reals(r, type, 3 * (uint64_t)n, r->points, NULL, "POINTS");
}

static int id_range_error(vtk_reader *r, int64_t cell, int64_t id)
{
    return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                            "CELLS: cell %lld uses point id %lld, expected 0 <= id < 2^31-1", (long long)cell,
                            (long long)id);
}

/* Old form: per cell a count then that many ids; `size` numbers in all. */
static int read_cell_lists(vtk_reader *r, int64_t n, int64_t size)
{
    if (size < n)
        return fail_kw(r, "CELLS %lld %lld: the size must count every cell's point count too (at least %lld)",
                       (long long)n, (long long)size, (long long)n);
    if (check_room(r, VT_I32, (uint64_t)size, "CELLS"))
        return -1;
    r->offsets = malloc(sizeof(int64_t) * (size_t)(n + 1));
    r->conn = malloc(sizeof(int32_t) * (size_t)(size - n > 0 ? size - n : 1));
    if (!r->offsets || !r->conn)
        return fail_kw(r, "CELLS %lld %lld: out of memory", (long long)n, (long long)size);
    r->cell_count = n;
    int64_t used = 0, k = 0;
    r->offsets[0] = 0;
    if (r->binary) {
        const unsigned char *p = r->s.data + r->s.pos;
        for (int64_t c = 0; c < n; c++) {
            if (used >= size)
                return fail_kw(r, "CELLS %lld %lld: the size is used up after %lld of %lld cells", (long long)n,
                               (long long)size, (long long)c, (long long)n);
            int64_t count = (int32_t)be32(p + 4 * used);
            if (count < 0 || count > size - used - 1 - (n - c - 1))
                return tpk_scan_fail_at(&r->s, r->s.pos + 4 * (size_t)used, 0,
                                        "CELLS: cell %lld has point count %lld, but the CELLS size %lld "
                                        "leaves room for at most %lld", (long long)c, (long long)count,
                                        (long long)size, (long long)(size - used - 1 - (n - c - 1)));
            used++;
            for (int64_t j = 0; j < count; j++, used++) {
                int32_t id = (int32_t)be32(p + 4 * used);
                if (id < 0)
                    return id_range_error(r, c, id);
                r->conn[k++] = id;
            }
            r->offsets[c + 1] = k;
        }
        r->s.pos += 4 * (size_t)size;
    } else {
        for (int64_t c = 0; c < n; c++) {
            int64_t count;
            if (used >= size)
                return fail_kw(r, "CELLS %lld %lld: the size is used up after %lld of %lld cells", (long long)n,
                               (long long)size, (long long)c, (long long)n);
            if (tpk_scan_int64(&r->s, &count, "a cell's point count"))
                return -1;
            if (count < 0 || count > size - used - 1 - (n - c - 1))
                return tpk_scan_fail(&r->s, "CELLS: cell %lld has point count %lld, but the CELLS size %lld "
                                     "leaves room for at most %lld", (long long)c, (long long)count,
                                     (long long)size, (long long)(size - used - 1 - (n - c - 1)));
            used++;
            for (int64_t j = 0; j < count; j++, used++) {
                int64_t id;
                if (tpk_scan_int64(&r->s, &id, "a point id"))
                    return -1;
                if (id < 0 || id > INT32_MAX)
                    return tpk_scan_fail(&r->s, "CELLS: cell %lld uses point id %lld, expected 0 <= id < 2^31-1",
                                         (long long)c, (long long)id);
                r->conn[k++] = (int32_t)id;
            }
            r->offsets[c + 1] = k;
        }
    }
    if (used != size)
        return fail_kw(r, "CELLS %lld %lld: the %lld cells hold %lld numbers, expected %lld", (long long)n,
                       (long long)size, (long long)n, (long long)used, (long long)size);
    return 0;
}

/* VTK 5.1 form: CELLS n+1 m, then OFFSETS type (n+1 values) and CONNECTIVITY type (m values). */
static int read_offsets_connectivity(vtk_reader *r, int64_t n_offsets, int64_t m)
{
    vtk_type type;
    if (n_offsets < 1)
        return fail_kw(r, "CELLS %lld %lld: expected at least one offset", (long long)n_offsets, (long long)m);
    if (arg_type(r, "OFFSETS", &type) || tpk_scan_end_line(&r->s, "OFFSETS type") ||
        check_room(r, type, (uint64_t)n_offsets, "OFFSETS"))
        return -1;
    int64_t n = n_offsets - 1;
    if (n > INT32_MAX)
        return fail_kw(r, "CELLS: %lld cells, more than 2^31-1", (long long)n);
    r->offsets = malloc(sizeof(int64_t) * (size_t)n_offsets);
    if (!r->offsets)
        return fail_kw(r, "OFFSETS: out of memory");
    r->cell_count = n;
    size_t offsets_pos = r->s.pos;
    int64_t offsets_line = r->s.line;
    if (read_ints(r, type, (uint64_t)n_offsets, r->offsets, "OFFSETS"))
        return -1;
    if (r->offsets[0] != 0)
        return tpk_scan_fail_at(&r->s, offsets_pos, offsets_line, "OFFSETS: expected the first offset 0, found %lld",
                                (long long)r->offsets[0]);
    for (int64_t c = 0; c < n; c++)
        if (r->offsets[c + 1] < r->offsets[c] || r->offsets[c + 1] > m)
            return tpk_scan_fail_at(&r->s, offsets_pos, offsets_line,
                                    "OFFSETS: cell %lld ends at %lld, expected a value between %lld and %lld",
                                    (long long)c, (long long)r->offsets[c + 1], (long long)r->offsets[c], (long long)m);
    if (r->offsets[n] != m)
        return tpk_scan_fail_at(&r->s, offsets_pos, offsets_line,
                                "OFFSETS: expected the last offset to equal the CELLS size %lld, found %lld",
                                (long long)m, (long long)r->offsets[n]);
    const char *tok;
    size_t len = tpk_scan_token(&r->s, &tok);
    r->kw_pos = r->s.tok_pos;
    r->kw_line = r->s.tok_line;
    if (!tpk_token_is(tok, len, "CONNECTIVITY")) {
        char q[64];
        return tpk_scan_fail(&r->s, "expected 'CONNECTIVITY type' after the OFFSETS block, found '%s'",
                             len ? quote(tok, len, q, sizeof q) : "end of file");
    }
    if (arg_type(r, "CONNECTIVITY", &type) || tpk_scan_end_line(&r->s, "CONNECTIVITY type"))
        return -1;
    if (!is_integer_type(type))
        return fail_kw(r, "CONNECTIVITY: expected an integer data type, found a floating-point one");
    if (check_room(r, type, (uint64_t)m, "CONNECTIVITY"))
        return -1;
    r->conn = malloc(sizeof(int32_t) * (size_t)(m ? m : 1));
    if (!r->conn)
        return fail_kw(r, "CONNECTIVITY: out of memory");
    if (r->binary) {
        const unsigned char *p = r->s.data + r->s.pos;
        for (int64_t k = 0; k < m; k++) {
            int64_t id = type == VT_I64 ? (int64_t)be64(p + 8 * k)
                         : type == VT_I32 ? (int32_t)be32(p + 4 * k)
                                          : (int64_t)be_real(p, type, (uint64_t)k);
            if (id < 0 || id > INT32_MAX)
                return id_range_error(r, cell_of_entry(r->offsets, n, k), id);
            r->conn[k] = (int32_t)id;
        }
        r->s.pos += bytes_for(type, (uint64_t)m);
        return 0;
    }
    for (int64_t k = 0; k < m; k++) {
        int64_t id;
        const char *t;
        size_t tl = tpk_scan_token(&r->s, &t);
        if (!tl || tpk_parse_int64(t, tl, &id) != 0) {
            char q[64];
            if (!tl)
                return ascii_value_error(r, t, tl, "CONNECTIVITY", (uint64_t)k, (uint64_t)m);
            return tpk_scan_fail(&r->s, "CONNECTIVITY: expected a point id (value %lld of %lld), found '%s'",
                                 (long long)k + 1, (long long)m, quote(t, tl, q, sizeof q));
        }
        if (id < 0 || id > INT32_MAX)
            return tpk_scan_fail(&r->s, "CONNECTIVITY: cell %lld uses point id %lld, expected 0 <= id < 2^31-1",
                                 (long long)cell_of_entry(r->offsets, n, k), (long long)id);
        r->conn[k] = (int32_t)id;
    }
    return 0;
}

static int read_cells(vtk_reader *r)
{
    int64_t n, size;
    if (r->cell_count >= 0)
        return fail_kw(r, "expected one CELLS section, found a second");
    r->cells_pos = r->kw_pos;
    r->cells_line = r->kw_line;
    if (arg_count(r, "CELLS", "a cell count", &n) || arg_count(r, "CELLS", "the CELLS size", &size) ||
        tpk_scan_end_line(&r->s, "CELLS n size"))
        return -1;
    if (next_is(r, "OFFSETS")) {
        r->kw_pos = r->s.tok_pos;
        r->kw_line = r->s.tok_line;
        r->offsets_form = 1;
        return read_offsets_connectivity(r, n, size);
    }
    if (n > INT32_MAX)
        return fail_kw(r, "CELLS %lld: more than 2^31-1 cells", (long long)n);
    return read_cell_lists(r, n, size);
}

static int read_cell_types(vtk_reader *r)
{
    int64_t n;
    if (r->type_count >= 0)
        return fail_kw(r, "expected one CELL_TYPES section, found a second");
    r->types_pos = r->kw_pos;
    r->types_line = r->kw_line;
    if (arg_count(r, "CELL_TYPES", "a cell count", &n) || tpk_scan_end_line(&r->s, "CELL_TYPES n"))
        return -1;
    if (r->cell_count < 0)
        return fail_kw(r, "expected CELLS before CELL_TYPES");
    if (n != r->cell_count)
        return fail_kw(r, "CELL_TYPES %lld: expected one type per cell (CELLS has %lld cells)", (long long)n,
                       (long long)r->cell_count);
    if (check_room(r, VT_I32, (uint64_t)n, "CELL_TYPES"))
        return -1;
    int64_t *values = malloc(sizeof(int64_t) * (size_t)(n ? n : 1));
    r->types = malloc((size_t)(n ? n : 1));
    if (!values || !r->types) {
        free(values);
        return fail_kw(r, "CELL_TYPES: out of memory");
    }
    r->type_count = n;
    int rc = read_ints(r, VT_I32, (uint64_t)n, values, "CELL_TYPES");
    for (int64_t c = 0; rc == 0 && c < n; c++) {
        if (values[c] < 0 || values[c] > 255)
            rc = fail_kw(r, "CELL_TYPES: cell %lld has unsupported cell type %lld", (long long)c, (long long)values[c]);
        else
            r->types[c] = (uint8_t)values[c];
    }
    free(values);
    return rc;
}

static int read_data_header(vtk_reader *r, int assoc)
{
    const char *kw = assoc == TPK_ASSOC_POINT ? "POINT_DATA" : "CELL_DATA";
    int64_t n;
    if (arg_count(r, kw, "a count", &n) || tpk_scan_end_line(&r->s, kw))
        return -1;
    int64_t expected = assoc == TPK_ASSOC_POINT ? r->point_count : r->cell_count;
    if (expected < 0)
        return fail_kw(r, "expected %s before %s", assoc == TPK_ASSOC_POINT ? "POINTS" : "CELLS", kw);
    if (n != expected && !(r->s.diag && r->s.diag->lenient_fields))
        return fail_kw(r, "%s %lld: expected %lld (one per %s)", kw, (long long)n, (long long)expected,
                       assoc == TPK_ASSOC_POINT ? "point" : "cell");
    r->assoc = assoc;
    r->assoc_count = n;
    r->assoc_expected = expected;
    return 0;
}

/* A data array of `tuples` tuples where the mesh needs r->assoc_expected: recorded (lenient, the array is
 * dropped: returns 0 and clears *keep) or an error. */
static int wrong_length(vtk_reader *r, const char *name, int64_t comps, int64_t tuples, int *keep)
{
    char place[96];
    snprintf(place, sizeof place, "line %lld", (long long)r->kw_line);
    if (tpk_diag_field_problem(r->s.diag, name, (long long)(r->assoc_expected * comps),
                               (long long)(tuples * comps), place) == 0) {
        *keep = 0;
        return 0;
    }
    return fail_kw(r, "array '%s' has %lld tuples, expected %lld (one per %s)", name, (long long)tuples,
                   (long long)r->assoc_expected, r->assoc == TPK_ASSOC_POINT ? "point" : "cell");
}

/* Read `tuples * comps` values and keep them as a field (keep = 0: parse and drop). */
static int read_field_values(vtk_reader *r, const char *name, vtk_type type, int64_t comps, int64_t tuples,
                             int keep, const char *block)
{
    if (comps < 1 || comps > 65536)
        return fail_kw(r, "%s '%s': expected 1 to 65536 components, found %lld", block, name, (long long)comps);
    if (tuples > INT64_MAX / comps)
        return fail_kw(r, "%s '%s': %lld tuples of %lld components is too many", block, name, (long long)tuples,
                       (long long)comps);
    if (keep && tuples != r->assoc_expected && wrong_length(r, name, comps, tuples, &keep))
        return -1;
    uint64_t count = (uint64_t)(tuples * comps);
    if (check_room(r, type, count, block))
        return -1;
    if (!keep && r->binary) {
        r->s.pos += bytes_for(type, count);
        return 0;
    }
    float *values = malloc(sizeof(float) * (size_t)(count ? count : 1));
    if (!values)
        return fail_kw(r, "%s '%s': out of memory", block, name);
    if (read_reals(r, type, count, NULL, values, block) != 0) {
        free(values);
        return -1;
    }
    if (!keep) {
        free(values);
        return 0;
    }
    int assoc = r->assoc == TPK_ASSOC_POINT ? TPK_ASSOC_POINT : TPK_ASSOC_TET;
    if (tpk_mesh_add_field(&r->fields, name, assoc, (int)comps, 1, values) != 0) {
        free(values);
        return fail_kw(r, "%s '%s': out of memory", block, name);
    }
    return 0;
}

static int need_data_section(vtk_reader *r, const char *kw)
{
    if (r->assoc < 0)
        return fail_kw(r, "expected POINT_DATA or CELL_DATA before %s", kw);
    return 0;
}

/* SCALARS name type [components], then an optional LOOKUP_TABLE name line. */
static int read_scalars(vtk_reader *r)
{
    char name[TPK_NAME_MAX];
    vtk_type type;
    int64_t comps = 1;
    if (need_data_section(r, "SCALARS") || arg_name(r, "SCALARS", name) || arg_type(r, "SCALARS", &type))
        return -1;
    const char *tok;
    size_t len = tpk_scan_line_token(&r->s, &tok);
    if (len && (tpk_parse_int64(tok, len, &comps) != 0 || comps < 1)) {
        char q[64];
        return tpk_scan_fail(&r->s, "SCALARS %s: expected a component count, found '%s'", name,
                             quote(tok, len, q, sizeof q));
    }
    if (tpk_scan_end_line(&r->s, "SCALARS name type components"))
        return -1;
    if (next_is(r, "LOOKUP_TABLE")) {
        if (arg_token(r, "LOOKUP_TABLE", "a table name", &tok, &len) || tpk_scan_end_line(&r->s, "LOOKUP_TABLE name"))
            return -1;
    }
    return read_field_values(r, name, type, comps, r->assoc_count, 1, "SCALARS");
}

/* VECTORS, NORMALS, TENSORS, TENSORS6, GLOBAL_IDS, PEDIGREE_IDS: name type, fixed components. */
static int read_fixed_attribute(vtk_reader *r, const char *kw, int comps)
{
    char name[TPK_NAME_MAX];
    vtk_type type;
    if (need_data_section(r, kw) || arg_name(r, kw, name) || arg_type(r, kw, &type) ||
        tpk_scan_end_line(&r->s, kw))
        return -1;
    return read_field_values(r, name, type, comps, r->assoc_count, 1, kw);
}

static int read_texture_coordinates(vtk_reader *r)
{
    char name[TPK_NAME_MAX];
    int64_t dim;
    vtk_type type;
    const char *kw = "TEXTURE_COORDINATES";
    if (need_data_section(r, kw) || arg_name(r, kw, name) || arg_count(r, kw, "a dimension (1 to 3)", &dim) ||
        arg_type(r, kw, &type) || tpk_scan_end_line(&r->s, kw))
        return -1;
    if (dim < 1 || dim > 3)
        return fail_kw(r, "%s %s: expected a dimension 1 to 3, found %lld", kw, name, (long long)dim);
    return read_field_values(r, name, type, dim, r->assoc_count, 1, kw);
}

/* COLOR_SCALARS name n: floats in ASCII, unsigned chars (scaled to [0,1]) in BINARY. */
static int read_color_scalars(vtk_reader *r)
{
    char name[TPK_NAME_MAX];
    int64_t comps;
    const char *kw = "COLOR_SCALARS";
    if (need_data_section(r, kw) || arg_name(r, kw, name) || arg_count(r, kw, "a component count", &comps) ||
        tpk_scan_end_line(&r->s, kw))
        return -1;
    if (read_field_values(r, name, r->binary ? VT_U8 : VT_F32, comps, r->assoc_count, 1, kw))
        return -1;
    if (r->binary) {
        tpk_src_field *f = &r->fields.fields[r->fields.field_count - 1];
        for (int64_t i = 0; i < comps * r->assoc_count; i++)
            f->values[i] /= 255.0f;
    }
    return 0;
}

/* A lookup table definition: LOOKUP_TABLE name size, then size RGBA entries. Skipped. */
static int skip_lookup_table(vtk_reader *r)
{
    const char *tok;
    size_t len;
    int64_t n;
    if (arg_token(r, "LOOKUP_TABLE", "a table name", &tok, &len) ||
        arg_count(r, "LOOKUP_TABLE", "a table size", &n) || tpk_scan_end_line(&r->s, "LOOKUP_TABLE name size"))
        return -1;
    return read_field_values(r, "lookup_table", r->binary ? VT_U8 : VT_F32, 4, n, 0, "LOOKUP_TABLE");
}

/* METADATA: lines of text up to an empty line. */
static void skip_metadata(vtk_reader *r)
{
    tpk_scan_skip_line(&r->s);
    while (r->s.pos < r->s.size) {
        size_t p = r->s.pos;
        while (p < r->s.size && (r->s.data[p] == ' ' || r->s.data[p] == '\t' || r->s.data[p] == '\r'))
            p++;
        int blank = p >= r->s.size || r->s.data[p] == '\n';
        tpk_scan_skip_line(&r->s);
        if (blank)
            break;
    }
}

/* FIELD name k, then k arrays "name components tuples type" + values. Inside POINT_DATA/CELL_DATA the
 * arrays become fields and must have one tuple per point/cell; at dataset level they are skipped. */
static int read_field(vtk_reader *r)
{
    const char *tok;
    size_t len;
    int64_t arrays;
    if (arg_token(r, "FIELD", "a name", &tok, &len) || arg_count(r, "FIELD", "an array count", &arrays) ||
        tpk_scan_end_line(&r->s, "FIELD name count"))
        return -1;
    for (int64_t a = 0; a < arrays; a++) {
        len = tpk_scan_token(&r->s, &tok);
        while (len && tpk_token_is(tok, len, "METADATA")) {
            skip_metadata(r);
            len = tpk_scan_token(&r->s, &tok);
        }
        r->kw_pos = r->s.tok_pos;
        r->kw_line = r->s.tok_line;
        if (!len)
            return tpk_scan_fail(&r->s, "FIELD: expected array %lld of %lld ('name components tuples type'), "
                                 "found end of file", (long long)a + 1, (long long)arrays);
        if (tpk_token_is(tok, len, "NULL_ARRAY")) {
            if (tpk_scan_end_line(&r->s, "NULL_ARRAY"))
                return -1;
            continue;
        }
        char name[TPK_NAME_MAX];
        int64_t comps, tuples;
        vtk_type type;
        decode_name(tok, len, name);
        if (arg_count(r, name, "a component count", &comps) || arg_count(r, name, "a tuple count", &tuples) ||
            arg_type(r, name, &type) || tpk_scan_end_line(&r->s, "name components tuples type"))
            return -1;
        int keep = r->assoc >= 0;
        if (read_field_values(r, name, type, comps, tuples, keep, "FIELD array"))
            return -1;
    }
    return 0;
}

/* ---- Cells: classify, reduce, drop -------------------------------------------------------------- */


/* A polyhedron keeps its face stream (nfaces, then per face npts and npts ids) in place of its point
 * ids, in both CELLS forms (VTK's legacy writers put it there). Errors give the entry's place in the
 * CELLS block (old form: counting every cell's count) or in CONNECTIVITY. */
static int check_face_stream(vtk_reader *r, int64_t cell, const int32_t *e, int64_t n)
{
    int64_t bad_at;
    char why[200];
    if (tpk_face_stream_check(e, n, r->point_count, &bad_at, why, sizeof why) == 0)
        return 0;
    int64_t at = r->offsets[cell] + bad_at + (r->offsets_form ? 0 : cell + 1);
    return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                            "CELLS: cell %lld (polyhedron): %s (face stream entry %lld, %s value %lld)", (long long)cell,
                            why, (long long)bad_at, r->offsets_form ? "CONNECTIVITY" : "CELLS", (long long)at);
}

static int check_cell(vtk_reader *r, int64_t c, const tpk_cell_rule *rule)
{
    int64_t begin = r->offsets[c], n = r->offsets[c + 1] - begin;
    const int32_t *ids = r->conn + begin;
    if (rule->kind == TPK_RULE_UNKNOWN)
        return tpk_scan_fail_at(&r->s, r->types_pos, r->types_line, "CELL_TYPES: cell %lld has unsupported cell type %d (%s)",
                                (long long)c, r->types[c], rule->name);
    if (rule->kind != TPK_RULE_DROP && r->types[c] == 42)
        return check_face_stream(r, c, ids, n);
    if ((rule->nodes > 0 && n != rule->nodes) || (rule->nodes < 0 && n < -rule->nodes))
        return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                                "CELLS: cell %lld (%s, type %d) has %lld points, expected %s%d", (long long)c,
                                rule->name, r->types[c], (long long)n, rule->nodes < 0 ? "at least " : "",
                                rule->nodes < 0 ? -rule->nodes : rule->nodes);
    for (int64_t j = 0; j < n; j++)
        if (ids[j] >= r->point_count)
            return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                                    "CELLS: cell %lld uses point id %d, but there are only %lld points (0 to %lld)",
                                    (long long)c, ids[j], (long long)r->point_count, (long long)r->point_count - 1);
    return 0;
}

static void filter_cell_fields(vtk_reader *r, const uint8_t *keep)
{
    for (int i = 0; i < r->fields.field_count; i++) {
        tpk_src_field *f = &r->fields.fields[i];
        if (f->association != TPK_ASSOC_TET)
            continue;
        int64_t k = 0;
        for (int64_t c = 0; c < r->cell_count; c++)
            if (keep[c])
                memmove(f->values + k++ * f->components, f->values + c * f->components,
                        sizeof(float) * (size_t)f->components);
    }
}

static int finish_mesh(vtk_reader *r, tpk_mesh *out)
{
    if (r->point_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a POINTS section, found end of file");
    if (r->cell_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a CELLS section, found end of file");
    if (r->type_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a CELL_TYPES section, found end of file");
    int64_t dropped[256] = {0}, reduced[256] = {0};
    int64_t drop_total = 0, reduce_total = 0, kept = 0, conn_size = 0;
    for (int64_t c = 0; c < r->cell_count; c++) {
        tpk_cell_rule rule = tpk_cell_rule_for(r->types[c]);
        if (check_cell(r, c, &rule))
            return -1;
        if (rule.kind == TPK_RULE_DROP) {
            dropped[r->types[c]]++;
            drop_total++;
            continue;
        }
        if (rule.kind == TPK_RULE_REDUCE) {
            reduced[r->types[c]]++;
            reduce_total++;
        }
        kept++;
        conn_size += rule.kind == TPK_RULE_REDUCE ? rule.out_nodes : r->offsets[c + 1] - r->offsets[c];
    }
    if (drop_total)
        tpk_warn_cell_counts(r->s.diag, r->s.name, dropped, drop_total,
                             "dropped cells that are not volumes:");
    if (reduce_total)
        tpk_warn_cell_counts(r->s.diag, r->s.name, reduced, reduce_total,
                             "reduced higher-order cells to their corner nodes:");

    out->point_count = r->point_count;
    out->points = r->points;
    r->points = NULL;
    out->cell_count = kept;
    if (!drop_total && !reduce_total) {
        out->cell_types = r->types;
        out->cell_offsets = r->offsets;
        out->cell_conn = r->conn;
        r->types = NULL;
        r->offsets = NULL;
        r->conn = NULL;
    } else {
        uint8_t *keep = malloc((size_t)(r->cell_count ? r->cell_count : 1));
        out->cell_types = malloc((size_t)(kept ? kept : 1));
        out->cell_offsets = malloc(sizeof(int64_t) * (size_t)(kept + 1));
        out->cell_conn = malloc(sizeof(int32_t) * (size_t)(conn_size ? conn_size : 1));
        if (!keep || !out->cell_types || !out->cell_offsets || !out->cell_conn) {
            free(keep);
            return tpk_diag_fail(r->s.diag, "%s: out of memory", r->s.name);
        }
        int64_t k = 0, o = 0;
        out->cell_offsets[0] = 0;
        for (int64_t c = 0; c < r->cell_count; c++) {
            tpk_cell_rule rule = tpk_cell_rule_for(r->types[c]);
            keep[c] = rule.kind != TPK_RULE_DROP;
            if (!keep[c])
                continue;
            int64_t n = rule.kind == TPK_RULE_REDUCE ? rule.out_nodes : r->offsets[c + 1] - r->offsets[c];
            memcpy(out->cell_conn + o, r->conn + r->offsets[c], sizeof(int32_t) * (size_t)n);
            o += n;
            out->cell_types[k] = rule.out_type;
            out->cell_offsets[++k] = o;
        }
        filter_cell_fields(r, keep);
        free(keep);
    }
    out->fields = r->fields.fields;
    out->field_count = r->fields.field_count;
    r->fields.fields = NULL;
    r->fields.field_count = 0;
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "%s", r->binary ? "vtk-legacy-binary" : "vtk-legacy-ascii");
    if (tpk_mesh_take_face_streams(out))
        return tpk_diag_fail(r->s.diag, "%s: out of memory", r->s.name);
    return 0;
}

/* ---- Header and section loop -------------------------------------------------------------------- */

static int read_header(vtk_reader *r)
{
    tpk_scan *s = &r->s;
    const char *magic = "# vtk DataFile Version";
    size_t mlen = strlen(magic);
    size_t line_len = 0;
    while (line_len < s->size && s->data[line_len] != '\n')
        line_len++;
    if (line_len < mlen || !tpk_token_is((const char *)s->data, mlen, magic)) {
        char q[64];
        return tpk_scan_fail_at(s, 0, 1, "expected '# vtk DataFile Version x.y', found '%s'",
                                s->size ? quote((const char *)s->data, line_len, q, sizeof q) : "an empty file");
    }
    tpk_scan_skip_line(s); /* version line */
    if (s->pos >= s->size)
        return tpk_scan_fail_at(s, s->pos, s->line, "expected a title line, found end of file");
    tpk_scan_skip_line(s); /* title */
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    char q[64];
    if (tpk_token_is(tok, len, "BINARY")) {
        r->binary = 1;
        s->byte_places = 1;
    } else if (!tpk_token_is(tok, len, "ASCII")) {
        return tpk_scan_fail(s, "expected 'ASCII' or 'BINARY', found '%s'",
                             len ? quote(tok, len, q, sizeof q) : "end of file");
    }
    if (tpk_scan_end_line(s, r->binary ? "BINARY" : "ASCII"))
        return -1;
    len = tpk_scan_token(s, &tok);
    if (!tpk_token_is(tok, len, "DATASET"))
        return tpk_scan_fail(s, "expected 'DATASET UNSTRUCTURED_GRID', found '%s'",
                             len ? quote(tok, len, q, sizeof q) : "end of file");
    len = tpk_scan_line_token(s, &tok);
    if (!tpk_token_is(tok, len, "UNSTRUCTURED_GRID"))
        return tpk_scan_fail(s, "unsupported dataset type '%s': expected UNSTRUCTURED_GRID",
                             len ? quote(tok, len, q, sizeof q) : "(none)");
    return tpk_scan_end_line(s, "DATASET UNSTRUCTURED_GRID");
}

static int read_section(vtk_reader *r, const char *tok, size_t len)
{
    if (tpk_token_is(tok, len, "POINTS"))
        return read_points(r);
    if (tpk_token_is(tok, len, "CELLS"))
        return read_cells(r);
    if (tpk_token_is(tok, len, "CELL_TYPES"))
        return read_cell_types(r);
    if (tpk_token_is(tok, len, "POINT_DATA"))
        return read_data_header(r, TPK_ASSOC_POINT);
    if (tpk_token_is(tok, len, "CELL_DATA"))
        return read_data_header(r, TPK_ASSOC_TET);
    if (tpk_token_is(tok, len, "SCALARS"))
        return read_scalars(r);
    if (tpk_token_is(tok, len, "VECTORS"))
        return read_fixed_attribute(r, "VECTORS", 3);
    if (tpk_token_is(tok, len, "NORMALS"))
        return read_fixed_attribute(r, "NORMALS", 3);
    if (tpk_token_is(tok, len, "TENSORS"))
        return read_fixed_attribute(r, "TENSORS", 9);
    if (tpk_token_is(tok, len, "TENSORS6"))
        return read_fixed_attribute(r, "TENSORS6", 6);
    if (tpk_token_is(tok, len, "GLOBAL_IDS"))
        return read_fixed_attribute(r, "GLOBAL_IDS", 1);
    if (tpk_token_is(tok, len, "PEDIGREE_IDS"))
        return read_fixed_attribute(r, "PEDIGREE_IDS", 1);
    if (tpk_token_is(tok, len, "TEXTURE_COORDINATES"))
        return read_texture_coordinates(r);
    if (tpk_token_is(tok, len, "COLOR_SCALARS"))
        return read_color_scalars(r);
    if (tpk_token_is(tok, len, "LOOKUP_TABLE"))
        return skip_lookup_table(r);
    if (tpk_token_is(tok, len, "FIELD"))
        return read_field(r);
    if (tpk_token_is(tok, len, "METADATA")) {
        skip_metadata(r);
        return 0;
    }
    char q[64];
    return tpk_scan_fail(&r->s, "expected a section (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, "
                         "VECTORS, FIELD, ...), found '%s'", quote(tok, len, q, sizeof q));
}

static void reader_free(vtk_reader *r)
{
    free(r->points);
    free(r->offsets);
    free(r->conn);
    free(r->types);
    tpk_mesh_free(&r->fields);
}

static int import_buffer(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name ? name : "(input)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    vtk_reader r;
    memset(&r, 0, sizeof r);
    tpk_scan_init(&r.s, name, data, size, diag);
    r.s.mapped = mapped;
    r.point_count = r.cell_count = r.type_count = -1;
    r.assoc = -1;
    int rc = read_header(&r);
    while (rc == 0) {
        const char *tok;
        size_t len = tpk_scan_token(&r.s, &tok);
        if (!len)
            break;
        r.kw_pos = r.s.tok_pos;
        r.kw_line = r.s.tok_line;
        rc = read_section(&r, tok, len);
        tpk_scan_release_consumed(&r.s);
    }
    if (rc == 0)
        rc = finish_mesh(&r, out);
    reader_free(&r);
    if (rc != 0)
        tpk_mesh_free(out);
    return rc;
}

int tpk_import_vtk_legacy_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_vtk_legacy(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
