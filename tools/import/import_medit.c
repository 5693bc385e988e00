/* Medit .mesh (ASCII) importer: the INRIA mesh format written by MMG, TetWild, refine and sfepy.
 * A file is a series of keywords; each element keyword is followed by a count and that many rows of
 * 1-based vertex ids ending with an integer reference. Tetrahedra and hexahedra become cells (their
 * references a cell field "ref"), surface and line elements are dropped with a count, and the known
 * per-vertex sections (corners, ridges, normals...) are skipped. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tetpack_format.h"

#include "mesh/cell_types.h"
#include "importers.h"
#include "base/text_scan.h"
#include "import_file.h"

typedef struct medit_reader {
    tpk_scan s;
    int64_t point_count; /* -1 until Vertices */
    double *points;
    float *point_refs;
    int any_point_ref;
    int64_t cell_count, conn_count;
    uint8_t *types;
    int64_t *offsets; /* cell_count + 1 */
    int32_t *conn;    /* 1-based while reading */
    float *cell_refs;
    int64_t dropped;  /* surface and line elements */
} medit_reader;

/* How each element keyword is read. cell_type 0: dropped after reading. */
typedef struct element_section {
    const char *keyword;
    int nodes;
    int cell_type;
} element_section;

static const element_section element_sections[] = {
    {"Edges", 2, 0},
    {"Triangles", 3, 0},
    {"Quadrilaterals", 4, 0},
    {"Tetrahedra", 4, 10},
    {"Hexahedra", 8, 12}, /* same node order as VTK: checked on sfepy/cube_medium_hexa.mesh */
};

/* Sections of per-item data that carry nothing a volume renderer uses: keyword, integers and reals per
 * row. */
static const struct {
    const char *keyword;
    int ints, reals;
} skipped_sections[] = {
    {"Corners", 1, 0},        {"RequiredVertices", 1, 0}, {"Ridges", 1, 0}, {"RequiredEdges", 1, 0},
    {"RequiredTriangles", 1, 0}, {"Normals", 0, 3},       {"Tangents", 0, 3}, {"NormalAtVertices", 2, 0},
};

/* Volume element keywords whose node order has not been checked against a real file yet: refused
 * rather than risking inverted cells (docs/ARCHITECTURE.md §7). */
static const char *const unverified_sections[] = {"Prisms", "Pyramids"};

/* Count of rows after a keyword, checked against the bytes left: each row holds `values` numbers of at
 * least one character and a separator, so absurd counts fail before anything is allocated. */
static int read_count(medit_reader *r, const char *keyword, int values, int64_t *n)
{
    char what[64];
    snprintf(what, sizeof what, "the number of %s", keyword);
    if (tpk_scan_int64(&r->s, n, what))
        return -1;
    size_t left = r->s.size - r->s.pos;
    if (*n < 0)
        return tpk_scan_fail(&r->s, "%s: expected a count of 0 or more, found %lld", keyword, (long long)*n);
    if ((uint64_t)*n > left / (2 * (uint64_t)values) + 1)
        return tpk_scan_fail(&r->s, "%s %lld: that many rows of %d numbers cannot fit in the %zu bytes left "
                                    "(wrong count or truncated file)",
                             keyword, (long long)*n, values, left);
    if (*n > INT32_MAX)
        return tpk_scan_fail(&r->s, "%s %lld: more than 2^31-1", keyword, (long long)*n);
    return 0;
}

static int read_vertices(medit_reader *r)
{
    int64_t n;
    if (r->point_count >= 0)
        return tpk_scan_fail(&r->s, "expected one Vertices section, found a second");
    if (read_count(r, "Vertices", 4, &n))
        return -1;
    r->points = malloc(sizeof *r->points * 3 * (size_t)(n ? n : 1));
    r->point_refs = malloc(sizeof *r->point_refs * (size_t)(n ? n : 1));
    if (!r->points || !r->point_refs)
        return tpk_scan_fail(&r->s, "Vertices %lld: out of memory", (long long)n);
    for (int64_t v = 0; v < n; v++) {
        int64_t ref;
        for (int k = 0; k < 3; k++)
            if (tpk_scan_double(&r->s, &r->points[3 * v + k], "a vertex coordinate"))
                return -1;
        if (tpk_scan_int64(&r->s, &ref, "a vertex reference (an integer)"))
            return -1;
        r->point_refs[v] = (float)ref;
        r->any_point_ref |= ref != 0;
    }
    r->point_count = n;
    return 0;
}

