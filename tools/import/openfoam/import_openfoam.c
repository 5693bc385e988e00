/* OpenFOAM case directories: constant/polyMesh (points, faces, owner, neighbour) into polyhedra (VTK 42),
 * one per cell from its faces (OpenFOAM's face normals point from owner to neighbour, so owner faces are
 * outward as stored and neighbour faces are reversed), and the latest numeric time directory's
 * volScalarField/volVectorField (cell fields) and pointScalarField (point fields). */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "foam_dict.h"
#include "foam_file.h"
#include "import/importers.h"
#include "mesh/polyhedron.h"
#include "tetpack_format.h"
#include "base/text_scan.h"
#include "import/import_file.h"

typedef struct poly_mesh {
    int64_t point_count, face_count, owner_count, neighbour_count;
    double *points;
    int64_t *face_starts;
    int32_t *face_ids;
    int32_t *owner, *neighbour;
} poly_mesh;

static void poly_mesh_free(poly_mesh *m)
{
    free(m->points);
    free(m->face_starts);
    free(m->face_ids);
    free(m->owner);
    free(m->neighbour);
}

static int is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static int has_faces(const char *dir)
{
    char p[4200];
    struct stat st;
    int n = snprintf(p, sizeof p, "%s/faces", dir); /* a path cut short names no file of the case */
    if (n > 0 && (size_t)n < sizeof p && stat(p, &st) == 0)
        return 1;
    n = snprintf(p, sizeof p, "%s/faces.gz", dir);
    return n > 0 && (size_t)n < sizeof p && stat(p, &st) == 0;
}

int tpk_openfoam_is_case(const char *path)
{
    char mesh_dir[4200];
    snprintf(mesh_dir, sizeof mesh_dir, "%s/constant/polyMesh", path);
    return is_dir(path) && (has_faces(mesh_dir) || has_faces(path));
}

/* The case directory and its polyMesh directory from the input path: the case, its constant/polyMesh,
 * or a file inside the case (ParaView's empty CASE.foam). */
static int locate(const char *path, char *case_dir, char *mesh_dir, size_t cap, tpk_diag *diag)
{
    if (is_dir(path) && has_faces(path)) {
        snprintf(mesh_dir, cap, "%s", path);
        snprintf(case_dir, cap, "%s/../..", path);
        return 0;
    }
    if (is_dir(path)) {
        snprintf(case_dir, cap, "%s", path);
    } else {
        const char *slash = strrchr(path, '/');
        if (slash)
            snprintf(case_dir, cap, "%.*s", (int)(slash - path), path);
        else
            snprintf(case_dir, cap, ".");
    }
    if (snprintf(mesh_dir, cap, "%s/constant/polyMesh", case_dir) >= (int)cap)
        return tpk_diag_fail(diag, "%s: path too long", path);
    if (!has_faces(mesh_dir))
        return tpk_diag_fail(diag, "%s: not an OpenFOAM case: no %s/faces or faces.gz", path, mesh_dir);
    return 0;
}

/* Open a required polyMesh file of the expected classes ('|'-separated). */
static int open_mesh_file(tpk_foam_file *f, const char *dir, const char *name, const char *classes, tpk_diag *diag)
{
    int rc = tpk_foam_open(f, dir, name, diag);
    if (rc == 1)
        return tpk_diag_fail(diag, "%s/%s: missing (an OpenFOAM polyMesh needs points, faces, owner and neighbour)",
                             dir, name);
    if (rc != 0)
        return -1;
    char padded[140];
    snprintf(padded, sizeof padded, "|%s|", f->class_name);
    char list[140];
    snprintf(list, sizeof list, "|%s|", classes);
    if (strstr(list, padded))
        return 0;
    tpk_foam_fail(f, "expected class %s, found '%s'", classes, f->class_name);
    tpk_foam_close(f);
    return -1;
}

