/* Private to the XDMF importer (import_xdmf*.c). XDMF's XML is small and refers back and forth (meshio's
 * time series include a mesh Grid written after them), so expat builds a tree first and the importer
 * reads the tree. Who owns what, top to bottom (a file calls only files below it, never back up):
 *   import_xdmf.c        tpk_import_xdmf, tpk_import_xdmf_memory: the Domain's grids, time steps, fields
 *   import_xdmf_grid.c   xdmf_grid_parts, xdmf_read_cells, xdmf_read_attribute (Topology, Geometry,
 *                        Attribute; XInclude and Reference resolved)
 *   import_xdmf_data.c   xdmf_read_item (DataItem: Dimensions, number type, XML text or HDF)
 *   import_xdmf_hdf.c    xdmf_read_hdf (the HDF5 library; a refusal when built without it)
 *   import_xdmf_path.c   xdmf_select (the XPath subset of XInclude xpointers and References)
 *   import_xdmf_tree.c   xdmf_parse_tree, xdmf_tree_free, xdmf_attr, xdmf_is, xdmf_trimmed,
 *                        xdmf_hdf_source
 *   import_xdmf_fail.c   xdmf_fail
 * Not installed. */
#ifndef TPK_IMPORT_XDMF_INTERNAL_H
#define TPK_IMPORT_XDMF_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "import/importers.h"

/* One XML element (or the document node above the root, name "#document"). */
typedef struct xdmf_node {
    char *name;                 /* as written, with any namespace prefix */
    char **attrs;               /* key, value, ..., NULL */
    char *text;                 /* the character data directly inside, NUL-terminated */
    size_t text_len;
    long line;
    struct xdmf_node *parent, *first, *last, *next;
} xdmf_node;

typedef struct xdmf_reader {
    const char *name;           /* the .xdmf file, for messages and for HDF paths relative to it */
    const char *data;
    size_t size;
    int allow_files;            /* 0 in the memory form: HDF data and other files are refused */
    tpk_diag *diag;
    int failed;
    xdmf_node *doc;
    void *hdf;                  /* the HDF5 file kept open between DataItems (import_xdmf_hdf.c) */
    char *hdf_path;
} xdmf_reader;

/* A DataItem's values, as doubles. */
typedef struct xdmf_values {
    double *v;
    int64_t count;
    int64_t dims[8];
    int rank;
    int integer;                /* NumberType Int or UInt */
} xdmf_values;

/* ---- Messages (import_xdmf_fail.c) ----------------------------------------------------------------
 * "FILE: line L: <Element>: message" (node NULL: "FILE: message"). The first failure wins the diag;
 * returns -1. */
int xdmf_fail(xdmf_reader *r, const xdmf_node *at, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* ---- The tree (import_xdmf_tree.c) --------------------------------------------------------------- */
/* Parse data[0 .. size) into r->doc. 0 or -1. */
int xdmf_parse_tree(xdmf_reader *r);
void xdmf_tree_free(xdmf_node *doc);
/* The value of attribute `key` (exact case), or NULL. */
const char *xdmf_attr(const xdmf_node *n, const char *key);
/* The element's name without a namespace prefix equals `name` (any case). */
int xdmf_is(const xdmf_node *n, const char *name);
/* The element's text without leading and trailing blanks: *len gets its length. */
const char *xdmf_trimmed(const xdmf_node *n, size_t *len);

/* A Format="HDF" DataItem's text "file.h5:/path/to/dataset": 0 with `path` the file relative to the
 * .xdmf file's folder (unless absolute) and *dataset pointing at "/path/to/dataset" in the text
 * (*dataset_len long); -1 when the text is not of that form (no message). */
int xdmf_hdf_source(const xdmf_reader *r, const xdmf_node *item, char *path, size_t cap, const char **dataset,
                    size_t *dataset_len);

/* ---- XPath subset (import_xdmf_path.c) -------------------------------------------------------------
 * Evaluate an absolute path like /Xdmf/Domain/Grid[@Name="mesh"][1]/Geometry
 * or //Grid[@Name='mesh']/Geometry from the document; *found gets a malloc'd array of *count nodes
 * (free it). `at` is the element that holds the path, for messages. 0 or -1. */
int xdmf_select(xdmf_reader *r, const xdmf_node *at, const char *path, size_t len, xdmf_node ***found,
                size_t *count);
/* Follow an element's Reference attribute (Reference="XML": the path is its text; otherwise the
 * attribute's value is the path) to the one element of the same kind it names, through chains of
 * References. *out = n itself when it has none. 0 or -1. */
int xdmf_follow_reference(xdmf_reader *r, const xdmf_node *n, const xdmf_node **out);

/* ---- HDF5 (import_xdmf_hdf.c) ---------------------------------------------------------------------
 * Read dataset `dataset` of the HDF5 file at `path` into out->v as doubles; its element count must be
 * `want`. `item` is the DataItem, for messages. 0 or -1. */
int xdmf_read_hdf(xdmf_reader *r, const xdmf_node *item, const char *path, const char *dataset, int64_t want,
                  xdmf_values *out);
/* Close the file kept open. */
void xdmf_hdf_close(xdmf_reader *r);

/* ---- DataItems (import_xdmf_data.c) -------------------------------------------------------------- */
/* Read the DataItem `item` (following its Reference): Dimensions, NumberType/DataType and Precision,
 * Format XML (the text) or HDF (file.h5:/path). 0 or -1; free out->v. */
int xdmf_read_item(xdmf_reader *r, const xdmf_node *item, xdmf_values *out);
/* The first DataItem child of `parent` (NULL when none; fails with a message then). */
const xdmf_node *xdmf_first_item(xdmf_reader *r, const xdmf_node *parent);

/* ---- Grids (import_xdmf_grid.c) ------------------------------------------------------------------ */
#define XDMF_MAX_ATTRIBUTES 256

/* A Uniform Grid's parts, after XInclude and Reference. */
typedef struct xdmf_grid {
    const xdmf_node *grid, *topology, *geometry, *time;
    const xdmf_node *attributes[XDMF_MAX_ATTRIBUTES];
    int attribute_count;
} xdmf_grid;

/* Collect the parts of Uniform Grid `grid`. 0 or -1. */
int xdmf_grid_parts(xdmf_reader *r, const xdmf_node *grid, xdmf_grid *parts);
/* Whether the Grid's TopologyType can hold volume cells (Mixed can). */
int xdmf_grid_has_volumes(const xdmf_grid *parts);

/* What xdmf_read_cells kept of the source cells, for cell-centred attributes. */
typedef struct xdmf_cells {
    int64_t source_count;       /* cells in the Topology */
    uint8_t *keep;              /* per source cell: 1 when kept */
} xdmf_cells;

/* Points and volume cells of a grid into `out` (lower-dimensional cells dropped with a warning,
 * higher-order ones whole). 0 or -1; free cells->keep. */
int xdmf_read_cells(xdmf_reader *r, const xdmf_grid *parts, tpk_mesh *out, xdmf_cells *cells);
/* An Attribute of a grid read into `out` as point or cell values of the kept cells: *values (malloc'd,
 * tuples * components floats), *association (TPK_ASSOC_POINT or TPK_ASSOC_TET), *components. Returns 1
 * when the attribute is skipped (Center Edge, Face or Grid; a wrong length read leniently), 0 or -1. */
int xdmf_read_attribute(xdmf_reader *r, const xdmf_node *attribute, const tpk_mesh *mesh, const xdmf_cells *cells,
                        float **values, int *association, int *components);

#endif
