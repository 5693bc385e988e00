/* The importer registry: one row per input format (importers.h), and tpk_import_any, which picks a row
 * from a forced format name, the file extension, or the file's first bytes.
 *
 * Rows are written one field per designated initializer, starting `{.name = "..."`, with no braces
 * inside a row: tests/fuzz/CMakeLists.txt reads the rows that have a .read_memory to make the fuzz
 * targets. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gzip_input.h"
#include "importers.h"
#include "isolate.h"
#include "mesh/higher_order.h"
#include "surface/surface.h"

#define VOLUME_CELLS (TPK_FORMAT_TETS | TPK_FORMAT_HEXAHEDRA | TPK_FORMAT_WEDGES | TPK_FORMAT_PYRAMIDS)
#define FIELDS (TPK_FORMAT_POINT_FIELDS | TPK_FORMAT_CELL_FIELDS)
#define GZ TPK_FORMAT_GZIP

#ifndef TPK_WITH_CGNS
/* A .cgns file still finds its row, which says why it cannot be read, rather than Exodus's. */
static int cgns_not_built(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    return tpk_diag_fail(diag, "%s: this tetpack was built without CGNS (TETPACK_WITH_CGNS=OFF); install the CGNS "
                         "library (Debian: libcgns-dev) and build again", path);
}
#endif

/* Detection takes the first row whose extension matches, then the first whose magic matches (either
 * only where the row's sniff, if any, accepts the first bytes): the order below is the detection order.
 * DOLFIN comes before VTU: both may start "<?xml", DOLFIN's sniff then looks for "<dolfin". */
