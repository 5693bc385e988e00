/* Source cells -> tets (pipeline stage 1). Tetra pass through, voxels, hexahedra, wedges and pyramids
 * are split conformally (tools/convert/cell_split.c); those that split cannot take, and polyhedra, get added
 * points (tools/convert/steiner.c); other 3-D types are refused by name (tools/mesh/cell_types.c knows every VTK
 * type), and lower-dimensional cells (boundary faces, edges, points) are skipped with a warning. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cell_split.h"
#include "mesh/cell_types.h"
#include "pipeline.h"
#include "mesh/polyhedron.h"
#include "base/parallel.h"
#include "split_plain.h"
#include "steiner.h"

/* Tets one cell of this type can give (for sizing); 0 when this converter does not split the type. */
static int max_tets(int type)
{
    return type == TPK_CELL_TETRA ? 1 : tpk_split_max_tets(type);
}

/* Most tets a polyhedron gives: one per face edge (a star with every face split at its centre). */
static int64_t polyhedron_max_tets(const tpk_mesh *src, int64_t c)
{
    const int32_t *stream = src->faces + src->face_offsets[c];
    return src->face_offsets[c + 1] - src->face_offsets[c] - 1 - stream[0];
}

/* The passes over every cell and point below run on all threads, each worker over a contiguous range in
 * order, stopping at its first bad cell: the smallest of the workers' firsts is the cell the serial loop
 * stopped at, checked again on the calling thread for the message. Results do not depend on the thread
 * count. */
typedef struct cell_pass {
    const tpk_mesh *src;
    tpk_tetmesh *out;
    int64_t first_bad[TPK_MAX_THREADS];     /* INT64_MAX: none */
    int64_t first_refused[TPK_MAX_THREADS]; /* survey_range: the first cell of a type refused */
    int64_t tets[TPK_MAX_THREADS], skipped[TPK_MAX_THREADS], first_skipped[TPK_MAX_THREADS];
    int not_plain[TPK_MAX_THREADS];
    int64_t type_tets[256];                 /* survey_range's fast path: tets of a cell of this type with */
    int64_t type_nodes[256];                /* this many nodes (0: any); -1: ask cell_tets */
} cell_pass;

static int pass_threads(int64_t count, int threads)
{
    return tpk_threads_for(count, tpk_thread_count(threads), (int64_t)1 << 16);
}

static int64_t run_cell_pass(cell_pass *job, int64_t count, int threads, tpk_range_fn fn)
{
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        job->first_bad[w] = job->first_skipped[w] = job->first_refused[w] = INT64_MAX;
        job->tets[w] = job->skipped[w] = 0;
        job->not_plain[w] = 0;
    }
    tpk_parallel_for(count, threads, fn, job);
    int64_t first = INT64_MAX;
    for (int w = 0; w < threads; w++)
        first = job->first_bad[w] < first ? job->first_bad[w] : first;
    return first;
}

/* Tets cell c can give, -2 for a cell of dimension < 3 (skipped), or -1 with a message (diag may be
 * NULL) for a cell the converter refuses. */
static int64_t cell_tets(const tpk_mesh *src, int64_t c, tpk_diag *diag)
{
    const tpk_cell_type_info *kind = tpk_cell_type(src->cell_types[c]);
    int64_t nodes = src->cell_offsets[c + 1] - src->cell_offsets[c];
    if (!kind)
        return tpk_diag_fail(diag, "cell %lld has VTK cell type %d, which this converter does not "
                             "know", (long long)c, src->cell_types[c]);
    if (kind->dim < 3)
        return -2;
    if (kind->type == TPK_CELL_POLYHEDRON)
        return polyhedron_max_tets(src, c);
    if (!max_tets(kind->type))
        return tpk_diag_fail(diag, "cell %lld is a %s (VTK type %d); this converter splits tetra, "
                             "voxels, hexahedra, wedges, pyramids and polyhedra", (long long)c, kind->name,
                             kind->type);
    if (kind->nodes > 0 && nodes != kind->nodes)
        return tpk_diag_fail(diag, "cell %lld is a %s with %lld nodes; a %s has %d",
                             (long long)c, kind->name, (long long)nodes, kind->name, kind->nodes);
    return max_tets(kind->type);
}

