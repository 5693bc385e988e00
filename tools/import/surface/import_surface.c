/* Surface and point-cloud input: the kind from the name or first bytes, dispatch to the readers, the
 * STL reader (ASCII and binary), and tpk_import_surface (read, then fill with tets: mesher/mesher.h).
 * OFF, PLY and CSV live in import_off.c, import_ply.c, import_csv.c. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "surface.h"
#include "surface_build.h"
#include "base/text_scan.h"

tpk_surface_kind tpk_surface_kind_from_name(const char *path)
{
    static const struct {
        const char *ext;
        tpk_surface_kind kind;
    } table[] = {{".stl", TPK_SURFACE_STL}, {".off", TPK_SURFACE_OFF}, {".ply", TPK_SURFACE_PLY},
                 {".csv", TPK_SURFACE_CSV}};
    size_t n = path ? strlen(path) : 0;
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (n > 4 && strcasecmp(path + n - 4, table[i].ext) == 0)
            return table[i].kind;
    return TPK_SURFACE_UNKNOWN;
}

static int binary_stl_size_matches(const char *data, size_t size)
{
    return size >= 84 && (uint64_t)size == 84 + 50 * (uint64_t)tpk_surf_u32((const unsigned char *)data + 80, 0);
}

/* The first line names x, y and z among comma-separated columns. */
static int looks_like_csv_header(const char *data, size_t size)
{
    const char *nl = memchr(data, '\n', size);
    size_t len = nl ? (size_t)(nl - data) : size;
    int commas = 0, axes = 0;
    for (size_t i = 0; i < len; i++) {
        commas += data[i] == ',';
        axes += data[i] == 'x' || data[i] == 'y' || data[i] == 'z' || data[i] == 'X' || data[i] == 'Y' ||
                data[i] == 'Z';
    }
    return commas >= 2 && axes >= 3;
}

tpk_surface_kind tpk_surface_kind_sniff(const char *data, size_t size)
{
    size_t at = 0;
    while (at < size && (data[at] == ' ' || data[at] == '\t' || data[at] == '\r' || data[at] == '\n'))
        at++;
    const char *head = data + at;
    size_t left = size - at;
    if (left >= 4 && !memcmp(head, "ply", 3) && (head[3] == '\n' || head[3] == '\r'))
        return TPK_SURFACE_PLY;
    if ((left >= 3 && !memcmp(head, "OFF", 3)) || (left >= 4 && !memcmp(head, "COFF", 4)))
        return TPK_SURFACE_OFF;
    if (binary_stl_size_matches(data, size) || (left >= 5 && !strncasecmp(head, "solid", 5)))
        return TPK_SURFACE_STL;
    if (looks_like_csv_header(data, size))
        return TPK_SURFACE_CSV;
    return TPK_SURFACE_UNKNOWN;
}

/* Binary STL: 80-byte header, uint32 triangle count, then 50 bytes per triangle (normal, 3 corners as
 * little-endian float32, 2 attribute bytes). */
