/* Blocks of numbers in text on all threads (text_numbers.h). */
#include "text_numbers.h"

#include <stdlib.h>

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

static void count_piece(void *ctx, int64_t begin, int64_t end, int w)
{
    numbers_job *job = ctx;
    piece *p = &job->piece[w];
    (void)begin, (void)end;
    uint64_t tokens = 0;
    int64_t newlines = 0;
    int in_token = 0;
    for (size_t i = p->begin; i < p->end; i++) {
        unsigned char c = job->d[i];
        if (is_space(c)) {
            newlines += c == '\n';
            in_token = 0;
        } else if (!in_token) {
            tokens++;
            in_token = 1;
        }
    }
    p->tokens = tokens;
    p->newlines = newlines;
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
    /* A window that likely holds the block (16 bytes a number), doubled until it does. */
    size_t window = count < left / 16 ? (size_t)count * 16 : left;
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
        window = window > left / 2 ? left : 2 * window;
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