static int read_faces(tpk_foam_file *f, poly_mesh *m)
{
    if (strcmp(f->class_name, "faceList") == 0) {
        if (f->binary)
            return tpk_foam_fail(f, "binary faceList is not read (OpenFOAM writes faceCompactList in binary)");
        return tpk_foam_face_list(f, &m->face_count, &m->face_starts, &m->face_ids);
    }
    /* faceCompactList: the faces' starts (count + 1), then all their point ids. */
    int32_t *starts;
    int64_t n, ids;
    if (tpk_foam_labels(f, &n, &starts, "face starts") != 0)
        return -1;
    if (tpk_foam_labels(f, &ids, &m->face_ids, "face point ids") != 0) {
        free(starts);
        return -1;
    }
    m->face_count = n ? n - 1 : 0;
    if (!n || starts[0] != 0 || starts[n - 1] != ids) {
        int32_t first = n ? starts[0] : -1, last = n ? starts[n - 1] : -1;
        free(starts);
        return tpk_foam_fail(f, "face starts run from %d to %d, expected 0 to %lld (the point ids listed)", first,
                             last, (long long)ids);
    }
    if ((m->face_starts = malloc((size_t)n * sizeof *m->face_starts)) == NULL) {
        free(starts);
        return tpk_foam_fail(f, "out of memory");
    }
    for (int64_t i = 0; i < n; i++) {
        m->face_starts[i] = starts[i];
        int64_t points = i ? (int64_t)starts[i] - starts[i - 1] : 3;
        if (points < 3) {
            free(starts);
            return tpk_foam_fail(f, "face %lld has %lld points; a face needs at least 3", (long long)i - 1,
                                 (long long)points);
        }
    }
    free(starts);
    return 0;
}

/* Read one polyMesh file with `fn`, closing it whatever happens. */
static int read_points(tpk_foam_file *f, poly_mesh *m)
{
    return tpk_foam_scalars(f, 3, &m->point_count, &m->points, "points");
}

static int read_owner(tpk_foam_file *f, poly_mesh *m)
{
    return tpk_foam_labels(f, &m->owner_count, &m->owner, "owners");
}

static int read_neighbour(tpk_foam_file *f, poly_mesh *m)
{
    return tpk_foam_labels(f, &m->neighbour_count, &m->neighbour, "neighbours");
}

static int read_mesh_file(const char *dir, const char *name, const char *classes,
                          int (*fn)(tpk_foam_file *, poly_mesh *), poly_mesh *m, int *binary, tpk_diag *diag)
{
    tpk_foam_file f;
    if (open_mesh_file(&f, dir, name, classes, diag) != 0)
        return -1;
    int rc = fn(&f, m);
    *binary |= f.binary;
    tpk_foam_close(&f);
    return rc;
}

static int check_ids(const char *dir, const char *name, const int32_t *ids, int64_t n, int64_t limit,
                     const char *what, tpk_diag *diag)
{
    for (int64_t i = 0; i < n; i++)
        if (ids[i] < 0 || ids[i] >= limit)
            return tpk_diag_fail(diag, "%s/%s: entry %lld: expected a %s in [0, %lld), found %d", dir, name,
                                 (long long)i, what, (long long)limit, ids[i]);
    return 0;
}

static int load_poly_mesh(const char *dir, poly_mesh *m, int *binary, tpk_diag *diag)
{
    if (read_mesh_file(dir, "points", "vectorField", read_points, m, binary, diag) != 0 ||
        read_mesh_file(dir, "faces", "faceList|faceCompactList", read_faces, m, binary, diag) != 0 ||
        read_mesh_file(dir, "owner", "labelList", read_owner, m, binary, diag) != 0 ||
        read_mesh_file(dir, "neighbour", "labelList", read_neighbour, m, binary, diag) != 0)
        return -1;
    for (int64_t i = 0; i < 3 * m->point_count; i++)
        if (!isfinite(m->points[i]))
            return tpk_diag_fail(diag, "%s/points: point %lld: expected finite coordinates, found %g", dir,
                                 (long long)(i / 3), m->points[i]);
    if (check_ids(dir, "faces", m->face_ids, m->face_starts[m->face_count], m->point_count, "point id", diag))
        return -1;
    if (m->owner_count != m->face_count)
        return tpk_diag_fail(diag, "%s/owner: %lld owners, expected one per face (%lld)", dir,
                             (long long)m->owner_count, (long long)m->face_count);
    if (m->neighbour_count > m->face_count)
        return tpk_diag_fail(diag, "%s/neighbour: %lld neighbours, more than the %lld faces", dir,
                             (long long)m->neighbour_count, (long long)m->face_count);
    /* Cells are numbered from 0 without gaps: the owners and neighbours name them all. */
    if (check_ids(dir, "owner", m->owner, m->owner_count, INT32_MAX, "cell id", diag) ||
        check_ids(dir, "neighbour", m->neighbour, m->neighbour_count, INT32_MAX, "cell id", diag))
        return -1;
    return 0;
}

