/* VTU importer: DataArray contents. Ascii numbers, base64 ("binary") and raw or base64 appended data,
 * each with a UInt32 or UInt64 header, optionally as zlib-compressed blocks. Every size read from the
 * file is checked against the bytes that can hold it before allocating. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "import_vtu_internal.h"
#include "base/text_scan.h"

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

const char *vtu_type_name(vtu_type t)
{
    for (size_t i = 0; i < sizeof type_table / sizeof type_table[0]; i++)
        if (type_table[i].type == t)
            return type_table[i].name;
    return "?";
}

vtu_type vtu_type_from_name(const char *name)
{
    vtu_type type = T_NONE;
    for (size_t i = 0; name && i < sizeof type_table / sizeof type_table[0]; i++)
        if (!strcmp(name, type_table[i].name))
            type = type_table[i].type;
    return type;
}

/* ---- Byte sources: raw bytes, or base64 text decoded as it is read ------------------------------ */

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

int vtu_is_space(unsigned char c)
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
            if (vtu_is_space(c))
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
        return vtu_fail_array(r, a, "expected the header's %s (%s), %s", what,
                              r->header_size == 8 ? "UInt64" : "UInt32", s->error);
    *out = get_uint(b, r->header_size, r->big_endian);
    return 0;
}

/* Uncompressed data: a byte count, then the bytes. */
static unsigned char *read_plain(vtu_reader *r, const vtu_array *a, bsrc *s, uint64_t expected, uint64_t want,
                                 uint64_t *nbytes)
{
    uint64_t n = 0;
    if (read_header_word(r, a, s, &n, "byte count"))
        return NULL;
    if (want != UINT64_MAX && n != want) {
        vtu_fail_array(r, a, "expected %llu bytes (%llu %s values), found a header saying %llu", (unsigned long long)want,
                       (unsigned long long)expected, vtu_type_name(a->type), (unsigned long long)n);
        return NULL;
    }
    if (n > src_left(s)) {
        vtu_fail_array(r, a, "data truncated: the header says %llu bytes, at most %llu are left",
                       (unsigned long long)n, (unsigned long long)src_left(s));
        return NULL;
    }
    unsigned char *buf = malloc(n ? (size_t)n : 1);
    if (!buf) {
        vtu_fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)n);
        return NULL;
    }
    if (src_read(s, buf, (size_t)n)) {
        free(buf);
        vtu_fail_array(r, a, "expected %llu data bytes, %s", (unsigned long long)n, s->error);
        return NULL;
    }
    *nbytes = n;
    return buf;
}

/* The zlib header of compressed data: block count, block size, last block size, then each block's
 * compressed size. */
typedef struct zlib_blocks {
    uint64_t count, size, last, total; /* last: the last block's size (never 0); total: all bytes */
    uint64_t *csizes, cmax;            /* compressed sizes, and the largest */
} zlib_blocks;

static int read_block_counts(vtu_reader *r, const vtu_array *a, bsrc *s, uint64_t expected, uint64_t want,
                             zlib_blocks *z)
{
    uint64_t last_size = 0;
    if (read_header_word(r, a, s, &z->count, "block count") || read_header_word(r, a, s, &z->size, "block size") ||
        read_header_word(r, a, s, &last_size, "last block size"))
        return -1;
    if (z->count > src_left(s) / r->header_size)
        return vtu_fail_array(r, a, "expected at most %llu compressed blocks in the data left, found a header "
                              "saying %llu", (unsigned long long)(src_left(s) / r->header_size),
                              (unsigned long long)z->count);
    if (last_size > z->size)
        return vtu_fail_array(r, a, "expected the last block size (%llu) <= the block size (%llu)",
                              (unsigned long long)last_size, (unsigned long long)z->size);
    z->last = last_size ? last_size : z->size;
    z->total = 0;
    if (z->count) {
        if (z->size && z->count - 1 > (UINT64_MAX - z->last) / z->size)
            return vtu_fail_array(r, a, "%llu blocks of %llu bytes: too large for any file",
                                  (unsigned long long)z->count, (unsigned long long)z->size);
        z->total = (z->count - 1) * z->size + z->last;
    }
    if (want != UINT64_MAX && z->total != want)
        return vtu_fail_array(r, a, "expected %llu bytes (%llu %s values), found a compression header saying %llu",
                              (unsigned long long)want, (unsigned long long)expected, vtu_type_name(a->type),
                              (unsigned long long)z->total);
    return 0;
}

