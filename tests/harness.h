/* A minimal test harness: TPK_TEST(name) defines a test that registers itself; CHECK* report the
 * failing expression with file and line and fail the test. `<exe> NAME` runs one test, `<exe>` all. */
#ifndef TPK_HARNESS_H
#define TPK_HARNESS_H

#include <stdio.h>
#include <stdlib.h>

typedef void (*tpk_test_fn)(void);
void tpk_test_register(const char *name, tpk_test_fn fn);
extern int tpk_test_failures;

/* Exit status of a run in which a test skipped and none failed: ctest's SKIP_RETURN_CODE
 * (tests/CMakeLists.txt), so a skip shows as "Skipped", never as "Passed". */
#define TPK_TEST_SKIPPED 77
/* Record that the running test could not run here (an optional component is missing): prints "SKIP:
 * why". Under TETPACK_REQUIRE_ALL=1 (CI, which has every component) a skip is a failure instead. */
void tpk_test_skip(const char *why);
#define TPK_SKIP(why)       \
    do {                    \
        tpk_test_skip(why); \
        return;             \
    } while (0)

/* Path of a file under ../shared/data (static buffer per call site is not needed: returns a
 * pointer into a small ring of buffers). */
const char *tpk_data_path(const char *relative);
/* A fresh temporary directory for this test process (created on first use, removed at exit). */
const char *tpk_temp_dir(void);
/* tpk_temp_dir() + "/" + name, in a ring buffer. */
const char *tpk_temp_path(const char *name);

#define TPK_TEST(name)                                                      \
    static void test_##name(void);                                          \
    __attribute__((constructor)) static void register_##name(void)          \
    {                                                                       \
        tpk_test_register(#name, test_##name);                              \
    }                                                                       \
    static void test_##name(void)

#define CHECK(expr)                                                                   \
    do {                                                                              \
        if (!(expr)) {                                                                \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #expr);  \
            tpk_test_failures++;                                                      \
            return;                                                                   \
        }                                                                             \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                                      \
    do {                                                                                        \
        long long check_a_ = (long long)(a), check_b_ = (long long)(b);                         \
        if (check_a_ != check_b_) {                                                             \
            fprintf(stderr, "%s:%d: CHECK failed: %s == %s (%lld vs %lld)\n", __FILE__, __LINE__, \
                    #a, #b, check_a_, check_b_);                                                \
            tpk_test_failures++;                                                                \
            return;                                                                             \
        }                                                                                       \
    } while (0)

#define CHECK_MSG(expr, ...)                                                          \
    do {                                                                              \
        if (!(expr)) {                                                                \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #expr);  \
            fprintf(stderr, __VA_ARGS__);                                             \
            fprintf(stderr, "\n");                                                    \
            tpk_test_failures++;                                                      \
            return;                                                                   \
        }                                                                             \
    } while (0)

#endif
