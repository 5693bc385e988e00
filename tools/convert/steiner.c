/* Warped cells and polyhedra into tets (tools/convert/steiner.h): the entry, which has the cells decided
 * (steiner_decide.c: a cone, a star from added points, or TetGen inside the fixed boundary, in rounds
 * until no cell asks for a change), then emits every decided cell's tets and points. */
#include "steiner.h"

#include <stdlib.h>
#include <string.h>

#include "fixed_boundary.h"
#include "steiner_internal.h"
#include "mesh/cell_types.h"

void tpk_added_points_free(tpk_added_points *added)
{
    free(added->corner_start);
    free(added->corners);
    free(added->cells);
    memset(added, 0, sizeof *added);
}

/* ---- Emission -------------------------------------------------------------------------------------- */

static int push_tet(stage *st, int32_t a, int32_t b, int32_t c, int32_t d, int64_t cell)
{
    tpk_tetmesh *out = st->out;
    if (out->tet_count == *st->tet_capacity) {
        int64_t cap = 2 * *st->tet_capacity + 64;
        int32_t *tets = realloc(out->tets, sizeof *tets * 4 * (size_t)cap);
        if (tets)
            out->tets = tets;
        int32_t *source = realloc(out->tet_source, sizeof *source * (size_t)cap);
        if (source)
            out->tet_source = source;
        if (!tets || !source)
            return -1;
        *st->tet_capacity = cap;
    }
    int32_t *t = out->tets + 4 * out->tet_count;
    t[0] = a, t[1] = b, t[2] = c, t[3] = d;
    out->tet_source[out->tet_count++] = (int32_t)cell;
    out->flat_tets += tpk_tet_is_flat(out->points, t);
    return 0;
}

/* Counts a split cell (a polyhedron, a mirrored one: the first is remembered for the refusal). */
static void count_split(stage *st, int64_t c)
{
    tpk_tetmesh *out = st->out;
    out->polyhedra += st->src->cell_types[c] == TPK_CELL_POLYHEDRON;
    if (st->w.mirrored && (out->mirrored_cells == 0 || c < out->first_mirrored_cell))
        out->first_mirrored_cell = c;
    out->mirrored_cells += st->w.mirrored;
}

/* Tets of a decided cell: its cone, or its star (adding its centre and any new face points). */
static int emit_cell(stage *st, int64_t c, int cone)
{
    cell_work *w = &st->w;
    const tpk_mesh *src = st->src;
    const int32_t *corners = src->cell_conn + src->cell_offsets[c];
    int64_t corner_count = src->cell_offsets[c + 1] - src->cell_offsets[c];
    if (steiner_load_cell(st, c))
        return -1; /* it loaded when decided: only memory can fail now */
    steiner_lookup_faces(st);
    int32_t apex = corners[0];
    for (int64_t k = 1; cone && k < corner_count; k++)
        apex = corners[k] < apex ? corners[k] : apex;
    if (!cone && (apex = steiner_push_point(st, w->centre, corners, corner_count, c)) < 0)
        return -1;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        const int32_t *v = w->faces.ids + w->faces.starts[f];
        int64_t n = steiner_face_size(w, f), m = steiner_fan_start(st, f), touches = 0;
        if (steiner_has_point(st, w->entry[f])) {
            int32_t q = steiner_face_point(st, w->entry[f], c);
            if (q < 0)
                return -1;
            v = w->faces.ids + w->faces.starts[f]; /* steiner_face_point may not move it, but be plain */
            for (int64_t i = 0; i < n; i++)
                if (push_tet(st, v[i], q, v[(i + 1) % n], apex, c))
                    return -1;
            continue;
        }
        for (int64_t i = 0; i < n; i++)
            touches |= v[i] == apex;
        for (int64_t i = 0; !touches && i + 2 < n; i++) {
            int32_t t[3];
            steiner_fan_triangle(w, f, m, i, t);
            if (push_tet(st, t[0], t[2], t[1], apex, c))
                return -1;
        }
    }
    st->out->steiner_cells += !cone;
    count_split(st, c);
    return 0;
}

/* Tets of a cell no star fits: tetrahedralized inside its boundary triangles (tools/convert/fixed_boundary.h),
 * interior points added as its centre would be (the mean of its corners for fields). Returns 0 (also
 * for a cell left out under TPK_TETRA_SKIP_BAD_CELLS), -1 when out of memory, -2 with a message. */
