/* Bit interleaving for the space-filling curves (the converter's Hilbert order, tetpack-mpi's Morton
 * keys): one definition, so both cut space the same way. */
#ifndef TPK_SPREAD_BITS_H
#define TPK_SPREAD_BITS_H

#include <stdint.h>

/* The low 21 bits of x spread out so that bit i lands at bit 3i. */
static inline uint64_t tpk_spread_bits3(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

#endif