/* Each cell's VTK face stream into cell_conn (nfaces, then npts ids per face), then moved into
 * mesh->faces by tpk_mesh_take_face_streams. */
static int build_cells(const poly_mesh *m, tpk_mesh *out, tpk_diag *diag, const char *dir)
{
    int64_t cells = 0;
    for (int64_t f = 0; f < m->owner_count; f++)
        cells = m->owner[f] + 1 > cells ? m->owner[f] + 1 : cells;
    for (int64_t f = 0; f < m->neighbour_count; f++)
        cells = m->neighbour[f] + 1 > cells ? m->neighbour[f] + 1 : cells;
    /* Every cell is some face's owner or neighbour: a larger id leaves gaps (and is not allocated). */
    if (cells > m->owner_count + m->neighbour_count)
        return tpk_diag_fail(diag, "%s/owner, neighbour: cell ids up to %lld, but only %lld owner and neighbour "
                             "entries to name them", dir, (long long)cells - 1,
                             (long long)(m->owner_count + m->neighbour_count));
    int64_t *len = calloc((size_t)cells + 1, sizeof *len);
    if (!len)
        return tpk_diag_fail(diag, "%s: out of memory for %lld cells", dir, (long long)cells);
    for (int64_t f = 0; f < m->face_count; f++) {
        int64_t n = 1 + m->face_starts[f + 1] - m->face_starts[f];
        len[m->owner[f]] += n;
        if (f < m->neighbour_count)
            len[m->neighbour[f]] += n;
    }
    out->cell_count = cells;
    out->cell_offsets = malloc(((size_t)cells + 1) * sizeof *out->cell_offsets);
    out->cell_types = malloc((size_t)cells + 1);
    int64_t total = 0;
    for (int64_t c = 0; c < cells; c++)
        total += 1 + len[c];
    if (total > INT32_MAX || !out->cell_offsets || !out->cell_types ||
        (out->cell_conn = malloc((size_t)total * sizeof *out->cell_conn)) == NULL) {
        free(len);
        return tpk_diag_fail(diag, "%s: out of memory (or too large) for %lld cells' faces", dir, (long long)cells);
    }
    int64_t *fill = len; /* reused: each cell's next free slot in its stream */
    out->cell_offsets[0] = 0;
    for (int64_t c = 0; c < cells; c++) {
        out->cell_offsets[c + 1] = out->cell_offsets[c] + 1 + len[c];
        out->cell_types[c] = TPK_CELL_POLYHEDRON;
        out->cell_conn[out->cell_offsets[c]] = 0;
        fill[c] = out->cell_offsets[c] + 1;
    }
    for (int64_t f = 0; f < m->face_count; f++) {
        const int32_t *ids = m->face_ids + m->face_starts[f];
        int32_t n = (int32_t)(m->face_starts[f + 1] - m->face_starts[f]);
        for (int side = 0; side < 1 + (f < m->neighbour_count); side++) {
            int64_t c = side ? m->neighbour[f] : m->owner[f];
            int32_t *stream = out->cell_conn + fill[c];
            out->cell_conn[out->cell_offsets[c]]++;
            stream[0] = n;
            for (int32_t k = 0; k < n; k++)
                stream[1 + k] = side ? ids[n - 1 - k] : ids[k];
            fill[c] += 1 + n;
        }
    }
    free(len);
    for (int64_t c = 0; c < cells; c++) {
        int64_t bad;
        char why[200];
        int64_t at = out->cell_offsets[c], n = out->cell_offsets[c + 1] - at;
        if (tpk_face_stream_check(out->cell_conn + at, n, out->point_count, &bad, why, sizeof why) != 0)
            return tpk_diag_fail(diag, "%s: cell %lld: %s", dir, (long long)c, why);
    }
    if (tpk_mesh_take_face_streams(out) != 0)
        return tpk_diag_fail(diag, "%s: out of memory", dir);
    return 0;
}

