/* Reading one rank's pieces and appending them into one tpk_mesh: points and cells concatenated (a point on
 * a boundary between pieces appears once per piece until global ids merge it), fields matched by name. */
#include "pieces.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import/importers.h"
#include "import/openfoam/foam_file.h"
#include "tetpack.h"

int tpk_is_volume_cell(uint8_t type)
{
    return (type >= TPK_CELL_TETRA && type <= TPK_CELL_PYRAMID) || type == TPK_CELL_POLYHEDRON;
}

void tpk_rank_pieces_free(tpk_rank_pieces *p)
{
    tpk_mesh_free(&p->mesh);
    free(p->given_ids);
    free(p->given_cell_ids);
    free(p->cell_piece);
    free(p->cell_volume);
    memset(p, 0, sizeof *p);
}

static int same_fields(const tpk_mesh *a, const tpk_mesh *b)
{
    if (a->field_count != b->field_count)
        return 0;
    for (int f = 0; f < a->field_count; f++)
        if (strcmp(a->fields[f].name, b->fields[f].name) || a->fields[f].association != b->fields[f].association ||
            a->fields[f].components != b->fields[f].components || a->fields[f].step_count != b->fields[f].step_count)
            return 0;
    return 1;
}

static void *grow(void *ptr, size_t bytes, int *failed)
{
    void *p = realloc(ptr, bytes ? bytes : 1);
    if (!p)
        *failed = 1;
    return p ? p : ptr;
}

/* Field values are step-major: each step's block grows by the piece's block. */
static int append_field(tpk_src_field *dst, int64_t dst_n, const tpk_src_field *src, int64_t src_n)
{
    size_t comp = (size_t)dst->components, steps = (size_t)dst->step_count;
    float *values = malloc(sizeof *values * comp * steps * (size_t)(dst_n + src_n) + 1);
    if (!values)
        return -1;
    for (size_t s = 0; s < steps; s++) {
        if (dst_n > 0) /* the first piece's values go into an empty field */
            memcpy(values + s * comp * (size_t)(dst_n + src_n), dst->values + s * comp * (size_t)dst_n,
                   sizeof *values * comp * (size_t)dst_n);
        memcpy(values + s * comp * (size_t)(dst_n + src_n) + comp * (size_t)dst_n,
               src->values + s * comp * (size_t)src_n, sizeof *values * comp * (size_t)src_n);
    }
    free(dst->values);
    dst->values = values;
    return 0;
}

void tpk_face_stream_ids(tpk_mesh *mesh, int64_t first_cell, const int32_t *map, int32_t offset)
{
    if (!mesh->face_offsets)
        return;
    for (int64_t c = first_cell; c < mesh->cell_count; c++) {
        if (mesh->face_offsets[c] == mesh->face_offsets[c + 1])
            continue;
        int32_t *stream = mesh->faces + mesh->face_offsets[c];
        int64_t at = 1;
        for (int32_t f = 0; f < stream[0]; f++) {
            int32_t n = stream[at++];
            for (int32_t j = 0; j < n; j++, at++)
                stream[at] = map ? map[stream[at]] : stream[at] + offset;
        }
    }
}

/* The piece's polyhedra face streams after the ones before (offsets for every cell once any piece has
 * polyhedra). Called before the cells are counted in: d->cell_count is still the cells before. */
static int append_streams(tpk_mesh *d, const tpk_mesh *m)
{
    if (!m->face_offsets && !d->face_offsets)
        return 0;
    int64_t nc = d->cell_count, before = d->face_offsets ? d->face_offsets[nc] : 0;
    int64_t added = m->face_offsets ? m->face_offsets[m->cell_count] : 0;
    int64_t *offsets = realloc(d->face_offsets, sizeof *offsets * (size_t)(nc + m->cell_count + 1));
    if (!offsets)
        return -1;
    if (!d->face_offsets)
        memset(offsets, 0, sizeof *offsets * (size_t)(nc + 1)); /* the cells before: no streams */
    d->face_offsets = offsets;
    int32_t *faces = realloc(d->faces, sizeof *faces * (size_t)(before + added + 1));
    if (!faces)
        return -1;
    d->faces = faces;
    if (added)
        memcpy(faces + before, m->faces, sizeof *faces * (size_t)added);
    for (int64_t c = 0; c < m->cell_count; c++)
        offsets[nc + c + 1] = before + (m->face_offsets ? m->face_offsets[c + 1] : 0);
    return 0;
}

