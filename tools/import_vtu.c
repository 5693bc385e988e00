/* VTK XML UnstructuredGrid (.vtu) importer. expat parses the XML; the DataArrays' contents are decoded
 * here: ascii numbers, base64 ("binary") and raw or base64 appended data, each with a UInt32 or UInt64
 * header, optionally as zlib-compressed blocks. Raw appended data is not XML, so the buffer is split at
 * the '_' that starts it: expat sees only the XML before, the blocks are read by their offsets.
 * Every size read from the file is checked against the bytes that can hold it before allocating. */
#include <expat.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "cell_types.h"
#include "importers.h"
#include "polyhedron.h"
#include "tetpack_format.h"
#include "text_scan.h"

/* zlib's deflate never packs more than this many bytes into one compressed byte (plus a small constant). */
#define ZLIB_MAX_RATIO 1032u

typedef enum vtu_type { T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64, T_NONE } vtu_type;

static const struct {
    const char *name;
    vtu_type type;
    unsigned size;
} type_table[] = {{"Int8", T_I8, 1},    {"UInt8", T_U8, 1},    {"Int16", T_I16, 2},   {"UInt16", T_U16, 2},
                  {"Int32", T_I32, 4},  {"UInt32", T_U32, 4},  {"Int64", T_I64, 8},   {"UInt64", T_U64, 8},
                  {"Float32", T_F32, 4}, {"Float64", T_F64, 8}, {"Char", T_I8, 1},     {"UChar", T_U8, 1}};

static unsigned type_size(vtu_type t)
{
    static const unsigned sizes[] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8, 0};
    return sizes[t];
}

static const char *type_name(vtu_type t)
{
    for (size_t i = 0; i < sizeof type_table / sizeof type_table[0]; i++)
        if (type_table[i].type == t)
            return type_table[i].name;
    return "?";
}

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
    vtu_array cur;
    char *text;
    size_t text_len, text_cap;
    /* Every DataArray kept, in file order. */
    vtu_array *arrays;
    int array_count, array_cap;
    /* Appended data. */
    int appended_seen;     /* the AppendedData start tag was parsed */
    int appended_base64;
    size_t app_start, app_end;
} vtu_reader;

/* ---- Messages ----------------------------------------------------------------------------------- */

