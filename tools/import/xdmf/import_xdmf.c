/* XDMF (.xdmf, .xmf; versions 2 and 3) importer, as meshio, FEniCS/dolfinx and many solvers write it:
 * the Domain's Uniform Grid with volume cells gives the mesh and its fields; a Temporal Collection
 * gives fields with one step per distinct Time Value (several collections, one per function as dolfinx
 * writes them, are merged by time). Every step must hold the same mesh: the same Topology and Geometry
 * by XInclude or Reference, or identical ones. This file sits on top and calls down: the tree
 * (import_xdmf_tree.c), the grids (import_xdmf_grid.c), which read DataItems (import_xdmf_data.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "import_xdmf_internal.h"
#include "tetpack_format.h"
#include "base/text_scan.h"
#include "import/import_file.h"

#define MAX_STEPS 100000

/* A Uniform Grid of a Temporal Collection: one time step of some fields. */
typedef struct step_grid {
    const xdmf_node *grid;
    double time;
    int order, step;
} step_grid;

/* The grids of the Domain. */
typedef struct domain_grids {
    const xdmf_node *uniform[64];
    int uniform_count;
    step_grid *steps;
    int step_count, step_cap;
} domain_grids;

static const char *grid_name(const xdmf_node *grid)
{
    const char *name = xdmf_attr(grid, "Name");
    return name ? name : "";
}

static int grid_type_is(const xdmf_node *grid, const char *type)
{
    const char *t = xdmf_attr(grid, "GridType");
    return t ? !strcasecmp(t, type) : !strcasecmp(type, "Uniform");
}

static int add_step(xdmf_reader *r, domain_grids *d, const xdmf_node *grid, int index)
{
    double time = index;
    for (const xdmf_node *c = grid->first; c; c = c->next) {
        const char *value = xdmf_is(c, "Time") ? xdmf_attr(c, "Value") : NULL;
        if (value && tpk_parse_double(value, strlen(value), &time))
            return xdmf_fail(r, c, "expected a number as the Time Value, found \"%.40s\"", value);
    }
    if (d->step_count == d->step_cap) {
        int cap = d->step_cap ? 2 * d->step_cap : 16;
        step_grid *grown = cap <= 2 * MAX_STEPS ? realloc(d->steps, sizeof *grown * (size_t)cap) : NULL;
        if (!grown)
            return xdmf_fail(r, grid, "expected at most %d time steps, found more (or out of memory)", MAX_STEPS);
        d->steps = grown;
        d->step_cap = cap;
    }
    d->steps[d->step_count] = (step_grid){grid, time, d->step_count, 0};
    d->step_count++;
    return 0;
}

static int collect_grids(xdmf_reader *r, const xdmf_node *domain, domain_grids *d)
{
    for (const xdmf_node *g = domain->first; g; g = g->next) {
        if (!xdmf_is(g, "Grid"))
            continue;
        if (grid_type_is(g, "Uniform")) {
            if (d->uniform_count == 64)
                return xdmf_fail(r, g, "expected at most 64 Grids in the Domain, found more");
            d->uniform[d->uniform_count++] = g;
            continue;
        }
        const char *type = xdmf_attr(g, "GridType"), *collection = xdmf_attr(g, "CollectionType");
        if (strcasecmp(type, "Collection") || !collection || strcasecmp(collection, "Temporal"))
            return xdmf_fail(r, g, "Grid '%.60s': expected GridType Uniform or a Collection with CollectionType "
                             "Temporal, found GridType \"%.30s\"%s%.30s%s (spatial collections, partitioned "
                             "meshes, are not read)", grid_name(g), type, collection ? " CollectionType \"" : "",
                             collection ? collection : "", collection ? "\"" : "");
        int index = 0;
        for (const xdmf_node *s = g->first; s; s = s->next) {
            if (!xdmf_is(s, "Grid"))
                continue;
            if (!grid_type_is(s, "Uniform"))
                return xdmf_fail(r, s, "Grid '%.60s' in Temporal Collection '%.60s': expected GridType Uniform, "
                                 "found \"%.30s\"", grid_name(s), grid_name(g), xdmf_attr(s, "GridType"));
            if (add_step(r, d, s, index++))
                return -1;
        }
    }
    return 0;
}

static int by_time(const void *a, const void *b)
{
    const step_grid *x = a, *y = b;
    return x->time < y->time ? -1 : x->time > y->time ? 1 : x->order - y->order;
}

/* ---- Fields over the steps ---------------------------------------------------------------------- */

typedef struct step_field {
    char name[TPK_NAME_MAX];
    int association, components;
    float *values;            /* steps * tuples * components */
    uint8_t *have;            /* per step */
} step_field;