/* A polyhedron's faces (tools/mesh/polyhedron.h): importers check them; meshes built in memory may not. */
static int check_face_stream(const tpk_mesh *src, int64_t c, tpk_diag *diag)
{
    if (!src->face_offsets || !src->faces)
        return tpk_diag_fail(diag, "cell %lld is a polyhedron, but the mesh has no faces for it", (long long)c);
    int64_t begin = src->face_offsets[c], bad_at;
    char why[200];
    if (src->face_offsets[c + 1] < begin ||
        tpk_face_stream_check(src->faces + begin, src->face_offsets[c + 1] - begin, src->point_count, &bad_at, why,
                              sizeof why))
        return tpk_diag_fail(diag, "cell %lld (a polyhedron): %s (face stream entry %lld)", (long long)c,
                             src->face_offsets[c + 1] < begin ? "face offsets decrease" : why,
                             (long long)(src->face_offsets[c + 1] < begin ? 0 : bad_at));
    return 0;
}

/* Cell c's offsets, face stream and point ids: 0, or -1 with a message (diag may be NULL). */
static int check_cell_connectivity(const tpk_mesh *src, int64_t c, tpk_diag *diag)
{
    if (src->cell_offsets[c + 1] < src->cell_offsets[c])
        return tpk_diag_fail(diag, "cell %lld: offsets decrease", (long long)c);
    if (src->cell_types[c] == TPK_CELL_POLYHEDRON && check_face_stream(src, c, diag))
        return -1;
    for (int64_t i = src->cell_offsets[c]; i < src->cell_offsets[c + 1]; i++)
        if (src->cell_conn[i] < 0 || src->cell_conn[i] >= src->point_count)
            return tpk_diag_fail(diag, "cell %lld names point %d; the mesh has %lld points",
                                 (long long)c, src->cell_conn[i], (long long)src->point_count);
    return 0;
}

/* One pass over the cells for what the split needs first, on all threads: each cell's offsets, face
 * stream and point ids checked (check_cell_connectivity), its tets counted (cell_tets, a table for the
 * usual types), and whether every cell is a tetra stored as 4 consecutive ids in cell order. A bad
 * connectivity is reported before a refused cell type, wherever the two are, as the two passes this
 * replaced did: a worker notes its first refused type and goes on checking ids until its first bad one. */
static void survey_range(void *ctx, int64_t begin, int64_t end, int w)
{
    cell_pass *job = ctx;
    const tpk_mesh *src = job->src;
    uint64_t points = (uint64_t)src->point_count;
    int not_plain = 0;
    for (int64_t c = begin; c < end; c++) {
        int type = src->cell_types[c];
        int64_t b = src->cell_offsets[c], e = src->cell_offsets[c + 1];
        int bad = e < b || type == TPK_CELL_POLYHEDRON;
        for (int64_t i = b; i < e; i++) /* a negative id is a huge unsigned one */
            bad |= (uint64_t)(int64_t)src->cell_conn[i] >= points;
        if (bad && check_cell_connectivity(src, c, NULL)) {
            job->first_bad[w] = c;
            break;
        }
        not_plain |= type != TPK_CELL_TETRA || b != 4 * c;
        if (job->first_refused[w] != INT64_MAX)
            continue; /* counted no further: the conversion stops there, unless a cell's ids are bad */
        int64_t tets = job->type_tets[type];
        if (tets >= 0 && (job->type_nodes[type] == 0 || e - b == job->type_nodes[type])) {
            job->tets[w] += tets;
            continue;
        }
        tets = cell_tets(src, c, NULL);
        if (tets == -1) {
            job->first_refused[w] = c;
        } else if (tets == -2) {
            if (job->first_skipped[w] == INT64_MAX)
                job->first_skipped[w] = c;
            job->skipped[w]++;
        } else {
            job->tets[w] += tets;
        }
    }
    job->not_plain[w] = not_plain;
}

/* Checks every cell, counts the tets (refusing unsupported 3-D cells, skipping lower-dimensional ones) and
 * says whether the cells are plain tets (*plain: 4 consecutive ids each, in cell order, as many as the
 * tets: the connectivity is then already the tet array). */
