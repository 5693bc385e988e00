/* CGNS importer (.cgns, HDF5 or ADF) through the CGNS mid-level library: the first base of cell
 * dimension 3, every zone of it merged into one mesh. Zones keep their own vertices: points on a zone
 * interface appear once per zone (`--merge-duplicates` welds them). Unstructured zones come from
 * cgns_sections.c; a structured zone's (i, j, k) grid becomes hexahedra, i fastest, in the order CGNS
 * numbers its cells, so CellCenter data lines up. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "base/parallel.h"
#include "import/importers.h"
#include "import_cgns_internal.h"
#include "mesh/polyhedron.h"

/* Structured zone: vertex counts along i, j, k; cells from their product. */
static int scan_structured(const cgns_reader *r, cgns_zone *zone, const cgsize_t *size)
{
    int64_t cells = 1, vertices = 1;
    for (int a = 0; a < 3; a++) {
        zone->dims[a] = size[a];
        if (size[a] < 2 || size[a] > r->file_size)
            return tpk_diag_fail(r->diag, "%s: structured zone '%s' has %lld vertices along %c, expected 2 to %lld "
                                 "(the file's size)", r->path, zone->name, (long long)size[a], "ijk"[a],
                                 (long long)r->file_size);
        cells *= size[a] - 1;
        vertices *= size[a]; /* at most file size cubed so far: no overflow before the check in scan_zone */
        if (vertices > r->file_size)
            break;
    }
    zone->vertices = vertices;
    zone->cells = cells;
    zone->conn = 8 * cells;
    return 0;
}

/* Zone type and sizes, and (unstructured) its sections. */
static int scan_zone(const cgns_reader *r, cgns_zone *zone)
{
    cgsize_t size[9] = {0};
    CGNS_ENUMT(ZoneType_t) type;
    if (cg_zone_type(r->fn, r->base, zone->index, &type) || cg_zone_read(r->fn, r->base, zone->index, zone->name, size))
        return CGNS_FAIL(r, "cannot read zone %d", zone->index);
    zone->structured = type == CGNS_ENUMV(Structured);
    int rc = zone->structured ? scan_structured(r, zone, size) : 0;
    if (!zone->structured) {
        if (type != CGNS_ENUMV(Unstructured))
            return tpk_diag_fail(r->diag, "%s: zone '%s' has zone type %s, expected Structured or Unstructured",
                                 r->path, zone->name, cg_ZoneTypeName(type));
        zone->vertices = size[0];
        rc = cgns_sections_load(r, zone);
    }
    /* Coordinates take at least a byte per vertex in the file: a larger count is a damaged header. */
    if (rc == 0 && (zone->vertices < 1 || zone->vertices > r->file_size))
        return tpk_diag_fail(r->diag, "%s: zone '%s' declares %lld vertices, expected 1 to %lld (the file's size)",
                             r->path, zone->name, (long long)zone->vertices, (long long)r->file_size);
    return rc;
}

/* One axis of a zone's coordinates into the mesh's points, on all threads (the library reads serially). */
typedef struct axis_job {
    double *points; /* the zone's first point */
    const double *values;
    int axis;
} axis_job;

static void axis_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const axis_job *job = ctx;
    (void)worker;
    for (int64_t v = begin; v < end; v++)
        job->points[3 * v + job->axis] = job->values[v];
}

/* The zone's CoordinateX/Y/Z (Cartesian only) into out->points from zone->first_point. */
static int read_coordinates(const cgns_reader *r, const cgns_zone *zone, tpk_mesh *out)
{
    static const char *const names[3] = {"CoordinateX", "CoordinateY", "CoordinateZ"};
    cgsize_t lo[3] = {1, 1, 1}, hi[3];
    for (int a = 0; a < 3; a++)
        hi[a] = zone->structured ? (cgsize_t)zone->dims[a] : (cgsize_t)zone->vertices;
    double *xyz = malloc(sizeof *xyz * (size_t)zone->vertices);
    if (!xyz)
        return tpk_diag_fail(r->diag, "%s: out of memory for zone '%s'", r->path, zone->name);
    for (int a = 0; a < 3; a++) {
        if (cg_coord_read(r->fn, r->base, zone->index, names[a], CGNS_ENUMV(RealDouble), lo, hi, xyz)) {
            free(xyz);
            return CGNS_FAIL(r, "zone '%s': cannot read %s, expected %lld values (Cartesian coordinates)",
                             zone->name, names[a], (long long)zone->vertices);
        }
        axis_job job = {out->points + 3 * zone->first_point, xyz, a};
        tpk_parallel_for(zone->vertices, cgns_threads(zone->vertices), axis_range, &job);
    }
    free(xyz);
    return 0;
}

