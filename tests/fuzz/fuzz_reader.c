/* Fuzz target for the container reader: open from memory with small limits, verify, load every layout,
 * read every chunk (bounded), close. Any result code is fine; crashes, overreads and leaks are not.
 * Each input is tried as is and with its checksums recomputed, so mutations reach the rules behind them. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "tetpack.h"
#include "tpk_input.h"

/* Recompute the checksums of uncompressed chunks, the directory and the header where they lie in range. */
static void fix_checksums(uint8_t *bytes, size_t size)
{
    tpk_header h;
    if (size < sizeof h)
        return;
    memcpy(&h, bytes, sizeof h);
    if (h.directory_offset <= size && h.chunk_count <= (size - h.directory_offset) / sizeof(tpk_dir_entry)) {
        for (uint64_t i = 0; i < h.chunk_count; i++) {
            tpk_dir_entry e;
            uint8_t *at = bytes + h.directory_offset + i * sizeof e;
            memcpy(&e, at, sizeof e);
            if (e.codec == TPK_CODEC_NONE && e.offset <= size && e.raw_size <= size - e.offset)
                e.checksum = XXH64(bytes + e.offset, e.raw_size, 0);
            memcpy(at, &e, sizeof e);
        }
        h.directory_checksum = XXH64(bytes + h.directory_offset, h.chunk_count * sizeof(tpk_dir_entry), 0);
    }
    memcpy(bytes, &h, sizeof h);
    h.header_checksum = XXH64(bytes, offsetof(tpk_header, header_checksum), 0);
    memcpy(bytes, &h, sizeof h);
}

static void try_input(const uint8_t *data, size_t size)
{
    static const uint32_t flag_sets[3] = {0, TPK_OPEN_VERIFY_ALL, TPK_OPEN_TRUSTED};
    for (int k = 0; k < 3; k++) {
        uint32_t flags = flag_sets[k];
        tpk_open_options options = {.size = sizeof options, .flags = flags,
                                    .limits = {.max_chunks = 256,
                                               .max_chunk_bytes = FUZZ_MAX_CHUNK_BYTES,
                                               .max_total_bytes = 4 * FUZZ_MAX_CHUNK_BYTES}};
        tpk_file *file = NULL;
        char err[256];
        if (tpk_open_memory(&file, data, size, &options, err, sizeof err) != TPK_OK)
            continue;
        tpk_fuzz_use_tpk(file);
        tpk_close(file);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    try_input(data, size);
    uint8_t *fixed = malloc(size ? size : 1); /* exact size: overreads hit the redzone */
    if (!fixed)
        return 0;
    if (size)
        memcpy(fixed, data, size);
    fix_checksums(fixed, size);
    try_input(fixed, size);
    free(fixed);
    return 0;
}