static int survey_cells(const tpk_mesh *src, int threads, int64_t *tet_count, int *plain, tpk_diag *diag)
{
    if (src->point_count > INT32_MAX)
        return tpk_diag_fail(diag, "%lld points exceed the limit of 2^31-1 per file; split the mesh "
                             "into parts", (long long)src->point_count);
    int64_t tets = 0, skipped = 0, first_skipped = -1, refused = INT64_MAX;
    cell_pass *job = malloc(sizeof *job);
    if (!job)
        return tpk_diag_fail(diag, "tetrahedralize: out of memory");
    job->src = src;
    for (int t = 0; t < 256; t++) { /* what cell_tets says of a cell of type t with the right node count */
        const tpk_cell_type_info *kind = tpk_cell_type(t);
        int ok = kind && kind->dim >= 3 && kind->type != TPK_CELL_POLYHEDRON && max_tets(kind->type);
        job->type_tets[t] = ok ? max_tets(kind->type) : -1;
        job->type_nodes[t] = ok && kind->nodes > 0 ? kind->nodes : 0;
    }
    threads = pass_threads(src->cell_count, threads);
    int64_t bad = run_cell_pass(job, src->cell_count, threads, survey_range);
    int not_plain = 0;
    for (int w = 0; w < threads; w++) {
        tets += job->tets[w];
        skipped += job->skipped[w];
        if (first_skipped < 0 && job->first_skipped[w] != INT64_MAX)
            first_skipped = job->first_skipped[w];
        refused = job->first_refused[w] < refused ? job->first_refused[w] : refused;
        not_plain |= job->not_plain[w];
    }
    free(job);
    if (bad != INT64_MAX)
        return check_cell_connectivity(src, bad, diag);
    if (refused != INT64_MAX)
        return (int)cell_tets(src, refused, diag);
    if (skipped)
        tpk_diag_warn(diag, "skipped %lld cells of dimension < 3 (the first is cell %lld, a %s)",
                      (long long)skipped, (long long)first_skipped,
                      tpk_cell_type(src->cell_types[first_skipped])->name);
    if (tets == 0)
        return tpk_diag_fail(diag, "the mesh has no volume cells (%lld cells, none 3-D)",
                             (long long)src->cell_count);
    if (tets > INT32_MAX)
        return tpk_diag_fail(diag, "%lld tets exceed the limit of 2^31-1 per file; split the mesh "
                             "into parts", (long long)tets);
    *tet_count = tets;
    *plain = !not_plain && tets == src->cell_count;
    return 0;
}

/* ---- fields ---------------------------------------------------------------------------------- */

enum { PICK_SCALAR = -1, PICK_MAG = -2 }; /* or a component index >= 0 */

typedef struct field_request {
    const tpk_src_field *field;
    int pick;
    char name[TPK_NAME_MAX];
} field_request;

static void list_fields(const tpk_mesh *src, char *text, size_t cap)
{
    size_t used = 0;
    text[0] = 0;
    for (int i = 0; i < src->field_count && used < cap; i++) {
        const tpk_src_field *f = &src->fields[i];
        int n = snprintf(text + used, cap - used, "%s%s (%s%s)", i ? ", " : "", f->name,
                         f->association == TPK_ASSOC_POINT ? "point" : "cell",
                         f->components == 1 ? "" : f->components == 3 ? ", vector" : ", tuple");
        if (n < 0)
            break;
        used += (size_t)n;
    }
    if (src->field_count == 0)
        snprintf(text, cap, "none");
}

static const tpk_src_field *find_field(const tpk_mesh *src, const char *name, size_t len)
{
    for (int i = 0; i < src->field_count; i++)
        if (strlen(src->fields[i].name) == len && !memcmp(src->fields[i].name, name, len))
            return &src->fields[i];
    return NULL;
}