static const tpk_import_format formats[] = {
    {.name = "vtk", .aliases = "vtk-legacy", .title = "VTK legacy UNSTRUCTURED_GRID, ASCII or BINARY",
     .extensions = ".vtk", .magic = "# vtk DataFile", .read = tpk_import_vtk_legacy,
     .read_memory = tpk_import_vtk_legacy_memory,
     .supports = VOLUME_CELLS | TPK_FORMAT_VOXELS | TPK_FORMAT_POLYHEDRA | FIELDS | GZ},
    {.name = "tetgen", .title = "TetGen .node/.ele (a path may name either file or their stem)",
     .extensions = ".node .ele", .read = tpk_import_tetgen, .read_memory = tpk_import_tetgen_bundle_memory,
     .supports = TPK_FORMAT_TETS | FIELDS},
    {.name = "dolfin", .aliases = "dolfin-xml fenics", .title = "legacy DOLFIN XML (FEniCS): tetrahedra, hexahedra, domains",
     .extensions = ".xml", .magic = "<dolfin|<?xml", .sniff = tpk_sniff_dolfin, .read = tpk_import_dolfin,
     .read_memory = tpk_import_dolfin_memory, .supports = TPK_FORMAT_TETS | TPK_FORMAT_HEXAHEDRA | TPK_FORMAT_CELL_FIELDS | GZ},
    {.name = "vtu", .title = "VTK XML UnstructuredGrid: ascii, base64, appended raw, zlib",
     .extensions = ".vtu", .magic = "<VTKFile|<?xml", .read = tpk_import_vtu, .read_memory = tpk_import_vtu_memory,
     .supports = VOLUME_CELLS | TPK_FORMAT_VOXELS | TPK_FORMAT_POLYHEDRA | FIELDS | GZ},
    {.name = "pvd", .title = "ParaView series: one .vtu per time step", .extensions = ".pvd",
     .read = tpk_import_pvd,
     .supports = VOLUME_CELLS | TPK_FORMAT_VOXELS | TPK_FORMAT_POLYHEDRA | FIELDS | TPK_FORMAT_TIME_STEPS},
    {.name = "gmsh", .title = "Gmsh .msh 2.2 and 4.1, ASCII and binary", .extensions = ".msh",
     .magic = "$MeshFormat", .read = tpk_import_gmsh, .read_memory = tpk_import_gmsh_memory,
     .supports = VOLUME_CELLS | FIELDS | TPK_FORMAT_TIME_STEPS | GZ},
    {.name = "medit", .title = "Medit .mesh (ASCII; INRIA, MMG, TetWild, refine, sfepy)", .extensions = ".mesh",
     .magic = "MeshVersionFormatted", .read = tpk_import_medit, .read_memory = tpk_import_medit_memory,
     .supports = TPK_FORMAT_TETS | TPK_FORMAT_HEXAHEDRA | FIELDS | GZ},
    {.name = "ugrid", .title = "NASA/AFLR3 UGRID: ASCII, big- and little-endian binary",
     .extensions = ".ugrid .b8.ugrid .lb8.ugrid", .read = tpk_import_ugrid, .read_memory = tpk_import_ugrid_memory,
     .supports = VOLUME_CELLS | GZ},
    {.name = "exodus", .title = "Exodus II (netCDF classic or netCDF-4), every time step",
     .extensions = ".exo .e .g .ex2", .magic = "CDF\x01|CDF\x02|\x89HDF", .read = tpk_import_exodus,
     .supports = VOLUME_CELLS | FIELDS | TPK_FORMAT_TIME_STEPS, .isolated = "netCDF"},
#ifdef TPK_WITH_CGNS
    /* After exodus: its netCDF-4 files share the HDF5 signature, so an HDF5 file without an extension
     * reads as Exodus; .cgns is told by its extension, ADF-format CGNS by its header (the ADF library
     * writes its "@(#)" with the high bits set). */
    {.name = "cgns", .title = "CGNS (HDF5 or ADF): unstructured, structured and polyhedral zones, every step",
     .extensions = ".cgns", .magic = "\xc0\xa8\xa3\xa9" "ADF Database|@(#)ADF Database", .read = tpk_import_cgns,
     .supports = VOLUME_CELLS | TPK_FORMAT_POLYHEDRA | FIELDS | TPK_FORMAT_TIME_STEPS, .isolated = "CGNS"},
#else
    {.name = "cgns", .title = "CGNS: not in this build (TETPACK_WITH_CGNS=OFF)", .extensions = ".cgns",
     .read = cgns_not_built},
#endif
    {.name = "meshb", .aliases = "medit", .title = "Medit binary .meshb (libMeshb 1-4, either byte order)",
     .extensions = ".meshb", .read = tpk_import_meshb, .read_memory = tpk_import_meshb_memory,
     .supports = TPK_FORMAT_TETS | TPK_FORMAT_HEXAHEDRA | FIELDS | GZ},
    {.name = "inp", .aliases = "abaqus calculix", .title = "Abaqus / CalculiX .inp: solids, element sets, includes",
     .extensions = ".inp", .magic = "*HEADING|*NODE", .read = tpk_import_inp, .read_memory = tpk_import_inp_memory,
     .supports = TPK_FORMAT_TETS | TPK_FORMAT_HEXAHEDRA | TPK_FORMAT_WEDGES | TPK_FORMAT_CELL_FIELDS | GZ},
    /* The HDF5 signature is Exodus's (netCDF-4) and CGNS's too: .vtkhdf and .hdf by extension, other names
     * by the probe (an HDF5 file with a /VTKHDF group). */
    {.name = "vtkhdf", .title = "VTKHDF (VTK's HDF5 format) UnstructuredGrid 1.x, 2.x: partitions, steps, polyhedra",
     .extensions = ".vtkhdf .hdf", .magic = "\x89HDF\r\n\x1a\n", .probe = tpk_import_vtkhdf_probe,
     .read = tpk_import_vtkhdf, .read_memory = tpk_import_vtkhdf_memory,
     .supports = VOLUME_CELLS | TPK_FORMAT_VOXELS | TPK_FORMAT_POLYHEDRA | FIELDS | TPK_FORMAT_TIME_STEPS,
     .isolated = "HDF5"},
    {.name = "xdmf", .title = "XDMF 2 and 3 (meshio, FEniCS/dolfinx): XML or HDF5 data, temporal collections",
     .extensions = ".xdmf .xmf", .magic = "<Xdmf", .sniff = tpk_import_xdmf_sniff, .read = tpk_import_xdmf,
     .read_memory = tpk_import_xdmf_memory, .supports = VOLUME_CELLS | FIELDS | TPK_FORMAT_TIME_STEPS,
     .isolated = "HDF5"}, /* its HDF DataItems */
    /* Its files may each be .gz, read by the reader itself: the row does not say gzip (FILE.gz inputs). */
    {.name = "openfoam", .title = "OpenFOAM case directory (or its CASE.foam): polyMesh ASCII, binary, .gz; fields",
     .extensions = ".foam", .read = tpk_import_openfoam,
     .supports = TPK_FORMAT_POLYHEDRA | FIELDS | TPK_FORMAT_TIME_STEPS},
    {.name = "stl", .title = "STL closed surface, ASCII or binary (TetGen fills it)", .extensions = ".stl",
     .magic = "solid", .read_memory = tpk_read_stl, .surface_kind = TPK_SURFACE_STL,
     .surface_mode = TPK_SURFACE_FACES, .supports = TPK_FORMAT_SURFACE},
    {.name = "off", .title = "OFF closed surface (TetGen fills it)", .extensions = ".off", .magic = "OFF|COFF",
     .read_memory = tpk_read_off, .surface_kind = TPK_SURFACE_OFF, .surface_mode = TPK_SURFACE_FACES,
     .supports = TPK_FORMAT_SURFACE},
    {.name = "ply", .title = "PLY closed surface, or vertices alone as a point cloud (TetGen)",
     .extensions = ".ply", .magic = "ply", .read_memory = tpk_read_ply, .surface_kind = TPK_SURFACE_PLY,
     .surface_mode = TPK_SURFACE_AUTO, .supports = TPK_FORMAT_SURFACE | TPK_FORMAT_POINT_CLOUD | TPK_FORMAT_POINT_FIELDS},
    {.name = "csv", .title = "CSV point cloud x,y,z,NAME... (TetGen: Delaunay)", .extensions = ".csv",
     .read_memory = tpk_read_csv_points, .surface_kind = TPK_SURFACE_CSV, .surface_mode = TPK_SURFACE_POINTS,
     .supports = TPK_FORMAT_POINT_CLOUD | TPK_FORMAT_POINT_FIELDS},
    {.name = "surface", .title = "any STL, OFF or PLY file read as a closed surface", .extensions = "",
     .surface_kind = TPK_SURFACE_UNKNOWN, .surface_mode = TPK_SURFACE_FACES, .supports = TPK_FORMAT_SURFACE},
    {.name = "points", .title = "any STL, OFF, PLY or CSV file read as a point cloud (faces ignored)",
     .extensions = "", .surface_kind = TPK_SURFACE_UNKNOWN, .surface_mode = TPK_SURFACE_POINTS,
     .supports = TPK_FORMAT_POINT_CLOUD | TPK_FORMAT_POINT_FIELDS},
};

