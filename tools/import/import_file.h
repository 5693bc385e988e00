/* What every importer does around its parser: start with an empty mesh, and read a path by mapping the
 * file and parsing its bytes (base/text_scan.h maps and scans; this is the importers' own glue). */
#ifndef TPK_IMPORT_FILE_H
#define TPK_IMPORT_FILE_H

#include <stddef.h>

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

#endif
