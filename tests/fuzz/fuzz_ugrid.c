/* Fuzz target for the UGRID importer: the first byte picks ASCII, big- or little-endian binary. */
#include <stdint.h>
#include <string.h>

#include "import/importers.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const names[3] = {"fuzz.ugrid", "fuzz.b8.ugrid", "fuzz.lb8.ugrid"};
    if (size == 0)
        return 0;
    tpk_mesh mesh;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_import_ugrid_memory(names[data[0] % 3], (const char *)data + 1, size - 1, &mesh, &diag) == 0)
        tpk_mesh_free(&mesh);
    return 0;
}