static int emit_fixed(stage *st, int64_t c, tpk_diag *diag)
{
    const tpk_mesh *src = st->src;
    const int32_t *corners = src->cell_conn + src->cell_offsets[c];
    int64_t corner_count = src->cell_offsets[c + 1] - src->cell_offsets[c];
    local_boundary b;
    tpk_fixed_tets fixed = {0};
    char why[600];
    if (steiner_load_cell(st, c))
        return -1; /* it loaded when decided: only memory can fail now */
    steiner_lookup_faces(st);
    int rc = steiner_local_boundary_build(st, c, 1, &b);
    if (rc == 0)
        rc = tpk_fixed_boundary_tets(b.points, (int32_t)b.id_count, b.triangles, (int32_t)b.triangle_count, &fixed,
                                     why, sizeof why);
    if (rc == 1 && (st->flags & TPK_TETRA_SKIP_BAD_CELLS)) {
        st->out->bad_cells_skipped++;
        rc = 0;
    } else if (rc == 1) {
        tpk_diag_fail(diag, "cell %lld (a %s) is too warped or non-convex for a point at its centre or its face "
                      "centres to split it, and %s; pass --skip-bad-cells to leave such cells out", (long long)c,
                      tpk_cell_type(src->cell_types[c])->name, why);
        rc = -2;
    } else if (rc == 0) {
        int32_t *vertex = malloc(sizeof *vertex * (size_t)(fixed.point_count ? fixed.point_count : 1));
        rc = vertex ? 0 : -1;
        for (int32_t k = (int32_t)b.id_count; k < fixed.point_count; k++)
            steiner_to_file_grid(st, fixed.points + 3 * (int64_t)k);
        for (int64_t t = 0; rc == 0 && t < fixed.tet_count; t++) {
            const int32_t *v = fixed.tets + 4 * t;
            const double *p = fixed.points;
            if (tpk_orient3d_exact(p + 3 * v[0], p + 3 * v[1], p + 3 * v[2], p + 3 * v[3]) <= 0) {
                tpk_diag_fail(diag, "cell %lld (a %s): a tet TetGen made inside its boundary is flat or inverted once "
                              "its points are rounded to the file's float32 grid", (long long)c,
                              tpk_cell_type(src->cell_types[c])->name);
                rc = -2;
            }
        }
        for (int32_t k = 0; rc == 0 && k < fixed.point_count; k++)
            if ((vertex[k] = k < b.id_count ? b.ids[k] : steiner_push_point(st, fixed.points + 3 * (int64_t)k, corners,
                                                                    corner_count, c)) < 0)
                rc = -1;
        for (int64_t t = 0; rc == 0 && t < fixed.tet_count; t++) {
            const int32_t *v = fixed.tets + 4 * t;
            rc = push_tet(st, vertex[v[0]], vertex[v[1]], vertex[v[2]], vertex[v[3]], c);
        }
        free(vertex);
        if (rc == 0) {
            st->out->fixed_boundary_cells++;
            count_split(st, c);
        }
    }
    tpk_fixed_tets_free(&fixed);
    steiner_local_boundary_free(&b);
    return rc;
}

int tpk_steiner_stage(const tpk_mesh *src, const int64_t *hard, int64_t hard_count, int flags,
                      int64_t *tet_capacity, tpk_tetmesh *out, tpk_added_points *added, tpk_diag *diag)
{
    stage st;
    memset(&st, 0, sizeof st);
    st.src = src, st.out = out, st.added = added, st.flags = flags;
    st.tet_capacity = tet_capacity;
    st.point_capacity = out->vertex_count;
    st.state = calloc((size_t)(src->cell_count ? src->cell_count : 1), 1);
    int rc = st.state ? 0 : -1;
    for (int64_t i = 0; rc == 0 && i < hard_count; i++)
        st.state[hard[i]] = S_PENDING;
    if (rc == 0)
        rc = steiner_run_rounds(&st, hard, hard_count);
    if (rc == 0) {
        steiner_drop_forced_tets(&st);
        rc = steiner_report_bad(&st, diag);
    }
    for (int64_t c = 0; rc == 0 && c < src->cell_count; c++) {
        int mode = st.state[c] & S_MODE;
        if (mode == S_STAR || mode == S_CONE)
            rc = emit_cell(&st, c, mode == S_CONE);
        else if (mode == S_FIXED)
            rc = emit_fixed(&st, c, diag);
    }
    if (rc == -1 && out->vertex_count >= INT32_MAX) {
        tpk_diag_fail(diag, "the points added to split cells pass the limit of 2^31-1 vertices per file; split "
                      "the mesh into parts");
        rc = -2;
    }
    free(st.state);
    tpk_face_table_free(&st.table);
    tpk_polygons_free(&st.w.faces);
    free(st.w.entry);
    free(st.w.key);
    free(st.w.ring);
    return rc;
}
