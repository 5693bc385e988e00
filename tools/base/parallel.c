/* pthread parallel-for over contiguous ranges (see parallel.h). */
#include "parallel.h"

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static _Atomic int default_threads;

int tpk_set_default_threads(int threads)
{
    return atomic_exchange(&default_threads, threads > 0 ? threads : 0);
}

int tpk_thread_count(int requested)
{
    if (requested <= 0)
        requested = atomic_load(&default_threads);
    if (requested <= 0) {
        long online = sysconf(_SC_NPROCESSORS_ONLN);
        requested = online > 0 ? (int)(online < TPK_MAX_THREADS ? online : TPK_MAX_THREADS) : 1;
    }
    return requested > TPK_MAX_THREADS ? TPK_MAX_THREADS : requested;
}

int tpk_threads_for(int64_t count, int threads, int64_t grain)
{
    int64_t most = grain > 0 ? count / grain : count;
    if (most < 1)
        most = 1;
    return threads < most ? threads : (int)most;
}

void tpk_parallel_range(int64_t count, int threads, int w, int64_t *begin, int64_t *end)
{
    *begin = count / threads * w + (w < count % threads ? w : count % threads);
    *end = *begin + count / threads + (w < count % threads ? 1 : 0);
}

typedef struct worker_job {
    tpk_range_fn fn;
    void *ctx;
    int64_t begin, end;
    int worker;
} worker_job;

static void *run_job(void *arg)
{
    worker_job *job = arg;
    job->fn(job->ctx, job->begin, job->end, job->worker);
    return NULL;
}

void tpk_parallel_for(int64_t count, int threads, tpk_range_fn fn, void *ctx)
{
    if (threads < 1)
        threads = 1;
    if (threads > TPK_MAX_THREADS)
        threads = TPK_MAX_THREADS;
    worker_job jobs[TPK_MAX_THREADS];
    pthread_t ids[TPK_MAX_THREADS];
    int started[TPK_MAX_THREADS] = {0};
    for (int w = 0; w < threads; w++) {
        jobs[w] = (worker_job){fn, ctx, 0, 0, w};
        tpk_parallel_range(count, threads, w, &jobs[w].begin, &jobs[w].end);
    }
    for (int w = 1; w < threads; w++)
        started[w] = pthread_create(&ids[w], NULL, run_job, &jobs[w]) == 0;
    run_job(&jobs[0]);
    for (int w = 1; w < threads; w++) {
        if (started[w])
            pthread_join(ids[w], NULL);
        else
            run_job(&jobs[w]);
    }
}

typedef struct chunks_job {
    tpk_range_fn fn;
    void *ctx;
    int64_t count, chunk;
    _Atomic int64_t next; /* the next chunk to take */
} chunks_job;

static void take_chunks(void *ctx, int64_t begin, int64_t end, int worker)
{
    chunks_job *job = ctx;
    (void)begin, (void)end;
    for (;;) {
        int64_t k = atomic_fetch_add(&job->next, 1);
        if (k >= (job->count + job->chunk - 1) / job->chunk)
            return;
        int64_t from = k * job->chunk, to = job->count - from < job->chunk ? job->count : from + job->chunk;
        job->fn(job->ctx, from, to, worker);
    }
}

void tpk_parallel_chunks(int64_t count, int threads, int64_t chunk, tpk_range_fn fn, void *ctx)
{
    if (threads < 2 || chunk < 1 || count <= chunk) {
        tpk_parallel_for(count, threads < 1 ? 1 : threads, fn, ctx);
        return;
    }
    chunks_job job = {fn, ctx, count, chunk, 0};
    tpk_parallel_for(threads, threads, take_chunks, &job);
}

/* The blocks tpk_free_large keeps (see parallel.h), each with its size; unused slots are NULL. */
#define KEPT_BLOCKS 6
static struct {
    pthread_mutex_t lock;
    void *block[KEPT_BLOCKS];
    size_t size[KEPT_BLOCKS];
} kept = {PTHREAD_MUTEX_INITIALIZER, {NULL}, {0}};

