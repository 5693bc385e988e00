/* Fuzz target for the Gmsh .msh importer. */
#include <stdint.h>
#include <string.h>

#include "import/importers.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    tpk_mesh mesh;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_import_gmsh_memory("fuzz.msh", (const char *)data, size, &mesh, &diag) == 0)
        tpk_mesh_free(&mesh);
    return 0;
}
