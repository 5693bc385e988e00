/* Scratch folders and multi-file inputs for the fuzz targets that read by path (support.h). */
#define _XOPEN_SOURCE 700 /* nftw */
#include "support.h"

#include <errno.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char scratch[256];
static char work[300]; /* scratch/work: emptied for each input; scratch keeps what lasts (a fixture) */
static char fresh[400];

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    if (ftw->level > 0)
        remove(path);
    return 0;
}

static void clear(const char *dir)
{
    nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

static void remove_scratch(void)
{
    clear(scratch);
    rmdir(scratch);
}

const char *tpk_fuzz_scratch(void)
{
    if (scratch[0])
        return scratch;
    const char *keep = getenv("TPK_FUZZ_KEEP"); /* ./dev fuzz: leave a finding's files for tetpack */
    const char *base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    if (keep && *keep)
        snprintf(scratch, sizeof scratch, "%s", keep);
    else
        snprintf(scratch, sizeof scratch, "%s/tpk-fuzz-%ld", base, (long)getpid());
    if (mkdir(scratch, 0700) != 0 && errno != EEXIST) {
        perror(scratch);
        abort();
    }
    if (!(keep && *keep))
        atexit(remove_scratch);
    snprintf(work, sizeof work, "%s/work", scratch);
    return scratch;
}

const char *tpk_fuzz_fresh_dir(const char *sub)
{
    tpk_fuzz_scratch();
    clear(work);
    if (mkdir(work, 0700) != 0 && errno != EEXIST) {
        perror(work);
        abort();
    }
    snprintf(fresh, sizeof fresh, "%s%s%s", work, sub ? "/" : "", sub ? sub : "");
    if (sub && mkdir(fresh, 0700) != 0) {
        perror(fresh);
        abort();
    }
    return fresh;
}

static int make_parents(char *path)
{
    for (char *slash = strchr(path + 1, '/'); slash; slash = strchr(slash + 1, '/')) {
        *slash = 0;
        int rc = mkdir(path, 0700);
        *slash = '/';
        if (rc != 0 && errno != EEXIST)
            return -1;
    }
    return 0;
}

int tpk_fuzz_write(const char *path, const void *data, size_t size)
{
    char copy[1024];
    snprintf(copy, sizeof copy, "%s", path);
    if (make_parents(copy) != 0)
        return -1;
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    size_t done = size ? fwrite(data, 1, size, f) : 0;
    return fclose(f) == 0 && done == size ? 0 : -1;
}

/* A relative name of allowed characters, no "..", no empty part, at most 4 levels. */
static int name_allowed(const char *name, size_t length)
{
    if (length == 0 || length > 200 || name[0] == '/' || name[length - 1] == '/')
        return 0;
    int levels = 1;
    for (size_t i = 0; i < length; i++) {
        char c = name[i];
        if (c == '/') {
            if (name[i + 1] == '/' || ++levels > 4)
                return 0;
        } else if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                     c == '_' || c == '-')) {
            return 0;
        }
        if (c == '.' && i + 1 < length && name[i + 1] == '.') /* the name is not NUL-terminated */
            return 0;
    }
    return 1;
}

/* Where the next file mark starts at or after `from` (a mark begins the input or a line), or size. */
static size_t next_mark(const uint8_t *data, size_t size, size_t from)
{
    const size_t mark = strlen(TPK_FUZZ_FILE_MARK);
    for (size_t at = from; at + mark <= size; at++)
        if ((at == 0 || data[at - 1] == '\n') && !memcmp(data + at, TPK_FUZZ_FILE_MARK, mark))
            return at;
    return size;
}

int tpk_fuzz_split_files(const char *dir, const char *first_name, const uint8_t *data, size_t size)
{
    const size_t mark = strlen(TPK_FUZZ_FILE_MARK);
    char path[1024];
    int written = 0;
    size_t end = next_mark(data, size, 0);
    if (end > 0) { /* text before the first mark */
        snprintf(path, sizeof path, "%s/%s", dir, first_name);
        size_t length = end > 0 && data[end - 1] == '\n' && end < size ? end - 1 : end;
        written += tpk_fuzz_write(path, data, length) == 0;
    }
    while (end < size) {
        size_t name_at = end + mark;
        const uint8_t *newline = memchr(data + name_at, '\n', size - name_at);
        size_t body = newline ? (size_t)(newline - data) + 1 : size;
        size_t name_length = (newline ? (size_t)(newline - data) : size) - name_at;
        end = next_mark(data, size, body);
        size_t length = end - body;
        if (end < size && length > 0 && data[end - 1] == '\n')
            length--; /* the newline before the next mark belongs to the mark */
        if (!name_allowed((const char *)data + name_at, name_length))
            continue;
        snprintf(path, sizeof path, "%s/%.*s", dir, (int)name_length, (const char *)data + name_at);
        written += tpk_fuzz_write(path, data + body, length) == 0;
    }
    return written;
}

void tpk_fuzz_ignore(void *user, const char *text)
{
    (void)user;
    (void)text;
}