static int fail_line(vtu_reader *r, long line, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail_line(vtu_reader *r, long line, const char *fmt, ...)
{
    char text[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (!r->failed) {
        r->failed = 1;
        if (line > 0)
            tpk_diag_fail(r->diag, "%s: line %ld: %s", r->name, line, text);
        else
            tpk_diag_fail(r->diag, "%s: %s", r->name, text);
    }
    if (r->parser)
        XML_StopParser(r->parser, XML_FALSE);
    return -1;
}

static int fail_array(vtu_reader *r, const vtu_array *a, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail_array(vtu_reader *r, const vtu_array *a, const char *fmt, ...)
{
    char text[700];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (!r->failed) {
        r->failed = 1;
        tpk_diag_fail(r->diag, "%s: DataArray '%s' (line %ld): %s", r->name, a->name, a->line, text);
    }
    if (r->parser)
        XML_StopParser(r->parser, XML_FALSE);
    return -1;
}

static long cur_line(vtu_reader *r)
{
    return (long)XML_GetCurrentLineNumber(r->parser);
}

static const char *quote(const char *s, char *buf, size_t cap)
{
    return tpk_scan_quote(s, strlen(s), buf, cap);
}

static const char *attr(const XML_Char **atts, const char *key)
{
    for (int i = 0; atts[i]; i += 2)
        if (!strcmp(atts[i], key))
            return atts[i + 1];
    return NULL;
}

static int parse_count(const char *s, int64_t *out)
{
    size_t len = strlen(s);
    while (len && (s[len - 1] == ' ' || s[len - 1] == '\t' || s[len - 1] == '\n' || s[len - 1] == '\r'))
        len--;
    while (len && (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r'))
        s++, len--;
    return tpk_parse_int64(s, len, out) != 0 || *out < 0 ? -1 : 0;
}

/* ---- Byte sources: raw bytes, or base64 text decoded as it is read -------------------------------- */

typedef struct bsrc {
    const unsigned char *p;
    size_t len, pos;
    int b64;
    unsigned char pend[3];
    int npend, ipend;
    int in_file;           /* p points into the file at `base` (appended data): places are file offsets */
    size_t base;
    const char *error;     /* why a read failed, with the place */
    char error_buf[160];
} bsrc;

static int src_fail(bsrc *s, const char *what)
{
    if (s->in_file)
        snprintf(s->error_buf, sizeof s->error_buf, "%s at byte %zu of the file", what, s->base + s->pos);
    else
        snprintf(s->error_buf, sizeof s->error_buf, "%s at character %zu of the array's text", what, s->pos);
    s->error = s->error_buf;
    return -1;
}

static int b64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z')
        return c - 'A';
    if (c >= 'a' && c <= 'z')
        return c - 'a' + 26;
    if (c >= '0' && c <= '9')
        return c - '0' + 52;
    if (c == '+')
        return 62;
    if (c == '/')
        return 63;
    if (c == '=')
        return -2;
    return -1;
}

static int is_space(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/* An upper bound on the bytes the source can still give. */
static uint64_t src_left(const bsrc *s)
{
    if (!s->b64)
        return s->len - s->pos;
    return (uint64_t)(s->len - s->pos) / 4 * 3 + 3 + (uint64_t)(s->npend - s->ipend);
}

/* Base64 is decoded group by group, so streams concatenated with their own '=' padding (VTK encodes
 * the header and the data separately) decode as one. */
static int src_read(bsrc *s, unsigned char *out, size_t n)
{
    if (!s->b64) {
        if (n > s->len - s->pos) {
            return src_fail(s, "found the end of the data");
        }
        memcpy(out, s->p + s->pos, n);
        s->pos += n;
        return 0;
    }
    while (n) {
        if (s->ipend < s->npend) {
            *out++ = s->pend[s->ipend++];
            n--;
            continue;
        }
        int v[4], k = 0;
        while (k < 4 && s->pos < s->len) {
            unsigned char c = s->p[s->pos++];
            if (is_space(c))
                continue;
            v[k] = b64_value(c);
            if (v[k] == -1) {
                s->pos--;
                return src_fail(s, "found a character that is not base64");
            }
            k++;
        }
        if (k == 0) {
            return src_fail(s, "found the end of the base64 data");
        }
        if (k < 4 || v[0] < 0 || v[1] < 0 || (v[2] == -2 && v[3] != -2)) {
            return src_fail(s, "found an incomplete or badly padded base64 group");
        }
        uint32_t bits = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 | (uint32_t)(v[2] < 0 ? 0 : v[2]) << 6 |
                        (uint32_t)(v[3] < 0 ? 0 : v[3]);
        s->pend[0] = (unsigned char)(bits >> 16);
        s->pend[1] = (unsigned char)(bits >> 8);
        s->pend[2] = (unsigned char)bits;
        s->npend = v[2] == -2 ? 1 : v[3] == -2 ? 2 : 3;
        s->ipend = 0;
    }
    return 0;
}

static uint64_t get_uint(const unsigned char *p, unsigned size, int big)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < size; i++)
        v |= (uint64_t)p[big ? size - 1 - i : i] << (8 * i);
    return v;
}

static int read_header_word(vtu_reader *r, const vtu_array *a, bsrc *s, uint64_t *out, const char *what)
{
    unsigned char b[8];
    if (src_read(s, b, r->header_size))
        return fail_array(r, a, "expected the header's %s (%s), %s", what, r->header_size == 8 ? "UInt64" : "UInt32",
                          s->error);
    *out = get_uint(b, r->header_size, r->big_endian);
    return 0;
}

/* The array's bytes (header and data, compressed or not); `expected` values when known (else
 * UINT64_MAX). Returns a malloc'ed buffer of *nbytes bytes (at least 1 allocated) or NULL. */
static unsigned char *read_binary(vtu_reader *r, const vtu_array *a, bsrc *s, uint64_t expected, uint64_t *nbytes)
{
    unsigned tsize = type_size(a->type);
    uint64_t want = expected == UINT64_MAX ? UINT64_MAX : expected * tsize;
    if (!r->compressed) {
        uint64_t n = 0;
        if (read_header_word(r, a, s, &n, "byte count"))
            return NULL;
        if (want != UINT64_MAX && n != want) {
            fail_array(r, a, "expected %llu bytes (%llu %s values), found a header saying %llu", (unsigned long long)want,
                       (unsigned long long)expected, type_name(a->type), (unsigned long long)n);
            return NULL;
        }
        if (n > src_left(s)) {
            fail_array(r, a, "data truncated: the header says %llu bytes, at most %llu are left",
                       (unsigned long long)n, (unsigned long long)src_left(s));
            return NULL;
        }
        unsigned char *buf = malloc(n ? (size_t)n : 1);
        if (!buf) {
            fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)n);
            return NULL;
        }
        if (src_read(s, buf, (size_t)n)) {
            free(buf);
            fail_array(r, a, "expected %llu data bytes, %s", (unsigned long long)n, s->error);
            return NULL;
        }
        *nbytes = n;
        return buf;
    }
    uint64_t blocks = 0, block_size = 0, last_size = 0;
    if (read_header_word(r, a, s, &blocks, "block count") || read_header_word(r, a, s, &block_size, "block size") ||
        read_header_word(r, a, s, &last_size, "last block size"))
        return NULL;
    if (blocks > src_left(s) / r->header_size) {
        fail_array(r, a, "expected at most %llu compressed blocks in the data left, found a header saying %llu",
                   (unsigned long long)(src_left(s) / r->header_size), (unsigned long long)blocks);
        return NULL;
    }
    if (last_size > block_size) {
        fail_array(r, a, "expected the last block size (%llu) <= the block size (%llu)", (unsigned long long)last_size,
                   (unsigned long long)block_size);
        return NULL;
    }
    uint64_t last = last_size ? last_size : block_size;
    uint64_t total = 0;
    if (blocks) {
        if (block_size && blocks - 1 > (UINT64_MAX - last) / block_size) {
            fail_array(r, a, "%llu blocks of %llu bytes: too large for any file", (unsigned long long)blocks,
                       (unsigned long long)block_size);
            return NULL;
        }
        total = (blocks - 1) * block_size + last;
    }
    if (want != UINT64_MAX && total != want) {
        fail_array(r, a, "expected %llu bytes (%llu %s values), found a compression header saying %llu",
                   (unsigned long long)want, (unsigned long long)expected, type_name(a->type), (unsigned long long)total);
        return NULL;
    }
    uint64_t *csizes = malloc(sizeof(uint64_t) * (size_t)(blocks ? blocks : 1));
    if (!csizes) {
        fail_array(r, a, "out of memory");
        return NULL;
    }
    uint64_t csum = 0, cmax = 0;
    for (uint64_t b = 0; b < blocks; b++) {
        if (read_header_word(r, a, s, &csizes[b], "compressed block size")) {
            free(csizes);
            return NULL;
        }
        uint64_t usize = b + 1 == blocks ? last : block_size;
        if (csizes[b] > src_left(s) || (usize > 64 && (usize - 64) / ZLIB_MAX_RATIO > csizes[b])) {
            fail_array(r, a, "zlib block %llu of %llu: expected a compressed size that can hold %llu bytes within "
                       "the data left (%llu), found %llu", (unsigned long long)b + 1, (unsigned long long)blocks,
                       (unsigned long long)usize, (unsigned long long)src_left(s), (unsigned long long)csizes[b]);
            free(csizes);
            return NULL;
        }
        csum += csizes[b];
        if (csizes[b] > cmax)
            cmax = csizes[b];
    }
    if (csum > src_left(s)) {
        fail_array(r, a, "data truncated: the compressed blocks take %llu bytes, at most %llu are left",
                   (unsigned long long)csum, (unsigned long long)src_left(s));
        free(csizes);
        return NULL;
    }
    unsigned char *out = malloc(total ? (size_t)total : 1);
    unsigned char *tmp = malloc(cmax ? (size_t)cmax : 1);
    if (!out || !tmp) {
        free(out);
        free(tmp);
        free(csizes);
        fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)total);
        return NULL;
    }
    uint64_t o = 0;
    for (uint64_t b = 0; b < blocks; b++) {
        uint64_t usize = b + 1 == blocks ? last : block_size;
        if (src_read(s, tmp, (size_t)csizes[b])) {
            fail_array(r, a, "zlib block %llu of %llu: expected %llu compressed bytes, %s", (unsigned long long)b + 1,
                       (unsigned long long)blocks, (unsigned long long)csizes[b], s->error);
            goto fail;
        }
        uLongf dlen = (uLongf)usize;
        int zrc = uncompress(out + o, &dlen, tmp, (uLong)csizes[b]);
        if (zrc != Z_OK) {
            fail_array(r, a, "zlib block %llu of %llu does not decompress: %s", (unsigned long long)b + 1,
                       (unsigned long long)blocks, zrc == Z_BUF_ERROR ? "it is incomplete or holds more than the header's size" : zError(zrc));
            goto fail;
        }
        if (dlen != usize) {
            fail_array(r, a, "zlib block %llu of %llu: expected %llu bytes, found %llu", (unsigned long long)b + 1,
                       (unsigned long long)blocks, (unsigned long long)usize, (unsigned long long)dlen);
            goto fail;
        }
        o += usize;
    }
    free(tmp);
    free(csizes);
    *nbytes = total;
    return out;
