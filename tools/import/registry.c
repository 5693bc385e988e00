/* tpk_import_any: pick an importer from a forced format name, the file extension, or the file's
 * first bytes. */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "importers.h"
#include "import/surface/surface.h"

#define SUPPORTED_FORMATS                                                                                    \
    "vtk (VTK legacy .vtk, ASCII or BINARY), vtu (VTK XML .vtu), pvd (.pvd series of .vtu), gmsh (.msh 2.2, 4.1), tetgen (.node/.ele), medit (.mesh, .meshb), ugrid (.ugrid, "    \
    ".b8.ugrid, .lb8.ugrid), exodus (.exo, .e, .g, .ex2), surfaces for TetGen: stl, off, ply; point clouds: csv, ply " \
    "(surface and points force either reading)"

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

/* Surfaces and point clouds (TetGen): a forced format name, or -2 when `format` names none of them. */
static int import_surface_format(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                                 tpk_mesh *out, tpk_diag *diag)
{
    static const struct {
        const char *name;
        tpk_surface_kind kind;
        tpk_surface_mode mode;
    } table[] = {{"stl", TPK_SURFACE_STL, TPK_SURFACE_FACES},     {"off", TPK_SURFACE_OFF, TPK_SURFACE_FACES},
                 {"ply", TPK_SURFACE_PLY, TPK_SURFACE_AUTO},      {"csv", TPK_SURFACE_CSV, TPK_SURFACE_POINTS},
                 {"surface", TPK_SURFACE_UNKNOWN, TPK_SURFACE_FACES}, {"points", TPK_SURFACE_UNKNOWN, TPK_SURFACE_POINTS}};
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (!strcasecmp(format, table[i].name))
            return tpk_import_surface(path, table[i].kind, table[i].mode, tetgen, out, diag);
    return -2;
}

int tpk_import_any(const char *path, const char *format, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_any_with(path, format, NULL, out, diag);
}

int tpk_import_any_with(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                        tpk_mesh *out, tpk_diag *diag)
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
        int rc = import_surface_format(path, format, tetgen, out, diag);
        if (rc != -2)
            return rc;
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
    if (tpk_surface_kind_from_name(path) != TPK_SURFACE_UNKNOWN)
        return tpk_import_surface(path, TPK_SURFACE_UNKNOWN, TPK_SURFACE_AUTO, tetgen, out, diag);
    if (starts_with(path, "# vtk DataFile"))
        return tpk_import_vtk_legacy(path, out, diag);
    if (starts_with(path, "MeshVersionFormatted"))
        return tpk_import_medit(path, out, diag);
    if (starts_with(path, "$MeshFormat"))
        return tpk_import_gmsh(path, out, diag);
    if (starts_with(path, "<VTKFile") || starts_with(path, "<?xml"))
        return tpk_import_vtu(path, out, diag);
    if (starts_with(path, "ply") || starts_with(path, "OFF") || starts_with(path, "COFF") || starts_with(path, "solid"))
        return tpk_import_surface(path, TPK_SURFACE_UNKNOWN, TPK_SURFACE_AUTO, tetgen, out, diag);
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
