/* The large-block reuse of tools/base/parallel.c that the convert stages share: a freed block serves the
 * next request it fits (at least half its size), the smallest such first; a request no kept block fits
 * frees all but the largest; tpk_calloc_large zeroes a reused (dirty) block; tpk_release_kept empties
 * the list. Pointers are compared, not timed: reuse is what saves the page faults. */
#include <stdint.h>
#include <string.h>

#include "base/parallel.h"
#include "harness.h"

#define MIB ((size_t)1 << 20)

TPK_TEST(reuse_fitting_block)
{
    tpk_release_kept();
    char *a = tpk_alloc_large(8 * MIB);
    CHECK(a != NULL);
    memset(a, 0x5a, 8 * MIB);
    tpk_free_large(a, 8 * MIB);
    char *b = tpk_alloc_large(5 * MIB); /* fits: 5 MiB is at least half of 8 */
    CHECK(b == a);
    tpk_free_large(b, 8 * MIB);
    int *z = tpk_calloc_large(MIB, sizeof *z); /* 4 MiB from the dirty 8 MiB block, zeroed */
    CHECK(z == (int *)a);
    int nonzero = 0;
    for (size_t i = 0; i < MIB; i++)
        nonzero += z[i] != 0;
    CHECK_EQ_INT(nonzero, 0);
    tpk_free_large(z, 8 * MIB);
    tpk_release_kept();
}

TPK_TEST(reuse_smallest_fit_and_miss_keeps_largest)
{
    tpk_release_kept();
    char *big = tpk_alloc_large(40 * MIB), *mid = tpk_alloc_large(12 * MIB), *small = tpk_alloc_large(6 * MIB);
    CHECK(big && mid && small);
    big[0] = mid[0] = small[0] = 1;
    tpk_free_large(big, 40 * MIB);
    tpk_free_large(mid, 12 * MIB);
    tpk_free_large(small, 6 * MIB);
    char *c = tpk_alloc_large(6 * MIB); /* both 6 and 12 MiB fit: the smaller is taken */
    CHECK(c == small);
    char *d = tpk_alloc_large(100 * MIB); /* fits none: mid is freed, big kept */
    CHECK(d != NULL && d != big);
    char *e = tpk_alloc_large(11 * MIB); /* big is more than twice 11 MiB: not taken */
    CHECK(e != NULL && e != big);
    char *f = tpk_alloc_large(30 * MIB); /* big survived both misses */
    CHECK(f == big);
    CHECK(f[0] == 1);
    tpk_free_large(c, 6 * MIB);
    tpk_free_large(d, 100 * MIB);
    tpk_free_large(e, 11 * MIB);
    tpk_free_large(f, 40 * MIB);
    tpk_release_kept();
    char *g = tpk_alloc_large(100 * MIB); /* released: nothing to reuse */
    CHECK(g != NULL);
    tpk_free_large(g, 100 * MIB);
    tpk_release_kept();
}