fail:
    free(tmp);
    free(csizes);
    free(out);
    return NULL;
}

static double value_at(const unsigned char *p, vtu_type t, int big)
{
    unsigned size = type_size(t);
    uint64_t u = get_uint(p, size, big);
    switch (t) {
    case T_I8: return (int8_t)u;
    case T_U8: return (double)u;
    case T_I16: return (int16_t)u;
    case T_U16: return (double)u;
    case T_I32: return (int32_t)u;
    case T_U32: return (double)u;
    case T_I64: return (double)(int64_t)u;
    case T_U64: return (double)u;
    case T_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        return f;
    }
    case T_F64: {
        double d;
        memcpy(&d, &u, 8);
        return d;
    }
    case T_NONE: break;
    }
    return 0;
}

/* The number of values expected in an array of this role, or UINT64_MAX when not known yet. */
static uint64_t expected_count(const vtu_reader *r, const vtu_array *a)
{
    switch (a->role) {
    case ROLE_POINTS: return 3 * (uint64_t)r->point_count;
    case ROLE_OFFSETS:
    case ROLE_TYPES:
    case ROLE_FACEOFFSETS: return (uint64_t)r->cell_count;
    case ROLE_POINT_FIELD: return (uint64_t)r->point_count * (uint64_t)a->components;
    case ROLE_CELL_FIELD: return (uint64_t)r->cell_count * (uint64_t)a->components;
    default: return UINT64_MAX;
    }
}

static int decode_binary(vtu_reader *r, vtu_array *a, bsrc *s)
{
    uint64_t expected = expected_count(r, a), nbytes = 0;
    unsigned char *bytes = read_binary(r, a, s, expected, &nbytes);
    if (!bytes)
        return -1;
    unsigned tsize = type_size(a->type);
    if (nbytes % tsize) {
        free(bytes);
        return fail_array(r, a, "expected a whole number of %s values, found %llu bytes", type_name(a->type),
                          (unsigned long long)nbytes);
    }
    uint64_t n = nbytes / tsize;
    a->values = malloc(sizeof(double) * (size_t)(n ? n : 1));
    if (!a->values) {
        free(bytes);
        return fail_array(r, a, "out of memory for %llu values", (unsigned long long)n);
    }
    for (uint64_t i = 0; i < n; i++)
        a->values[i] = value_at(bytes + i * tsize, a->type, r->big_endian);
    a->count = n;
    free(bytes);
    return 0;
}

static int is_int_type(vtu_type t)
{
    return t != T_F32 && t != T_F64;
}

static int decode_ascii(vtu_reader *r, vtu_array *a, const char *text, size_t len)
{
    uint64_t n = 0;
    for (size_t i = 0; i < len;) {
        while (i < len && is_space((unsigned char)text[i]))
            i++;
        if (i >= len)
            break;
        n++;
        while (i < len && !is_space((unsigned char)text[i]))
            i++;
    }
    uint64_t expected = expected_count(r, a);
    if (expected != UINT64_MAX && n != expected)
        return fail_array(r, a, "expected %llu values, found %llu", (unsigned long long)expected, (unsigned long long)n);
    a->values = malloc(sizeof(double) * (size_t)(n ? n : 1));
    if (!a->values)
        return fail_array(r, a, "out of memory for %llu values", (unsigned long long)n);
    uint64_t k = 0;
    for (size_t i = 0; i < len;) {
        while (i < len && is_space((unsigned char)text[i]))
            i++;
        if (i >= len)
            break;
        size_t b = i;
        while (i < len && !is_space((unsigned char)text[i]))
            i++;
        int64_t iv;
        double dv;
        int bad;
        if (is_int_type(a->type)) {
            bad = tpk_parse_int64(text + b, i - b, &iv) != 0;
            dv = (double)iv;
        } else {
            bad = tpk_parse_double(text + b, i - b, &dv) != 0;
        }
        if (bad) {
            char q[64];
            return fail_array(r, a, "expected %s (value %llu of %llu), found '%s'",
                              is_int_type(a->type) ? "an integer" : "a number", (unsigned long long)k + 1,
                              (unsigned long long)n, tpk_scan_quote(text + b, i - b, q, sizeof q));
        }
        a->values[k++] = dv;
    }
    a->count = n;
    return 0;
}