typedef struct field_set {
    step_field *fields;
    int count;
    int steps;
    const double *times;
} field_set;

static void field_set_free(field_set *f)
{
    for (int i = 0; i < f->count; i++)
        free(f->fields[i].values), free(f->fields[i].have);
    free(f->fields);
}

/* The field `name` of that association, created on first sight. */
static step_field *field_for(xdmf_reader *r, field_set *f, const xdmf_node *at, const char *name, int association,
                             int components, size_t per_step)
{
    for (int i = 0; i < f->count; i++)
        if (!strncmp(f->fields[i].name, name, TPK_NAME_MAX - 1) && f->fields[i].association == association) {
            if (f->fields[i].components != components)
                xdmf_fail(r, at, "Attribute '%.60s': expected %d components as in its first step, found %d", name,
                          f->fields[i].components, components);
            return f->fields[i].components == components ? &f->fields[i] : NULL;
        }
    step_field *grown = realloc(f->fields, sizeof *grown * (size_t)(f->count + 1));
    if (!grown) {
        xdmf_fail(r, at, "out of memory");
        return NULL;
    }
    f->fields = grown;
    step_field *s = &grown[f->count];
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "%s", name);
    s->association = association, s->components = components;
    s->values = malloc(sizeof *s->values * per_step * (size_t)f->steps);
    s->have = calloc((size_t)f->steps, 1);
    f->count++;
    if (!s->values || !s->have) {
        xdmf_fail(r, at, "out of memory for %d time steps of '%.60s'", f->steps, name);
        return NULL;
    }
    return s;
}

/* The Attributes of one grid as step `step` of the fields. */
static int read_step_fields(xdmf_reader *r, const xdmf_grid *parts, int step, const tpk_mesh *mesh,
                            const xdmf_cells *cells, field_set *f)
{
    for (int a = 0; a < parts->attribute_count; a++) {
        const xdmf_node *at = parts->attributes[a];
        const char *name = xdmf_attr(at, "Name") ? xdmf_attr(at, "Name") : "unnamed";
        float *values;
        int association, components;
        int rc = xdmf_read_attribute(r, at, mesh, cells, &values, &association, &components);
        if (rc < 0)
            return -1;
        if (rc > 0)
            continue; /* skipped, with a warning */
        size_t per = (size_t)(association == TPK_ASSOC_POINT ? mesh->point_count : mesh->cell_count) *
                     (size_t)components;
        step_field *s = field_for(r, f, at, name, association, components, per);
        if (s && s->have[step])
            rc = xdmf_fail(r, at, "Attribute '%.60s': expected one value per time step, found a second at time %.17g",
                           name, f->times[step]);
        if (s && rc == 0)
            memcpy(s->values + per * (size_t)step, values, sizeof *values * per), s->have[step] = 1;
        free(values);
        if (!s || rc)
            return -1;
    }
    return 0;
}

/* Every field must have a value at every time; then they move into out. */
static int move_fields(xdmf_reader *r, field_set *f, tpk_mesh *out)
{
    for (int i = 0; i < f->count; i++) {
        step_field *s = &f->fields[i];
        for (int t = 0; t < f->steps; t++)
            if (!s->have[t])
                return xdmf_fail(r, NULL, "Attribute '%s' has no value at time %.17g (step %d of %d); every "
                                 "attribute of a time series needs one per step", s->name, f->times[t], t, f->steps);
        if (tpk_mesh_add_field(out, s->name, s->association, s->components, f->steps, s->values))
            return xdmf_fail(r, NULL, "out of memory");
        s->values = NULL;
    }
    return 0;
}

/* The mesh of step grid `parts` is the first step's: the same elements, or the same contents. */
static int check_same_mesh(xdmf_reader *r, const xdmf_grid *first, const xdmf_grid *parts, const tpk_mesh *mesh)
{
    if (parts->topology == first->topology && parts->geometry == first->geometry)
        return 0;
    tpk_mesh other;
    xdmf_cells cells;
    memset(&other, 0, sizeof other);
    int rc = xdmf_read_cells(r, parts, &other, &cells);
    if (rc == 0 && !tpk_mesh_same_cells(mesh, &other))
        rc = xdmf_fail(r, parts->grid, "Grid '%.60s' holds a different mesh (points or cells) than the first time "
                       "step's Grid '%.60s' (line %ld); a time series must keep its mesh", grid_name(parts->grid),
                       grid_name(first->grid), first->grid->line);
    free(cells.keep);
    tpk_mesh_free(&other);
    return rc;
}

