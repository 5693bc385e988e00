/* Fuzz target for the container reader: open from memory with small limits, verify, load every layout,
 * read every chunk (bounded), close. Any result code is fine; crashes, overreads and leaks are not.
 * Each input is tried as is and with its checksums recomputed, so mutations reach the rules behind them. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "tetpack.h"

#define FUZZ_MAX_CHUNK_BYTES (1u << 20)

static void read_chunks(tpk_file *file)
{
    tpk_file_info info;
    if (tpk_get_info(file, &info) != TPK_OK)
        return;
    for (uint64_t i = 0; i < info.chunk_count; i++) {
        tpk_dir_entry e;
        if (tpk_get_chunk(file, i, &e) != TPK_OK || e.raw_size > FUZZ_MAX_CHUNK_BYTES)
            continue;
        void *dst = malloc(e.raw_size ? (size_t)e.raw_size : 1);
        if (dst)
            tpk_read_chunk(file, i, dst, e.raw_size);
        free(dst);
        const void *view;
        uint64_t view_size;
        tpk_view_chunk(file, i, &view, &view_size);
    }
}

static void use_file(tpk_file *file)
{
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    tpk_verify(file);
    for (int k = 0; k < 3; k++) {
        tpk_mesh_arrays arrays;
        tpk_load_arrays(file, layouts[k], NULL, 0, &arrays);
    }
    for (uint32_t f = 0; f < tpk_field_count(file); f++) {
        tpk_field_desc desc;
        double time;
        if (tpk_get_field(file, f, &desc) == TPK_OK)
            tpk_get_time(file, desc.step_count - 1, &time);
    }
    read_chunks(file);
}

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
        use_file(file);
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
