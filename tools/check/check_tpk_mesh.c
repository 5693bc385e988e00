/* A .tpk file as a tpk_mesh for the mesh-level check groups: tets as cells of type 10 (Tet32 ids, or
 * recovered from Tet20/Tet16 by the library's walk), world coordinates, every field with all steps and
 * the time values. */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "check.h"
#include "tetpack.h"

static int fail_file(tpk_file *file, tpk_diag *diag, const char *what)
{
    return tpk_diag_fail(diag, "%s: %s", what, tpk_error_text(file));
}

static int load_cells(tpk_file *file, int32_t *tets, tpk_mesh *out, tpk_diag *diag)
{
    out->cell_conn = tets; /* owned by out from here: tpk_mesh_free frees it on every path */
    static const struct {
        uint32_t tag;
        tpk_layout layout;
    } order[3] = {{TPK_TAG_TT32, TPK_LAYOUT_TET32}, {TPK_TAG_TT20, TPK_LAYOUT_TET20}, {TPK_TAG_TT16, TPK_LAYOUT_TET16}};
    uint64_t i;
    int k = 0;
    while (k < 2 && tpk_find_chunk(file, order[k].tag, 0, 0, &i) != TPK_OK)
        k++;
    tpk_mesh_arrays m;
    if (tpk_load_arrays(file, order[k].layout, NULL, 0, &m) != TPK_OK)
        return fail_file(file, diag, "cannot load the tets");
    int64_t V = (int64_t)m.vertex_count, T = (int64_t)m.tet_count;
    out->point_count = V;
    out->cell_count = T;
    out->points = malloc(sizeof *out->points * (size_t)(3 * V + 1));
    out->cell_types = malloc((size_t)T + 1);
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(T + 1));
    if (!out->cell_conn)
        out->cell_conn = malloc(sizeof *out->cell_conn * (size_t)(4 * T + 1));
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn)
        return tpk_diag_fail(diag, "out of memory for a mesh of %" PRId64 " tets", T);
    for (int64_t p = 0; p < 3 * V; p++)
        out->points[p] = m.origin[p % 3] + (double)m.positions[p];
    memset(out->cell_types, TPK_CELL_TETRA, (size_t)T);
    for (int64_t c = 0; c <= T; c++)
        out->cell_offsets[c] = 4 * c;
    if (tets)
        return 0;
    tpk_result r = tpk_recover_tets_threads(&m, out->cell_conn, tpk_thread_count(0));
    if (r != TPK_OK)
        return tpk_diag_fail(diag, "the tets cannot be recovered from the Tet%d layout (%s); the 6xx findings "
                             "say why", (int)order[k].layout, tpk_result_string(r));
    return 0;
}

static int load_field(tpk_file *file, uint32_t f, tpk_mesh *out, tpk_diag *diag)
{
    tpk_field_desc d;
    if (tpk_get_field(file, f, &d) != TPK_OK)
        return fail_file(file, diag, "cannot read a field descriptor");
    uint64_t n = d.association == TPK_ASSOC_POINT ? (uint64_t)out->point_count : (uint64_t)out->cell_count;
    float *values = malloc(sizeof *values * (size_t)(n * d.step_count + 1));
    if (!values)
        return tpk_diag_fail(diag, "out of memory for field '%s'", d.name);
    for (uint32_t s = 0; s < d.step_count; s++) {
        uint64_t i;
        if (tpk_find_chunk(file, TPK_TAG_FDAT, f, s, &i) != TPK_OK ||
            tpk_read_chunk(file, i, values + n * s, n * sizeof *values) != TPK_OK) {
            free(values);
            return fail_file(file, diag, "cannot read field data");
        }
    }
    if (tpk_mesh_add_field(out, d.name, (int)d.association, 1, (int)d.step_count, values)) {
        free(values);
        return tpk_diag_fail(diag, "out of memory for field '%s'", d.name);
    }
    out->step_count = (int)d.step_count > out->step_count ? (int)d.step_count : out->step_count;
    return 0;
}

static int load_times(tpk_file *file, tpk_mesh *out, tpk_diag *diag)
{
    uint64_t i;
    tpk_dir_entry e;
    if (tpk_find_chunk(file, TPK_TAG_TIME, 0, 0, &i) != TPK_OK || tpk_get_chunk(file, i, &e) != TPK_OK)
        return 0;
    out->times = malloc(sizeof *out->times * (size_t)(e.elem_count + 1));
    if (!out->times)
        return tpk_diag_fail(diag, "out of memory for time values");
    if (tpk_read_chunk(file, i, out->times, e.raw_size) != TPK_OK)
        return fail_file(file, diag, "cannot read the time values");
    return 0;
}

int tpk_check_tpk_mesh(tpk_file *file, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_check_tpk_mesh_tets(file, NULL, out, diag);
}

int tpk_check_tpk_mesh_tets(tpk_file *file, int32_t *tets, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    snprintf(out->format, sizeof out->format, "tpk");
    out->step_count = 1;
    int rc = load_cells(file, tets, out, diag);
    for (uint32_t f = 0; !rc && f < tpk_field_count(file); f++)
        rc = load_field(file, f, out, diag);
    if (!rc)
        rc = load_times(file, out, diag);
    if (rc)
        tpk_mesh_free(out);
    return rc;
}
