/* Reading one rank's pieces and appending them into one tpk_mesh: points and cells concatenated (a point on
 * a boundary between pieces appears once per piece until global ids merge it), fields matched by name. */
#include "pieces.h"

#include <stdlib.h>
#include <string.h>

#include "import/importers.h"
#include "tetpack.h"

int tpk_is_volume_cell(uint8_t type)
{
    return type >= TPK_CELL_TETRA && type <= TPK_CELL_PYRAMID;
}

void tpk_rank_pieces_free(tpk_rank_pieces *p)
{
    tpk_mesh_free(&p->mesh);
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
    if (failed)
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
        const char *why = m.face_offsets ? "polyhedra are not merged across pieces yet"
                          : k > first && !same_fields(&out->mesh, &m) ? "its fields differ from the first piece's"
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
        if (!why && append_piece(out, &m, k) != 0)
            why = "out of memory";
        out->points_read += m.point_count;
        tpk_mesh_free(&m);
        if (why) {
            tpk_rank_pieces_free(out);
            return tpk_diag_fail(diag, "%s: piece %d: %s", list->paths[k], k, why);
        }
    }
    return 0;
}