static int append_piece(tpk_rank_pieces *out, const tpk_mesh *m, int piece)
{
    tpk_mesh *d = &out->mesh;
    int failed = 0;
    int64_t np = d->point_count, nc = d->cell_count, nconn = nc ? d->cell_offsets[nc] : 0;
    int64_t mconn = m->cell_count ? m->cell_offsets[m->cell_count] : 0;
    d->points = grow(d->points, sizeof *d->points * 3 * (size_t)(np + m->point_count), &failed);
    d->cell_types = grow(d->cell_types, (size_t)(nc + m->cell_count), &failed);
    d->cell_offsets = grow(d->cell_offsets, sizeof *d->cell_offsets * (size_t)(nc + m->cell_count + 1), &failed);
    d->cell_conn = grow(d->cell_conn, sizeof *d->cell_conn * (size_t)(nconn + mconn), &failed);
    out->cell_piece = grow(out->cell_piece, sizeof *out->cell_piece * (size_t)(nc + m->cell_count), &failed);
    out->cell_volume = grow(out->cell_volume, sizeof *out->cell_volume * (size_t)(nc + m->cell_count), &failed);
    for (int f = 0; !failed && f < d->field_count; f++)
        failed = append_field(&d->fields[f], d->fields[f].association == TPK_ASSOC_POINT ? np : nc, &m->fields[f],
                              m->fields[f].association == TPK_ASSOC_POINT ? m->point_count : m->cell_count) != 0;
    if (failed || append_streams(d, m) != 0)
        return -1;
    memcpy(d->points + 3 * np, m->points, sizeof *d->points * 3 * (size_t)m->point_count);
    memcpy(d->cell_types + nc, m->cell_types, (size_t)m->cell_count);
    d->cell_offsets[0] = 0;
    int64_t volume = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        d->cell_offsets[nc + c + 1] = nconn + m->cell_offsets[c + 1];
        out->cell_piece[nc + c] = piece;
        out->cell_volume[nc + c] = tpk_is_volume_cell(m->cell_types[c]) ? volume++ : -1;
    }
    for (int64_t i = 0; i < mconn; i++)
        d->cell_conn[nconn + i] = m->cell_conn[i] + (int32_t)np;
    d->point_count = np + m->point_count;
    d->cell_count = nc + m->cell_count;
    tpk_face_stream_ids(d, nc, NULL, (int32_t)np);
    return 0;
}

/* The point field GlobalPointIds when it holds an exact integer per point (float32: below 2^24). */
static const float *id_field(const tpk_mesh *m)
{
    for (int f = 0; f < m->field_count; f++) {
        const tpk_src_field *g = &m->fields[f];
        if (strcmp(g->name, "GlobalPointIds") || g->association != TPK_ASSOC_POINT || g->components != 1)
            continue;
        for (int64_t i = 0; i < m->point_count; i++)
            if (!(g->values[i] >= 0 && g->values[i] < 16777216.0f && g->values[i] == (float)(int64_t)g->values[i]))
                return NULL;
        return g->values;
    }
    return NULL;
}

/* Piece k's global point ids into ids[0 .. point_count): 1 when it gives them, 0 when not, -1 on a
 * pointProcAddressing that cannot be read or does not fit the piece, or an id past 32 bits. The
 * importer's exact ids (Exodus node number maps) first, then OpenFOAM's, then a float field. */
