/* VTK legacy importer: POINT_DATA and CELL_DATA with their attributes (SCALARS, VECTORS, ..., FIELD
 * arrays), kept as fields in r->fields; lookup tables and METADATA are skipped. */
#include <stdio.h>
#include <stdlib.h>

#include "import_vtk_internal.h"
#include "base/text_scan.h"

/* ---- POINT_DATA, CELL_DATA ---------------------------------------------------------------------- */

int vtk_read_data_header(vtk_reader *r, int assoc)
{
    const char *kw = assoc == TPK_ASSOC_POINT ? "POINT_DATA" : "CELL_DATA";
    int64_t n;
    if (vtk_arg_count(r, kw, "a count", &n) || tpk_scan_end_line(&r->s, kw))
        return -1;
    int64_t expected = assoc == TPK_ASSOC_POINT ? r->point_count : r->cell_count;
    if (expected < 0)
        return vtk_fail_kw(r, "expected %s before %s", assoc == TPK_ASSOC_POINT ? "POINTS" : "CELLS", kw);
    if (n != expected && !(r->s.diag && r->s.diag->lenient_fields))
        return vtk_fail_kw(r, "%s %lld: expected %lld (one per %s)", kw, (long long)n, (long long)expected,
                           assoc == TPK_ASSOC_POINT ? "point" : "cell");
    r->assoc = assoc;
    r->assoc_count = n;
    r->assoc_expected = expected;
    return 0;
}

/* A data array of `tuples` tuples where the mesh needs r->assoc_expected: recorded (lenient, the array is
 * dropped: returns 0 and clears *keep) or an error. */
static int wrong_length(vtk_reader *r, const char *name, int64_t comps, int64_t tuples, int *keep)
{
    char place[96];
    snprintf(place, sizeof place, "line %lld", (long long)r->kw_line);
    if (tpk_diag_field_problem(r->s.diag, name, (long long)(r->assoc_expected * comps),
                               (long long)(tuples * comps), place) == 0) {
        *keep = 0;
        return 0;
    }
    return vtk_fail_kw(r, "array '%s' has %lld tuples, expected %lld (one per %s)", name, (long long)tuples,
                       (long long)r->assoc_expected, r->assoc == TPK_ASSOC_POINT ? "point" : "cell");
}

/* Read `tuples * comps` values, each divided by `unit`, and keep them as a field (keep = 0: parse and drop). The
 * division happens here, on the values just read, because a field read leniently may be dropped: no caller
 * may assume the mesh's last field is the one it asked for. */
static int read_field_values(vtk_reader *r, const char *name, vtk_type type, int64_t comps, int64_t tuples,
                             int keep, float unit, const char *block)
{
    if (comps < 1 || comps > 65536)
        return vtk_fail_kw(r, "%s '%s': expected 1 to 65536 components, found %lld", block, name, (long long)comps);
    if (tuples > INT64_MAX / comps)
        return vtk_fail_kw(r, "%s '%s': %lld tuples of %lld components is too many", block, name, (long long)tuples,
                           (long long)comps);
    if (keep && tuples != r->assoc_expected && wrong_length(r, name, comps, tuples, &keep))
        return -1;
    uint64_t count = (uint64_t)(tuples * comps);
    if (vtk_check_room(r, type, count, block))
        return -1;
    if (!keep && r->binary) {
        r->s.pos += vtk_bytes_for(type, count);
        return 0;
    }
    float *values = malloc(sizeof(float) * (size_t)(count ? count : 1));
    if (!values)
        return vtk_fail_kw(r, "%s '%s': out of memory", block, name);
    if (vtk_read_reals(r, type, count, NULL, values, block) != 0) {
        free(values);
        return -1;
    }
    if (!keep) {
        free(values);
        return 0;
    }
    if (unit != 1.0f)
        for (uint64_t i = 0; i < count; i++)
            values[i] /= unit;
    int assoc = r->assoc == TPK_ASSOC_POINT ? TPK_ASSOC_POINT : TPK_ASSOC_TET;
    if (tpk_mesh_add_field(&r->fields, name, assoc, (int)comps, 1, values) != 0) {
        free(values);
        return vtk_fail_kw(r, "%s '%s': out of memory", block, name);
    }
    return 0;
}

static int need_data_section(vtk_reader *r, const char *kw)
{
    if (r->assoc < 0)
        return vtk_fail_kw(r, "expected POINT_DATA or CELL_DATA before %s", kw);
    return 0;
}

/* SCALARS name type [components], then an optional LOOKUP_TABLE name line. */
int vtk_read_scalars(vtk_reader *r)
{
    char name[TPK_NAME_MAX];
    vtk_type type;
    int64_t comps = 1;
    if (need_data_section(r, "SCALARS") || vtk_arg_name(r, "SCALARS", name) || vtk_arg_type(r, "SCALARS", &type))
        return -1;
    const char *tok;
    size_t len = tpk_scan_line_token(&r->s, &tok);
    if (len && (tpk_parse_int64(tok, len, &comps) != 0 || comps < 1)) {
        char q[64];
        return tpk_scan_fail(&r->s, "SCALARS %s: expected a component count, found '%s'", name,
                             vtk_quote(tok, len, q, sizeof q));
    }
    if (tpk_scan_end_line(&r->s, "SCALARS name type components"))
        return -1;
    if (vtk_next_is(r, "LOOKUP_TABLE")) {
        if (vtk_arg_token(r, "LOOKUP_TABLE", "a table name", &tok, &len) ||
            tpk_scan_end_line(&r->s, "LOOKUP_TABLE name"))
            return -1;
    }
    return read_field_values(r, name, type, comps, r->assoc_count, 1, 1.0f, "SCALARS");
}