static int keep_array(vtu_reader *r, vtu_array *a)
{
    if (r->array_count == r->array_cap) {
        int cap = r->array_cap ? 2 * r->array_cap : 8;
        vtu_array *grown = realloc(r->arrays, sizeof *grown * (size_t)cap);
        if (!grown)
            return fail_array(r, a, "out of memory");
        r->arrays = grown;
        r->array_cap = cap;
    }
    r->arrays[r->array_count++] = *a;
    a->values = NULL;
    return 0;
}

/* ---- XML handlers ------------------------------------------------------------------------------- */

static int start_vtkfile(vtu_reader *r, const XML_Char **atts)
{
    char q[64];
    const char *type = attr(atts, "type"), *order = attr(atts, "byte_order"), *header = attr(atts, "header_type"),
               *comp = attr(atts, "compressor");
    if (!type || strcmp(type, "UnstructuredGrid"))
        return fail_line(r, cur_line(r), "VTKFile: expected type=\"UnstructuredGrid\", found %s%s%s",
                         type ? "\"" : "", type ? quote(type, q, sizeof q) : "no type", type ? "\"" : "");
    if (order && !strcmp(order, "BigEndian"))
        r->big_endian = 1;
    else if (order && strcmp(order, "LittleEndian"))
        return fail_line(r, cur_line(r), "VTKFile: expected byte_order LittleEndian or BigEndian, found \"%s\"",
                         quote(order, q, sizeof q));
    if (header && !strcmp(header, "UInt64"))
        r->header_size = 8;
    else if (header && strcmp(header, "UInt32"))
        return fail_line(r, cur_line(r), "VTKFile: expected header_type UInt32 or UInt64, found \"%s\"",
                         quote(header, q, sizeof q));
    if (comp && !strcmp(comp, "vtkZLibDataCompressor"))
        r->compressed = 1;
    else if (comp && comp[0])
        return fail_line(r, cur_line(r), "VTKFile: expected compressor vtkZLibDataCompressor or none, found \"%s\" "
                         "(not supported)", quote(comp, q, sizeof q));
    return 0;
}

static int start_piece(vtu_reader *r, const XML_Char **atts)
{
    if (r->piece_seen)
        return fail_line(r, cur_line(r), "expected one Piece, found a second (multi-piece files are not read)");
    r->piece_seen = 1;
    const char *np = attr(atts, "NumberOfPoints"), *nc = attr(atts, "NumberOfCells");
    char q[64];
    if (!np || parse_count(np, &r->point_count))
        return fail_line(r, cur_line(r), "Piece: expected NumberOfPoints >= 0, found %s",
                         np ? quote(np, q, sizeof q) : "none");
    if (!nc || parse_count(nc, &r->cell_count))
        return fail_line(r, cur_line(r), "Piece: expected NumberOfCells >= 0, found %s",
                         nc ? quote(nc, q, sizeof q) : "none");
    /* Every point and cell takes at least one byte of the file, zlib packing up to ZLIB_MAX_RATIO. */
    uint64_t cap = (uint64_t)r->size * ZLIB_MAX_RATIO;
    if (r->point_count > INT32_MAX || (uint64_t)r->point_count > cap)
        return fail_line(r, cur_line(r), "Piece: NumberOfPoints %lld cannot be held in a file of %zu bytes "
                         "(at most 2^31-1 points)", (long long)r->point_count, r->size);
    if (r->cell_count > INT32_MAX || (uint64_t)r->cell_count > cap)
        return fail_line(r, cur_line(r), "Piece: NumberOfCells %lld cannot be held in a file of %zu bytes "
                         "(at most 2^31-1 cells)", (long long)r->cell_count, r->size);
    return 0;
}

static int start_array(vtu_reader *r, const XML_Char **atts)
{
    vtu_array *a = &r->cur;
    memset(a, 0, sizeof *a);
    a->line = cur_line(r);
    const char *name = attr(atts, "Name"), *type = attr(atts, "type"), *comps = attr(atts, "NumberOfComponents"),
               *format = attr(atts, "format"), *offset = attr(atts, "offset");
    snprintf(a->name, sizeof a->name, "%s", name && name[0] ? name : "unnamed");
    char q[64];
    switch (r->section) {
    case SEC_POINTS: a->role = ROLE_POINTS; break;
    case SEC_POINT_DATA: a->role = ROLE_POINT_FIELD; break;
    case SEC_CELL_DATA: a->role = ROLE_CELL_FIELD; break;
    default:
        if (!name)
            return fail_array(r, a, "Cells: expected a Name (connectivity, offsets, types, faces, faceoffsets)");
        if (!strcmp(name, "connectivity"))
            a->role = ROLE_CONN;
        else if (!strcmp(name, "offsets"))
            a->role = ROLE_OFFSETS;
        else if (!strcmp(name, "types"))
            a->role = ROLE_TYPES;
        else if (!strcmp(name, "faces"))
            a->role = ROLE_FACES;
        else if (!strcmp(name, "faceoffsets"))
            a->role = ROLE_FACEOFFSETS;
        else
            return 0; /* another array under Cells: ignored */
    }
    a->type = T_NONE;
    for (size_t i = 0; type && i < sizeof type_table / sizeof type_table[0]; i++)
        if (!strcmp(type, type_table[i].name))
            a->type = type_table[i].type;
    if (a->type == T_NONE)
        return fail_array(r, a, "expected a type (Int8..Int64, UInt8..UInt64, Float32, Float64), found %s",
                          type ? quote(type, q, sizeof q) : "none");
    int64_t nc = 1;
    if (comps && (parse_count(comps, &nc) || nc < 1 || nc > 1024))
        return fail_array(r, a, "expected NumberOfComponents from 1 to 1024, found %s", quote(comps, q, sizeof q));
    a->components = (int)nc;
    if (a->role == ROLE_POINTS && nc != 3)
        return fail_array(r, a, "Points: expected NumberOfComponents=\"3\", found %d", a->components);
    if (a->role != ROLE_POINTS && a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD && nc != 1)
        return fail_array(r, a, "expected NumberOfComponents=\"1\", found %d", a->components);
    if (a->role != ROLE_POINTS && a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD && !is_int_type(a->type))
        return fail_array(r, a, "expected an integer type, found %s", type_name(a->type));
    if (!format || !strcmp(format, "ascii"))
        a->format = 0;
    else if (!strcmp(format, "binary"))
        a->format = 1;
    else if (!strcmp(format, "appended"))
        a->format = 2;
    else
        return fail_array(r, a, "expected format ascii, binary or appended, found \"%s\"", quote(format, q, sizeof q));
    if (a->format == 2) {
        int64_t off;
        if (!offset || parse_count(offset, &off))
            return fail_array(r, a, "expected an offset >= 0 into the appended data, found %s",
                              offset ? quote(offset, q, sizeof q) : "none");
        a->offset = (uint64_t)off;
    }
    for (int i = 0; i < r->array_count; i++)
        if (r->arrays[i].role == a->role && a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD)
            return fail_array(r, a, "expected one such array, found a second");
    r->in_array = 1;
    r->array_depth = r->depth;
    r->collect = a->format != 2;
    r->text_len = 0;
    return 0;
}