typedef struct time_dir {
    double time;
    char name[64];
} time_dir;

static int compare_times(const void *a, const void *b)
{
    double x = ((const time_dir *)a)->time, y = ((const time_dir *)b)->time;
    return (x > y) - (x < y);
}

/* The case's numeric time directories, in time order (malloc'ed; *count may be 0). */
static int list_times(const char *case_dir, time_dir **out, int *count, tpk_diag *diag)
{
    *out = NULL;
    *count = 0;
    DIR *d = opendir(case_dir);
    if (!d)
        return tpk_diag_fail(diag, "%s: cannot list the case directory", case_dir);
    int cap = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        char *end, path[4400];
        double t = strtod(e->d_name, &end);
        snprintf(path, sizeof path, "%s/%s", case_dir, e->d_name);
        if (end == e->d_name || *end || strlen(e->d_name) >= sizeof(*out)->name || !is_dir(path))
            continue;
        if (*count == cap) {
            cap = 2 * cap + 8;
            time_dir *grown = realloc(*out, (size_t)cap * sizeof *grown);
            if (!grown) {
                closedir(d);
                return tpk_diag_fail(diag, "%s: out of memory", case_dir);
            }
            *out = grown;
        }
        (*out)[*count].time = t;
        memcpy((*out)[(*count)++].name, e->d_name, strlen(e->d_name) + 1); /* fits: checked above */
    }
    closedir(d);
    if (*count > 1) /* qsort must not be given NULL, even for no elements */
        qsort(*out, (size_t)*count, sizeof **out, compare_times);
    return 0;
}

/* A field file's class: components and association (-1: not a field read here). */
static int field_kind(const char *class_name, int *components)
{
    *components = strcmp(class_name, "volVectorField") == 0 ? 3 : 1;
    if (strcmp(class_name, "volScalarField") == 0 || strcmp(class_name, "volVectorField") == 0)
        return TPK_ASSOC_TET;
    if (strcmp(class_name, "pointScalarField") == 0)
        return TPK_ASSOC_POINT;
    return -1;
}

static int is_word(tpk_foam_dict *d, const tpk_foam_token *t, const char *w)
{
    return t->kind == TPK_FOAM_WORD && tpk_foam_token_is(d, t, w);
}

static int token_number(tpk_foam_dict *d, const tpk_foam_token *t, double *v)
{
    char buf[64], *end;
    if (t->kind != TPK_FOAM_WORD || t->len >= sizeof buf)
        return -1;
    memcpy(buf, tpk_foam_dict_file(d, t)->data + t->pos, t->len);
    buf[t->len] = 0;
    *v = strtod(buf, &end);
    return end == buf || *end || !isfinite(*v) ? -1 : 0;
}

/* A uniform value: one number, or "(x y z)" for a vector. */
static int uniform_value(tpk_foam_dict *d, const tpk_foam_token *t, int n, int components, double *v)
{
    int ok = components == 1 ? n == 1 && token_number(d, t, v) == 0
                             : n == components + 2 && tpk_foam_token_is(d, &t[0], "(") &&
                                 tpk_foam_token_is(d, &t[n - 1], ")");
    for (int k = 0; ok && components > 1 && k < components; k++)
        ok = token_number(d, &t[1 + k], &v[k]) == 0;
    return ok ? 0 : -1;
}

/* `nonuniform List<T> N{V}`: OpenFOAM's short form of a list whose N items are all V. */
static int uniform_list(tpk_foam_dict *d, const tpk_foam_token *list, int components, int64_t count, double *v)
{
    const char *s = tpk_foam_dict_file(d, list)->data + list->pos;
    char *end;
    long long n = strtoll(s, &end, 10);
    int ok = components == 1 ? sscanf(end, "{ %lf }", &v[0]) == 1
                             : sscanf(end, "{ ( %lf %lf %lf ) }", &v[0], &v[1], &v[2]) == 3;
    if (!ok || !isfinite(v[0]) || (components > 1 && !(isfinite(v[1]) && isfinite(v[2]))))
        return tpk_foam_dict_fail(d, list, "expected N{value} with a %s value, found '%.*s'",
                                  components > 1 ? "vector" : "scalar", (int)(list->len > 40 ? 40 : list->len), s);
    if (n != count)
        return tpk_foam_dict_fail(d, list, "%lld field values, expected %lld (one per cell or point)", n,
                                  (long long)count);
    return 0;
}

