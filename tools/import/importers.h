/* Importers: each reads one file format into a tpk_mesh. On error they return -1 with a message in
 * diag naming the file, the place (line or byte offset), what was expected and what was found, and
 * leave *out empty. Bounded memory on absurd counts: counts are checked against the file size.
 *
 * The registry (registry.c) holds one row per format: its name, extensions, a content sniffer, its
 * readers and what it carries. `--format`, detection, the `--help` lists, `tetpack formats` and the
 * fuzz targets (tests/fuzz/CMakeLists.txt reads the rows) all come from it: adding a format is one
 * reader file plus one row. */
#ifndef TPK_IMPORTERS_H
#define TPK_IMPORTERS_H

#include <stddef.h>

#include "base/diag.h"
#include "mesh/mesh.h"

/* VTK legacy UNSTRUCTURED_GRID, ASCII or BINARY (big-endian). */
int tpk_import_vtk_legacy(const char *path, tpk_mesh *out, tpk_diag *diag);
/* Same from memory (for fuzzing); `name` is used in messages. */
int tpk_import_vtk_legacy_memory(const char *name, const char *data, size_t size, tpk_mesh *out,
                                 tpk_diag *diag);
/* Called once per file an input consists of (tpk_import_input_files). */
typedef void (*tpk_import_file_fn)(void *user, const char *file);

/* TetGen .node/.ele: path may name either file or their common stem. */
int tpk_import_tetgen(const char *path, tpk_mesh *out, tpk_diag *diag);
/* Its two files, STEM.node then STEM.ele, whether or not they exist. */
void tpk_import_tetgen_files(const char *path, tpk_import_file_fn each, void *user);
/* Same from memory (for fuzzing); messages name `name`.node and `name`.ele. */
int tpk_import_tetgen_memory(const char *name, const char *node_data, size_t node_size, const char *ele_data,
                             size_t ele_size, tpk_mesh *out, tpk_diag *diag);
/* Both files in one buffer (the registry's memory form): the .node text, a line "@@ele", then the .ele
 * text; without that line all of it is the .node file. A ".node" or ".ele" ending of `name` is dropped. */
int tpk_import_tetgen_bundle_memory(const char *name, const char *data, size_t size, tpk_mesh *out,
                                    tpk_diag *diag);

/* Medit .mesh (ASCII): Vertices, Tetrahedra, Hexahedra (surface and line elements dropped with a
 * warning); element references become the cell field "ref", non-zero vertex references "vertex_ref". */
