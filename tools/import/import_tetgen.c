/* TetGen .node/.ele importer. Records are line-based ('#' comments anywhere); the index base (0 or
 * 1) comes from the first point index, as in TetGen. Point and tet attributes become fields. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "importers.h"
#include "tetpack_format.h"
#include "base/text_scan.h"
#include "import_file.h"

/* One number of a record. first = 1: the record's first number (may follow blank and comment lines);
 * otherwise it must be on the same line. Messages: "expected <what> of <item> <index>, found ...". */
static int record_number(tpk_scan *s, int first, int integer, double *d, int64_t *i, const char *what,
                         const char *item, int64_t index)
{
    const char *tok;
    size_t len = first ? tpk_scan_token(s, &tok) : tpk_scan_line_token(s, &tok);
    int ok = len && (integer ? tpk_parse_int64(tok, len, i) : tpk_parse_double(tok, len, d)) == 0;
    if (ok)
        return 0;
    char q[64];
    if (!len)
        return tpk_scan_fail(s, "expected %s of %s %lld, found end of %s", what, item, (long long)index,
                             s->pos >= s->size ? "file" : "line");
    return tpk_scan_fail(s, "expected %s of %s %lld, found '%s'", what, item, (long long)index,
                         tpk_scan_quote(tok, len, q, sizeof q));
}

/* Header numbers: the first is required, later ones default when the line ends. */
static int header_number(tpk_scan *s, int first, int64_t *out, int64_t fallback, const char *what)
{
    const char *tok;
    size_t len = first ? tpk_scan_token(s, &tok) : tpk_scan_line_token(s, &tok);
    if (!len && !first) {
        *out = fallback;
        return 0;
    }
    char q[64];
    if (!len)
        return tpk_scan_fail(s, "expected %s in the header, found end of file", what);
    if (tpk_parse_int64(tok, len, out) != 0 || *out < 0)
        return tpk_scan_fail(s, "expected %s in the header, found '%s'", what, tpk_scan_quote(tok, len, q, sizeof q));
    return 0;
}

static int add_attribute_fields(tpk_mesh *mesh, const char *prefix, int assoc, float *values, int64_t attrs,
                                int64_t count)
{
    for (int64_t a = 0; a < attrs; a++) {
        float *field = malloc(sizeof(float) * (size_t)(count ? count : 1));
        if (!field)
            return -1;
        for (int64_t i = 0; i < count; i++)
            field[i] = values[i * attrs + a];
        char name[TPK_NAME_MAX];
        snprintf(name, sizeof name, "%s_%lld", prefix, (long long)a);
        if (tpk_mesh_add_field(mesh, name, assoc, 1, 1, field) != 0) {
            free(field);
            return -1;
        }
    }
    return 0;
}

static int read_nodes(tpk_scan *s, tpk_mesh *mesh, int *base)
{
    int64_t n, dim, attrs, markers;
    if (header_number(s, 1, &n, 0, "the point count") || header_number(s, 0, &dim, 3, "the dimension") ||
        header_number(s, 0, &attrs, 0, "the attribute count") ||
        header_number(s, 0, &markers, 0, "the boundary marker flag (0 or 1)"))
        return -1;
    if (dim != 3)
        return tpk_scan_fail(s, "expected dimension 3 in the header, found %lld", (long long)dim);
    if (markers > 1)
        return tpk_scan_fail(s, "expected a boundary marker flag 0 or 1 in the header, found %lld", (long long)markers);
    if (attrs > 1024)
        return tpk_scan_fail(s, "expected at most 1024 attributes per point, found %lld", (long long)attrs);
    tpk_scan_skip_line(s);
    size_t left = s->size - s->pos;
    /* A point line holds at least 4 numbers and 4 separators. */
    if ((uint64_t)n > left / 8 + 1)
        return tpk_scan_fail(s, "%lld points cannot fit in the %zu bytes left in the file "
                             "(wrong count or truncated file)", (long long)n, left);
    if (n > INT32_MAX)
        return tpk_scan_fail(s, "%lld points: more than 2^31-1", (long long)n);
    mesh->points = malloc(sizeof(double) * 3 * (size_t)(n ? n : 1));
    float *values = attrs ? malloc(sizeof(float) * (size_t)(n > 0 ? n * attrs : 1)) : NULL;
    if (!mesh->points || (attrs && !values)) {
        free(values);
        return tpk_scan_fail(s, "out of memory for %lld points", (long long)n);
    }
    mesh->point_count = n;
    static const char *coord[3] = {"the x coordinate", "the y coordinate", "the z coordinate"};
    for (int64_t i = 0; i < n; i++) {
        int64_t index, marker;
        double v;
        if (record_number(s, 1, 1, NULL, &index, "the index", "point", i + 1))
            goto fail;
        if (i == 0) {
            if (index != 0 && index != 1) {
                tpk_scan_fail(s, "expected the first point index to be 0 or 1, found %lld", (long long)index);
                goto fail;
            }
            *base = (int)index;
        }
        for (int k = 0; k < 3; k++) {
            if (record_number(s, 0, 0, &mesh->points[3 * i + k], NULL, coord[k], "point", index))
                goto fail;
        }
        for (int64_t a = 0; a < attrs; a++) {
            if (record_number(s, 0, 0, &v, NULL, "an attribute", "point", index))
                goto fail;
            values[i * attrs + a] = (float)v;
        }
        if (markers && record_number(s, 0, 1, NULL, &marker, "the boundary marker", "point", index))
            goto fail;
        tpk_scan_skip_line(s);
    }
    if (attrs && add_attribute_fields(mesh, "attribute", TPK_ASSOC_POINT, values, attrs, n) != 0) {
        tpk_scan_fail(s, "out of memory for point attributes");
        goto fail;
    }
    free(values);
    return 0;
fail:
    free(values);
    return -1;
}