static int read_stl_binary(tpk_scan *s, tpk_mesh *out)
{
    const unsigned char *d = s->data;
    s->byte_places = 1;
    if (s->size < 84)
        return tpk_scan_fail_at(s, s->size, 0, "truncated binary STL: expected an 80-byte header and a "
                                "triangle count (84 bytes), found %zu bytes", s->size);
    uint64_t n = tpk_surf_u32(d + 80, 0), need = 84 + 50 * n;
    if (need > s->size) {
        uint64_t whole = (s->size - 84) / 50;
        return tpk_scan_fail_at(s, (size_t)(84 + 50 * whole), 0,
                                "truncated binary STL: the header says %llu triangles (%llu bytes), the file "
                                "has %zu bytes; triangle %llu is cut off",
                                (unsigned long long)n, (unsigned long long)need, s->size, (unsigned long long)whole);
    }
    if (need < s->size)
        return tpk_scan_fail_at(s, (size_t)need, 0, "binary STL: %zu bytes after the %llu triangles the "
                                "header announces (wrong count?)", s->size - (size_t)need, (unsigned long long)n);
    if (n > INT32_MAX / 3)
        return tpk_scan_fail_at(s, 80, 0, "binary STL: %llu triangles: more than tetpack handles", (unsigned long long)n);
    double *corners = malloc(sizeof(double) * 9 * (size_t)(n ? n : 1));
    if (!corners)
        return tpk_scan_fail_at(s, 80, 0, "out of memory for %llu triangles", (unsigned long long)n);
    for (uint64_t t = 0; t < n; t++)
        for (int k = 0; k < 9; k++) {
            size_t at = (size_t)(84 + 50 * t + 12 + 4 * k);
            double value = tpk_surf_f32(d + at, 0);
            if (!isfinite(value)) {
                free(corners);
                return tpk_scan_fail_at(s, at, 0, "expected a finite coordinate of triangle %llu, found %g",
                                        (unsigned long long)t, value);
            }
            corners[9 * t + k] = value;
        }
    int rc = tpk_surf_from_corners(out, corners, (int64_t)n);
    free(corners);
    strcpy(out->format, "stl-binary");
    return rc ? tpk_scan_fail_at(s, 80, 0, "out of memory for %llu triangles", (unsigned long long)n) : 0;
}

/* The next token must be `word`; `where` names the facet for the message. */
static int expect_word(tpk_scan *s, const char *word, int64_t facet)
{
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    if (len && tpk_token_is(tok, len, word))
        return 0;
    char q[64];
    return tpk_scan_fail(s, "expected '%s' in facet %lld, found %s%s%s", word, (long long)facet, len ? "'" : "",
                         len ? tpk_scan_quote(tok, len, q, sizeof q) : "end of file", len ? "'" : "");
}

static int stl_coordinate(tpk_scan *s, double *v, int64_t facet)
{
    char what[64];
    snprintf(what, sizeof what, "a vertex coordinate of facet %lld", (long long)facet);
    if (tpk_scan_line_double(s, v, what))
        return -1;
    if (!isfinite(*v))
        return tpk_scan_fail(s, "expected a finite vertex coordinate of facet %lld, found %g", (long long)facet, *v);
    return 0;
}

/* One "facet normal ... endfacet" block (the word "facet" already read) into 9 corner coordinates. */
static int read_stl_facet(tpk_scan *s, int64_t facet, double corner[9])
{
    double normal;
    if (expect_word(s, "normal", facet))
        return -1;
    for (int k = 0; k < 3; k++)
        if (tpk_scan_line_double(s, &normal, "a normal component"))
            return -1;
    if (expect_word(s, "outer", facet) || expect_word(s, "loop", facet))
        return -1;
    for (int v = 0; v < 3; v++) {
        if (expect_word(s, "vertex", facet))
            return -1;
        for (int k = 0; k < 3; k++)
            if (stl_coordinate(s, &corner[3 * v + k], facet))
                return -1;
    }
    return expect_word(s, "endloop", facet) || expect_word(s, "endfacet", facet) ? -1 : 0;
}

/* ASCII STL: one or more "solid NAME ... endsolid NAME" blocks of facets. */
static int read_stl_ascii(tpk_scan *s, tpk_mesh *out)
{
    size_t cap = 1024, count = 0;
    double *corners = malloc(sizeof(double) * 9 * cap);
    const char *tok;
    size_t len;
    int in_solid = 0;
    if (!corners)
        return tpk_scan_fail(s, "out of memory");
    while ((len = tpk_scan_token(s, &tok)) != 0) {
        char q[64];
        if (!in_solid && tpk_token_is(tok, len, "solid")) {
            in_solid = 1;
            tpk_scan_skip_line(s); /* the solid's name */
        } else if (in_solid && tpk_token_is(tok, len, "endsolid")) {
            in_solid = 0;
            tpk_scan_skip_line(s);
        } else if (in_solid && tpk_token_is(tok, len, "facet")) {
            if (count == cap) {
                double *grown = realloc(corners, sizeof(double) * 9 * (cap *= 2));
                if (!grown)
                    goto oom;
                corners = grown;
            }
            if (read_stl_facet(s, (int64_t)count, corners + 9 * count))
                goto fail;
            count++;
        } else {
            tpk_scan_fail(s, "expected %s, found '%s'", in_solid ? "'facet' or 'endsolid'" : "'solid'",
                          tpk_scan_quote(tok, len, q, sizeof q));
            goto fail;
        }
    }
    if (in_solid) {
        tpk_scan_fail_at(s, s->size, s->line, "expected 'endsolid', found end of file (truncated file?)");
        goto fail;
    }
    if (count > INT32_MAX / 3) {
        tpk_scan_fail(s, "%zu facets: more than tetpack handles", count);
        goto fail;
    }
    if (tpk_surf_from_corners(out, corners, (int64_t)count) != 0)
        goto oom;
    free(corners);
    strcpy(out->format, "stl-ascii");
    return 0;
oom:
    tpk_scan_fail(s, "out of memory for %zu facets", count);
fail:
    free(corners);
    return -1;
}

