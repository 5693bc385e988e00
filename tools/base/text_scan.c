/* Bounded tokenizer and number scanner for the text importers: every read is checked against the
 * buffer size, numbers are parsed without heap allocations, and messages carry file and place. */
#include "text_scan.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "parallel.h"

void tpk_scan_init(tpk_scan *s, const char *name, const void *data, size_t size, tpk_diag *diag)
{
    memset(s, 0, sizeof *s);
    s->name = name ? name : "(input)";
    s->data = data;
    s->size = data ? size : 0;
    s->line = 1;
    s->tok_line = 1;
    s->diag = diag;
}

static int vfail_at(tpk_scan *s, size_t pos, int64_t line, const char *fmt, va_list ap)
{
    char text[900];
    vsnprintf(text, sizeof text, fmt, ap);
    if (s->byte_places)
        return tpk_diag_fail(s->diag, "%s: byte %zu: %s", s->name, pos, text);
    return tpk_diag_fail(s->diag, "%s:%lld: %s", s->name, (long long)line, text);
}

int tpk_scan_fail(tpk_scan *s, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail_at(s, s->tok_pos, s->tok_line, fmt, ap);
    va_end(ap);
    return -1;
}

int tpk_scan_fail_at(tpk_scan *s, size_t pos, int64_t line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail_at(s, pos, line, fmt, ap);
    va_end(ap);
    return -1;
}

