/* PLY reader (ascii, binary_little_endian, binary_big_endian 1.0): the "vertex" element gives points
 * (x, y, z) and point fields (its other scalar properties), the "face" element polygons (its list
 * property vertex_indices or vertex_index); other elements and properties are read and skipped. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surface.h"
#include "tetpack_format.h"
#include "surface_build.h"
#include "base/text_scan.h"

#define PLY_MAX_ELEMENTS 16
#define PLY_MAX_PROPERTIES 64

enum { PLY_ASCII, PLY_LITTLE, PLY_BIG };

typedef struct ply_type {
    const char *name, *alias;
    int size, is_float, is_signed;
} ply_type;

static const ply_type ply_types[] = {
    {"char", "int8", 1, 0, 1},     {"uchar", "uint8", 1, 0, 0},   {"short", "int16", 2, 0, 1},
    {"ushort", "uint16", 2, 0, 0}, {"int", "int32", 4, 0, 1},     {"uint", "uint32", 4, 0, 0},
    {"float", "float32", 4, 1, 1}, {"double", "float64", 8, 1, 1}};

typedef struct ply_property {
    char name[TPK_NAME_MAX];
    const ply_type *type;       /* the value type (items of a list) */
    const ply_type *count_type; /* a list's count type, or NULL */
} ply_property;

typedef struct ply_element {
    char name[TPK_NAME_MAX];
    int64_t count;
    int property_count;
    ply_property properties[PLY_MAX_PROPERTIES];
} ply_element;

typedef struct ply_file {
    tpk_scan scan;
    int encoding;
    int element_count;
    ply_element elements[PLY_MAX_ELEMENTS];
} ply_file;

static const ply_type *find_type(const char *tok, size_t len)
{
    for (size_t i = 0; i < sizeof ply_types / sizeof ply_types[0]; i++)
        if (tpk_token_is(tok, len, ply_types[i].name) || tpk_token_is(tok, len, ply_types[i].alias))
            return &ply_types[i];
    return NULL;
}

static void copy_name(char *dst, const char *tok, size_t len)
{
    len = len < TPK_NAME_MAX - 1 ? len : TPK_NAME_MAX - 1;
    memcpy(dst, tok, len);
    dst[len] = 0;
}

