/* Reading a file in a child process (isolate.h). The child writes records to a pipe: 'W' + length + text
 * for each warning as it comes, then one 'R' with the reader's return, the diag (message, field
 * problems) and, on success, the mesh: the struct, then each array its counts call for. The parent reads
 * them as they come (no size limit, nothing on disk), then waits for the child: a child that died, or
 * whose stream ended early, is an error however much arrived. */
#define _POSIX_C_SOURCE 200809L
#include "isolate.h"

#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "base/fd_io.h"
#include "tetpack_format.h"

int tpk_isolate_enabled(void)
{
    const char *v = getenv("TETPACK_ISOLATE");
    return !(v && strcmp(v, "0") == 0);
}

/* ---- the child's side ---- */

static void child_warn(void *user, const char *text)
{
    int fd = *(int *)user;
    uint32_t len = (uint32_t)strlen(text);
    char tag = 'W';
    if (tpk_fd_write_all(fd, &tag, 1) || tpk_fd_write_all(fd, &len, sizeof len) || tpk_fd_write_all(fd, text, len))
        _exit(3);
}

/* Lengths of a mesh's arrays, from its counts (the same on both sides). */
typedef struct mesh_lengths {
    int64_t conn, faces, face_offsets;
} mesh_lengths;

static int64_t field_length(const tpk_mesh *m, const tpk_src_field *f)
{
    int64_t per = f->association == TPK_ASSOC_POINT ? m->point_count : m->cell_count;
    return (int64_t)f->step_count * per * f->components;
}

#define PUT(ptr, count)                                                                                     \
    do {                                                                                                    \
        if ((ptr) && tpk_fd_write_all(fd, (ptr), sizeof *(ptr) * (size_t)(count)))                                \
            return -1;                                                                                      \
    } while (0)

static int write_mesh(int fd, const tpk_mesh *m)
{
    if (tpk_fd_write_all(fd, m, sizeof *m))
        return -1;
    PUT(m->points, 3 * m->point_count);
    PUT(m->cell_types, m->cell_count);
    PUT(m->cell_offsets, m->cell_count + 1);
    PUT(m->cell_conn, m->cell_offsets ? m->cell_offsets[m->cell_count] : 0);
    PUT(m->face_offsets, m->cell_count + 1);
    PUT(m->faces, m->face_offsets ? m->face_offsets[m->cell_count] : 0);
    for (int i = 0; i < m->field_count; i++) {
        if (tpk_fd_write_all(fd, &m->fields[i], sizeof m->fields[i]))
            return -1;
        PUT(m->fields[i].values, field_length(m, &m->fields[i]));
    }
    PUT(m->times, m->step_count);
    PUT(m->global_point_ids, m->point_count);
    PUT(m->global_cell_ids, m->cell_count);
    return 0;
}

static int write_result(int fd, int rc, const tpk_diag *diag, const tpk_mesh *out)
{
    char tag = 'R';
    int32_t r = rc;
    if (tpk_fd_write_all(fd, &tag, 1) || tpk_fd_write_all(fd, &r, sizeof r) || tpk_fd_write_all(fd, diag, sizeof *diag))
        return -1;
    return rc == 0 && out ? write_mesh(fd, out) : 0;
}

/* ---- the parent's side ---- */

/* Replace *ptr (a flag from the child's struct: NULL or not) by count elements read from fd. */
static int take(int fd, void *ptr_address, size_t element, int64_t count)
{
    void **ptr = ptr_address;
    if (!*ptr)
        return 0;
    *ptr = NULL;
    if (count < 0 || (uint64_t)count > SIZE_MAX / element)
        return -1;
    size_t bytes = element * (size_t)count;
    if (!(*ptr = malloc(bytes ? bytes : 1)))
        return -1;
    return tpk_fd_read_all(fd, *ptr, bytes);
}

#define TAKE(field, count) take(fd, &(field), sizeof *(field), (count))