static int read_elements(tpk_scan *s, tpk_mesh *mesh, int base)
{
    int64_t n, nodes, attrs;
    if (header_number(s, 1, &n, 0, "the tet count") || header_number(s, 0, &nodes, 4, "the nodes per tet (4 or 10)") ||
        header_number(s, 0, &attrs, 0, "the attribute count"))
        return -1;
    if (nodes != 4 && nodes != 10)
        return tpk_scan_fail(s, "expected 4 or 10 nodes per tet in the header, found %lld", (long long)nodes);
    if (attrs > 1024)
        return tpk_scan_fail(s, "expected at most 1024 attributes per tet, found %lld", (long long)attrs);
    tpk_scan_skip_line(s);
    size_t left = s->size - s->pos;
    /* A tet line holds at least 5 numbers and 5 separators. */
    if ((uint64_t)n > left / 10 + 1)
        return tpk_scan_fail(s, "%lld tets cannot fit in the %zu bytes left in the file "
                             "(wrong count or truncated file)", (long long)n, left);
    if (n > INT32_MAX)
        return tpk_scan_fail(s, "%lld tets: more than 2^31-1", (long long)n);
    mesh->cell_types = malloc((size_t)(n ? n : 1));
    mesh->cell_offsets = malloc(sizeof(int64_t) * (size_t)(n + 1));
    mesh->cell_conn = malloc(sizeof(int32_t) * 4 * (size_t)(n ? n : 1));
    float *values = attrs ? malloc(sizeof(float) * (size_t)(n > 0 ? n * attrs : 1)) : NULL;
    if (!mesh->cell_types || !mesh->cell_offsets || !mesh->cell_conn || (attrs && !values)) {
        free(values);
        return tpk_scan_fail(s, "out of memory for %lld tets", (long long)n);
    }
    mesh->cell_count = n;
    mesh->cell_offsets[0] = 0;
    for (int64_t t = 0; t < n; t++) {
        int64_t index, id;
        double v;
        if (record_number(s, 1, 1, NULL, &index, "the index", "tet", t + base))
            goto fail;
        for (int64_t k = 0; k < nodes; k++) {
            if (record_number(s, 0, 1, NULL, &id, "a point id", "tet", index))
                goto fail;
            if (id < base || id - base >= mesh->point_count) {
                tpk_scan_fail(s, "tet %lld uses point id %lld, expected %d to %lld (the .node file has %lld points)",
                              (long long)index, (long long)id, base, (long long)mesh->point_count - 1 + base,
                              (long long)mesh->point_count);
                goto fail;
            }
            if (k < 4)
                mesh->cell_conn[4 * t + k] = (int32_t)(id - base);
        }
        for (int64_t a = 0; a < attrs; a++) {
            if (record_number(s, 0, 0, &v, NULL, "a region attribute", "tet", index))
                goto fail;
            values[t * attrs + a] = (float)v;
        }
        mesh->cell_types[t] = TPK_CELL_TETRA;
        mesh->cell_offsets[t + 1] = 4 * (t + 1);
        tpk_scan_skip_line(s);
    }
    if (attrs && add_attribute_fields(mesh, "region_attribute", TPK_ASSOC_TET, values, attrs, n) != 0) {
        tpk_scan_fail(s, "out of memory for tet attributes");
        goto fail;
    }
    free(values);
    if (nodes == 10 && n)
        tpk_diag_warn(s->diag, "%s: reduced %lld 10-node (quadratic) tets to their 4 corner nodes", s->name,
                      (long long)n);
    return 0;
fail:
    free(values);
    return -1;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

static int parse_buffer(const char *name, const char *data, size_t size, tpk_mesh *mesh, int *base, int nodes,
                        tpk_diag *diag)
{
    tpk_scan s;
    tpk_scan_init(&s, name, data, size, diag);
    s.hash_comments = 1;
    return nodes ? read_nodes(&s, mesh, base) : read_elements(&s, mesh, *base);
}

static int parse_file(const char *path, tpk_mesh *mesh, int *base, int nodes, tpk_diag *diag)
{
    const char *data;
    size_t size;
    if (tpk_map_file(path, &data, &size, diag) != 0)
        return -1;
    int rc = parse_buffer(path, data, size, mesh, base, nodes, diag);
    tpk_unmap_file(data, size);
    return rc;
}

static int finish_import(int rc, tpk_mesh *out)
{
    if (rc == 0) {
        out->step_count = 1;
        snprintf(out->format, sizeof out->format, "tetgen");
    } else {
        tpk_mesh_free(out);
    }
    return rc;
}

int tpk_import_tetgen_memory(const char *name, const char *node_data, size_t node_size, const char *ele_data,
                             size_t ele_size, tpk_mesh *out, tpk_diag *diag)
{
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
    char node_name[256], ele_name[256];
    snprintf(node_name, sizeof node_name, "%s.node", name ? name : "(input)");
    snprintf(ele_name, sizeof ele_name, "%s.ele", name ? name : "(input)");
    int base = 0;
    int rc = parse_buffer(node_name, node_data, node_size, out, &base, 1, diag);
    if (rc == 0)
        rc = parse_buffer(ele_name, ele_data, ele_size, out, &base, 0, diag);
    return finish_import(rc, out);
}

int tpk_import_tetgen_bundle_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    static const char marker[] = "\n@@ele\n";
    size_t node_size = size, ele_at = size;
    for (size_t i = 0; data && i + sizeof marker - 1 <= size; i++)
        if (!memcmp(data + i, marker, sizeof marker - 1)) {
            node_size = i + 1;
            ele_at = i + sizeof marker - 1;
            break;
        }
    char stem[256];
    snprintf(stem, sizeof stem, "%s", name ? name : "(input)");
    size_t len = strlen(stem);
    if (ends_with(stem, ".node") || ends_with(stem, ".ele"))
        stem[len - (ends_with(stem, ".ele") ? 4 : 5)] = 0;
    return tpk_import_tetgen_memory(stem, data, node_size, data ? data + ele_at : NULL, size - ele_at, out, diag);
}

