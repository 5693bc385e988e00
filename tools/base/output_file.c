/* Output files of the tools: checked up front, written unnamed (O_TMPFILE) and linked into place whole,
 * or, where the filesystem cannot, under a temporary name that a fatal signal removes (output_file.h). */
#define _GNU_SOURCE /* O_TMPFILE (Linux) */
#include "output_file.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* ---- the checks before any work --------------------------------------------------------------------- */

static const char *kind_of(mode_t mode)
{
    if (S_ISDIR(mode))
        return "a directory";
    if (S_ISCHR(mode))
        return "a character device";
    if (S_ISBLK(mode))
        return "a block device";
    if (S_ISFIFO(mode))
        return "a FIFO";
    if (S_ISSOCK(mode))
        return "a socket";
    if (S_ISLNK(mode))
        return "a symbolic link";
    return "not a regular file";
}

/* The directory `path` is in ("." for a bare name), into dir[cap]; -1 when it does not fit. */
static int parent_dir(const char *path, char *dir, size_t cap)
{
    const char *slash = strrchr(path, '/');
    size_t len = !slash ? 0 : slash == path ? 1 : (size_t)(slash - path);
    if (len + 2 > cap)
        return -1;
    if (len == 0)
        memcpy(dir, ".", 2);
    else {
        memcpy(dir, path, len);
        dir[len] = 0;
    }
    return 0;
}

