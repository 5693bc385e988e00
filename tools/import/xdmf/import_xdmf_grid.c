/* XDMF importer: one Uniform Grid. Its Topology becomes cells in VTK node order (XDMF's linear
 * Tetrahedron, Pyramid, Wedge and Hexahedron list their nodes as VTK does: checked on meshio's files,
 * which convert with no mirrored cell; tests/cli/xdmf.sh), higher-order ones are kept whole, in VTK's
 * node order as meshio writes them; surfaces, lines and points are dropped. Geometry XYZ, XY or X_Y_Z gives
 * the points; Attributes centred on nodes or cells give fields. xi:include elements and References
 * stand for the elements they name. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "import_xdmf_internal.h"
#include "base/text_scan.h"
#include "mesh/cell_types.h"
#include "tetpack_format.h"

/* XDMF's topology types: name, code in a Mixed topology, nodes (0: a count follows the code in a Mixed
 * topology), and the VTK type of the same cell (its table says dropped or kept). */
typedef struct topology_kind {
    const char *name, *alias;
    int code, nodes, vtk_type;
} topology_kind;

static const topology_kind kinds[] = {
    {"Polyvertex", NULL, 0x1, 0, 2},        {"Polyline", NULL, 0x2, 0, 4},
    {"Polygon", NULL, 0x3, 0, 7},           {"Triangle", NULL, 0x4, 3, 5},
    {"Quadrilateral", "Quad", 0x5, 4, 9},   {"Tetrahedron", "Tet", 0x6, 4, 10},
    {"Pyramid", NULL, 0x7, 5, 14},          {"Wedge", NULL, 0x8, 6, 13},
    {"Hexahedron", "Hex", 0x9, 8, 12},      {"Edge_3", NULL, 0x22, 3, 21},
    {"Quadrilateral_9", "Quad_9", 0x23, 9, 28}, {"Triangle_6", "Tri_6", 0x24, 6, 22},
    {"Quadrilateral_8", "Quad_8", 0x25, 8, 23}, {"Tetrahedron_10", "Tet_10", 0x26, 10, 24},
    {"Pyramid_13", NULL, 0x27, 13, 27},     {"Wedge_15", NULL, 0x28, 15, 26},
    {"Wedge_18", NULL, 0x29, 18, 32},       {"Hexahedron_20", "Hex_20", 0x30, 20, 25},
    {"Hexahedron_24", "Hex_24", 0x31, 24, 33}, {"Hexahedron_27", "Hex_27", 0x32, 27, 29},
};
#define KIND_COUNT (sizeof kinds / sizeof kinds[0])

static const topology_kind *kind_named(const char *name)
{
    for (size_t i = 0; name && i < KIND_COUNT; i++)
        if (!strcasecmp(name, kinds[i].name) || (kinds[i].alias && !strcasecmp(name, kinds[i].alias)))
            return &kinds[i];
    return NULL;
}

static const topology_kind *kind_coded(double code)
{
    for (size_t i = 0; i < KIND_COUNT; i++)
        if ((double)kinds[i].code == code)
            return &kinds[i];
    return NULL;
}

/* ---- The grid's parts --------------------------------------------------------------------------- */

static int add_part(xdmf_reader *r, xdmf_grid *g, const xdmf_node *n)
{
    const xdmf_node **slot = xdmf_is(n, "Topology") ? &g->topology : xdmf_is(n, "Geometry") ? &g->geometry
                             : xdmf_is(n, "Time")   ? &g->time : NULL;
    if (slot && *slot && *slot != n)
        return xdmf_fail(r, n, "expected one <%s> in Grid '%.60s', found a second (the first on line %ld)", n->name,
                         xdmf_attr(g->grid, "Name") ? xdmf_attr(g->grid, "Name") : "", (*slot)->line);
    if (slot) {
        *slot = n;
        return xdmf_follow_reference(r, n, slot);
    }
    if (!xdmf_is(n, "Attribute"))
        return 0; /* Information and such */
    if (g->attribute_count == XDMF_MAX_ATTRIBUTES)
        return xdmf_fail(r, n, "expected at most %d Attributes in one Grid, found more", XDMF_MAX_ATTRIBUTES);
    return xdmf_follow_reference(r, n, &g->attributes[g->attribute_count++]);
}

