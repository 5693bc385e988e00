/* Fuzz target for the surface and point-cloud readers (STL, OFF, PLY, CSV; parsing only, no TetGen):
 * the kind comes from the first bytes (binary STL when nothing else matches), then the closed-surface
 * check runs on whatever was read. */
#include <stdint.h>
#include <string.h>

#include "import/surface/surface.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *text = (const char *)data;
    tpk_surface_kind kind = tpk_surface_kind_sniff(text, size);
    tpk_mesh mesh;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = NULL;
    if (tpk_read_surface_memory("fuzz", text, size, kind ? kind : TPK_SURFACE_STL, &mesh, &diag) == 0) {
        if (mesh.cell_count > 0)
            tpk_surface_check_closed("fuzz", &mesh, &diag);
        tpk_mesh_free(&mesh);
    }
    return 0;
}