/* The internalField entry, macros expanded: `uniform V`, `nonuniform List<T> N(...)` (read in place, ASCII
 * or binary) or `nonuniform List<T> N{V}`, as count * components values into dst. */
static int internal_field(tpk_foam_dict *d, const tpk_foam_token *t, int n, int components, int64_t count,
                          float *dst)
{
    const char *list_type = components > 1 ? "List<vector>" : "List<scalar>";
    double v[3];
    if (n >= 1 && is_word(d, &t[0], "uniform")) {
        if (uniform_value(d, t + 1, n - 1, components, v) != 0)
            return tpk_foam_dict_fail(d, &t[0], "expected a uniform %s value after 'uniform', found %d tokens",
                                      components > 1 ? "vector (x y z)" : "scalar", n - 1);
        for (int64_t i = 0; i < count * components; i++)
            dst[i] = (float)v[i % components];
        return 0;
    }
    if (n != 3 || !is_word(d, &t[0], "nonuniform") || !is_word(d, &t[1], list_type) || t[2].kind != TPK_FOAM_LIST) {
        const char *s = tpk_foam_dict_file(d, &t[0])->data + t[0].pos;
        return tpk_foam_dict_fail(d, &t[0], "expected 'uniform VALUE' or 'nonuniform %s N(...)' for internalField, "
                                  "found '%.*s'", list_type, (int)(t[0].len > 20 ? 20 : t[0].len), s);
    }
    tpk_foam_file *f = tpk_foam_dict_file(d, &t[2]);
    size_t open = strspn(f->data + t[2].pos, "0123456789 \t\r\n"); /* N, then '(' or '{' */
    if (f->data[t[2].pos + open] == '{') {
        if (uniform_list(d, &t[2], components, count, v) != 0)
            return -1;
        for (int64_t i = 0; i < count * components; i++)
            dst[i] = (float)v[i % components];
        return 0;
    }
    int64_t found;
    double *values;
    f->pos = t[2].pos;
    if (tpk_foam_scalars(f, components, &found, &values, "field values") != 0)
        return -1;
    if (found != count) {
        free(values);
        return tpk_foam_dict_fail(d, &t[2], "%lld field values, expected %lld (one per %s)", (long long)found,
                                  (long long)count, count ? "cell or point" : "cell");
    }
    for (int64_t i = 0; i < count * components; i++)
        dst[i] = (float)values[i];
    free(values);
    return 0;
}

/* Parse a field file (which it takes over) and read its internalField. */
static int read_internal_field(tpk_foam_file *file, const char *case_dir, int components, int64_t count,
                               float *dst, tpk_diag *diag)
{
    tpk_foam_dict *d = tpk_foam_dict_parse(file, case_dir, diag);
    if (!d)
        return -1;
    tpk_foam_token *t;
    int n;
    int rc = tpk_foam_dict_value(d, "internalField", &t, &n);
    if (rc == 0)
        rc = internal_field(d, t, n, components, count, dst);
    free(t);
    tpk_foam_dict_free(d);
    return rc;
}

/* One field name read from every time directory into a field with one step per directory. A field that
 * cannot be read is left out with a warning saying where and why, unless diag->strict_fields. */
