/* Fuzz target for .tpk files with libFuzzer's own byte mutations: the twin of fuzz_tpk_struct (the same
 * work, tpk_input.h), so that the two compare the mutators. Most mutations break a checksum and stop at
 * open; fuzz_tpk_struct keeps them valid. */
#include "tpk_input.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    tpk_fuzz_tpk_input(data, size);
    return 0;
}
