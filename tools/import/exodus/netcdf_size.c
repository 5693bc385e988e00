/* The size a classic netCDF file (CDF-1, CDF-2, CDF-5) must have, from its header. The netCDF library
 * zero-fills reads past the end of a short file, so a truncated Exodus file would otherwise import
 * with zeros where its data was cut off. The header layout is the netCDF classic format specification:
 * magic, numrecs, then the dimension, global attribute and variable lists, all big-endian. */
#include "netcdf_size.h"

#include <string.h>

enum { NC_DIMENSION = 0x0A, NC_VARIABLE = 0x0B, NC_ATTRIBUTE = 0x0C, MAX_DIMS = 1024 };

typedef struct cdf {
    const unsigned char *data;
    size_t size, pos;
    int version; /* 1, 2 or 5 */
    int bad;
} cdf;

static uint64_t get(cdf *c, int bytes)
{
    if (c->bad || c->size - c->pos < (size_t)bytes) {
        c->bad = 1;
        return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++)
        v = v << 8 | c->data[c->pos + (size_t)i];
    c->pos += (size_t)bytes;
    return v;
}

static uint64_t count(cdf *c) { return get(c, c->version == 5 ? 8 : 4); }

static void skip(cdf *c, uint64_t bytes)
{
    if (c->bad || bytes > c->size - c->pos)
        c->bad = 1;
    else
        c->pos += (size_t)bytes;
}

static uint64_t padded(uint64_t n) { return (n + 3) / 4 * 4; }

static int type_size(uint64_t type)
{
    static const int sizes[12] = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8};
    return type >= 1 && type <= 11 ? sizes[type] : 0;
}

static void skip_name(cdf *c) { skip(c, padded(count(c))); }

static void skip_attributes(cdf *c)
{
    uint64_t tag = get(c, 4), n = count(c);
    if (tag == 0)
        return; /* ABSENT */
    if (tag != NC_ATTRIBUTE) {
        c->bad = 1;
        return;
    }
    for (uint64_t i = 0; i < n && !c->bad; i++) {
        skip_name(c);
        int size = type_size(get(c, 4));
        uint64_t values = count(c);
        if (!size || values > c->size)
            c->bad = 1;
        skip(c, padded(values * (uint64_t)size));
    }
}

int tpk_netcdf_classic_size(const unsigned char *data, size_t size, uint64_t *expected)
{
    if (size < 4 || memcmp(data, "CDF", 3) != 0)
        return 1;
    cdf c = {data, size, 4, data[3], 0};
    if (c.version != 1 && c.version != 2 && c.version != 5)
        return -1;
    uint64_t numrecs = count(&c), dims[MAX_DIMS], dim_count = 0;
    uint64_t tag = get(&c, 4), n = count(&c);
    if (tag == NC_DIMENSION) {
        if (n > MAX_DIMS)
            return -1;
        for (dim_count = 0; dim_count < n && !c.bad; dim_count++) {
            skip_name(&c);
            dims[dim_count] = count(&c);
        }
    } else if (tag != 0) {
        return -1;
    }
    skip_attributes(&c);
    tag = get(&c, 4), n = count(&c);
    if (tag != NC_VARIABLE && tag != 0)
        return -1;
    uint64_t fixed_end = c.pos, record_start = UINT64_MAX, record_size = 0, record_vars = 0, lone_record = 0;
    for (uint64_t v = 0; tag == NC_VARIABLE && v < n && !c.bad; v++) {
        skip_name(&c);
        uint64_t rank = count(&c), elements = 1;
        int record = 0;
        if (rank > MAX_DIMS)
            return -1;
        for (uint64_t d = 0; d < rank && !c.bad; d++) {
            uint64_t id = count(&c);
            if (id >= dim_count)
                return -1;
            if (dims[id] == 0 && d == 0)
                record = 1; /* the unlimited dimension comes first */
            else if (dims[id] && elements > UINT64_MAX / dims[id])
                return -1;
            else if (dims[id])
                elements *= dims[id];
        }
        skip_attributes(&c);
        int tsize = type_size(get(&c, 4));
        count(&c); /* vsize: recomputed, it saturates for huge variables */
        uint64_t begin = get(&c, c.version == 1 ? 4 : 8);
        if (!tsize || elements > UINT64_MAX / 8)
            return -1;
        uint64_t bytes = padded(elements * (uint64_t)tsize);
        if (record) {
            record_start = begin < record_start ? begin : record_start;
            record_size += bytes;
            record_vars++;
            lone_record = elements * (uint64_t)tsize; /* a lone record variable is not padded */
        } else if (begin + bytes > fixed_end) {
            fixed_end = begin + bytes;
        }
    }
    if (c.bad)
        return -1;
    uint64_t end = fixed_end;
    if (record_vars == 1)
        record_size = lone_record;
    if (record_start != UINT64_MAX && numrecs != 0xffffffffu && numrecs > 0)
        end = record_start + numrecs * record_size > end ? record_start + numrecs * record_size : end;
    *expected = end;
    return 0;
}
