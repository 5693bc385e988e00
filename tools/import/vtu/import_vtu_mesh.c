/* VTU importer: the tpk_mesh from the decoded DataArrays. Offsets and cell types are checked, polyhedron
 * face streams too; cells are kept (higher-order ones whole) or dropped (cell_types.h); fields follow the
 * kept cells. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "mesh/cell_types.h"
#include "import_vtu_internal.h"
#include "mesh/polyhedron.h"

/* ---- Building the mesh -------------------------------------------------------------------------- */

static vtu_array *find_role(vtu_reader *r, int role)
{
    for (int i = 0; i < r->array_count; i++)
        if (r->arrays[i].role == role)
            return &r->arrays[i];
    return NULL;
}

/* Per cell: where its nodes (or, for a polyhedron, its face stream) are. */
typedef struct cell_span {
    const double *v;
    int64_t n;
} cell_span;

/* Every point a polyhedron's faces use must be in its connectivity (VTK's and meshio's writers list
 * exactly those points there); `ids` is the checked stream, `scratch` room for the connectivity. */
static int check_face_points(vtu_reader *r, const vtu_array *conn, int64_t cell, const int32_t *ids,
                             const double *points, int64_t point_count, int32_t *scratch)
{
    for (int64_t j = 0; j < point_count; j++) {
        if (!(points[j] >= 0 && points[j] < (double)r->point_count))
            return vtu_fail_array(r, conn, "cell %lld (polyhedron) lists point id %.17g, expected 0 to %lld",
                                  (long long)cell, points[j], (long long)r->point_count - 1);
        scratch[j] = (int32_t)points[j];
    }
    qsort(scratch, (size_t)point_count, sizeof *scratch, tpk_compare_int32);
    for (int64_t f = 0, k = 1; f < ids[0]; f++)
        for (int32_t left = ids[k++]; left > 0; left--, k++)
            if (!bsearch(&ids[k], scratch, (size_t)point_count, sizeof *scratch, tpk_compare_int32))
                return vtu_fail_array(r, conn, "cell %lld (polyhedron): its faces use point %d, which its "
                                      "connectivity does not list", (long long)cell, ids[k]);
    return 0;
}

/* A polyhedron's face stream e[0 .. n), starting at value `at` of the faces array (tools/mesh/polyhedron.h
 * checks its layout), and its connectivity points[0 .. point_count). */
static int check_face_stream(vtu_reader *r, const vtu_array *fa, const vtu_array *conn, int64_t cell, const double *e,
                             int64_t n, int64_t at, const double *points, int64_t point_count)
{
    int32_t *ids = malloc(sizeof *ids * (size_t)(n + point_count + 1));
    if (!ids)
        return vtu_fail_array(r, fa, "out of memory");
    int64_t bad_at = -1;
    char why[200];
    for (int64_t k = 0; k < n && bad_at < 0; k++) {
        if (e[k] >= -2147483648.0 && e[k] <= 2147483647.0 && e[k] == (double)(int64_t)e[k])
            ids[k] = (int32_t)e[k];
        else
            bad_at = k, snprintf(why, sizeof why, "expected an integer, found %.17g", e[k]);
    }
    int rc = 0;
    if (bad_at >= 0 || tpk_face_stream_check(ids, n, r->point_count, &bad_at, why, sizeof why))
        rc = vtu_fail_array(r, fa, "cell %lld (polyhedron): %s (face stream entry %lld, value %lld of the array)",
                            (long long)cell, why, (long long)bad_at, (long long)(at + bad_at));
    else
        rc = check_face_points(r, conn, cell, ids, points, point_count, ids + n);
    free(ids);
    return rc;
}

/* The arrays of the Cells element and the face arrays of polyhedra. */
typedef struct cell_arrays {
    vtu_array *conn, *offs, *types, *faces, *foffs;
} cell_arrays;

/* What the per-cell pass found: kept and dropped cells, the output connectivity size. */
typedef struct cell_tally {
    int64_t dropped[256];
    int64_t drop_total, kept, conn_size;
} cell_tally;