static int read_mesh(int fd, tpk_mesh *m)
{
    if (tpk_fd_read_all(fd, m, sizeof *m)) {
        memset(m, 0, sizeof *m);
        return -1;
    }
    tpk_src_field *fields = m->fields;
    int field_count = m->field_count;
    m->fields = NULL, m->field_count = 0; /* until read: tpk_mesh_free on failure frees what arrived */
    if (TAKE(m->points, 3 * m->point_count) || TAKE(m->cell_types, m->cell_count) ||
        TAKE(m->cell_offsets, m->cell_count + 1) ||
        TAKE(m->cell_conn, m->cell_offsets ? m->cell_offsets[m->cell_count] : 0) ||
        TAKE(m->face_offsets, m->cell_count + 1) ||
        TAKE(m->faces, m->face_offsets ? m->face_offsets[m->cell_count] : 0))
        return -1;
    if (fields && field_count > 0) {
        if (!(m->fields = calloc((size_t)field_count, sizeof *m->fields)))
            return -1;
        for (int i = 0; i < field_count; i++) {
            if (tpk_fd_read_all(fd, &m->fields[i], sizeof m->fields[i])) {
                m->fields[i].values = NULL;
                return -1;
            }
            m->field_count = i + 1;
            if (TAKE(m->fields[i].values, field_length(m, &m->fields[i])))
                return -1;
        }
    }
    if (TAKE(m->times, m->step_count) || TAKE(m->global_point_ids, m->point_count) ||
        TAKE(m->global_cell_ids, m->cell_count))
        return -1;
    return 0;
}

/* What the child said before its result ended, or where it stopped. */
typedef enum { STREAM_RESULT, STREAM_ENDED } stream_end;

static stream_end read_stream(int fd, tpk_diag *diag, int *rc, tpk_mesh *out, int *result)
{
    for (;;) {
        char tag;
        if (tpk_fd_read_all(fd, &tag, 1))
            return STREAM_ENDED;
        if (tag == 'W') {
            uint32_t len;
            char text[1024];
            if (tpk_fd_read_all(fd, &len, sizeof len) || len >= sizeof text || tpk_fd_read_all(fd, text, len))
                return STREAM_ENDED;
            text[len] = 0;
            tpk_diag_warn(diag, "%s", text);
            continue;
        }
        if (tag != 'R')
            return STREAM_ENDED;
        int32_t r;
        tpk_diag child;
        if (tpk_fd_read_all(fd, &r, sizeof r) || tpk_fd_read_all(fd, &child, sizeof child))
            return STREAM_ENDED;
        *rc = r;
        if (result)
            *result = r;
        if (diag) {
            memcpy(diag->message, child.message, sizeof diag->message);
            diag->message[sizeof diag->message - 1] = 0;
            diag->field_problem_count = child.field_problem_count;
            memcpy(diag->field_problems, child.field_problems, sizeof diag->field_problems);
        }
        if (r == 0 && out && read_mesh(fd, out)) {
            tpk_mesh_free(out);
            return STREAM_ENDED;
        }
        return STREAM_RESULT;
    }
}

/* The child's end as words: "signal 11, SIGSEGV" or "exit status 3". */
static void describe_end(int status, char *buf, size_t cap)
{
    if (WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        const char *name = sig == SIGSEGV ? "SIGSEGV" : sig == SIGABRT ? "SIGABRT" : sig == SIGBUS ? "SIGBUS"
                         : sig == SIGFPE ? "SIGFPE" : sig == SIGILL ? "SIGILL" : sig == SIGKILL ? "SIGKILL" : "";
        snprintf(buf, cap, "signal %d%s%s", sig, *name ? ", " : "", name);
    } else {
        snprintf(buf, cap, "exit status %d", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    }
}

/* The child's address space: what the file could decode to (every byte a deflated chunk, at zlib's
 * largest ratio, 1032:1) plus 1 GiB, so that a library believing a damaged file's sizes fails an
 * allocation instead of taking the machine's memory (HDF5 took 24 GB, then the kernel's OOM killer, for
 * a 14 kB VTKHDF file of fuzz_vtkhdf's campaign; with the limit: a clean error). Not under
 * AddressSanitizer, whose shadow memory needs the whole address space. */
#if defined(__SANITIZE_ADDRESS__)
#define TPK_ISOLATE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TPK_ISOLATE_ASAN 1
#endif
#endif
static void limit_memory(const char *path)
{
#ifndef TPK_ISOLATE_ASAN
    struct stat st;
    if (stat(path, &st) != 0 || st.st_size < 0)
        return;
    double bytes = (double)st.st_size * 1032.0 + 1073741824.0;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) != 0 || (rl.rlim_cur != RLIM_INFINITY && (double)rl.rlim_cur <= bytes))
        return;
    rl.rlim_cur = bytes >= 9.0e18 ? RLIM_INFINITY : (rlim_t)bytes;
    setrlimit(RLIMIT_AS, &rl);