/* STEM.node and STEM.ele for a path naming either file or their stem (malloc'd; both NULL or both set). */
static int sibling_paths(const char *path, char **node_path, char **ele_path)
{
    size_t len = strlen(path);
    size_t stem = ends_with(path, ".node") ? len - 5 : ends_with(path, ".ele") ? len - 4 : len;
    *node_path = malloc(stem + 6);
    *ele_path = malloc(stem + 5);
    if (!*node_path || !*ele_path) {
        free(*node_path);
        free(*ele_path);
        *node_path = *ele_path = NULL;
        return -1;
    }
    memcpy(*node_path, path, stem);
    memcpy(*node_path + stem, ".node", 6);
    memcpy(*ele_path, path, stem);
    memcpy(*ele_path + stem, ".ele", 5);
    return 0;
}

void tpk_import_tetgen_files(const char *path, tpk_import_file_fn each, void *user)
{
    char *node_path, *ele_path;
    if (sibling_paths(path, &node_path, &ele_path) != 0)
        return;
    each(user, node_path);
    each(user, ele_path);
    free(node_path);
    free(ele_path);
}

int tpk_import_tetgen(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (!out || !path)
        return tpk_diag_fail(diag, "%s: no path or output mesh given", path ? path : "(null)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    char *node_path, *ele_path;
    int rc = -1;
    if (sibling_paths(path, &node_path, &ele_path) != 0) {
        tpk_diag_fail(diag, "%s: out of memory", path);
        goto done;
    }
    int base = 0;
    rc = parse_file(node_path, out, &base, 1, diag);
    if (rc == 0)
        rc = parse_file(ele_path, out, &base, 0, diag);
done:
    free(node_path);
    free(ele_path);
    return finish_import(rc, out);
}
