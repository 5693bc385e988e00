/* Clocks for the benchmarks: wall time, and CPU time of the whole process (all threads), which is the
 * steadier measure on a shared, loaded machine; the median of timings and the PSNR of two images; and
 * what their command lines share: the count of runs, the file opened or the reason it was not. */
#ifndef TPK_BENCH_CLOCK_H
#define TPK_BENCH_CLOCK_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "tetpack.h"

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

static inline int bench_compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of n values (sorts them: v[0] is then the fastest). */
static inline double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, bench_compare_double);
    return v[n / 2];
}

/* PSNR in dB of two byte images of n bytes (99 when equal). */
static inline double bench_psnr(const uint8_t *a, const uint8_t *b, size_t n)
{
    double se = 0;
    for (size_t i = 0; i < n; i++)
        se += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
    return se == 0 ? 99.0 : 10.0 * log10(255.0 * 255.0 / (se / (double)n));
}

/* argv[at] as a count of runs, 1 to 1000; `fallback` when it is absent or out of that range. */
static inline int bench_runs(int argc, char **argv, int at, int fallback)
{
    int runs = argc > at ? atoi(argv[at]) : fallback;
    return runs < 1 || runs > 1000 ? fallback : runs;
}

/* The .tpk at path, opened; NULL, with the file and the reason on stderr, when it cannot be. */
static inline tpk_file *bench_open_file(const char *path)
{
    tpk_file *f = NULL;
    char err[512];
    if (tpk_open_path(&f, path, NULL, err, sizeof err) != TPK_OK) {
        fprintf(stderr, "%s: %s\n", path, err);
        return NULL;
    }
    return f;
}

#endif
