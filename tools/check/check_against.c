/* check --against (check_against.h): sample each source cell through its own map, find the converted tet
 * holding the point (first among the tets TMAP gives the cell, else through a grid of tet boxes), and
 * compare the fields there. */
#include "check_against.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "import/importers.h"
#include "mesh/cell_map.h"
#include "mesh/cell_types.h"
#include "tetpack.h"

typedef struct against {
    tpk_file *file;
    tpk_file_info info;
    const float *positions;
    tpk_layout layout;   /* one the file has */
    int32_t *tets;
    int32_t *tmap;
    int64_t *cell_start; /* tets of source cell c: by_cell[cell_start[c] .. [c+1]) */
    int32_t *by_cell;
    /* the grid of tet boxes */
    double lo[3], step[3];
    int dim[3];
    int64_t *bin_start;
    int32_t *bin_tets;
} against;

static void vertex(const against *a, int32_t v, double x[3])
{
    for (int k = 0; k < 3; k++)
        x[k] = a->info.origin[k] + a->positions[3 * (int64_t)v + k];
}

static double det3(const double m[3][3])
{
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/* Barycentric coordinates of x in tet t; returns the smallest (>= 0 inside). */
static double barycentric(const against *a, int64_t t, const double x[3], double lambda[4])
{
    double p[4][3];
    for (int i = 0; i < 4; i++)
        vertex(a, a->tets[4 * t + i], p[i]);
    double m[3][3], b[3];
    for (int k = 0; k < 3; k++) {
        m[k][0] = p[1][k] - p[0][k], m[k][1] = p[2][k] - p[0][k], m[k][2] = p[3][k] - p[0][k];
        b[k] = x[k] - p[0][k];
    }
    double det = det3(m);
    if (det == 0)
        return -1;
    for (int c = 0; c < 3; c++) { /* Cramer: column c replaced by b */
        double q[3][3];
        memcpy(q, m, sizeof q);
        for (int k = 0; k < 3; k++)
            q[k][c] = b[k];
        lambda[c + 1] = det3(q) / det;
    }
    lambda[0] = 1 - lambda[1] - lambda[2] - lambda[3];
    double least = lambda[0];
    for (int i = 1; i < 4; i++)
        least = lambda[i] < least ? lambda[i] : least;
    return least;
}

static int bin_of(const against *a, const double x[3], int axis)
{
    int i = (int)((x[axis] - a->lo[axis]) / a->step[axis]);
    return i < 0 ? 0 : i >= a->dim[axis] ? a->dim[axis] - 1 : i;
}

/* Tets into the bins their boxes overlap (two passes: counts, then ids). */
static int build_grid(against *a)
{
    int64_t n = (int64_t)a->info.tet_count;
    int side = (int)cbrt((double)n / 2) + 1;
    for (int k = 0; k < 3; k++) {
        a->lo[k] = a->info.bounds_min[k];
        a->dim[k] = side;
        a->step[k] = (a->info.bounds_max[k] - a->info.bounds_min[k]) / side;
        if (!(a->step[k] > 0))
            a->step[k] = 1;
    }
    int64_t bins = (int64_t)side * side * side;
    a->bin_start = calloc((size_t)bins + 1, sizeof *a->bin_start);
    if (!a->bin_start)
        return -1;
    for (int pass = 0; pass < 2; pass++) {
        for (int64_t t = 0; t < n; t++) {
            int lo[3], hi[3];
            for (int k = 0; k < 3; k++)
                lo[k] = a->dim[k], hi[k] = -1;
            for (int i = 0; i < 4; i++) {
                double x[3];
                vertex(a, a->tets[4 * t + i], x);
                for (int k = 0; k < 3; k++) {
                    int b = bin_of(a, x, k);
                    lo[k] = b < lo[k] ? b : lo[k], hi[k] = b > hi[k] ? b : hi[k];
                }
            }
            for (int z = lo[2]; z <= hi[2]; z++)
                for (int y = lo[1]; y <= hi[1]; y++)
                    for (int x = lo[0]; x <= hi[0]; x++) {
                        int64_t b = ((int64_t)z * side + y) * side + x;
                        if (pass == 0)
                            a->bin_start[b + 1]++;
                        else
                            a->bin_tets[a->bin_start[b]++] = (int32_t)t;
                    }
        }
        if (pass == 0) {
            for (int64_t b = 0; b < bins; b++)
                a->bin_start[b + 1] += a->bin_start[b];
            if (!(a->bin_tets = malloc(sizeof *a->bin_tets * (size_t)(a->bin_start[bins] ? a->bin_start[bins] : 1))))
                return -1;
        } else { /* the fill moved each start to the next bin's: move them back */
            for (int64_t b = bins; b > 0; b--)
                a->bin_start[b] = a->bin_start[b - 1];
            a->bin_start[0] = 0;
        }
    }
    return 0;
}

/* The tet holding x (cell c's tets first), its barycentric coordinates; -1 when none does. */
static int64_t locate(const against *a, int64_t c, const double x[3], double lambda[4])
{
    const double tol = -1e-9;
    int64_t best = -1;
    double best_least = -INFINITY, l[4];
    for (int64_t i = c >= 0 ? a->cell_start[c] : 0; c >= 0 && i < a->cell_start[c + 1]; i++) {
        double least = barycentric(a, a->by_cell[i], x, l);
        if (least > best_least)
            best_least = least, best = a->by_cell[i], memcpy(lambda, l, sizeof l);
    }
    if (best >= 0 && best_least >= tol)
        return best;
    int64_t b = ((int64_t)bin_of(a, x, 2) * a->dim[1] + bin_of(a, x, 1)) * a->dim[0] + bin_of(a, x, 0);
    for (int64_t i = a->bin_start[b]; i < a->bin_start[b + 1]; i++) {
        double least = barycentric(a, a->bin_tets[i], x, l);
        if (least >= tol) {
            memcpy(lambda, l, sizeof l);
            return a->bin_tets[i];
        }
    }
    return -1;
}

/* Parametric sample points of a shape: the cell-centred lattice of `k` per axis, those inside it. */
static int samples_of(int linear, int k, double (*r)[3], int cap)
{
    int n = 0;
    for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++)
            for (int l = 0; l < k; l++) {
                double p[3] = {(i + 0.5) / k, (j + 0.5) / k, (l + 0.5) / k}, half = 0.5 * (1 - p[2]);
                int inside = linear == 12   ? 1
                             : linear == 10 ? p[0] + p[1] + p[2] < 1
                             : linear == 13 ? p[0] + p[1] < 1
                                            : fabs(p[0] - 0.5) < half && fabs(p[1] - 0.5) < half; /* pyramid */
                if (inside && n < cap)
                    memcpy(r[n++], p, sizeof p);
            }
    return n;
}