static void XMLCALL on_start(void *user, const XML_Char *el, const XML_Char **atts)
{
    vtu_reader *r = user;
    if (r->failed)
        return;
    r->depth++;
    if (r->in_array)
        return; /* InformationKey and such inside a DataArray */
    char q[64];
    if (r->depth == 1) {
        if (strcmp(el, "VTKFile")) {
            fail_line(r, cur_line(r), "expected <VTKFile> (a VTK XML file), found <%s>", quote(el, q, sizeof q));
            return;
        }
        r->root_seen = 1;
        start_vtkfile(r, atts);
        return;
    }
    if (r->depth == 2 && !strcmp(el, "AppendedData")) {
        const char *enc = attr(atts, "encoding");
        if (enc && !strcmp(enc, "base64"))
            r->appended_base64 = 1;
        else if (enc && strcmp(enc, "raw")) {
            fail_line(r, cur_line(r), "AppendedData: expected encoding raw or base64, found \"%s\"",
                      quote(enc, q, sizeof q));
            return;
        }
        r->appended_seen = 1;
        return;
    }
    if (r->depth == 2 && !strcmp(el, "UnstructuredGrid")) {
        r->grid_depth = 2;
        return;
    }
    if (r->grid_depth && r->depth == 3 && !strcmp(el, "Piece")) {
        r->piece_depth = 3;
        start_piece(r, atts);
        return;
    }
    if (r->piece_depth && r->depth == 4) {
        r->section = !strcmp(el, "Points")      ? SEC_POINTS
                     : !strcmp(el, "Cells")     ? SEC_CELLS
                     : !strcmp(el, "PointData") ? SEC_POINT_DATA
                     : !strcmp(el, "CellData")  ? SEC_CELL_DATA
                                                : SEC_OTHER;
        return;
    }
    if (r->piece_depth && r->depth == 5 && r->section != SEC_OTHER && r->section != SEC_NONE &&
        !strcmp(el, "DataArray"))
        start_array(r, atts);
}

static void end_array(vtu_reader *r)
{
    vtu_array *a = &r->cur;
    r->in_array = 0;
    if (a->format == 0 && decode_ascii(r, a, r->text, r->text_len))
        return;
    if (a->format == 1) {
        bsrc s = {.p = (const unsigned char *)r->text, .len = r->text_len, .b64 = 1};
        if (decode_binary(r, a, &s))
            return;
    }
    keep_array(r, a);
}

static void XMLCALL on_end(void *user, const XML_Char *el)
{
    vtu_reader *r = user;
    (void)el;
    if (r->failed)
        return;
    if (r->in_array && r->depth == r->array_depth)
        end_array(r);
    if (r->depth == 4 && r->piece_depth)
        r->section = SEC_NONE;
    if (r->depth == 3 && r->piece_depth)
        r->piece_depth = 0;
    if (r->depth == 2 && r->grid_depth)
        r->grid_depth = 0;
    r->depth--;
}

static void XMLCALL on_text(void *user, const XML_Char *s, int len)
{
    vtu_reader *r = user;
    if (r->failed || !r->in_array || !r->collect || r->depth != r->array_depth || len <= 0)
        return;
    if (r->text_len + (size_t)len > r->text_cap) {
        size_t cap = r->text_cap ? r->text_cap : 4096;
        while (cap < r->text_len + (size_t)len)
            cap *= 2;
        char *grown = realloc(r->text, cap);
        if (!grown) {
            fail_array(r, &r->cur, "out of memory for the array's text");
            return;
        }
        r->text = grown;
        r->text_cap = cap;
    }
    memcpy(r->text + r->text_len, s, (size_t)len);
    r->text_len += (size_t)len;
}

static void XMLCALL on_doctype(void *user, const XML_Char *name, const XML_Char *sysid, const XML_Char *pubid,
                               int has_internal)
{
    vtu_reader *r = user;
    (void)name, (void)sysid, (void)pubid, (void)has_internal;
    fail_line(r, cur_line(r), "expected a VTK XML file, found a DOCTYPE declaration (not read)");
}

/* ---- Splitting off the appended data ------------------------------------------------------------- */

static const unsigned char *find(const unsigned char *p, size_t n, const char *word)
{
    size_t w = strlen(word);
    while (n >= w) {
        const unsigned char *c = memchr(p, word[0], n - w + 1);
        if (!c)
            return NULL;
        if (!memcmp(c, word, w))
            return c;
        n -= (size_t)(c - p) + 1;
        p = c + 1;
    }
    return NULL;
}