static int header_type(ply_file *p, const ply_type **type)
{
    const char *tok;
    size_t len = tpk_scan_line_token(&p->scan, &tok);
    char q[64];
    if (!(*type = find_type(tok, len)))
        return tpk_scan_fail(&p->scan, "expected a PLY type (char, uchar, short, ushort, int, uint, float, "
                             "double or int8 ... float64), found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    return 0;
}

static int header_property(ply_file *p)
{
    if (p->element_count == 0)
        return tpk_scan_fail(&p->scan, "expected 'element' before the first 'property'");
    ply_element *e = &p->elements[p->element_count - 1];
    if (e->property_count == PLY_MAX_PROPERTIES)
        return tpk_scan_fail(&p->scan, "more than %d properties in element '%s'", PLY_MAX_PROPERTIES, e->name);
    ply_property *prop = &e->properties[e->property_count++];
    const char *tok;
    size_t len = tpk_scan_line_token(&p->scan, &tok);
    p->scan.pos -= len; /* re-read it as a type unless it is "list" */
    if (tpk_token_is(tok, len, "list")) {
        p->scan.pos += len;
        if (header_type(p, &prop->count_type))
            return -1;
        if (prop->count_type->is_float)
            return tpk_scan_fail(&p->scan, "expected an integer type for a list count, found '%s'",
                                 prop->count_type->name);
    }
    if (header_type(p, &prop->type))
        return -1;
    len = tpk_scan_line_token(&p->scan, &tok);
    if (!len)
        return tpk_scan_fail(&p->scan, "expected a property name, found end of line");
    copy_name(prop->name, tok, len);
    return tpk_scan_end_line(&p->scan, "the property name");
}

static int header_element(ply_file *p)
{
    if (p->element_count == PLY_MAX_ELEMENTS)
        return tpk_scan_fail(&p->scan, "more than %d elements", PLY_MAX_ELEMENTS);
    ply_element *e = &p->elements[p->element_count++];
    const char *tok;
    size_t len = tpk_scan_line_token(&p->scan, &tok);
    if (!len)
        return tpk_scan_fail(&p->scan, "expected an element name, found end of line");
    copy_name(e->name, tok, len);
    if (tpk_scan_line_int64(&p->scan, &e->count, "the element count"))
        return -1;
    if (e->count < 0 || e->count > INT32_MAX)
        return tpk_scan_fail(&p->scan, "expected an element count from 0 to 2^31-1, found %lld", (long long)e->count);
    return tpk_scan_end_line(&p->scan, "the element count");
}

static int header_format(ply_file *p)
{
    const char *tok;
    size_t len = tpk_scan_line_token(&p->scan, &tok);
    char q[64];
    if (tpk_token_is(tok, len, "ascii"))
        p->encoding = PLY_ASCII;
    else if (tpk_token_is(tok, len, "binary_little_endian"))
        p->encoding = PLY_LITTLE;
    else if (tpk_token_is(tok, len, "binary_big_endian"))
        p->encoding = PLY_BIG;
    else
        return tpk_scan_fail(&p->scan, "expected ascii, binary_little_endian or binary_big_endian, found '%s'",
                             tpk_scan_quote(tok, len, q, sizeof q));
    len = tpk_scan_line_token(&p->scan, &tok);
    if (!tpk_token_is(tok, len, "1.0"))
        return tpk_scan_fail(&p->scan, "expected PLY version 1.0, found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    return tpk_scan_end_line(&p->scan, "the version");
}

/* Header lines up to and including end_header; leaves the scanner at the first data byte. */
static int read_header(ply_file *p)
{
    tpk_scan *s = &p->scan;
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    char q[64];
    if (!tpk_token_is(tok, len, "ply") || tpk_scan_end_line(s, "ply"))
        return tpk_scan_fail(s, "expected 'ply' on the first line, found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    int have_format = 0;
    for (;;) {
        len = tpk_scan_line_token(s, &tok);
        if (!len && s->pos < s->size) {
            tpk_scan_end_line(s, "");
            continue;
        }
        if (!len)
            return tpk_scan_fail_at(s, s->size, s->line, "expected 'end_header', found end of file");
        int rc = 0;
        if (tpk_token_is(tok, len, "comment") || tpk_token_is(tok, len, "obj_info"))
            tpk_scan_skip_line(s);
        else if (tpk_token_is(tok, len, "format") && !have_format)
            rc = header_format(p), have_format = 1;
        else if (tpk_token_is(tok, len, "element") && have_format)
            rc = header_element(p);
        else if (tpk_token_is(tok, len, "property") && have_format)
            rc = header_property(p);
        else if (tpk_token_is(tok, len, "end_header") && have_format)
            return tpk_scan_end_line(s, "end_header");
        else
            return tpk_scan_fail(s, "expected %s, found '%s'",
                                 have_format ? "'element', 'property', 'comment' or 'end_header'" : "'format'",
                                 tpk_scan_quote(tok, len, q, sizeof q));
        if (rc)
            return -1;
    }
}

/* One value of `type`: an ASCII token or binary bytes in the file's byte order. */
static int read_value(ply_file *p, const ply_type *type, double *v, const char *what, int64_t item)
{
    tpk_scan *s = &p->scan;
    if (p->encoding == PLY_ASCII) {
        char full[96];
        snprintf(full, sizeof full, "%s of item %lld", what, (long long)item);
        return tpk_scan_double(s, v, full);
    }
    if (s->size - s->pos < (size_t)type->size)
        return tpk_scan_fail_at(s, s->pos, 0, "expected %s of item %lld (%d bytes), found end of file "
                                "(truncated file or wrong count)", what, (long long)item, type->size);
    const unsigned char *b = s->data + s->pos;
    int big = p->encoding == PLY_BIG;
    switch (type->size * 2 + type->is_float) {
    case 2: *v = type->is_signed ? (double)(int8_t)b[0] : (double)b[0]; break;
    case 4: {
        unsigned u = big ? (unsigned)b[0] << 8 | b[1] : (unsigned)b[1] << 8 | b[0];
        *v = type->is_signed ? (double)(int16_t)u : (double)u;
        break;
    }
    case 8: {
        uint32_t u = tpk_surf_u32(b, big);
        *v = type->is_signed ? (double)(int32_t)u : (double)u;
        break;
    }
    case 9: *v = tpk_surf_f32(b, big); break;
    default: *v = tpk_surf_f64(b, big); break;
    }
    s->tok_pos = s->pos;
    s->pos += (size_t)type->size;
    return 0;
}

/* Smallest bytes an item of `e` takes, to bound its count by the bytes left. */
static size_t min_item_bytes(const ply_file *p, const ply_element *e)
{
    size_t n = 0;
    for (int i = 0; i < e->property_count; i++) {
        const ply_property *prop = &e->properties[i];
        n += p->encoding == PLY_ASCII ? 2 : (size_t)(prop->count_type ? prop->count_type->size : prop->type->size);
    }
    return n;
}

/* Where the properties of the vertex and face elements go. */
typedef struct ply_target {
    tpk_mesh *mesh;
    float *field_values[PLY_MAX_PROPERTIES]; /* per vertex property; NULL for x, y, z and lists */
    int axis[PLY_MAX_PROPERTIES];            /* 0, 1, 2 for x, y, z; -1 otherwise */
    int index_list;                          /* the face element's index list property, or -1 */
    int64_t conn_cap;
} ply_target;

static int store_face_corner(ply_file *p, ply_target *t, int64_t face, int64_t k, double v)
{
    tpk_mesh *m = t->mesh;
    int64_t at = m->cell_offsets[face] + k;
    if (v != floor(v) || v < 0 || v >= (double)m->point_count)
        return tpk_scan_fail(&p->scan, "expected a vertex index of face %lld from 0 to %lld, found %g",
                             (long long)face, (long long)m->point_count - 1, v);
    if (at >= t->conn_cap) {
        int32_t *grown = realloc(m->cell_conn, sizeof(int32_t) * (size_t)(t->conn_cap *= 2));
        if (!grown)
            return tpk_scan_fail(&p->scan, "out of memory for the corners of face %lld", (long long)face);
        m->cell_conn = grown;
    }
    m->cell_conn[at] = (int32_t)v;
    return 0;
}

/* A list property: its count, then the items (face corners when it is the face's index list). */
static int read_list(ply_file *p, ply_target *t, const ply_property *prop, int is_faces, int64_t item)
{
    double count, v;
    if (read_value(p, prop->count_type, &count, "a list count", item))
        return -1;
    if (count != floor(count) || count < 0 || count > 1000000 || (is_faces && count < 3))
        return tpk_scan_fail(&p->scan, "expected a count of '%s' from %d to 1000000 in item %lld, found %g",
                             prop->name, is_faces ? 3 : 0, (long long)item, count);
    for (int64_t k = 0; k < (int64_t)count; k++) {
        if (read_value(p, prop->type, &v, prop->name, item))
            return -1;
        if (is_faces && store_face_corner(p, t, item, k, v))
            return -1;
    }
    if (is_faces) {
        t->mesh->cell_offsets[item + 1] = t->mesh->cell_offsets[item] + (int64_t)count;
        t->mesh->cell_types[item] = count == 3 ? TPK_CELL_SURF_TRIANGLE : TPK_CELL_SURF_POLYGON;
    }
    return 0;
}

static int read_element(ply_file *p, ply_target *t, const ply_element *e, int role)
{
    size_t need = min_item_bytes(p, e), left = p->scan.size - p->scan.pos;
    if (need && (uint64_t)e->count > left / need)
        return tpk_scan_fail_at(&p->scan, p->scan.pos, p->scan.line, "%lld items of element '%s' cannot fit in "
                                "the %zu bytes left (wrong count or truncated file)", (long long)e->count, e->name, left);
    for (int64_t item = 0; item < e->count; item++) {
        for (int i = 0; i < e->property_count; i++) {
            const ply_property *prop = &e->properties[i];
            double v;
            if (prop->count_type) {
                if (read_list(p, t, prop, role == 2 && i == t->index_list, item))
                    return -1;
                continue;
            }
            if (read_value(p, prop->type, &v, prop->name, item))
                return -1;
            if (role == 1 && t->axis[i] >= 0) {
                if (!isfinite(v))
                    return tpk_scan_fail(&p->scan, "expected a finite %s of vertex %lld, found %g", prop->name,
                                         (long long)item, v);
                t->mesh->points[3 * item + t->axis[i]] = v;
            } else if (role == 1) {
                t->field_values[i][item] = (float)v;
            }
        }
    }
    return 0;
}

static const ply_element *find_element(const ply_file *p, const char *name)
{
    for (int i = 0; i < p->element_count; i++)
        if (!strcmp(p->elements[i].name, name))
            return &p->elements[i];
    return NULL;
}

/* Roles of the vertex properties and the face index list; allocates the mesh and field arrays. */
static int plan_targets(ply_file *p, const ply_element *vertices, const ply_element *faces, ply_target *t)
{
    int found[3] = {0, 0, 0};
    for (int i = 0; i < vertices->property_count; i++) {
        const ply_property *prop = &vertices->properties[i];
        t->axis[i] = -1;
        for (int k = 0; k < 3 && !prop->count_type; k++)
            if (!strcmp(prop->name, (const char *[]){"x", "y", "z"}[k]))
                t->axis[i] = k, found[k] = 1;
    }
    if (!found[0] || !found[1] || !found[2])
        return tpk_scan_fail(&p->scan, "element 'vertex' lacks scalar property x, y or z");
    t->index_list = -1;
    for (int i = 0; faces && i < faces->property_count; i++)
        if (faces->properties[i].count_type && (!strcmp(faces->properties[i].name, "vertex_indices") ||
                                                !strcmp(faces->properties[i].name, "vertex_index")))
            t->index_list = i;
    if (faces && faces->count > 0 && t->index_list < 0)
        return tpk_scan_fail(&p->scan, "element 'face' lacks a list property vertex_indices (or vertex_index)");
    int64_t nf = faces ? faces->count : 0;
    t->conn_cap = 3 * nf + 16;
    if (tpk_surf_alloc(t->mesh, vertices->count, nf, t->conn_cap) != 0)
        return tpk_scan_fail(&p->scan, "out of memory for %lld vertices", (long long)vertices->count);
    for (int i = 0; i < vertices->property_count; i++) {
        if (t->axis[i] >= 0 || vertices->properties[i].count_type)
            continue;
        t->field_values[i] = malloc(sizeof(float) * (size_t)(vertices->count ? vertices->count : 1));
        if (!t->field_values[i])
            return tpk_scan_fail(&p->scan, "out of memory for vertex property '%s'", vertices->properties[i].name);
    }
    return 0;
}

/* Hand the vertex property arrays to the mesh as point fields (in property order). */
static int attach_fields(ply_file *p, const ply_element *vertices, ply_target *t)
{
    for (int i = 0; i < vertices->property_count; i++) {
        if (!t->field_values[i])
            continue;
        if (tpk_mesh_add_field(t->mesh, vertices->properties[i].name, TPK_ASSOC_POINT, 1, 1, t->field_values[i]))
            return tpk_scan_fail(&p->scan, "out of memory for vertex property '%s'", vertices->properties[i].name);
        t->field_values[i] = NULL;
    }
    return 0;
}

static int read_body(ply_file *p, tpk_mesh *out, ply_target *t)
{
    if (read_header(p))
        return -1;
    const ply_element *vertices = find_element(p, "vertex"), *faces = find_element(p, "face");
    if (!vertices)
        return tpk_scan_fail(&p->scan, "the header declares no element 'vertex'");
    t->mesh = out;
    if (plan_targets(p, vertices, faces, t))
        return -1;
    if (p->encoding != PLY_ASCII)
        p->scan.byte_places = 1;
    for (int i = 0; i < p->element_count; i++) {
        const ply_element *e = &p->elements[i];
        if (read_element(p, t, e, e == vertices ? 1 : e == faces ? 2 : 0))
            return -1;
    }
    if (attach_fields(p, vertices, t))
        return -1;
    const char *tok;
    size_t len = p->encoding == PLY_ASCII ? tpk_scan_token(&p->scan, &tok) : p->scan.size - p->scan.pos;
    if (len)
        return tpk_scan_fail_at(&p->scan, p->scan.pos - (p->encoding == PLY_ASCII ? len : 0), p->scan.line,
                                "data after the last element the header declares (wrong count?)");
    snprintf(out->format, sizeof out->format, "ply-%s",
             p->encoding == PLY_ASCII ? "ascii" : p->encoding == PLY_LITTLE ? "binary-le" : "binary-be");
    return 0;
}

int tpk_read_ply(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    ply_file *p = calloc(1, sizeof *p);
    ply_target t;
    memset(&t, 0, sizeof t);
    memset(out, 0, sizeof *out);
    if (!p)
        return tpk_diag_fail(diag, "%s: out of memory", name);
    tpk_scan_init(&p->scan, name, data, size, diag);
    int rc = read_body(p, out, &t);
    for (int i = 0; i < PLY_MAX_PROPERTIES; i++)
        free(t.field_values[i]);
    if (rc)
        tpk_mesh_free(out);
    free(p);
    return rc;
}
