/* NASA/AFLR3 UGRID importer: `.ugrid` (ASCII), `.b8.ugrid` (big-endian binary) and `.lb8.ugrid`
 * (little-endian binary), the format large CFD meshes travel in. Layout: the counts
 * nnode ntri nquad ntet npyr nprism nhex, the coordinates, surface triangles and quads, their surface
 * ids, then the volume elements, all ids 1-based; binary files hold 4-byte ints and 8-byte reals in the
 * same order. Surface elements are dropped (counted), their ids kept as nothing; tetrahedra, pyramids,
 * prisms and hexahedra become cells in VTK node order. UGRID orders pyramids and prisms differently
 * from VTK (docs/ARCHITECTURE.md §7): the maps below are those of NASA refine (src/ref_import.c, the UGRID tool
 * behind the acceptance meshes in ../shared/data/nasa_refine), whose diagrams put UGRID's pyramid base
 * 0 1 4 3 with apex 2 and its prism as VTK's with the first two corners of each triangle swapped;
 * tetrahedra (checked on refine's files) and hexahedra are as in VTK. meshio 5 agrees on pyramids but
 * reads prisms unchanged; we follow refine, which writes the meshes. A prism map that were wrong would
 * show as mirrored prisms, which the converter refuses by name (--reorient turns them over). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "importers.h"
#include "base/text_scan.h"
#include "import_file.h"

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
    if (r->count[3] + r->count[4] + r->count[5] + r->count[6] == 0)
        return tpk_scan_fail(&r->s, "the file has no volume cells (no tetrahedra, pyramids, prisms or hexahedra)");
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

/* Volume kinds in file order: nodes per element, VTK type, and VTK node k = UGRID node map[k]. */
static const struct {
    const char *name;
    int nodes, vtk_type;
    int map[8];
} volume_kinds[4] = {
    {"tetrahedron", 4, 10, {0, 1, 2, 3}},
    {"pyramid", 5, 14, {1, 0, 3, 4, 2}},
    {"prism", 6, 13, {1, 0, 2, 4, 3, 5}},
    {"hexahedron", 8, 12, {0, 1, 2, 3, 4, 5, 6, 7}},
};

static int read_mesh(ugrid_reader *r, tpk_mesh *out)
{
    int64_t nv = r->count[0], nc = 0, nconn = 0;
    for (int k = 0; k < 4; k++) {
        nc += r->count[3 + k];
        nconn += r->count[3 + k] * volume_kinds[k].nodes;
    }
    out->point_count = nv;
    out->points = malloc(sizeof *out->points * 3 * (size_t)(nv ? nv : 1));
    out->cell_count = nc;
    out->cell_types = malloc((size_t)nc);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(nc + 1));
    out->cell_conn = malloc(sizeof *out->cell_conn * (size_t)nconn);
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn)
        return tpk_scan_fail(&r->s, "out of memory for %lld nodes and %lld volume elements", (long long)nv,
                             (long long)nc);
    for (int64_t i = 0; i < 3 * nv; i++)
        if (read_real(r, &out->points[i], "a node coordinate"))
            return -1;
    /* Surface triangles and quadrilaterals, then their surface ids: not volume cells. */
    if (skip_ints(r, 3 * r->count[1] + 4 * r->count[2] + r->count[1] + r->count[2], "a surface element id"))
        return -1;
    int64_t c = 0, at = 0;
    for (int k = 0; k < 4; k++) {
        const char *name = volume_kinds[k].name;
        int n = volume_kinds[k].nodes;
        for (int64_t e = 0; e < r->count[3 + k]; e++, c++) {
            int32_t ids[8];
            for (int j = 0; j < n; j++) {
                int64_t id;
                char what[64];
                snprintf(what, sizeof what, "a %s's node id", name);
                if (read_int(r, &id, what))
                    return -1;
                if (id < 1 || id > nv)
                    return tpk_scan_fail(&r->s, "%s %lld: node id %lld, expected 1 to %lld", name, (long long)e + 1,
                                         (long long)id, (long long)nv);
                ids[j] = (int32_t)(id - 1);
            }
            out->cell_types[c] = (uint8_t)volume_kinds[k].vtk_type;
            out->cell_offsets[c] = at;
            for (int j = 0; j < n; j++)
                out->cell_conn[at + j] = ids[volume_kinds[k].map[j]];
            at += n;
        }
    }
    out->cell_offsets[nc] = at;
    return 0;
}

static int import_buffer(const char *name, const char *data, size_t size, int binary, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
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