/* Length of the XML part to give expat: everything, or up to and including the AppendedData start tag
 * when there is one (then app_start is the byte after its '_'). */
static int split_appended(vtu_reader *r, size_t *xml_len)
{
    *xml_len = r->size;
    const unsigned char *p = r->data, *end = r->data + r->size;
    for (;;) {
        const unsigned char *tag = find(p, (size_t)(end - p), "<AppendedData");
        if (!tag)
            return 0;
        const unsigned char *after = tag + 13;
        if (after < end && !is_space(*after) && *after != '>' && *after != '/') {
            p = after;
            continue;
        }
        const unsigned char *gt = memchr(after, '>', (size_t)(end - after));
        if (!gt)
            return fail_line(r, 0, "byte %zu: AppendedData: expected '>' closing the tag, found end of file",
                             (size_t)(tag - r->data));
        if (gt[-1] == '/')
            return 0; /* an empty <AppendedData/>: nothing appended */
        const unsigned char *u = memchr(gt + 1, '_', (size_t)(end - gt - 1));
        if (!u)
            return fail_line(r, 0, "byte %zu: AppendedData: expected '_' marking the start of the data, found end "
                             "of file", (size_t)(gt + 1 - r->data));
        for (const unsigned char *c = gt + 1; c < u; c++)
            if (!is_space(*c))
                return fail_line(r, 0, "byte %zu: AppendedData: expected '_' marking the start of the data, found "
                                 "'%c'", (size_t)(c - r->data), *c >= 32 && *c < 127 ? *c : '?');
        *xml_len = (size_t)(gt + 1 - r->data);
        r->app_start = (size_t)(u + 1 - r->data);
        r->app_end = r->size;
        return 0;
    }
}

static int parse_xml(vtu_reader *r)
{
    size_t xml_len;
    if (split_appended(r, &xml_len))
        return -1;
    int partial = xml_len < r->size;
    r->parser = XML_ParserCreate(NULL);
    if (!r->parser)
        return fail_line(r, 0, "out of memory for the XML parser");
    XML_SetUserData(r->parser, r);
    XML_SetElementHandler(r->parser, on_start, on_end);
    XML_SetCharacterDataHandler(r->parser, on_text);
    XML_SetStartDoctypeDeclHandler(r->parser, on_doctype);
    size_t pos = 0;
    const size_t chunk = (size_t)1 << 30;
    int rc = 0;
    do {
        size_t n = xml_len - pos < chunk ? xml_len - pos : chunk;
        int last = pos + n == xml_len && !partial;
        if (XML_Parse(r->parser, (const char *)r->data + pos, (int)n, last) == XML_STATUS_ERROR) {
            if (!r->failed) {
                long line = (long)XML_GetCurrentLineNumber(r->parser);
                long col = (long)XML_GetCurrentColumnNumber(r->parser);
                enum XML_Error e = XML_GetErrorCode(r->parser);
                r->failed = 1;
                tpk_diag_fail(r->diag, "%s: line %ld, column %ld: expected well-formed XML, found an error: %s%s", r->name,
                              line, col, XML_ErrorString(e),
                              e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN ||
                                      e == XML_ERROR_PARTIAL_CHAR
                                  ? " (truncated file?)"
                                  : "");
            }
            rc = -1;
            break;
        }
        pos += n;
    } while (pos < xml_len);
    if (r->failed)
        rc = -1;
    XML_ParserFree(r->parser);
    r->parser = NULL;
    if (rc == 0 && partial && !r->appended_seen)
        return fail_line(r, 0, "byte %zu: expected the AppendedData element directly inside VTKFile, found it "
                         "elsewhere", r->app_start);
    return rc;
}

static int decode_appended(vtu_reader *r)
{
    for (int i = 0; i < r->array_count; i++) {
        vtu_array *a = &r->arrays[i];
        if (a->format != 2)
            continue;
        if (!r->app_start)
            return fail_array(r, a, "expected an AppendedData section for format=\"appended\", found none");
        bsrc s = {.p = r->data + r->app_start, .len = r->app_end - r->app_start, .b64 = r->appended_base64,
                  .in_file = 1, .base = r->app_start};
        if (r->appended_base64) {
            const unsigned char *lt = memchr(s.p, '<', s.len);
            if (lt)
                s.len = (size_t)(lt - s.p);
        }
        if (a->offset > s.len)
            return fail_array(r, a, "expected an offset within the %zu bytes of appended data, found %llu", s.len,
                              (unsigned long long)a->offset);
        s.pos = (size_t)a->offset;
        if (decode_binary(r, a, &s))
            return -1;
    }
    return 0;
}

/* ---- Building the mesh --------------------------------------------------------------------------- */


static vtu_array *find_role(vtu_reader *r, int role)
{
    for (int i = 0; i < r->array_count; i++)
        if (r->arrays[i].role == role)
            return &r->arrays[i];
    return NULL;
}

/* Per cell: where its nodes (or, for a polyhedron, its face stream) are. */
typedef struct cell_span {
    const double *v;
    int64_t n;
} cell_span;

static int compare_int32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Every point a polyhedron's faces use must be in its connectivity (VTK's and meshio's writers list
 * exactly those points there); `ids` is the checked stream, `scratch` room for the connectivity. */
static int check_face_points(vtu_reader *r, const vtu_array *conn, int64_t cell, const int32_t *ids,
                             const double *points, int64_t point_count, int32_t *scratch)
{
    for (int64_t j = 0; j < point_count; j++) {
        if (!(points[j] >= 0 && points[j] < (double)r->point_count))
            return fail_array(r, conn, "cell %lld (polyhedron) lists point id %.17g, expected 0 to %lld",
                              (long long)cell, points[j], (long long)r->point_count - 1);
        scratch[j] = (int32_t)points[j];
    }
    qsort(scratch, (size_t)point_count, sizeof *scratch, compare_int32);
    for (int64_t f = 0, k = 1; f < ids[0]; f++)
        for (int32_t left = ids[k++]; left > 0; left--, k++)
            if (!bsearch(&ids[k], scratch, (size_t)point_count, sizeof *scratch, compare_int32))
                return fail_array(r, conn, "cell %lld (polyhedron): its faces use point %d, which its "
                                  "connectivity does not list", (long long)cell, ids[k]);
    return 0;
}