static int read_block_sizes(vtu_reader *r, const vtu_array *a, bsrc *s, zlib_blocks *z)
{
    z->csizes = malloc(sizeof(uint64_t) * (size_t)(z->count ? z->count : 1));
    if (!z->csizes)
        return vtu_fail_array(r, a, "out of memory");
    uint64_t csum = 0;
    z->cmax = 0;
    for (uint64_t b = 0; b < z->count; b++) {
        if (read_header_word(r, a, s, &z->csizes[b], "compressed block size"))
            return -1;
        uint64_t usize = b + 1 == z->count ? z->last : z->size;
        if (z->csizes[b] > src_left(s) || (usize > 64 && (usize - 64) / ZLIB_MAX_RATIO > z->csizes[b]))
            return vtu_fail_array(r, a, "zlib block %llu of %llu: expected a compressed size that can hold %llu "
                                  "bytes within the data left (%llu), found %llu", (unsigned long long)b + 1,
                                  (unsigned long long)z->count, (unsigned long long)usize,
                                  (unsigned long long)src_left(s), (unsigned long long)z->csizes[b]);
        csum += z->csizes[b];
        if (z->csizes[b] > z->cmax)
            z->cmax = z->csizes[b];
    }
    if (csum > src_left(s))
        return vtu_fail_array(r, a, "data truncated: the compressed blocks take %llu bytes, at most %llu are left",
                              (unsigned long long)csum, (unsigned long long)src_left(s));
    return 0;
}

/* Inflates every block into out (z->total bytes); tmp holds z->cmax bytes. */
static int inflate_blocks(vtu_reader *r, const vtu_array *a, bsrc *s, const zlib_blocks *z, unsigned char *out,
                          unsigned char *tmp)
{
    uint64_t o = 0;
    for (uint64_t b = 0; b < z->count; b++) {
        uint64_t usize = b + 1 == z->count ? z->last : z->size;
        if (src_read(s, tmp, (size_t)z->csizes[b]))
            return vtu_fail_array(r, a, "zlib block %llu of %llu: expected %llu compressed bytes, %s",
                                  (unsigned long long)b + 1, (unsigned long long)z->count,
                                  (unsigned long long)z->csizes[b], s->error);
        uLongf dlen = (uLongf)usize;
        int zrc = uncompress(out + o, &dlen, tmp, (uLong)z->csizes[b]);
        if (zrc != Z_OK)
            return vtu_fail_array(r, a, "zlib block %llu of %llu does not decompress: %s", (unsigned long long)b + 1,
                                  (unsigned long long)z->count,
                                  zrc == Z_BUF_ERROR ? "it is incomplete or holds more than the header's size"
                                                     : zError(zrc));
        if (dlen != usize)
            return vtu_fail_array(r, a, "zlib block %llu of %llu: expected %llu bytes, found %llu",
                                  (unsigned long long)b + 1, (unsigned long long)z->count, (unsigned long long)usize,
                                  (unsigned long long)dlen);
        o += usize;
    }
    return 0;
}

/* The array's bytes (header and data, compressed or not); `expected` values when known (else
 * UINT64_MAX). Returns a malloc'ed buffer of *nbytes bytes (at least 1 allocated) or NULL. */
static unsigned char *read_binary(vtu_reader *r, const vtu_array *a, bsrc *s, uint64_t expected, uint64_t *nbytes)
{
    uint64_t want = expected == UINT64_MAX ? UINT64_MAX : expected * type_size(a->type);
    if (!r->compressed)
        return read_plain(r, a, s, expected, want, nbytes);
    zlib_blocks z = {0};
    unsigned char *out = NULL, *tmp = NULL;
    int rc = read_block_counts(r, a, s, expected, want, &z);
    if (rc == 0)
        rc = read_block_sizes(r, a, s, &z);
    if (rc == 0) {
        out = malloc(z.total ? (size_t)z.total : 1);
        tmp = malloc(z.cmax ? (size_t)z.cmax : 1);
        rc = out && tmp ? inflate_blocks(r, a, s, &z, out, tmp)
                        : vtu_fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)z.total);
    }
    free(tmp);
    free(z.csizes);
    if (rc) {
        free(out);
        return NULL;
    }
    *nbytes = z.total;
    return out;
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