/* Offsets increasing and ending at the connectivity's size; types in 0..255. */
static int check_offsets_and_types(vtu_reader *r, const cell_arrays *a)
{
    int64_t nc = r->cell_count, prev = 0;
    for (int64_t c = 0; c < nc; c++) {
        double v = a->offs->values[c];
        if (!(v >= (double)prev && v <= (double)a->conn->count))
            return vtu_fail_array(r, a->offs, "cell %lld: expected an offset from %lld to %llu (not decreasing, "
                                  "within the connectivity), found %.17g", (long long)c, (long long)prev,
                                  (unsigned long long)a->conn->count, v);
        prev = (int64_t)v;
    }
    if (nc > 0 && (uint64_t)prev != a->conn->count)
        return vtu_fail_array(r, a->offs, "expected the last offset to be the connectivity size %llu, found %lld",
                              (unsigned long long)a->conn->count, (long long)prev);
    for (int64_t c = 0; c < nc; c++)
        if (!(a->types->values[c] >= 0 && a->types->values[c] <= 255))
            return vtu_fail_array(r, a->types, "cell %lld: expected a VTK cell type 0..255, found %.17g", (long long)c,
                                  a->types->values[c]);
    if (a->foffs && !a->faces)
        return vtu_fail_array(r, a->foffs, "expected a faces DataArray with faceoffsets, found none");
    return 0;
}

/* Cell c's face offset (advancing *face_prev), and for a polyhedron its span in the faces array;
 * *face_begin gets where that span starts. */
static int locate_faces(vtu_reader *r, const cell_arrays *a, int64_t c, int type, int64_t *face_prev,
                        int64_t *face_begin, cell_span *span)
{
    if (!a->foffs || !(a->foffs->values[c] >= 0))
        return 0;
    double fv = a->foffs->values[c];
    if (!(fv >= (double)*face_prev && fv <= (double)a->faces->count))
        return vtu_fail_array(r, a->foffs, "cell %lld: expected a face offset from %lld to %llu, found %.17g",
                              (long long)c, (long long)*face_prev, (unsigned long long)a->faces->count, fv);
    if (type == TPK_CELL_POLYHEDRON) {
        *face_begin = *face_prev;
        span->v = a->faces->values + *face_prev;
        span->n = (int64_t)fv - *face_prev;
    }
    *face_prev = (int64_t)fv;
    return 0;
}

/* Cell c's node count (or face stream) and point ids. */
static int check_cell_nodes(vtu_reader *r, const cell_arrays *a, int64_t c, int type, tpk_cell_rule rule,
                            const cell_span *span, int64_t face_begin)
{
    int64_t begin = c ? (int64_t)a->offs->values[c - 1] : 0;
    if (type == TPK_CELL_POLYHEDRON) {
        if (!a->foffs || !(a->foffs->values[c] >= 0))
            return vtu_fail_array(r, a->types, "cell %lld is a polyhedron: expected its faces in faces/faceoffsets, "
                                  "found none", (long long)c);
        return check_face_stream(r, a->faces, a->conn, c, span->v, span->n, face_begin, a->conn->values + begin,
                                 (int64_t)a->offs->values[c] - begin);
    }
    if (rule.kind != TPK_RULE_DROP &&
        ((rule.nodes > 0 && span->n != rule.nodes) || (rule.nodes < 0 && span->n < -rule.nodes)))
        return vtu_fail_array(r, a->conn, "cell %lld (%s, type %d) has %lld points, expected %s%d", (long long)c,
                              rule.name, type, (long long)span->n, rule.nodes < 0 ? "at least " : "",
                              rule.nodes < 0 ? -rule.nodes : rule.nodes);
    for (int64_t j = 0; j < span->n; j++)
        if (!(span->v[j] >= 0 && span->v[j] < (double)r->point_count))
            return vtu_fail_array(r, a->conn, "cell %lld uses point id %.17g, but there are only %lld points "
                                  "(0 to %lld)", (long long)c, span->v[j], (long long)r->point_count,
                                  (long long)r->point_count - 1);
    return 0;
}

/* A checked cell of n nodes counted as kept or dropped. */
static void tally_cell(cell_tally *t, int type, tpk_cell_rule rule, int64_t n)
{
    if (rule.kind == TPK_RULE_DROP) {
        t->dropped[type]++;
        t->drop_total++;
        return;
    }
    t->kept++;
    t->conn_size += n;
}

