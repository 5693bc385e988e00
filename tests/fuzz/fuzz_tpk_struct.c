/* Structure-aware .tpk fuzzing: a custom mutator (libFuzzer's LLVMFuzzerCustomMutator) that reads the
 * chunk index, changes one thing (a chunk's payload, decoded from zstd first when it is compressed; the
 * header's counts, origin and bounds; a chunk's index and step; a chunk dropped, repeated or its codec
 * switched) and writes the file again with libtetpack's own writer (tpk_writer_open_fd into a memfd), so
 * checksums, alignment and the chunk index are right and mutations get past the container checks into
 * chunk decoding, the layout walks and check's 6xx groups. Inputs it cannot parse, and one mutation in
 * eight, get libFuzzer's plain byte mutations. The work per input is fuzz_tpk's (tpk_input.h). */
#define _GNU_SOURCE /* memfd_create */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>
#include <zstd.h>

#include "tetpack.h"
#include "tpk_input.h"

#define STRUCT_MAX_CHUNKS 64
#define STRUCT_MAX_RAW (1u << 20)

size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size);

typedef struct chunk {
    tpk_chunk_desc desc;
    uint8_t *payload; /* decoded, malloc'd; capacity bytes */
    size_t size, capacity;
} chunk;

typedef struct parsed {
    tpk_header_fields header;
    chunk chunks[STRUCT_MAX_CHUNKS];
    uint64_t count;
} parsed;

static uint64_t next_random(uint64_t *state)
{
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return *state;
}

static void free_parsed(parsed *p)
{
    for (uint64_t i = 0; i < p->count; i++)
        free(p->chunks[i].payload);
    p->count = 0;
}

/* One chunk's decoded bytes, with room to grow (capacity: twice the size, at least 64 bytes). */
static int decode_chunk(const uint8_t *data, size_t size, const tpk_dir_entry *e, chunk *out)
{
    if (e->raw_size > STRUCT_MAX_RAW || e->offset > size || e->stored_size > size - e->offset)
        return -1;
    out->size = (size_t)e->raw_size;
    out->capacity = out->size * 2 + 64;
    if (!(out->payload = malloc(out->capacity)))
        return -1;
    if (e->codec == TPK_CODEC_NONE) {
        if (e->stored_size != e->raw_size)
            return -1;
        memcpy(out->payload, data + e->offset, out->size);
        return 0;
    }
    size_t got = ZSTD_decompress(out->payload, out->capacity, data + e->offset, (size_t)e->stored_size);
    return e->codec == TPK_CODEC_ZSTD && !ZSTD_isError(got) && got == out->size ? 0 : -1;
}

/* The header and every chunk, decoded; -1 for anything the writer could not write again. */
static int parse(const uint8_t *data, size_t size, parsed *p)
{
    tpk_header h;
    memset(p, 0, sizeof *p);
    if (size < sizeof h)
        return -1;
    memcpy(&h, data, sizeof h);
    if (h.chunk_count == 0 || h.chunk_count > STRUCT_MAX_CHUNKS || h.directory_offset > size ||
        h.chunk_count * sizeof(tpk_dir_entry) > size - h.directory_offset)
        return -1;
    p->header = (tpk_header_fields){h.vertex_count, h.tet_count, h.shell_face_count,
                                    {h.origin[0], h.origin[1], h.origin[2]},
                                    {h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]},
                                    {h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]}};
    for (uint64_t i = 0; i < h.chunk_count; i++) {
        tpk_dir_entry e;
        memcpy(&e, data + h.directory_offset + i * sizeof e, sizeof e);
        chunk *c = &p->chunks[p->count++];
        c->desc = (tpk_chunk_desc){.tag = e.tag, .flags = e.flags, .codec = e.codec, .elem_type = e.elem_type,
                                   .elem_size = e.elem_size, .index = e.index, .step = e.step,
                                   .elem_count = e.elem_count, .zstd_level = 1};
        /* the writer takes elem_count * elem_size bytes: a directory that says otherwise is not rewritten */
        if (e.elem_size == 0 || e.raw_size / e.elem_size != e.elem_count || e.raw_size % e.elem_size ||
            decode_chunk(data, size, &e, c) != 0) {
            free_parsed(p);
            return -1;
        }
    }
    return 0;
}

/* Change one thing. */
static void mutate_parsed(parsed *p, uint64_t *random)
{
    chunk *c = &p->chunks[next_random(random) % p->count];
    switch (next_random(random) % 16) {
    case 0: /* counts, origin, bounds */
        LLVMFuzzerMutate((uint8_t *)&p->header, sizeof p->header, sizeof p->header);
        break;
    case 1: /* which field and step an FDAT says it is */
        LLVMFuzzerMutate((uint8_t *)&c->desc.index, sizeof c->desc.index, sizeof c->desc.index);
        LLVMFuzzerMutate((uint8_t *)&c->desc.step, sizeof c->desc.step, sizeof c->desc.step);
        break;
    case 2: /* a chunk left out */
        if (p->count > 1) {
            free(c->payload);
            *c = p->chunks[--p->count];
        }
        break;
    case 3: /* a chunk twice */
        if (p->count < STRUCT_MAX_CHUNKS && (p->chunks[p->count].payload = malloc(c->capacity))) {
            memcpy(p->chunks[p->count].payload, c->payload, c->size);
            p->chunks[p->count].desc = c->desc;
            p->chunks[p->count].size = c->size;
            p->chunks[p->count++].capacity = c->capacity;
        }
        break;
    case 4:
        c->desc.codec = c->desc.codec == TPK_CODEC_NONE ? TPK_CODEC_ZSTD : TPK_CODEC_NONE;
        break;
    default: { /* the payload, whole elements */
        size_t size = LLVMFuzzerMutate(c->payload, c->size, c->capacity);
        c->size = size - size % c->desc.elem_size;
        c->desc.elem_count = c->size / c->desc.elem_size;
    }
    }
}

/* The file again, written by libtetpack's writer into `fd`; its size, or 0 when the writer refuses. */
static size_t write_parsed(const parsed *p, int fd)
{
    if (ftruncate(fd, 0) != 0 || lseek(fd, 0, SEEK_SET) != 0)
        return 0;
    tpk_writer *w = NULL;
    char err[256];
    if (tpk_writer_open_fd(&w, fd, "fuzz.tpk", NULL, err, sizeof err) != TPK_OK)
        return 0;
    for (uint64_t i = 0; i < p->count; i++)
        if (tpk_writer_add_chunk(w, &p->chunks[i].desc, p->chunks[i].payload) != TPK_OK) {
            tpk_writer_abort(w);
            return 0;
        }
    if (tpk_writer_finish(w, &p->header) != TPK_OK)
        return 0;
    off_t end = lseek(fd, 0, SEEK_END);
    return end > 0 ? (size_t)end : 0;
}

size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed)
{
    static int fd = -1;
    static parsed p;
    uint64_t random = seed * 0x9E3779B97F4A7C15ull + 1;
    if (fd < 0 && (fd = memfd_create("fuzz_tpk_struct", 0)) < 0)
        abort();
    if (next_random(&random) % 8 == 0 || parse(data, size, &p) != 0)
        return LLVMFuzzerMutate(data, size, max_size);
    mutate_parsed(&p, &random);
    size_t written = write_parsed(&p, fd);
    free_parsed(&p);
    if (written == 0 || written > max_size || pread(fd, data, written, 0) != (ssize_t)written)
        return LLVMFuzzerMutate(data, size, max_size);
    return written;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    tpk_fuzz_tpk_input(data, size);
    return 0;
}