/* An xi:include: the elements its xpointer names stand in its place (another file's are refused). */
static int add_included(xdmf_reader *r, xdmf_grid *g, const xdmf_node *inc)
{
    const char *href = xdmf_attr(inc, "href"), *xpointer = xdmf_attr(inc, "xpointer");
    if (href && href[0])
        return xdmf_fail(r, inc, "xi:include of another file (href=\"%.100s\") is not read", href);
    size_t len = xpointer ? strlen(xpointer) : 0;
    if (!xpointer || len < 10 || strncmp(xpointer, "xpointer(", 9) || xpointer[len - 1] != ')')
        return xdmf_fail(r, inc, "expected xpointer=\"xpointer(/path)\", found %s%.100s%s", xpointer ? "\"" : "",
                         xpointer ? xpointer : "none", xpointer ? "\"" : "");
    xdmf_node **found;
    size_t count;
    if (xdmf_select(r, inc, xpointer + 9, len - 10, &found, &count))
        return -1;
    int rc = count ? 0 : xdmf_fail(r, inc, "xpointer \"%.100s\" names no element", xpointer);
    for (size_t i = 0; rc == 0 && i < count; i++)
        rc = xdmf_is(found[i], "include") ? xdmf_fail(r, inc, "xpointer names another xi:include (not followed)")
                                         : add_part(r, g, found[i]);
    free(found);
    return rc;
}

int xdmf_grid_parts(xdmf_reader *r, const xdmf_node *grid, xdmf_grid *parts)
{
    memset(parts, 0, sizeof *parts);
    parts->grid = grid;
    for (const xdmf_node *c = grid->first; c; c = c->next)
        if (xdmf_is(c, "include") ? add_included(r, parts, c) : add_part(r, parts, c))
            return -1;
    const char *name = xdmf_attr(grid, "Name");
    if (!parts->topology || !parts->geometry)
        return xdmf_fail(r, grid, "Grid '%.60s': expected a Topology and a Geometry, found no %s", name ? name : "",
                         parts->topology ? "Geometry" : "Topology");
    return 0;
}

int xdmf_grid_has_volumes(const xdmf_grid *parts)
{
    const char *type = xdmf_attr(parts->topology, "TopologyType");
    if (!type)
        type = xdmf_attr(parts->topology, "Type");
    const topology_kind *k = kind_named(type);
    if (!k)
        return 1; /* Mixed, or a type read_cells refuses with a message */
    const tpk_cell_type_info *info = tpk_cell_type(k->vtk_type);
    return info && info->dim == 3;
}

/* ---- Points ------------------------------------------------------------------------------------- */

static int read_points(xdmf_reader *r, const xdmf_node *geometry, tpk_mesh *out)
{
    const char *type = xdmf_attr(geometry, "GeometryType");
    if (!type)
        type = xdmf_attr(geometry, "Type");
    int split = type && !strcasecmp(type, "X_Y_Z"), dim = type && !strcasecmp(type, "XY") ? 2 : 3;
    if (type && strcasecmp(type, "XYZ") && strcasecmp(type, "XY") && !split)
        return xdmf_fail(r, geometry, "expected GeometryType XYZ, XY or X_Y_Z, found \"%.40s\" (structured "
                         "geometries are not read)", type);
    xdmf_values v[3];
    memset(v, 0, sizeof v);
    const xdmf_node *item = xdmf_first_item(r, geometry);
    int rc = item ? 0 : -1;
    for (int k = 0; rc == 0 && k < (split ? 3 : 1); k++) {
        if (k && !(item = item->next))
            rc = xdmf_fail(r, geometry, "X_Y_Z: expected three DataItems (x, y, z), found %d", k);
        while (rc == 0 && k && item && !xdmf_is(item, "DataItem") && (item = item->next) == NULL)
            rc = xdmf_fail(r, geometry, "X_Y_Z: expected three DataItems (x, y, z), found %d", k);
        if (rc == 0)
            rc = xdmf_read_item(r, item, &v[k]);
        if (rc == 0 && k && v[k].count != v[0].count)
            rc = xdmf_fail(r, item, "X_Y_Z: expected as many values as x has (%lld), found %lld",
                           (long long)v[0].count, (long long)v[k].count);
    }
    if (rc == 0 && !split && v[0].count % dim)
        rc = xdmf_fail(r, item, "Geometry %s: expected a multiple of %d values, found %lld", dim == 2 ? "XY" : "XYZ",
                       dim, (long long)v[0].count);
    int64_t n = split ? v[0].count : v[0].count / dim;
    if (rc == 0 && n > INT32_MAX)
        rc = xdmf_fail(r, geometry, "expected at most 2^31-1 points, found %lld", (long long)n);
    if (rc == 0 && !(out->points = malloc(sizeof *out->points * 3 * (size_t)(n ? n : 1))))
        rc = xdmf_fail(r, geometry, "out of memory for %lld points", (long long)n);
    for (int64_t p = 0; rc == 0 && p < n; p++)
        for (int k = 0; k < 3; k++)
            out->points[3 * p + k] = split ? v[k].v[p] : k < dim ? v[0].v[dim * p + k] : 0.0;
    if (rc == 0)
        out->point_count = n;
    for (int k = 0; k < 3; k++)
        free(v[k].v);
    return rc;
}