int tpk_read_stl(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    tpk_scan s;
    tpk_scan_init(&s, name, data, size, diag);
    memset(out, 0, sizeof *out);
    size_t at = 0;
    while (at < size && (data[at] == ' ' || data[at] == '\t' || data[at] == '\r' || data[at] == '\n'))
        at++;
    /* Binary files may start with "solid" too: the size decides first; a text file has no NUL bytes. */
    int ascii = !binary_stl_size_matches(data, size) && size - at >= 5 && !strncasecmp(data + at, "solid", 5) &&
                !memchr(data, 0, size < 512 ? size : 512);
    int rc = ascii ? read_stl_ascii(&s, out) : read_stl_binary(&s, out);
    if (rc)
        tpk_mesh_free(out);
    return rc;
}

int tpk_read_surface_memory(const char *name, const char *data, size_t size, tpk_surface_kind kind,
                            tpk_mesh *out, tpk_diag *diag)
{
    if (kind == TPK_SURFACE_UNKNOWN)
        kind = tpk_surface_kind_sniff(data, size);
    switch (kind) {
    case TPK_SURFACE_STL:
        return tpk_read_stl(name, data, size, out, diag);
    case TPK_SURFACE_OFF:
        return tpk_read_off(name, data, size, out, diag);
    case TPK_SURFACE_PLY:
        return tpk_read_ply(name, data, size, out, diag);
    case TPK_SURFACE_CSV:
        return tpk_read_csv_points(name, data, size, out, diag);
    default:
        memset(out, 0, sizeof *out);
        return tpk_diag_fail(diag, "%s: not an STL, OFF, PLY or CSV point file (first bytes unknown)", name);
    }
}

int tpk_read_surface(const char *path, tpk_surface_kind kind, tpk_mesh *out, tpk_diag *diag)
{
    const char *data;
    size_t size;
    memset(out, 0, sizeof *out);
    if (tpk_map_file(path, &data, &size, diag) != 0)
        return -1;
    if (kind == TPK_SURFACE_UNKNOWN)
        kind = tpk_surface_kind_from_name(path);
    int rc = tpk_read_surface_memory(path, data, size, kind, out, diag);
    tpk_unmap_file(data, size);
    return rc;
}

int tpk_import_surface(const char *path, tpk_surface_kind kind, tpk_surface_mode mode,
                       const tpk_tetgen_options *options, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    if (tpk_tetgen_available(path, diag) != 0)
        return -1;
    tpk_mesh surface;
    if (tpk_read_surface(path, kind, &surface, diag) != 0)
        return -1;
    if (mode == TPK_SURFACE_FACES && surface.cell_count == 0) {
        tpk_mesh_free(&surface);
        return tpk_diag_fail(diag, "%s: the file has no faces, so it is no surface (a point cloud? use --format "
                             "points)", path);
    }
    if (mode == TPK_SURFACE_POINTS) { /* the vertices alone */
        free(surface.cell_types), free(surface.cell_offsets), free(surface.cell_conn);
        surface.cell_types = NULL, surface.cell_offsets = NULL, surface.cell_conn = NULL;
        surface.cell_count = 0;
    }
    return tpk_surface_tetrahedralize(path, &surface, options, out, diag);
}
