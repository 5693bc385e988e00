/* What the .tpk fuzz targets do with an input (fuzz_tpk, fuzz_tpk_struct: the same work, so that their
 * coverage compares the mutators alone). Not a target itself (no fuzz_ prefix). */
#ifndef TPK_FUZZ_TPK_INPUT_H
#define TPK_FUZZ_TPK_INPUT_H

#include <stddef.h>
#include <stdint.h>

#include "tetpack.h"

#define FUZZ_MAX_CHUNK_BYTES (1u << 20) /* the open limits of the .tpk targets */

/* Open the bytes as a .tpk (with and without checking every chunk's checksum up front), verify, load
 * every layout, read every field, time and chunk, then run `tetpack check`'s 6xx groups on the handle
 * and, when they recover the tets, the mesh groups on them, as `tetpack check FILE.tpk` does. */
void tpk_fuzz_tpk_input(const uint8_t *data, size_t size);

/* What every .tpk target does with an open handle: verify, load every layout, read every field's last
 * time and every chunk (decoded and viewed). */
void tpk_fuzz_use_tpk(tpk_file *file);

#endif