/* ---- Cells -------------------------------------------------------------------------------------- */

/* The topology being walked: one kind for all cells, or Mixed (kind == NULL) with codes inline. */
typedef struct cell_walk {
    const xdmf_node *topology, *item;
    const xdmf_values *values;
    const topology_kind *kind;
    int64_t nodes_per;         /* uniform topology: nodes per cell */
    int64_t pos, cell;         /* next value, next cell */
} cell_walk;

/* The next cell: its kind, and its nodes values[*first .. *first + *n). 0 or -1. */
static int next_cell(xdmf_reader *r, cell_walk *w, const topology_kind **kind, int64_t *first, int64_t *n)
{
    const double *v = w->values->v;
    int64_t count = w->values->count;
    if (w->kind) {
        *kind = w->kind, *first = w->pos, *n = w->nodes_per;
    } else {
        const topology_kind *k = w->pos < count ? kind_coded(v[w->pos]) : NULL;
        if (!k)
            return xdmf_fail(r, w->item, "Mixed topology, cell %lld (value %lld): expected an XDMF cell type code, "
                             "found %.17g", (long long)w->cell, (long long)w->pos, w->pos < count ? v[w->pos] : -1.0);
        int64_t at = w->pos + 1, nodes = k->nodes;
        if (!nodes) {
            if (at >= count || !(v[at] >= 1 && v[at] <= 1e9))
                return xdmf_fail(r, w->item, "Mixed topology, cell %lld (%s): expected its node count, found %s",
                                 (long long)w->cell, k->name, at < count ? "a value < 1" : "the end of the data");
            nodes = (int64_t)v[at++];
        }
        *kind = k, *first = at, *n = nodes;
    }
    if (*first + *n > count)
        return xdmf_fail(r, w->item, "cell %lld (%s): expected %lld node ids, found the end of the data (%lld values)",
                         (long long)w->cell, (*kind)->name, (long long)*n, (long long)count);
    w->pos = *first + *n;
    w->cell++;
    return 0;
}

/* Topology type, NodesPerElement and NumberOfElements (or Dimensions) into the walk; *cells the count. */
static int start_walk(xdmf_reader *r, const xdmf_node *topology, const xdmf_values *values, cell_walk *w,
                      int64_t *cells)
{
    memset(w, 0, sizeof *w);
    w->topology = topology, w->values = values, w->item = xdmf_first_item(r, topology);
    const char *type = xdmf_attr(topology, "TopologyType"), *per = xdmf_attr(topology, "NodesPerElement"),
               *number = xdmf_attr(topology, "NumberOfElements");
    if (!type)
        type = xdmf_attr(topology, "Type");
    int mixed = type && !strcasecmp(type, "Mixed");
    w->kind = kind_named(type);
    if (!mixed && !w->kind)
        return xdmf_fail(r, topology, "expected TopologyType Tetrahedron, Pyramid, Wedge, Hexahedron, Mixed (or a "
                         "surface, line or higher-order type), found %s%.40s%s", type ? "\"" : "",
                         type ? type : "none", type ? "\"" : "");
    int64_t n = -1;
    if (number && (tpk_parse_int64(number, strlen(number), &n) || n < 0))
        return xdmf_fail(r, topology, "expected NumberOfElements >= 0, found \"%.40s\"", number);
    if (w->kind) {
        w->nodes_per = w->kind->nodes;
        int64_t given;
        if (per && (tpk_parse_int64(per, strlen(per), &given) || given < 1 || given > 1000 ||
                    (w->nodes_per && given != w->nodes_per)))
            return xdmf_fail(r, topology, "%s: expected NodesPerElement %s, found \"%.40s\"", w->kind->name,
                             w->nodes_per ? "as the type has" : "from 1 to 1000", per);
        if (!w->nodes_per && !per)
            return xdmf_fail(r, topology, "%s: expected a NodesPerElement attribute, found none", w->kind->name);
        if (!w->nodes_per)
            w->nodes_per = given;
        if (n < 0)
            n = values->count / w->nodes_per;
        if (n > values->count || n * w->nodes_per != values->count) /* (n <= count: no overflow below) */
            return xdmf_fail(r, w->item, "%s topology: expected %.0f node ids (%lld cells of %lld nodes), found %lld",
                             w->kind->name, (double)n * (double)w->nodes_per, (long long)n, (long long)w->nodes_per,
                             (long long)values->count);
    } else if (n < 0)
        return xdmf_fail(r, topology, "Mixed: expected a NumberOfElements attribute, found none");
    if (n > values->count || n > INT32_MAX)
        return xdmf_fail(r, topology, "NumberOfElements %lld cannot be held in %lld values", (long long)n,
                         (long long)values->count);
    *cells = n;
    return 0;
}