#define FORMAT_COUNT (sizeof formats / sizeof formats[0])

const tpk_import_format *tpk_import_formats(size_t *count)
{
    if (count)
        *count = FORMAT_COUNT;
    return formats;
}

/* `word` is one of the space-separated words of `list` (any case). */
static int word_in(const char *list, const char *word)
{
    size_t n = strlen(word);
    for (const char *at = list; at && *at;) {
        while (*at == ' ')
            at++;
        size_t len = strcspn(at, " ");
        if (len == n && n && strncasecmp(at, word, n) == 0)
            return 1;
        at += len;
    }
    return 0;
}

/* `path` ends with one of the space-separated extensions (the path must be longer than the extension). */
static int has_any_extension(const char *path, const char *extensions)
{
    size_t n = strlen(path);
    for (const char *at = extensions; at && *at;) {
        while (*at == ' ')
            at++;
        size_t len = strcspn(at, " ");
        if (len && n > len && strncasecmp(path + n - len, at, len) == 0)
            return 1;
        at += len;
    }
    return 0;
}

/* One of the '|'-separated prefixes starts `head` after leading blanks and newlines. */
static int magic_matches(const char *magic, const char *head, size_t got)
{
    size_t at = 0;
    while (at < got && (head[at] == ' ' || head[at] == '\t' || head[at] == '\r' || head[at] == '\n'))
        at++;
    for (const char *m = magic; m && *m;) {
        size_t len = strcspn(m, "|");
        if (len && got >= at + len && strncasecmp(head + at, m, len) == 0)
            return 1;
        m += len + (m[len] == '|');
    }
    return 0;
}

const tpk_import_format *tpk_import_format_named(const char *name, const char *path)
{
    const tpk_import_format *first = NULL;
    for (size_t i = 0; name && i < FORMAT_COUNT; i++) {
        if (strcasecmp(formats[i].name, name) != 0 && !word_in(formats[i].aliases, name))
            continue;
        if (path && has_any_extension(path, formats[i].extensions))
            return &formats[i];
        if (!first)
            first = &formats[i];
    }
    return first;
}

/* `path` ends in ".gz" (any case) after something. */
static int gzipped(const char *path)
{
    size_t n = strlen(path);
    return n > 3 && strcasecmp(path + n - 3, ".gz") == 0;
}

static int sniff_passes(const tpk_import_format *row, const char *head, size_t got)
{
    return !row->sniff || row->sniff(head, got);
}

/* The row for a file named `name` (its extension) starting with head[0..got); `path`, when not NULL, is
 * the file for the rows' probes. */
