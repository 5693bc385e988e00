/* tpk_import_any: pick an importer from a forced format name, the file extension, or the file's
 * first bytes. */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "importers.h"

#define SUPPORTED_FORMATS                                                                                    \
    "vtk (VTK legacy .vtk, ASCII or BINARY), vtu (VTK XML .vtu), pvd (.pvd series of .vtu), gmsh (.msh 2.2, 4.1), tetgen (.node/.ele), medit (.mesh, .meshb), ugrid (.ugrid, "    \
    ".b8.ugrid, .lb8.ugrid), exodus (.exo, .e, .g, .ex2)"

static int has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), m = strlen(ext);
    return n > m && strcasecmp(path + n - m, ext) == 0;
}

/* The file starts with `magic` (after leading blanks and newlines). */
static int starts_with(const char *path, const char *magic)
{
    char head[64] = {0};
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    size_t got = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    size_t at = 0, n = strlen(magic);
    while (at < got && (head[at] == ' ' || head[at] == '\t' || head[at] == '\r' || head[at] == '\n'))
        at++;
    return got >= at + n && strncasecmp(head + at, magic, n) == 0;
}

int tpk_import_any(const char *path, const char *format, tpk_mesh *out, tpk_diag *diag)
{
    if (!path || !out)
        return tpk_diag_fail(diag, "tpk_import_any: no path or output mesh given");
    if (format && *format && strcasecmp(format, "auto") != 0) {
        if (!strcasecmp(format, "vtk") || !strcasecmp(format, "vtk-legacy"))
            return tpk_import_vtk_legacy(path, out, diag);
        if (!strcasecmp(format, "vtu"))
            return tpk_import_vtu(path, out, diag);
        if (!strcasecmp(format, "pvd"))
            return tpk_import_pvd(path, out, diag);
        if (!strcasecmp(format, "gmsh"))
            return tpk_import_gmsh(path, out, diag);
        if (!strcasecmp(format, "tetgen"))
            return tpk_import_tetgen(path, out, diag);
        if (!strcasecmp(format, "medit"))
            return has_extension(path, ".meshb") ? tpk_import_meshb(path, out, diag)
                                                 : tpk_import_medit(path, out, diag);
        if (!strcasecmp(format, "ugrid"))
            return tpk_import_ugrid(path, out, diag);
        if (!strcasecmp(format, "exodus"))
            return tpk_import_exodus(path, out, diag);
        memset(out, 0, sizeof *out);
        return tpk_diag_fail(diag, "%s: unknown input format '%s'; supported: %s", path, format, SUPPORTED_FORMATS);
    }
    if (has_extension(path, ".vtk"))
        return tpk_import_vtk_legacy(path, out, diag);
    if (has_extension(path, ".node") || has_extension(path, ".ele"))
        return tpk_import_tetgen(path, out, diag);
    if (has_extension(path, ".vtu"))
        return tpk_import_vtu(path, out, diag);
    if (has_extension(path, ".pvd"))
        return tpk_import_pvd(path, out, diag);
    if (has_extension(path, ".msh"))
        return tpk_import_gmsh(path, out, diag);
    if (has_extension(path, ".mesh"))
        return tpk_import_medit(path, out, diag);
    if (has_extension(path, ".ugrid"))
        return tpk_import_ugrid(path, out, diag);
    if (has_extension(path, ".exo") || has_extension(path, ".e") || has_extension(path, ".g") ||
        has_extension(path, ".ex2") || starts_with(path, "CDF\x01") || starts_with(path, "CDF\x02") ||
        starts_with(path, "\x89HDF"))
        return tpk_import_exodus(path, out, diag);
    if (has_extension(path, ".meshb"))
        return tpk_import_meshb(path, out, diag);
    if (starts_with(path, "# vtk DataFile"))
        return tpk_import_vtk_legacy(path, out, diag);
    if (starts_with(path, "MeshVersionFormatted"))
        return tpk_import_medit(path, out, diag);
    if (starts_with(path, "$MeshFormat"))
        return tpk_import_gmsh(path, out, diag);
    if (starts_with(path, "<VTKFile") || starts_with(path, "<?xml"))
        return tpk_import_vtu(path, out, diag);
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) {
        /* A TetGen stem names no file itself. */
        char node[4096];
        snprintf(node, sizeof node, "%s.node", path);
        FILE *g = fopen(node, "rb");
        if (g) {
            fclose(g);
            return tpk_import_tetgen(path, out, diag);
        }
        return tpk_diag_fail(diag, "%s: cannot open the file, and no %s.node exists", path, path);
    }
    fclose(f);
    return tpk_diag_fail(diag, "%s: cannot tell the input format from the extension or the first bytes; "
                         "supported: %s (force one with a format name)", path, SUPPORTED_FORMATS);
}