/* A polyhedron's face stream e[0 .. n), starting at value `at` of the faces array (tools/polyhedron.h
 * checks its layout), and its connectivity points[0 .. point_count). */
static int check_face_stream(vtu_reader *r, const vtu_array *fa, const vtu_array *conn, int64_t cell, const double *e,
                             int64_t n, int64_t at, const double *points, int64_t point_count)
{
    int32_t *ids = malloc(sizeof *ids * (size_t)(n + point_count + 1));
    if (!ids)
        return fail_array(r, fa, "out of memory");
    int64_t bad_at = -1;
    char why[200];
    for (int64_t k = 0; k < n && bad_at < 0; k++) {
        if (e[k] >= -2147483648.0 && e[k] <= 2147483647.0 && e[k] == (double)(int64_t)e[k])
            ids[k] = (int32_t)e[k];
        else
            bad_at = k, snprintf(why, sizeof why, "expected an integer, found %.17g", e[k]);
    }
    int rc = 0;
    if (bad_at >= 0 || tpk_face_stream_check(ids, n, r->point_count, &bad_at, why, sizeof why))
        rc = fail_array(r, fa, "cell %lld (polyhedron): %s (face stream entry %lld, value %lld of the array)",
                        (long long)cell, why, (long long)bad_at, (long long)(at + bad_at));
    else
        rc = check_face_points(r, conn, cell, ids, points, point_count, ids + n);
    free(ids);
    return rc;
}