static int read_field(const char *case_dir, const time_dir *times, int steps, const char *name, tpk_mesh *out,
                      tpk_diag *diag)
{
    float *values = NULL;
    int components = 1, assoc = -1;
    int64_t count = 0;
    for (int s = 0; s < steps; s++) {
        char dir[4400];
        snprintf(dir, sizeof dir, "%s/%s", case_dir, times[s].name);
        tpk_foam_file f;
        int rc = tpk_foam_open(&f, dir, name, diag);
        if (rc == 1) {
            tpk_diag_warn(diag, "%s: field %s is not in every time directory (not in %s); left out", case_dir, name,
                          times[s].name);
            free(values);
            return 0;
        }
        if (rc != 0)
            goto unreadable;
        int c;
        int a = field_kind(f.class_name, &c);
        if (s == 0) {
            assoc = a, components = c;
            count = assoc == TPK_ASSOC_POINT ? out->point_count : out->cell_count;
            if (assoc >= 0 && (values = malloc((size_t)(steps * count * components + 1) * sizeof *values)) == NULL) {
                tpk_foam_close(&f);
                return tpk_diag_fail(diag, "%s: out of memory", f.path);
            }
        }
        if (assoc < 0 || a != assoc || c != components) {
            tpk_foam_close(&f);
            free(values);
            return 0; /* a field class not read (surface fields, tensors, uniformDimensionedFields) */
        }
        if (read_internal_field(&f, case_dir, components, count, values + s * count * components, diag) != 0)
            goto unreadable;
    }
    if (tpk_mesh_add_field(out, name, assoc, components, steps, values) == 0)
        return 0;
    free(values);
    return tpk_diag_fail(diag, "%s: out of memory for field %s", case_dir, name);
unreadable:
    free(values);
    if (diag && diag->strict_fields)
        return -1;
    tpk_diag_warn(diag, "%s; field %s left out (--strict-fields makes this an error)", diag ? diag->message : "",
                  name);
    if (diag)
        diag->message[0] = 0;
    return 0;
}

/* Fields: the names in the latest time directory, read from every one (a time step each). */
static int read_fields(const char *case_dir, tpk_mesh *out, tpk_diag *diag)
{
    time_dir *times;
    int steps;
    if (list_times(case_dir, &times, &steps, diag) != 0)
        return -1;
    int rc = 0;
    DIR *d = NULL;
    char latest[4400];
    if (steps) {
        snprintf(latest, sizeof latest, "%s/%s", case_dir, times[steps - 1].name);
        d = opendir(latest);
    }
    for (struct dirent *e; d && rc == 0 && (e = readdir(d)) != NULL;) {
        char name[256];
        size_t n = strlen(e->d_name);
        char file[4700];
        snprintf(file, sizeof file, "%s/%s", latest, e->d_name);
        /* Solvers write folders (uniform/) and files of other kinds beside the fields: fields are files. */
        if (e->d_name[0] == '.' || n >= sizeof name || is_dir(file))
            continue;
        snprintf(name, sizeof name, "%.*s", (int)(n > 3 && strcmp(e->d_name + n - 3, ".gz") == 0 ? n - 3 : n),
                 e->d_name);
        rc = read_field(case_dir, times, steps, name, out, diag);
    }
    if (d)
        closedir(d);
    if (rc == 0 && out->field_count && steps > 1) {
        out->step_count = steps;
        if ((out->times = malloc((size_t)steps * sizeof *out->times)) == NULL)
            rc = tpk_diag_fail(diag, "%s: out of memory", case_dir);
        for (int s = 0; rc == 0 && s < steps; s++)
            out->times[s] = times[s].time;
    }
    free(times);
    return rc;
}

void tpk_import_openfoam_files(const char *path, tpk_import_file_fn each, void *user)
{
    static const char *const names[] = {"points", "faces", "owner", "neighbour"};
    char case_dir[4096], mesh_dir[4096];
    if (locate(path, case_dir, mesh_dir, sizeof case_dir, NULL) != 0)
        return;
    for (int i = 0; i < 8; i++) {
        char file[4200];
        snprintf(file, sizeof file, "%s/%s%s", mesh_dir, names[i / 2], i % 2 ? ".gz" : "");
        each(user, file);
    }
}

int tpk_import_openfoam(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (tpk_import_begin(path, out, diag) != 0)
        return -1;
    char case_dir[4096], mesh_dir[4096];
    poly_mesh m = {0};
    int binary = 0;
    if (locate(path, case_dir, mesh_dir, sizeof case_dir, diag) != 0 ||
        load_poly_mesh(mesh_dir, &m, &binary, diag) != 0)
        goto fail;
    out->point_count = m.point_count;
    out->points = m.points;
    m.points = NULL;
    out->step_count = 1;
    snprintf(out->format, sizeof out->format, "openfoam-%s", binary ? "binary" : "ascii");
    if (build_cells(&m, out, diag, mesh_dir) != 0 || read_fields(case_dir, out, diag) != 0)
        goto fail;
    poly_mesh_free(&m);
    return 0;
fail:
    poly_mesh_free(&m);
    tpk_mesh_free(out);
    memset(out, 0, sizeof *out);
    return -1;
}
