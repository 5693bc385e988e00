/* The importers' glue (import_file.h): an emptied output mesh, and a path mapped and parsed. */
#include "import_file.h"

#include <string.h>

#include "base/text_scan.h"

int tpk_import_begin(const char *name, tpk_mesh *out, tpk_diag *diag)
{
    if (!out)
        return tpk_diag_fail(diag, "%s: no output mesh given", name ? name : "(input)");
    memset(out, 0, sizeof *out);
    if (diag)
        diag->message[0] = 0;
    return 0;
}

int tpk_import_mapped(const char *path, tpk_parse_fn parse, tpk_mesh *out, tpk_diag *diag)
{
    const char *data;
    size_t size;
    if (out)
        memset(out, 0, sizeof *out);
    if (tpk_map_file(path, &data, &size, diag) != 0)
        return -1;
    int rc = parse(path, data, size, 1, out, diag);
    tpk_unmap_file(data, size);
    return rc;
}
