/* tpk_iso_run: read the field, the step and the tets of a .tpk, extract (iso_march.c) and write
 * (iso_write.c). Only the chunks needed are read: positions, one layout, the shell, one FDAT step each. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/parallel.h"
#include "iso.h"

typedef struct iso_job {
    const tpk_iso_options *o;
    tpk_iso_report *rep;
    tpk_diag *diag;
    tpk_file *file;
    tpk_field_desc desc, color_desc;
    uint32_t field_index, color_index, color_step;
    tpk_mesh_arrays mesh;
    int32_t *tets;
    float *color_owned;
    const float *colors;
} iso_job;

static int fail_file(iso_job *j)
{
    return tpk_diag_fail(j->diag, "%s: %s", j->o->input, tpk_error_text(j->file));
}

/* Field `name` (NULL: the first point field) as a point field with step `step`. */
static int pick_field(iso_job *j, const char *name, const char *role, uint32_t step, uint32_t *index,
                      tpk_field_desc *desc)
{
    uint32_t n = tpk_field_count(j->file);
    for (uint32_t i = 0; i < n; i++) {
        tpk_field_desc d;
        if (tpk_get_field(j->file, i, &d) != TPK_OK)
            return fail_file(j);
        if (name ? !strcmp(d.name, name) : d.association == TPK_ASSOC_POINT) {
            if (d.association != TPK_ASSOC_POINT)
                return tpk_diag_fail(j->diag, "%s: %s '%s' is a tet field (one value per tet, no crossing inside a "
                                     "tet): iso extracts point fields; convert the source with --cell-to-point to "
                                     "average cell fields to points", j->o->input, role, d.name);
            if (step >= d.step_count)
                return tpk_diag_fail(j->diag, "%s: %s '%s' has steps 0..%u; step %u asked", j->o->input, role, d.name,
                                     d.step_count - 1, step);
            *index = i;
            *desc = d;
            return 0;
        }
    }
    if (name)
        return tpk_diag_fail(j->diag, "%s: no field named '%s' (the file has %u fields; tetpack info lists them)",
                             j->o->input, name, n);
    return tpk_diag_fail(j->diag, "%s: no point field to extract an isosurface from (the file has %u fields)",
                         j->o->input, n);
}

/* The tets as vertex quadruples from the first layout present (Tet32 holds them; the others are walked). */
static int load_mesh(iso_job *j)
{
    static const struct {
        tpk_layout layout;
        uint32_t tag;
    } layouts[3] = {{TPK_LAYOUT_TET32, TPK_TAG_TT32}, {TPK_LAYOUT_TET20, TPK_TAG_TT20}, {TPK_LAYOUT_TET16, TPK_TAG_TT16}};
    uint64_t i;
    int k = 0;
    while (k < 3 && tpk_find_chunk(j->file, layouts[k].tag, 0, 0, &i) != TPK_OK)
        k++;
    if (k == 3)
        return tpk_diag_fail(j->diag, "%s: no tet layout in the file (tetpack info lists its chunks)", j->o->input);
    if (tpk_load_arrays(j->file, layouts[k].layout, j->desc.name, j->o->step, &j->mesh) != TPK_OK)
        return fail_file(j);
    j->tets = malloc(sizeof *j->tets * 4 * (size_t)(j->mesh.tet_count ? j->mesh.tet_count : 1));
    if (!j->tets)
        return tpk_diag_fail(j->diag, "out of memory for %llu tets", (unsigned long long)j->mesh.tet_count);
    if (tpk_recover_tets_threads(&j->mesh, j->tets, tpk_thread_count(j->o->threads)) != TPK_OK)
        return fail_file(j);
    return 0;
}

/* The color field's values at its step: a view of the file, or decoded. */
static int load_colors(iso_job *j)
{
    uint64_t i;
    tpk_dir_entry e;
    if (tpk_find_chunk(j->file, TPK_TAG_FDAT, j->color_index, j->color_step, &i) != TPK_OK ||
        tpk_get_chunk(j->file, i, &e) != TPK_OK)
        return fail_file(j);
    if (e.elem_size != 4 || e.elem_count != j->mesh.vertex_count)
        return tpk_diag_fail(j->diag, "%s: field '%s' step %u has %llu values for %llu vertices", j->o->input,
                             j->color_desc.name, j->color_step, (unsigned long long)e.elem_count,
                             (unsigned long long)j->mesh.vertex_count);
    if (e.codec == TPK_CODEC_NONE) {
        const void *data;
        uint64_t size;
        if (tpk_view_chunk(j->file, i, &data, &size) != TPK_OK)
            return fail_file(j);
        j->colors = data;
        return 0;
    }
    if (!(j->color_owned = malloc(e.raw_size ? (size_t)e.raw_size : 1)))
        return tpk_diag_fail(j->diag, "out of memory for field '%s'", j->color_desc.name);
    if (tpk_read_chunk(j->file, i, j->color_owned, e.raw_size) != TPK_OK)
        return fail_file(j);
    j->colors = j->color_owned;
    return 0;
}

