/* ParaView series (.pvd): an XML Collection of DataSet entries (timestep, file), one VTU per time step.
 * Every file must hold the same mesh (points and cells); the fields of the steps become fields with
 * one step per DataSet, sorted by time, and the time values are kept. */
#include <expat.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import_file.h"
#include "importers.h"
#include "tetpack_format.h"
#include "base/text_scan.h"

#define MAX_STEPS 100000

typedef struct dataset {
    double time;
    char *file;
} dataset;

typedef struct pvd_parse {
    dataset *sets;
    int count, capacity, error;
    char message[256];
} pvd_parse;

static void XMLCALL on_start(void *user, const XML_Char *name, const XML_Char **attrs)
{
    pvd_parse *p = user;
    if (p->error || strcmp(name, "DataSet") != 0)
        return;
    const char *file = NULL, *time = NULL;
    for (int i = 0; attrs[i]; i += 2) {
        if (!strcmp(attrs[i], "file"))
            file = attrs[i + 1];
        else if (!strcmp(attrs[i], "timestep"))
            time = attrs[i + 1];
    }
    if (!file) {
        p->error = 1;
        snprintf(p->message, sizeof p->message, "a DataSet without a 'file' attribute");
        return;
    }
    if (p->count == p->capacity) {
        int capacity = p->capacity ? 2 * p->capacity : 16;
        dataset *grown = capacity <= MAX_STEPS ? realloc(p->sets, sizeof *grown * (size_t)capacity) : NULL;
        if (!grown) {
            p->error = 1;
            snprintf(p->message, sizeof p->message, "more than %d DataSets, or out of memory", MAX_STEPS);
            return;
        }
        p->sets = grown;
        p->capacity = capacity;
    }
    char *end = NULL;
    double t = time ? strtod(time, &end) : (double)p->count;
    if (time && (end == time || *end)) {
        p->error = 1;
        snprintf(p->message, sizeof p->message, "DataSet '%.100s': timestep '%.40s' is not a number", file, time);
        return;
    }
    p->sets[p->count].time = t;
    p->sets[p->count].file = strdup(file);
    if (!p->sets[p->count].file) {
        p->error = 1;
        snprintf(p->message, sizeof p->message, "out of memory");
        return;
    }
    p->count++;
}

static void XMLCALL on_end(void *user, const XML_Char *name)
{
    (void)user;
    (void)name;
}

static int by_time(const void *a, const void *b)
{
    double x = ((const dataset *)a)->time, y = ((const dataset *)b)->time;
    return (x > y) - (x < y);
}

/* Append step s of every field of `step` to the matching field of `out` (grown to `steps` steps). */
static int merge_fields(tpk_mesh *out, const tpk_mesh *step, int s, int steps, const char *file, tpk_diag *diag)
{
    if (step->field_count != out->field_count)
        return tpk_diag_fail(diag, "%s: has %d fields, the series' first file %d", file, step->field_count,
                             out->field_count);
    for (int f = 0; f < out->field_count; f++) {
        tpk_src_field *dst = &out->fields[f];
        const tpk_src_field *src = &step->fields[f];
        if (strcmp(dst->name, src->name) || dst->association != src->association || dst->components != src->components)
            return tpk_diag_fail(diag, "%s: field %d is '%s', the series' first file has '%s' there", file, f,
                                 src->name, dst->name);
        size_t per = (size_t)(dst->association == TPK_ASSOC_POINT ? out->point_count : out->cell_count) *
                     (size_t)dst->components;
        if (s == 1) {
            float *grown = realloc(dst->values, sizeof *grown * per * (size_t)steps);
            if (!grown)
                return tpk_diag_fail(diag, "out of memory for %d time steps", steps);
            dst->values = grown;
        }
        memcpy(dst->values + per * (size_t)s, src->values, sizeof *src->values * per);
        dst->step_count = s + 1;
    }
    return 0;
}