/* The META bound, if the converter recorded one ("max_error": a fraction of each field's range), and the
 * fields it holds for ("max_error_fields", the text of its list, malloc'ed; NULL: every field). */
static char *read_bound(against *a, tpk_against_report *out)
{
    uint64_t i;
    tpk_dir_entry e;
    if (tpk_find_chunk(a->file, TPK_TAG_META, 0, 0, &i) != TPK_OK || tpk_get_chunk(a->file, i, &e) != TPK_OK ||
        e.raw_size > (1u << 24))
        return NULL;
    char *text = malloc(e.raw_size + 1), *list = NULL; /* read, not viewed: META may be compressed (--zstd) */
    if (!text || tpk_read_chunk(a->file, i, text, e.raw_size) != TPK_OK) {
        free(text);
        return NULL;
    }
    text[e.raw_size] = 0;
    const char *at = strstr(text, "\"max_error\":"), *fields = strstr(text, "\"max_error_fields\":[");
    if (at && sscanf(at + 12, "%lf", &out->bound) == 1)
        out->has_bound = 1;
    const char *end = fields ? strchr(fields, ']') : NULL;
    if (end && (list = malloc((size_t)(end - fields) + 1))) {
        memcpy(list, fields, (size_t)(end - fields));
        list[end - fields] = 0;
    }
    free(text);
    return list;
}

/* Is field `name` held to the bound: every field without a list, else those it names. */
static int bounded(const char *list, const char *name)
{
    if (!list)
        return 1;
    size_t n = strlen(name);
    for (const char *at = strchr(list, '['); at && (at = strchr(at, '"'));) {
        const char *close = strchr(at + 1, '"');
        if (!close)
            return 0;
        if ((size_t)(close - at - 1) == n && !strncmp(at + 1, name, n))
            return 1;
        at = close + 1;
    }
    return 0;
}

