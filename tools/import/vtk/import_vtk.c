/* VTK legacy UNSTRUCTURED_GRID importer (ASCII and big-endian BINARY, old CELLS lists and the 5.1
 * OFFSETS/CONNECTIVITY form). Parses from one in-memory buffer with explicit bounds: every count is
 * checked against the bytes left in the file before anything is allocated.
 * This file: the header, the section loop, cell classification and the final mesh, the entry points;
 * import_vtk_tokens.c reads tokens and value blocks, import_vtk_cells.c POINTS, CELLS and CELL_TYPES,
 * import_vtk_data.c POINT_DATA/CELL_DATA and their arrays. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/cell_types.h"
#include "import_vtk_internal.h"
#include "base/parallel.h"
#include "mesh/polyhedron.h"
#include "base/text_scan.h"
#include "import/import_file.h"

/* ---- Cells: classify, keep, drop ---------------------------------------------------------------- */

/* A polyhedron keeps its face stream (nfaces, then per face npts and npts ids) in place of its point
 * ids, in both CELLS forms (VTK's legacy writers put it there). Errors give the entry's place in the
 * CELLS block (old form: counting every cell's count) or in CONNECTIVITY. */
static int check_face_stream(vtk_reader *r, int64_t cell, const int32_t *e, int64_t n)
{
    int64_t bad_at;
    char why[200];
    if (tpk_face_stream_check(e, n, r->point_count, &bad_at, why, sizeof why) == 0)
        return 0;
    int64_t at = r->offsets[cell] + bad_at + (r->offsets_form ? 0 : cell + 1);
    return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                            "CELLS: cell %lld (polyhedron): %s (face stream entry %lld, %s value %lld)", (long long)cell,
                            why, (long long)bad_at, r->offsets_form ? "CONNECTIVITY" : "CELLS", (long long)at);
}

/* Whether a cell of n ids has a size its rule refuses (not the face stream of type 42, checked apart). */
static int size_refused(const tpk_cell_rule *rule, int64_t n)
{
    return (rule->nodes > 0 && n != rule->nodes) || (rule->nodes < 0 && n < -rule->nodes);
}

static int check_cell(vtk_reader *r, int64_t c, const tpk_cell_rule *rule)
{
    int64_t begin = r->offsets[c], n = r->offsets[c + 1] - begin;
    const int32_t *ids = r->conn + begin;
    if (rule->kind == TPK_RULE_UNKNOWN)
        return tpk_scan_fail_at(&r->s, r->types_pos, r->types_line, "CELL_TYPES: cell %lld has unsupported cell type %d (%s)",
                                (long long)c, r->types[c], rule->name);
    if (rule->kind != TPK_RULE_DROP && r->types[c] == 42)
        return check_face_stream(r, c, ids, n);
    if (size_refused(rule, n))
        return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                                "CELLS: cell %lld (%s, type %d) has %lld points, expected %s%d", (long long)c,
                                rule->name, r->types[c], (long long)n, rule->nodes < 0 ? "at least " : "",
                                rule->nodes < 0 ? -rule->nodes : rule->nodes);
    for (int64_t j = 0; j < n; j++)
        if (ids[j] >= r->point_count)
            return tpk_scan_fail_at(&r->s, r->cells_pos, r->cells_line,
                                    "CELLS: cell %lld uses point id %d, but there are only %lld points (0 to %lld)",
                                    (long long)c, ids[j], (long long)r->point_count, (long long)r->point_count - 1);
    return 0;
}

static void filter_cell_fields(vtk_reader *r, const uint8_t *keep)
{
    for (int i = 0; i < r->fields.field_count; i++) {
        tpk_src_field *f = &r->fields.fields[i];
        if (f->association != TPK_ASSOC_TET)
            continue;
        int64_t k = 0;
        for (int64_t c = 0; c < r->cell_count; c++)
            if (keep[c])
                memmove(f->values + k++ * f->components, f->values + c * f->components,
                        sizeof(float) * (size_t)f->components);
    }
}

