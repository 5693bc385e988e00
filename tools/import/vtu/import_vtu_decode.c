/* VTU importer: DataArray contents. Ascii numbers, base64 ("binary") and raw or base64 appended data,
 * each with a UInt32 or UInt64 header, optionally as zlib-compressed blocks. Every size read from the
 * file is checked against the bytes that can hold it before allocating. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_vtu_internal.h"
#include "base/parallel.h"
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
    if (vtu_src_read(s, b, r->header_size))
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
    if (n > vtu_src_left(s)) {
        vtu_fail_array(r, a, "data truncated: the header says %llu bytes, at most %llu are left",
                       (unsigned long long)n, (unsigned long long)vtu_src_left(s));
        return NULL;
    }
    unsigned char *buf = tpk_alloc_large(n ? (size_t)n : 1); /* huge-page advised when large */
    if (!buf) {
        vtu_fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)n);
        return NULL;
    }
    if (vtu_src_read(s, buf, (size_t)n)) {
        free(buf);
        vtu_fail_array(r, a, "expected %llu data bytes, %s", (unsigned long long)n, s->error);
        return NULL;
    }
    *nbytes = n;
    return buf;
}

static int read_block_counts(vtu_reader *r, const vtu_array *a, bsrc *s, uint64_t expected, uint64_t want,
                             zlib_blocks *z)
{
    uint64_t last_size = 0;
    if (read_header_word(r, a, s, &z->count, "block count") || read_header_word(r, a, s, &z->size, "block size") ||
        read_header_word(r, a, s, &last_size, "last block size"))
        return -1;
    if (z->count > vtu_src_left(s) / r->header_size)
        return vtu_fail_array(r, a, "expected at most %llu compressed blocks in the data left, found a header "
                              "saying %llu", (unsigned long long)(vtu_src_left(s) / r->header_size),
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
        if (z->csizes[b] > vtu_src_left(s) || (usize > 64 && (usize - 64) / ZLIB_MAX_RATIO > z->csizes[b]))
            return vtu_fail_array(r, a, "zlib block %llu of %llu: expected a compressed size that can hold %llu "
                                  "bytes within the data left (%llu), found %llu", (unsigned long long)b + 1,
                                  (unsigned long long)z->count, (unsigned long long)usize,
                                  (unsigned long long)vtu_src_left(s), (unsigned long long)z->csizes[b]);
        csum += z->csizes[b];
        if (z->csizes[b] > z->cmax)
            z->cmax = z->csizes[b];
    }
    if (csum > vtu_src_left(s))
        return vtu_fail_array(r, a, "data truncated: the compressed blocks take %llu bytes, at most %llu are left",
                              (unsigned long long)csum, (unsigned long long)vtu_src_left(s));
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
    unsigned char *out = NULL;
    int rc = read_block_counts(r, a, s, expected, want, &z);
    if (rc == 0)
        rc = read_block_sizes(r, a, s, &z);
    if (rc == 0) {
        out = tpk_alloc_large(z.total ? (size_t)z.total : 1); /* huge-page advised when large */
        rc = out ? vtu_inflate_blocks(r, a, s, &z, out)
                 : vtu_fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)z.total);
    }
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

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char first;
    memcpy(&first, &one, 1);
    return first == 1;
}

/* value_at for every value of a host-order array, one loop per type (the per-value switch and byte
 * assembly cost more than the rest of decoding). */
#define WIDEN(ctype)                                                                                                    \
    for (uint64_t i = 0; i < n; i++) {                                                                                \
        ctype v;                                                                                                      \
        memcpy(&v, bytes + i * sizeof v, sizeof v);                                                                   \
        out[i] = (double)v;                                                                                           \
    }                                                                                                                 \
    break
static void widen_native(const unsigned char *bytes, uint64_t n, vtu_type t, double *out)
{
    switch (t) {
    case T_I8: WIDEN(int8_t);
    case T_U8: WIDEN(uint8_t);
    case T_I16: WIDEN(int16_t);
    case T_U16: WIDEN(uint16_t);
    case T_I32: WIDEN(int32_t);
    case T_U32: WIDEN(uint32_t);
    case T_I64: WIDEN(int64_t);
    case T_U64: WIDEN(uint64_t);
    case T_F32: WIDEN(float);
    case T_F64: WIDEN(double);
    case T_NONE: break;
    }
}
#undef WIDEN

typedef struct widen_job {
    const unsigned char *bytes;
    vtu_type type;
    size_t size; /* bytes per value */
    double *out;
} widen_job;

static void widen_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const widen_job *job = ctx;
    (void)worker;
    widen_native(job->bytes + job->size * (size_t)begin, (uint64_t)(end - begin), job->type, job->out + begin);
}

/* widen_native on all cores for large arrays; in place too (out == bytes, 8-byte values): each range
 * reads and writes only its own values. */
static void widen_all(const unsigned char *bytes, uint64_t n, vtu_type t, size_t tsize, double *out)
{
    int threads = tpk_threads_for((int64_t)n, tpk_thread_count(0), (int64_t)1 << 20);
    if (threads < 2) {
        widen_native(bytes, n, t, out);
        return;
    }
    widen_job job = {bytes, t, tsize, out};
    tpk_parallel_for((int64_t)n, threads, widen_range, &job);
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
    if (tsize == sizeof(double) && !r->big_endian && host_is_little_endian()) {
        /* Widened where they lie: each value is read before its own 8 bytes are written, and a fresh
         * array as large as the data (points, and meshio's Int64 connectivity) costs its page faults. */
        widen_all(bytes, n, a->type, tsize, (double *)(void *)bytes);
        a->values = (double *)(void *)bytes;
        a->count = n;
        return 0;
    }
    a->values = tpk_alloc_large(sizeof(double) * (size_t)(n ? n : 1));
    if (!a->values) {
        free(bytes);
        return vtu_fail_array(r, a, "out of memory for %llu values", (unsigned long long)n);
    }
    if (!r->big_endian && host_is_little_endian())
        widen_all(bytes, n, a->type, tsize, a->values);
    else
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