/* VECTORS, NORMALS, TENSORS, TENSORS6, GLOBAL_IDS, PEDIGREE_IDS: name type, fixed components. */
int vtk_read_fixed_attribute(vtk_reader *r, const char *kw, int comps)
{
    char name[TPK_NAME_MAX];
    vtk_type type;
    if (need_data_section(r, kw) || vtk_arg_name(r, kw, name) || vtk_arg_type(r, kw, &type) ||
        tpk_scan_end_line(&r->s, kw))
        return -1;
    return read_field_values(r, name, type, comps, r->assoc_count, 1, 1.0f, kw);
}

int vtk_read_texture_coordinates(vtk_reader *r)
{
    char name[TPK_NAME_MAX];
    int64_t dim;
    vtk_type type;
    const char *kw = "TEXTURE_COORDINATES";
    if (need_data_section(r, kw) || vtk_arg_name(r, kw, name) || vtk_arg_count(r, kw, "a dimension (1 to 3)", &dim) ||
        vtk_arg_type(r, kw, &type) || tpk_scan_end_line(&r->s, kw))
        return -1;
    if (dim < 1 || dim > 3)
        return vtk_fail_kw(r, "%s %s: expected a dimension 1 to 3, found %lld", kw, name, (long long)dim);
    return read_field_values(r, name, type, dim, r->assoc_count, 1, 1.0f, kw);
}

/* COLOR_SCALARS name n: floats in ASCII, unsigned chars (scaled to [0,1]) in BINARY. */
int vtk_read_color_scalars(vtk_reader *r)
{
    char name[TPK_NAME_MAX];
    int64_t comps;
    const char *kw = "COLOR_SCALARS";
    if (need_data_section(r, kw) || vtk_arg_name(r, kw, name) || vtk_arg_count(r, kw, "a component count", &comps) ||
        tpk_scan_end_line(&r->s, kw))
        return -1;
    return read_field_values(r, name, r->binary ? VT_U8 : VT_F32, comps, r->assoc_count, 1,
                             r->binary ? 255.0f : 1.0f, kw);
}

/* A lookup table definition: LOOKUP_TABLE name size, then size RGBA entries. Skipped. */
int vtk_skip_lookup_table(vtk_reader *r)
{
    const char *tok;
    size_t len;
    int64_t n;
    if (vtk_arg_token(r, "LOOKUP_TABLE", "a table name", &tok, &len) ||
        vtk_arg_count(r, "LOOKUP_TABLE", "a table size", &n) || tpk_scan_end_line(&r->s, "LOOKUP_TABLE name size"))
        return -1;
    return read_field_values(r, "lookup_table", r->binary ? VT_U8 : VT_F32, 4, n, 0, 1.0f, "LOOKUP_TABLE");
}

/* METADATA: lines of text up to an empty line. */
void vtk_skip_metadata(vtk_reader *r)
{
    tpk_scan_skip_line(&r->s);
    while (r->s.pos < r->s.size) {
        size_t p = r->s.pos;
        while (p < r->s.size && (r->s.data[p] == ' ' || r->s.data[p] == '\t' || r->s.data[p] == '\r'))
            p++;
        int blank = p >= r->s.size || r->s.data[p] == '\n';
        tpk_scan_skip_line(&r->s);
        if (blank)
            break;
    }
}

/* FIELD name k, then k arrays "name components tuples type" + values. Inside POINT_DATA/CELL_DATA the
 * arrays become fields and must have one tuple per point/cell; at dataset level they are skipped. */
int vtk_read_field(vtk_reader *r)
{
    const char *tok;
    size_t len;
    int64_t arrays;
    if (vtk_arg_token(r, "FIELD", "a name", &tok, &len) || vtk_arg_count(r, "FIELD", "an array count", &arrays) ||
        tpk_scan_end_line(&r->s, "FIELD name count"))
        return -1;
    for (int64_t a = 0; a < arrays; a++) {
        len = tpk_scan_token(&r->s, &tok);
        while (len && tpk_token_is(tok, len, "METADATA")) {
            vtk_skip_metadata(r);
            len = tpk_scan_token(&r->s, &tok);
        }
        r->kw_pos = r->s.tok_pos;
        r->kw_line = r->s.tok_line;
        if (!len)
            return tpk_scan_fail(&r->s, "FIELD: expected array %lld of %lld ('name components tuples type'), "
                                 "found end of file", (long long)a + 1, (long long)arrays);
        if (tpk_token_is(tok, len, "NULL_ARRAY")) {
            if (tpk_scan_end_line(&r->s, "NULL_ARRAY"))
                return -1;
            continue;
        }
        char name[TPK_NAME_MAX];
        int64_t comps, tuples;
        vtk_type type;
        vtk_decode_name(tok, len, name);
        if (vtk_arg_count(r, name, "a component count", &comps) || vtk_arg_count(r, name, "a tuple count", &tuples) ||
            vtk_arg_type(r, name, &type) || tpk_scan_end_line(&r->s, "name components tuples type"))
            return -1;
        int keep = r->assoc >= 0;
        if (read_field_values(r, name, type, comps, tuples, keep, 1.0f, "FIELD array"))
            return -1;
    }
    return 0;
}