/* check_cell without a message, for the workers: 1 when the cell passes. */
static int cell_ok(const vtk_reader *r, int64_t c, const tpk_cell_rule *rule)
{
    int64_t begin = r->offsets[c], n = r->offsets[c + 1] - begin;
    const int32_t *ids = r->conn + begin;
    if (rule->kind == TPK_RULE_UNKNOWN)
        return 0;
    if (rule->kind != TPK_RULE_DROP && r->types[c] == 42) {
        int64_t bad_at;
        char why[200];
        return tpk_face_stream_check(ids, n, r->point_count, &bad_at, why, sizeof why) == 0;
    }
    if ((rule->nodes > 0 && n != rule->nodes) || (rule->nodes < 0 && n < -rule->nodes))
        return 0;
    for (int64_t j = 0; j < n; j++)
        if (ids[j] >= r->point_count)
            return 0;
    return 1;
}

/* The cells checked and counted on all threads: per worker its first bad cell (the smallest of them is
 * the one the serial loop stopped at), and the counts by type of the cells it drops. */
typedef struct cell_tally {
    int64_t dropped[256];
    int64_t kept, conn_size, first_bad;
} cell_tally;

typedef struct check_job {
    const vtk_reader *r;
    tpk_cell_rule rule[256];
    cell_tally *tally; /* one per worker */
} check_job;

static void check_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const check_job *job = ctx;
    const vtk_reader *r = job->r;
    cell_tally *t = &job->tally[worker];
    for (int64_t c = begin; c < end; c++) {
        const tpk_cell_rule *rule = &job->rule[r->types[c]];
        if (!cell_ok(r, c, rule)) {
            t->first_bad = c;
            return;
        }
        if (rule->kind == TPK_RULE_DROP) {
            t->dropped[r->types[c]]++;
            continue;
        }
        t->kept++;
        t->conn_size += r->offsets[c + 1] - r->offsets[c];
    }
}

/* The checked cells into the mesh, those that are not volumes left out (and their cell fields' values). */
static int take_cells(vtk_reader *r, tpk_mesh *out, const int64_t dropped[256], int64_t drop_total, int64_t kept,
                      int64_t conn_size)
{
    if (drop_total)
        tpk_warn_cell_counts(r->s.diag, r->s.name, dropped, drop_total,
                             "dropped cells that are not volumes:");

    out->point_count = r->point_count;
    out->points = r->points;
    r->points = NULL;
    out->cell_count = kept;
    if (!drop_total) {
        out->cell_types = r->types;
        out->cell_offsets = r->offsets;
        out->cell_conn = r->conn;
        r->types = NULL;
        r->offsets = NULL;
        r->conn = NULL;
    } else {
        uint8_t *keep = malloc((size_t)(r->cell_count ? r->cell_count : 1));
        out->cell_types = malloc((size_t)(kept ? kept : 1));
        out->cell_offsets = malloc(sizeof(int64_t) * (size_t)(kept + 1));
        out->cell_conn = malloc(sizeof(int32_t) * (size_t)(conn_size ? conn_size : 1));
        if (!keep || !out->cell_types || !out->cell_offsets || !out->cell_conn) {
            free(keep);
            return tpk_diag_fail(r->s.diag, "%s: out of memory", r->s.name);
        }
        int64_t k = 0, o = 0;
        out->cell_offsets[0] = 0;
        for (int64_t c = 0; c < r->cell_count; c++) {
            tpk_cell_rule rule = tpk_cell_rule_for(r->types[c]);
            keep[c] = rule.kind != TPK_RULE_DROP;
            if (!keep[c])
                continue;
            int64_t n = r->offsets[c + 1] - r->offsets[c];
            memcpy(out->cell_conn + o, r->conn + r->offsets[c], sizeof(int32_t) * (size_t)n);
            o += n;
            out->cell_types[k] = rule.out_type;
            out->cell_offsets[++k] = o;
        }
        filter_cell_fields(r, keep);
        free(keep);
    }
    out->fields = r->fields.fields;
    out->field_count = r->fields.field_count;
    r->fields.fields = NULL;
    r->fields.field_count = 0;
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "%s", r->binary ? "vtk-legacy-binary" : "vtk-legacy-ascii");
    if (tpk_mesh_take_face_streams(out))
        return tpk_diag_fail(r->s.diag, "%s: out of memory", r->s.name);
    return 0;
}

/* The cells' check and counts from what the binary passes proved (import_vtk_internal.h, each_size), with
 * no pass over the cells: one cell type, one size that its rule takes, no id at or above the point count
 * (the passes refused negative ones). 1 when that holds (every cell passes check_cell, the counts are
 * set); 0 otherwise, and the cells are checked one by one. Saves a pass over the offsets, ids and types
 * (a fifth of grid 120's import on one thread). */
