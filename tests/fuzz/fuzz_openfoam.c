/* Fuzz target for OpenFOAM case directories (tools/import/openfoam/): the input is split into the files
 * of a case (support.h: "@@ constant/polyMesh/points" starts a file; text before the first mark is
 * constant/polyMesh/points; "@@ 0/include/x" makes folders), written to a fresh folder on tmpfs, and read
 * as `tetpack convert` (strict), `tetpack check` (lenient fields) and `convert --strict-fields` read a
 * case: field files through the dictionary reader (foam_dict.c: macros, includes, #inputMode). A failure
 * must leave the mesh empty and say why. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "import/importers.h"
#include "support.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *dir = tpk_fuzz_fresh_dir("case");
    if (tpk_fuzz_split_files(dir, "constant/polyMesh/points", data, size) == 0)
        return 0;
    for (int mode = 0; mode < 3; mode++) { /* strict import, check's lenient fields, --strict-fields */
        tpk_mesh mesh;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        diag.warn = tpk_fuzz_ignore;
        diag.lenient_fields = mode == 1;
        diag.strict_fields = mode == 2;
        if (tpk_import_openfoam(dir, &mesh, &diag) == 0)
            tpk_mesh_free(&mesh);
        else if (mesh.points || mesh.cell_conn || mesh.fields || mesh.cell_count || !diag.message[0])
            abort(); /* a failure must leave the mesh empty and say why */
    }
    return 0;
}