/* Counts per VTK type of dropped cells, for the warning, and of what is kept. */
typedef struct cell_tally {
    int64_t dropped[256], drop_total, kept, conn_size;
} cell_tally;

/* First pass: check every cell's node ids and count what is kept. */
static int scan_cells(xdmf_reader *r, cell_walk *w, int64_t cells, int64_t point_count, uint8_t *keep,
                      cell_tally *t)
{
    for (int64_t c = 0; c < cells; c++) {
        const topology_kind *k;
        int64_t first, n;
        if (next_cell(r, w, &k, &first, &n))
            return -1;
        tpk_cell_rule rule = tpk_cell_rule_for(k->vtk_type);
        for (int64_t j = 0; j < n && rule.kind != TPK_RULE_DROP; j++) {
            double id = w->values->v[first + j];
            if (!(id >= 0 && id < (double)point_count))
                return xdmf_fail(r, w->item, "cell %lld (%s) uses point id %.17g, expected 0 to %lld", (long long)c,
                                 k->name, id, (long long)point_count - 1);
        }
        keep[c] = rule.kind != TPK_RULE_DROP;
        if (rule.kind == TPK_RULE_DROP)
            t->dropped[k->vtk_type]++, t->drop_total++;
        if (keep[c])
            t->kept++, t->conn_size += n;
    }
    if (w->pos != w->values->count)
        return xdmf_fail(r, w->item, "Mixed topology: expected %lld values for its %lld cells, found %lld",
                         (long long)w->pos, (long long)cells, (long long)w->values->count);
    return 0;
}

/* Second pass: the kept cells into out. */
static int copy_cells(xdmf_reader *r, cell_walk *w, int64_t cells, const cell_tally *t, tpk_mesh *out)
{
    out->cell_types = malloc((size_t)(t->kept ? t->kept : 1));
    out->cell_offsets = malloc(sizeof *out->cell_offsets * (size_t)(t->kept + 1));
    out->cell_conn = malloc(sizeof *out->cell_conn * (size_t)(t->conn_size ? t->conn_size : 1));
    if (!out->cell_types || !out->cell_offsets || !out->cell_conn)
        return xdmf_fail(r, w->topology, "out of memory for %lld cells", (long long)t->kept);
    w->pos = w->cell = 0;
    int64_t k = 0, o = 0;
    out->cell_offsets[0] = 0;
    for (int64_t c = 0; c < cells; c++) {
        const topology_kind *kind;
        int64_t first, n;
        next_cell(r, w, &kind, &first, &n); /* checked by scan_cells */
        tpk_cell_rule rule = tpk_cell_rule_for(kind->vtk_type);
        if (rule.kind == TPK_RULE_DROP)
            continue;
        for (int64_t j = 0; j < n; j++)
            out->cell_conn[o++] = (int32_t)w->values->v[first + j];
        out->cell_types[k] = rule.out_type;
        out->cell_offsets[++k] = o;
    }
    out->cell_count = k;
    return 0;
}

