/* Legacy DOLFIN XML importer (FEniCS before DOLFINx; meshio's "dolfin-xml"): <dolfin><mesh celltype=
 * "tetrahedron"|"hexahedron" dim="3"> with <vertices size=N><vertex index x y z/> and <cells size=M>
 * <tetrahedron index v0..v3/> (or <hexahedron v0..v7/>); <domains> value collections of dimension 3
 * become cell fields. Parsed with expat; a DOCTYPE is refused (no entity expansion). */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tetpack_format.h"

#include "base/text_scan.h"
#include "import_file.h"
#include "importers.h"
#include "xml_input.h"

/* DOLFIN numbers a hexahedron's vertices lexicographically (x fastest, then y, then z: its
 * UnitCubeMesh and BoxMesh write them so); VTK goes around each face. */
static const int hex_to_vtk[8] = {0, 1, 3, 2, 4, 5, 7, 6};

typedef struct dolfin_field {
    char name[TPK_NAME_MAX];
    float *values; /* per cell, 0 where the collection gives none */
} dolfin_field;

typedef struct dolfin_reader {
    const char *name;
    size_t size;
    XML_Parser parser;
    tpk_diag *diag;
    int failed;
    int in_dolfin, in_mesh, in_vertices, in_cells, in_collection;
    int cell_nodes, cell_type; /* from celltype */
    const char *cell_tag;
    int64_t point_count, points_seen; /* -1 until <vertices> */
    double *points;
    uint8_t *point_set;
    int64_t cell_count, cells_seen;   /* -1 until <cells> */
    int32_t *conn;
    uint8_t *cell_set;
    dolfin_field *fields;
    int field_count;
    int collection_dim;
    int64_t ignored; /* elements this reader does not use */
} dolfin_reader;

