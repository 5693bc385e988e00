/* tpk_extract: read the chosen layout, field and steps of a .tpk (only those chunks), keep the tets
 * the clip box needs (extract_subset.c) and write them as a new file through base/output_file.h. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "base/parallel.h"
#include "base/output_file.h"
#include "convert/pipeline.h"
#include "render/render.h"
#include "extract_internal.h"

typedef struct extraction {
    const tpk_extract_options *o;
    tpk_extract_report *rep;
    tpk_diag *diag;
    tpk_file *parent;      /* with options->level: the file the level is in */
    tpk_file *file;
    tpk_file_info info;
    tpk_layout layout;
    int field;             /* source field number, -1 for none */
    tpk_field_desc desc;   /* its descriptor, as the output states it */
    tpk_mesh_arrays mesh;
    int32_t *tets;         /* recovered vertex quadruples of the source */
    tpk_subset sub;
    tpk_writer *writer;
    tpk_header_fields header;
} extraction;

static uint32_t layout_tag(tpk_layout layout)
{
    return layout == TPK_LAYOUT_TET16 ? TPK_TAG_TT16 : layout == TPK_LAYOUT_TET20 ? TPK_TAG_TT20 : TPK_TAG_TT32;
}

static int fail_file(extraction *x)
{
    return tpk_diag_fail(x->diag, "%s: %s", x->o->input, tpk_error_text(x->file));
}