static const tpk_import_format *detect_row(const char *name, const char *path, const char *head, size_t got)
{
    for (size_t i = 0; i < FORMAT_COUNT; i++)
        if (has_any_extension(name, formats[i].extensions) && sniff_passes(&formats[i], head, got))
            return &formats[i];
    for (size_t i = 0; i < FORMAT_COUNT; i++)
        if (formats[i].sniff && formats[i].sniff(head, got))
            return &formats[i];
    for (size_t i = 0; path && i < FORMAT_COUNT; i++)
        if (formats[i].probe && magic_matches(formats[i].magic, head, got) &&
            (formats[i].isolated ? tpk_isolated_probe(formats[i].probe, path) : formats[i].probe(path)))
            return &formats[i];
    for (size_t i = 0; i < FORMAT_COUNT; i++)
        if (magic_matches(formats[i].magic, head, got) && sniff_passes(&formats[i], head, got))
            return &formats[i];
    return NULL;
}

const tpk_import_format *tpk_import_format_detect(const char *path)
{
    char head[TPK_IMPORT_HEAD_BYTES + 1] = {0};
    size_t got = 0;
    if (gzipped(path)) {
        char inner[4096];
        snprintf(inner, sizeof inner, "%.*s", (int)strlen(path) - 3, path);
        return detect_row(inner, NULL, head, tpk_gzip_head(path, head, TPK_IMPORT_HEAD_BYTES));
    }
    FILE *f = fopen(path, "rb");
    if (f) {
        got = fread(head, 1, TPK_IMPORT_HEAD_BYTES, f);
        fclose(f);
    }
    return detect_row(path, path, head, got);
}

const char *tpk_import_format_names(char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = 0;
    for (size_t i = 0; i < FORMAT_COUNT && used < cap; i++) {
        int n = snprintf(buf + used, cap - used, "%s%s", i ? ", " : "", formats[i].name);
        used += n > 0 ? (size_t)n : 0;
    }
    return buf;
}

const char *tpk_import_format_supports(unsigned supports, char *buf, size_t cap)
{
    static const char *const words[] = {"tets", "hexahedra", "wedges", "pyramids", "voxels", "polyhedra",
                                        "surface", "point-cloud", "point-fields", "cell-fields", "time-steps",
                                        "gzip"};
    size_t used = 0;
    buf[0] = 0;
    for (size_t b = 0; b < sizeof words / sizeof words[0] && used < cap; b++) {
        if (!(supports & (1u << b)))
            continue;
        int n = snprintf(buf + used, cap - used, "%s%s", used ? " " : "", words[b]);
        used += n > 0 ? (size_t)n : 0;
    }
    return buf;
}

/* Read with a row. `forced`: chosen by name, so a TetGen reading takes the row's kind and mode;
 * detected surfaces let the surface reader look again (extension, then content) and take faces when
 * there are any. */
static int import_with(const tpk_import_format *row, int forced, const char *path,
                       const struct tpk_tetgen_options *tetgen, tpk_mesh *out, tpk_diag *diag)
{
    if (row->read && row->isolated)
        return tpk_isolated_read(row->read, row->isolated, path, out, diag);
    if (row->read)
        return row->read(path, out, diag);
    if (forced)
        return tpk_import_surface(path, (tpk_surface_kind)row->surface_kind, (tpk_surface_mode)row->surface_mode,
                                  tetgen, out, diag);
    return tpk_import_surface(path, TPK_SURFACE_UNKNOWN, TPK_SURFACE_AUTO, tetgen, out, diag);
}

/* "inner..." as "inner.gz..." into buf: messages about the inflated bytes name the file read. */
static const char *name_gz(const char *text, const char *inner, char *buf, size_t cap)
{
    size_t n = strlen(inner), all = strlen(text);
    if (strncmp(text, inner, n) != 0 || all + 4 > cap)
        return text;
    memcpy(buf, text, n);
    memcpy(buf + n, ".gz", 3);
    memcpy(buf + n + 3, text + n, all - n + 1);
    return buf;
}

/* Warnings of the memory reader, renamed, to where the caller's would go. */
typedef struct gz_warnings {
    tpk_diag *diag;
    void (*warn)(void *user, const char *text);
    void *user;
    const char *inner;
} gz_warnings;

static void warn_gz(void *user, const char *text)
{
    gz_warnings *w = user;
    char renamed[1100];
    text = name_gz(text, w->inner, renamed, sizeof renamed);
    if (w->warn)
        w->warn(w->user, text);
    else
        fprintf(stderr, "warning: %s\n", text);
}

/* FILE.gz: inflated, then read by the row's memory reader under the name without ".gz" (UGRID takes its
 * encoding from it, .inp its includes' folder); messages then name the .gz file. */
