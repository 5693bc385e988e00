/* TetGen in a child process (tetgen_child.c): TetGen runs in-process code that can crash (a failed
 * assert, a bad access in its memory pools after a failed Delaunay) or run for hours, and neither a
 * signal nor an abort can be caught by the shim's try/catch. The child runs tpk_tetgen_run and sends the
 * result back through an anonymous file; the parent turns a signal, a time-out or a hit memory limit
 * into a message. */
#ifndef TPK_TETGEN_GUARD_H
#define TPK_TETGEN_GUARD_H

#include <stddef.h>
#include <stdint.h>

#include "tetgen_shim.h"

/* 1 in an AddressSanitizer build, where memory_limit is not applied. */
#if defined(__SANITIZE_ADDRESS__)
#define TPK_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TPK_ASAN 1
#endif
#endif
#ifndef TPK_ASAN
#define TPK_ASAN 0
#endif

typedef struct tpk_tetgen_guard {
    const char *what;     /* for messages and progress: "tetrahedralizing the surface" */
    double time_limit;    /* seconds of wall-clock time before the child is killed; <= 0: none */
    int64_t memory_limit; /* bytes of address space for the child (RLIMIT_AS); <= 0: none. Not applied
                             under AddressSanitizer, whose shadow memory needs terabytes of it. */
    int progress;         /* a line on stderr with the stage and the seconds spent, once a second */
} tpk_tetgen_guard;

/* tpk_tetgen_run in a child process (fork; POSIX). Returns 0 with *out filled (free with
 * tpk_tetgen_output_free), a TetGen code (tetgen_shim.h) with its message, TPK_TETGEN_CRASHED ("TetGen
 * crashed (signal 11, SIGSEGV) while <what>; it said: <its last lines>"), TPK_TETGEN_TIMED_OUT or
 * TPK_TETGEN_NOT_STARTED. Call it before starting threads of one's own, or with none of them holding
 * locks the child needs: the child only runs TetGen (which allocates with malloc/new, fork-safe in
 * glibc), writes with write() and leaves with _exit(), so no atexit handler, leak check or stdio buffer
 * of the parent runs twice. */
int tpk_tetgen_run_guarded(const char *switches, const tpk_tetgen_input *in, const tpk_tetgen_guard *guard,
                           tpk_tetgen_output *out, char *message, size_t cap);

#endif
