/* Gzip-compressed inputs inflated into memory (gzip_input.h): no temporary file, a bounded size. */
#include "gzip_input.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "base/text_scan.h"

size_t tpk_gzip_default_limit(void)
{
    long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    uint64_t half = pages > 0 && page > 0 ? (uint64_t)pages * (uint64_t)page / 2 : 0;
    uint64_t floor = (uint64_t)64 << 20;
    if (half < floor)
        half = floor;
    return half > SIZE_MAX ? SIZE_MAX : (size_t)half;
}

/* The first buffer: the last member's size field (mod 2^32, so a hint only), at most the limit and what
 * deflate can reach (about 1032:1). */
static size_t first_capacity(const unsigned char *data, size_t size, size_t limit)
{
    size_t hint = size >= 18 ? (size_t)data[size - 4] | (size_t)data[size - 3] << 8 | (size_t)data[size - 2] << 16 |
                                   (size_t)data[size - 1] << 24
                             : 0;
    size_t reach = size > SIZE_MAX / 1032 ? SIZE_MAX : size * 1032;
    if (hint > reach)
        hint = reach;
    if (hint > limit)
        hint = limit;
    return hint < 4096 ? 4096 : hint;
}

int tpk_gzip_inflate(const char *name, const char *data, size_t size, size_t limit, char **out, size_t *out_size,
                     tpk_diag *diag)
{
    *out = NULL;
    *out_size = 0;
    if (!limit)
        limit = tpk_gzip_default_limit();
    const unsigned char *in = (const unsigned char *)data;
    if (size < 2 || in[0] != 0x1f || in[1] != 0x8b)
        return tpk_diag_fail(diag, "%s: byte 0: expected the gzip signature 1f 8b, found %s", name,
                             size < 2 ? "end of file" : "other bytes (not a gzip file)");
    size_t cap = first_capacity(in, size, limit), used = 0;
    unsigned char *buf = malloc(cap);
    z_stream z;
    memset(&z, 0, sizeof z);
    if (!buf || inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) {
        free(buf);
        return tpk_diag_fail(diag, "%s: out of memory for inflating", name);
    }
    size_t consumed = 0; /* input before the current piece (z.avail_in is a uInt) */
    const char *why = NULL;
    while (!why) {
        if (z.avail_in == 0 && consumed < size) {
            size_t piece = size - consumed > (1u << 30) ? (1u << 30) : size - consumed;
            z.next_in = (unsigned char *)in + consumed;
            z.avail_in = (uInt)piece;
            consumed += piece;
        }
        if (used == cap) {
            if (cap >= limit) {
                why = "limit";
                break;
            }
            size_t bigger = cap > limit / 2 ? limit : cap * 2;
            unsigned char *grown = realloc(buf, bigger);
            if (!grown) {
                why = "out of memory";
                break;
            }
            buf = grown;
            cap = bigger;
        }
        size_t room = cap - used > (1u << 30) ? (1u << 30) : cap - used;
        z.next_out = buf + used;
        z.avail_out = (uInt)room;
        int rc = inflate(&z, Z_NO_FLUSH);
        used += room - z.avail_out;
        if (rc == Z_STREAM_END) {
            size_t at = consumed - z.avail_in;
            if (at == size)
                break;
            if (size - at < 2 || in[at] != 0x1f || in[at + 1] != 0x8b) {
                tpk_diag_warn(diag, "%s: %zu bytes after the gzip data ignored", name, size - at);
                break;
            }
            inflateReset(&z); /* another member follows: gzip concatenates them */
        } else if (rc == Z_OK || rc == Z_BUF_ERROR) {
            if (z.avail_out != 0 && z.avail_in == 0 && consumed == size)
                why = "the data ends early (truncated file)";
        } else {
            why = z.msg ? z.msg : "corrupt data";
        }
    }
    size_t at = consumed - z.avail_in;
    inflateEnd(&z);
    if (why) {
        free(buf);
        if (!strcmp(why, "limit"))
            return tpk_diag_fail(diag, "%s: inflates to more than %zu bytes, the limit (half the memory available); "
                                       "gunzip it and read the file itself",
                                 name, limit);
        return tpk_diag_fail(diag, "%s: byte %zu of the compressed data: cannot inflate: %s", name, at, why);
    }
    *out = (char *)buf;
    *out_size = used;
    return 0;
}

int tpk_gzip_inflate_file(const char *path, size_t limit, char **out, size_t *out_size, tpk_diag *diag)
{
    const char *data;
    size_t size;
    *out = NULL;
    *out_size = 0;
    if (tpk_map_file(path, &data, &size, diag) != 0)
        return -1;
    int rc = tpk_gzip_inflate(path, data, size, limit, out, out_size, diag);
    tpk_unmap_file(data, size);
    return rc;
}

size_t tpk_gzip_head(const char *path, char *head, size_t cap)
{
    gzFile f = gzopen(path, "rb");
    if (!f)
        return 0;
    int got = gzread(f, head, (unsigned)cap);
    gzclose(f);
    return got > 0 ? (size_t)got : 0;
}