static int load_file(against *a, const char *path, tpk_diag *diag)
{
    char err[512] = "";
    if (tpk_open_path(&a->file, path, NULL, err, sizeof err) != TPK_OK)
        return tpk_diag_fail(diag, "%s: %s", path, err);
    tpk_get_info(a->file, &a->info);
    tpk_mesh_arrays arrays;
    const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    tpk_result rc = TPK_ERR_NOT_FOUND;
    for (int i = 0; i < 3 && rc != TPK_OK; i++)
        rc = tpk_load_arrays(a->file, a->layout = layouts[i], NULL, 0, &arrays);
    if (rc != TPK_OK)
        return tpk_diag_fail(diag, "%s: %s", path, tpk_error_text(a->file));
    a->positions = arrays.positions;
    size_t n = (size_t)(a->info.tet_count ? a->info.tet_count : 1);
    a->tets = malloc(sizeof *a->tets * 4 * n);
    a->tmap = malloc(sizeof *a->tmap * n);
    uint64_t i;
    if (!a->tets || !a->tmap)
        return tpk_diag_fail(diag, "out of memory for %llu tets", (unsigned long long)a->info.tet_count);
    if (tpk_recover_tets_threads(&arrays, a->tets, tpk_thread_count(0)) != TPK_OK)
        return tpk_diag_fail(diag, "%s: cannot recover its tets: %s", path, tpk_error_text(a->file));
    if (tpk_find_chunk(a->file, TPK_TAG_TMAP, 0, 0, &i) != TPK_OK ||
        tpk_read_chunk(a->file, i, a->tmap, sizeof *a->tmap * a->info.tet_count) != TPK_OK)
        return tpk_diag_fail(diag, "%s: no TMAP chunk (tets to source cells), which --against needs", path);
    return 0;
}

/* Tets by source cell (TMAP values outside 0..cells are left out). */
static int group_by_cell(against *a, int64_t cells)
{
    a->cell_start = calloc((size_t)cells + 2, sizeof *a->cell_start);
    a->by_cell = malloc(sizeof *a->by_cell * (size_t)(a->info.tet_count ? a->info.tet_count : 1));
    if (!a->cell_start || !a->by_cell)
        return -1;
    for (uint64_t t = 0; t < a->info.tet_count; t++)
        if (a->tmap[t] >= 0 && a->tmap[t] < cells)
            a->cell_start[a->tmap[t] + 2]++;
    for (int64_t c = 0; c < cells; c++)
        a->cell_start[c + 2] += a->cell_start[c + 1];
    for (uint64_t t = 0; t < a->info.tet_count; t++)
        if (a->tmap[t] >= 0 && a->tmap[t] < cells)
            a->by_cell[a->cell_start[a->tmap[t] + 1]++] = (int32_t)t;
    return 0;
}

/* The fields both have: source point field of one component, file point field of the same name. */
static void pick_fields(against *a, const tpk_mesh *src, const tpk_src_field **pairs, tpk_against_report *out)
{
    for (int i = 0; i < src->field_count && out->field_count < TPK_AGAINST_MAX_FIELDS; i++) {
        const tpk_src_field *f = &src->fields[i];
        uint32_t k;
        tpk_field_desc d;
        if (f->association != TPK_ASSOC_POINT || f->components != 1 || tpk_find_field(a->file, f->name, &k) != TPK_OK ||
            tpk_get_field(a->file, k, &d) != TPK_OK || d.association != TPK_ASSOC_POINT)
            continue;
        tpk_against_field *o = &out->fields[out->field_count];
        snprintf(o->name, sizeof o->name, "%s", f->name);
        o->steps = (int)d.step_count < f->step_count ? (int)d.step_count : f->step_count;
        double lo = INFINITY, hi = -INFINITY;
        for (int64_t v = 0; v < (int64_t)o->steps * src->point_count; v++)
            if (isfinite(f->values[v]))
                lo = f->values[v] < lo ? f->values[v] : lo, hi = f->values[v] > hi ? f->values[v] : hi;
        o->range = hi > lo ? hi - lo : 1;
        pairs[out->field_count++] = f;
    }
}

