/* tetpack export: a .tpk's tets and fields as VTU, its shell as PLY. */
#include <string.h>

#include "cli.h"
#include "exporters.h"

static const char export_help[] =
    "usage: tetpack export FILE.tpk [--vtu OUT.vtu] [--shell OUT.ply]\n"
    "\n"
    "  --vtu OUT.vtu     tets (positive vertex order), points in world coordinates, every field and\n"
    "                    time step, and the tet->source-cell map; opens in ParaView and meshio\n"
    "  --shell OUT.ply   the boundary faces, outward, as binary PLY with a per-face 'tet' property\n"
    "Outputs are written atomically (temporary file, then rename).\n";

int tpk_cmd_export(int argc, char **argv)
{
    const char *path = NULL, *vtu = NULL, *ply = NULL;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
            fputs(export_help, stdout);
            return TPK_EXIT_OK;
        } else if (!strncmp(arg, "--vtu", 5)) {
            if (!(vtu = tpk_cli_value(argc, argv, &i, "--vtu")))
                return tpk_cli_fail("export", "--vtu expects an output path");
        } else if (!strncmp(arg, "--shell", 7)) {
            if (!(ply = tpk_cli_value(argc, argv, &i, "--shell")))
                return tpk_cli_fail("export", "--shell expects an output path");
        } else if (arg[0] == '-' && arg[1]) {
            return tpk_cli_fail("export", "unknown option '%s' (see tetpack export --help)", arg);
        } else if (!path) {
            path = arg;
        } else {
            return tpk_cli_fail("export", "expected one FILE.tpk, found a second argument '%s'", arg);
        }
    }
    if (!path || (!vtu && !ply))
        return tpk_cli_fail("export", "expected FILE.tpk and --vtu OUT.vtu and/or --shell OUT.ply");
    tpk_file *file = NULL;
    if (tpk_cli_open("export", path, &file))
        return TPK_EXIT_USAGE;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = 0;
    if (vtu)
        rc = tpk_export_vtu(file, vtu, &diag);
    if (rc == 0 && ply)
        rc = tpk_export_shell_ply(file, ply, &diag);
    tpk_close(file);
    if (rc != 0)
        return tpk_cli_fail("export", "%s", diag.message);
    return TPK_EXIT_OK;
}