/* "NAME", "NAME:mag", "NAME:x|y|z". An exact field name wins over a selector reading. */
static int parse_request(const tpk_mesh *src, const char *spec, field_request *req, tpk_diag *diag)
{
    char available[700];
    memset(req, 0, sizeof *req);
    req->pick = PICK_SCALAR;
    req->field = find_field(src, spec, strlen(spec));
    const char *colon = strrchr(spec, ':');
    const char *suffix = NULL;
    if (!req->field && colon) {
        suffix = colon + 1;
        req->field = find_field(src, spec, (size_t)(colon - spec));
        if (req->field) {
            if (!strcmp(suffix, "mag"))
                req->pick = PICK_MAG;
            else if (!strcmp(suffix, "x") || !strcmp(suffix, "y") || !strcmp(suffix, "z"))
                req->pick = suffix[0] - 'x';
            else
                return tpk_diag_fail(diag, "field '%s': unknown selector ':%s' (use :mag, :x, :y or "
                                     ":z)", spec, suffix);
        }
    }
    if (!req->field) {
        list_fields(src, available, sizeof available);
        return tpk_diag_fail(diag, "no field named '%s'; available fields: %s", spec, available);
    }
    const tpk_src_field *f = req->field;
    if (req->pick == PICK_SCALAR && f->components != 1)
        return tpk_diag_fail(diag, "field '%s' has %d components; pick one with '%s:mag', '%s:x', "
                             "'%s:y' or '%s:z'", f->name, f->components, f->name, f->name, f->name,
                             f->name);
    if (req->pick >= 0 && req->pick >= f->components)
        return tpk_diag_fail(diag, "field '%s' has %d components; '%s' is out of range", f->name,
                             f->components, spec);
    if (f->step_count < 1)
        return tpk_diag_fail(diag, "field '%s' has %d time steps", f->name, f->step_count);
    int n = req->pick == PICK_SCALAR ? snprintf(req->name, sizeof req->name, "%s", f->name)
                                     : snprintf(req->name, sizeof req->name, "%s_%s", f->name, suffix);
    if (n < 0 || (size_t)n >= sizeof req->name)
        return tpk_diag_fail(diag, "field name '%s_%s' is longer than %d bytes", f->name,
                             suffix ? suffix : "", TPK_NAME_MAX - 1);
    return 0;
}

static int build_requests(const tpk_mesh *src, const char *const *names, int name_count, int flags,
                          field_request **out, int *out_count, tpk_diag *diag)
{
    int cap = names ? name_count : src->field_count;
    field_request *reqs = calloc((size_t)(cap > 0 ? cap : 1), sizeof *reqs);
    int count = 0;
    if (!reqs)
        return tpk_diag_fail(diag, "out of memory");
    if (names) {
        for (int i = 0; i < name_count; i++) {
            if (parse_request(src, names[i], &reqs[count], diag)) {
                free(reqs);
                return -1;
            }
            int duplicate = 0;
            for (int j = 0; j < count; j++)
                duplicate |= !strcmp(reqs[j].name, reqs[count].name);
            if (duplicate)
                tpk_diag_warn(diag, "field '%s' requested twice; kept once", reqs[count].name);
            else
                count++;
        }
    } else {
        for (int i = 0; i < src->field_count; i++) {
            const tpk_src_field *f = &src->fields[i];
            int is_point = f->association == TPK_ASSOC_POINT;
            if (!is_point && !(flags & TPK_TETRA_CELL_TO_POINT))
                continue;
            if (f->components != 1 || f->step_count < 1) {
                tpk_diag_warn(diag, "%s field '%s' has %d components and is skipped; select it as "
                              "'%s:mag' or '%s:x' to keep it", is_point ? "point" : "cell", f->name,
                              f->components, f->name, f->name);
                continue;
            }
            reqs[count].field = f;
            reqs[count].pick = PICK_SCALAR;
            snprintf(reqs[count].name, sizeof reqs[count].name, "%s", f->name);
            count++;
        }
    }
    *out = reqs;
    *out_count = count;
    return 0;
}

static float pick_value(const float *v, int components, int pick)
{
    if (pick == PICK_SCALAR)
        return v[0];
    if (pick >= 0)
        return v[pick];
    double sum = 0;
    for (int c = 0; c < components; c++)
        sum += (double)v[c] * v[c];
    return (float)sqrt(sum);
}

/* Point fields keep their vertex order (vertex_source is the identity); cell fields go per tet. */
/* A point field's value at added point i: the mean over the corners it is the mean of, its cell's or its
 * face's (exact for a linear field, and for the trilinear interpolant at a hexahedron's centre). */
static float added_value(const tpk_added_points *added, const float *step, const field_request *req, int64_t i)
{
    const tpk_src_field *f = req->field;
    int64_t begin = added->corner_start[i], corners = added->corner_start[i + 1] - begin;
    double sum = 0;
    for (int64_t k = 0; k < corners; k++)
        sum += pick_value(step + (int64_t)added->corners[begin + k] * f->components, f->components, req->pick);
    return (float)(sum / (double)corners);
}

