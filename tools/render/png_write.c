/* PNG output, written atomically: an output file (base/output_file.h), put in place whole. The encoder
 * is ours (the chunks are few and fixed): every row filtered by Up (type 2), bands of PNG_BAND_ROWS rows
 * deflated apart on all threads (raw deflate, level 1, run-length strategy; each band ends on a sync
 * flush, the last on the stream's end), joined into one zlib stream whose Adler-32 is combined from
 * the bands'. The bands do not depend on the thread count, so neither do the bytes. libpng's default
 * (level 6, all five filters tried per row) took many times a GPU frame (bench/README, figures). */
#include "render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "base/output_file.h"
#include "base/parallel.h"

#define PNG_BAND_ROWS 32

typedef struct png_band {
    uint8_t *data; /* deflated, with room for the zlib header (band 0) and Adler-32 (last band) */
    size_t size;   /* bytes of data used */
    uLong adler;   /* of the band's filtered bytes */
    uLong filtered;
    int failed;
} png_band;

typedef struct png_job {
    const uint8_t *rgba;
    int width, height;
    int64_t bands;
    png_band *band;
} png_job;

/* Band b: its rows filtered into a scratch buffer, deflated into band->data after `lead` bytes. */
static int deflate_band(const png_job *job, int64_t b, png_band *band)
{
    const size_t stride = 4 * (size_t)job->width, line = stride + 1;
    const int y0 = (int)(b * PNG_BAND_ROWS), rows = job->height - y0 < PNG_BAND_ROWS ? job->height - y0 : PNG_BAND_ROWS;
    const int last = b == job->bands - 1;
    const size_t lead = b == 0 ? 2 : 0;
    uint8_t *filtered = malloc(line * (size_t)rows);
    if (!filtered)
        return -1;
    for (int r = 0; r < rows; r++) {
        int y = y0 + r;
        const uint8_t *row = job->rgba + (size_t)y * stride, *up = y > 0 ? row - stride : NULL;
        uint8_t *dst = filtered + (size_t)r * line;
        dst[0] = 2; /* Up: the row above, zeros above the first */
        for (size_t i = 0; i < stride; i++)
            dst[1 + i] = (uint8_t)(row[i] - (up ? up[i] : 0));
    }
    band->filtered = (uLong)(line * (size_t)rows);
    band->adler = adler32(adler32(0L, Z_NULL, 0), filtered, (uInt)band->filtered);
    z_stream z;
    memset(&z, 0, sizeof z);
    int rc = -1;
    if (deflateInit2(&z, 1, Z_DEFLATED, -15, 8, Z_RLE) == Z_OK) {
        size_t cap = deflateBound(&z, band->filtered) + 16 + lead + 4; /* a sync flush adds 5 bytes at most */
        band->data = malloc(cap);
        if (band->data) {
            z.next_in = filtered;
            z.avail_in = (uInt)band->filtered;
            z.next_out = band->data + lead;
            z.avail_out = (uInt)(cap - lead - 4);
            int flush = last ? Z_FINISH : Z_SYNC_FLUSH;
            int zr = deflate(&z, flush);
            if ((last ? zr == Z_STREAM_END : zr == Z_OK) && z.avail_in == 0) {
                band->size = lead + (size_t)z.total_out;
                rc = 0;
            }
        }
        deflateEnd(&z);
    }
    free(filtered);
    return rc;
}

static void deflate_bands(void *ctx, int64_t begin, int64_t end, int worker)
{
    (void)worker;
    png_job *job = ctx;
    for (int64_t b = begin; b < end; b++)
        job->band[b].failed = deflate_band(job, b, &job->band[b]) != 0;
}

static void put_be32(uint8_t *p, uint32_t x)
{
    p[0] = (uint8_t)(x >> 24), p[1] = (uint8_t)(x >> 16), p[2] = (uint8_t)(x >> 8), p[3] = (uint8_t)x;
}

/* One chunk: length, type, data, CRC of type and data. */
static int write_chunk(FILE *file, const char type[4], const uint8_t *data, size_t size)
{
    uint8_t head[8], tail[4];
    put_be32(head, (uint32_t)size);
    memcpy(head + 4, type, 4);
    uLong crc = crc32(crc32(0L, Z_NULL, 0), head + 4, 4);
    if (size)
        crc = crc32(crc, data, (uInt)size);
    put_be32(tail, (uint32_t)crc);
    return fwrite(head, 1, 8, file) == 8 && (!size || fwrite(data, 1, size, file) == size) &&
                   fwrite(tail, 1, 4, file) == 4
               ? 0
               : -1;
}

/* Encode into an open stream; returns 0, or -1 with *why set. */
static int encode(FILE *file, int width, int height, const uint8_t *rgba, const char **why)
{
    png_job job = {rgba, width, height, (height + PNG_BAND_ROWS - 1) / PNG_BAND_ROWS, NULL};
    job.band = calloc((size_t)job.bands, sizeof *job.band);
    if (!job.band) {
        *why = "out of memory";
        return -1;
    }
    tpk_parallel_for(job.bands, tpk_threads_for(job.bands, tpk_thread_count(0), 1), deflate_bands, &job);
    int rc = 0;
    uLong adler = adler32(0L, Z_NULL, 0);
    for (int64_t b = 0; b < job.bands; b++) {
        rc |= job.band[b].failed;
        adler = adler32_combine(adler, job.band[b].adler, (z_off_t)job.band[b].filtered);
    }
    if (rc) {
        *why = "out of memory or a deflate error";
    } else {
        job.band[0].data[0] = 0x78, job.band[0].data[1] = 0x01; /* deflate, 32K window, fastest; check bits */
        put_be32(job.band[job.bands - 1].data + job.band[job.bands - 1].size, (uint32_t)adler);
        job.band[job.bands - 1].size += 4;
        static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
        uint8_t ihdr[13] = {0};
        put_be32(ihdr, (uint32_t)width);
        put_be32(ihdr + 4, (uint32_t)height);
        ihdr[8] = 8, ihdr[9] = 6; /* 8 bits, RGBA; deflate, adaptive filtering, no interlace */
        rc = fwrite(signature, 1, 8, file) == 8 ? write_chunk(file, "IHDR", ihdr, sizeof ihdr) : -1;
        for (int64_t b = 0; b < job.bands && rc == 0; b++)
            rc = write_chunk(file, "IDAT", job.band[b].data, job.band[b].size);
        if (rc == 0)
            rc = write_chunk(file, "IEND", NULL, 0);
        if (rc != 0)
            *why = "a write failed";
    }
    for (int64_t b = 0; b < job.bands; b++)
        free(job.band[b].data);
    free(job.band);
    return rc;
}

int tpk_write_png(const char *path, int width, int height, const uint8_t *rgba, tpk_diag *diag)
{
    if (!path || !rgba || width < 1 || height < 1 || width > 1000000 || height > 1000000 ||
        (uint64_t)width * 4 * PNG_BAND_ROWS > 0x7fffffffu)
        return tpk_diag_fail(diag, "%s: cannot write a %dx%d PNG", path ? path : "(null)", width, height);
    tpk_output out;
    if (tpk_output_open(&out, path, diag) != 0)
        return -1;
    FILE *file = tpk_output_stream(&out, diag);
    const char *why = "";
    if (!file || encode(file, width, height, rgba, &why) != 0) {
        tpk_output_abort(&out);
        return file ? tpk_diag_fail(diag, "%s: PNG encoding failed: %s", path, why) : -1;
    }
    return tpk_output_commit(&out, diag);
}
