/* VTKHDF importer internals (HDF5 only, TPK_HAVE_HDF5): the reader state and the helpers its files
 * share. import_vtkhdf.c opens the file and drives; _data.c reads datasets and attributes with checked
 * shapes; _mesh.c reads the partitions' points and cells and merges the partitions; _fields.c reads
 * PointData and CellData at every step. */
#ifndef TPK_IMPORT_VTKHDF_INTERNAL_H
#define TPK_IMPORT_VTKHDF_INTERNAL_H

#include <stdint.h>

#include <hdf5.h>

#include "base/diag.h"
#include "import/import_file.h"
#include "mesh/mesh.h"

#ifndef TPK_HAVE_HDF5
#error "the VTKHDF reader's files but import_vtkhdf.c need HDF5 (tools/CMakeLists.txt leaves them out without it)"
#endif

/* One time step: the partitions it uses (Steps/PartOffsets, NumberOfParts; the whole file without Steps)
 * and where its field values start (filled per field). */
typedef struct vh_step {
    int64_t part0, parts;
} vh_step;

typedef struct vh_reader {
    const char *name;       /* the file, in messages */
    tpk_diag *diag;
    hid_t root;             /* the /VTKHDF group */
    int64_t version[2];
    int64_t partitions;     /* entries of NumberOfPoints (= NumberOfCells = NumberOfConnectivityIds) */
    int64_t *part_points, *part_cells, *part_conn;      /* per partition */
    int polyhedra;          /* FaceConnectivity & co. are present */
    int64_t *part_faces, *part_face_conn, *part_poly_faces; /* per partition, when polyhedra */
    /* Where each partition starts in the datasets: sums of the counts of the partitions before it. */
    int64_t *point_start, *cell_start, *conn_start, *face_start, *face_conn_start, *poly_face_start;
    int64_t step_count;     /* Steps/NSteps, or 1 */
    vh_step *steps;
    double *times;          /* Steps/Values, or NULL */
    /* The mesh of step 0 as read: per point of its partitions (in partition order) the merged point it
     * became; per merged point the first point that became it; per cell whether it was kept. */
    int64_t raw_points;
    int32_t *merged_of;
    int64_t *first_raw;
    int64_t raw_cells;
    uint8_t *kept;
} vh_reader;

/* "NAME: ..." (import_file.h) */
#define vh_fail(r, ...) tpk_import_fail((r)->diag, NULL, (tpk_import_place){(r)->name, 0, -1, NULL}, __VA_ARGS__)

/* Dataset `path` under /VTKHDF: rank 1 (*cols = 1) or 2; checked against the bytes it stores. -1 with a
 * message naming it when missing or otherwise. */
int vh_shape(vh_reader *r, const char *path, int64_t *rows, int64_t *cols);
/* Rows [first, first + count) of dataset `path` (all its columns, `cols` of them as vh_shape found),
 * converted to `memtype` (H5T_NATIVE_INT64 or H5T_NATIVE_DOUBLE) into dst. `what` says what the rows
 * are for ("partition 2's points") in the message when the dataset is shorter. */
int vh_read_rows(vh_reader *r, const char *path, int64_t first, int64_t count, int64_t cols, hid_t memtype,
                 void *dst, const char *what);
/* A whole 1-D (or N x 1) integer dataset of exactly `want` rows (want < 0: any), malloc'd into *out. */
int vh_read_ints(vh_reader *r, const char *path, int64_t want, int64_t **out, int64_t *count);
/* `name` exists as a link under `group` (an open group or file). */
int vh_exists(hid_t group, const char *name);

/* import_vtkhdf_mesh.c: the partitions' counts and starts (vh_reader's per-partition arrays). */
int vh_read_partitions(vh_reader *r);
/* The mesh of `step` (points merged across its partitions, cells kept by tpk_cell_rule_for, polyhedra
 * as face streams moved into out->faces). With `record`, also fills r->merged_of, first_raw, kept. */
int vh_read_geometry(vh_reader *r, int64_t step, int record, tpk_mesh *out);

/* import_vtkhdf_fields.c: every PointData and CellData array, at every step, as fields of `out`. */
int vh_read_fields(vh_reader *r, tpk_mesh *out);

#endif
