/* tpk_tetgen_run_guarded (tetgen_guard.h): TetGen in a forked child. The child writes its result to an
 * anonymous temporary file (a header, then the arrays of tpk_tetgen_output) and TetGen's printing, with
 * its stderr (assert messages), to a second one; the parent waits with a time limit and reads both. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "base/fd_io.h"
#include "tetgen_guard.h"

enum { CHILD_MAGIC = 0x54475431, CHILD_WRITE_FAILED = 3 };

/* What the child writes first; the arrays follow in the order of tpk_tetgen_output. */
typedef struct child_header {
    uint32_t magic;
    int32_t code;
    int32_t point_count, triangle_count;
    int64_t tet_count;
    char message[1024];
} child_header;

static void limit_memory(int64_t bytes)
{
    struct rlimit limit;
    if (TPK_ASAN || bytes <= 0 || getrlimit(RLIMIT_AS, &limit))
        return;
    if (limit.rlim_cur == RLIM_INFINITY || (uint64_t)limit.rlim_cur > (uint64_t)bytes)
        limit.rlim_cur = (rlim_t)bytes;
    setrlimit(RLIMIT_AS, &limit);
}

/* The child: run TetGen, write the result, _exit (never return: no atexit handler, no stdio flush of
 * the parent's buffers, no leak check of the parent's memory). */
static void run_child(const char *switches, const tpk_tetgen_input *in, const tpk_tetgen_guard *guard,
                      int result_fd, int printed_fd)
{
#ifdef __linux__
    prctl(PR_SET_PDEATHSIG, SIGKILL); /* a killed tetpack leaves no TetGen running on */
#endif
    /* Unbuffered, appended: what TetGen printed before a crash is in the file, in order. */
    setvbuf(stdout, NULL, _IONBF, 0);
    fcntl(printed_fd, F_SETFL, fcntl(printed_fd, F_GETFL) | O_APPEND);
    dup2(printed_fd, 2);
    limit_memory(guard->memory_limit);
    child_header h;
    memset(&h, 0, sizeof h);
    tpk_tetgen_output out;
    h.magic = CHILD_MAGIC;
    h.code = tpk_tetgen_run_printing_to(printed_fd, switches, in, &out, h.message, sizeof h.message);
    if (h.code == TPK_TETGEN_OUT_OF_MEMORY && !TPK_ASAN && guard->memory_limit > 0) {
        size_t at = strlen(h.message);
        snprintf(h.message + at, sizeof h.message - at, "; TetGen's process may use at most %.3g GiB of "
                 "address space", (double)guard->memory_limit / (1024.0 * 1024.0 * 1024.0));
    }
    h.point_count = out.point_count, h.tet_count = out.tet_count, h.triangle_count = out.triangle_count;
    int failed = tpk_fd_write_all(result_fd, &h, sizeof h) ||
                 tpk_fd_write_all(result_fd, out.points, sizeof(double) * 3 * (size_t)out.point_count) ||
                 tpk_fd_write_all(result_fd, out.tets, sizeof(int32_t) * 4 * (size_t)out.tet_count) ||
                 tpk_fd_write_all(result_fd, out.triangles, sizeof(int32_t) * 3 * (size_t)out.triangle_count);
    _exit(failed ? CHILD_WRITE_FAILED : 0);
}

static int read_array(FILE *f, void **dst, size_t size)
{
    *dst = malloc(size ? size : 1);
    return *dst && fread(*dst, 1, size, f) == size ? 0 : -1;
}

/* The child's result file into *out: counts checked against the file's size. */
static int read_result(FILE *f, tpk_tetgen_output *out, char *message, size_t cap)
{
    child_header h;
    struct stat st;
    rewind(f);
    if (fstat(fileno(f), &st) || fread(&h, sizeof h, 1, f) != 1 || h.magic != CHILD_MAGIC)
        goto broken;
    h.message[sizeof h.message - 1] = 0;
    if (h.code) {
        snprintf(message, cap, "%s", h.message);
        return h.code;
    }
    size_t points = sizeof(double) * 3 * (size_t)h.point_count, tets = sizeof(int32_t) * 4 * (size_t)h.tet_count,
           triangles = sizeof(int32_t) * 3 * (size_t)h.triangle_count;
    if (h.point_count < 0 || h.tet_count < 0 || h.triangle_count < 0 ||
        (uint64_t)st.st_size != sizeof h + points + tets + triangles)
        goto broken;
    out->point_count = h.point_count, out->tet_count = h.tet_count, out->triangle_count = h.triangle_count;
    if (read_array(f, (void **)&out->points, points) || read_array(f, (void **)&out->tets, tets) ||
        read_array(f, (void **)&out->triangles, triangles)) {
        tpk_tetgen_output_free(out);
        snprintf(message, cap, "out of memory for TetGen's result (%d points, %lld tets)", h.point_count,
                 (long long)h.tet_count);
        return TPK_TETGEN_OUT_OF_MEMORY;
    }
    return 0;
broken:
    snprintf(message, cap, "TetGen's process ended without a complete result");
    return TPK_TETGEN_CRASHED;
}

