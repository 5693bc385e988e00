/* libtetpack private declarations: one job's shares on threads, for the files that split work (range_build.c,
 * recover.c, set_mesh.c). Not installed.
 * Owner: threads.c, which calls no other file of libtetpack (every file may call it). */
#ifndef TPK_INTERNAL_THREADS_H
#define TPK_INTERNAL_THREADS_H

/* The most threads one job runs on. */
#define TPKI_THREADS_MAX 64

/* The online cores (sysconf), in [1, TPKI_THREADS_MAX]. */
int tpki_cores(void);

/* Runs fn(arg, share, shares) once for every share in [0, shares), shares being n clamped to
 * [1, TPKI_THREADS_MAX], and returns when all have returned. Share 0 runs on the calling thread, each
 * other on a thread of its own; when a thread cannot start, no more are started and the shares left run
 * on the calling thread, one after another, before share 0. So every share runs whatever the system
 * allows, but not always at the same time: fn must not wait for another share. */
void tpki_run_threads(int n, void (*fn)(void *arg, int share, int shares), void *arg);

#endif
