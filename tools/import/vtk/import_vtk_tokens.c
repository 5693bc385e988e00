/* VTK legacy importer: tokens and value blocks. Keyword arguments (counts, data types, names), the
 * room check before any allocation, and ASCII or big-endian binary blocks of reals and integers. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "import_vtk_internal.h"
#include "base/parallel.h"
#include "base/text_numbers.h"
#include "base/text_scan.h"

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

static const unsigned type_size[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8}; /* bit: packed, see vtk_bytes_for */

/* ---- Small helpers ------------------------------------------------------------------------------ */

int vtk_fail_kw(vtk_reader *r, const char *fmt, ...)
{
    char text[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    return tpk_scan_fail_at(&r->s, r->kw_pos, r->kw_line, "%s", text);
}

const char *vtk_quote(const char *tok, size_t len, char *buf, size_t cap)
{
    return tpk_scan_quote(tok, len, buf, cap);
}

/* Next token on the keyword's line, or an error saying what was expected after which keyword. */
int vtk_arg_token(vtk_reader *r, const char *keyword, const char *what, const char **tok, size_t *len)
{
    *len = tpk_scan_line_token(&r->s, tok);
    if (!*len)
        return tpk_scan_fail(&r->s, "%s: expected %s, found end of %s", keyword, what,
                             r->s.pos >= r->s.size ? "file" : "line");
    return 0;
}

int vtk_arg_count(vtk_reader *r, const char *keyword, const char *what, int64_t *out)
{
    const char *tok;
    size_t len;
    if (vtk_arg_token(r, keyword, what, &tok, &len))
        return -1;
    char q[64];
    if (tpk_parse_int64(tok, len, out) != 0)
        return tpk_scan_fail(&r->s, "%s: expected %s, found '%s'", keyword, what, vtk_quote(tok, len, q, sizeof q));
    if (*out < 0)
        return tpk_scan_fail(&r->s, "%s: expected %s (>= 0), found %lld", keyword, what, (long long)*out);
    return 0;
}

int vtk_arg_type(vtk_reader *r, const char *keyword, vtk_type *out)
{
    const char *tok;
    size_t len;
    if (vtk_arg_token(r, keyword, "a data type (float, double, int, ...)", &tok, &len))
        return -1;
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++) {
        if (tpk_token_is(tok, len, type_names[i].name)) {
            *out = type_names[i].type;
            return 0;
        }
    }
    char q[64];
    return tpk_scan_fail(&r->s, "%s: expected a data type (float, double, int, unsigned_char, vtktypeint64, ...), "
                         "found '%s'", keyword, vtk_quote(tok, len, q, sizeof q));
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
void vtk_decode_name(const char *tok, size_t len, char *name)
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

int vtk_arg_name(vtk_reader *r, const char *keyword, char *name)
{
    const char *tok;
    size_t len;
    if (vtk_arg_token(r, keyword, "a name", &tok, &len))
        return -1;
    vtk_decode_name(tok, len, name);
    return 0;
}

/* Peek: is the next token `word`? Leaves the position unchanged when it is not. */
int vtk_next_is(vtk_reader *r, const char *word)
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

uint64_t vtk_bytes_for(vtk_type type, uint64_t count)
{
    return type == VT_BIT ? (count + 7) / 8 : count * type_size[type];
}

/* Before allocating for `count` values: do they fit in what is left of the file? Binary: exactly;
 * ASCII: every value takes at least one character and a separator. */
int vtk_check_room(vtk_reader *r, vtk_type type, uint64_t count, const char *block)
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
        return vtk_fail_kw(r, "%s: %llu values cannot fit in the %zu bytes left in the file "
                           "(wrong count or truncated file)", block, (unsigned long long)count, left);
    return 0;
}

int vtk_ascii_value_error(vtk_reader *r, const char *tok, size_t len, const char *block, uint64_t i,
                          uint64_t count)
{
    char q[64];
    if (!len)
        return tpk_scan_fail(&r->s, "%s block truncated: expected %llu values, found %llu before end of file",
                             block, (unsigned long long)count, (unsigned long long)i);
    return tpk_scan_fail(&r->s, "%s: expected a number (value %llu of %llu), found '%s'", block,
                         (unsigned long long)i + 1, (unsigned long long)count, vtk_quote(tok, len, q, sizeof q));
}

/* Binary blocks are byte-swapped and converted on all threads (tpk_thread_count(0): convert's --threads),
 * in chunks (tpk_parallel_chunks): every value lands where the serial loop put it, whatever the thread
 * count. */