int xdmf_read_cells(xdmf_reader *r, const xdmf_grid *parts, tpk_mesh *out, xdmf_cells *cells)
{
    memset(cells, 0, sizeof *cells);
    if (read_points(r, parts->geometry, out))
        return -1;
    const xdmf_node *item = xdmf_first_item(r, parts->topology);
    xdmf_values values;
    if (!item || xdmf_read_item(r, item, &values))
        return -1;
    cell_walk w;
    cell_tally *t = calloc(1, sizeof *t);
    int64_t count = 0;
    int rc = !t ? xdmf_fail(r, parts->topology, "out of memory") : start_walk(r, parts->topology, &values, &w, &count);
    if (rc == 0 && !(cells->keep = malloc((size_t)(count ? count : 1))))
        rc = xdmf_fail(r, parts->topology, "out of memory for %lld cells", (long long)count);
    if (rc == 0)
        rc = scan_cells(r, &w, count, out->point_count, cells->keep, t);
    const char *name = xdmf_attr(parts->grid, "Name");
    char grid[128];
    snprintf(grid, sizeof grid, "%s: Grid '%.60s'", r->name, name ? name : "");
    if (rc == 0 && t->drop_total)
        tpk_warn_cell_counts(r->diag, grid, t->dropped, t->drop_total, "dropped cells that are not volumes:");
    if (rc == 0)
        rc = copy_cells(r, &w, count, t, out);
    cells->source_count = count;
    free(t);
    free(values.v);
    return rc;
}

/* ---- Attributes --------------------------------------------------------------------------------- */

int xdmf_read_attribute(xdmf_reader *r, const xdmf_node *attribute, const tpk_mesh *mesh, const xdmf_cells *cells,
                        float **values, int *association, int *components)
{
    const char *name = xdmf_attr(attribute, "Name"), *center = xdmf_attr(attribute, "Center"),
               *type = xdmf_attr(attribute, "AttributeType");
    if (!type)
        type = xdmf_attr(attribute, "Type");
    if (!name)
        name = "unnamed";
    int on_cells = center && !strcasecmp(center, "Cell");
    if (center && !on_cells && strcasecmp(center, "Node")) {
        tpk_diag_warn(r->diag, "%s: line %ld: Attribute '%.60s': Center \"%.20s\" skipped (Node and Cell are read)",
                      r->name, attribute->line, name, center);
        return 1;
    }
    const xdmf_node *item = xdmf_first_item(r, attribute);
    xdmf_values v;
    if (!item || xdmf_read_item(r, item, &v))
        return -1;
    int64_t tuples = on_cells ? cells->source_count : mesh->point_count;
    int64_t comps = tuples ? v.count / tuples : 1;
    int scalar = !type || !strcasecmp(type, "Scalar");
    if (!tuples || v.count % tuples || comps < 1 || comps > 1024 || (scalar && comps != 1)) {
        char place[96];
        snprintf(place, sizeof place, "line %ld", item->line);
        int lenient = tpk_diag_field_problem(r->diag, name, (long long)(scalar ? tuples : 3 * tuples),
                                             (long long)v.count, place) == 0;
        free(v.v);
        if (lenient)
            return 1;
        return xdmf_fail(r, item, "Attribute '%.60s' (%s, Center %s): expected %s%lld values (one %s per %s), "
                         "found %lld", name, type ? type : "Scalar", on_cells ? "Cell" : "Node",
                         scalar ? "" : "a multiple of ", (long long)tuples, scalar ? "value" : "tuple",
                         on_cells ? "cell" : "point", (long long)v.count);
    }
    int64_t kept = on_cells ? mesh->cell_count : tuples;
    float *out = malloc(sizeof *out * (size_t)(kept ? kept : 1) * (size_t)comps);
    if (!out) {
        free(v.v);
        return xdmf_fail(r, item, "out of memory");
    }
    for (int64_t t = 0, k = 0; t < tuples; t++) {
        if (on_cells && !cells->keep[t])
            continue;
        for (int64_t j = 0; j < comps; j++)
            out[k * comps + j] = (float)v.v[t * comps + j];
        k++;
    }
    free(v.v);
    *values = out;
    *association = on_cells ? TPK_ASSOC_TET : TPK_ASSOC_POINT;
    *components = (int)comps;
    return 0;
}