static int check_directory(const char *arg, const char *path, tpk_diag *diag)
{
    char dir[PATH_MAX];
    struct stat st;
    if (parent_dir(path, dir, sizeof dir) != 0)
        return tpk_diag_fail(diag, "%s '%s': the path is too long", arg, path);
    if (stat(dir, &st) != 0)
        return tpk_diag_fail(diag, "%s '%s': the directory '%s' does not exist (%s)", arg, path, dir, strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return tpk_diag_fail(diag, "%s '%s': '%s' is not a directory", arg, path, dir);
    if (access(dir, W_OK | X_OK) != 0)
        return tpk_diag_fail(diag, "%s '%s': cannot create files in the directory '%s' (%s)", arg, path, dir,
                             strerror(errno));
    return 0;
}

/* The output is the same file (device and inode) as one the command reads. */
static int check_not_input(const char *arg, const char *path, const struct stat *out, const tpk_output_input *inputs,
                           size_t count, tpk_diag *diag)
{
    for (size_t i = 0; i < count; i++) {
        const char *file = inputs[i].file ? inputs[i].file : inputs[i].given;
        struct stat st;
        if (stat(file, &st) != 0 || st.st_dev != out->st_dev || st.st_ino != out->st_ino)
            continue; /* an input that cannot be read is reported when it is read */
        if (!strcmp(file, inputs[i].given))
            return tpk_diag_fail(diag, "%s '%s' is the input file (same file as %s '%s'); choose another output path",
                                 arg, path, inputs[i].arg, inputs[i].given);
        return tpk_diag_fail(diag, "%s '%s' is a file the input reads (same file as '%s', read for %s '%s'); choose "
                             "another output path", arg, path, file, inputs[i].arg, inputs[i].given);
    }
    return 0;
}

int tpk_output_check(const char *arg, const char *path, const tpk_output_input *inputs, size_t count,
                     tpk_diag *diag)
{
    if (!path || !*path)
        return tpk_diag_fail(diag, "%s is empty; expected a file path", arg);
    struct stat st;
    if (stat(path, &st) == 0) { /* follows links: a link to an input is that input */
        if (S_ISDIR(st.st_mode))
            return tpk_diag_fail(diag, "%s '%s' is a directory; expected a file path", arg, path);
        if (check_not_input(arg, path, &st, inputs, count, diag) != 0)
            return -1;
    } else if (errno != ENOENT) {
        return tpk_diag_fail(diag, "%s '%s': %s", arg, path, strerror(errno));
    } else if (path[strlen(path) - 1] == '/') {
        return tpk_diag_fail(diag, "%s '%s' names a directory (ends with '/'); expected a file path", arg, path);
    }
    /* Putting the output in place replaces what is there: only ever a regular file (never a device
     * such as /dev/null, a FIFO, or a symbolic link, which would be replaced rather than followed). */
    if (lstat(path, &st) == 0 && !S_ISREG(st.st_mode))
        return tpk_diag_fail(diag, "%s '%s' is %s; tetpack replaces only regular files", arg, path,
                             kind_of(st.st_mode));
    return check_directory(arg, path, diag);
}

/* ---- named temporary files and fatal signals -------------------------------------------------------- */

/* Named temporary files that exist now, removed by a fatal signal. Static buffers, not pointers, so the
 * handler never reads freed memory; a slot is published by `temp_used` after its name is written. */
#define TEMP_SLOTS 4
static char temp_names[TEMP_SLOTS][PATH_MAX];
static volatile sig_atomic_t temp_used[TEMP_SLOTS];
static const int fatal_signals[] = {SIGINT, SIGTERM, SIGHUP};

static void remove_temps_and_die(int sig)
{
    int saved = errno;
    for (int i = 0; i < TEMP_SLOTS; i++)
        if (temp_used[i])
            unlink(temp_names[i]);
    errno = saved;
    raise(sig); /* SA_RESETHAND restored the default action: this ends the process as the signal would */
}

/* Installed once, only over the default action (a signal the caller ignores, as nohup does, stays
 * ignored). */
static void install_handlers(void)
{
    static int installed;
    if (installed)
        return;
    installed = 1;
    for (size_t i = 0; i < sizeof fatal_signals / sizeof fatal_signals[0]; i++) {
        struct sigaction old, act;
        if (sigaction(fatal_signals[i], NULL, &old) != 0 || old.sa_handler != SIG_DFL)
            continue;
        memset(&act, 0, sizeof act);
        act.sa_handler = remove_temps_and_die;
        act.sa_flags = SA_RESETHAND;
        sigemptyset(&act.sa_mask);
        sigaction(fatal_signals[i], &act, NULL);
    }
}

/* Block the fatal signals while a named file is created and registered, so none comes in between. */
static void block_fatal_signals(sigset_t *old)
{
    sigset_t set;
    sigemptyset(&set);
    for (size_t i = 0; i < sizeof fatal_signals / sizeof fatal_signals[0]; i++)
        sigaddset(&set, fatal_signals[i]);
    pthread_sigmask(SIG_BLOCK, &set, old);
}

static void register_temp(const char *name)
{
    install_handlers();
    for (int i = 0; i < TEMP_SLOTS; i++)
        if (!temp_used[i]) {
            snprintf(temp_names[i], sizeof temp_names[i], "%s", name);
            temp_used[i] = 1;
            return;
        }
}

static void forget_temp(const char *name)
{
    for (int i = 0; i < TEMP_SLOTS; i++)
        if (temp_used[i] && !strcmp(temp_names[i], name))
            temp_used[i] = 0;
}

/* Remove our named temporary file (if any) and forget it. */
static void drop_temp(tpk_output *o)
{
    if (!o->temp)
        return;
    unlink(o->temp);
    forget_temp(o->temp);
    free(o->temp);
    o->temp = NULL;
}

/* "<path>.tmp.XXXXXX", the X's left for mkstemp (`fill` 0) or replaced by 6 fresh characters for
 * linkat, which has no such template; -1 when it does not fit. */
static int temp_name(const char *path, int fill, char *name, size_t cap)
{
    static const char letters[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    static unsigned long counter;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    unsigned long long v = (unsigned long long)ts.tv_nsec ^ ((unsigned long long)getpid() << 20) ^ (++counter * 7919);
    int n = snprintf(name, cap, "%s.tmp.XXXXXX", path);
    if (n < 0 || (size_t)n >= cap)
        return -1;
    for (int i = n - 6; fill && i < n; i++, v /= 62)
        name[i] = letters[v % 62];
    return 0;
}

/* Create a named temporary file beside the target (the fallback where O_TMPFILE is not supported). */
static int open_named(tpk_output *o, tpk_diag *diag)
{
    char name[PATH_MAX];
    if (temp_name(o->path, 0, name, sizeof name) != 0)
        return tpk_diag_fail(diag, "%s: the path is too long", o->path);
    sigset_t old;
    block_fatal_signals(&old);
    o->fd = mkstemp(name);
    int saved = errno;
    if (o->fd >= 0) {
        register_temp(name);
        o->temp = strdup(name);
    }
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (o->fd < 0)
        return tpk_diag_fail(diag, "%s: cannot create a temporary file beside it: %s", o->path, strerror(saved));
    if (!o->temp) {
        unlink(name);
        forget_temp(name);
        return tpk_diag_fail(diag, "%s: out of memory", o->path);
    }
    return 0;
}

/* ---- open, commit, abort ---------------------------------------------------------------------------- */

/* An unnamed file in the target's directory: it has no name until commit links it in, so a process
 * killed before that (even by SIGKILL) leaves nothing. Linking needs /proc/self/fd. The test hook
 * TPK_TEST_OUTPUT_NAMED=1 takes the named fallback, as on a filesystem without O_TMPFILE. */
static int open_unnamed(tpk_output *o)
{
#ifdef O_TMPFILE
    const char *named = getenv("TPK_TEST_OUTPUT_NAMED");
    char dir[PATH_MAX];
    if ((named && *named == '1') || access("/proc/self/fd", X_OK) != 0 ||
        parent_dir(o->path, dir, sizeof dir) != 0)
        return -1;
    o->fd = open(dir, O_TMPFILE | O_WRONLY | O_CLOEXEC, 0644);
    return o->fd >= 0 ? 0 : -1;
#else
    (void)o;
    return -1;
#endif
}

int tpk_output_open(tpk_output *o, const char *path, tpk_diag *diag)
{
    memset(o, 0, sizeof *o);
    o->fd = -1;
    if (!path || !*path)
        return tpk_diag_fail(diag, "no output path given");
    o->path = strdup(path);
    if (!o->path)
        return tpk_diag_fail(diag, "%s: out of memory", path);
    int rc = open_unnamed(o) == 0 ? 0 : open_named(o, diag);
    if (rc == 0)
        (void)fchmod(o->fd, 0644); /* readable by others, as a data file is meant to be (umask aside) */
    else
        tpk_output_abort(o);
    return rc;
}

FILE *tpk_output_stream(tpk_output *o, tpk_diag *diag)
{
    if (o->stream)
        return o->stream;
    o->stream = fdopen(o->fd, "wb");
    if (!o->stream) {
        tpk_diag_fail(diag, "%s: %s", o->path, strerror(errno));
        return NULL;
    }
    setvbuf(o->stream, NULL, _IOFBF, 1 << 20);
    return o->stream;
}

/* Test hook (tests/cli/outputs.sh): with TPK_TEST_OUTPUT_HOLD=FLAG, a complete output waits here, just
 * before it is put in place: FLAG is created, and the process waits while it exists. A test kills the
 * process at that moment, or removes FLAG to let it go on, with no timing involved. */
static void hold_for_test(void)
{
    const char *flag = getenv("TPK_TEST_OUTPUT_HOLD");
    if (!flag || !*flag)
        return;
    int fd = open(flag, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd >= 0)
        close(fd);
    const struct timespec tick = {0, 10 * 1000 * 1000};
    while (fd >= 0 && access(flag, F_OK) == 0)
        nanosleep(&tick, NULL);
}

static int rename_into_place(tpk_output *o)
{
    if (rename(o->temp, o->path) != 0)
        return errno;
    forget_temp(o->temp);
    free(o->temp);
    o->temp = NULL;
    return 0;
}

/* Give the unnamed file its name: straight at the path when nothing is there, else under a temporary
 * name renamed over the old file (rename is what replaces atomically). */
static int link_into_place(tpk_output *o)
{
    char proc[64], name[PATH_MAX];
    snprintf(proc, sizeof proc, "/proc/self/fd/%d", o->fd);
    if (linkat(AT_FDCWD, proc, AT_FDCWD, o->path, AT_SYMLINK_FOLLOW) == 0)
        return 0;
    if (errno != EEXIST)
        return errno;
    for (int attempt = 0; attempt < 100 && !o->temp; attempt++) {
        if (temp_name(o->path, 1, name, sizeof name) != 0)
            return ENAMETOOLONG;
        sigset_t old;
        block_fatal_signals(&old);
        int linked = linkat(AT_FDCWD, proc, AT_FDCWD, name, AT_SYMLINK_FOLLOW) == 0;
        int saved = errno;
        if (linked) {
            register_temp(name);
            o->temp = strdup(name);
        }
        pthread_sigmask(SIG_SETMASK, &old, NULL);
        if (linked && !o->temp) {
            unlink(name);
            forget_temp(name);
            return ENOMEM;
        }
        if (!linked && saved != EEXIST)
            return saved;
    }
    return o->temp ? rename_into_place(o) : EEXIST;
}

/* Something other than a regular file may have appeared at the path since the check: never replace it. */
static int still_replaceable(const tpk_output *o, tpk_diag *diag)
{
    struct stat st;
    if (lstat(o->path, &st) == 0 && !S_ISREG(st.st_mode))
        return tpk_diag_fail(diag, "%s is now %s; tetpack replaces only regular files (nothing was written)", o->path,
                             kind_of(st.st_mode));
    return 0;
}

int tpk_output_commit(tpk_output *o, tpk_diag *diag)
{
    int err = 0;
    if (o->stream && fflush(o->stream) != 0)
        err = errno ? errno : EIO;
    if (!err && fsync(o->fd) != 0 && errno != EINVAL) /* EINVAL: a file system that cannot sync */
        err = errno;
    if (!err)
        hold_for_test();
    if (!err && still_replaceable(o, diag) != 0) {
        tpk_output_abort(o);
        return -1;
    }
    if (!err)
        err = o->temp ? rename_into_place(o) : link_into_place(o);
    if (o->stream && fclose(o->stream) != 0 && !err)
        err = errno ? errno : EIO;
    else if (!o->stream && o->fd >= 0 && close(o->fd) != 0 && !err)
        err = errno;
    o->stream = NULL;
    o->fd = -1;
    if (err)
        tpk_diag_fail(diag, "%s: write failed: %s (nothing was written)", o->path, strerror(err));
    tpk_output_abort(o); /* what is left: a temporary name (on failure) and the path copy */
    return err ? -1 : 0;
}

void tpk_output_abort(tpk_output *o)
{
    if (o->stream)
        fclose(o->stream);
    else if (o->fd >= 0)
        close(o->fd);
    o->stream = NULL;
    o->fd = -1;
    drop_temp(o);
    free(o->path);
    o->path = NULL;
}