/* The smallest kept block that holds size bytes and is at most twice that, taken out of the list. On a
 * miss the caller maps fresh pages next: every kept block but the largest (likely the next stage's big
 * array: reorder's old tets become connect's neighbors) is freed first, so that what is kept adds little
 * to the fresh pages (the peak stays near that of the arrays in use). */
static void *take_kept(size_t size)
{
    void *block = NULL, *drop[KEPT_BLOCKS] = {NULL};
    size_t drop_size[KEPT_BLOCKS] = {0};
    pthread_mutex_lock(&kept.lock);
    int best = -1, largest = -1;
    for (int i = 0; i < KEPT_BLOCKS; i++) {
        if (!kept.block[i])
            continue;
        if (size <= kept.size[i] && size >= kept.size[i] / 2 && (best < 0 || kept.size[i] < kept.size[best]))
            best = i;
        if (largest < 0 || kept.size[i] > kept.size[largest])
            largest = i;
    }
    for (int i = 0; i < KEPT_BLOCKS; i++) {
        if (best >= 0 ? i != best : i == largest)
            continue;
        if (i == best)
            block = kept.block[i];
        else
            drop[i] = kept.block[i], drop_size[i] = kept.size[i];
        kept.block[i] = NULL;
        kept.size[i] = 0;
    }
    pthread_mutex_unlock(&kept.lock);
    for (int i = 0; i < KEPT_BLOCKS; i++)
        tpk_free_spread(drop[i], drop_size[i]);
    return block;
}

void tpk_free_large(void *block, size_t size)
{
    if (!block || size < ((size_t)2 << 20)) {
        free(block);
        return;
    }
    pthread_mutex_lock(&kept.lock);
    int slot = 0; /* an empty slot, else the smallest block, which the new one replaces if larger */
    for (int i = 1; i < KEPT_BLOCKS && kept.block[slot]; i++)
        if (!kept.block[i] || kept.size[i] < kept.size[slot])
            slot = i;
    if (!kept.block[slot] || size > kept.size[slot]) {
        void *swap = kept.block[slot];
        size_t swap_size = kept.size[slot];
        kept.block[slot] = block;
        kept.size[slot] = size;
        block = swap;
        size = swap_size;
    }
    pthread_mutex_unlock(&kept.lock);
    tpk_free_spread(block, size);
}

/* Whether huge pages make a fresh block cheaper here. Not inside a virtual machine whose balloon device
 * takes free memory back (virtio's free page reporting, feature bit 5): the host is handed free blocks of
 * 2 MiB and more, the very blocks a huge page is made of, so a huge page faulted later is mostly memory
 * the host must first map again, a fault in the host for each of its 4 KiB pages, while 4 KiB pages come
 * from smaller free blocks it was never handed. On this project's 2-core machine (Firecracker, reporting
 * on, order 9) grid 120 at --threads 1, a run after a pause: 1.02 -> 0.51 s of system time, reorder
 * 1.19 -> 0.81 s, without the advice (5 alternating runs, medians); a page fault each 4 KiB costs less
 * than that. Elsewhere the advice stays: a fresh huge page is faulted and zeroed 3x faster than 4 KiB ones. */
static pthread_once_t huge_once = PTHREAD_ONCE_INIT;
static int huge_pays = 1;

static void find_free_page_reporting(void)
{
    const char *driver = "/sys/bus/virtio/drivers/virtio_balloon";
    DIR *dir = opendir(driver);
    for (struct dirent *e; dir && (e = readdir(dir));) {
        char path[320], bits[8] = "";
        if (strncmp(e->d_name, "virtio", 6) != 0 || strlen(e->d_name) > 64)
            continue; /* the driver's devices are linked here as virtioN */
        snprintf(path, sizeof path, "%s/%s/features", driver, e->d_name);
        int fd = open(path, O_RDONLY);
        if (fd < 0)
            continue;
        ssize_t n = read(fd, bits, sizeof bits);
        close(fd);
        if (n > 5 && bits[5] == '1') /* the features as '0'/'1' from bit 0; 5: VIRTIO_BALLOON_F_REPORTING */
            huge_pays = 0;
    }
    if (dir)
        closedir(dir);
}

