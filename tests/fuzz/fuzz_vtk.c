/* Fuzz target for the VTK legacy importer: parse from memory, free, strictly (convert) and leniently
 * (tetpack check: wrong-length arrays recorded and dropped). Any crash, sanitizer report or leak is a
 * bug; errors are expected and must leave the mesh empty. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "import/importers.h"

static void ignore_warning(void *user, const char *text)
{
    (void)user;
    (void)text;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (int lenient = 0; lenient < 2; lenient++) {
        tpk_mesh mesh;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        diag.warn = ignore_warning;
        diag.lenient_fields = lenient;
        if (tpk_import_vtk_legacy_memory("fuzz.vtk", (const char *)data, size, &mesh, &diag) == 0)
            tpk_mesh_free(&mesh);
        else if (mesh.points || mesh.cell_conn || mesh.fields || mesh.cell_count || !diag.message[0])
            abort(); /* a failure must leave the mesh empty and say why */
    }
    return 0;
}