/* A structured grid is right- or left-handed as a whole, by how its writer ordered i, j and k; CGNS
 * leaves that open. The sign of the summed corner volumes says which, so hexes are built positive. */
static void find_handedness(cgns_zone *zone, const double *points)
{
    const int64_t ni = zone->dims[0], nj = zone->dims[1], nk = zone->dims[2];
    double sum = 0;
    for (int64_t k = 0; k + 1 < nk; k++)
        for (int64_t j = 0; j + 1 < nj; j++)
            for (int64_t i = 0; i + 1 < ni; i++) {
                const double *o = points + 3 * (i + ni * (j + nj * k));
                const double *a = o + 3, *b = o + 3 * ni, *c = o + 3 * ni * nj;
                double u[3], v[3], w[3];
                for (int d = 0; d < 3; d++)
                    u[d] = a[d] - o[d], v[d] = b[d] - o[d], w[d] = c[d] - o[d];
                sum += u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                       u[2] * (v[0] * w[1] - v[1] * w[0]);
            }
    zone->left_handed = sum < 0;
}

/* Hexahedra of a structured zone, i fastest (CGNS's cell order): VTK's bottom quad at k, top at k + 1,
 * swapped for a left-handed grid. */
static void emit_structured(cgns_zone *zone, tpk_mesh *out)
{
    find_handedness(zone, out->points + 3 * zone->first_point);
    const int64_t ni = zone->dims[0], nj = zone->dims[1], nk = zone->dims[2];
    const int64_t quad[4] = {0, 1, 1 + ni, ni}, layer = ni * nj;
    int64_t c = out->cell_count, at = out->cell_offsets[c];
    for (int64_t k = 0; k + 1 < nk; k++)
        for (int64_t j = 0; j + 1 < nj; j++)
            for (int64_t i = 0; i + 1 < ni; i++, c++) {
                int64_t base = zone->first_point + i + ni * (j + nj * k);
                out->cell_types[c] = TPK_CELL_HEXAHEDRON;
                out->cell_offsets[c] = at;
                for (int h = 0; h < 8; h++) {
                    int top = (h >= 4) != zone->left_handed;
                    out->cell_conn[at++] = (int32_t)(base + quad[h % 4] + (top ? layer : 0));
                }
            }
    out->cell_count = c;
    out->cell_offsets[c] = at;
}

/* The first base of cell and physical dimension 3. */
static int find_base(cgns_reader *r)
{
    int bases = 0;
    if (cg_nbases(r->fn, &bases))
        return CGNS_FAIL(r, "cannot read the bases%s", "");
    char name[33], seen[256] = "";
    for (int b = 1; b <= bases; b++) {
        int cell_dim = 0, phys_dim = 0;
        if (cg_base_read(r->fn, b, name, &cell_dim, &phys_dim))
            return CGNS_FAIL(r, "cannot read base %d", b);
        if (cell_dim == 3 && phys_dim == 3) {
            r->base = b;
            if (b < bases)
                tpk_diag_warn(r->diag, "%s: read base '%s'; %d later bases left out", r->path, name, bases - b);
            return 0;
        }
        size_t used = strlen(seen);
        snprintf(seen + used, sizeof seen - used, "%s'%s' (cell dimension %d, physical %d)", used ? ", " : "",
                 name, cell_dim, phys_dim);
    }
    return tpk_diag_fail(r->diag, "%s: expected a base of cell and physical dimension 3 (a volume mesh), found %s",
                         r->path, bases ? seen : "no base");
}

static int alloc_mesh(const cgns_reader *r, tpk_mesh *out, int64_t points, int64_t cells, int64_t conn)
{
    out->points = malloc(sizeof *out->points * 3 * (size_t)points);
    out->cell_types = malloc((size_t)cells + 1);
    out->cell_offsets = calloc((size_t)cells + 1, sizeof *out->cell_offsets);
    out->cell_conn = malloc(sizeof *out->cell_conn * (size_t)(conn + 1));
    if (!out->points || !out->cell_types || !out->cell_offsets || !out->cell_conn)
        return tpk_diag_fail(r->diag, "%s: out of memory for %lld points and %lld cells", r->path, (long long)points,
                             (long long)cells);
    out->point_count = points;
    return 0;
}

