/* VTU importer: zlib-compressed DataArray blocks, inflated on all cores. VTK compresses each block
 * (32 KiB by default) as its own zlib stream, so the blocks are independent: they are first read in
 * order (raw appended blocks are used where they lie in the file, base64 ones are decoded into one
 * buffer), then inflated in parallel by libdeflate, which inflates a whole buffer about twice as fast as
 * zlib's streaming inflate. A block libdeflate does not inflate to exactly its size is inflated again
 * by zlib, whose verdict counts: what is accepted and every message stay those of the zlib reader. */
#include <libdeflate.h>
#include <stdlib.h>
#include <zlib.h>

#include "import_vtu_internal.h"
#include "base/parallel.h"

typedef struct inflate_job {
    const zlib_blocks *z;
    const unsigned char **cblock; /* where each block's compressed bytes are */
    unsigned char *out;
    int *exact;                   /* per block: libdeflate gave exactly its size */
} inflate_job;

static uint64_t block_usize(const zlib_blocks *z, uint64_t b)
{
    return b + 1 == z->count ? z->last : z->size;
}

static void inflate_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    (void)worker;
    inflate_job *job = ctx;
    struct libdeflate_decompressor *d = libdeflate_alloc_decompressor();
    for (int64_t b = begin; b < end; b++) {
        uint64_t usize = block_usize(job->z, (uint64_t)b);
        size_t got = 0;
        job->exact[b] = d && libdeflate_zlib_decompress(d, job->cblock[b], (size_t)job->z->csizes[b],
                                                        job->out + (uint64_t)b * job->z->size, (size_t)usize,
                                                        &got) == LIBDEFLATE_SUCCESS && got == usize;
    }
    libdeflate_free_decompressor(d);
}

/* zlib's verdict on block b (out at its place): 0, or -1 with the message the reader always gave. */
static int inflate_with_zlib(vtu_reader *r, const vtu_array *a, const zlib_blocks *z, uint64_t b,
                             const unsigned char *cblock, unsigned char *out)
{
    uint64_t usize = block_usize(z, b);
    uLongf dlen = (uLongf)usize;
    int zrc = uncompress(out, &dlen, cblock, (uLong)z->csizes[b]);
    if (zrc != Z_OK)
        return vtu_fail_array(r, a, "zlib block %llu of %llu does not decompress: %s", (unsigned long long)b + 1,
                              (unsigned long long)z->count,
                              zrc == Z_BUF_ERROR ? "it is incomplete or holds more than the header's size"
                                                 : zError(zrc));
    if (dlen != usize)
        return vtu_fail_array(r, a, "zlib block %llu of %llu: expected %llu bytes, found %llu",
                              (unsigned long long)b + 1, (unsigned long long)z->count, (unsigned long long)usize,
                              (unsigned long long)dlen);
    return 0;
}

/* Where each block's compressed bytes are, in order; *readable: how many could be read (a base64
 * source can end early: the header sizes were checked against an upper bound only). Base64 blocks go
 * to *decoded (malloc'ed, the caller frees). */
static int locate_blocks(vtu_reader *r, const vtu_array *a, bsrc *s, const zlib_blocks *z,
                         const unsigned char **cblock, unsigned char **decoded, uint64_t *readable)
{
    uint64_t csum = 0;
    for (uint64_t b = 0; b < z->count; b++)
        csum += z->csizes[b];
    *decoded = NULL;
    if (s->b64 && !(*decoded = tpk_alloc_large(csum ? (size_t)csum : 1)))
        return vtu_fail_array(r, a, "out of memory for %llu bytes", (unsigned long long)csum);
    uint64_t at = 0;
    if (s->b64) { /* all blocks' base64 in one read (decoded on all cores when large); where it fails, again
                   * block by block from the start, which finds how many blocks were whole */
        bsrc saved = *s;
        if (vtu_src_read(s, *decoded, (size_t)csum) == 0) {
            for (uint64_t b = 0; b < z->count; at += z->csizes[b], b++)
                cblock[b] = *decoded + at;
            *readable = z->count;
            return 0;
        }
        *s = saved;
    }
    for (*readable = 0; *readable < z->count; ++*readable) {
        uint64_t b = *readable, n = z->csizes[b];
        if (s->b64) {
            if (vtu_src_read(s, *decoded + at, (size_t)n))
                break;
            cblock[b] = *decoded + at;
            at += n;
        } else {
            if (n > s->len - s->pos)
                break;
            cblock[b] = s->p + s->pos;
            s->pos += (size_t)n;
        }
    }
    return 0;
}

int vtu_inflate_blocks(vtu_reader *r, const vtu_array *a, bsrc *s, const zlib_blocks *z, unsigned char *out)
{
    const unsigned char **cblock = malloc(sizeof *cblock * (size_t)(z->count ? z->count : 1));
    int *exact = malloc(sizeof *exact * (size_t)(z->count ? z->count : 1));
    unsigned char *decoded = NULL;
    uint64_t readable = 0;
    int rc = !cblock || !exact ? vtu_fail_array(r, a, "out of memory")
                               : locate_blocks(r, a, s, z, cblock, &decoded, &readable);
    if (rc == 0) {
        inflate_job job = {z, cblock, out, exact};
        int threads = tpk_threads_for((int64_t)readable, tpk_thread_count(0), 8);
        tpk_parallel_for((int64_t)readable, threads, inflate_range, &job);
    }
    /* Block by block as the sequential reader went: the first block that fails names the problem. */
    for (uint64_t b = 0; rc == 0 && b < readable; b++)
        if (!exact[b])
            rc = inflate_with_zlib(r, a, z, b, cblock[b], out + b * z->size);
    if (rc == 0 && readable < z->count) {
        if (!s->b64)
            vtu_src_fail(s, "found the end of the data");
        rc = vtu_fail_array(r, a, "zlib block %llu of %llu: expected %llu compressed bytes, %s",
                            (unsigned long long)readable + 1, (unsigned long long)z->count,
                            (unsigned long long)z->csizes[readable], s->error);
    }
    free(decoded);
    free(exact);
    free(cblock);
    return rc;
}