/* The layout render would march: the asked one, else the first of Tet16, Tet20, Tet32 present. */
static int pick_layout(extraction *x)
{
    static const tpk_layout order[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    uint64_t i;
    for (int k = 0; k < 3 && !x->layout; k++)
        if ((!x->o->layout || x->o->layout == order[k]) &&
            tpk_find_chunk(x->file, layout_tag(order[k]), 0, 0, &i) == TPK_OK)
            x->layout = order[k];
    if (!x->layout)
        return tpk_diag_fail(x->diag, "%s: no Tet%d layout in the file (tetpack info lists its chunks)", x->o->input,
                             (int)x->o->layout);
    x->rep->layout = x->layout;
    return 0;
}

/* The field render would show: the named one, else the first point field, else none. */
static int pick_field(extraction *x)
{
    x->field = -1;
    uint32_t n = tpk_field_count(x->file);
    for (uint32_t i = 0; i < n && x->field < 0; i++) {
        tpk_field_desc d;
        if (tpk_get_field(x->file, i, &d) != TPK_OK)
            return fail_file(x);
        if (x->o->field ? !strcmp(d.name, x->o->field) : d.association == TPK_ASSOC_POINT)
            x->field = (int)i, x->desc = d;
    }
    if (x->o->field && x->field < 0)
        return tpk_diag_fail(x->diag, "%s: no field named '%s' (the file has %u fields; tetpack info lists them)",
                             x->o->input, x->o->field, n);
    if (x->field < 0 && x->o->step_last > 0)
        return tpk_diag_fail(x->diag, "%s: steps %d..%d asked, but the file has no point field (name a field with "
                             "--field)", x->o->input, x->o->step_first, x->o->step_last);
    if (x->field < 0)
        return 0;
    if (x->o->step_first < 0 || x->o->step_last < x->o->step_first || (uint32_t)x->o->step_last >= x->desc.step_count)
        return tpk_diag_fail(x->diag, "%s: field '%s' has steps 0..%u; steps %d..%d asked", x->o->input,
                             x->desc.name, x->desc.step_count - 1, x->o->step_first, x->o->step_last);
    snprintf(x->rep->field, sizeof x->rep->field, "%s", x->desc.name);
    x->rep->field_is_tet = x->desc.association == TPK_ASSOC_TET;
    x->rep->field_min = x->desc.min_value;
    x->rep->field_max = x->desc.max_value;
    x->rep->steps = x->o->step_last - x->o->step_first + 1;
    return 0;
}

/* Positions, the layout and the shell (tpk_load_arrays reads only these, and a point field's step), then
 * the tets' vertex quadruples. */
static int load_mesh(extraction *x)
{
    int point = x->field >= 0 && x->desc.association == TPK_ASSOC_POINT;
    if (tpk_load_arrays(x->file, x->layout, point ? x->desc.name : NULL, point ? (uint32_t)x->o->step_first : 0,
                        &x->mesh) != TPK_OK)
        return fail_file(x);
    x->rep->diagonal = tpk_positions_diagonal(&x->mesh); /* the diagonal render takes */
    x->tets = malloc(sizeof *x->tets * 4 * (size_t)(x->mesh.tet_count ? x->mesh.tet_count : 1));
    if (!x->tets)
        return tpk_diag_fail(x->diag, "out of memory for %llu tets", (unsigned long long)x->mesh.tet_count);
    if (tpk_recover_tets_threads(&x->mesh, x->tets, tpk_thread_count(x->o->threads)) != TPK_OK)
        return fail_file(x);
    return 0;
}

/* ---- writing -------------------------------------------------------------------------------------------- */

/* The codec of the source's chunk (tag, index, step) unless the options say otherwise. */
static int chunk_level(const extraction *x, uint32_t tag, uint32_t index, uint32_t step, uint8_t *codec)
{
    uint64_t i;
    tpk_dir_entry e;
    int zstd = x->o->zstd_level > 0;
    if (x->o->zstd_level < 0)
        zstd = tpk_find_chunk(x->file, tag, index, step, &i) == TPK_OK && tpk_get_chunk(x->file, i, &e) == TPK_OK &&
               e.codec == TPK_CODEC_ZSTD;
    *codec = zstd ? TPK_CODEC_ZSTD : TPK_CODEC_NONE;
    return x->o->zstd_level > 0 ? x->o->zstd_level : 0;
}

static int put(extraction *x, uint32_t tag, uint32_t src_index, uint32_t src_step, int required, tpk_elem_type type,
               uint32_t size, uint64_t count, uint32_t index, uint32_t step, const void *data)
{
    tpk_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.tag = tag;
    d.flags = required ? TPK_CHUNK_REQUIRED : 0;
    d.zstd_level = chunk_level(x, tag, src_index, src_step, &d.codec);
    d.elem_type = (uint8_t)type;
    d.elem_size = size;
    d.elem_count = count;
    d.index = index;
    d.step = step;
    if (tpk_writer_add_chunk(x->writer, &d, data) != TPK_OK)
        return tpk_diag_fail(x->diag, "%s", tpk_writer_error_text(x->writer));
    return 0;
}

static int write_geometry(extraction *x)
{
    tpk_subset *s = &x->sub;
    for (int k = 0; k < 3; k++) {
        x->header.bounds_min[k] = INFINITY;
        x->header.bounds_max[k] = -INFINITY;
    }
    for (int64_t v = 0; v < s->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            double w = x->info.origin[k] + (double)s->positions[3 * v + k];
            x->header.bounds_min[k] = w < x->header.bounds_min[k] ? w : x->header.bounds_min[k];
            x->header.bounds_max[k] = w > x->header.bounds_max[k] ? w : x->header.bounds_max[k];
        }
    int rc = put(x, TPK_TAG_POS3, 0, 0, 1, TPK_ELEM_VEC3_F32, 12, (uint64_t)s->vertex_count, 0, 0, s->positions);
    uint32_t size = (uint32_t)x->layout;
    void *records = rc == 0 ? malloc((size_t)size * (size_t)s->tet_count) : NULL;
    int64_t shell_count = tpk_count_shell_faces(s->neighbors, s->tet_count);
    tpk_shell_face *shell = rc == 0 ? malloc(sizeof *shell * (size_t)(shell_count ? shell_count : 1)) : NULL;
    if (rc == 0 && (!records || !shell))
        rc = tpk_diag_fail(x->diag, "out of memory for the records of %lld tets", (long long)s->tet_count);
    if (rc == 0) {
        if (x->layout == TPK_LAYOUT_TET16)
            tpk_build_tet16(s->tets, s->neighbors, s->tet_count, records);
        else if (x->layout == TPK_LAYOUT_TET20)
            tpk_build_tet20(s->tets, s->neighbors, s->tet_count, records);
        else
            tpk_build_tet32(s->tets, s->neighbors, s->tet_count, records);
        tpk_elem_type type = x->layout == TPK_LAYOUT_TET16 ? TPK_ELEM_TET16 : x->layout == TPK_LAYOUT_TET20
                                                                                  ? TPK_ELEM_TET20 : TPK_ELEM_TET32;
        rc = put(x, layout_tag(x->layout), 0, 0, 1, type, size, (uint64_t)s->tet_count, 0, 0, records);
    }
    if (rc == 0) {
        tpk_build_shell(s->tets, s->neighbors, s->tet_count, shell);
        rc = put(x, TPK_TAG_SHEL, 0, 0, 1, TPK_ELEM_SHELL_FACE, 16, (uint64_t)shell_count, 0, 0, shell);
    }
    free(records);
    free(shell);
    x->header.vertex_count = (uint64_t)s->vertex_count;
    x->header.tet_count = (uint64_t)s->tet_count;
    x->header.shell_face_count = (uint64_t)shell_count;
    return rc;
}

/* Source chunk (tag, index, step) decoded into memory the caller frees; count: its element count. */
static void *read_source(extraction *x, uint32_t tag, uint32_t index, uint32_t step, uint64_t *count)
{
    uint64_t i;
    tpk_dir_entry e;
    if (tpk_find_chunk(x->file, tag, index, step, &i) != TPK_OK || tpk_get_chunk(x->file, i, &e) != TPK_OK)
        return NULL;
    void *data = malloc(e.raw_size ? e.raw_size : 1);
    if (!data || tpk_read_chunk(x->file, i, data, e.raw_size) != TPK_OK) {
        free(data);
        fail_file(x);
        return NULL;
    }
    *count = e.elem_count;
    return data;
}

/* values[new] = source[old[new]], 4-byte elements (f32 or i32). */
static void gather(const void *source, const int32_t *old, int64_t n, void *values)
{
    const uint32_t *src = source;
    uint32_t *dst = values;
    for (int64_t i = 0; i < n; i++)
        dst[i] = src[old[i]];
}

static int write_field(extraction *x)
{
    if (x->field < 0)
        return 0;
    int per_tet = x->desc.association == TPK_ASSOC_TET;
    const int32_t *old = per_tet ? x->sub.tet_old : x->sub.vertex_old;
    int64_t n = per_tet ? x->sub.tet_count : x->sub.vertex_count;
    int steps = x->rep->steps;
    float *values = malloc(sizeof *values * (size_t)n * (size_t)steps);
    if (!values)
        return tpk_diag_fail(x->diag, "out of memory for %d steps of field '%s'", steps, x->desc.name);
    for (int s = 0; s < steps; s++) {
        uint64_t count;
        void *src = read_source(x, TPK_TAG_FDAT, (uint32_t)x->field, (uint32_t)(x->o->step_first + s), &count);
        if (!src) {
            free(values);
            return -1;
        }
        gather(src, old, n, values + (size_t)n * (size_t)s);
        free(src);
    }
    float lo = INFINITY, hi = -INFINITY; /* TPK-M12: the extremes of the values stored, NaN ignored */
    for (size_t i = 0; i < (size_t)n * (size_t)steps; i++)
        if (values[i] == values[i])
            lo = values[i] < lo ? values[i] : lo, hi = values[i] > hi ? values[i] : hi;
    tpk_field_desc d = x->desc;
    d.step_count = (uint32_t)steps;
    d.min_value = lo <= hi ? lo : NAN;
    d.max_value = lo <= hi ? hi : NAN;
    int rc = put(x, TPK_TAG_FDSC, 0, 0, 1, TPK_ELEM_FIELD_DESC, 128, 1, 0, 0, &d);
    for (int s = 0; rc == 0 && s < steps; s++)
        rc = put(x, TPK_TAG_FDAT, (uint32_t)x->field, (uint32_t)(x->o->step_first + s), 1, TPK_ELEM_F32, 4,
                 (uint64_t)n, 0, (uint32_t)s, values + (size_t)n * (size_t)s);
    free(values);
    return rc;
}

/* TIME (the kept steps' values, when the source has them and a field is kept), TMAP and VMAP (mapped
 * through the subset, so a pick in the small file names the same source cell and point). */
static int write_maps(extraction *x)
{
    uint64_t count = 0;
    int rc = 0;
    double *times = x->field >= 0 ? read_source(x, TPK_TAG_TIME, 0, 0, &count) : NULL;
    if (times && (uint64_t)x->o->step_last < count)
        rc = put(x, TPK_TAG_TIME, 0, 0, 0, TPK_ELEM_F64, 8, (uint64_t)x->rep->steps, 0, 0, times + x->o->step_first);
    free(times);
    const struct { uint32_t tag; const int32_t *old; int64_t n; } maps[2] = {
        {TPK_TAG_TMAP, x->sub.tet_old, x->sub.tet_count}, {TPK_TAG_VMAP, x->sub.vertex_old, x->sub.vertex_count}};
    for (int m = 0; rc == 0 && m < 2; m++) {
        int32_t *src = read_source(x, maps[m].tag, 0, 0, &count);
        int32_t *kept = src ? malloc(sizeof *kept * (size_t)(maps[m].n ? maps[m].n : 1)) : NULL;
        if (kept) {
            gather(src, maps[m].old, maps[m].n, kept);
            rc = put(x, maps[m].tag, 0, 0, 0, TPK_ELEM_I32, 4, (uint64_t)maps[m].n, 0, 0, kept);
        } else if (src) {
            rc = tpk_diag_fail(x->diag, "out of memory for a map of %lld ids", (long long)maps[m].n);
        }
        free(kept);
        free(src);
    }
    return rc;
}

static void add_numbers(cJSON *obj, const char *key, const double *v, int n)
{
    cJSON *a = cJSON_AddArrayToObject(obj, key);
    for (int k = 0; a && k < n; k++)
        cJSON_AddItemToArray(a, cJSON_CreateNumber(v[k]));
}

/* META: what was kept and from what, with the source's own META under "source_meta". */
static int write_meta(extraction *x)
{
    const tpk_extract_options *o = x->o;
    cJSON *root = cJSON_CreateObject();
    cJSON *tool = cJSON_AddObjectToObject(root, "extractor");
    cJSON_AddStringToObject(tool, "name", "tetpack");
    cJSON_AddStringToObject(tool, "version", TPK_LIBRARY_VERSION);
    cJSON_AddStringToObject(root, "command_line", o->command_line ? o->command_line : "");
    cJSON *ex = cJSON_AddObjectToObject(root, "extract");
    cJSON_AddStringToObject(ex, "input", o->input);
    cJSON_AddNumberToObject(ex, "layout", (double)x->layout);
    if (o->level > 0)
        cJSON_AddNumberToObject(ex, "level", o->level);
    if (x->field >= 0) {
        cJSON_AddStringToObject(ex, "field", x->desc.name);
        double steps[2] = {o->step_first, o->step_last};
        add_numbers(ex, "source_steps", steps, 2);
    }
    double box[6] = {o->clip_min[0], o->clip_min[1], o->clip_min[2], o->clip_max[0], o->clip_max[1], o->clip_max[2]};
    if (o->clip)
        add_numbers(ex, "clip_box", box, 6);
    cJSON *probes = o->probe_count > 0 ? cJSON_AddArrayToObject(ex, "probes") : NULL;
    for (int i = 0; probes && i < o->probe_count; i++) {
        char text[256];
        tpk_probe_format(&o->probes[i], text, sizeof text);
        cJSON_AddItemToArray(probes, cJSON_CreateString(text));
    }
    double tets[2] = {(double)x->info.tet_count, (double)x->sub.tet_count};
    add_numbers(ex, "tets", tets, 2);
    uint64_t count = 0;
    char *source_meta = read_source(x, TPK_TAG_META, 0, 0, &count);
    cJSON *parsed = source_meta ? cJSON_ParseWithLength(source_meta, (size_t)count) : NULL;
    if (parsed)
        cJSON_AddItemToObject(root, "source_meta", parsed);
    free(source_meta);
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!text)
        return tpk_diag_fail(x->diag, "out of memory for metadata");
    int rc = put(x, TPK_TAG_META, 0, 0, 0, TPK_ELEM_BYTE, 1, strlen(text), 0, 0, text);
    free(text);
    return rc;
}