static int piece_ids(const tpk_piece_list *list, int k, const tpk_mesh *m, int64_t *ids, tpk_diag *diag)
{
    if (m->global_point_ids) { /* exact, from the importer (Exodus node number maps) */
        for (int64_t i = 0; i < m->point_count; i++)
            if ((ids[i] = m->global_point_ids[i]) > INT32_MAX - 1)
                return tpk_diag_fail(diag, "%s: point %lld has global id %lld, expected an id below 2^31-1 (a part "
                                     "set numbers its vertices in 32 bits)",
                                     list->paths[k], (long long)i, (long long)ids[i]);
        return 1;
    }
    if (!list->openfoam) {
        const float *f = id_field(m);
        for (int64_t i = 0; f && i < m->point_count; i++)
            ids[i] = (int64_t)f[i];
        return f != NULL;
    }
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/constant/polyMesh", list->paths[k]);
    tpk_foam_file file;
    int32_t *labels = NULL;
    int64_t count = 0;
    if (tpk_foam_open(&file, dir, "pointProcAddressing", diag) != 0)
        return -1;
    int rc = tpk_foam_labels(&file, &count, &labels, "point addresses");
    tpk_foam_close(&file);
    if (rc == 0 && count != m->point_count)
        rc = tpk_diag_fail(diag, "%s/pointProcAddressing: expected %lld addresses (the piece's points), found %lld",
                           dir, (long long)m->point_count, (long long)count);
    for (int64_t i = 0; rc == 0 && i < count; i++)
        if ((ids[i] = labels[i]) < 0)
            rc = tpk_diag_fail(diag, "%s/pointProcAddressing: address %lld is %d; expected a point id >= 0", dir,
                               (long long)i, labels[i]);
    free(labels);
    return rc == 0 ? 1 : -1;
}

/* Appends piece k's given ids after the points before it, or drops them all once a piece has none. */
static int append_ids(tpk_rank_pieces *out, const tpk_piece_list *list, int k, int first, const tpk_mesh *m,
                      tpk_diag *diag)
{
    if (k > first && !out->given_ids)
        return 0;
    int64_t before = out->mesh.point_count - m->point_count;
    int64_t *grown = realloc(out->given_ids, sizeof *grown * (size_t)(out->mesh.point_count + 1));
    if (!grown)
        return tpk_diag_fail(diag, "out of memory for global ids");
    out->given_ids = grown;
    int rc = piece_ids(list, k, m, grown + before, diag);
    if (rc <= 0) {
        free(out->given_ids);
        out->given_ids = NULL;
    }
    return rc < 0 ? -1 : 0;
}

/* Appends piece k's global cell ids (kept only while every piece gives them). */
static int append_cell_ids(tpk_rank_pieces *out, int k, int first, const tpk_mesh *m)
{
    if ((k > first && !out->given_cell_ids) || !m->global_cell_ids) {
        free(out->given_cell_ids);
        out->given_cell_ids = NULL;
        return 0;
    }
    int64_t before = out->mesh.cell_count - m->cell_count;
    int64_t *grown = realloc(out->given_cell_ids, sizeof *grown * (size_t)(out->mesh.cell_count + 1));
    if (!grown)
        return -1;
    out->given_cell_ids = grown;
    memcpy(grown + before, m->global_cell_ids, sizeof *grown * (size_t)m->cell_count);
    return 0;
}

int tpk_read_pieces(const tpk_piece_list *list, int first, int last, tpk_rank_pieces *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    for (int k = first; k < last; k++) {
        tpk_mesh m;
        if (tpk_import_any(list->paths[k], NULL, &m, diag) != 0) {
            tpk_rank_pieces_free(out);
            return -1;
        }
        const char *why = k > first && !same_fields(&out->mesh, &m) ? "its fields differ from the first piece's"
                          : out->mesh.point_count + m.point_count > INT32_MAX ? "a rank holds at most 2^31-1 points"
                                                                               : NULL;
        if (!why && k == first) { /* the first piece gives the field list (values appended below) */
            out->mesh.fields = calloc((size_t)(m.field_count ? m.field_count : 1), sizeof *out->mesh.fields);
            out->mesh.field_count = m.field_count;
            for (int f = 0; out->mesh.fields && f < m.field_count; f++) {
                out->mesh.fields[f] = m.fields[f];
                out->mesh.fields[f].values = NULL;
            }
            out->mesh.step_count = m.step_count;
            out->mesh.times = m.times;
            m.times = NULL;
            memcpy(out->mesh.format, m.format, sizeof m.format);
            why = out->mesh.fields ? NULL : "out of memory";
        }
        if (!why && (append_piece(out, &m, k) != 0 || append_cell_ids(out, k, first, &m) != 0))
            why = "out of memory";
        if (!why && append_ids(out, list, k, first, &m, diag) != 0) {
            tpk_mesh_free(&m);
            tpk_rank_pieces_free(out);
            return -1;
        }
        out->points_read += m.point_count;
        tpk_mesh_free(&m);
        if (why) {
            tpk_rank_pieces_free(out);
            return tpk_diag_fail(diag, "%s: piece %d: %s", list->paths[k], k, why);
        }
    }
    return 0;
}
