/* tetpack export: a .tpk's tets and fields as VTU or VTKHDF, its shell as PLY, OBJ, OFF or STL. */
#include <string.h>
#include <sys/stat.h>

#include "base/output_file.h"
#include "cli.h"
#include "export/exporters.h"

static const char export_help[] =
    "usage: tetpack export FILE.tpk [--vtu OUT.vtu] [--vtkhdf OUT.vtkhdf] [--shell OUT.ply|.obj|.off|.stl]\n"
    "\n"
    "  --vtu OUT.vtu     tets (positive vertex order), points in world coordinates, every field and\n"
    "                    time step, and the tet->source-cell map; opens in ParaView and meshio\n"
    "  --vtkhdf OUT      the same as VTKHDF (VTK's HDF5 format): one step as Version 1.0, which VTK 9.1\n"
    "                    and later read; several as Version 2.0 with a Steps group (VTK 9.3 and later\n"
    "                    read the steps, 9.1 and 9.2 only the first). Needs a build with HDF5\n"
    "  --shell OUT.EXT   the boundary faces, outward (counter-clockwise seen from outside), only the\n"
    "                    vertices they use, in world coordinates; the format from the extension:\n"
    "                      .ply  binary, float64 positions and a per-face 'tet' property\n"
    "                      .obj  ASCII, float32 positions (OpenMesh's writer)\n"
    "                      .off  ASCII, float32 positions (OpenMesh's writer)\n"
    "                      .stl  binary, float32 positions and outward normals (OpenMesh's writer)\n"
    "                    OpenMesh's writers round positions to float32: far from the origin that moves\n"
    "                    vertices (a warning says by how much); .ply keeps float64.\n"
    "                    A non-manifold shell (faces meeting at a lone vertex or edge) is written whole\n"
    "                    to OBJ/OFF/STL, those faces on copies of their vertices, with a warning.\n"
    "Outputs are written atomically (an unnamed temporary file, linked into place when complete); an\n"
    "output that is FILE.tpk itself, a directory or not a regular file is refused.\n";

/* Two outputs are the same file when their names match or they already exist as one inode. */
static int same_output(const char *a, const char *b)
{
    struct stat sa, sb;
    if (!strcmp(a, b))
        return 1;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

int tpk_cmd_export(int argc, char **argv)
{
    const char *path = NULL, *vtu = NULL, *vtkhdf = NULL, *shell = NULL;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
            fputs(export_help, stdout);
            return TPK_EXIT_OK;
        } else if (!strncmp(arg, "--vtu", 5)) {
            if (!(vtu = tpk_cli_value(argc, argv, &i, "--vtu")))
                return tpk_cli_fail("export", "--vtu expects an output path");
        } else if (!strncmp(arg, "--vtkhdf", 8)) {
            if (!(vtkhdf = tpk_cli_value(argc, argv, &i, "--vtkhdf")))
                return tpk_cli_fail("export", "--vtkhdf expects an output path");
        } else if (!strncmp(arg, "--shell", 7)) {
            if (!(shell = tpk_cli_value(argc, argv, &i, "--shell")))
                return tpk_cli_fail("export", "--shell expects an output path");
        } else if (arg[0] == '-' && arg[1]) {
            return tpk_cli_fail("export", "unknown option '%s' (see tetpack export --help)", arg);
        } else if (!path) {
            path = arg;
        } else {
            return tpk_cli_fail("export", "expected one FILE.tpk, found a second argument '%s'", arg);
        }
    }
    if (!path || (!vtu && !vtkhdf && !shell))
        return tpk_cli_fail("export", "expected FILE.tpk and one or more of --vtu OUT.vtu, --vtkhdf OUT.vtkhdf, "
                            "--shell OUT.ply|.obj|.off|.stl");
    const char *outputs[3] = {vtu, vtkhdf, shell}, *option[3] = {"--vtu", "--vtkhdf", "--shell"};
    for (int a = 0; a < 3; a++)
        for (int b = a + 1; b < 3; b++)
            if (outputs[a] && outputs[b] && same_output(outputs[a], outputs[b]))
                return tpk_cli_fail("export", "%s '%s' and %s '%s' name the same file; the second would replace "
                                    "the first: choose two paths", option[a], outputs[a], option[b], outputs[b]);
    tpk_output_input input = {.arg = "FILE.tpk", .given = path};
    if ((vtu && tpk_cli_check_output("export", "--vtu", vtu, &input, 1)) ||
        (vtkhdf && tpk_cli_check_output("export", "--vtkhdf", vtkhdf, &input, 1)) ||
        (shell && tpk_cli_check_output("export", "--shell", shell, &input, 1)))
        return TPK_EXIT_USAGE;
    tpk_file *file = NULL;
    if (tpk_cli_open("export", path, &file))
        return TPK_EXIT_USAGE;
    /* Issue 10: a damaged chunk met while writing was reported under the output's name. Every chunk
     * is checked first, so damage is reported against the input, before any output is started. */
    if (tpk_verify(file) != TPK_OK) {
        tpk_cli_fail("export", "%s: %s", path, tpk_error_text(file));
        tpk_close(file);
        return TPK_EXIT_USAGE;
    }
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    int rc = 0;
    if (vtu)
        rc = tpk_export_vtu(file, vtu, &diag);
    if (rc == 0 && vtkhdf)
        rc = tpk_export_vtkhdf(file, vtkhdf, &diag);
    if (rc == 0 && shell)
        rc = tpk_export_shell(file, shell, &diag);
    tpk_close(file);
    if (rc != 0)
        return tpk_cli_fail("export", "%s", diag.message);
    return TPK_EXIT_OK;
}
