/* The large-block reuse of tools/base/parallel.c that the convert stages share: a freed block serves the
 * next request it fits (at least half its size), the smallest such first; a request no kept block fits
 * frees all but the largest; tpk_calloc_large zeroes a reused (dirty) block; tpk_release_kept empties
 * the list. Pointers are compared, not timed: reuse is what saves the page faults. Also the chunked
 * parallel-for and the release of a block's pages on several threads. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "harness.h"

#define MIB ((size_t)1 << 20)

TPK_TEST(reuse_fitting_block)
{
    tpk_release_kept();
    char *a = tpk_alloc_large(8 * MIB);
    CHECK(a != NULL);
    memset(a, 0x5a, 8 * MIB);
    tpk_free_large(a, 8 * MIB);
    char *b = tpk_alloc_large(5 * MIB); /* fits: 5 MiB is at least half of 8 */
    CHECK(b == a);
    tpk_free_large(b, 8 * MIB);
    int *z = tpk_calloc_large(MIB, sizeof *z); /* 4 MiB from the dirty 8 MiB block, zeroed */
    CHECK(z == (int *)a);
    int nonzero = 0;
    for (size_t i = 0; i < MIB; i++)
        nonzero += z[i] != 0;
    CHECK_EQ_INT(nonzero, 0);
    tpk_free_large(z, 8 * MIB);
    tpk_release_kept();
}

TPK_TEST(reuse_smallest_fit_and_miss_keeps_largest)
{
    tpk_release_kept();
    char *big = tpk_alloc_large(40 * MIB), *mid = tpk_alloc_large(12 * MIB), *small = tpk_alloc_large(6 * MIB);
    CHECK(big && mid && small);
    big[0] = mid[0] = small[0] = 1;
    tpk_free_large(big, 40 * MIB);
    tpk_free_large(mid, 12 * MIB);
    tpk_free_large(small, 6 * MIB);
    char *c = tpk_alloc_large(6 * MIB); /* both 6 and 12 MiB fit: the smaller is taken */
    CHECK(c == small);
    char *d = tpk_alloc_large(100 * MIB); /* fits none: mid is freed, big kept */
    CHECK(d != NULL && d != big);
    char *e = tpk_alloc_large(11 * MIB); /* big is more than twice 11 MiB: not taken */
    CHECK(e != NULL && e != big);
    char *f = tpk_alloc_large(30 * MIB); /* big survived both misses */
    CHECK(f == big);
    CHECK(f[0] == 1);
    tpk_free_large(c, 6 * MIB);
    tpk_free_large(d, 100 * MIB);
    tpk_free_large(e, 11 * MIB);
    tpk_free_large(f, 40 * MIB);
    tpk_release_kept();
    char *g = tpk_alloc_large(100 * MIB); /* released: nothing to reuse */
    CHECK(g != NULL);
    tpk_free_large(g, 100 * MIB);
    tpk_release_kept();
}

/* tpk_parallel_chunks: every item in exactly one call, each call within one chunk, a worker's calls in
 * increasing order; one thread: a single call over everything. */
typedef struct chunk_log {
    int *seen;                        /* calls that covered each item */
    int64_t last_end[TPK_MAX_THREADS]; /* a worker's previous call's end */
    int out_of_order, too_long, calls[TPK_MAX_THREADS];
    int64_t chunk;
} chunk_log;

static void log_range(void *ctx, int64_t begin, int64_t end, int w)
{
    chunk_log *log = ctx;
    if (begin < log->last_end[w])
        log->out_of_order = 1;
    if (end - begin > log->chunk || (begin % log->chunk) != 0)
        log->too_long = 1;
    log->last_end[w] = end;
    log->calls[w]++;
    for (int64_t i = begin; i < end; i++)
        log->seen[i]++;
}

TPK_TEST(parallel_chunks_cover_once_in_order)
{
    const int64_t count = 100003;
    for (int threads = 1; threads <= 3; threads++) {
        chunk_log log;
        memset(&log, 0, sizeof log);
        log.seen = calloc((size_t)count, sizeof *log.seen);
        log.chunk = threads == 1 ? count : 4096;
        tpk_parallel_chunks(count, threads, 4096, log_range, &log);
        int wrong = 0, calls = 0;
        for (int64_t i = 0; i < count; i++)
            wrong += log.seen[i] != 1;
        for (int w = 0; w < threads; w++)
            calls += log.calls[w];
        CHECK_EQ_INT(wrong, 0);
        CHECK(!log.out_of_order && !log.too_long);
        CHECK_EQ_INT(calls, threads == 1 ? 1 : (int)((count + 4095) / 4096));
        free(log.seen);
    }
}

/* tpk_release_pages gives back the whole pages inside a block on several threads (they read as zero
 * after), keeps the bytes on partial pages at its ends, and with one thread leaves everything. */
TPK_TEST(release_pages_zeroes_whole_pages_only)
{
    size_t size = 40 * MIB + 1000;
    char *block = malloc(size);
    CHECK(block != NULL);
    for (int threads = 1; threads <= 2; threads++) {
        memset(block, 0x5a, size);
        int previous = tpk_set_default_threads(threads);
        tpk_release_pages(block + 100, size - 200);
        tpk_set_default_threads(previous);
        size_t page = 4096, first = ((uintptr_t)block + 100 + page - 1) / page * page - (uintptr_t)block;
        size_t last = ((uintptr_t)block + size - 100) / page * page - (uintptr_t)block;
        int kept_ends = block[100] == 0x5a && block[size - 101] == 0x5a && block[first - 1] == 0x5a &&
                        block[last] == 0x5a;
        size_t zero = 0;
        for (size_t i = first; i < last; i += 4096)
            zero += block[i] == 0 && block[i + 4095] == 0;
        CHECK(kept_ends);
        CHECK(zero == (threads == 1 ? 0 : (last - first) / 4096));
    }
    tpk_free_spread(block, size);
}