/* Checks every cell, finds its span, and counts what is kept and dropped; rule_of[type]:
 * tpk_cell_rule_for(type), looked up once per type rather than once per cell. */
static int scan_cells(vtu_reader *r, const cell_arrays *a, const tpk_cell_rule *rule_of, cell_span *span,
                      cell_tally *t)
{
    int64_t face_prev = 0;
    for (int64_t c = 0; c < r->cell_count; c++) {
        int type = (int)a->types->values[c];
        int64_t begin = c ? (int64_t)a->offs->values[c - 1] : 0, face_begin = 0;
        span[c].v = a->conn->values + begin;
        span[c].n = (int64_t)a->offs->values[c] - begin;
        tpk_cell_rule rule = rule_of[type];
        if (rule.kind == TPK_RULE_UNKNOWN)
            return vtu_fail_array(r, a->types, "cell %lld has unsupported cell type %d (%s)", (long long)c, type,
                                  rule.name);
        if (locate_faces(r, a, c, type, &face_prev, &face_begin, &span[c]) ||
            check_cell_nodes(r, a, c, type, rule, &span[c], face_begin))
            return -1;
        tally_cell(t, type, rule, span[c].n);
    }
    return 0;
}

/* ---- The same two passes on all cores (meshes without polyhedra) ---------------------------------- */

/* Each worker checks and tallies its range of cells; the first cell that fails any check stops it, and
 * then the one-core pass runs from the start to word the message (so it names the first bad cell, as
 * before). Then each worker copies its kept cells where the tallies before it put them. */
typedef struct cells_job {
    vtu_reader *r;
    const cell_arrays *a;
    const tpk_cell_rule *rule_of;
    uint8_t *keep;
    tpk_mesh *out;
    cell_tally tally[TPK_MAX_THREADS];
    int64_t bad[TPK_MAX_THREADS];
    int64_t first_cell[TPK_MAX_THREADS], first_conn[TPK_MAX_THREADS]; /* where a worker's kept cells go */
} cells_job;

static void scan_range(void *ctx, int64_t begin, int64_t end, int w)
{
    cells_job *job = ctx;
    const cell_arrays *a = job->a;
    cell_tally *t = &job->tally[w];
    double points = (double)job->r->point_count;
    job->bad[w] = -1;
    for (int64_t c = begin; c < end; c++) {
        int type = (int)a->types->values[c];
        int64_t first = c ? (int64_t)a->offs->values[c - 1] : 0, n = (int64_t)a->offs->values[c] - first;
        const double *v = a->conn->values + first;
        tpk_cell_rule rule = job->rule_of[type];
        int ok = rule.kind != TPK_RULE_UNKNOWN && type != TPK_CELL_POLYHEDRON &&
                 (rule.kind == TPK_RULE_DROP || !((rule.nodes > 0 && n != rule.nodes) || (rule.nodes < 0 && n < -rule.nodes)));
        for (int64_t j = 0; ok && j < n; j++)
            ok = v[j] >= 0 && v[j] < points;
        if (!ok) {
            job->bad[w] = c;
            return;
        }
        tally_cell(t, type, rule, n);
    }
}

static void copy_range(void *ctx, int64_t begin, int64_t end, int w)
{
    cells_job *job = ctx;
    tpk_mesh *out = job->out;
    const cell_arrays *a = job->a;
    int64_t k = job->first_cell[w], o = job->first_conn[w];
    for (int64_t c = begin; c < end; c++) {
        tpk_cell_rule rule = job->rule_of[(int)a->types->values[c]];
        job->keep[c] = rule.kind != TPK_RULE_DROP;
        if (!job->keep[c])
            continue;
        int64_t first = c ? (int64_t)a->offs->values[c - 1] : 0; /* as scan_range found it */
        int64_t n = (int64_t)a->offs->values[c] - first;
        const double *v = a->conn->values + first;
        for (int64_t j = 0; j < n; j++)
            out->cell_conn[o++] = (int32_t)v[j];
        out->cell_types[k] = rule.out_type;
        out->cell_offsets[++k] = o;
    }
}