static double seconds_since(const struct timespec *start)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)(now.tv_sec - start->tv_sec) + 1e-9 * (double)(now.tv_nsec - start->tv_nsec);
}

/* Wait for the child; kill it past the time limit. Returns its wait status, with *timed_out set. */
static int wait_child(pid_t pid, const tpk_tetgen_guard *guard, int *timed_out)
{
    struct timespec start, nap = {0, 1000000};
    clock_gettime(CLOCK_MONOTONIC, &start);
    int status = 0, shown = -1;
    *timed_out = 0;
    for (;;) {
        /* The progress line first, so a stage that ends at once still says it ran. */
        double spent = seconds_since(&start);
        if (guard->progress && (int)spent != shown) {
            shown = (int)spent;
            fprintf(stderr, "\r\033[K[tetpack] TetGen: %s... %d s", guard->what, shown);
            if (guard->time_limit > 0)
                fprintf(stderr, " (of at most %g)", guard->time_limit);
            fflush(stderr);
        }
        pid_t got = waitpid(pid, &status, WNOHANG);
        if (got == pid || (got < 0 && errno != EINTR))
            break;
        if (guard->time_limit > 0 && spent > guard->time_limit && !*timed_out) {
            kill(pid, SIGKILL);
            *timed_out = 1;
        }
        nanosleep(&nap, NULL);
        if (nap.tv_nsec < 50000000) /* short runs return quickly, long ones cost no CPU */
            nap.tv_nsec *= 2;
    }
    if (guard->progress && shown >= 0)
        fprintf(stderr, "\r\033[K");
    return status;
}

static const char *signal_name(int sig)
{
    switch (sig) {
    case SIGSEGV: return "SIGSEGV, a bad memory access";
    case SIGABRT: return "SIGABRT, a failed assertion or abort";
    case SIGBUS: return "SIGBUS";
    case SIGFPE: return "SIGFPE";
    case SIGILL: return "SIGILL";
    case SIGKILL: return "SIGKILL, killed from outside: the system's out-of-memory killer?";
    case SIGTERM: return "SIGTERM";
    default: return "a signal";
    }
}

/* A message for a child that did not finish normally, with what TetGen printed last. */
static int describe_end(int status, int timed_out, const tpk_tetgen_guard *guard, FILE *printed, char *message,
                        size_t cap)
{
    char said[600] = "", text[8192];
    struct stat st;
    /* The last lines are at the end: read the file's tail. */
    long from = !fstat(fileno(printed), &st) && st.st_size > (off_t)sizeof text ? (long)(st.st_size - (off_t)sizeof text) : 0;
    size_t got = fseek(printed, from, SEEK_SET) ? 0 : fread(text, 1, sizeof text, printed);
    tpk_tetgen_last_words(text, got, said, sizeof said);
    const char *sep = said[0] ? "; it said: " : "";
    if (timed_out) {
        snprintf(message, cap, "TetGen ran past the time limit of %g s while %s and was stopped "
                 "(--tetgen-time-limit raises it)%s%s", guard->time_limit, guard->what, sep, said);
        return TPK_TETGEN_TIMED_OUT;
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == CHILD_WRITE_FAILED) {
        snprintf(message, cap, "TetGen's process could not write its result while %s (disk full?)", guard->what);
        return TPK_TETGEN_NOT_STARTED;
    }
    if (WIFSIGNALED(status))
        snprintf(message, cap, "TetGen crashed (signal %d, %s) while %s%s%s", WTERMSIG(status),
                 signal_name(WTERMSIG(status)), guard->what, sep, said);
    else
        snprintf(message, cap, "TetGen crashed (its process exited with status %d) while %s%s%s",
                 WIFEXITED(status) ? WEXITSTATUS(status) : -1, guard->what, sep, said);
    return TPK_TETGEN_CRASHED;
}

int tpk_tetgen_run_guarded(const char *switches, const tpk_tetgen_input *in, const tpk_tetgen_guard *guard,
                           tpk_tetgen_output *out, char *message, size_t cap)
{
    memset(out, 0, sizeof *out);
    if (cap)
        message[0] = 0;
    FILE *result = tmpfile(), *printed = tmpfile();
    int code = TPK_TETGEN_NOT_STARTED;
    if (!result || !printed) {
        snprintf(message, cap, "cannot create a temporary file for TetGen's result: %s", strerror(errno));
        goto done;
    }
    fflush(NULL); /* the child must not write the parent's buffered output a second time */
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(message, cap, "cannot start a process for TetGen: %s", strerror(errno));
        goto done;
    }
    if (pid == 0)
        run_child(switches, in, guard, fileno(result), fileno(printed));
    int timed_out, status = wait_child(pid, guard, &timed_out);
    if (!timed_out && WIFEXITED(status) && WEXITSTATUS(status) == 0)
        code = read_result(result, out, message, cap);
    else
        code = describe_end(status, timed_out, guard, printed, message, cap);
done:
    if (result)
        fclose(result);
    if (printed)
        fclose(printed);
    return code;
}
