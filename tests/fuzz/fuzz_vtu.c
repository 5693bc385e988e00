/* Fuzz target for the VTK XML UnstructuredGrid (.vtu) importer, strict (convert) and lenient (tetpack
 * check: wrong-length field arrays recorded and dropped). */
#include <stdint.h>
#include <string.h>

#include "import/importers.h"

static void ignore(void *user, const char *text)
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
        diag.warn = ignore;
        diag.lenient_fields = lenient;
        if (tpk_import_vtu_memory("fuzz.vtu", (const char *)data, size, &mesh, &diag) == 0)
            tpk_mesh_free(&mesh);
    }
    return 0;
}