/* Every zone scanned, then points and cells in zone order. */
static int read_zones(cgns_reader *r, cgns_zone *zones, int zone_count, tpk_mesh *out)
{
    int64_t points = 0, cells = 0, conn = 0, dropped = 0, reduced = 0;
    for (int z = 0; z < zone_count; z++) {
        zones[z].index = z + 1;
        if (scan_zone(r, &zones[z]))
            return -1;
        zones[z].first_point = points, zones[z].first_cell = cells;
        points += zones[z].vertices, cells += zones[z].cells, conn += zones[z].conn;
        dropped += zones[z].dropped, reduced += zones[z].reduced;
    }
    if (points > INT32_MAX || conn > INT32_MAX)
        return tpk_diag_fail(r->diag, "%s: %lld points and %lld connectivity entries, expected at most %d of each",
                             r->path, (long long)points, (long long)conn, INT32_MAX);
    if (cells == 0)
        return tpk_diag_fail(r->diag, "%s: no volume cells in %d zones: expected TETRA, PYRA, PENTA, HEXA, MIXED or "
                             "NFACE_n elements, or a structured zone; found %lld faces, edges or nodes", r->path,
                             zone_count, (long long)dropped);
    if (dropped)
        tpk_diag_warn(r->diag, "%s: left out %lld elements that are not volumes (faces, edges, nodes)", r->path,
                      (long long)dropped);
    if (reduced)
        tpk_diag_warn(r->diag, "%s: reduced %lld volume elements to their corner nodes: kept whole are orders 1 "
                      "and 2 (TETRA_10, PYRA_13/14, PENTA_15/18, HEXA_20/27), not TETRA_16/20, PYRA_21 and up, "
                      "PENTA_24 and up, HEXA_32 and up", r->path, (long long)reduced);
    if (zone_count > 1)
        tpk_diag_warn(r->diag, "%s: %d zones merged, each with its own vertices (points on zone interfaces are "
                      "not joined; --merge-duplicates welds them)", r->path, zone_count);
    if (alloc_mesh(r, out, points, cells, conn))
        return -1;
    for (int z = 0; z < zone_count; z++) {
        if (read_coordinates(r, &zones[z], out))
            return -1;
        if (zones[z].structured)
            emit_structured(&zones[z], out);
        else if (cgns_sections_emit(r, &zones[z], out))
            return -1;
    }
    if (tpk_mesh_take_face_streams(out))
        return tpk_diag_fail(r->diag, "%s: out of memory for the polyhedra", r->path);
    return 0;
}

static int read_file(cgns_reader *r, tpk_mesh *out)
{
    int zone_count = 0;
    if (find_base(r))
        return -1;
    if (cg_nzones(r->fn, r->base, &zone_count))
        return CGNS_FAIL(r, "cannot read the zones of base %d", r->base);
    if (zone_count < 1)
        return tpk_diag_fail(r->diag, "%s: base %d has no zones, expected at least one", r->path, r->base);
    cgns_zone *zones = calloc((size_t)zone_count, sizeof *zones);
    if (!zones)
        return tpk_diag_fail(r->diag, "%s: out of memory for %d zones", r->path, zone_count);
    int rc = read_zones(r, zones, zone_count, out);
    if (rc == 0)
        rc = cgns_read_times(r, out);
    if (rc == 0)
        rc = cgns_read_solutions(r, zones, zone_count, out);
    for (int z = 0; z < zone_count; z++)
        cgns_sections_free(&zones[z]);
    free(zones);
    return rc;
}

int tpk_import_cgns(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    if (!out || !path)
        return tpk_diag_fail(diag, "%s: no path or output mesh given", path ? path : "(null)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    struct stat st;
    if (stat(path, &st) != 0)
        return tpk_diag_fail(diag, "%s: cannot open the file", path);
    cgns_reader r = {.path = path, .file_size = (int64_t)st.st_size, .diag = diag};
    /* cg_is_cgns first: cg_open on a file that is neither HDF5 nor ADF may leave a half-open handle. */
    int file_type = 0;
    if (cg_is_cgns(path, &file_type))
        return tpk_diag_fail(diag, "%s: cannot open it as a CGNS file: expected an HDF5 or ADF file with a "
                             "CGNSLibraryVersion node (or it is cut short or damaged)", path);
    if (cg_open(path, CG_MODE_READ, &r.fn))
        return CGNS_FAIL(&r, "cannot open it as a CGNS file%s", "");
    int rc = read_file(&r, out);
    cg_close(r.fn);
    if (rc == 0)
        snprintf(out->format, sizeof out->format, "cgns");
    else
        tpk_mesh_free(out);
    return rc ? -1 : 0;
}
