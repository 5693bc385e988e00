/* Fuzz target for the TetGen importer: the input is a .node file, a line "@@ele", then an .ele file
 * (without the marker, all of it is the .node file and the .ele file is empty). */
#include <stdint.h>
#include <string.h>

#include "import/importers.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char marker[] = "\n@@ele\n";
    const char *text = (const char *)data;
    size_t node_size = size, ele_at = size;
    for (size_t i = 0; i + sizeof marker - 1 <= size; i++)
        if (!memcmp(text + i, marker, sizeof marker - 1)) {
            node_size = i + 1;
            ele_at = i + sizeof marker - 1;
            break;
        }
    tpk_mesh mesh;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = NULL;
    if (tpk_import_tetgen_memory("fuzz", text, node_size, text + ele_at, size - ele_at, &mesh, &diag) == 0)
        tpk_mesh_free(&mesh);
    return 0;
}