/* A cell field at added point i: its cell's value, or the mean over the cells on its face. */
static float added_cell_value(const tpk_added_points *added, const float *step, const field_request *req, int64_t i)
{
    const tpk_src_field *f = req->field;
    double sum = 0;
    int count = 0;
    for (int k = 0; k < 2; k++) {
        int32_t c = added->cells[2 * i + k];
        if (c >= 0) {
            sum += pick_value(step + (int64_t)c * f->components, f->components, req->pick);
            count++;
        }
    }
    return (float)(sum / count); /* every added point serves at least the cell that made it */
}

/* A cell field averaged to the output vertices: the mean over the kept volume cells around each source
 * point (NaN for points in none), at an added cell centre its own cell's value, at a face centre the mean
 * over the cells on the face. */
static int cell_to_point(const tpk_mesh *src, const field_request *req, const tpk_added_points *added, int threads,
                         tpk_tetmesh *out)
{
    const tpk_src_field *f = req->field;
    int64_t nv = out->vertex_count, np = src->point_count;
    (void)threads; /* a scatter into the points: serial, so the sums add in one order */
    float *values = malloc(sizeof *values * (size_t)(nv * f->step_count > 0 ? nv * f->step_count : 1));
    double *sum = malloc(sizeof *sum * (size_t)(np ? np : 1));
    int32_t *count = malloc(sizeof *count * (size_t)(np ? np : 1));
    uint8_t *kept = calloc((size_t)(src->cell_count ? src->cell_count : 1), 1);
    if (!values || !sum || !count || !kept) {
        free(values), free(sum), free(count), free(kept);
        return -1;
    }
    for (int64_t t = 0; t < out->tet_count; t++) /* a NULL map: the identity (TPK_TETRA_IDENTITY_SOURCE_NULL) */
        kept[out->tet_source ? out->tet_source[t] : t] = 1;
    /* All-tet input through tpk_tetrahedralize_consume: the connectivity was taken over as the tet array,
     * unchanged so far (cell c is tet c, 4 ids each, before orientation). */
    const int32_t *conn = src->cell_conn ? src->cell_conn : out->tets;
    for (int s = 0; s < f->step_count; s++) {
        const float *step = f->values + (size_t)s * (size_t)src->cell_count * (size_t)f->components;
        memset(sum, 0, sizeof *sum * (size_t)np);
        memset(count, 0, sizeof *count * (size_t)np);
        for (int64_t c = 0; c < src->cell_count; c++) {
            if (!kept[c])
                continue;
            double value = pick_value(step + c * f->components, f->components, req->pick);
            for (int64_t k = src->cell_offsets[c]; k < src->cell_offsets[c + 1]; k++) {
                sum[conn[k]] += value;
                count[conn[k]]++;
            }
        }
        float *dst = values + (size_t)s * (size_t)nv;
        for (int64_t i = 0; i < nv; i++) {
            int32_t from = out->vertex_source[i];
            if (from < 0)
                dst[i] = added_cell_value(added, step, req, i - np);
            else
                dst[i] = count[from] ? (float)(sum[from] / count[from]) : NAN;
        }
    }
    free(sum), free(count), free(kept);
    tpk_src_field *field = &out->fields[out->field_count++];
    memset(field, 0, sizeof *field);
    memcpy(field->name, req->name, sizeof field->name);
    field->association = TPK_ASSOC_POINT;
    field->components = 1;
    field->step_count = f->step_count;
    field->values = values;
    return 0;
}

typedef struct copy_job {
    const tpk_mesh *src;
    const field_request *req;
    const tpk_added_points *added;
    const tpk_tetmesh *out;
    const float *step;
    float *dst;
} copy_job;

static void copy_range(void *ctx, int64_t begin, int64_t end, int w)
{
    const copy_job *job = ctx;
    const tpk_src_field *f = job->req->field;
    int per_point = f->association == TPK_ASSOC_POINT;
    (void)w;
    for (int64_t i = begin; i < end; i++) {
        int64_t from = per_point ? job->out->vertex_source[i] : job->out->tet_source ? job->out->tet_source[i] : i;
        job->dst[i] = from < 0 ? added_value(job->added, job->step, job->req, i - job->src->point_count)
                               : pick_value(job->step + from * f->components, f->components, job->req->pick);
    }
}

