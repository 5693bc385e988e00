/* Duplicate-vertex merging (merge_vertices.h): a representative per point (exact coordinates in a hash
 * table, or a tolerance on a hash grid), a check for cells that collapse, then compaction of the
 * points, the cells and their fields. */
#include "merge_vertices.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/cell_types.h"
#include "tetpack.h"

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

static uint64_t coordinate_bits(double x)
{
    uint64_t bits;
    x = x == 0.0 ? 0.0 : x; /* -0 and +0 compare equal, so they must hash equal */
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

static size_t table_size(int64_t count)
{
    size_t size = 16;
    while (size < 2 * (size_t)count)
        size *= 2;
    return size;
}

/* rep[p] = the lowest id with exactly p's coordinates. Open addressing: the first point inserted with
 * given coordinates is the lowest id, since points are visited in id order. */
static int exact_representatives(const tpk_mesh *mesh, int32_t *rep)
{
    size_t size = table_size(mesh->point_count);
    int32_t *slot = malloc(sizeof *slot * size);
    if (!slot)
        return -1;
    memset(slot, 0xff, sizeof *slot * size);
    for (int64_t p = 0; p < mesh->point_count; p++) {
        const double *x = mesh->points + 3 * p;
        uint64_t h = mix64(coordinate_bits(x[0]) ^ mix64(coordinate_bits(x[1]) ^ mix64(coordinate_bits(x[2]))));
        size_t i = (size_t)h & (size - 1);
        rep[p] = (int32_t)p;
        for (; slot[i] >= 0; i = (i + 1) & (size - 1)) {
            const double *y = mesh->points + 3 * (int64_t)slot[i];
            if (x[0] == y[0] && x[1] == y[1] && x[2] == y[2]) {
                rep[p] = slot[i];
                break;
            }
        }
        if (slot[i] < 0)
            slot[i] = (int32_t)p;
    }
    free(slot);
    return 0;
}

/* A hash grid of kept points: cells of side `cell` (a little over the reach, so that rounding in the
 * cell index never hides a point within reach two cells away), each a linked list through next[]. */
typedef struct grid {
    double lo[3], cell, reach2;
    size_t size;
    int64_t (*key)[3]; /* per slot: the grid cell, valid where head >= 0 */
    int32_t *head;     /* per slot: first kept point in the cell, -1 for an empty slot */
    int32_t *next;     /* per point: the next kept point in its cell */
} grid;

static void grid_cell(const grid *g, const double *x, int64_t cell[3])
{
    for (int k = 0; k < 3; k++)
        cell[k] = (int64_t)floor((x[k] - g->lo[k]) / g->cell);
}

static size_t grid_slot(const grid *g, const int64_t cell[3])
{
    uint64_t h = mix64((uint64_t)cell[0] ^ mix64((uint64_t)cell[1] ^ mix64((uint64_t)cell[2])));
    size_t i = (size_t)h & (g->size - 1);
    while (g->head[i] >= 0 && memcmp(g->key[i], cell, sizeof g->key[i]))
        i = (i + 1) & (g->size - 1);
    return i;
}

/* The lowest-id kept point within reach of x, or -1. */
static int32_t grid_nearest_kept(const grid *g, const double *points, const double *x)
{
    int64_t centre[3], cell[3];
    int32_t best = -1;
    grid_cell(g, x, centre);
    for (int d = 0; d < 27; d++) {
        cell[0] = centre[0] + d % 3 - 1;
        cell[1] = centre[1] + d / 3 % 3 - 1;
        cell[2] = centre[2] + d / 9 - 1;
        for (int32_t q = g->head[grid_slot(g, cell)]; q >= 0; q = g->next[q]) {
            const double *y = points + 3 * (int64_t)q;
            double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
            if (dx * dx + dy * dy + dz * dz <= g->reach2 && (best < 0 || q < best))
                best = q;
        }
    }
    return best;
}

static void bounding_box(const tpk_mesh *mesh, double lo[3], double *diagonal)
{
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    lo[0] = lo[1] = lo[2] = INFINITY;
    for (int64_t p = 0; p < mesh->point_count; p++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->points[3 * p + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    *diagonal = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* rep[p] = the lowest-id kept point within reach, visiting points in id order (see the header). */
static int grid_representatives(const tpk_mesh *mesh, double reach, const double lo[3], int32_t *rep)
{
    grid g = {{lo[0], lo[1], lo[2]}, reach * (1.0 + 1e-9), reach * reach, table_size(mesh->point_count),
              NULL, NULL, NULL};
    g.key = malloc(sizeof *g.key * g.size);
    g.head = malloc(sizeof *g.head * g.size);
    g.next = malloc(sizeof *g.next * (size_t)mesh->point_count);
    int rc = g.key && g.head && g.next ? 0 : -1;
    if (rc == 0)
        memset(g.head, 0xff, sizeof *g.head * g.size);
    for (int64_t p = 0; rc == 0 && p < mesh->point_count; p++) {
        const double *x = mesh->points + 3 * p;
        int32_t near = grid_nearest_kept(&g, mesh->points, x);
        rep[p] = near >= 0 ? near : (int32_t)p;
        if (near >= 0)
            continue;
        int64_t cell[3];
        grid_cell(&g, x, cell);
        size_t i = grid_slot(&g, cell);
        memcpy(g.key[i], cell, sizeof g.key[i]);
        g.next[p] = g.head[i];
        g.head[i] = (int32_t)p;
    }
    free(g.key);
    free(g.head);
    free(g.next);
    return rc;
}

/* A volume cell of fixed node count whose corners now include one point twice; *a, *b its two nodes. */
static int collapses(const tpk_mesh *mesh, int64_t c, const int32_t *rep, int32_t *a, int32_t *b)
{
    const tpk_cell_type_info *kind = tpk_cell_type(mesh->cell_types[c]);
    if (!kind || kind->dim != 3 || kind->nodes <= 0) /* others: skipped or refused by the tetrahedralizer */
        return 0;
    const int32_t *nodes = mesh->cell_conn + mesh->cell_offsets[c];
    int64_t n = mesh->cell_offsets[c + 1] - mesh->cell_offsets[c];
    for (int64_t i = 0; i < n; i++)
        for (int64_t j = i + 1; j < n; j++)
            if (rep[nodes[i]] == rep[nodes[j]]) {
                *a = nodes[i];
                *b = nodes[j];
                return 1;
            }
    return 0;
}

static int refuse_collapsed(const tpk_mesh *mesh, int64_t first, int32_t a, int32_t b, int64_t count,
                            tpk_diag *diag)
{
    const double *pa = mesh->points + 3 * (int64_t)a, *pb = mesh->points + 3 * (int64_t)b;
    return tpk_diag_fail(diag, "cell %lld (a %s) collapses when duplicate points are merged: its points %d "
                               "(%.17g, %.17g, %.17g) and %d (%.17g, %.17g, %.17g) become one; %lld cells collapse "
                               "in all; pass --drop-degenerate to remove them (or merge with a smaller tolerance)",
                         (long long)first, tpk_cell_type(mesh->cell_types[first])->name, a, pa[0], pa[1], pa[2], b,
                         pb[0], pb[1], pb[2], (long long)count);
}

/* Keeps the cells with keep[c]: connectivity, types, offsets and cell-field values move down. */
static void compact_cells(tpk_mesh *mesh, const uint8_t *keep, int32_t *cell_source)
{
    int64_t old_count = mesh->cell_count, kept = 0, conn = 0;
    for (int64_t c = 0; c < old_count; c++) {
        int64_t begin = mesh->cell_offsets[c], n = mesh->cell_offsets[c + 1] - begin;
        if (!keep[c])
            continue;
        memmove(mesh->cell_conn + conn, mesh->cell_conn + begin, sizeof *mesh->cell_conn * (size_t)n);
        mesh->cell_types[kept] = mesh->cell_types[c];
        mesh->cell_offsets[kept] = conn;
        cell_source[kept++] = (int32_t)c;
        conn += n;
    }
    mesh->cell_offsets[kept] = conn;
    for (int i = 0; i < mesh->field_count; i++) {
        tpk_src_field *f = &mesh->fields[i];
        if (f->association == TPK_ASSOC_POINT)
            continue;
        size_t width = (size_t)f->components, out = 0;
        for (int s = 0; s < f->step_count; s++)
            for (int64_t c = 0; c < old_count; c++) {
                if (!keep[c])
                    continue;
                memmove(f->values + out, f->values + ((size_t)s * (size_t)old_count + (size_t)c) * width,
                        sizeof *f->values * width);
                out += width;
            }
    }
    mesh->cell_count = kept;
}

/* Kept points (rep[p] == p) move down in id order; cells are renumbered; point fields keep the kept
 * point's values. rep[] becomes the new id of every source point. */
static void compact_points(tpk_mesh *mesh, int32_t *rep, int32_t *point_source)
{
    int64_t old_count = mesh->point_count, kept = 0;
    for (int64_t p = 0; p < old_count; p++) {
        if (rep[p] != p) {
            rep[p] = rep[rep[p]]; /* the kept point has a lower id: already renumbered */
            continue;
        }
        memmove(mesh->points + 3 * kept, mesh->points + 3 * p, 3 * sizeof *mesh->points);
        point_source[kept] = (int32_t)p;
        rep[p] = (int32_t)kept++;
    }
    for (int64_t i = 0; mesh->cell_offsets && i < mesh->cell_offsets[mesh->cell_count]; i++)
        mesh->cell_conn[i] = rep[mesh->cell_conn[i]];
    for (int i = 0; i < mesh->field_count; i++) {
        tpk_src_field *f = &mesh->fields[i];
        if (f->association != TPK_ASSOC_POINT)
            continue;
        size_t width = (size_t)f->components;
        for (int s = 0; s < f->step_count; s++)
            for (int64_t k = 0; k < kept; k++)
                memmove(f->values + ((size_t)s * (size_t)kept + (size_t)k) * width,
                        f->values + ((size_t)s * (size_t)old_count + (size_t)point_source[k]) * width,
                        sizeof *f->values * width);
    }
    mesh->point_count = kept;
}

static int representatives(const tpk_mesh *mesh, double tolerance, int32_t *rep, tpk_diag *diag)
{
    if (tolerance == 0.0)
        return exact_representatives(mesh, rep);
    double lo[3], diagonal;
    bounding_box(mesh, lo, &diagonal);
    double reach = tolerance * diagonal;
    if (!(reach > 0.0) || !isfinite(reach)) {
        tpk_diag_warn(diag, "merging duplicates: the points span no volume (bounding-box diagonal %g); "
                            "merging exactly equal points only", diagonal);
        return exact_representatives(mesh, rep);
    }
    return grid_representatives(mesh, reach, lo, rep);
}

/* Finds the collapsed cells (keep[c] = 0); 0, or -1 with a message when they are not to be dropped. */
static int find_collapsed(const tpk_mesh *mesh, const int32_t *rep, int drop, uint8_t *keep, int64_t *count,
                          tpk_diag *diag)
{
    int64_t first = -1;
    int32_t a = -1, b = -1, na = -1, nb = -1;
    *count = 0;
    for (int64_t c = 0; c < mesh->cell_count; c++) {
        keep[c] = !collapses(mesh, c, rep, &na, &nb);
        if (keep[c])
            continue;
        if (first < 0) {
            first = c;
            a = na;
            b = nb;
        }
        (*count)++;
    }
    if (*count > 0 && !drop)
        return refuse_collapsed(mesh, first, a, b, *count, diag);
    return 0;
}

int tpk_merge_vertices(tpk_mesh *mesh, double tolerance, int drop_collapsed, tpk_merge_report *report,
                       tpk_diag *diag)
{
    memset(report, 0, sizeof *report);
    if (!mesh || (mesh->point_count > 0 && !mesh->points) || mesh->point_count > INT32_MAX ||
        mesh->cell_count > INT32_MAX)
        return tpk_diag_fail(diag, "merging duplicates: invalid source mesh");
    if (!(tolerance == 0.0 || (tolerance >= TPK_MERGE_MIN_TOLERANCE && tolerance <= 1.0)))
        return tpk_diag_fail(diag, "merging duplicates: tolerance %g is outside [%g, 1] (a fraction of the "
                                   "bounding-box diagonal; 0 for exactly equal points)",
                             tolerance, TPK_MERGE_MIN_TOLERANCE);
    size_t np = (size_t)(mesh->point_count ? mesh->point_count : 1), nc = (size_t)(mesh->cell_count ? mesh->cell_count : 1);
    int32_t *rep = malloc(sizeof *rep * np);
    uint8_t *keep = malloc(nc);
    int rc = -1;
    if (!rep || !keep || representatives(mesh, tolerance, rep, diag) != 0) {
        tpk_diag_fail(diag, "merging duplicates: out of memory (%lld points)", (long long)mesh->point_count);
        goto done;
    }
    int64_t kept = 0;
    for (int64_t p = 0; p < mesh->point_count; p++)
        kept += rep[p] == p;
    report->merged_vertices = mesh->point_count - kept;
    if (report->merged_vertices == 0) {
        rc = 0;
        goto done;
    }
    if (find_collapsed(mesh, rep, drop_collapsed, keep, &report->collapsed_cells, diag) != 0)
        goto done;
    report->point_source = malloc(sizeof *report->point_source * (size_t)(kept ? kept : 1));
    if (report->collapsed_cells > 0)
        report->cell_source = malloc(sizeof *report->cell_source * nc);
    if (!report->point_source || (report->collapsed_cells > 0 && !report->cell_source)) {
        tpk_diag_fail(diag, "merging duplicates: out of memory (%lld points)", (long long)mesh->point_count);
        goto done;
    }
    if (report->collapsed_cells > 0)
        compact_cells(mesh, keep, report->cell_source);
    compact_points(mesh, rep, report->point_source);
    rc = 0;
done:
    if (rc != 0)
        tpk_merge_report_free(report);
    free(rep);
    free(keep);
    return rc;
}

void tpk_merge_report_free(tpk_merge_report *report)
{
    free(report->point_source);
    free(report->cell_source);
    report->point_source = NULL;
    report->cell_source = NULL;
}
