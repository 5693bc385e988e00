/* A tiny pthread parallel-for for the converter: [0, count) is cut into `threads` contiguous ranges
 * that depend only on count and threads, so per-worker results can be merged deterministically. */
#ifndef TPK_PARALLEL_H
#define TPK_PARALLEL_H

#include <stddef.h>
#include <stdint.h>

#define TPK_MAX_THREADS 64

/* requested <= 0: the process default (tpk_set_default_threads), else the number of online CPUs. Clamped
 * to [1, TPK_MAX_THREADS]. */
int tpk_thread_count(int requested);

/* What tpk_thread_count(0) gives from now on (threads <= 0: the online CPUs again); returns the previous
 * setting. For stages that take no thread count of their own (the importers): convert sets its --threads
 * here for the run, so that --threads 1 runs on one core throughout. */
int tpk_set_default_threads(int threads);

/* Fewer workers for small jobs: at most one per `grain` items (at least 1). */
int tpk_threads_for(int64_t count, int threads, int64_t grain);

/* Range of worker `w` out of `threads` over [0, count). */
void tpk_parallel_range(int64_t count, int threads, int w, int64_t *begin, int64_t *end);

/* Cut n buckets, whose entries start at the prefix sums starts[0..n], into `parts` contiguous ranges of
 * about entries / parts entries each: begin[w] is the first bucket starting at or after w * entries /
 * parts (begin[0] = 0, begin[parts] = n). begin holds parts + 1 values. */
void tpk_split_prefix(const int64_t *starts, int64_t n, int64_t entries, int parts, int64_t *begin);
/* tpk_split_prefix where bucket b's first entry is first(ctx, b) (nondecreasing in b), for starts kept in
 * another form. */
void tpk_split_by(int64_t (*first)(const void *ctx, int64_t b), const void *ctx, int64_t n, int64_t entries,
                  int parts, int64_t *begin);

typedef void (*tpk_range_fn)(void *ctx, int64_t begin, int64_t end, int worker);

/* Call fn(ctx, begin, end, w) for w = 0..threads-1 on the ranges above, worker 0 on the calling
 * thread, and wait for all. If a thread cannot be started its range runs on the calling thread, so
 * the call always completes. */
void tpk_parallel_for(int64_t count, int threads, tpk_range_fn fn, void *ctx);

/* tpk_parallel_for where the workers take [0, count) in chunks of `chunk` items, each the next one not
 * taken, until none is left: a worker that starts late or is held up by other work on a shared machine
 * leaves its share to the others rather than making them wait at the end. fn(ctx, begin, end, w) is
 * called for each chunk, a worker's chunks in increasing order: per-worker results must accumulate over
 * the calls (a first bad item: the smaller; counts: added), and only what does not depend on which
 * worker took which chunk may be kept (every item's output at its own place, a smallest or largest). */
void tpk_parallel_chunks(int64_t count, int threads, int64_t chunk, tpk_range_fn fn, void *ctx);

/* malloc for large scratch arrays: the block tpk_free_large kept, when it fits (below), else fresh,
 * 2 MiB aligned and, where the kernel offers it, backed by huge pages (fewer page faults on first touch,
 * which dominate a pass over a fresh 500 MB array), except inside a virtual machine whose balloon takes
 * free memory back (parallel.c says why). Only malloc's alignment is promised. Release with
 * free() or tpk_free_large. NULL when out of memory. */
void *tpk_alloc_large(size_t size);

/* free() for a large array the caller is done with (any malloc'ed block of `size` bytes): blocks of 2 MiB
 * or more are kept, already in memory (the six largest), and the next tpk_alloc_large of between half a
 * block's size and its size gets the smallest that fits instead of fresh pages (a first touch of fresh
 * pages costs time, bench/README "Figures behind code comments": reorder's old tet array becomes
 * connect's neighbors, its old points the new tet sources). A tpk_alloc_large that no kept block fits
 * frees all but the largest before it maps fresh pages, so keeping adds little to the peak (971k
 * hexahedra: 307 MiB, as before). */
void tpk_free_large(void *block, size_t size);

/* Frees the blocks tpk_free_large keeps: for a stage that allocates no more large arrays, so that the
 * kernel hands those recently used pages to what comes next (the page cache of a file being written)
 * rather than pages never touched, whose first use costs more. */
void tpk_release_kept(void);

/* MADV_DONTNEED of the pages [first, first + size) (first page aligned) on `threads` threads, in chunks
 * of 4 MiB (tpk_parallel_chunks: the zaps share the mapping's lock, and a worker held up leaves the rest
 * to the others). The next touch of a page finds a zeroed one, or in a file mapping the file's. */
void tpk_drop_pages(void *first, size_t size, int threads);

/* The pages of [block, block + size) (those wholly inside it) given back to the kernel on all threads
 * (tpk_thread_count(0)) where it is large, the block staying the caller's: the next touch of a page finds
 * a zeroed one. For a block about to be freed (tpk_free_spread), so that the free's unmapping is not all
 * on one core. */
void tpk_release_pages(void *block, size_t size);

/* free() of a block of `size` bytes (malloc'ed, or NULL) after tpk_release_pages. */
void tpk_free_spread(void *block, size_t size);

/* calloc through tpk_alloc_large (zeroed here: a kept block holds old data). NULL when out of memory. */
void *tpk_calloc_large(size_t count, size_t size);

#endif