static int copy_field(const tpk_mesh *src, const field_request *req, const tpk_added_points *added, int threads,
                      tpk_tetmesh *out)
{
    const tpk_src_field *f = req->field;
    int per_point = f->association == TPK_ASSOC_POINT;
    int64_t n = per_point ? out->vertex_count : out->tet_count;
    int64_t src_n = per_point ? src->point_count : src->cell_count;
    float *values = malloc(sizeof *values * (size_t)(n * f->step_count > 0 ? n * f->step_count : 1));
    if (!values)
        return -1;
    for (int s = 0; s < f->step_count; s++) {
        copy_job job = {src, req, added, out, f->values + (size_t)s * (size_t)src_n * (size_t)f->components,
                        values + (size_t)s * (size_t)n};
        tpk_parallel_for(n, pass_threads(n, threads), copy_range, &job);
    }
    tpk_src_field *dst = &out->fields[out->field_count++];
    memset(dst, 0, sizeof *dst);
    memcpy(dst->name, req->name, sizeof dst->name);
    dst->association = per_point ? TPK_ASSOC_POINT : TPK_ASSOC_TET;
    dst->components = 1;
    dst->step_count = f->step_count;
    dst->values = values;
    return 0;
}

/* ---- the stage ------------------------------------------------------------------------------- */

/* Only with TPK_TETRA_REFUSE_MIRRORED (--strict-orientation): a cell whose every tet is negative is
 * listed in the mirrored node order, a labeling that turning over fixes without changing the geometry,
 * so that is the default. The refusal is for who wants to catch a writer's or importer's node-order bug
 * (docs/ARCHITECTURE.md §7); the message says whether the whole file or a few cells are mirrored. */
static int refuse_mirrored(const tpk_mesh *src, int64_t first, const tpk_tetmesh *out, tpk_diag *diag)
{
    int64_t begin = src->cell_offsets[first], nodes = src->cell_offsets[first + 1] - begin;
    int64_t split = out->steiner_cells;
    for (int k = 2; k <= 6; k++)
        split += out->cells_into[k];
    char where[700];
    int used = snprintf(where, sizeof where, "cell %lld (a %s) is mirrored (its node order is the mirror image of "
                        "VTK's: every tet of its split is inverted)", (long long)first,
                        tpk_cell_type(src->cell_types[first])->name);
    for (int64_t k = 0; k < nodes && used > 0 && (size_t)used < sizeof where; k++) {
        const double *p = out->points + 3 * (int64_t)src->cell_conn[begin + k]; /* src's may be taken */
        used += snprintf(where + used, sizeof where - (size_t)used, "%s %d (%.9g, %.9g, %.9g)", k ? "," : ": points",
                         src->cell_conn[begin + k], p[0], p[1], p[2]);
    }
    if (out->mirrored_cells == split)
        return tpk_diag_fail(diag, "%s; so are all %lld split cells: the file lists their nodes in the mirrored "
                             "(left-handed) order; without --strict-orientation they are turned over", where, (long long)split);
    return tpk_diag_fail(diag, "%s; %lld of %lld split cells are mirrored; without --strict-orientation they "
                         "are turned over", where,
                         (long long)out->mirrored_cells, (long long)split);
}

/* Plain split of every hexahedron, wedge and pyramid into the tet array (sized by survey_cells), on all
 * cores (split_plain.c); cells it refuses, and polyhedra, go to tools/convert/steiner.c, which appends
 * theirs and may take back the plain split of a cell next to a face it puts a point on. Returns 0, -1
 * when out of memory, or -2 with a message for a cell that cannot be split. */
static int split_cells(const tpk_mesh *src, int flags, int threads, const tpk_tetra_progress *progress,
                       int64_t *tet_capacity, tpk_added_points *added, tpk_tetmesh *out, tpk_diag *diag)
{
    tpk_plain_split plain;
    if (tpk_split_plain(src, out->points, threads, progress, out->tets, out->tet_source, &plain))
        return -1;
    out->tet_count = plain.tet_count;
    /* tpk_split_cell checks each tet's sign exactly and keeps a cell only when all are strictly positive
     * (after turning a mirrored cell over); tetra cells are copied unchecked, and the Steiner stage
     * builds its own. On the file grid, the stored frame is an exact translation, so the signs hold. */
    out->positive_known = out->on_grid && plain.hard_count == 0 && plain.cells_into[1] == 0;
    for (int k = 0; k < 7; k++)
        out->cells_into[k] += plain.cells_into[k];
    out->flat_tets += plain.flat_tets;
    if (plain.mirrored_cells) {
        out->mirrored_cells = plain.mirrored_cells;
        out->first_mirrored_cell = plain.first_mirrored_cell;
    }
    int rc = plain.hard_count ? tpk_steiner_stage(src, plain.hard, plain.hard_count, flags, tet_capacity, out, added,
                                                  diag)
                              : 0;
    free(plain.hard);
    return rc;
}

