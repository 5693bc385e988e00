/* NASA/AFLR3 UGRID importer: `.ugrid` (ASCII), `.b8.ugrid` (big-endian binary) and `.lb8.ugrid`
 * (little-endian binary), the format large CFD meshes travel in. Layout: the counts
 * nnode ntri nquad ntet npyr nprism nhex, the coordinates, surface triangles and quads, their surface
 * ids, then the volume elements, all ids 1-based; binary files hold 4-byte ints and 8-byte reals in the
 * same order. Surface elements are dropped (counted), their ids kept as nothing; tetrahedra become
 * cells. Pyramids, prisms and hexahedra are refused until their UGRID node order is checked against a
 * real file (DESIGN.md §10: UGRID orders pyramids differently from VTK). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "importers.h"
#include "text_scan.h"

typedef struct ugrid_reader {
    tpk_scan s;
    int binary;        /* 0 ASCII, 1 big-endian, 2 little-endian */
    int64_t count[7];  /* nnode ntri nquad ntet npyr nprism nhex */
} ugrid_reader;

static const char *const count_names[7] = {"nodes", "surface triangles", "surface quadrilaterals",
                                            "tetrahedra", "pyramids", "prisms", "hexahedra"};

static uint32_t load32(const unsigned char *p, int big)
{
    return big ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
               : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

static int read_int(ugrid_reader *r, int64_t *out, const char *what)
{
    if (!r->binary)
        return tpk_scan_int64(&r->s, out, what);
    if (r->s.size - r->s.pos < 4)
        return tpk_scan_fail(&r->s, "expected %s (4 bytes), found end of file", what);
    *out = (int32_t)load32(r->s.data + r->s.pos, r->binary == 1);
    r->s.pos += 4;
    return 0;
}

static int read_real(ugrid_reader *r, double *out, const char *what)
{
    if (!r->binary)
        return tpk_scan_double(&r->s, out, what);
    if (r->s.size - r->s.pos < 8)
        return tpk_scan_fail(&r->s, "expected %s (8 bytes), found end of file", what);
    const unsigned char *p = r->s.data + r->s.pos;
    uint64_t hi = load32(p + (r->binary == 1 ? 0 : 4), r->binary == 1);
    uint64_t lo = load32(p + (r->binary == 1 ? 4 : 0), r->binary == 1);
    uint64_t bits = hi << 32 | lo;
    memcpy(out, &bits, sizeof bits);
    r->s.pos += 8;
    return 0;
}

/* The seven counts, checked against the bytes left: every node needs 3 reals and every element its ids. */
static int read_counts(ugrid_reader *r)
{
    static const int values[7] = {3, 4, 5, 4, 5, 6, 8}; /* numbers per item (surface ids included) */
    uint64_t needed = 0;
    for (int i = 0; i < 7; i++) {
        char what[64];
        snprintf(what, sizeof what, "the number of %s", count_names[i]);
        if (read_int(r, &r->count[i], what))
            return -1;
        if (r->count[i] < 0 || r->count[i] > INT32_MAX)
            return tpk_scan_fail(&r->s, "expected 0 to 2^31-1 %s, found %lld", count_names[i],
                                 (long long)r->count[i]);
        needed += (uint64_t)r->count[i] * (uint64_t)values[i] * (r->binary ? 4 : 2);
    }
    size_t left = r->s.size - r->s.pos;
    if (needed > left)
        return tpk_scan_fail(&r->s, "the counts need at least %llu more bytes, the file has %zu left "
                                    "(wrong counts or truncated file)",
                             (unsigned long long)needed, left);
    for (int i = 4; i < 7; i++)
        if (r->count[i] > 0)
            return tpk_scan_fail(&r->s, "%lld %s: not read yet (their UGRID node order is not checked against "
                                        "a real file); convert the mesh to VTK or Gmsh meanwhile",
                                 (long long)r->count[i], count_names[i]);
    if (r->count[3] == 0)
        return tpk_scan_fail(&r->s, "the file has no tetrahedra (no volume cells)");
    return 0;
}

static int skip_ints(ugrid_reader *r, int64_t n, const char *what)
{
    for (int64_t i = 0; i < n; i++) {
        int64_t v;
        if (read_int(r, &v, what))
            return -1;
    }
    return 0;
}

static int read_mesh(ugrid_reader *r, tpk_mesh *out)
{
    int64_t nv = r->count[0], nt = r->count[3];
    out->point_count = nv;
    out->points = malloc(sizeof *out->points * 3 * (size_t)(nv ? nv : 1));
    out->cell_count = nt;
    out->cell_types = malloc((size_t)nt);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(nt + 1));
    out->cell_conn = malloc(sizeof *out->cell_conn * 4 * (size_t)nt);
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn)
        return tpk_scan_fail(&r->s, "out of memory for %lld nodes and %lld tetrahedra", (long long)nv, (long long)nt);
    for (int64_t i = 0; i < 3 * nv; i++)
        if (read_real(r, &out->points[i], "a node coordinate"))
            return -1;
    /* Surface triangles and quadrilaterals, then their surface ids: not volume cells. */
    if (skip_ints(r, 3 * r->count[1] + 4 * r->count[2] + r->count[1] + r->count[2], "a surface element id"))
        return -1;
    for (int64_t t = 0; t < nt; t++) {
        out->cell_types[t] = 10;
        out->cell_offsets[t] = 4 * t;
        for (int k = 0; k < 4; k++) {
            int64_t id;
            if (read_int(r, &id, "a tetrahedron's node id"))
                return -1;
            if (id < 1 || id > nv)
                return tpk_scan_fail(&r->s, "tetrahedron %lld: node id %lld, expected 1 to %lld", (long long)t + 1,
                                     (long long)id, (long long)nv);
            out->cell_conn[4 * t + k] = (int32_t)(id - 1);
        }
    }
    out->cell_offsets[nt] = 4 * nt;
    return 0;
}

static int import_buffer(const char *name, const char *data, size_t size, int binary, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name ? name : "(input)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    ugrid_reader r;
    memset(&r, 0, sizeof r);
    tpk_scan_init(&r.s, name, data, size, diag);
    r.s.byte_places = binary != 0;
    r.s.mapped = mapped;
    r.binary = binary;
    int rc = read_counts(&r);
    if (rc == 0)
        rc = read_mesh(&r, out);
    if (rc == 0) {
        if (r.count[1] + r.count[2])
            tpk_diag_warn(diag, "%s: dropped %lld surface triangles and %lld quadrilaterals", name,
                          (long long)r.count[1], (long long)r.count[2]);
        out->step_count = 1;
        snprintf(out->format, sizeof out->format, "%s", binary == 1 ? "ugrid-b8" : binary ? "ugrid-lb8" : "ugrid");
    } else {
        tpk_mesh_free(out);
    }
    return rc ? -1 : 0;
}

/* 0 ASCII (.ugrid), 1 big-endian (.b8.ugrid), 2 little-endian (.lb8.ugrid). */
static int binary_kind(const char *name)
{
    size_t n = strlen(name);
    if (n >= 10 && !strcmp(name + n - 10, ".lb8.ugrid"))
        return 2;
    if (n >= 9 && !strcmp(name + n - 9, ".b8.ugrid"))
        return 1;
    return 0;
}

/* tpk_parse_fn: the binary kind comes from the name. */
static int parse_ugrid(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, binary_kind(name ? name : ""), mapped, out, diag);
}

int tpk_import_ugrid_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, binary_kind(name ? name : ""), 0, out, diag);
}

int tpk_import_ugrid(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, parse_ugrid, out, diag);
}