/* Each field's values at each step compared, from the file (views or handle-owned: loaded once). */
static void compare(against *a, const tpk_mesh *src, const tpk_src_field *const *pairs, const float *const *values,
                    tpk_against_report *out, int per_axis, double *sum_sq)
{
    double r[512][3], w[TPK_CELL_MAP_MAX_NODES], lambda[4];
    int32_t nodes[TPK_CELL_MAP_MAX_NODES];
    for (int64_t c = 0; c < src->cell_count; c++) {
        /* the cell's own type as convert --max-error maps it (voxels, Lagrange cells of order 2 included) */
        const int source = src->cell_types[c];
        int type = tpk_cell_map_source_type(source, src->cell_offsets[c + 1] - src->cell_offsets[c]);
        int n = type ? tpk_cell_map_nodes(type) : 0;
        if (!n) {
            out->cells_skipped += tpk_cell_type(source) && tpk_cell_type(source)->dim == 3;
            continue;
        }
        for (int k = 0; k < n; k++)
            nodes[k] = src->cell_conn[src->cell_offsets[c] + tpk_cell_map_source_node(source, k)];
        out->cells++;
        int linear = source == TPK_CELL_VOXEL ? TPK_CELL_HEXAHEDRON : tpk_cell_type(source)->linear_type;
        int ns = samples_of(linear, per_axis, r, 512);
        for (int s = 0; s < ns; s++) {
            double x[3];
            tpk_cell_map_point(type, nodes, src->points, r[s], x);
            tpk_cell_map_weights(type, r[s], w);
            out->samples++;
            int64_t t = locate(a, c, x, lambda);
            if (t < 0) {
                out->outside++;
                continue;
            }
            for (int f = 0, at = 0; f < out->field_count; at += out->fields[f].steps, f++)
                for (int step = 0; step < out->fields[f].steps; step++) {
                    const float *src_step = pairs[f]->values + (int64_t)step * src->point_count;
                    const float *file = values[at + step];
                    double want = 0, got = 0;
                    for (int k = 0; k < n; k++)
                        want += w[k] * src_step[nodes[k]];
                    for (int i = 0; i < 4; i++)
                        got += lambda[i] * file[a->tets[4 * t + i]];
                    double e = fabs(want - got) / out->fields[f].range;
                    if (!(e <= out->fields[f].max_error))
                        out->fields[f].max_error = isnan(e) ? INFINITY : e;
                    sum_sq[f] += e * e;
                }
        }
    }
}

/* The file's values of every compared field and step, in field order (NULL when out of memory). */
static const float **load_values(against *a, tpk_against_report *out, tpk_diag *diag)
{
    int total = 0;
    for (int f = 0; f < out->field_count; f++)
        total += out->fields[f].steps;
    const float **values = calloc((size_t)(total ? total : 1), sizeof *values);
    if (!values) {
        tpk_diag_fail(diag, "out of memory");
        return NULL;
    }
    for (int f = 0, at = 0; f < out->field_count; f++)
        for (int step = 0; step < out->fields[f].steps; step++, at++) {
            tpk_mesh_arrays arrays;
            if (tpk_load_arrays(a->file, a->layout, out->fields[f].name, (uint32_t)step, &arrays) != TPK_OK) {
                tpk_diag_fail(diag, "field '%s' step %d: %s", out->fields[f].name, step, tpk_error_text(a->file));
                free(values);
                return NULL;
            }
            values[at] = arrays.scalars;
        }
    return values;
}

int tpk_check_against(const char *tpk_path, const char *source, const char *format, int per_axis,
                      tpk_against_report *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    against a;
    memset(&a, 0, sizeof a);
    tpk_mesh src;
    memset(&src, 0, sizeof src);
    const tpk_src_field *pairs[TPK_AGAINST_MAX_FIELDS];
    double sum_sq[TPK_AGAINST_MAX_FIELDS] = {0};
    char *list = NULL;
    int rc = load_file(&a, tpk_path, diag);
    if (rc == 0)
        rc = tpk_import_any_whole(source, format, NULL, 1, &src, diag);
    if (rc == 0 && (group_by_cell(&a, src.cell_count) || build_grid(&a)))
        rc = tpk_diag_fail(diag, "out of memory for the tets of %s", tpk_path);
    if (rc == 0) {
        list = read_bound(&a, out);
        pick_fields(&a, &src, pairs, out);
        const float **values = load_values(&a, out, diag);
        if (!values)
            rc = -1;
        else
            compare(&a, &src, pairs, values, out, per_axis < 1 ? 1 : per_axis > 8 ? 8 : per_axis, sum_sq);
        free(values);
        int64_t inside = out->samples - out->outside;
        for (int f = 0; f < out->field_count; f++) {
            tpk_against_field *o = &out->fields[f];
            o->rms_error = inside > 0 ? sqrt(sum_sq[f] / ((double)inside * o->steps)) : 0;
            o->bounded = out->has_bound && bounded(list, o->name);
            out->bound_exceeded |= o->bounded && o->max_error > out->bound;
        }
    }
    if (a.file)
        tpk_close(a.file);
    free(a.tets), free(a.tmap), free(a.cell_start), free(a.by_cell), free(a.bin_start), free(a.bin_tets);
    tpk_mesh_free(&src);
    free(list);
    return rc;
}