static int import_gzip(const tpk_import_format *row, const char *path, tpk_mesh *out, tpk_diag *diag)
{
    char inner[4096];
    memset(out, 0, sizeof *out);
    if (!row)
        return tpk_diag_fail(diag, "%s: cannot tell the input format from the name without .gz or the inflated "
                                   "first bytes (force one with --format; tetpack formats lists them)", path);
    if (!(row->supports & TPK_FORMAT_GZIP) || !row->read_memory)
        return tpk_diag_fail(diag, "%s: %s input is not read compressed (tetpack formats lists the formats whose "
                                   "CARRIES say gzip); gunzip it first", path, row->name);
    char *data;
    size_t size;
    if (tpk_gzip_inflate_file(path, 0, &data, &size, diag) != 0)
        return -1;
    snprintf(inner, sizeof inner, "%.*s", (int)strlen(path) - 3, path);
    gz_warnings w = {diag, diag ? diag->warn : NULL, diag ? diag->warn_user : NULL, inner};
    if (diag) {
        diag->warn = warn_gz;
        diag->warn_user = &w;
    }
    int rc = row->read_memory(inner, data, size, out, diag);
    free(data);
    if (diag) {
        diag->warn = w.warn;
        diag->warn_user = w.user;
    }
    char renamed[sizeof diag->message];
    if (rc != 0 && diag)
        snprintf(diag->message, sizeof diag->message, "%s", name_gz(diag->message, inner, renamed, sizeof renamed));
    return rc;
}

static int import_any(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                      tpk_mesh *out, tpk_diag *diag);

int tpk_import_any(const char *path, const char *format, tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_any_with(path, format, NULL, out, diag);
}

int tpk_import_any_with(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                        tpk_mesh *out, tpk_diag *diag)
{
    return tpk_import_any_whole(path, format, tetgen, 0, out, diag);
}

int tpk_import_any_whole(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                         int higher_order_whole, tpk_mesh *out, tpk_diag *diag)
{
    int rc = import_any(path, format, tetgen, out, diag);
    if (rc == 0 && !higher_order_whole)
        tpk_reduce_higher_order(out, path, diag);
    return rc;
}

static int import_any(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                      tpk_mesh *out, tpk_diag *diag)
{
    if (!path || !out)
        return tpk_diag_fail(diag, "tpk_import_any: no path or output mesh given");
    char names[512];
    if (format && *format && strcasecmp(format, "auto") != 0) {
        const tpk_import_format *row = tpk_import_format_named(format, path);
        if (row && gzipped(path))
            return import_gzip(row, path, out, diag);
        if (row)
            return import_with(row, 1, path, tetgen, out, diag);
        memset(out, 0, sizeof *out);
        return tpk_diag_fail(diag, "%s: unknown input format '%s'; supported: %s (tetpack formats lists them)",
                             path, format, tpk_import_format_names(names, sizeof names));
    }
    /* A directory names no format by extension or content: an OpenFOAM case is told by its polyMesh. */
    if (tpk_openfoam_is_case(path))
        return import_with(tpk_import_format_named("openfoam", NULL), 0, path, tetgen, out, diag);
    const tpk_import_format *row = tpk_import_format_detect(path);
    if (gzipped(path) && access(path, F_OK) == 0)
        return import_gzip(row, path, out, diag);
    if (row)
        return import_with(row, 0, path, tetgen, out, diag);
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
                         "supported: %s (force one with --format; tetpack formats lists them)", path,
                         tpk_import_format_names(names, sizeof names));
}

void tpk_import_input_files(const char *path, const char *format, tpk_import_file_fn each, void *user)
{
    each(user, path);
    const tpk_import_format *row = format && *format && strcasecmp(format, "auto") != 0
                                       ? tpk_import_format_named(format, path)
                                       : tpk_import_format_detect(path);
    struct stat st;
    if (gzipped(path)) /* one file: the compressed forms of TetGen and .pvd are refused */
        return;
    if ((row && row->read == tpk_import_tetgen) || (!row && stat(path, &st) != 0)) /* a TetGen stem */
        tpk_import_tetgen_files(path, each, user);
    else if (row && row->read == tpk_import_pvd)
        tpk_import_pvd_files(path, each, user);
    else if (row && row->read == tpk_import_xdmf)
        tpk_import_xdmf_files(path, each, user);
    else if ((row && row->read == tpk_import_openfoam) || tpk_openfoam_is_case(path))
        tpk_import_openfoam_files(path, each, user);
}