#else
    (void)path;
#endif
}

/* Run the reader (read != NULL) or the probe in a child; *ended gets the child's end as words when it did
 * not finish its stream and exit 0 ("" otherwise). */
static int run_child(int (*read)(const char *, tpk_mesh *, tpk_diag *), int (*probe)(const char *),
                     const char *path, tpk_mesh *out, tpk_diag *diag, char *ended, size_t ended_cap)
{
    ended[0] = 0;
    int fds[2];
    if (pipe(fds) != 0)
        return -2;
    fflush(stdout), fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]), close(fds[1]);
        return -2;
    }
    if (pid == 0) { /* the child: read, send, leave without running the parent's exit handlers */
        close(fds[0]);
        /* A fault of the library ends the child by its signal, which the parent names; under the
         * sanitizers, their handlers would first print a report of a crash that is the point of this. */
        static const int fatal[] = {SIGPIPE, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
        for (size_t i = 0; i < sizeof fatal / sizeof fatal[0]; i++)
            signal(fatal[i], SIG_DFL);
        limit_memory(path);
        int fd = fds[1];
        int rc;
        if (read) {
            tpk_diag mine;
            memset(&mine, 0, sizeof mine);
            mine.lenient_fields = diag ? diag->lenient_fields : 0;
            mine.strict_fields = diag ? diag->strict_fields : 0;
            mine.warn = child_warn;
            mine.warn_user = &fd;
            rc = read(path, out, &mine);
            if (write_result(fd, rc, &mine, out))
                _exit(3);
        } else {
            tpk_diag none;
            memset(&none, 0, sizeof none);
            rc = probe(path);
            if (write_result(fd, rc, &none, NULL))
                _exit(3);
        }
        close(fd);
        _exit(0);
    }
    close(fds[1]);
    int rc = -1, result = 0;
    tpk_diag scratch;
    memset(&scratch, 0, sizeof scratch);
    tpk_diag *into = diag ? diag : &scratch;
    if (out)
        memset(out, 0, sizeof *out);
    stream_end end = read_stream(fds[0], into, &rc, read ? out : NULL, read ? NULL : &result);
    close(fds[0]); /* a child still writing gets SIGPIPE */
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (end != STREAM_RESULT || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        describe_end(status, ended, ended_cap);
        if (out)
            tpk_mesh_free(out);
        return -1;
    }
    return read ? rc : result;
}

int tpk_isolated_read(int (*read)(const char *path, tpk_mesh *out, tpk_diag *diag), const char *what,
                      const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (!tpk_isolate_enabled())
        return read(path, out, diag);
    char ended[64];
    int rc = run_child(read, NULL, path, out, diag, ended, sizeof ended);
    if (rc == -2) /* no pipe or no process: read here, as without isolation */
        return read(path, out, diag);
    if (ended[0])
        return tpk_diag_fail(diag, "%s: the %s library failed reading this file (its process ended with %s): the "
                                   "file is damaged or not what it claims; nothing was read from it",
                             path, what, ended);
    return rc;
}

int tpk_isolated_probe(int (*probe)(const char *path), const char *path)
{
    if (!tpk_isolate_enabled())
        return probe(path);
    char ended[64];
    int found = run_child(NULL, probe, path, NULL, NULL, ended, sizeof ended);
    if (found == -2)
        return probe(path);
    return ended[0] ? 0 : found;
}