/* Grow the cell arrays for `more` cells of `nodes` nodes. */
static int reserve_cells(medit_reader *r, int64_t more, int nodes)
{
    int64_t cells = r->cell_count + more, conn = r->conn_count + more * nodes;
    if (cells > INT32_MAX)
        return tpk_scan_fail(&r->s, "%lld volume elements in all: more than 2^31-1", (long long)cells);
    uint8_t *types = realloc(r->types, (size_t)(cells ? cells : 1));
    if (types)
        r->types = types;
    int64_t *offsets = realloc(r->offsets, sizeof *offsets * (size_t)(cells + 1));
    if (offsets)
        r->offsets = offsets;
    int32_t *ids = realloc(r->conn, sizeof *ids * (size_t)(conn ? conn : 1));
    if (ids)
        r->conn = ids;
    float *refs = realloc(r->cell_refs, sizeof *refs * (size_t)(cells ? cells : 1));
    if (refs)
        r->cell_refs = refs;
    if (!types || !offsets || !ids || !refs)
        return tpk_scan_fail(&r->s, "out of memory for %lld elements", (long long)cells);
    r->offsets[r->cell_count] = r->conn_count;
    return 0;
}

static int read_elements(medit_reader *r, const element_section *sec)
{
    int64_t n;
    if (read_count(r, sec->keyword, sec->nodes + 1, &n))
        return -1;
    if (sec->cell_type && reserve_cells(r, n, sec->nodes))
        return -1;
    char what[80];
    snprintf(what, sizeof what, "a vertex id of one of the %s", sec->keyword);
    for (int64_t e = 0; e < n; e++) {
        int64_t id, ref;
        for (int k = 0; k < sec->nodes; k++) {
            if (tpk_scan_int64(&r->s, &id, what))
                return -1;
            if (id < 1 || id > INT32_MAX)
                return tpk_scan_fail(&r->s, "%s %lld: vertex id %lld, expected 1 or more (ids are 1-based)",
                                     sec->keyword, (long long)e + 1, (long long)id);
            if (sec->cell_type)
                r->conn[r->conn_count + k] = (int32_t)id;
        }
        if (tpk_scan_int64(&r->s, &ref, "an element reference (an integer)"))
            return -1;
        if (!sec->cell_type) {
            r->dropped++;
            continue;
        }
        r->types[r->cell_count] = (uint8_t)sec->cell_type;
        r->cell_refs[r->cell_count] = (float)ref;
        r->conn_count += sec->nodes;
        r->offsets[++r->cell_count] = r->conn_count;
    }
    return 0;
}

static int skip_section(medit_reader *r, const char *keyword, int ints, int reals)
{
    int64_t n;
    if (read_count(r, keyword, ints + reals, &n))
        return -1;
    for (int64_t i = 0; i < n; i++) {
        int64_t iv;
        double dv;
        for (int k = 0; k < ints; k++)
            if (tpk_scan_int64(&r->s, &iv, "an integer"))
                return -1;
        for (int k = 0; k < reals; k++)
            if (tpk_scan_double(&r->s, &dv, "a number"))
                return -1;
    }
    return 0;
}

static int read_header(medit_reader *r)
{
    const char *tok;
    size_t len = tpk_scan_token(&r->s, &tok);
    char q[64];
    int64_t version, dim;
    if (!len || !tpk_token_is(tok, len, "MeshVersionFormatted"))
        return tpk_scan_fail(&r->s, "expected 'MeshVersionFormatted' (a Medit .mesh file), found '%s'",
                             len ? tpk_scan_quote(tok, len, q, sizeof q) : "end of file");
    if (tpk_scan_int64(&r->s, &version, "the format version"))
        return -1;
    if (version < 1 || version > 4)
        return tpk_scan_fail(&r->s, "expected format version 1 to 4, found %lld", (long long)version);
    len = tpk_scan_token(&r->s, &tok);
    if (!len || !tpk_token_is(tok, len, "Dimension"))
        return tpk_scan_fail(&r->s, "expected 'Dimension', found '%s'",
                             len ? tpk_scan_quote(tok, len, q, sizeof q) : "end of file");
    if (tpk_scan_int64(&r->s, &dim, "the dimension"))
        return -1;
    if (dim != 3)
        return tpk_scan_fail(&r->s, "expected dimension 3 (a volume mesh), found %lld", (long long)dim);
    return 0;
}

