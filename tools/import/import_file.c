/* The importers' glue (import_file.h): an emptied output mesh, a path mapped and parsed, the arrays handed
 * over, and a failure worded with its place. */
#include "import_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/text_scan.h"

int tpk_import_begin(const char *name, tpk_mesh *out, tpk_diag *diag)
{
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name ? name : "(input)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    return 0;
}

/* The file at path mapped and handed to parse (mapped: 1) or read. */
static int import_mapped(const char *path, tpk_parse_fn parse, tpk_memory_fn read, tpk_mesh *out, tpk_diag *diag)
{
    const char *data;
    size_t size;
    if (out)
        memset(out, 0, sizeof *out);
    if (tpk_map_file(path, &data, &size, diag) != 0)
        return -1;
    int rc = parse ? parse(path, data, size, 1, out, diag) : read(path, data, size, out, diag);
    tpk_unmap_file(data, size);
    return rc;
}

int tpk_import_mapped(const char *path, tpk_parse_fn parse, tpk_mesh *out, tpk_diag *diag)
{
    return import_mapped(path, parse, NULL, out, diag);
}

int tpk_import_mapped_memory(const char *path, tpk_memory_fn read, tpk_mesh *out, tpk_diag *diag)
{
    return import_mapped(path, NULL, read, out, diag);
}

int tpk_import_take_cells(tpk_mesh *out, int64_t point_count, double **points, int64_t cell_count, uint8_t **types,
                          int64_t **offsets, int32_t **conn)
{
    out->point_count = point_count;
    out->points = *points;
    out->cell_count = cell_count;
    out->cell_types = *types;
    out->cell_offsets = *offsets;
    out->cell_conn = *conn;
    *points = NULL, *types = NULL, *offsets = NULL, *conn = NULL;
    if (!out->cell_offsets && !(out->cell_offsets = calloc(1, sizeof *out->cell_offsets)))
        return -1;
    if (!out->cell_types && !(out->cell_types = malloc(1)))
        return -1;
    if (!out->cell_conn && !(out->cell_conn = malloc(sizeof *out->cell_conn)))
        return -1;
    return 0;
}

int tpk_import_end(int rc, tpk_mesh *out)
{
    if (rc == 0)
        return 0;
    if (out) {
        tpk_mesh_free(out);
        memset(out, 0, sizeof *out);
    }
    return -1;
}

int tpk_import_vfail(tpk_diag *diag, int *failed, tpk_import_place at, const char *fmt, va_list ap)
{
    if (failed && *failed)
        return -1;
    if (failed)
        *failed = 1;
    char what[800], place[160] = "";
    vsnprintf(what, sizeof what, fmt, ap);
    if (at.line > 0)
        snprintf(place, sizeof place, "line %ld: ", at.line);
    else if (at.byte >= 0)
        snprintf(place, sizeof place, "byte %lld: ", (long long)at.byte);
    return tpk_diag_fail(diag, "%s: %s%s%s%s", at.name, place, at.context ? at.context : "", at.context ? ": " : "",
                         what);
}

int tpk_import_fail(tpk_diag *diag, int *failed, tpk_import_place at, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = tpk_import_vfail(diag, failed, at, fmt, ap);
    va_end(ap);
    return rc;
}