void *tpk_alloc_large(size_t size)
{
    const size_t huge_page = (size_t)2 << 20;
    if (size < huge_page)
        return malloc(size ? size : 1);
    void *block = take_kept(size);
    if (block)
        return block;
    if (posix_memalign(&block, huge_page, size) != 0)
        return NULL;
#ifdef MADV_HUGEPAGE
    pthread_once(&huge_once, find_free_page_reporting);
    if (huge_pays)
        madvise(block, size, MADV_HUGEPAGE); /* advice only: failure changes nothing */
#endif
    return block;
}

void tpk_release_kept(void)
{
    void *drop[KEPT_BLOCKS];
    size_t drop_size[KEPT_BLOCKS];
    pthread_mutex_lock(&kept.lock);
    for (int i = 0; i < KEPT_BLOCKS; i++) {
        drop[i] = kept.block[i];
        drop_size[i] = kept.size[i];
        kept.block[i] = NULL;
        kept.size[i] = 0;
    }
    pthread_mutex_unlock(&kept.lock);
    for (int i = 0; i < KEPT_BLOCKS; i++)
        tpk_free_spread(drop[i], drop_size[i]);
}

/* Pieces of at least this many bytes per thread: below, starting a thread costs more than it saves. */
#define RELEASE_PIECE ((int64_t)8 << 20)

typedef struct release_job {
    char *base; /* page aligned */
    size_t size, page;
} release_job;

static void release_range(void *ctx, int64_t begin, int64_t end, int w)
{
    const release_job *job = ctx;
    (void)w;
    size_t b = (size_t)begin / job->page * job->page, e = (size_t)end;
    if (e != job->size)
        e = e / job->page * job->page;
    if (e > b)
        madvise(job->base + b, e - b, MADV_DONTNEED);
}

void tpk_drop_pages(void *first, size_t size, int threads)
{
    release_job job = {first, size, (size_t)sysconf(_SC_PAGESIZE)};
    tpk_parallel_chunks((int64_t)size, threads, (int64_t)4 << 20, release_range, &job);
}

void tpk_release_pages(void *block, size_t size)
{
    int threads = tpk_threads_for((int64_t)size, tpk_thread_count(0), RELEASE_PIECE);
    if (!block || threads < 2)
        return;
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    uintptr_t first = ((uintptr_t)block + page - 1) / page * page, last = ((uintptr_t)block + size) / page * page;
    if (last > first)
        tpk_drop_pages((void *)first, last - first, threads);
}

void tpk_free_spread(void *block, size_t size)
{
    tpk_release_pages(block, size);
    free(block);
}

void *tpk_calloc_large(size_t count, size_t size)
{
    if (size && count > SIZE_MAX / size)
        return NULL;
    void *block = tpk_alloc_large(count * size);
    if (block)
        memset(block, 0, count * size > 0 ? count * size : 1);
    return block;
}

void tpk_split_by(int64_t (*first)(const void *ctx, int64_t b), const void *ctx, int64_t n, int64_t entries,
                  int parts, int64_t *begin)
{
    begin[0] = 0;
    for (int w = 1; w < parts; w++) {
        int64_t target = entries / parts * w, lo = begin[w - 1], hi = n;
        while (lo < hi) { /* first bucket starting at or after target */
            int64_t mid = lo + (hi - lo) / 2;
            if (first(ctx, mid) < target)
                lo = mid + 1;
            else
                hi = mid;
        }
        begin[w] = lo;
    }
    begin[parts] = n;
}

static int64_t start_in_array(const void *ctx, int64_t b)
{
    return ((const int64_t *)ctx)[b];
}

void tpk_split_prefix(const int64_t *starts, int64_t n, int64_t entries, int parts, int64_t *begin)
{
    tpk_split_by(start_in_array, starts, n, entries, parts, begin);
}
