/* VTU importer: the tpk_mesh from the decoded DataArrays. Offsets and cell types are checked, polyhedron
 * face streams too; cells are kept, reduced to their corners or dropped (cell_types.h); fields follow the
 * kept cells. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

int vtu_build_mesh(vtu_reader *r, tpk_mesh *out)
{
    if (!r->root_seen)
        return vtu_fail_line(r, 0, "expected a <VTKFile> element, found none");
    if (!r->piece_seen)
        return vtu_fail_line(r, 0, "expected an UnstructuredGrid with a Piece, found none");
    vtu_array *pts = find_role(r, ROLE_POINTS), *conn = find_role(r, ROLE_CONN), *offs = find_role(r, ROLE_OFFSETS),
              *types = find_role(r, ROLE_TYPES), *faces = find_role(r, ROLE_FACES),
              *foffs = find_role(r, ROLE_FACEOFFSETS);
    if (!pts && r->point_count > 0)
        return vtu_fail_line(r, 0, "expected a Points DataArray, found none");
    if (r->cell_count > 0 && (!conn || !offs || !types))
        return vtu_fail_line(r, 0, "Cells: expected DataArrays connectivity, offsets and types, found %s missing",
                             !conn ? "connectivity" : !offs ? "offsets" : "types");
    int64_t nc = r->cell_count;
    /* Offsets: increasing, ending at the connectivity's size. */
    int64_t prev = 0;
    for (int64_t c = 0; c < nc; c++) {
        double v = offs->values[c];
        if (!(v >= (double)prev && v <= (double)conn->count))
            return vtu_fail_array(r, offs, "cell %lld: expected an offset from %lld to %llu (not decreasing, within "
                                  "the connectivity), found %.17g", (long long)c, (long long)prev,
                                  (unsigned long long)conn->count, v);
        prev = (int64_t)v;
    }
    if (nc > 0 && (uint64_t)prev != conn->count)
        return vtu_fail_array(r, offs, "expected the last offset to be the connectivity size %llu, found %lld",
                              (unsigned long long)conn->count, (long long)prev);
    for (int64_t c = 0; c < nc; c++)
        if (!(types->values[c] >= 0 && types->values[c] <= 255))
            return vtu_fail_array(r, types, "cell %lld: expected a VTK cell type 0..255, found %.17g", (long long)c,
                                  types->values[c]);
    if (foffs && !faces)
        return vtu_fail_array(r, foffs, "expected a faces DataArray with faceoffsets, found none");
    cell_span *span = malloc(sizeof *span * (size_t)(nc ? nc : 1));
    if (!span)
        return vtu_fail_line(r, 0, "out of memory");
    int64_t dropped[256] = {0}, reduced[256] = {0};
    int64_t drop_total = 0, reduce_total = 0, kept = 0, conn_size = 0, face_prev = 0;
    int rc = 0;
    for (int64_t c = 0; c < nc && rc == 0; c++) {
        int type = (int)types->values[c];
        int64_t begin = c ? (int64_t)offs->values[c - 1] : 0, face_begin = 0;
        span[c].v = conn->values + begin;
        span[c].n = (int64_t)offs->values[c] - begin;
        tpk_cell_rule rule = tpk_cell_rule_for(type);
        if (rule.kind == TPK_RULE_UNKNOWN) {
            rc = vtu_fail_array(r, types, "cell %lld has unsupported cell type %d (%s)", (long long)c, type, rule.name);
            break;
        }
        if (foffs && foffs->values[c] >= 0) {
            double fv = foffs->values[c];
            if (!(fv >= (double)face_prev && fv <= (double)faces->count)) {
                rc = vtu_fail_array(r, foffs, "cell %lld: expected a face offset from %lld to %llu, found %.17g",
                                    (long long)c, (long long)face_prev, (unsigned long long)faces->count, fv);
                break;
            }
            if (type == TPK_CELL_POLYHEDRON) {
                face_begin = face_prev;
                span[c].v = faces->values + face_prev;
                span[c].n = (int64_t)fv - face_prev;
            }
            face_prev = (int64_t)fv;
        }
        if (type == TPK_CELL_POLYHEDRON) {
            if (!foffs || !(foffs->values[c] >= 0)) {
                rc = vtu_fail_array(r, types, "cell %lld is a polyhedron: expected its faces in faces/faceoffsets, "
                                    "found none", (long long)c);
                break;
            }
            rc = check_face_stream(r, faces, conn, c, span[c].v, span[c].n, face_begin, conn->values + begin,
                                   (int64_t)offs->values[c] - begin);
        } else if (rule.kind != TPK_RULE_DROP) {
            if ((rule.nodes > 0 && span[c].n != rule.nodes) || (rule.nodes < 0 && span[c].n < -rule.nodes)) {
                rc = vtu_fail_array(r, conn, "cell %lld (%s, type %d) has %lld points, expected %s%d", (long long)c,
                                    rule.name, type, (long long)span[c].n, rule.nodes < 0 ? "at least " : "",
                                    rule.nodes < 0 ? -rule.nodes : rule.nodes);
                break;
            }
        }
        if (type != TPK_CELL_POLYHEDRON)
            for (int64_t j = 0; j < span[c].n; j++)
                if (!(span[c].v[j] >= 0 && span[c].v[j] < (double)r->point_count)) {
                    rc = vtu_fail_array(r, conn, "cell %lld uses point id %.17g, but there are only %lld points "
                                        "(0 to %lld)", (long long)c, span[c].v[j], (long long)r->point_count,
                                        (long long)r->point_count - 1);
                    break;
                }
        if (rc)
            break;
        if (rule.kind == TPK_RULE_DROP) {
            dropped[type]++;
            drop_total++;
            continue;
        }
        if (rule.kind == TPK_RULE_REDUCE) {
            reduced[type]++;
            reduce_total++;
        }
        kept++;
        conn_size += rule.kind == TPK_RULE_REDUCE ? rule.out_nodes : span[c].n;
    }
    if (rc) {
        free(span);
        return -1;
    }
    if (drop_total)
        tpk_warn_cell_counts(r->diag, r->name, dropped, drop_total,
                             "dropped cells that are not volumes:");
    if (reduce_total)
        tpk_warn_cell_counts(r->diag, r->name, reduced, reduce_total,
                             "reduced higher-order cells to their corner nodes:");

    out->point_count = r->point_count;
    out->points = malloc(sizeof(double) * 3 * (size_t)(r->point_count ? r->point_count : 1));
    out->cell_count = kept;
    out->cell_types = malloc((size_t)(kept ? kept : 1));
    out->cell_offsets = malloc(sizeof(int64_t) * (size_t)(kept + 1));
    out->cell_conn = malloc(sizeof(int32_t) * (size_t)(conn_size ? conn_size : 1));
    uint8_t *keep = malloc((size_t)(nc ? nc : 1));
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn || !keep) {
        free(keep);
        free(span);
        return vtu_fail_line(r, 0, "out of memory");
    }
    if (r->point_count)
        memcpy(out->points, pts->values, sizeof(double) * 3 * (size_t)r->point_count);
    int64_t k = 0, o = 0;
    out->cell_offsets[0] = 0;
    for (int64_t c = 0; c < nc; c++) {
        tpk_cell_rule rule = tpk_cell_rule_for((int)types->values[c]);
        keep[c] = rule.kind != TPK_RULE_DROP;
        if (!keep[c])
            continue;
        int64_t n = rule.kind == TPK_RULE_REDUCE ? rule.out_nodes : span[c].n;
        for (int64_t j = 0; j < n; j++)
            out->cell_conn[o++] = (int32_t)span[c].v[j];
        out->cell_types[k] = rule.out_type;
        out->cell_offsets[++k] = o;
    }
    free(span);
    for (int i = 0; i < r->array_count; i++) {
        vtu_array *a = &r->arrays[i];
        if (a->role != ROLE_POINT_FIELD && a->role != ROLE_CELL_FIELD)
            continue;
        uint64_t want = (uint64_t)(a->role == ROLE_POINT_FIELD ? r->point_count : nc) * (uint64_t)a->components;
        if (a->count != want) { /* only when read leniently: decoding refuses it otherwise */
            char place[96];
            snprintf(place, sizeof place, "line %ld", a->line);
            if (tpk_diag_field_problem(r->diag, a->name, (long long)want, (long long)a->count, place) == 0)
                continue;
            free(keep);
            return vtu_fail_array(r, a, "expected %llu values, found %llu", (unsigned long long)want,
                                  (unsigned long long)a->count);
        }
        int64_t tuples = a->role == ROLE_POINT_FIELD ? r->point_count : kept;
        float *v = malloc(sizeof(float) * (size_t)(tuples ? tuples : 1) * (size_t)a->components);
        if (!v) {
            free(keep);
            return vtu_fail_array(r, a, "out of memory");
        }
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
            free(keep);
            return vtu_fail_array(r, a, "out of memory");
        }
    }
    free(keep);
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "vtu");
    if (tpk_mesh_take_face_streams(out)) /* the streams went into cell_conn above */
        return vtu_fail_line(r, 0, "out of memory");
    return 0;
}
