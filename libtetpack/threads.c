/* One job's shares on threads (internal_threads.h): the start, fall-back and join that the files which
 * split work share, and the count of cores they default to. */
#include <pthread.h>
#include <unistd.h>

#include "internal_threads.h"

int tpki_cores(void)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    return cores < 1 ? 1 : cores > TPKI_THREADS_MAX ? TPKI_THREADS_MAX : (int)cores;
}

typedef struct share {
    void (*fn)(void *arg, int share, int shares);
    void *arg;
    int index, count;
    pthread_t thread;
} share;

static void *share_run(void *p)
{
    share *s = p;
    s->fn(s->arg, s->index, s->count);
    return NULL;
}

void tpki_run_threads(int n, void (*fn)(void *arg, int share, int shares), void *arg)
{
    n = n < 1 ? 1 : n > TPKI_THREADS_MAX ? TPKI_THREADS_MAX : n;
    share s[TPKI_THREADS_MAX];
    for (int i = 0; i < n; i++)
        s[i] = (share){.fn = fn, .arg = arg, .index = i, .count = n};
    int started = 1; /* shares [1, started) have a thread */
    while (started < n && pthread_create(&s[started].thread, NULL, share_run, &s[started]) == 0)
        started++;
    for (int i = started; i < n; i++)
        share_run(&s[i]); /* the shares of threads that could not start */
    share_run(&s[0]);
    for (int i = 1; i < started; i++)
        pthread_join(s[i].thread, NULL);
}
