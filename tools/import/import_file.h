/* What every importer does around its parser, written once: start with an empty mesh, read a path by
 * mapping the file and parsing its bytes (base/text_scan.h maps and scans), hand the parsed arrays to the
 * mesh, free it on failure, and word a failure with the place it was found. */
#ifndef TPK_IMPORT_FILE_H
#define TPK_IMPORT_FILE_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* An importer's parser over a whole file's bytes; `mapped` says they are a tpk_map_file mapping (so
 * consumed pages may be dropped). Names the input `name` in messages; leaves *out empty on error. */
typedef int (*tpk_parse_fn)(const char *name, const char *data, size_t size, int mapped, tpk_mesh *out,
                            tpk_diag *diag);
/* What every importer does first: 0 with *out emptied and diag's message cleared, or -1 when no output
 * mesh is given (the message names `name`). */
int tpk_import_begin(const char *name, tpk_mesh *out, tpk_diag *diag);
/* What every path importer does: empty *out, map the file, parse it, unmap. */
int tpk_import_mapped(const char *path, tpk_parse_fn parse, tpk_mesh *out, tpk_diag *diag);
/* A reader of a whole input in memory (the importers' tpk_import_*_memory). */
typedef int (*tpk_memory_fn)(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
/* tpk_import_mapped for a reader that has no use for `mapped`: the path importer of a memory reader. */
int tpk_import_mapped_memory(const char *path, tpk_memory_fn read, tpk_mesh *out, tpk_diag *diag);

/* The epilogue of a parse: hand the reader's arrays to *out (point_count points; cell_count cells with their
 * types, offsets and connectivity), leaving the reader's pointers NULL, so that its own free frees none
 * of them; a mesh without cells gets its one offset (0) and empty arrays, never NULL. 0, or -1 when out of
 * memory (no message: the importer words it, with its place). */
int tpk_import_take_cells(tpk_mesh *out, int64_t point_count, double **points, int64_t cell_count, uint8_t **types,
                          int64_t **offsets, int32_t **conn);
/* The last line of an importer: on failure (rc != 0) *out is freed and left empty. 0 or -1. */
int tpk_import_end(int rc, tpk_mesh *out);

/* Where an importer's message points: the input's name, then a line (line > 0), else a byte offset
 * (byte >= 0), then a context (an element, an array; NULL: none). */
typedef struct tpk_import_place {
    const char *name;
    long line;
    int64_t byte;
    const char *context;
} tpk_import_place;

/* An importer's failure, written once for all: "NAME: line N: CONTEXT: what" into diag, what from fmt.
 * With `failed` (the reader's flag), only the first failure words the message and sets *failed. -1. */
int tpk_import_fail(tpk_diag *diag, int *failed, tpk_import_place at, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
int tpk_import_vfail(tpk_diag *diag, int *failed, tpk_import_place at, const char *fmt, va_list ap)
    __attribute__((format(printf, 4, 0)));

#endif
