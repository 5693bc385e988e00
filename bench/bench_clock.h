/* Clocks for the benchmarks: wall time, and CPU time of the whole process (all threads), which is the
 * steadier measure on a shared, loaded machine. */
#ifndef TPK_BENCH_CLOCK_H
#define TPK_BENCH_CLOCK_H

#include <time.h>

static inline double bench_clock(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline double now(void)
{
    return bench_clock(CLOCK_MONOTONIC);
}

static inline double cpu_now(void)
{
    return bench_clock(CLOCK_PROCESS_CPUTIME_ID);
}

#endif
