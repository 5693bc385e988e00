/* Binary Medit (.meshb, libMeshb versions 1-4), as written by MMG, refine and TetWild. The file holds
 * an endianness word (1), the version, then keywords: a code, the byte offset of the next keyword, a
 * count and that many rows. Reals are 4 bytes in version 1 and 8 after; ints are 4 bytes up to version
 * 3 and 8 in version 4; offsets are 4 bytes in versions 1-2 and 8 from 3. Tetrahedra and hexahedra
 * (VTK node order, as in the ASCII form) become cells with their references as the cell field "ref";
 * every other keyword is skipped by its offset. */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "importers.h"
#include "tetpack_format.h"
#include "base/text_scan.h"
#include "import_file.h"

enum { KW_DIMENSION = 3, KW_VERTICES = 4, KW_TETRAHEDRA = 8, KW_PRISMS = 9, KW_HEXAHEDRA = 10, KW_PYRAMIDS = 49,
       KW_END = 54 };

typedef struct meshb_reader {
    const char *name;
    const unsigned char *data;
    size_t size, pos;
    int swap, version;
    tpk_diag *diag;
} meshb_reader;

/* "NAME: byte AT: ..." (import_file.h) */
#define fail(r, at, ...) tpk_import_fail((r)->diag, NULL, (tpk_import_place){(r)->name, 0, (int64_t)(at), NULL}, __VA_ARGS__)

static uint64_t load(meshb_reader *r, size_t at, int bytes)
{
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++) {
        int k = r->swap ? bytes - 1 - i : i;
        v |= (uint64_t)r->data[at + (size_t)k] << (8 * i);
    }
    return v;
}

/* A signed integer of `bytes` at the current position; fails past the end. */
static int read_int(meshb_reader *r, int bytes, int64_t *out, const char *what)
{
    if (r->size - r->pos < (size_t)bytes)
        return fail(r, r->pos, "expected %s (%d bytes), found end of file", what, bytes);
    uint64_t v = load(r, r->pos, bytes);
    *out = bytes == 4 ? (int64_t)(int32_t)(uint32_t)v : (int64_t)v;
    r->pos += (size_t)bytes;
    return 0;
}

static double read_real_unchecked(meshb_reader *r)
{
    double d;
    if (r->version == 1) {
        uint32_t bits = (uint32_t)load(r, r->pos, 4);
        float f;
        memcpy(&f, &bits, sizeof f);
        d = f;
        r->pos += 4;
    } else {
        uint64_t bits = load(r, r->pos, 8);
        memcpy(&d, &bits, sizeof d);
        r->pos += 8;
    }
    return d;
}

static int int_bytes(const meshb_reader *r) { return r->version >= 4 ? 8 : 4; }
static int real_bytes(const meshb_reader *r) { return r->version >= 2 ? 8 : 4; }
static int pos_bytes(const meshb_reader *r) { return r->version >= 3 ? 8 : 4; }

/* A count of rows of `row_bytes` each, checked against the bytes left. */
static int read_count(meshb_reader *r, const char *keyword, uint64_t row_bytes, int64_t *n)
{
    size_t at = r->pos;
    if (read_int(r, int_bytes(r), n, "a count"))
        return -1;
    if (*n < 0 || *n > INT32_MAX)
        return fail(r, at, "%s: expected a count from 0 to 2^31-1, found %lld", keyword, (long long)*n);
    if ((uint64_t)*n * row_bytes > r->size - r->pos)
        return fail(r, at, "%s %lld: %llu bytes of rows, but %zu are left (wrong count or truncated file)", keyword,
                    (long long)*n, (unsigned long long)((uint64_t)*n * row_bytes), r->size - r->pos);
    return 0;
}

static int read_vertices(meshb_reader *r, tpk_mesh *out)
{
    int64_t n;
    if (out->points)
        return fail(r, r->pos, "expected one Vertices keyword, found a second");
    if (read_count(r, "Vertices", 3 * (uint64_t)real_bytes(r) + (uint64_t)int_bytes(r), &n))
        return -1;
    out->points = malloc(sizeof *out->points * 3 * (size_t)(n ? n : 1));
    if (!out->points)
        return fail(r, r->pos, "Vertices %lld: out of memory", (long long)n);
    out->point_count = n;
    for (int64_t v = 0; v < n; v++) {
        for (int k = 0; k < 3; k++)
            out->points[3 * v + k] = read_real_unchecked(r);
        r->pos += (size_t)int_bytes(r); /* vertex reference */
    }
    return 0;
}

typedef struct cells {
    int64_t count, capacity_conn, conn_count;
    uint8_t *types;
    int64_t *offsets;
    int32_t *conn;
    float *refs;
} cells;