static void writer_message(void *user, tpk_result code, const char *text)
{
    (void)code;
    tpk_diag_fail(user, "%s", text);
}

static int write_output(extraction *x)
{
    tpk_output out;
    if (tpk_output_open(&out, x->o->output, x->diag) != 0)
        return -1;
    tpk_write_options wopt = {.size = sizeof wopt, .message = writer_message, .message_user = x->diag};
    char err[512] = "";
    if (tpk_writer_open_fd(&x->writer, out.fd, x->o->output, &wopt, err, sizeof err) != TPK_OK) {
        tpk_output_abort(&out);
        return tpk_diag_fail(x->diag, "%s", err);
    }
    memcpy(x->header.origin, x->info.origin, sizeof x->header.origin);
    int rc = write_geometry(x);
    if (rc == 0)
        rc = write_field(x);
    if (rc == 0)
        rc = write_maps(x);
    if (rc == 0)
        rc = write_meta(x);
    if (rc != 0) {
        tpk_writer_abort(x->writer);
        tpk_output_abort(&out);
        return -1;
    }
    if (tpk_writer_finish(x->writer, &x->header) != TPK_OK) {
        tpk_output_abort(&out);
        return x->diag->message[0] ? -1 : tpk_diag_fail(x->diag, "%s: could not finish the file", x->o->output);
    }
    return tpk_output_commit(&out, x->diag);
}