/* Points and the output arrays for t->kept cells. */
static int alloc_output(vtu_reader *r, const vtu_array *pts, const cell_tally *t, tpk_mesh *out)
{
    out->point_count = r->point_count;
    out->points = malloc(sizeof(double) * 3 * (size_t)(r->point_count ? r->point_count : 1));
    out->cell_count = t->kept;
    out->cell_types = malloc((size_t)(t->kept ? t->kept : 1));
    out->cell_offsets = malloc(sizeof(int64_t) * (size_t)(t->kept + 1));
    out->cell_conn = malloc(sizeof(int32_t) * (size_t)(t->conn_size ? t->conn_size : 1));
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn)
        return vtu_fail_line(r, 0, "out of memory");
    if (r->point_count)
        memcpy(out->points, pts->values, sizeof(double) * 3 * (size_t)r->point_count);
    out->cell_offsets[0] = 0;
    return 0;
}

/* scan_cells and copy_cells on all cores: 1 when it did both (or failed, -1), 0 when the mesh is one for
 * the one-core passes (polyhedra, few cells, or a bad cell to word). */
static int build_cells_parallel(vtu_reader *r, const vtu_array *pts, const cell_arrays *a,
                                const tpk_cell_rule *rule_of, cell_tally *t, uint8_t *keep,
                                tpk_mesh *out)
{
    int64_t nc = r->cell_count;
    if (nc < 65536 || a->foffs || a->faces)
        return 0;
    cells_job *job = calloc(1, sizeof *job);
    if (!job)
        return 0;
    job->r = r, job->a = a, job->rule_of = rule_of, job->keep = keep, job->out = out;
    int threads = tpk_threads_for(nc, tpk_thread_count(0), 65536);
    tpk_parallel_for(nc, threads, scan_range, job);
    int clean = 1;
    for (int w = 0; w < threads; w++)
        clean &= job->bad[w] < 0;
    if (!clean) {
        free(job);
        return 0;
    }
    for (int w = 0; w < threads; w++) {
        const cell_tally *x = &job->tally[w];
        job->first_cell[w] = t->kept;
        job->first_conn[w] = t->conn_size;
        for (int type = 0; type < 256; type++)
            t->dropped[type] += x->dropped[type];
        t->drop_total += x->drop_total;
        t->kept += x->kept;
        t->conn_size += x->conn_size;
    }
    int rc = alloc_output(r, pts, t, out);
    if (rc == 0)
        tpk_parallel_for(nc, threads, copy_range, job);
    free(job);
    return rc ? -1 : 1;
}

/* Points and the kept cells into `out`; keep[c] says whether source cell c was kept. */
static int copy_cells(vtu_reader *r, const vtu_array *pts, const cell_arrays *a, const tpk_cell_rule *rule_of,
                      const cell_span *span, const cell_tally *t, uint8_t *keep, tpk_mesh *out)
{
    if (alloc_output(r, pts, t, out))
        return -1;
    int64_t k = 0, o = 0;
    for (int64_t c = 0; c < r->cell_count; c++) {
        tpk_cell_rule rule = rule_of[(int)a->types->values[c]];
        keep[c] = rule.kind != TPK_RULE_DROP;
        if (!keep[c])
            continue;
        int64_t n = span[c].n;
        for (int64_t j = 0; j < n; j++)
            out->cell_conn[o++] = (int32_t)span[c].v[j];
        out->cell_types[k] = rule.out_type;
        out->cell_offsets[++k] = o;
    }
    return 0;
}

