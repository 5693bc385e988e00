/* The library-defect screen of the fuzz targets (library_defect.h). */
#define _GNU_SOURCE
#include "library_defect.h"

#include <errno.h>
#include <execinfo.h>
#include <regex.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

/* Frames of the machinery around a fault, skipped to find whose code faulted. */
static int machinery(const char *frame)
{
    static const char *const marks[] = {"__interceptor_", "__asan", "__sanitizer", "__ubsan", "__lsan", "fuzzer::",
                                        "libclang_rt", "compiler-rt", "/sysdeps/", "/string/", "libc.so",
                                        "/libc-", "__libc_", "LLVMFuzzer", "/malloc/", "(memcpy+", "(__memcpy", "(__memmove"};
    for (size_t i = 0; i < sizeof marks / sizeof marks[0]; i++)
        if (strstr(frame, marks[i]))
            return 1;
    /* the sanitizer runtime linked into the target itself: "in malloc (/path/fuzz_x+0x1b0a8e)" */
    static const char *const calls[] = {" in malloc ", " in calloc ", " in realloc ", " in free ", " in memcpy ",
                                        " in memmove ", " in memset ", " in strlen ", " in operator new"};
    for (size_t i = 0; i < sizeof calls / sizeof calls[0]; i++)
        if (strstr(frame, calls[i]))
            return 1;
    return 0;
}

static int names_library(const char *frame, const char *libraries)
{
    for (const char *at = libraries; *at;) {
        size_t n = strcspn(at, "|");
        char name[64];
        snprintf(name, sizeof name, "%.*s", (int)n, at);
        if (n && strstr(frame, name))
            return 1;
        at += n + (at[n] == '|');
    }
    return 0;
}

/* An allocator's entry point as a frame: the sanitizer's "in malloc (...)" form is machinery() already;
 * glibc's form "fuzz_x(malloc+0x10e)" follows frames of the sanitizer allocator that have no name. */
static int allocator_entry(const char *frame)
{
    static const char *const entries[] = {"(malloc+", "(calloc+", "(realloc+", "(free+", "(posix_memalign+"};
    for (size_t i = 0; i < sizeof entries / sizeof entries[0]; i++)
        if (strstr(frame, entries[i]))
            return 1;
    return 0;
}

/* 1 when the report's first frame that is not machinery names one of the libraries. A stack that begins
 * inside the allocator (the alarm struck there) is read from the allocator's caller on. */
static int report_blames(FILE *report, const char *libraries)
{
    regex_t frame;
    /* a sanitizer's "    #3 0x7f.. in H5C_protect (/lib/.../libhdf5_serial.so.103+0x8e659)", or glibc's
     * "/lib/.../libhdf5_serial.so.103(H5F__accum_read+0x1ff)[0x7f..]" */
    if (regcomp(&frame, "^ *#[0-9]+ 0x[0-9a-f]+ |^[^ ]+\\(.*\\) ?\\[0x[0-9a-f]+\\]$", REG_EXTENDED | REG_NOSUB) != 0)
        return 0;
    enum { most = 64, top = 8 }; /* frames read; how deep an allocator entry may lie to be the stack's start */
    static char frames[most][512];
    int n = 0, from = 0, blamed = 0;
    char line[4096];
    while (n < most && fgets(line, sizeof line, report)) {
        line[strcspn(line, "\n")] = 0;
        if (regexec(&frame, line, 0, NULL, 0) == 0)
            snprintf(frames[n++], sizeof frames[0], "%.*s", (int)sizeof frames[0] - 1, line); /* a frame cut, not an error */
    }
    for (int i = 0; i < n && i < top; i++)
        if (allocator_entry(frames[i]))
            from = i + 1;
    for (int i = from; i < n; i++)
        if (!machinery(frames[i])) {
            blamed = names_library(frames[i], libraries);
            break;
        }
    regfree(&frame);
    return blamed;
}

/* The sanitizers' death callback, which libFuzzer sets to save the input as a finding: in the child,
 * nothing (the parent decides). Weak: absent without a sanitizer (the ctest replay of the corpus). */
void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

static void no_artifact(void)
{
}

/* A fault in the child, or its time running out: its stack as glibc writes it ("module(symbol+offset)
 * [address]", no allocation), then the end by exit status 99. The two innermost frames are this handler
 * and the kernel's return trampoline. (libFuzzer's and the sanitizers' handlers would save the input as a
 * finding.) At the alarm the stack says whose loop the time went to: a library that keeps allocating
 * small blocks from a damaged file's counts (HDF5's free lists; its allocations past the address-space
 * bound fail, and it goes on) is blamed like a library crash. */
static void fault(int sig)
{
    (void)sig;
    void *frames[64];
    int n = backtrace(frames, 64);
    if (n > 2)
        backtrace_symbols_fd(frames + 2, n - 2, 2);
    _exit(99);
}

static long mapped_bytes(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0;
    if (f) {
        if (fscanf(f, "%ld", &pages) != 1)
            pages = 0;
        fclose(f);
    }
    return pages * sysconf(_SC_PAGESIZE);
}

void tpk_fuzz_limit_address_space(long mb)
{
    struct rlimit limit = {.rlim_cur = (rlim_t)(mapped_bytes() + (mb << 20))};
    limit.rlim_max = RLIM_INFINITY;
    setrlimit(RLIMIT_AS, &limit);
}

int tpk_fuzz_library_defect(void (*read)(void *user), void *user, const char *libraries, int seconds)
{
    FILE *report = tmpfile();
    if (!report)
        return 0;
    fflush(stdout), fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        fclose(report);
        return 0;
    }
    if (pid == 0) {
        dup2(fileno(report), 2);
        if (__sanitizer_set_death_callback)
            __sanitizer_set_death_callback(no_artifact);
        static const int faults[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM};
        for (size_t i = 0; i < sizeof faults / sizeof faults[0]; i++)
            signal(faults[i], fault);
        void *warm[1];
        backtrace(warm, 1); /* loads libgcc's unwinder now, not in the handler */
        alarm((unsigned)seconds);
        read(user);
        _exit(0);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    int blamed = 0;
    if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
        rewind(report);
        blamed = report_blames(report, libraries);
        if (getenv("TPK_FUZZ_SHOW_REPORT")) {
            rewind(report);
            char line[4096];
            fprintf(stderr, "[child ended: status %d, blamed %d]\n", status, blamed);
            while (fgets(line, sizeof line, report))
                fputs(line, stderr);
        }
    }
    fclose(report);
    return blamed;
}