/* One keyword and its section. Returns 1 at End, 0 to go on, -1 on error. */
static int read_keyword(medit_reader *r, const char *tok, size_t len)
{
    char q[64];
    if (tpk_token_is(tok, len, "End"))
        return 1;
    if (tpk_token_is(tok, len, "Vertices"))
        return read_vertices(r);
    for (size_t i = 0; i < sizeof element_sections / sizeof element_sections[0]; i++)
        if (tpk_token_is(tok, len, element_sections[i].keyword))
            return read_elements(r, &element_sections[i]);
    for (size_t i = 0; i < sizeof skipped_sections / sizeof skipped_sections[0]; i++)
        if (tpk_token_is(tok, len, skipped_sections[i].keyword))
            return skip_section(r, skipped_sections[i].keyword, skipped_sections[i].ints, skipped_sections[i].reals);
    for (size_t i = 0; i < sizeof unverified_sections / sizeof unverified_sections[0]; i++)
        if (tpk_token_is(tok, len, unverified_sections[i]))
            return tpk_scan_fail(&r->s, "%s are not read yet (their Medit node order is not checked against a "
                                        "real file); convert the mesh to VTK or Gmsh meanwhile",
                                 unverified_sections[i]);
    return tpk_scan_fail(&r->s, "unknown Medit keyword '%s'; this reader knows Vertices, Edges, Triangles, "
                                "Quadrilaterals, Tetrahedra, Hexahedra, Corners, Ridges, Required*, Normals, "
                                "Tangents and End", tpk_scan_quote(tok, len, q, sizeof q));
}

/* Ids to 0-based, checked against the vertex count; the mesh takes over the arrays. */
static int finish(medit_reader *r, tpk_mesh *out)
{
    if (r->point_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a Vertices section, found end of file");
    for (int64_t c = 0; c < r->cell_count; c++)
        for (int64_t k = r->offsets[c]; k < r->offsets[c + 1]; k++) {
            if (r->conn[k] > r->point_count)
                return tpk_scan_fail_at(&r->s, r->s.size, r->s.line,
                                        "element %lld (%s) uses vertex %d, but there are only %lld vertices",
                                        (long long)c + 1, tpk_cell_type(r->types[c])->name, r->conn[k],
                                        (long long)r->point_count);
            r->conn[k] -= 1;
        }
    if (r->dropped)
        tpk_diag_warn(r->s.diag, "%s: dropped %lld surface and line elements (edges, triangles, quadrilaterals)",
                      r->s.name, (long long)r->dropped);
    if (tpk_import_take_cells(out, r->point_count, &r->points, r->cell_count, &r->types, &r->offsets, &r->conn))
        return tpk_scan_fail(&r->s, "out of memory");
    if (tpk_mesh_add_field(out, "ref", TPK_ASSOC_TET, 1, 1, r->cell_refs))
        return tpk_scan_fail(&r->s, "out of memory");
    r->cell_refs = NULL;
    if (r->any_point_ref) {
        if (tpk_mesh_add_field(out, "vertex_ref", TPK_ASSOC_POINT, 1, 1, r->point_refs))
            return tpk_scan_fail(&r->s, "out of memory");
        r->point_refs = NULL;
    }
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "medit-ascii");
    return 0;
}

static void reader_free(medit_reader *r)
{
    free(r->points);
    free(r->point_refs);
    free(r->types);
    free(r->offsets);
    free(r->conn);
    free(r->cell_refs);
}

static int import_buffer(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
    medit_reader r;
    memset(&r, 0, sizeof r);
    tpk_scan_init(&r.s, name, data, size, diag);
    r.s.hash_comments = 1;
    r.s.mapped = mapped;
    r.point_count = -1;
    int rc = read_header(&r);
    while (rc == 0) {
        const char *tok;
        size_t len = tpk_scan_token(&r.s, &tok);
        if (!len)
            break;
        rc = read_keyword(&r, tok, len);
        tpk_scan_release_consumed(&r.s);
    }
    if (rc >= 0)
        rc = finish(&r, out);
    reader_free(&r);
    return tpk_import_end(rc, out);
}

int tpk_import_medit_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_medit(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