static int run(extraction *x)
{
    char err[1024] = "";
    if (tpk_open_path(&x->file, x->o->input, NULL, err, sizeof err) != TPK_OK)
        return tpk_diag_fail(x->diag, "%s: %s", x->o->input, err);
    if (x->o->level > 0) { /* the level, read as the file it is */
        x->parent = x->file;
        x->file = NULL;
        if (tpk_open_level(x->parent, (uint32_t)x->o->level, NULL, &x->file, err, sizeof err) != TPK_OK)
            return tpk_diag_fail(x->diag, "%s: %s", x->o->input, err);
    }
    tpk_get_info(x->file, &x->info);
    tpk_extract_report *r = x->rep;
    r->bytes_before = x->info.file_size;
    r->vertices_before = x->info.vertex_count, r->tets_before = x->info.tet_count;
    r->shell_before = x->info.shell_face_count;
    memcpy(r->bounds_min, x->info.bounds_min, sizeof r->bounds_min);
    memcpy(r->bounds_max, x->info.bounds_max, sizeof r->bounds_max);
    if (pick_layout(x) || pick_field(x) || load_mesh(x) ||
        tpk_subset_build(&x->mesh, x->tets, x->o, &x->sub, x->diag) || write_output(x))
        return -1;
    r->vertices_after = x->header.vertex_count, r->tets_after = x->header.tet_count;
    r->shell_after = x->header.shell_face_count;
    struct stat st;
    if (stat(x->o->output, &st) == 0)
        r->bytes_after = (uint64_t)st.st_size;
    return 0;
}

int tpk_extract(const tpk_extract_options *options, tpk_extract_report *report, tpk_diag *diag)
{
    extraction x;
    memset(&x, 0, sizeof x);
    memset(report, 0, sizeof *report);
    x.o = options, x.rep = report, x.diag = diag;
    int rc = run(&x);
    tpk_subset_free(&x.sub);
    free(x.tets);
    tpk_close(x.file);
    tpk_close(x.parent);
    return rc;
}
