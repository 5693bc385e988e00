/* VTKHDF importer: PointData and CellData arrays as fields, one step per Steps entry. A step's values
 * start at Steps/PointDataOffsets/NAME (CellDataOffsets) where the file has it, else where the step's
 * first partition's points (cells) start; partitions follow in order. Point values are those of the
 * first of the points merged into one; cell values those of the kept cells. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_vtkhdf_internal.h"
#include "tetpack.h"

/* Names of the links in `group` (creation order where the file tracks it, else by name). */
static int list_names(vh_reader *r, const char *group, char ***names, int64_t *count)
{
    *names = NULL;
    *count = 0;
    if (!vh_exists(r->root, group))
        return 0;
    hid_t g = H5Gopen2(r->root, group, H5P_DEFAULT);
    H5G_info_t info;
    if (g < 0 || H5Gget_info(g, &info) < 0) {
        if (g >= 0)
            H5Gclose(g);
        return vh_fail(r, "/VTKHDF/%s: expected a group, found something else", group);
    }
    *names = calloc(info.nlinks ? info.nlinks : 1, sizeof **names);
    H5_index_t order = H5Lget_name_by_idx(g, ".", H5_INDEX_CRT_ORDER, H5_ITER_INC, 0, NULL, 0, H5P_DEFAULT) >= 0
                           ? H5_INDEX_CRT_ORDER
                           : H5_INDEX_NAME;
    int rc = *names ? 0 : vh_fail(r, "out of memory");
    for (hsize_t i = 0; rc == 0 && i < info.nlinks; i++) {
        ssize_t n = H5Lget_name_by_idx(g, ".", order, H5_ITER_INC, i, NULL, 0, H5P_DEFAULT);
        char *name = n >= 0 && n < 4096 ? malloc((size_t)n + 1) : NULL;
        if (!name || H5Lget_name_by_idx(g, ".", order, H5_ITER_INC, i, name, (size_t)n + 1, H5P_DEFAULT) < 0) {
            free(name);
            rc = vh_fail(r, "/VTKHDF/%s: cannot read the name of array %llu", group, (unsigned long long)i);
            break;
        }
        (*names)[(*count)++] = name;
    }
    H5Gclose(g);
    return rc;
}

/* Where step `s`'s values of array NAME start. */
static int step_offset(vh_reader *r, const char *offsets_group, const char *name, int64_t s, int64_t fallback,
                       int64_t *at)
{
    char path[512];
    snprintf(path, sizeof path, "Steps/%s/%s", offsets_group, name);
    *at = fallback;
    if (!r->times)
        return 0;
    hid_t steps = H5Gopen2(r->root, "Steps", H5P_DEFAULT);
    int has = steps >= 0 && vh_exists(steps, offsets_group);
    if (has) {
        hid_t g = H5Gopen2(steps, offsets_group, H5P_DEFAULT);
        has = g >= 0 && vh_exists(g, name);
        if (g >= 0)
            H5Gclose(g);
    }
    if (steps >= 0)
        H5Gclose(steps);
    if (!has)
        return 0;
    int64_t rows, cols;
    if (vh_shape(r, path, &rows, &cols))
        return -1;
    if (rows < r->step_count || cols != 1)
        return vh_fail(r, "/VTKHDF/%s: expected %lld offsets (Steps' NSteps), found %lld x %lld", path,
                       (long long)r->step_count, (long long)rows, (long long)cols);
    return vh_read_rows(r, path, s, 1, 1, H5T_NATIVE_INT64, at, "the step's offset");
}

/* One array at every step into a new field of `out`. */
static int read_field(vh_reader *r, const char *group, const char *name, int cells, tpk_mesh *out)
{
    char path[512];
    if (strlen(name) > 400)
        return vh_fail(r, "/VTKHDF/%s: an array name of %zu characters", group, strlen(name));
    snprintf(path, sizeof path, "%s/%s", group, name);
    int64_t rows, comps;
    if (vh_shape(r, path, &rows, &comps))
        return -1;
    if (comps < 1 || comps > 64)
        return vh_fail(r, "/VTKHDF/%s: expected 1 to 64 components, found %lld", path, (long long)comps);
    int64_t raw = cells ? r->raw_cells : r->raw_points, tuples = cells ? out->cell_count : out->point_count;
    int64_t per_step = tuples * comps, steps = r->step_count;
    double *buf = malloc(sizeof *buf * (size_t)(raw ? raw : 1) * (size_t)comps);
    float *values = malloc(sizeof *values * (size_t)(per_step ? per_step : 1) * (size_t)steps);
    int rc = buf && values ? 0 : vh_fail(r, "/VTKHDF/%s: out of memory for %lld steps", path, (long long)steps);
    for (int64_t s = 0; rc == 0 && s < steps; s++) {
        const vh_step *st = &r->steps[s];
        int64_t fallback = cells ? r->cell_start[st->part0] : r->point_start[st->part0], first;
        char what[64];
        snprintf(what, sizeof what, "step %lld's values", (long long)s);
        rc = step_offset(r, cells ? "CellDataOffsets" : "PointDataOffsets", name, s, fallback, &first);
        if (rc == 0)
            rc = vh_read_rows(r, path, first, raw, comps, H5T_NATIVE_DOUBLE, buf, what);
        float *dst = values + s * per_step;
        if (rc == 0 && cells) {
            for (int64_t c = 0, t = 0; c < raw; c++) {
                if (!r->kept[c])
                    continue;
                for (int64_t k = 0; k < comps; k++)
                    dst[comps * t + k] = (float)buf[comps * c + k];
                t++;
            }
        } else if (rc == 0) {
            for (int64_t m = 0; m < tuples; m++)
                for (int64_t k = 0; k < comps; k++)
                    dst[comps * m + k] = (float)buf[comps * r->first_raw[m] + k];
        }
    }
    if (rc == 0 && tpk_mesh_add_field(out, name, cells ? TPK_ASSOC_TET : TPK_ASSOC_POINT, (int)comps, (int)steps, values))
        rc = vh_fail(r, "/VTKHDF/%s: out of memory", path);
    if (rc == 0)
        values = NULL;
    free(buf);
    free(values);
    return rc;
}

int vh_read_fields(vh_reader *r, tpk_mesh *out)
{
    static const char *const groups[2] = {"PointData", "CellData"};
    int rc = 0;
    for (int cells = 0; rc == 0 && cells < 2; cells++) {
        char **names;
        int64_t count;
        rc = list_names(r, groups[cells], &names, &count);
        for (int64_t i = 0; rc == 0 && i < count; i++)
            rc = read_field(r, groups[cells], names[i], cells, out);
        for (int64_t i = 0; i < count; i++)
            free(names[i]);
        free(names);
    }
    return rc;
}