static int cells_proved(const vtk_reader *r, int64_t dropped[256], int64_t *kept, int64_t *conn_size)
{
    if (r->cell_count <= 0 || r->each_size < 0 || r->type_lo < 0 || r->type_lo != r->type_hi ||
        r->max_id >= r->point_count)
        return 0;
    int type = r->type_lo;
    tpk_cell_rule rule = tpk_cell_rule_for(type);
    int64_t n = r->each_size;
    if (rule.kind == TPK_RULE_UNKNOWN || type == 42 || size_refused(&rule, n))
        return 0;
    if (rule.kind == TPK_RULE_DROP) {
        dropped[type] = r->cell_count;
        return 1;
    }
    *kept = r->cell_count;
    *conn_size = r->cell_count * n;
    return 1;
}

static int finish_mesh(vtk_reader *r, tpk_mesh *out)
{
    if (r->point_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a POINTS section, found end of file");
    if (r->cell_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a CELLS section, found end of file");
    if (r->type_count < 0)
        return tpk_scan_fail_at(&r->s, r->s.size, r->s.line, "expected a CELL_TYPES section, found end of file");
    int64_t dropped[256] = {0};
    int64_t drop_total = 0, kept = 0, conn_size = 0;
    if (cells_proved(r, dropped, &kept, &conn_size)) {
        drop_total = dropped[r->type_lo];
        return take_cells(r, out, dropped, drop_total, kept, conn_size);
    }
    int threads = vtk_threads_for((uint64_t)r->cell_count);
    check_job *job = malloc(sizeof *job);
    cell_tally *tally = calloc((size_t)threads, sizeof *tally);
    if (!job || !tally) {
        free(job), free(tally);
        return tpk_diag_fail(r->s.diag, "%s: out of memory", r->s.name);
    }
    job->r = r;
    job->tally = tally;
    for (int t = 0; t < 256; t++)
        job->rule[t] = tpk_cell_rule_for(t);
    for (int w = 0; w < threads; w++)
        tally[w].first_bad = INT64_MAX;
    tpk_parallel_for(r->cell_count, threads, check_range, job);
    int64_t bad = INT64_MAX;
    for (int w = 0; w < threads; w++) {
        bad = tally[w].first_bad < bad ? tally[w].first_bad : bad;
        kept += tally[w].kept;
        conn_size += tally[w].conn_size;
        for (int t = 0; t < 256; t++) {
            dropped[t] += tally[w].dropped[t];
            drop_total += tally[w].dropped[t];
        }
    }
    free(tally);
    int rc = bad != INT64_MAX ? check_cell(r, bad, &job->rule[r->types[bad]]) : 0;
    free(job);
    if (rc)
        return -1;
    return take_cells(r, out, dropped, drop_total, kept, conn_size);
}

/* ---- Header and section loop -------------------------------------------------------------------- */

static int read_header(vtk_reader *r)
{
    tpk_scan *s = &r->s;
    const char *magic = "# vtk DataFile Version";
    size_t mlen = strlen(magic);
    size_t line_len = 0;
    while (line_len < s->size && s->data[line_len] != '\n')
        line_len++;
    if (line_len < mlen || !tpk_token_is((const char *)s->data, mlen, magic)) {
        char q[64];
        return tpk_scan_fail_at(s, 0, 1, "expected '# vtk DataFile Version x.y', found '%s'",
                                s->size ? vtk_quote((const char *)s->data, line_len, q, sizeof q) : "an empty file");
    }
    tpk_scan_skip_line(s); /* version line */
    if (s->pos >= s->size)
        return tpk_scan_fail_at(s, s->pos, s->line, "expected a title line, found end of file");
    tpk_scan_skip_line(s); /* title */
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    char q[64];
    if (tpk_token_is(tok, len, "BINARY")) {
        r->binary = 1;
        s->byte_places = 1;
    } else if (!tpk_token_is(tok, len, "ASCII")) {
        return tpk_scan_fail(s, "expected 'ASCII' or 'BINARY', found '%s'",
                             len ? vtk_quote(tok, len, q, sizeof q) : "end of file");
    }
    if (tpk_scan_end_line(s, r->binary ? "BINARY" : "ASCII"))
        return -1;
    len = tpk_scan_token(s, &tok);
    if (!tpk_token_is(tok, len, "DATASET"))
        return tpk_scan_fail(s, "expected 'DATASET UNSTRUCTURED_GRID', found '%s'",
                             len ? vtk_quote(tok, len, q, sizeof q) : "end of file");
    len = tpk_scan_line_token(s, &tok);
    if (!tpk_token_is(tok, len, "UNSTRUCTURED_GRID"))
        return tpk_scan_fail(s, "unsupported dataset type '%s': expected UNSTRUCTURED_GRID",
                             len ? vtk_quote(tok, len, q, sizeof q) : "(none)");
    return tpk_scan_end_line(s, "DATASET UNSTRUCTURED_GRID");
}

static int read_section(vtk_reader *r, const char *tok, size_t len)
{
    if (tpk_token_is(tok, len, "POINTS"))
        return vtk_read_points(r);
    if (tpk_token_is(tok, len, "CELLS"))
        return vtk_read_cells(r);
    if (tpk_token_is(tok, len, "CELL_TYPES"))
        return vtk_read_cell_types(r);
    if (tpk_token_is(tok, len, "POINT_DATA"))
        return vtk_read_data_header(r, TPK_ASSOC_POINT);
    if (tpk_token_is(tok, len, "CELL_DATA"))
        return vtk_read_data_header(r, TPK_ASSOC_TET);
    if (tpk_token_is(tok, len, "SCALARS"))
        return vtk_read_scalars(r);
    if (tpk_token_is(tok, len, "VECTORS"))
        return vtk_read_fixed_attribute(r, "VECTORS", 3);
    if (tpk_token_is(tok, len, "NORMALS"))
        return vtk_read_fixed_attribute(r, "NORMALS", 3);
    if (tpk_token_is(tok, len, "TENSORS"))
        return vtk_read_fixed_attribute(r, "TENSORS", 9);
    if (tpk_token_is(tok, len, "TENSORS6"))
        return vtk_read_fixed_attribute(r, "TENSORS6", 6);
    if (tpk_token_is(tok, len, "GLOBAL_IDS"))
        return vtk_read_fixed_attribute(r, "GLOBAL_IDS", 1);
    if (tpk_token_is(tok, len, "PEDIGREE_IDS"))
        return vtk_read_fixed_attribute(r, "PEDIGREE_IDS", 1);
    if (tpk_token_is(tok, len, "TEXTURE_COORDINATES"))
        return vtk_read_texture_coordinates(r);
    if (tpk_token_is(tok, len, "COLOR_SCALARS"))
        return vtk_read_color_scalars(r);
    if (tpk_token_is(tok, len, "LOOKUP_TABLE"))
        return vtk_skip_lookup_table(r);
    if (tpk_token_is(tok, len, "FIELD"))
        return vtk_read_field(r);
    if (tpk_token_is(tok, len, "METADATA")) {
        vtk_skip_metadata(r);
        return 0;
    }
    char q[64];
    return tpk_scan_fail(&r->s, "expected a section (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, "
                         "VECTORS, FIELD, ...), found '%s'", vtk_quote(tok, len, q, sizeof q));
}

static void reader_free(vtk_reader *r)
{
    free(r->points);
    free(r->offsets);
    free(r->conn);
    free(r->types);
    tpk_mesh_free(&r->fields);
}

static int import_buffer(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                         tpk_diag *diag)
{
    if (tpk_import_begin(name, out, diag) != 0)
        return -1;
    vtk_reader r;
    memset(&r, 0, sizeof r);
    tpk_scan_init(&r.s, name, data, size, diag);
    r.s.mapped = mapped;
    r.point_count = r.cell_count = r.type_count = -1;
    r.each_size = r.max_id = -1;
    r.type_lo = r.type_hi = -1;
    r.assoc = -1;
    int rc = read_header(&r);
    while (rc == 0) {
        const char *tok;
        size_t len = tpk_scan_token(&r.s, &tok);
        if (!len)
            break;
        r.kw_pos = r.s.tok_pos;
        r.kw_line = r.s.tok_line;
        rc = read_section(&r, tok, len);
        tpk_scan_release_consumed(&r.s);
    }
    if (rc == 0)
        rc = finish_mesh(&r, out);
    reader_free(&r);
    if (rc != 0)
        tpk_mesh_free(out);
    return rc;
}

int tpk_import_vtk_legacy_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    return import_buffer(name, data, size, 0, out, diag);
}

int tpk_import_vtk_legacy(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, import_buffer, out, diag);
}
