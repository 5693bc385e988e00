/* tpk_load_arrays: the positions, one tet layout, the shell and a scalar field of a file as plain
 * arrays, zero-copy for uncompressed chunks and decoded once into handle-owned memory for zstd chunks.
 * Every chunk handed out has had its checksum (unless TRUSTED) and its id ranges (rule 17) checked. */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "internal_file.h"

/* Verified bytes of the chunk (tag, index, step), which the directory rules guarantee exists. */
static tpk_result load_chunk(tpk_file *file, uint32_t tag, uint32_t index, uint32_t step, const void **out)
{
    uint64_t i;
    if (tpk_find_chunk(file, tag, index, step, &i) != TPK_OK) {
        char name[16];
        tpki_tag_name(tag, name);
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "no %s chunk with index %" PRIu32 " step %" PRIu32, name,
                             index, step);
    }
    tpk_result r = tpki_file_chunk_bytes(file, i, out);
    return r == TPK_OK ? tpki_file_check_ids(file, i, *out) : r;
}

static uint32_t layout_tag(tpk_layout layout)
{
    switch (layout) {
    case TPK_LAYOUT_TET16: return TPK_TAG_TT16;
    case TPK_LAYOUT_TET20: return TPK_TAG_TT20;
    case TPK_LAYOUT_TET32: return TPK_TAG_TT32;
    }
    return 0;
}

static tpk_result layout_not_found(tpk_file *file, tpk_layout layout)
{
    static const tpk_layout all[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    char present[64] = "";
    uint64_t i;
    for (int k = 0; k < 3; k++) {
        if (tpk_find_chunk(file, layout_tag(all[k]), 0, 0, &i) == TPK_OK)
            snprintf(present + strlen(present), sizeof present - strlen(present), "%sTet%d",
                     present[0] ? ", " : "", (int)all[k]);
    }
    return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "the file has no Tet%d layout; layouts present: %s", (int)layout,
                         present);
}

static tpk_result load_tets(tpk_file *file, tpk_layout layout, tpk_mesh_arrays *m)
{
    uint64_t i;
    if (tpk_find_chunk(file, layout_tag(layout), 0, 0, &i) != TPK_OK)
        return layout_not_found(file, layout);
    const void *tets;
    tpk_result r = load_chunk(file, layout_tag(layout), 0, 0, &tets);
    if (r != TPK_OK)
        return r;
    m->tet16 = layout == TPK_LAYOUT_TET16 ? tets : NULL;
    m->tet20 = layout == TPK_LAYOUT_TET20 ? tets : NULL;
    m->tet32 = layout == TPK_LAYOUT_TET32 ? tets : NULL;
    return TPK_OK;
}

/* The field to load: the named one (must be per point), or the first point field, or none (*out_i =
 * UINT32_MAX). */
static tpk_result pick_field(tpk_file *file, const char *field_name, uint32_t *out_i)
{
    *out_i = UINT32_MAX;
    if (!field_name) {
        for (uint32_t f = 0; f < file->field_count && *out_i == UINT32_MAX; f++) {
            if (file->fields[f].association == TPK_ASSOC_POINT)
                *out_i = f;
        }
        return TPK_OK;
    }
    if (tpk_find_field(file, field_name, out_i) != TPK_OK)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "no field named '%s' (the file has %" PRIu32 " fields)",
                             field_name, file->field_count);
    if (file->fields[*out_i].association != TPK_ASSOC_POINT)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND,
                             "field '%s' is per-tet; tpk_load_arrays needs a per-point field (read its 'FDAT' "
                             "chunk with tpk_read_chunk)", field_name);
    return TPK_OK;
}

static tpk_result load_scalars(tpk_file *file, const char *field_name, uint32_t step, tpk_mesh_arrays *m)
{
    uint32_t f;
    tpk_result r = pick_field(file, field_name, &f);
    if (r != TPK_OK || f == UINT32_MAX)
        return r;
    if (step >= file->fields[f].step_count)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "field '%s' has %" PRIu32 " steps, step %" PRIu32 " asked",
                             file->fields[f].name, file->fields[f].step_count, step);
    const void *values;
    r = load_chunk(file, TPK_TAG_FDAT, f, step, &values);
    if (r == TPK_OK)
        m->scalars = values;
    return r;
}

tpk_result tpk_load_arrays(tpk_file *file, tpk_layout layout, const char *field_name, uint32_t step,
                           tpk_mesh_arrays *out)
{
    if (!file || !out)
        return TPK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!layout_tag(layout))
        return tpki_file_fail(file, TPK_ERR_INVALID_ARGUMENT, "layout %d is not 16, 20 or 32", (int)layout);
    tpk_result r = tpki_file_usable(file);
    if (r != TPK_OK)
        return r;
    tpk_mesh_arrays m = {.vertex_count = file->header.vertex_count, .tet_count = file->header.tet_count,
                         .shell_face_count = file->header.shell_face_count, .layout = layout};
    memcpy(m.origin, file->header.origin, sizeof m.origin);
    const void *positions, *shell;
    r = load_chunk(file, TPK_TAG_POS3, 0, 0, &positions);
    if (r == TPK_OK)
        r = load_tets(file, layout, &m);
    if (r == TPK_OK)
        r = load_chunk(file, TPK_TAG_SHEL, 0, 0, &shell);
    if (r == TPK_OK)
        r = load_scalars(file, field_name, step, &m);
    if (r != TPK_OK)
        return r;
    m.positions = positions;
    m.shell = shell;
    *out = m;
    return TPK_OK;
}

tpk_result tpk_load_tet_field(tpk_file *file, const char *field_name, uint32_t step, const float **out)
{
    if (!file || !field_name || !out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    tpk_result r = tpki_file_usable(file);
    if (r != TPK_OK)
        return r;
    uint32_t f;
    if (tpk_find_field(file, field_name, &f) != TPK_OK)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "no field named '%s' (the file has %" PRIu32 " fields)",
                             field_name, file->field_count);
    const tpk_field_desc *d = &file->fields[f];
    if (d->association != TPK_ASSOC_TET)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "field '%s' is per-point, not per-tet", field_name);
    if (step >= d->step_count)
        return tpki_file_fail(file, TPK_ERR_NOT_FOUND, "field '%s' has %" PRIu32 " steps, step %" PRIu32 " asked",
                             d->name, d->step_count, step);
    const void *values;
    r = load_chunk(file, TPK_TAG_FDAT, f, step, &values);
    if (r == TPK_OK)
        *out = values;
    return r;
}

tpk_result tpk_load_cull(tpk_file *file, tpk_cull *out)
{
    if (!file || !out)
        return TPK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    tpk_result r = tpki_file_usable(file);
    if (r != TPK_OK)
        return r;
    uint64_t i;
    if (tpk_find_chunk(file, TPK_TAG_CULL, 0, 0, &i) != TPK_OK)
        return TPK_ERR_NOT_FOUND;
    const void *raw;
    r = load_chunk(file, TPK_TAG_CULL, 0, 0, &raw); /* rule 17 checks the structure (rules.c check_cull) */
    if (r != TPK_OK)
        return r;
    const int32_t *w = raw;
    out->block_tets = (uint32_t)w[0];
    out->block_count = (uint64_t)w[1], out->seed_count = (uint64_t)w[2], out->interval_count = (uint64_t)w[3];
    out->seed_start = w + TPK_CULL_HEADER_WORDS;
    out->interval_start = out->seed_start + out->block_count + 1;
    out->seeds = out->interval_start + out->block_count + 1;
    out->intervals = out->seeds + TPK_CULL_SEED_WORDS * out->seed_count;
    return TPK_OK;
}
