/* CGNS importer, private: the reader's state shared by its three files. import_cgns.c (the entry, zones,
 * coordinates, structured zones) calls down into cgns_sections.c (unstructured element sections) and
 * cgns_solutions.c (time values, FlowSolution fields); neither calls back. */
#ifndef TPK_IMPORT_CGNS_INTERNAL_H
#define TPK_IMPORT_CGNS_INTERNAL_H

#include <cgnslib.h>
#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* A failure with the file's name in front and the CGNS library's last error behind (it says which node
 * of the file it could not read). At least one argument after the format. */
#define CGNS_FAIL(r, fmt, ...)                                                                            \
    tpk_diag_fail((r)->diag, "%s: " fmt " (CGNS library: %s)", (r)->path, __VA_ARGS__, cg_get_error())

typedef struct cgns_reader {
    const char *path;
    int fn, base;          /* open file, the base read (1-based) */
    int64_t file_size;     /* counts are checked against it before allocating */
    int steps;             /* BaseIterativeData NumberOfSteps (0: none) */
    tpk_diag *diag;
} cgns_reader;

/* One element section of an unstructured zone, as read. */
typedef struct cgns_section {
    int index;                     /* S, 1-based */
    char name[33];
    CGNS_ENUMT(ElementType_t) type;
    cgsize_t start, end;           /* element numbers */
    cgsize_t *elements;            /* the ElementConnectivity array */
    cgsize_t *offsets;             /* ElementStartOffset (MIXED, NGON_n, NFACE_n), end-start+2 entries */
    cgsize_t data_size;
} cgns_section;

typedef struct cgns_zone {
    int index;                     /* Z, 1-based */
    char name[33];
    int structured;
    int64_t dims[3];               /* structured: vertices along i, j, k */
    int left_handed;               /* structured: i, j, k form a left-handed frame; hexes are built mirrored */
    int64_t vertices, cells, conn; /* volume cells kept and their cell_conn entries (face streams included) */
    int64_t first_point, first_cell;
    int64_t polyhedra, dropped;    /* NFACE_n cells; elements of lower dimension left out */
    int64_t reduced;               /* volume elements of an order not kept whole, read by their corners */
    int section_count;
    cgns_section *sections;        /* sorted by start */
} cgns_zone;

/* The passes over what the library read run on all threads (convert's --threads) in contiguous ranges
 * of at least this many items, each item written by one worker: the mesh is the same for any count. */
#define CGNS_GRAIN ((int64_t)1 << 16)
int cgns_threads(int64_t items);

/* Unstructured zones: read every section (sorted by element number), count the volume cells they keep
 * and their connectivity entries into zone->cells and zone->conn. Returns 0 or -1 (diag set). */
int cgns_sections_load(const cgns_reader *r, cgns_zone *zone);
/* Append the zone's volume cells in element-number order at out->cell_count, points offset by
 * zone->first_point: VTK types and node orders, polyhedra as face streams in cell_conn (the caller moves
 * them with tpk_mesh_take_face_streams). Returns 0 or -1. */
int cgns_sections_emit(const cgns_reader *r, const cgns_zone *zone, tpk_mesh *out);
void cgns_sections_free(cgns_zone *zone);

/* BaseIterativeData: r->steps, out->step_count and out->times (TimeValues, when present). */
int cgns_read_times(cgns_reader *r, tpk_mesh *out);
/* FlowSolution fields of every zone at Vertex and CellCenter, merged over zones by name (NaN where a
 * zone lacks one), with a step per BaseIterativeData step where ZoneIterativeData points at them. */
int cgns_read_solutions(const cgns_reader *r, const cgns_zone *zones, int zone_count, tpk_mesh *out);

#endif