static int read_series(xdmf_reader *r, domain_grids *d, tpk_mesh *out)
{
    qsort(d->steps, (size_t)d->step_count, sizeof *d->steps, by_time);
    double *times = malloc(sizeof *times * (size_t)d->step_count);
    if (!times)
        return xdmf_fail(r, NULL, "out of memory");
    int steps = 0;
    for (int i = 0; i < d->step_count; i++) {
        if (!steps || times[steps - 1] != d->steps[i].time)
            times[steps++] = d->steps[i].time;
        d->steps[i].step = steps - 1;
    }
    xdmf_grid *first = malloc(sizeof *first), *parts = malloc(sizeof *parts);
    xdmf_cells cells = {0};
    field_set f = {.steps = steps, .times = times};
    int rc = !first || !parts ? xdmf_fail(r, NULL, "out of memory") : xdmf_grid_parts(r, d->steps[0].grid, first);
    if (rc == 0)
        rc = xdmf_read_cells(r, first, out, &cells);
    for (int i = 0; rc == 0 && i < d->step_count; i++) {
        rc = xdmf_grid_parts(r, d->steps[i].grid, parts);
        if (rc == 0 && i)
            rc = check_same_mesh(r, first, parts, out);
        if (rc == 0)
            rc = read_step_fields(r, parts, d->steps[i].step, out, &cells, &f);
    }
    if (rc == 0)
        rc = move_fields(r, &f, out);
    field_set_free(&f);
    free(cells.keep);
    free(first);
    free(parts);
    out->step_count = steps;
    out->times = times;
    for (int u = 0; rc == 0 && u < d->uniform_count; u++)
        for (const xdmf_node *c = d->uniform[u]->first; c; c = c->next)
            if (xdmf_is(c, "Attribute")) {
                tpk_diag_warn(r->diag, "%s: line %ld: Grid '%.60s' is outside the time series: its Attributes are "
                              "not read", r->name, d->uniform[u]->line, grid_name(d->uniform[u]));
                break;
            }
    return rc;
}

/* No time series: the one Uniform Grid with volume cells (others, such as dolfinx's facet tags, dropped). */
static int read_static(xdmf_reader *r, domain_grids *d, tpk_mesh *out)
{
    xdmf_grid *parts = malloc(sizeof *parts), *chosen = malloc(sizeof *chosen);
    int found = 0, rc = !parts || !chosen ? xdmf_fail(r, NULL, "out of memory") : 0;
    for (int u = 0; rc == 0 && u < d->uniform_count; u++) {
        rc = xdmf_grid_parts(r, d->uniform[u], parts);
        if (rc || !xdmf_grid_has_volumes(parts)) {
            if (rc == 0)
                tpk_diag_warn(r->diag, "%s: line %ld: Grid '%.60s' has no volume cells (TopologyType %s): dropped",
                              r->name, d->uniform[u]->line, grid_name(d->uniform[u]),
                              xdmf_attr(parts->topology, "TopologyType") ? xdmf_attr(parts->topology, "TopologyType")
                                                                         : xdmf_attr(parts->topology, "Type"));
            continue;
        }
        if (found++)
            rc = xdmf_fail(r, d->uniform[u], "expected one Grid with volume cells, found a second, '%.60s' (the first "
                           "is '%.60s', line %ld; multi-block files are not read)", grid_name(d->uniform[u]),
                           grid_name(chosen->grid), chosen->grid->line);
        *chosen = *parts;
    }
    if (rc == 0 && !found)
        rc = xdmf_fail(r, NULL, "expected a Uniform Grid with volume cells (tetrahedra, pyramids, wedges, "
                       "hexahedra), found %d Grids without", d->uniform_count);
    xdmf_cells cells = {0};
    if (rc == 0)
        rc = xdmf_read_cells(r, chosen, out, &cells);
    for (int a = 0; rc == 0 && a < chosen->attribute_count; a++) {
        float *values;
        int association, components;
        int got = xdmf_read_attribute(r, chosen->attributes[a], out, &cells, &values, &association, &components);
        const char *name = xdmf_attr(chosen->attributes[a], "Name");
        if (got == 0 && tpk_mesh_add_field(out, name ? name : "unnamed", association, components, 1, values)) {
            free(values);
            got = xdmf_fail(r, NULL, "out of memory");
        }
        rc = got < 0 ? -1 : 0;
    }
    free(cells.keep);
    free(parts);
    free(chosen);
    out->step_count = 1;
    return rc;
}

static const xdmf_node *child_named(const xdmf_node *n, const char *name)
{
    for (const xdmf_node *c = n ? n->first : NULL; c; c = c->next)
        if (xdmf_is(c, name))
            return c;
    return NULL;
}