/* Identity maps (vertex_source, tet_source) filled on all threads. */
static void identity_range(void *ctx, int64_t begin, int64_t end, int w)
{
    int32_t *map = ctx;
    (void)w;
    for (int64_t i = begin; i < end; i++)
        map[i] = (int32_t)i;
}

static void fill_identity(int32_t *map, int64_t count, int threads)
{
    tpk_parallel_for(count, pass_threads(count, threads), identity_range, map);
}

typedef struct snap_job {
    double *points;
    const double *origin;
} snap_job;

static void snap_range(void *ctx, int64_t begin, int64_t end, int w)
{
    const snap_job *job = ctx;
    (void)w;
    for (int64_t v = begin; v < end; v++)
        for (int k = 0; k < 3; k++) {
            double rel = (double)(float)(job->points[3 * v + k] - job->origin[k]);
            if (isfinite(rel))
                job->points[3 * v + k] = job->origin[k] + rel;
        }
}

/* TPK_TETRA_FILE_GRID: every point moved onto the float32 grid relative to the file's origin
 * (tpk_points_origin), as the file will store it; in world coordinates still (grid_origin + a float32
 * value, exact in double). A coordinate float32 cannot hold is left as it is, for the converter to
 * refuse by name before writing (TPK-M11). */
static void snap_to_file_grid(const tpk_mesh *src, int threads, tpk_tetmesh *out)
{
    if (src->has_grid_origin) /* a piece of a larger mesh: the whole's grid */
        memcpy(out->grid_origin, src->grid_origin, sizeof out->grid_origin);
    else
        tpk_points_origin_threads(out->points, out->vertex_count, threads, out->grid_origin);
    snap_job job = {out->points, out->grid_origin};
    tpk_parallel_for(out->vertex_count, pass_threads(out->vertex_count, threads), snap_range, &job);
    out->on_grid = 1;
}

/* Points and tets: copied from src, or taken over from `donor` (== src) when it is given, which saves a
 * copy and the memory of a second mesh in the converter; with plain_cells (survey_cells), the connectivity
 * is the tet array. */
static int take_geometry(const tpk_mesh *src, tpk_mesh *donor, int64_t tet_capacity, int plain_cells, int flags,
                         int threads, const tpk_tetra_progress *progress, tpk_added_points *added,
                         tpk_tetmesh *out, tpk_diag *diag)
{
    size_t nv = (size_t)(out->vertex_count ? out->vertex_count : 1);
    int plain = donor && plain_cells;
    if (donor && donor->points) {
        out->points = donor->points;
        donor->points = NULL;
    } else {
        out->points = malloc(sizeof *out->points * 3 * nv);
        if (!out->points)
            return -1;
        memcpy(out->points, src->points, sizeof *out->points * 3 * (size_t)out->vertex_count);
    }
    if (flags & TPK_TETRA_FILE_GRID)
        snap_to_file_grid(src, threads, out);
    if (plain) {
        out->tets = donor->cell_conn;
        donor->cell_conn = NULL;
        if (!(flags & TPK_TETRA_IDENTITY_SOURCE_NULL)) {
            out->tet_source = tpk_alloc_large(sizeof *out->tet_source * (size_t)tet_capacity);
            if (!out->tet_source)
                return -1;
            fill_identity(out->tet_source, tet_capacity, threads);
        }
        out->tet_count = tet_capacity;
        out->cells_into[1] = tet_capacity;
        return 0;
    }
    out->tets = tpk_alloc_large(sizeof *out->tets * 4 * (size_t)tet_capacity);
    out->tet_source = tpk_alloc_large(sizeof *out->tet_source * (size_t)tet_capacity);
    if (!out->tets || !out->tet_source)
        return -1;
    return split_cells(src, flags, threads, progress, &tet_capacity, added, out, diag);
}

