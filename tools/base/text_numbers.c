/* Blocks of numbers in text on all threads (text_numbers.h). */
#include "text_numbers.h"

#include <stdlib.h>
#include <string.h>

#include "parallel.h"

static inline int is_space(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

typedef struct piece {
    size_t begin, end;   /* [begin, end): starts at a token or whitespace, ends at whitespace or the window's end */
    uint64_t tokens;     /* tokens starting in it */
    int64_t newlines;
    uint64_t first;      /* index of its first token (prefix sum) */
} piece;

typedef struct numbers_job {
    const unsigned char *d;
    uint64_t count;
    tpk_number_kind kind;
    void *dst;
    piece piece[TPK_MAX_THREADS];
    int failed[TPK_MAX_THREADS];
    /* the piece holding token count - 1 sets these */
    size_t last_begin, last_end;
    int64_t last_newlines; /* newlines in its piece before it */
} numbers_job;

#define ONES 0x0101010101010101ull
#define LOW7 0x7f7f7f7f7f7f7f7full
#define HIGH 0x8080808080808080ull

/* The spaces (is_space) of 8 bytes, little-endian: bit 7 of each byte. Bytes of 128 and more are not. */
static inline uint64_t space_bits(uint64_t x)
{
    uint64_t m = x & LOW7;
    uint64_t ge9 = m + 0x77 * ONES, ge14 = m + 0x72 * ONES; /* bit 7: m >= 9, m >= 14 (no carry out) */
    uint64_t blank = ~((m ^ 0x20 * ONES) + LOW7);           /* bit 7: m == ' ' */
    return (((ge9 & ~ge14) | blank) & ~x) & HIGH;
}

static inline uint64_t newline_bits(uint64_t x)
{
    return ~(((x & LOW7) ^ 0x0a * ONES) + LOW7) & ~x & HIGH;
}

/* The number of bytes whose bit 7 is set in bits (only bit 7s set). */
static inline uint64_t count_high(uint64_t bits)
{
    return ((bits >> 7) * ONES) >> 56;
}

static void count_piece(void *ctx, int64_t begin, int64_t end, int w)
{
    numbers_job *job = ctx;
    piece *p = &job->piece[w];
    (void)begin, (void)end;
    /* Eight bytes at a time (a loop with a branch per byte cost more than the parsing): a token starts
     * at each non-space byte after a space; a piece starts at a token's first byte or at whitespace. */
    uint64_t tokens = 0, newlines = 0;
    uint64_t prev = 1; /* the byte before is a space */
    const unsigned char *d = job->d;
    size_t i = p->begin;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    for (; i + 8 <= p->end; i += 8) {
        uint64_t x;
        memcpy(&x, d + i, sizeof x);
        uint64_t space = space_bits(x);
        uint64_t before = (space << 8) | (prev << 7);
        tokens += count_high(~space & before & HIGH);
        newlines += count_high(newline_bits(x));
        prev = space >> 63;
    }
#endif
    for (; i < p->end; i++) {
        unsigned c = d[i];
        unsigned space = is_space(d[i]);
        tokens += prev & (space ^ 1u);
        newlines += c == '\n';
        prev = space;
    }
    p->tokens = tokens;
    p->newlines = (int64_t)newlines;
}

static int parse_one(const numbers_job *job, const char *tok, size_t len, uint64_t i)
{
    switch (job->kind) {
    case TPK_NUMBER_F64:
        return tpk_parse_double(tok, len, (double *)job->dst + i);
    case TPK_NUMBER_F32: {
        double v;
        if (tpk_parse_double(tok, len, &v))
            return -1;
        ((float *)job->dst)[i] = (float)v;
        return 0;
    }
    case TPK_NUMBER_I64:
        return tpk_parse_int64(tok, len, (int64_t *)job->dst + i);
    case TPK_NUMBER_ID32: {
        int64_t v;
        if (tpk_parse_int64(tok, len, &v) || v < 0 || v > INT32_MAX)
            return -1;
        ((int32_t *)job->dst)[i] = (int32_t)v;
        return 0;
    }
    }
    return -1;
}

static void parse_piece(void *ctx, int64_t begin, int64_t end, int w)
{
    numbers_job *job = ctx;
    const piece *p = &job->piece[w];
    (void)begin, (void)end;
    uint64_t i = p->first;
    int64_t newlines = 0;
    size_t at = p->begin;
    while (i < job->count && at < p->end) {
        unsigned char c = job->d[at];
        if (is_space(c)) {
            newlines += c == '\n';
            at++;
            continue;
        }
        size_t start = at;
        while (at < p->end && !is_space(job->d[at]))
            at++;
        if (parse_one(job, (const char *)job->d + start, at - start, i)) {
            job->failed[w] = 1;
            return;
        }
        if (i == job->count - 1) {
            job->last_begin = start;
            job->last_end = at;
            job->last_newlines = newlines;
        }
        i++;
    }
}

int tpk_scan_numbers(tpk_scan *s, uint64_t count, tpk_number_kind kind, void *dst, int threads)
{
    return tpk_scan_numbers_tuned(s, count, kind, dst, threads, 65536, (int64_t)1 << 20);
}

int tpk_scan_numbers_tuned(tpk_scan *s, uint64_t count, tpk_number_kind kind, void *dst, int threads,
                           uint64_t min_count, int64_t grain)
{
    threads = tpk_thread_count(threads);
    if (threads < 2 || count < min_count || count == 0 || s->hash_comments || s->pos >= s->size)
        return 1;
    numbers_job *job = calloc(1, sizeof *job);
    if (!job)
        return 1;
    *job = (numbers_job){.d = s->data, .count = count, .kind = kind, .dst = dst};
    size_t start = s->pos, left = s->size - start;
    /* A window that likely holds the block, doubled until it does: the bytes a number its first 64 numbers
     * take, a tenth more, and a page (counting a window costs about a third of parsing it, so one that
     * runs far past the block's end, as 16 bytes a number did for integers, costs time). */
    size_t sample = 0, seen = 0;
    for (int in = 0; start + sample < s->size && seen < 64; sample++) {
        int space = is_space(s->data[start + sample]);
        seen += !space && !in;
        in = !space;
    }
    double per = seen ? (double)sample / (double)seen : 16.0;
    double guess = (double)count * per * 1.1 + 4096.0;
    size_t window = guess < (double)left ? (size_t)guess : left;
    int pieces = 1;
    uint64_t total = 0;
    for (;;) {
        size_t wend = start + window;
        while (wend < s->size && !is_space(s->data[wend]))
            wend++;
        pieces = tpk_threads_for((int64_t)(wend - start), threads, grain);
        size_t b = start;
        for (int w = 0; w < pieces; w++) {
            size_t e = w + 1 == pieces ? wend : start + (wend - start) / (size_t)pieces * (size_t)(w + 1);
            if (e < b)
                e = b;
            while (e < wend && !is_space(s->data[e]))
                e++;
            job->piece[w].begin = b;
            job->piece[w].end = e;
            b = e;
        }
        tpk_parallel_for(pieces, pieces, count_piece, job);
        total = 0;
        for (int w = 0; w < pieces; w++) {
            job->piece[w].first = total;
            total += job->piece[w].tokens;
        }
        if (total >= count || wend >= s->size)
            break;
        /* the bytes a number the window held, a quarter more, and at least twice the window */
        double more = total ? (double)(wend - start) / (double)total * (double)count * 1.25 : 0.0;
        if (more < 2.0 * (double)window)
            more = 2.0 * (double)window;
        window = more < (double)left ? (size_t)more : left;
    }
    int rc = 1;
    if (total >= count) {
        tpk_parallel_for(pieces, pieces, parse_piece, job);
        int failed = 0;
        int64_t line = s->line;
        for (int w = 0; w < pieces; w++) {
            failed |= job->failed[w];
            if (job->piece[w].first + job->piece[w].tokens < count)
                line += job->piece[w].newlines;
            else if (job->piece[w].first < count)
                line += job->last_newlines;
        }
        if (!failed) {
            s->pos = job->last_end;
            s->line = line;
            s->tok_pos = job->last_begin;
            s->tok_line = line;
            rc = 0;
        }
    }
    free(job);
    return rc;
}
