/* Runner for the TPK_TEST harness: `<exe> NAME` runs one test, `<exe>` runs all, `<exe> --list`. */
#define _GNU_SOURCE
#include "harness.h"

#include <dirent.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAX_TESTS 256

static struct {
    const char *name;
    tpk_test_fn fn;
} tests[MAX_TESTS];
static int test_count;
int tpk_test_failures;
static int test_skips;
static char temp_dir[256];

void tpk_test_skip(const char *why)
{
    const char *require = getenv("TETPACK_REQUIRE_ALL");
    if (require && !strcmp(require, "1")) {
        fprintf(stderr, "FAIL (TETPACK_REQUIRE_ALL=1 forbids skips): %s\n", why);
        tpk_test_failures++;
        return;
    }
    printf("SKIP: %s\n", why);
    test_skips++;
}

void tpk_test_register(const char *name, tpk_test_fn fn)
{
    if (test_count < MAX_TESTS) {
        tests[test_count].name = name;
        tests[test_count].fn = fn;
        test_count++;
    }
}

static char *ring_buffer(void)
{
    static char ring[8][1024];
    static int next;
    next = (next + 1) % 8;
    return ring[next];
}

const char *tpk_data_path(const char *relative)
{
    char *buf = ring_buffer();
    snprintf(buf, 1024, "%s/%s", TPK_DATA_DIR, relative);
    return buf;
}

static void remove_tree(const char *path)
{
    DIR *dir = opendir(path);
    if (dir) {
        struct dirent *e;
        while ((e = readdir(dir)) != NULL) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char child[1024];
            snprintf(child, sizeof child, "%s/%s", path, e->d_name);
            struct stat st;
            if (lstat(child, &st) == 0 && S_ISDIR(st.st_mode))
                remove_tree(child);
            else
                unlink(child);
        }
        closedir(dir);
    }
    rmdir(path);
}

static void cleanup_temp(void)
{
    if (temp_dir[0] && !getenv("TPK_KEEP_TEMP"))
        remove_tree(temp_dir);
}

const char *tpk_temp_dir(void)
{
    if (!temp_dir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(temp_dir, sizeof temp_dir, "%s/tpk_test_XXXXXX", base ? base : "/tmp");
        if (!mkdtemp(temp_dir)) {
            perror("mkdtemp");
            exit(2);
        }
        atexit(cleanup_temp);
    }
    return temp_dir;
}

const char *tpk_temp_path(const char *name)
{
    char *buf = ring_buffer();
    snprintf(buf, 1024, "%s/%s", tpk_temp_dir(), name);
    return buf;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--list")) {
        for (int i = 0; i < test_count; i++)
            printf("%s\n", tests[i].name);
        return 0;
    }
    int ran = 0, failed = 0, skipped = 0;
    for (int i = 0; i < test_count; i++) {
        if (argc > 1 && strcmp(argv[1], tests[i].name) != 0)
            continue;
        int before = tpk_test_failures, skips_before = test_skips;
        tests[i].fn();
        ran++;
        if (tpk_test_failures != before) {
            failed++;
            fprintf(stderr, "FAIL %s\n", tests[i].name);
        } else if (test_skips != skips_before) {
            skipped++;
        }
    }
    if (ran == 0) {
        fprintf(stderr, "no test named %s\n", argc > 1 ? argv[1] : "(any)");
        return 2;
    }
    printf("%d passed, %d failed, %d skipped\n", ran - failed - skipped, failed, skipped);
    return failed ? 1 : skipped ? TPK_TEST_SKIPPED : 0;
}