static int open_and_load(iso_job *j)
{
    char err[512] = "";
    tpk_result r = tpk_open_path(&j->file, j->o->input, NULL, err, sizeof err);
    if (r != TPK_OK)
        return tpk_diag_fail(j->diag, "%s: %s", j->o->input, err[0] ? err : tpk_result_string(r));
    if (pick_field(j, j->o->field, "field", j->o->step, &j->field_index, &j->desc))
        return -1;
    if (j->o->color_field) {
        tpk_field_desc d;
        uint32_t index;
        /* the color field at the same step, or a field of one step (static data) at step 0 */
        if (pick_field(j, j->o->color_field, "--color-field", 0, &index, &d))
            return -1;
        j->color_step = d.step_count == 1 ? 0 : j->o->step;
        if (pick_field(j, j->o->color_field, "--color-field", j->color_step, &j->color_index, &j->color_desc))
            return -1;
    }
    if (load_mesh(j) || (j->o->color_field && load_colors(j)))
        return -1;
    return 0;
}

static void warn_empty(iso_job *j, const tpk_iso_surface *s)
{
    for (int i = 0; i < s->value_count; i++) {
        if (s->value_triangles[i])
            continue;
        double v = s->values[i];
        if (v < j->desc.min_value || v > j->desc.max_value)
            tpk_diag_warn(j->diag, "%s: value %g is outside the range [%g, %g] of field '%s': its surface is empty",
                          j->o->input, v, j->desc.min_value, j->desc.max_value, j->desc.name);
        else
            tpk_diag_warn(j->diag, "%s: value %g crosses no tet of field '%s' at step %u: its surface is empty",
                          j->o->input, v, j->desc.name, j->o->step);
    }
}

int tpk_iso_run(const tpk_iso_options *o, tpk_iso_report *rep, tpk_diag *diag)
{
    memset(rep, 0, sizeof *rep);
    tpk_iso_format format = tpk_iso_format_of(o->output);
    if (!format)
        return tpk_diag_fail(diag, "%s: unknown output extension: expected .ply, .obj or .glb", o->output);
    iso_job j = {.o = o, .rep = rep, .diag = diag};
    tpk_iso_surface s;
    memset(&s, 0, sizeof s);
    double t0 = tpk_now_seconds();
    int rc = open_and_load(&j);
    double t1 = tpk_now_seconds();
    if (rc == 0) {
        tpk_iso_input in = {.vertex_count = (int64_t)j.mesh.vertex_count, .tet_count = (int64_t)j.mesh.tet_count,
                            .positions = j.mesh.positions, .tets = j.tets, .scalars = j.mesh.scalars,
                            .colors = j.colors};
        memcpy(in.origin, j.mesh.origin, sizeof in.origin);
        rc = tpk_iso_extract_from(&in, o->values, o->value_count, o->threads, o->corners, &s, diag);
    }
    double t2 = tpk_now_seconds();
    if (rc == 0) {
        warn_empty(&j, &s);
        tpk_iso_labels labels = {.field = j.desc.name, .color_field = o->color_field ? j.color_desc.name : NULL,
                                 .step = o->step};
        memcpy(labels.origin, j.mesh.origin, sizeof labels.origin);
        rc = tpk_iso_write(&s, &labels, format, o->output, diag);
    }
    if (rc == 0) {
        snprintf(rep->field, sizeof rep->field, "%s", j.desc.name);
        if (o->color_field)
            snprintf(rep->color_field, sizeof rep->color_field, "%s", j.color_desc.name);
        rep->field_min = j.desc.min_value;
        rep->field_max = j.desc.max_value;
        rep->tets = (int64_t)j.mesh.tet_count;
        rep->vertices = s.vertex_count;
        rep->triangles = s.triangle_count;
        rep->threads = tpk_thread_count(o->threads);
        rep->seconds_load = t1 - t0;
        rep->seconds_extract = t2 - t1;
        rep->seconds_write = tpk_now_seconds() - t2;
        rep->value_count = s.value_count;
        memcpy(rep->values, s.values, sizeof rep->values);
        memcpy(rep->value_triangles, s.value_triangles, sizeof rep->value_triangles);
        memcpy(rep->value_vertices, s.value_vertices, sizeof rep->value_vertices);
    }
    tpk_iso_surface_free(&s);
    free(j.tets);
    free(j.color_owned);
    tpk_close(j.file);
    return rc;
}