/* The number of values expected in an array of this role, or UINT64_MAX when not known yet. Read
 * leniently (tetpack check), field arrays take any length; vtu_build_mesh records a wrong one. */
static uint64_t expected_count(const vtu_reader *r, const vtu_array *a)
{
    if (r->diag && r->diag->lenient_fields && (a->role == ROLE_POINT_FIELD || a->role == ROLE_CELL_FIELD))
        return UINT64_MAX;
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

int vtu_decode_binary(vtu_reader *r, vtu_array *a, bsrc *s)
{
    uint64_t expected = expected_count(r, a), nbytes = 0;
    unsigned char *bytes = read_binary(r, a, s, expected, &nbytes);
    if (!bytes)
        return -1;
    unsigned tsize = type_size(a->type);
    if (nbytes % tsize) {
        free(bytes);
        return vtu_fail_array(r, a, "expected a whole number of %s values, found %llu bytes", vtu_type_name(a->type),
                              (unsigned long long)nbytes);
    }
    uint64_t n = nbytes / tsize;
    a->values = malloc(sizeof(double) * (size_t)(n ? n : 1));
    if (!a->values) {
        free(bytes);
        return vtu_fail_array(r, a, "out of memory for %llu values", (unsigned long long)n);
    }
    for (uint64_t i = 0; i < n; i++)
        a->values[i] = value_at(bytes + i * tsize, a->type, r->big_endian);
    a->count = n;
    free(bytes);
    return 0;
}

int vtu_is_int_type(vtu_type t)
{
    return t != T_F32 && t != T_F64;
}

int vtu_decode_ascii(vtu_reader *r, vtu_array *a, const char *text, size_t len)
{
    uint64_t n = 0;
    for (size_t i = 0; i < len;) {
        while (i < len && vtu_is_space((unsigned char)text[i]))
            i++;
        if (i >= len)
            break;
        n++;
        while (i < len && !vtu_is_space((unsigned char)text[i]))
            i++;
    }
    uint64_t expected = expected_count(r, a);
    if (expected != UINT64_MAX && n != expected)
        return vtu_fail_array(r, a, "expected %llu values, found %llu", (unsigned long long)expected, (unsigned long long)n);
    a->values = malloc(sizeof(double) * (size_t)(n ? n : 1));
    if (!a->values)
        return vtu_fail_array(r, a, "out of memory for %llu values", (unsigned long long)n);
    uint64_t k = 0;
    for (size_t i = 0; i < len;) {
        while (i < len && vtu_is_space((unsigned char)text[i]))
            i++;
        if (i >= len)
            break;
        size_t b = i;
        while (i < len && !vtu_is_space((unsigned char)text[i]))
            i++;
        int64_t iv;
        double dv;
        int bad;
        if (vtu_is_int_type(a->type)) {
            bad = tpk_parse_int64(text + b, i - b, &iv) != 0;
            dv = (double)iv;
        } else {
            bad = tpk_parse_double(text + b, i - b, &dv) != 0;
        }
        if (bad) {
            char q[64];
            return vtu_fail_array(r, a, "expected %s (value %llu of %llu), found '%s'",
                                  vtu_is_int_type(a->type) ? "an integer" : "a number", (unsigned long long)k + 1,
                                  (unsigned long long)n, tpk_scan_quote(text + b, i - b, q, sizeof q));
        }
        a->values[k++] = dv;
    }
    a->count = n;
    return 0;
}

/* ---- Appended data ------------------------------------------------------------------------------ */

int vtu_decode_appended(vtu_reader *r)
{
    for (int i = 0; i < r->array_count; i++) {
        vtu_array *a = &r->arrays[i];
        if (a->format != 2)
            continue;
        if (!r->app_start)
            return vtu_fail_array(r, a, "expected an AppendedData section for format=\"appended\", found none");
        bsrc s = {.p = r->data + r->app_start, .len = r->app_end - r->app_start, .b64 = r->appended_base64,
                  .in_file = 1, .base = r->app_start};
        if (r->appended_base64) {
            const unsigned char *lt = memchr(s.p, '<', s.len);
            if (lt)
                s.len = (size_t)(lt - s.p);
        }
        if (a->offset > s.len)
            return vtu_fail_array(r, a, "expected an offset within the %zu bytes of appended data, found %llu", s.len,
                                  (unsigned long long)a->offset);
        s.pos = (size_t)a->offset;
        if (vtu_decode_binary(r, a, &s))
            return -1;
    }
    return 0;
}
