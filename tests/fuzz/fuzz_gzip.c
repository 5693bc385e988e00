/* Fuzz target for gzip inputs (tools/import/gzip_input.h): inflate with a small limit, then hand what
 * came out to the Gmsh memory reader, as `tetpack convert FILE.msh.gz` does. A failure must say why; a
 * crash, an overread or a leak is a bug. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "import/gzip_input.h"
#include "import/importers.h"

#define FUZZ_MAX_INFLATED (1u << 20)

static void ignore_warning(void *user, const char *text)
{
    (void)user;
    (void)text;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = ignore_warning;
    char *inflated;
    size_t inflated_size;
    if (tpk_gzip_inflate("fuzz.msh.gz", (const char *)data, size, FUZZ_MAX_INFLATED, &inflated, &inflated_size,
                         &diag) != 0) {
        if (inflated || !diag.message[0])
            abort(); /* a failure leaves nothing and says why */
        return 0;
    }
    tpk_mesh mesh;
    if (tpk_import_gmsh_memory("fuzz.msh", inflated, inflated_size, &mesh, &diag) == 0)
        tpk_mesh_free(&mesh);
    free(inflated);
    return 0;
}