/* One point or cell DataArray as a field of `out` (cell values of kept cells only). */
static int add_field(vtu_reader *r, vtu_array *a, const uint8_t *keep, int64_t kept, tpk_mesh *out)
{
    int64_t nc = r->cell_count;
    uint64_t want = (uint64_t)(a->role == ROLE_POINT_FIELD ? r->point_count : nc) * (uint64_t)a->components;
    if (a->count != want) { /* only when read leniently: decoding refuses it otherwise */
        char place[96];
        snprintf(place, sizeof place, "line %ld", a->line);
        if (tpk_diag_field_problem(r->diag, a->name, (long long)want, (long long)a->count, place) == 0)
            return 0;
        return vtu_fail_array(r, a, "expected %llu values, found %llu", (unsigned long long)want,
                              (unsigned long long)a->count);
    }
    int64_t tuples = a->role == ROLE_POINT_FIELD ? r->point_count : kept;
    float *v = malloc(sizeof(float) * (size_t)(tuples ? tuples : 1) * (size_t)a->components);
    if (!v)
        return vtu_fail_array(r, a, "out of memory");
    if (a->role == ROLE_POINT_FIELD) {
        for (uint64_t j = 0; j < a->count; j++)
            v[j] = (float)a->values[j];
    } else {
        int64_t t = 0;
        for (int64_t c = 0; c < nc; c++) {
            if (!keep[c])
                continue;
            for (int j = 0; j < a->components; j++)
                v[t * a->components + j] = (float)a->values[c * a->components + j];
            t++;
        }
    }
    if (tpk_mesh_add_field(out, a->name, a->role == ROLE_POINT_FIELD ? TPK_ASSOC_POINT : TPK_ASSOC_TET,
                           a->components, 1, v)) {
        free(v);
        return vtu_fail_array(r, a, "out of memory");
    }
    return 0;
}

int vtu_build_mesh(vtu_reader *r, tpk_mesh *out)
{
    if (!r->root_seen)
        return vtu_fail_line(r, 0, "expected a <VTKFile> element, found none");
    if (!r->piece_seen)
        return vtu_fail_line(r, 0, "expected an UnstructuredGrid with a Piece, found none");
    vtu_array *pts = find_role(r, ROLE_POINTS);
    cell_arrays a = {find_role(r, ROLE_CONN), find_role(r, ROLE_OFFSETS), find_role(r, ROLE_TYPES),
                     find_role(r, ROLE_FACES), find_role(r, ROLE_FACEOFFSETS)};
    if (!pts && r->point_count > 0)
        return vtu_fail_line(r, 0, "expected a Points DataArray, found none");
    if (r->cell_count > 0 && (!a.conn || !a.offs || !a.types))
        return vtu_fail_line(r, 0, "Cells: expected DataArrays connectivity, offsets and types, found %s missing",
                             !a.conn ? "connectivity" : !a.offs ? "offsets" : "types");
    if (check_offsets_and_types(r, &a))
        return -1;
    int64_t nc = r->cell_count;
    uint8_t *keep = malloc((size_t)(nc ? nc : 1));
    cell_tally t;
    memset(&t, 0, sizeof t);
    tpk_cell_rule rule_of[256];
    for (int type = 0; type < 256; type++)
        rule_of[type] = tpk_cell_rule_for(type);
    /* the one-core passes keep each cell's span (16 bytes a cell), which the parallel ones recompute */
    int both = keep ? build_cells_parallel(r, pts, &a, rule_of, &t, keep, out) : 0;
    cell_span *span = both ? NULL : malloc(sizeof *span * (size_t)(nc ? nc : 1));
    int rc = -1;
    if (both >= 0 && (!keep || (!both && !span)))
        rc = vtu_fail_line(r, 0, "out of memory");
    else if (both >= 0)
        rc = both ? 0 : scan_cells(r, &a, rule_of, span, &t);
    if (rc == 0 && t.drop_total)
        tpk_warn_cell_counts(r->diag, r->name, t.dropped, t.drop_total, "dropped cells that are not volumes:");
    if (rc == 0 && !both)
        rc = copy_cells(r, pts, &a, rule_of, span, &t, keep, out);
    free(span);
    for (int i = 0; rc == 0 && i < r->array_count; i++)
        if (r->arrays[i].role == ROLE_POINT_FIELD || r->arrays[i].role == ROLE_CELL_FIELD)
            rc = add_field(r, &r->arrays[i], keep, t.kept, out);
    free(keep);
    if (rc)
        return -1;
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "vtu");
    if (tpk_mesh_take_face_streams(out)) /* the streams went into cell_conn above */
        return vtu_fail_line(r, 0, "out of memory");
    return 0;
}