static int read_series(const char *path, pvd_parse *p, tpk_diag *diag)
{
    const char *data;
    size_t size;
    if (tpk_map_file(path, &data, &size, diag) != 0)
        return -1;
    XML_Parser parser = XML_ParserCreate(NULL);
    if (!parser) {
        tpk_unmap_file(data, size);
        return tpk_diag_fail(diag, "%s: out of memory", path);
    }
    XML_SetUserData(parser, p);
    XML_SetElementHandler(parser, on_start, on_end);
    int ok = size < (size_t)1 << 30 && XML_Parse(parser, data, (int)size, 1) == XML_STATUS_OK;
    int rc = 0;
    if (!ok)
        rc = tpk_diag_fail(diag, "%s:%lu: not a valid ParaView series (XML): %s", path,
                           (unsigned long)XML_GetCurrentLineNumber(parser), XML_ErrorString(XML_GetErrorCode(parser)));
    else if (p->error)
        rc = tpk_diag_fail(diag, "%s: %s", path, p->message);
    else if (p->count == 0)
        rc = tpk_diag_fail(diag, "%s: expected DataSet entries in a Collection, found none", path);
    XML_ParserFree(parser);
    tpk_unmap_file(data, size);
    return rc;
}

/* A DataSet's file: relative to the .pvd's directory unless absolute. */
static void piece_path(const char *pvd, const char *piece, char *file, size_t cap)
{
    const char *slash = strrchr(pvd, '/');
    size_t dir = slash ? (size_t)(slash - pvd) + 1 : 0;
    if (piece[0] == '/')
        snprintf(file, cap, "%s", piece);
    else
        snprintf(file, cap, "%.*s%s", (int)dir, pvd, piece);
}

static void free_series(pvd_parse *p)
{
    for (int s = 0; s < p->count; s++)
        free(p->sets[s].file);
    free(p->sets);
}

void tpk_import_pvd_files(const char *path, tpk_import_file_fn each, void *user)
{
    pvd_parse p;
    memset(&p, 0, sizeof p);
    tpk_diag quiet;
    memset(&quiet, 0, sizeof quiet);
    if (read_series(path, &p, &quiet) == 0)
        for (int s = 0; s < p.count; s++) {
            char file[4096];
            piece_path(path, p.sets[s].file, file, sizeof file);
            each(user, file);
        }
    free_series(&p);
}

int tpk_import_pvd(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (!out || !path)
        return tpk_diag_fail(diag, "%s: no path or output mesh given", path ? path : "(null)");
    memset(out, 0, sizeof *out);
    pvd_parse p;
    memset(&p, 0, sizeof p);
    int rc = read_series(path, &p, diag);
    if (rc == 0)
        qsort(p.sets, (size_t)p.count, sizeof *p.sets, by_time);
    for (int s = 0; rc == 0 && s < p.count; s++) {
        char file[4096];
        piece_path(path, p.sets[s].file, file, sizeof file);
        tpk_mesh step;
        if (tpk_import_vtu(file, s == 0 ? out : &step, diag) != 0) {
            rc = -1;
            break;
        }
        if (s == 0)
            continue;
        if (!tpk_mesh_same_cells(out, &step))
            rc = tpk_diag_fail(diag, "%s: step %d (%s) holds a different mesh than the first step; a series "
                                     "must keep its points and cells", path, s, file);
        else
            rc = merge_fields(out, &step, s, p.count, file, diag);
        tpk_mesh_free(&step);
    }
    if (rc == 0) {
        out->step_count = p.count;
        out->times = malloc(sizeof *out->times * (size_t)p.count);
        if (!out->times)
            rc = tpk_diag_fail(diag, "%s: out of memory", path);
        for (int s = 0; rc == 0 && s < p.count; s++)
            out->times[s] = p.sets[s].time;
        snprintf(out->format, sizeof out->format, "pvd");
    }
    free_series(&p);
    return tpk_import_end(rc, out);
}