static int tetrahedralize(const tpk_mesh *src, tpk_mesh *donor, const char *const *field_names,
                          int field_name_count, int flags, int threads, const tpk_tetra_progress *progress, tpk_tetmesh *out,
                          tpk_diag *diag)
{
    field_request *reqs = NULL;
    int req_count = 0;
    int64_t tet_capacity = 0;
    int plain = 0;
    tpk_added_points added; /* what each added point is the mean of */
    memset(out, 0, sizeof *out);
    memset(&added, 0, sizeof added);
    if (!src || (src->cell_count > 0 && (!src->cell_types || !src->cell_offsets || !src->cell_conn)) ||
        (src->point_count > 0 && !src->points) || src->cell_count > INT32_MAX)
        return tpk_diag_fail(diag, "tetrahedralize: invalid source mesh");
    if (survey_cells(src, threads, &tet_capacity, &plain, diag) ||
        build_requests(src, field_names, field_name_count, flags, &reqs, &req_count, diag))
        return -1;

    out->vertex_count = src->point_count;
    out->vertex_source = malloc(sizeof *out->vertex_source * (size_t)(out->vertex_count ? out->vertex_count : 1));
    out->fields = calloc((size_t)(req_count ? req_count : 1), sizeof *out->fields);
    if (!out->vertex_source || !out->fields)
        goto out_of_memory;
    fill_identity(out->vertex_source, out->vertex_count, threads);

    out->step_count = src->step_count > 0 ? src->step_count : 1;
    if (src->times && src->step_count > 0) {
        out->times = malloc(sizeof *out->times * (size_t)src->step_count);
        if (!out->times)
            goto out_of_memory;
        memcpy(out->times, src->times, sizeof *out->times * (size_t)src->step_count);
    }
    /* Geometry last: it may take src's points and (all-tet input) connectivity; after it, only the
     * field copy reads src (cell_to_point uses the taken-over connectivity as out->tets). */
    int geometry = take_geometry(src, donor, tet_capacity, plain, flags, threads, progress, &added, out, diag);
    if (geometry == 0 && out->mirrored_cells > 0 && (flags & TPK_TETRA_REFUSE_MIRRORED))
        geometry = refuse_mirrored(src, out->first_mirrored_cell, out, diag) ? -2 : 0;
    if (geometry == -2) {
        tpk_added_points_free(&added);
        free(reqs);
        tpk_tetmesh_free(out);
        return -1;
    }
    if (geometry)
        goto out_of_memory;
    if (out->tet_count == 0) {
        tpk_added_points_free(&added);
        free(reqs);
        tpk_tetmesh_free(out);
        return tpk_diag_fail(diag, "all %lld volume cells were left out as bad cells", (long long)src->cell_count);
    }
    for (int i = 0; i < req_count; i++) {
        int averaged = reqs[i].field->association != TPK_ASSOC_POINT && (flags & TPK_TETRA_CELL_TO_POINT);
        if ((averaged ? cell_to_point : copy_field)(src, &reqs[i], &added, threads, out))
            goto out_of_memory;
    }
    tpk_added_points_free(&added);
    free(reqs);
    return 0;

out_of_memory:
    tpk_added_points_free(&added);
    free(reqs);
    tpk_tetmesh_free(out);
    return tpk_diag_fail(diag, "tetrahedralize: out of memory (%lld points, %lld tets)",
                         (long long)src->point_count, (long long)tet_capacity);
}

int tpk_tetrahedralize(const tpk_mesh *src, const char *const *field_names, int field_name_count, int flags,
                       tpk_tetmesh *out, tpk_diag *diag)
{
    return tetrahedralize(src, NULL, field_names, field_name_count, flags, 0, NULL, out, diag);
}

int tpk_tetrahedralize_consume(tpk_mesh *src, const char *const *field_names, int field_name_count, int flags,
                               tpk_tetmesh *out, tpk_diag *diag)
{
    return tetrahedralize(src, src, field_names, field_name_count, flags, 0, NULL, out, diag);
}

int tpk_tetrahedralize_watched(tpk_mesh *src, const char *const *field_names, int field_name_count, int flags,
                               int threads, const tpk_tetra_progress *progress, tpk_tetmesh *out, tpk_diag *diag)
{
    return tetrahedralize(src, src, field_names, field_name_count, flags, threads, progress, out, diag);
}
