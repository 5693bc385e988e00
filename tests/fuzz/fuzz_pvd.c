/* Fuzz target for ParaView series (.pvd, tools/import/import_pvd.c), which has no memory reader: the
 * input is split into files (support.h: the series series.pvd first, then "@@ NAME" before each piece)
 * written to a fresh folder on tmpfs, and read strictly (convert) and leniently (check). A failure must
 * leave the mesh empty and say why. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import/importers.h"
#include "support.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *dir = tpk_fuzz_fresh_dir("series");
    if (tpk_fuzz_split_files(dir, "series.pvd", data, size) == 0)
        return 0;
    char path[512];
    snprintf(path, sizeof path, "%s/series.pvd", dir);
    for (int lenient = 0; lenient < 2; lenient++) {
        tpk_mesh mesh;
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        diag.warn = tpk_fuzz_ignore;
        diag.lenient_fields = lenient;
        if (tpk_import_any(path, "pvd", &mesh, &diag) == 0)
            tpk_mesh_free(&mesh);
        else if (mesh.points || mesh.cell_conn || mesh.fields || mesh.cell_count || !diag.message[0])
            abort(); /* a failure must leave the mesh empty and say why */
    }
    return 0;
}