static int read_elements(meshb_reader *r, cells *c, const char *keyword, int nodes, int type)
{
    int64_t n;
    size_t at = r->pos;
    if (read_count(r, keyword, (uint64_t)(nodes + 1) * (uint64_t)int_bytes(r), &n))
        return -1;
    int64_t total = c->count + n;
    if (total > INT32_MAX)
        return fail(r, at, "%lld volume elements in all: more than 2^31-1", (long long)total);
    uint8_t *types = realloc(c->types, (size_t)(total ? total : 1));
    if (types)
        c->types = types;
    int64_t *offsets = realloc(c->offsets, sizeof *offsets * (size_t)(total + 1));
    if (offsets)
        c->offsets = offsets;
    int32_t *conn = realloc(c->conn, sizeof *conn * (size_t)(c->conn_count + n * nodes + 1));
    if (conn)
        c->conn = conn;
    float *refs = realloc(c->refs, sizeof *refs * (size_t)(total ? total : 1));
    if (refs)
        c->refs = refs;
    if (!types || !offsets || !conn || !refs)
        return fail(r, at, "%s %lld: out of memory", keyword, (long long)n);
    for (int64_t e = 0; e < n; e++) {
        c->types[c->count] = (uint8_t)type;
        c->offsets[c->count] = c->conn_count;
        for (int k = 0; k < nodes; k++) {
            int64_t id = 0;
            read_int(r, int_bytes(r), &id, "a vertex id"); /* the count check above guarantees the bytes */
            if (id < 1 || id > INT32_MAX)
                return fail(r, r->pos - (size_t)int_bytes(r), "%s %lld: vertex id %lld, expected 1 or more",
                            keyword, (long long)e + 1, (long long)id);
            c->conn[c->conn_count++] = (int32_t)(id - 1);
        }
        int64_t ref = 0;
        read_int(r, int_bytes(r), &ref, "a reference");
        c->refs[c->count++] = (float)ref;
    }
    c->offsets[c->count] = c->conn_count;
    return 0;
}

static int read_keywords(meshb_reader *r, tpk_mesh *out, cells *c)
{
    while (r->pos < r->size) {
        size_t at = r->pos;
        int64_t code = 0, next = 0, dim = 0;
        if (read_int(r, 4, &code, "a keyword code"))
            return -1;
        if (code == KW_END)
            return 0;
        if (read_int(r, pos_bytes(r), &next, "the next keyword's offset"))
            return -1;
        if (next != 0 && ((uint64_t)next <= at || (uint64_t)next > r->size))
            return fail(r, at, "keyword %lld: the next keyword's offset %lld is not after it and inside the file "
                               "(%zu bytes)", (long long)code, (long long)next, r->size);
        int rc = 0;
        switch (code) {
        case KW_DIMENSION:
            rc = read_int(r, int_bytes(r), &dim, "the dimension");
            if (rc == 0 && dim != 3)
                rc = fail(r, r->pos, "expected dimension 3 (a volume mesh), found %lld", (long long)dim);
            break;
        case KW_VERTICES: rc = read_vertices(r, out); break;
        case KW_TETRAHEDRA: rc = read_elements(r, c, "Tetrahedra", 4, 10); break;
        case KW_HEXAHEDRA: rc = read_elements(r, c, "Hexahedra", 8, 12); break;
        case KW_PRISMS:
        case KW_PYRAMIDS:
            return fail(r, at, "%s are not read yet (their Medit node order is not checked against a real file)",
                        code == KW_PRISMS ? "Prisms" : "Pyramids");
        default: break; /* anything else: skipped by its offset */
        }
        if (rc)
            return rc;
        if (next == 0)
            return 0;
        r->pos = (size_t)next;
    }
    return 0;
}

static int import_buffer(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    (void)mapped; /* keywords are read by offset, not in one pass: no pages to drop */
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
    meshb_reader r = {name ? name : "(input)", (const unsigned char *)data, size, 0, 0, 0, diag};
    cells c;
    memset(&c, 0, sizeof c);
    int64_t word = 0, version = 0;
    int rc = read_int(&r, 4, &word, "the endianness word 1");
    if (rc == 0 && word != 1) {
        r.swap = 1;
        if ((uint32_t)load(&r, 0, 4) != 1)
            rc = fail(&r, 0, "expected the endianness word 1 of a binary Medit file, found 0x%08x",
                      (unsigned)(uint32_t)word);
    }
    if (rc == 0)
        rc = read_int(&r, 4, &version, "the version");
    if (rc == 0 && (version < 1 || version > 4))
        rc = fail(&r, 4, "expected version 1 to 4, found %lld", (long long)version);
    r.version = (int)version;
    if (rc == 0)
        rc = read_keywords(&r, out, &c);
    if (rc == 0 && !out->points)
        rc = fail(&r, r.pos, "expected a Vertices keyword, found none");
    for (int64_t k = 0; rc == 0 && k < c.conn_count; k++)
        if (c.conn[k] >= out->point_count)
            rc = fail(&r, r.pos, "an element uses vertex %d, but there are only %lld vertices", c.conn[k] + 1,
                      (long long)out->point_count);
    if (rc == 0) {
        double *points = out->points; /* read_keywords set them */
        if (tpk_import_take_cells(out, out->point_count, &points, c.count, &c.types, &c.offsets, &c.conn) ||
            tpk_mesh_add_field(out, "ref", TPK_ASSOC_TET, 1, 1, c.refs))
            rc = fail(&r, r.pos, "out of memory");
        else
            c.refs = NULL;
        out->step_count = 1;
        snprintf(out->format, sizeof out->format, "medit-binary-v%d", r.version);
    }
    free(c.types), free(c.offsets), free(c.conn), free(c.refs);
    return tpk_import_end(rc, out);
}

int tpk_import_meshb_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_meshb(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