static int fail(dolfin_reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static int fail(dolfin_reader *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    tpk_import_place at = {r->name, (long)XML_GetCurrentLineNumber(r->parser), -1, NULL};
    tpk_import_vfail(r->diag, &r->failed, at, fmt, ap);
    va_end(ap);
    XML_StopParser(r->parser, XML_FALSE);
    return -1;
}

/* The element name without a namespace prefix ("dolfin:mesh" -> "mesh"). */
static const char *local_name(const char *el)
{
    const char *colon = strrchr(el, ':');
    return colon ? colon + 1 : el;
}

/* An attribute value for a message: quoted, or "none" when absent. */
static const char *found(const char *v, char *buf, size_t cap)
{
    char q[64];
    if (!v)
        return "none";
    snprintf(buf, cap, "'%s'", tpk_scan_quote(v, strlen(v), q, sizeof q));
    return buf;
}

static const char *attr(const XML_Char **atts, const char *key)
{
    for (int i = 0; atts[i]; i += 2)
        if (!strcmp(atts[i], key))
            return atts[i + 1];
    return NULL;
}

/* Attribute `key` of element `el` as an integer in [0, max); -1 after failing with a message. */
static int int_attr(dolfin_reader *r, const char *el, const XML_Char **atts, const char *key, int64_t max,
                    int64_t *out)
{
    const char *v = attr(atts, key);
    char q[72];
    if (!v || tpk_parse_int64(v, strlen(v), out) != 0 || *out < 0 || *out >= max)
        return fail(r, "<%s>: expected %s to be an integer from 0 to %lld, found %s", el, key, (long long)max - 1,
                    found(v, q, sizeof q));
    return 0;
}

/* A count attribute ("size"), bounded by the file: each item takes at least `item_bytes` of it. */
static int count_attr(dolfin_reader *r, const char *el, const XML_Char **atts, size_t item_bytes, int64_t *out)
{
    int64_t bound = (int64_t)(r->size / item_bytes) + 1, n;
    if (bound > INT32_MAX)
        bound = INT32_MAX;
    const char *v = attr(atts, "size");
    if (v && tpk_parse_int64(v, strlen(v), &n) == 0 && n > bound)
        return fail(r, "<%s size=\"%lld\">: that many items cannot fit in the %zu bytes of the file (wrong count?)",
                    el, (long long)n, r->size);
    return int_attr(r, el, atts, "size", bound + 1, out);
}

static int start_mesh(dolfin_reader *r, const XML_Char **atts)
{
    const char *type = attr(atts, "celltype"), *dim = attr(atts, "dim");
    char q[72];
    if (r->in_mesh || r->point_count >= 0)
        return fail(r, "expected one <mesh>, found a second");
    if (type && !strcmp(type, "tetrahedron")) {
        r->cell_nodes = 4, r->cell_type = TPK_CELL_TETRA;
    } else if (type && !strcmp(type, "hexahedron")) {
        r->cell_nodes = 8, r->cell_type = TPK_CELL_HEXAHEDRON;
    } else {
        return fail(r, "<mesh>: expected celltype \"tetrahedron\" or \"hexahedron\" (a volume mesh), found %s",
                    found(type, q, sizeof q));
    }
    if (!dim || strcmp(dim, "3") != 0)
        return fail(r, "<mesh>: expected dim=\"3\", found %s", found(dim, q, sizeof q));
    r->cell_tag = r->cell_type == TPK_CELL_TETRA ? "tetrahedron" : "hexahedron";
    r->in_mesh = 1;
    return 0;
}

static int start_vertices(dolfin_reader *r, const XML_Char **atts)
{
    if (r->point_count >= 0)
        return fail(r, "expected one <vertices>, found a second");
    /* <vertex index="0" x="0" y="0" z="0"/> is 35 bytes at least */
    if (count_attr(r, "vertices", atts, 35, &r->point_count))
        return -1;
    size_t n = (size_t)(r->point_count ? r->point_count : 1);
    r->points = malloc(sizeof *r->points * 3 * n);
    r->point_set = calloc(n, 1);
    if (!r->points || !r->point_set)
        return fail(r, "<vertices>: out of memory for %lld vertices", (long long)r->point_count);
    r->in_vertices = 1;
    return 0;
}

static int start_vertex(dolfin_reader *r, const XML_Char **atts)
{
    int64_t v;
    if (int_attr(r, "vertex", atts, "index", r->point_count, &v))
        return -1;
    if (r->point_set[v])
        return fail(r, "<vertex index=\"%lld\">: expected each index once, found it again", (long long)v);
    static const char *const xyz[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; k++) {
        const char *c = attr(atts, xyz[k]);
        char q[72];
        if (!c || tpk_parse_double(c, strlen(c), &r->points[3 * v + k]) != 0)
            return fail(r, "<vertex index=\"%lld\">: expected a number %s, found %s", (long long)v, xyz[k],
                        found(c, q, sizeof q));
    }
    r->point_set[v] = 1;
    r->points_seen++;
    return 0;
}

static int start_cells(dolfin_reader *r, const XML_Char **atts)
{
    if (r->cell_count >= 0)
        return fail(r, "expected one <cells>, found a second");
    if (count_attr(r, "cells", atts, 40, &r->cell_count))
        return -1;
    size_t n = (size_t)(r->cell_count ? r->cell_count : 1);
    r->conn = malloc(sizeof *r->conn * (size_t)r->cell_nodes * n);
    r->cell_set = calloc(n, 1);
    if (!r->conn || !r->cell_set)
        return fail(r, "<cells>: out of memory for %lld cells", (long long)r->cell_count);
    r->in_cells = 1;
    return 0;
}

static int start_cell(dolfin_reader *r, const char *el, const XML_Char **atts)
{
    int64_t c, v;
    if (strcmp(el, r->cell_tag) != 0)
        return fail(r, "<cells>: expected <%s> (the mesh's celltype), found <%s>", r->cell_tag, el);
    if (int_attr(r, el, atts, "index", r->cell_count, &c))
        return -1;
    if (r->cell_set[c])
        return fail(r, "<%s index=\"%lld\">: expected each index once, found it again", el, (long long)c);
    if (r->point_count < 0)
        return fail(r, "<%s>: expected <vertices> before the cells, found none", el);
    for (int k = 0; k < r->cell_nodes; k++) {
        char key[4] = {'v', (char)('0' + k), 0, 0};
        if (int_attr(r, el, atts, key, r->point_count, &v))
            return -1;
        int at = r->cell_type == TPK_CELL_HEXAHEDRON ? hex_to_vtk[k] : k;
        r->conn[c * r->cell_nodes + at] = (int32_t)v;
    }
    r->cell_set[c] = 1;
    r->cells_seen++;
    return 0;
}

/* <mesh_value_collection name= dim= size=> in <domains>: dimension 3 is one value per cell. */
static int start_collection(dolfin_reader *r, const XML_Char **atts)
{
    const char *dim = attr(atts, "dim"), *name = attr(atts, "name");
    r->in_collection = 1;
    r->collection_dim = dim && !strcmp(dim, "3") ? 3 : 0;
    if (r->collection_dim != 3) {
        r->ignored++;
        return 0;
    }
    if (r->cell_count < 0)
        return fail(r, "<mesh_value_collection>: expected <cells> before it, found none");
    dolfin_field *grown = realloc(r->fields, sizeof *grown * (size_t)(r->field_count + 1));
    if (!grown)
        return fail(r, "out of memory");
    r->fields = grown;
    dolfin_field *f = &r->fields[r->field_count++];
    snprintf(f->name, sizeof f->name, "%s", name && *name ? name : "domain");
    f->values = calloc((size_t)(r->cell_count ? r->cell_count : 1), sizeof *f->values);
    if (!f->values)
        return fail(r, "out of memory");
    return 0;
}

static int start_value(dolfin_reader *r, const XML_Char **atts)
{
    int64_t c;
    double value;
    const char *v = attr(atts, "value");
    char q[72];
    if (r->collection_dim != 3)
        return 0;
    if (int_attr(r, "value", atts, "cell_index", r->cell_count, &c))
        return -1;
    if (!v || tpk_parse_double(v, strlen(v), &value) != 0)
        return fail(r, "<value cell_index=\"%lld\">: expected a number value, found %s", (long long)c,
                    found(v, q, sizeof q));
    r->fields[r->field_count - 1].values[c] = (float)value;
    return 0;
}

static void XMLCALL on_start(void *user, const XML_Char *tag, const XML_Char **atts)
{
    dolfin_reader *r = user;
    const char *el = local_name(tag);
    if (r->failed)
        return;
    if (!r->in_dolfin) {
        if (strcmp(el, "dolfin") != 0)
            fail(r, "expected a <dolfin> root element (a DOLFIN XML mesh), found <%.60s>", tag);
        r->in_dolfin = 1;
    } else if (!strcmp(el, "mesh")) {
        start_mesh(r, atts);
    } else if (r->in_vertices && !strcmp(el, "vertex")) {
        start_vertex(r, atts);
    } else if (r->in_cells) {
        start_cell(r, el, atts);
    } else if (r->in_collection && !strcmp(el, "value")) {
        start_value(r, atts);
    } else if (r->in_mesh && !strcmp(el, "vertices")) {
        start_vertices(r, atts);
    } else if (r->in_mesh && !strcmp(el, "cells")) {
        start_cells(r, atts);
    } else if (r->in_mesh && !strcmp(el, "mesh_value_collection")) {
        start_collection(r, atts);
    } else if (strcmp(el, "domains") != 0 && strcmp(el, "data") != 0) { /* containers: DOLFIN writes both */
        r->ignored++;
    }
}

static void XMLCALL on_end(void *user, const XML_Char *tag)
{
    dolfin_reader *r = user;
    const char *el = local_name(tag);
    if (!strcmp(el, "vertices"))
        r->in_vertices = 0;
    else if (!strcmp(el, "cells"))
        r->in_cells = 0;
    else if (!strcmp(el, "mesh_value_collection"))
        r->in_collection = 0;
    else if (!strcmp(el, "mesh"))
        r->in_mesh = 0;
}

static void XMLCALL on_doctype(void *user, const XML_Char *name, const XML_Char *sysid, const XML_Char *pubid,
                               int has_internal)
{
    (void)name, (void)sysid, (void)pubid, (void)has_internal;
    fail(user, "expected a DOLFIN XML file, found a DOCTYPE declaration (not read: entities could expand without "
               "bound)");
}

static int parse(dolfin_reader *r, const char *data, size_t size)
{
    r->parser = XML_ParserCreate(NULL);
    if (!r->parser)
        return tpk_diag_fail(r->diag, "%s: out of memory for the XML parser", r->name);
    XML_SetUserData(r->parser, r);
    XML_SetElementHandler(r->parser, on_start, on_end);
    XML_SetStartDoctypeDeclHandler(r->parser, on_doctype);
    return tpk_xml_parse(r->parser, r->name, data, size, 1, &r->failed, r->diag);
}

/* Every vertex and cell the counts promise is there; the mesh takes over the arrays. */
static int finish(dolfin_reader *r, tpk_mesh *out)
{
    if (r->point_count < 0 || r->cell_count < 0)
        return tpk_diag_fail(r->diag, "%s: expected <mesh> with <vertices> and <cells>, found %s", r->name,
                             r->point_count < 0 ? "no <vertices>" : "no <cells>");
    if (r->points_seen != r->point_count || r->cells_seen != r->cell_count)
        return tpk_diag_fail(r->diag, "%s: expected %lld vertices and %lld cells (the size attributes), found %lld "
                                      "and %lld", r->name, (long long)r->point_count, (long long)r->cell_count,
                             (long long)r->points_seen, (long long)r->cells_seen);
    size_t n = (size_t)r->cell_count;
    out->cell_types = malloc(n ? n : 1);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (n + 1));
    if (!out->cell_types || !out->cell_offsets)
        return tpk_diag_fail(r->diag, "%s: out of memory", r->name);
    for (size_t c = 0; c <= n; c++) {
        out->cell_offsets[c] = (int64_t)c * r->cell_nodes;
        if (c < n)
            out->cell_types[c] = (uint8_t)r->cell_type;
    }
    out->point_count = r->point_count;
    out->points = r->points;
    out->cell_count = r->cell_count;
    out->cell_conn = r->conn;
    r->points = NULL;
    r->conn = NULL;
    for (int i = 0; i < r->field_count; i++) {
        if (tpk_mesh_add_field(out, r->fields[i].name, TPK_ASSOC_TET, 1, 1, r->fields[i].values))
            return tpk_diag_fail(r->diag, "%s: out of memory", r->name);
        r->fields[i].values = NULL;
    }
    if (r->ignored)
        tpk_diag_warn(r->diag, "%s: ignored %lld elements this reader does not use (mesh data, value collections "
                               "of facets, edges or vertices)", r->name, (long long)r->ignored);
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "dolfin-xml");
    return 0;
}

int tpk_import_dolfin_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
    dolfin_reader r;
    memset(&r, 0, sizeof r);
    r.name = name;
    r.size = size;
    r.diag = diag;
    r.point_count = r.cell_count = -1;
    int rc = parse(&r, data, size);
    if (r.parser)
        XML_ParserFree(r.parser);
    if (rc == 0)
        rc = finish(&r, out);
    free(r.points);
    free(r.point_set);
    free(r.conn);
    free(r.cell_set);
    for (int i = 0; i < r.field_count; i++)
        free(r.fields[i].values);
    free(r.fields);
    return tpk_import_end(rc, out);
}

int tpk_import_dolfin(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped_memory(path, tpk_import_dolfin_memory, out, diag);
}

int tpk_sniff_dolfin(const char *head, size_t n)
{
    for (size_t i = 0; i + 7 <= n; i++)
        if (head[i] == '<' && !memcmp(head + i, "<dolfin", 7))
            return 1;
    return 0;
}