static int read_document(xdmf_reader *r, tpk_mesh *out)
{
    if (xdmf_parse_tree(r))
        return -1;
    const xdmf_node *root = r->doc->first, *domain = child_named(root, "Domain");
    if (!root || !xdmf_is(root, "Xdmf"))
        return xdmf_fail(r, root, "expected the root element <Xdmf>, found %s%.40s%s", root ? "<" : "",
                         root ? root->name : "none", root ? ">" : "");
    if (!domain)
        return xdmf_fail(r, root, "expected a <Domain> inside, found none");
    domain_grids d;
    memset(&d, 0, sizeof d);
    int rc = collect_grids(r, domain, &d);
    if (rc == 0)
        rc = d.step_count ? read_series(r, &d, out) : read_static(r, &d, out);
    free(d.steps);
    if (rc == 0 && out->cell_count == 0)
        rc = xdmf_fail(r, NULL, "expected volume cells, found none (every cell was dropped)");
    snprintf(out->format, sizeof out->format, "xdmf");
    return rc;
}

static int parse_xdmf(xdmf_reader *r, tpk_mesh *out)
{
    int rc = read_document(r, out);
    xdmf_hdf_close(r);
    xdmf_tree_free(r->doc);
    return tpk_import_end(rc, out);
}

int tpk_import_xdmf_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    if (!name)
        name = "(input)";
    if (tpk_import_begin(name, out, diag))
        return -1;
    xdmf_reader r = {.name = name, .data = data, .size = data ? size : 0, .diag = diag};
    return parse_xdmf(&r, out);
}

/* tpk_parse_fn for the file form: HDF datasets are read relative to the file. */
static int parse_file(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out, tpk_diag *diag)
{
    (void)mapped;
    if (tpk_import_begin(name, out, diag))
        return -1;
    xdmf_reader r = {.name = name, .data = data, .size = size, .allow_files = 1, .diag = diag};
    return parse_xdmf(&r, out);
}

int tpk_import_xdmf(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_mapped(path, parse_file, out, diag);
}

/* Each HDF file of the tree's DataItems once (in the order of first use). */
static void each_hdf_file(xdmf_reader *r, const xdmf_node *n, char *last, size_t cap, tpk_import_file_fn each,
                          void *user)
{
    for (const xdmf_node *c = n->first; c; c = c->next) {
        const char *format = xdmf_attr(c, "Format"), *dataset;
        char path[4096];
        size_t len;
        if (xdmf_is(c, "DataItem") && format && !strcasecmp(format, "HDF") &&
            xdmf_hdf_source(r, c, path, sizeof path, &dataset, &len) == 0 && strcmp(path, last)) {
            each(user, path);
            snprintf(last, cap, "%s", path);
        }
        each_hdf_file(r, c, last, cap, each, user);
    }
}

void tpk_import_xdmf_files(const char *path, tpk_import_file_fn each, void *user)
{
    tpk_diag quiet;
    memset(&quiet, 0, sizeof quiet);
    const char *data;
    size_t size;
    if (tpk_map_file(path, &data, &size, &quiet) != 0)
        return;
    xdmf_reader r = {.name = path, .data = data, .size = size, .allow_files = 1, .diag = &quiet};
    char last[4096] = "";
    if (xdmf_parse_tree(&r) == 0)
        each_hdf_file(&r, r.doc, last, sizeof last, each, user);
    xdmf_tree_free(r.doc);
    tpk_unmap_file(data, size);
}

/* After blanks, the end of the first `close` at or after `at`, or `got` when the head ends first. */
static size_t skip_past(const char *head, size_t got, size_t at, const char *close)
{
    size_t n = strlen(close);
    for (; at + n <= got; at++)
        if (!memcmp(head + at, close, n))
            return at + n;
    return got;
}

int tpk_import_xdmf_sniff(const char *head, size_t got)
{
    size_t at = 0;
    for (;;) {
        while (at < got && (head[at] == ' ' || head[at] == '\t' || head[at] == '\r' || head[at] == '\n'))
            at++;
        if (got - at >= 4 && !memcmp(head + at, "<!--", 4))
            at = skip_past(head, got, at + 4, "-->");
        else if (got - at >= 2 && !memcmp(head + at, "<?", 2))
            at = skip_past(head, got, at + 2, "?>");
        else if (got - at >= 2 && !memcmp(head + at, "<!", 2))
            at = skip_past(head, got, at + 2, ">"); /* a DOCTYPE; dolfinx's has an empty "[]" subset */
        else
            return got - at >= 6 && !memcmp(head + at, "<Xdmf", 5) &&
                   strchr(" \t\r\n>/", head[at + 5]) && head[at + 5];
    }
}