static int build_mesh(vtu_reader *r, tpk_mesh *out)
{
    if (!r->root_seen)
        return fail_line(r, 0, "expected a <VTKFile> element, found none");
    if (!r->piece_seen)
        return fail_line(r, 0, "expected an UnstructuredGrid with a Piece, found none");
    vtu_array *pts = find_role(r, ROLE_POINTS), *conn = find_role(r, ROLE_CONN), *offs = find_role(r, ROLE_OFFSETS),
              *types = find_role(r, ROLE_TYPES), *faces = find_role(r, ROLE_FACES),
              *foffs = find_role(r, ROLE_FACEOFFSETS);
    if (!pts && r->point_count > 0)
        return fail_line(r, 0, "expected a Points DataArray, found none");
    if (r->cell_count > 0 && (!conn || !offs || !types))
        return fail_line(r, 0, "Cells: expected DataArrays connectivity, offsets and types, found %s missing",
                         !conn ? "connectivity" : !offs ? "offsets" : "types");
    int64_t nc = r->cell_count;
    /* Offsets: increasing, ending at the connectivity's size. */
    int64_t prev = 0;
    for (int64_t c = 0; c < nc; c++) {
        double v = offs->values[c];
        if (!(v >= (double)prev && v <= (double)conn->count))
            return fail_array(r, offs, "cell %lld: expected an offset from %lld to %llu (not decreasing, within "
                              "the connectivity), found %.17g", (long long)c, (long long)prev,
                              (unsigned long long)conn->count, v);
        prev = (int64_t)v;
    }
    if (nc > 0 && (uint64_t)prev != conn->count)
        return fail_array(r, offs, "expected the last offset to be the connectivity size %llu, found %lld",
                          (unsigned long long)conn->count, (long long)prev);
    for (int64_t c = 0; c < nc; c++)
        if (!(types->values[c] >= 0 && types->values[c] <= 255))
            return fail_array(r, types, "cell %lld: expected a VTK cell type 0..255, found %.17g", (long long)c,
                              types->values[c]);
    if (foffs && !faces)
        return fail_array(r, foffs, "expected a faces DataArray with faceoffsets, found none");
    cell_span *span = malloc(sizeof *span * (size_t)(nc ? nc : 1));
    if (!span)
        return fail_line(r, 0, "out of memory");
    int64_t dropped[256] = {0}, reduced[256] = {0};
    int64_t drop_total = 0, reduce_total = 0, kept = 0, conn_size = 0, face_prev = 0;
    int rc = 0;
    for (int64_t c = 0; c < nc && rc == 0; c++) {
        int type = (int)types->values[c];
        int64_t begin = c ? (int64_t)offs->values[c - 1] : 0, face_begin = 0;
        span[c].v = conn->values + begin;
        span[c].n = (int64_t)offs->values[c] - begin;
        tpk_cell_rule rule = tpk_cell_rule_for(type);
        if (rule.kind == TPK_RULE_UNKNOWN) {
            rc = fail_array(r, types, "cell %lld has unsupported cell type %d (%s)", (long long)c, type, rule.name);
            break;
        }
        if (foffs && foffs->values[c] >= 0) {
            double fv = foffs->values[c];
            if (!(fv >= (double)face_prev && fv <= (double)faces->count)) {
                rc = fail_array(r, foffs, "cell %lld: expected a face offset from %lld to %llu, found %.17g",
                                (long long)c, (long long)face_prev, (unsigned long long)faces->count, fv);
                break;
            }
            if (type == TPK_CELL_POLYHEDRON) {
                face_begin = face_prev;
                span[c].v = faces->values + face_prev;
                span[c].n = (int64_t)fv - face_prev;
            }
            face_prev = (int64_t)fv;
        }
        if (type == TPK_CELL_POLYHEDRON) {
            if (!foffs || !(foffs->values[c] >= 0)) {
                rc = fail_array(r, types, "cell %lld is a polyhedron: expected its faces in faces/faceoffsets, "
                                "found none", (long long)c);
                break;
            }
            rc = check_face_stream(r, faces, conn, c, span[c].v, span[c].n, face_begin, conn->values + begin,
                                   (int64_t)offs->values[c] - begin);
        } else if (rule.kind != TPK_RULE_DROP) {
            if ((rule.nodes > 0 && span[c].n != rule.nodes) || (rule.nodes < 0 && span[c].n < -rule.nodes)) {
                rc = fail_array(r, conn, "cell %lld (%s, type %d) has %lld points, expected %s%d", (long long)c,
                                rule.name, type, (long long)span[c].n, rule.nodes < 0 ? "at least " : "",
                                rule.nodes < 0 ? -rule.nodes : rule.nodes);
                break;
            }
        }
        if (type != TPK_CELL_POLYHEDRON)
            for (int64_t j = 0; j < span[c].n; j++)
                if (!(span[c].v[j] >= 0 && span[c].v[j] < (double)r->point_count)) {
                    rc = fail_array(r, conn, "cell %lld uses point id %.17g, but there are only %lld points "
                                    "(0 to %lld)", (long long)c, span[c].v[j], (long long)r->point_count,
                                    (long long)r->point_count - 1);
                    break;
                }
        if (rc)
            break;
        if (rule.kind == TPK_RULE_DROP) {
            dropped[type]++;
            drop_total++;
            continue;
        }
        if (rule.kind == TPK_RULE_REDUCE) {
            reduced[type]++;
            reduce_total++;
        }
        kept++;
        conn_size += rule.kind == TPK_RULE_REDUCE ? rule.out_nodes : span[c].n;
    }
    if (rc) {
        free(span);
        return -1;
    }
    if (drop_total)
        tpk_warn_cell_counts(r->diag, r->name, dropped, drop_total,
                             "dropped cells that are not volumes:");
    if (reduce_total)
        tpk_warn_cell_counts(r->diag, r->name, reduced, reduce_total,
                             "reduced higher-order cells to their corner nodes:");

    out->point_count = r->point_count;
    out->points = malloc(sizeof(double) * 3 * (size_t)(r->point_count ? r->point_count : 1));
    out->cell_count = kept;
    out->cell_types = malloc((size_t)(kept ? kept : 1));
    out->cell_offsets = malloc(sizeof(int64_t) * (size_t)(kept + 1));
    out->cell_conn = malloc(sizeof(int32_t) * (size_t)(conn_size ? conn_size : 1));
    uint8_t *keep = malloc((size_t)(nc ? nc : 1));
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn || !keep) {
        free(keep);
        free(span);
        return fail_line(r, 0, "out of memory");
    }
    if (r->point_count)
        memcpy(out->points, pts->values, sizeof(double) * 3 * (size_t)r->point_count);
    int64_t k = 0, o = 0;
    out->cell_offsets[0] = 0;
    for (int64_t c = 0; c < nc; c++) {
        tpk_cell_rule rule = tpk_cell_rule_for((int)types->values[c]);
        keep[c] = rule.kind != TPK_RULE_DROP;
        if (!keep[c])
            continue;
        int64_t n = rule.kind == TPK_RULE_REDUCE ? rule.out_nodes : span[c].n;
        for (int64_t j = 0; j < n; j++)
            out->cell_conn[o++] = (int32_t)span[c].v[j];
        out->cell_types[k] = rule.out_type;
        out->cell_offsets[++k] = o;
    }
    free(span);
    for (int i = 0; i < r->array_count; i++) {
        vtu_array *a = &r->arrays[i];
        if (a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD)
            continue;
        int64_t tuples = a->role == ROLE_POINT_FIELD ? r->point_count : kept;
        float *v = malloc(sizeof(float) * (size_t)(tuples ? tuples : 1) * (size_t)a->components);
        if (!v) {
            free(keep);
            return fail_array(r, a, "out of memory");
        }
        if (a->role == ROLE_POINT_FIELD) {
            for (uint64_t j = 0; j < a->count; j++)
                v[j] = (float)a->values[j];
        } else {
            int64_t t = 0;
            for (int64_t c = 0; c < nc; c++) {
                if (!keep[c])
                    continue;
                for (int j = 0; j < a->components; j++)
                    v[t * a->components + j] = (float)a->values[c * a->components + j];
                t++;
            }
        }
        if (tpk_mesh_add_field(out, a->name, a->role == ROLE_POINT_FIELD ? TPK_ASSOC_POINT : TPK_ASSOC_TET,
                               a->components, 1, v)) {
            free(v);
            free(keep);
            return fail_array(r, a, "out of memory");
        }
    }
    free(keep);
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "vtu");
    if (tpk_mesh_take_face_streams(out)) /* the streams went into cell_conn above */
        return fail_line(r, 0, "out of memory");
    return 0;
}

/* ---- Entry points ------------------------------------------------------------------------------- */

static void reader_free(vtu_reader *r)
{
    for (int i = 0; i < r->array_count; i++)
        free(r->arrays[i].values);
    free(r->arrays);
    free(r->cur.values);
    free(r->text);
}

int tpk_import_vtu_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    if (!name)
        name = "(input)";
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name);
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    vtu_reader r;
    memset(&r, 0, sizeof r);
    r.name = name;
    r.data = (const unsigned char *)data;
    r.size = data ? size : 0;
    r.diag = diag;
    r.header_size = 4;
    int rc = parse_xml(&r);
    if (rc == 0)
        rc = decode_appended(&r);
    if (rc == 0)
        rc = build_mesh(&r, out);
    reader_free(&r);
    if (rc != 0)
        tpk_mesh_free(out);
    return rc;
}

/* tpk_parse_fn: the VTU reader has no use for `mapped` (it reads appended blocks by offset). */
static int parse_vtu(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out, tpk_diag *diag)
{
    (void)mapped;
    return tpk_import_vtu_memory(name, data, size, out, diag);
}

int tpk_import_vtu(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, parse_vtu, out, diag);
}
