/* Wall-clock seconds for stage timings and frame rates (monotonic: never steps back). */
#ifndef TPK_CLOCK_H
#define TPK_CLOCK_H

#include <time.h>

static inline double tpk_now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
