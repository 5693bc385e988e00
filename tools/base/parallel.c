/* pthread parallel-for over contiguous ranges (see parallel.h). */
#include "parallel.h"

#include <pthread.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

int tpk_thread_count(int requested)
{
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

/* The one block tpk_free_large keeps (see parallel.h), with its size. */
static struct {
    pthread_mutex_t lock;
    void *block;
    size_t size;
} spare = {PTHREAD_MUTEX_INITIALIZER, NULL, 0};

static void *take_spare(size_t size)
{
    void *block = NULL;
    pthread_mutex_lock(&spare.lock);
    if (spare.block && size <= spare.size && size >= spare.size / 2) {
        block = spare.block;
        spare.block = NULL;
        spare.size = 0;
    }
    pthread_mutex_unlock(&spare.lock);
    return block;
}

void tpk_free_large(void *block, size_t size)
{
    if (!block || size < ((size_t)2 << 20)) {
        free(block);
        return;
    }
    pthread_mutex_lock(&spare.lock);
    if (size > spare.size) { /* keep the larger: it serves more requests */
        void *swap = spare.block;
        spare.block = block;
        spare.size = size;
        block = swap;
    }
    pthread_mutex_unlock(&spare.lock);
    free(block);
}

void *tpk_alloc_large(size_t size)
{
    const size_t huge_page = (size_t)2 << 20;
    if (size < huge_page)
        return malloc(size ? size : 1);
    void *block = take_spare(size);
    if (block)
        return block;
    if (posix_memalign(&block, huge_page, size) != 0)
        return NULL;
#ifdef MADV_HUGEPAGE
    madvise(block, size, MADV_HUGEPAGE); /* advice only: failure changes nothing */
#endif
    return block;
}

void tpk_split_prefix(const int64_t *starts, int64_t n, int64_t entries, int parts, int64_t *begin)
{
    begin[0] = 0;
    for (int w = 1; w < parts; w++) {
        int64_t target = entries / parts * w, lo = begin[w - 1], hi = n;
        while (lo < hi) { /* first bucket starting at or after target */
            int64_t mid = lo + (hi - lo) / 2;
            if (starts[mid] < target)
                lo = mid + 1;
            else
                hi = mid;
        }
        begin[w] = lo;
    }
    begin[parts] = n;
}
