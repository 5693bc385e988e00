/* Gmsh importer, lowest layer: the numbers of a .msh file (ASCII, or little-endian binary after
 * $MeshFormat says so), row counts checked against the bytes left, and section ends. Called by every
 * other import_gmsh*.c file; calls none of them. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "import_gmsh_internal.h"
#include "base/text_scan.h"

size_t gmsh_bytes_left(const gmsh_reader *r)
{
    return r->s.size - r->s.pos;
}

/* Binary data: `n` bytes at the current position, or the message "expected <what>". */
int gmsh_bin_bytes(gmsh_reader *r, void *dst, size_t n, const char *what)
{
    r->s.tok_pos = r->s.pos;
    r->s.tok_line = r->s.line;
    if (gmsh_bytes_left(r) < n)
        return tpk_scan_fail(&r->s, "expected %s (%zu bytes), found %zu bytes before the end of the file", what,
                             n, gmsh_bytes_left(r));
    memcpy(dst, r->s.data + r->s.pos, n);
    r->s.pos += n;
    return 0;
}

/* An integer: ASCII, or in binary files (width 4: int, 8: size_t) a binary one; width 0: ASCII always. */
int gmsh_num(gmsh_reader *r, int64_t *v, const char *what, int width)
{
    if (!r->binary || width == 0)
        return tpk_scan_int64(&r->s, v, what);
    if (width == 4) {
        int32_t x = 0;
        if (gmsh_bin_bytes(r, &x, 4, what))
            return -1;
        *v = x;
        return 0;
    }
    uint64_t x = 0;
    if (gmsh_bin_bytes(r, &x, 8, what))
        return -1;
    if (x > (uint64_t)INT64_MAX)
        return tpk_scan_fail(&r->s, "expected %s, found %llu", what, (unsigned long long)x);
    *v = (int64_t)x;
    return 0;
}

int gmsh_real(gmsh_reader *r, double *v, const char *what)
{
    if (!r->binary)
        return tpk_scan_double(&r->s, v, what);
    return gmsh_bin_bytes(r, v, 8, what);
}

/* Binary data starts after the end of the current line. */
int gmsh_bin_start(gmsh_reader *r, const char *after)
{
    return r->binary ? tpk_scan_end_line(&r->s, after) : 0;
}

/* A count of rows of at least `values` numbers each, checked against the bytes left (each number takes
 * a character and a separator), so absurd counts fail before anything is allocated. */
int gmsh_read_count(gmsh_reader *r, const char *what, int values, int64_t *n, int width)
{
    char w[96];
    snprintf(w, sizeof w, "the number of %s", what);
    if (gmsh_num(r, n, w, width))
        return -1;
    size_t left = gmsh_bytes_left(r);
    if (*n < 0)
        return tpk_scan_fail(&r->s, "expected the number of %s (0 or more), found %lld", what, (long long)*n);
    if ((uint64_t)*n > left / (2 * (uint64_t)values) + 1)
        return tpk_scan_fail(&r->s, "%lld %s cannot fit in the %zu bytes left (wrong count or truncated file)",
                             (long long)*n, what, left);
    if (*n > INT32_MAX)
        return tpk_scan_fail(&r->s, "%lld %s: more than 2^31-1", (long long)*n, what);
    return 0;
}

/* The closing `$EndName` of a section. */
int gmsh_expect_end(gmsh_reader *r, const char *end)
{
    const char *tok;
    char q[64];
    size_t len = tpk_scan_token(&r->s, &tok);
    if (len == strlen(end) && !memcmp(tok, end, len))
        return 0;
    if (!len)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected '%s', found end of file", end);
    return tpk_scan_fail(&r->s, "expected '%s', found '%s'", end, tpk_scan_quote(tok, len, q, sizeof q));
}

/* Skip a section up to the line starting with `$End` + name (name: the section token without '$'). */
int gmsh_skip_section(gmsh_reader *r, const char *tok, size_t len)
{
    char end[80], q[64];
    if (len > 60)
        return tpk_scan_fail(&r->s, "expected a section name, found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    snprintf(end, sizeof end, "$End%.*s", (int)len - 1, tok + 1);
    size_t elen = strlen(end);
    const unsigned char *d = r->s.data;
    size_t p = r->s.pos;
    int64_t line = r->s.line;
    while (p < r->s.size) {
        if (d[p] == '\n') {
            line++;
            p++;
            continue;
        }
        /* at a line start or after the section token */
        size_t q0 = p;
        while (q0 < r->s.size && (d[q0] == ' ' || d[q0] == '\t' || d[q0] == '\r'))
            q0++;
        if (r->s.size - q0 >= elen && !memcmp(d + q0, end, elen) &&
            (r->s.size - q0 == elen || d[q0 + elen] <= ' ')) {
            r->s.pos = q0 + elen;
            r->s.line = line;
            return 0;
        }
        const unsigned char *nl = memchr(d + p, '\n', r->s.size - p);
        p = nl ? (size_t)(nl - d) : r->s.size;
    }
    return tpk_scan_fail(&r->s, "expected '%s' closing '%s', found end of file", end,
                         tpk_scan_quote(tok, len, q, sizeof q));
}
