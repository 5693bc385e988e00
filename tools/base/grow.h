/* Growing a malloc'ed array by doubling, for lists appended to one item at a time. */
#ifndef TPK_GROW_H
#define TPK_GROW_H

#include <stdint.h>
#include <stdlib.h>

/* `array` (capacity *cap items of `item` bytes) grown by realloc to twice its capacity (`first` when it
 * has none) or to `need`, whichever is more. Returns the array, *cap updated, or NULL when out of
 * memory, `array` and *cap unchanged. Callers call it when need > *cap. */
static inline void *tpk_grow(void *array, int64_t *cap, int64_t need, size_t item, int64_t first)
{
    int64_t grown = *cap > 0 ? 2 * *cap : first;
    if (grown < need)
        grown = need;
    void *p = realloc(array, item * (size_t)grown);
    if (p)
        *cap = grown;
    return p;
}

#endif