typedef struct binary_job {
    const unsigned char *p;
    vtk_type type;
    double *d64;
    float *f32;
    int64_t *i64;
} binary_job;

int vtk_threads_for(uint64_t count)
{
    return tpk_threads_for((int64_t)count, tpk_thread_count(0), (int64_t)1 << 16);
}

static void reals_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const binary_job *j = ctx;
    const unsigned char *p = j->p;
    (void)worker;
    if (j->type == VT_F64 && j->d64) {
        for (int64_t i = begin; i < end; i++)
            j->d64[i] = be_real(p, VT_F64, (uint64_t)i);
    } else if (j->type == VT_F32 && j->f32) {
        for (int64_t i = begin; i < end; i++)
            j->f32[i] = (float)be_real(p, VT_F32, (uint64_t)i);
    } else {
        for (int64_t i = begin; i < end; i++) {
            double v = be_real(p, j->type, (uint64_t)i);
            if (j->d64)
                j->d64[i] = v;
            else
                j->f32[i] = (float)v;
        }
    }
}

/* `count` values of `type` into doubles (d64) or floats (f32); room already checked. */
int vtk_read_reals(vtk_reader *r, vtk_type type, uint64_t count, double *d64, float *f32, const char *block)
{
    if (r->binary) {
        binary_job job = {r->s.data + r->s.pos, type, d64, f32, NULL};
        tpk_parallel_chunks((int64_t)count, vtk_threads_for(count), (int64_t)1 << 16, reals_range, &job);
        r->s.pos += vtk_bytes_for(type, count);
        return 0;
    }
    /* ASCII: on all threads where the block reads cleanly, else token by token for the message */
    if (tpk_scan_numbers(&r->s, count, d64 ? TPK_NUMBER_F64 : TPK_NUMBER_F32, d64 ? (void *)d64 : (void *)f32, 0) == 0)
        return 0;
    for (uint64_t i = 0; i < count; i++) {
        const char *tok;
        size_t len = tpk_scan_token(&r->s, &tok);
        double v;
        if (!len || tpk_parse_double(tok, len, &v) != 0)
            return vtk_ascii_value_error(r, tok, len, block, i, count);
        if (d64)
            d64[i] = v;
        else
            f32[i] = (float)v;
    }
    return 0;
}

int vtk_is_integer_type(vtk_type t)
{
    return t != VT_F32 && t != VT_F64;
}

static void ints_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const binary_job *j = ctx;
    const unsigned char *p = j->p;
    int64_t *dst = j->i64;
    (void)worker;
    for (int64_t i = begin; i < end; i++) {
        switch (j->type) {
        case VT_I32: dst[i] = (int32_t)be32(p + 4 * i); break;
        case VT_I64: dst[i] = (int64_t)be64(p + 8 * i); break;
        case VT_U64: {
            uint64_t u = be64(p + 8 * i);
            dst[i] = u > INT64_MAX ? -1 : (int64_t)u;
            break;
        }
        default: dst[i] = (int64_t)be_real(p, j->type, (uint64_t)i); break;
        }
    }
}

/* `count` integers into int64 (offsets, cell types); room already checked. */
int vtk_read_ints(vtk_reader *r, vtk_type type, uint64_t count, int64_t *dst, const char *block)
{
    if (!vtk_is_integer_type(type))
        return tpk_scan_fail(&r->s, "%s: expected an integer data type, found a floating-point one", block);
    if (r->binary) {
        binary_job job = {r->s.data + r->s.pos, type, NULL, NULL, dst};
        tpk_parallel_chunks((int64_t)count, vtk_threads_for(count), (int64_t)1 << 16, ints_range, &job);
        r->s.pos += vtk_bytes_for(type, count);
        return 0;
    }
    if (tpk_scan_numbers(&r->s, count, TPK_NUMBER_I64, dst, 0) == 0)
        return 0;
    for (uint64_t i = 0; i < count; i++) {
        const char *tok;
        size_t len = tpk_scan_token(&r->s, &tok);
        if (!len || tpk_parse_int64(tok, len, &dst[i]) != 0) {
            char q[64];
            if (!len)
                return vtk_ascii_value_error(r, tok, len, block, i, count);
            return tpk_scan_fail(&r->s, "%s: expected an integer (value %llu of %llu), found '%s'", block,
                                 (unsigned long long)i + 1, (unsigned long long)count,
                                 vtk_quote(tok, len, q, sizeof q));
        }
    }
    return 0;
}