int tpk_import_medit(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_medit_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
/* Binary Medit (.meshb, libMeshb versions 1-4, either byte order): the same content as the ASCII form;
 * unknown keywords are skipped by their offsets. */
int tpk_import_meshb(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_meshb_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* VTK XML UnstructuredGrid (.vtu): ascii, base64 binary and raw appended data, zlib-compressed or not,
 * UInt32 or UInt64 headers (expat parses the XML). Point and cell data arrays become fields. */
int tpk_import_vtu(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_vtu_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
/* ParaView series (.pvd): one .vtu per time step (paths relative to the .pvd), all with the same mesh;
 * their fields become fields with one step per file, in time order, with the time values. */
int tpk_import_pvd(const char *path, tpk_mesh *out, tpk_diag *diag);
/* The series' .vtu files, as tpk_import_pvd reads them; none when the .pvd does not parse (the import
 * then says why). */
void tpk_import_pvd_files(const char *path, tpk_import_file_fn each, void *user);

/* Gmsh .msh 2.2 and 4.1, ASCII and binary: volume elements (tets, hexes, prisms, pyramids, and their
 * higher-order kinds whole) in VTK node order, $NodeData/$ElementData as fields. */
int tpk_import_gmsh(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_gmsh_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* NASA/AFLR3 UGRID: .ugrid (ASCII), .b8.ugrid (big-endian), .lb8.ugrid (little-endian); tetrahedra
 * (surface elements dropped; pyramids, prisms and hexahedra refused until their node order is checked).
 * The memory form takes the kind from `name`'s extension. */
int tpk_import_ugrid(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_ugrid_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* Abaqus / CalculiX .inp: *NODE, *ELEMENT (solids C3D4/6/8/10/15/20/27 and variants, higher-order ones
 * whole; surfaces, shells and beams dropped), *ELSET and ELSET= as the cell field "elset"
 * (set numbers from 1 in the order the names first appear), *INCLUDE relative to the including file.
 * The memory form resolves includes relative to `name`. */
int tpk_import_inp(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_inp_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* Legacy DOLFIN XML (FEniCS; meshio's dolfin-xml): tetrahedron or hexahedron meshes (hexahedra from
 * DOLFIN's lexicographic vertex order to VTK's), <domains> value collections of cells as cell fields.
 * tpk_sniff_dolfin: "<dolfin" is among the first bytes. */
int tpk_import_dolfin(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_dolfin_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
int tpk_sniff_dolfin(const char *head, size_t n);

/* Exodus II (.exo, .e, .g, .ex2; netCDF classic or netCDF-4) through the Exodus library: tetra, hex,
 * wedge and pyramid blocks (higher-order ones whole), nodal and element variables with every
 * time step. */
int tpk_import_exodus(const char *path, tpk_mesh *out, tpk_diag *diag);

/* CGNS (.cgns; HDF5 or ADF) through the CGNS library, file only (the library reads files, so no memory
 * reader and no fuzz target): the first 3-D base, its zones merged (each keeps its vertices);
 * unstructured TETRA, PYRA, PENTA, HEXA (higher-order ones whole), MIXED and NGON_n/NFACE_n
 * (polyhedra) sections, structured zones as hexahedra; Vertex and CellCenter FlowSolutions as point and
 * cell fields, with a step per BaseIterativeData step where ZoneIterativeData points at them. Built
 * with TETPACK_WITH_CGNS (TPK_WITH_CGNS). */
int tpk_import_cgns(const char *path, tpk_mesh *out, tpk_diag *diag);
/* XDMF (.xdmf, .xmf; Xdmf 2 and 3) as meshio, FEniCS/dolfinx and many solvers write it: the Uniform
 * Grid with volume cells (Tetrahedron, Pyramid, Wedge, Hexahedron, Mixed; higher-order types whole;
 * surfaces dropped), Geometry XYZ, XY or X_Y_Z, Node and Cell Attributes as fields; a Temporal
 * Collection's grids as time steps (one mesh, by XInclude or Reference, or identical). DataItems in XML
 * text, or in HDF5 (file.h5:/dataset, relative to the .xdmf file; needs TETPACK_WITH_HDF5). */
int tpk_import_xdmf(const char *path, tpk_mesh *out, tpk_diag *diag);
/* The HDF5 files its DataItems name, as tpk_import_xdmf resolves them; none when the XML does not
 * parse (the import then says why). */
void tpk_import_xdmf_files(const char *path, tpk_import_file_fn each, void *user);
/* An XML declaration, comments and a DOCTYPE at most before the root element <Xdmf (registry sniff). */
int tpk_import_xdmf_sniff(const char *head, size_t got);
/* Same from memory (for fuzzing): XML DataItems only, HDF data refused. */
int tpk_import_xdmf_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);

/* VTKHDF (.vtkhdf, .hdf; VTK's HDF5 format) through the HDF5 C library: Type UnstructuredGrid, Version 1
 * and 2; the partitions of a step merged into one mesh (points of different partitions with equal
 * coordinates become one); volume cells as tpk_cell_rule_for keeps them, polyhedra from
 * FaceConnectivity/FaceOffsets/PolyhedronToFaces/PolyhedronOffsets; PointData and CellData as fields, a
 * step per Steps entry with Steps/Values as times (every step must have the same mesh). Built with
 * TETPACK_WITH_HDF5 (TPK_HAVE_HDF5); without it the readers say so. The memory form opens the bytes
 * as an HDF5 file image (the core driver, a copy). tpk_import_vtkhdf_probe: `path` is an HDF5 file with
 * a /VTKHDF group (detection of files without the extension). */
int tpk_import_vtkhdf(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_import_vtkhdf_memory(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
int tpk_import_vtkhdf_probe(const char *path);

/* OpenFOAM case directories: `path` is the case, its constant/polyMesh, or a file in the case (ParaView's
 * CASE.foam). constant/polyMesh's points, faces (faceList or faceCompactList), owner and neighbour, ASCII
 * or binary (arch "LSB;label=32;scalar=64"), each plain or .gz; every cell a polyhedron (VTK 42) with
 * outward faces. The numeric time directories' volScalarField, volVectorField (cell fields) and
 * pointScalarField (point fields) named in the latest one, one time step per directory in time order.
 * A directory format: no memory reader. tpk_openfoam_is_case: `path` is a directory holding
 * constant/polyMesh/faces or faces.gz, or is such a polyMesh directory (detection). */
int tpk_import_openfoam(const char *path, tpk_mesh *out, tpk_diag *diag);
int tpk_openfoam_is_case(const char *path);
/* The polyMesh files the case's mesh comes from (each plain and .gz, existing or not); none when `path`
 * is not a case. */
void tpk_import_openfoam_files(const char *path, tpk_import_file_fn each, void *user);

/* What a format carries into the converter (tetpack formats prints these). */
enum {
    TPK_FORMAT_TETS = 1u << 0,
    TPK_FORMAT_HEXAHEDRA = 1u << 1,
    TPK_FORMAT_WEDGES = 1u << 2,
    TPK_FORMAT_PYRAMIDS = 1u << 3,
    TPK_FORMAT_VOXELS = 1u << 4,
    TPK_FORMAT_POLYHEDRA = 1u << 5,
    TPK_FORMAT_SURFACE = 1u << 6,      /* a closed surface, filled with tets by TetGen */
    TPK_FORMAT_POINT_CLOUD = 1u << 7,  /* points, tetrahedralized (Delaunay) by TetGen */
    TPK_FORMAT_POINT_FIELDS = 1u << 8,
    TPK_FORMAT_CELL_FIELDS = 1u << 9,
    TPK_FORMAT_TIME_STEPS = 1u << 10,
    TPK_FORMAT_GZIP = 1u << 11         /* FILE.<ext>.gz is read too: inflated in memory for read_memory */
};

/* How many first bytes detection reads for magic and sniff. */
#define TPK_IMPORT_HEAD_BYTES 512

/* One row of the registry. */
typedef struct tpk_import_format {
    const char *name;       /* what --format takes */
    const char *aliases;    /* other names --format takes, space-separated; NULL: none */
    const char *title;      /* one line for the help and `tetpack formats` */
    const char *extensions; /* space-separated, compared case-insensitively ("" : only by name) */
    const char *magic;      /* sniffer: the file starts (after blanks) with one of these, '|'-separated;
                               NULL: not recognised by content */
    /* NULL, or a check of the first bytes (head[0 .. n), up to TPK_IMPORT_HEAD_BYTES): a match by extension
     * or magic must also pass it (for generic extensions and magic shared with other rows: ".xml",
     * "<?xml"), and detection asks it before any magic, so a row claims the files it recognises (XDMF's
     * "<?xml ... <Xdmf" before VTU's "<?xml"). */
    int (*sniff)(const char *head, size_t n);
    /* NULL, or a look into the file itself where the first bytes cannot tell (a container such as HDF5):
     * detection asks it, for a file whose first bytes match `magic` and whose extension no row takes,
     * before trying rows by magic (VTKHDF's /VTKHDF group before Exodus's "\x89HDF"). */
    int (*probe)(const char *path);
    /* The file reader; NULL for TetGen readings, which go through tpk_import_surface. */
    int (*read)(const char *path, tpk_mesh *out, tpk_diag *diag);
    /* Parses a whole file held in memory, nothing else (no TetGen); NULL: none. Each format that has one
     * gets a fuzz target fuzz_<name> over tests/fuzz/corpus/fuzz_<name>. */
    int (*read_memory)(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag);
    int surface_kind;       /* TetGen readings: tpk_surface_kind and tpk_surface_mode (surface.h) */
    int surface_mode;
    unsigned supports;      /* TPK_FORMAT_* */
    /* NULL, or the library we do not control that parses the files ("HDF5"): `read` and `probe` then run
     * in a child process (isolate.h), so that a crash of that library on a damaged file is an error
     * naming the file, not the end of tetpack. */
    const char *isolated;
} tpk_import_format;

/* The registry's rows, in detection order; *count gets their number. */
const tpk_import_format *tpk_import_formats(size_t *count);
/* The row `--format name` selects (name or alias, any case); where several rows take the name, the
 * one whose extension `path` has (may be NULL). NULL when no row takes it. */
const tpk_import_format *tpk_import_format_named(const char *name, const char *path);
/* The row for a file: the first whose extension `path` has (and whose sniff, if any, passes), else the
 * first whose sniff takes the file's first bytes, else the first whose magic starts the file. NULL when
 * none tells (or the file cannot be read). For FILE.gz, the same on the name without ".gz" and the
 * inflated first bytes. */
const tpk_import_format *tpk_import_format_detect(const char *path);
/* The format names (and aliases) as "vtk, vtu, ..." into buf; returns buf. */
const char *tpk_import_format_names(char *buf, size_t cap);
/* The supported-bits as words ("tets hexahedra ... time-steps") into buf; returns buf. */
const char *tpk_import_format_supports(unsigned supports, char *buf, size_t cap);

/* Every file that reading `path` (as tpk_import_any_with would, `format` forcing a row or NULL) opens,
 * each passed to `each`: `path` itself first, then TetGen's .node and .ele (from either file or their
 * stem), a .pvd's pieces, an XDMF file's HDF5 files; other formats are one file. Files need not exist.
 * For refusing an output that would replace an input (base/output_file.h). */
void tpk_import_input_files(const char *path, const char *format, tpk_import_file_fn each, void *user);

/* Pick the importer from the extension (and the file's first bytes); format may force one by a
 * registry name (tpk_import_format_named). A TetGen stem (no file, but STEM.node exists) reads as
 * TetGen. A path ending in ".gz" is inflated in memory (gzip_input.h) and read by the memory reader of
 * the row its inner name or content picks, when that row has TPK_FORMAT_GZIP; messages name the .gz
 * file, with places in the inflated bytes. */
int tpk_import_any(const char *path, const char *format, tpk_mesh *out, tpk_diag *diag);
/* The same with TetGen's settings for surfaces (NULL: defaults). The readers keep higher-order volume
 * cells whole (all their nodes, in VTK order); these two reduce them to their corners after reading
 * (mesh/higher_order.h, with a warning), as every tool but the converter wants them. */
struct tpk_tetgen_options;
int tpk_import_any_with(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                        tpk_mesh *out, tpk_diag *diag);
/* The same, keeping higher-order cells whole when higher_order_whole is set (the converter splits them). */
int tpk_import_any_whole(const char *path, const char *format, const struct tpk_tetgen_options *tetgen,
                         int higher_order_whole, tpk_mesh *out, tpk_diag *diag);

#endif