static inline int is_space(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

static inline int is_blank(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

void tpk_scan_skip_space(tpk_scan *s)
{
    const unsigned char *d = s->data;
    size_t p = s->pos, n = s->size;
    for (;;) {
        while (p < n && is_space(d[p])) {
            if (d[p] == '\n')
                s->line++;
            p++;
        }
        if (s->hash_comments && p < n && d[p] == '#') {
            while (p < n && d[p] != '\n')
                p++;
            continue;
        }
        break;
    }
    s->pos = p;
}

void tpk_scan_skip_blank(tpk_scan *s)
{
    const unsigned char *d = s->data;
    size_t p = s->pos, n = s->size;
    while (p < n && is_blank(d[p]))
        p++;
    if (s->hash_comments && p < n && d[p] == '#')
        while (p < n && d[p] != '\n')
            p++;
    s->pos = p;
}

static size_t take_token(tpk_scan *s, const char **tok)
{
    const unsigned char *d = s->data;
    size_t p = s->pos, n = s->size;
    s->tok_pos = p;
    s->tok_line = s->line;
    while (p < n && !is_space(d[p]) && !(s->hash_comments && d[p] == '#'))
        p++;
    *tok = (const char *)d + s->pos;
    size_t len = p - s->pos;
    s->pos = p;
    return len;
}

size_t tpk_scan_token(tpk_scan *s, const char **tok)
{
    tpk_scan_skip_space(s);
    return take_token(s, tok);
}

size_t tpk_scan_line_token(tpk_scan *s, const char **tok)
{
    tpk_scan_skip_blank(s);
    return take_token(s, tok);
}

int tpk_scan_end_line(tpk_scan *s, const char *after)
{
    const char *tok;
    size_t len = tpk_scan_line_token(s, &tok);
    if (len) {
        char q[64];
        return tpk_scan_fail(s, "expected end of line after '%s', found '%s'", after,
                             tpk_scan_quote(tok, len, q, sizeof q));
    }
    if (s->pos < s->size) { /* at '\n' */
        s->pos++;
        s->line++;
    }
    return 0;
}

void tpk_scan_skip_line(tpk_scan *s)
{
    const unsigned char *nl = s->pos < s->size ? memchr(s->data + s->pos, '\n', s->size - s->pos) : NULL;
    if (nl) {
        s->pos = (size_t)(nl - s->data) + 1;
        s->line++;
    } else {
        s->pos = s->size;
    }
}

const char *tpk_scan_quote(const char *tok, size_t len, char *buf, size_t cap)
{
    size_t o = 0;
    const size_t shown = 40;
    for (size_t i = 0; i < len && i < shown && o + 5 < cap; i++) {
        unsigned char c = (unsigned char)tok[i];
        if (c >= 0x20 && c < 0x7f && c != '\'') {
            buf[o++] = (char)c;
        } else {
            snprintf(buf + o, cap - o, "\\x%02x", c);
            o += 4;
        }
    }
    if (len > shown && o + 4 < cap) {
        memcpy(buf + o, "...", 3);
        o += 3;
    }
    buf[o < cap ? o : cap - 1] = 0;
    return buf;
}

int tpk_parse_int64(const char *tok, size_t len, int64_t *out)
{
    size_t i = 0;
    int neg = 0;
    if (i < len && (tok[i] == '+' || tok[i] == '-')) {
        neg = tok[i] == '-';
        i++;
    }
    if (i == len)
        return -1;
    uint64_t v = 0;
    for (; i < len; i++) {
        unsigned d = (unsigned)(unsigned char)tok[i] - '0';
        if (d > 9)
            return -1;
        if (v > (UINT64_C(9223372036854775807) - d) / 10)
            return -1; /* overflow: beyond int64 */
        v = v * 10 + d;
    }
    *out = neg ? -(int64_t)v : (int64_t)v;
    return 0;
}

static int parse_double_slow(const char *tok, size_t len, double *out)
{
    char buf[128];
    if (len == 0 || len >= sizeof buf)
        return -1;
    memcpy(buf, tok, len);
    buf[len] = 0;
    /* strtod also takes hex floats and "infinity"; accept only decimal forms, nan and inf. */
    for (size_t i = 0; i < len; i++)
        if (buf[i] == 'x' || buf[i] == 'X')
            return -1;
    char *end;
    double v = strtod(buf, &end);
    if (end != buf + len)
        return -1;
    *out = v;
    return 0;
}

/* Clinger's fast path: with at most 2^53 as mantissa and |exponent| <= 22, one correctly rounded
 * multiplication or division of two exact doubles gives the correctly rounded result. Longer or
 * unusual numbers go to strtod on a NUL-terminated copy. */
int tpk_parse_double(const char *tok, size_t len, double *out)
{
    static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                   1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    size_t i = 0;
    int neg = 0;
    if (i < len && (tok[i] == '+' || tok[i] == '-')) {
        neg = tok[i] == '-';
        i++;
    }
    uint64_t mant = 0;
    int digits = 0, exp10 = 0, any = 0, inexact = 0;
    for (; i < len; i++) {
        unsigned d = (unsigned)(unsigned char)tok[i] - '0';
        if (d > 9)
            break;
        any = 1;
        if (digits < 19) {
            mant = mant * 10 + d;
            if (mant)
                digits++;
        } else {
            exp10++;
            inexact |= d != 0;
        }
    }
    if (i < len && tok[i] == '.') {
        for (i++; i < len; i++) {
            unsigned d = (unsigned)(unsigned char)tok[i] - '0';
            if (d > 9)
                break;
            any = 1;
            if (digits < 19) {
                mant = mant * 10 + d;
                if (mant)
                    digits++;
                exp10--;
            } else {
                inexact |= d != 0;
            }
        }
    }
    if (!any)
        return parse_double_slow(tok, len, out); /* nan, inf, or not a number */
    if (i < len && (tok[i] == 'e' || tok[i] == 'E')) {
        i++;
        int eneg = 0, edigits = 0, e = 0;
        if (i < len && (tok[i] == '+' || tok[i] == '-')) {
            eneg = tok[i] == '-';
            i++;
        }
        for (; i < len; i++) {
            unsigned d = (unsigned)(unsigned char)tok[i] - '0';
            if (d > 9)
                break;
            if (e < 100000)
                e = e * 10 + (int)d;
            edigits++;
        }
        if (!edigits)
            return -1;
        exp10 += eneg ? -e : e;
    }
    if (i != len)
        return -1;
    if (inexact || mant > (UINT64_C(1) << 53) || exp10 < -22 || exp10 > 22)
        return parse_double_slow(tok, len, out);
    double v = (double)mant;
    v = exp10 < 0 ? v / p10[-exp10] : v * p10[exp10];
    *out = neg ? -v : v;
    return 0;
}

static int number_error(tpk_scan *s, const char *tok, size_t len, const char *what)
{
    if (!len)
        return tpk_scan_fail(s, "expected %s, found %s", what, s->pos >= s->size ? "end of file" : "end of line");
    char q[64];
    return tpk_scan_fail(s, "expected %s, found '%s'", what, tpk_scan_quote(tok, len, q, sizeof q));
}

int tpk_scan_int64(tpk_scan *s, int64_t *out, const char *what)
{
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    if (!len || tpk_parse_int64(tok, len, out) != 0)
        return number_error(s, tok, len, what);
    return 0;
}

int tpk_scan_double(tpk_scan *s, double *out, const char *what)
{
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    if (!len || tpk_parse_double(tok, len, out) != 0)
        return number_error(s, tok, len, what);
    return 0;
}

int tpk_scan_line_int64(tpk_scan *s, int64_t *out, const char *what)
{
    const char *tok;
    size_t len = tpk_scan_line_token(s, &tok);
    if (!len || tpk_parse_int64(tok, len, out) != 0)
        return number_error(s, tok, len, what);
    return 0;
}

int tpk_scan_line_double(tpk_scan *s, double *out, const char *what)
{
    const char *tok;
    size_t len = tpk_scan_line_token(s, &tok);
    if (!len || tpk_parse_double(tok, len, out) != 0)
        return number_error(s, tok, len, what);
    return 0;
}

int tpk_token_is(const char *tok, size_t len, const char *word)
{
    size_t n = strlen(word);
    if (n != len)
        return 0;
    for (size_t i = 0; i < n; i++) {
        char a = tok[i], b = word[i];
        if (a >= 'a' && a <= 'z')
            a = (char)(a - 'a' + 'A');
        if (b >= 'a' && b <= 'z')
            b = (char)(b - 'a' + 'A');
        if (a != b)
            return 0;
    }
    return 1;
}

/* Mappings of at least this many bytes a thread are populated on several, in chunks of SCAN_CHUNK bytes
 * (tpk_parallel_chunks: a worker held up leaves the rest to the others). */
#define POPULATE_PIECE ((int64_t)16 << 20)
#define SCAN_CHUNK ((int64_t)4 << 20)

typedef struct populate_job {
    const unsigned char *map;
    size_t size;
} populate_job;

/* MADV_POPULATE_READ (Linux 5.14) over [begin, end) rounded out to pages; where the kernel lacks it, a
 * read of a byte a page (the faults map the pages around it too). */
static void populate_range(void *ctx, int64_t begin, int64_t end, int w)
{
    const populate_job *job = ctx;
    (void)w;
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    size_t from = (size_t)begin / page * page, to = (size_t)end;
#ifdef MADV_POPULATE_READ
    if (madvise((void *)(job->map + from), to - from, MADV_POPULATE_READ) == 0)
        return;
#endif
    volatile unsigned char sink = 0;
    for (size_t at = from; at < to; at += page)
        sink ^= job->map[at];
    (void)sink;
}

int tpk_map_file(const char *path, const char **data, size_t *size, tpk_diag *diag)
{
    static const char empty[1];
    *data = NULL;
    *size = 0;
    /* O_NONBLOCK: opening a FIFO (or a device) returns at once instead of waiting for a writer, and
     * fstat then refuses it; a regular file reads the same either way. */
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0)
        return tpk_diag_fail(diag, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return tpk_diag_fail(diag, "%s: not a regular file", path);
    }
    size_t n = (size_t)st.st_size;
    if (n == 0) {
        close(fd);
        *data = empty;
        return 0;
    }
    /* A read-only mapping: no copy and no zeroed buffer; populated (read ahead and its page tables filled)
     * in one go, in pieces on all threads where there are several (one core's MAP_POPULATE of a 298 MB
     * input was 0.5% of a 2-thread convert, all of it serial). */
    int threads = tpk_threads_for((int64_t)n, tpk_thread_count(0), POPULATE_PIECE);
    void *map = mmap(NULL, n, PROT_READ, MAP_PRIVATE | (threads < 2 ? MAP_POPULATE : 0), fd, 0);
    int err = errno;
    close(fd);
    if (map == MAP_FAILED)
        return tpk_diag_fail(diag, "%s: cannot map %zu bytes: %s", path, n, strerror(err));
    if (threads >= 2) {
        populate_job job = {map, n};
        tpk_parallel_chunks((int64_t)n, threads, SCAN_CHUNK, populate_range, &job);
    }
    *data = map;
    *size = n;
    return 0;
}

/* A process-wide hook rather than a field of tpk_scan: the importers' signatures stay as they are, and only
 * the converter, which imports one file at a time, sets it. */
static void (*scan_watcher)(void *user, double fraction);
static void *scan_watcher_user;

void tpk_scan_watch(void (*fn)(void *user, double fraction), void *user)
{
    scan_watcher = fn;
    scan_watcher_user = user;
}

void tpk_scan_release_consumed(tpk_scan *s)
{
    if (scan_watcher && s->size)
        scan_watcher(scan_watcher_user, (double)s->pos / (double)s->size);
    if (!s->mapped)
        return;
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    size_t upto = s->pos / page * page;
    if (upto > s->released) {
        /* in pieces on all threads when large (one core's zap of a block's pages was 11 of 140 serial
         * samples of a 2-thread grid 120 convert): the zaps share the mapping's lock */
        int threads = tpk_threads_for((int64_t)(upto - s->released), tpk_thread_count(0), POPULATE_PIECE);
        tpk_drop_pages((void *)(s->data + s->released), upto - s->released, threads);
        s->released = upto;
    }
}

void tpk_unmap_file(const char *data, size_t size)
{
    if (data && size > 0)
        munmap((void *)data, size);
}
