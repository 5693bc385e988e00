/* CGNS importer: SEACAS's three CGNS files, and files written here with the CGNS library itself (a mixed
 * unstructured zone, a MIXED section, higher-order elements, NGON_n/NFACE_n polyhedra, a structured zone,
 * Vertex and CellCenter solutions with iterative data), read back through tetpack; damaged files. */
#include <cgnslib.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "tpk_assert.h"
#include "import/importers.h"
#include "convert/pipeline.h"
#include "mesh/polyhedron.h"

/* Convert `path` (tpk_convert_checked: the 6xx MUSTs hold) and return the report. */
static int convert_file(const char *path, int skip_bad_cells, tpk_convert_report *rep, tpk_diag *d)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = path;
    o.skip_bad_cells = skip_bad_cells;
    o.output = tpk_temp_path("out.tpk");
    o.threads = 1;
    memset(rep, 0, sizeof *rep);
    memset(d, 0, sizeof *d);
    return tpk_convert_checked(&o, rep, d);
}

static int count_fields(const tpk_mesh *m, int association, int steps)
{
    int n = 0;
    for (int i = 0; i < m->field_count; i++)
        n += m->fields[i].association == association && m->fields[i].step_count == steps;
    return n;
}

/* The three SEACAS files: cells, points, fields and steps as their writers (IOSS) put them; every
 * hexahedron positive in VTK order after conversion (no mirrored cell, no inverted tet).
 * BC_without_parents.cgns is an O-grid whose axis cells are nearly flat (1,696 hexes have two corners
 * within 1e-4 of each other, none exactly equal): 67 of them cannot split even from a centre point and
 * need --skip-bad-cells; the count is pinned so that a change in how they are read shows. */
TPK_TEST(seacas_files)
{
    static const struct {
        const char *path;
        int64_t points, cells;
        int point_fields, cell_fields, steps;
        int64_t bad_cells;
    } files[] = {{"seacas/BC_without_parents.cgns", 4505, 3840, 0, 0, 1, 67},
                 {"seacas/generated.cgns", 27, 8, 2, 3, 2, 0},
                 {"seacas/aero_blunt_wedge_test3.cgns", 50, 16, 0, 6, 5, 0}};
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        tpk_mesh m;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        CHECK_MSG(tpk_import_any(tpk_data_path(files[f].path), NULL, &m, &d) == 0, "%s", d.message);
        int hexes = 0;
        for (int64_t c = 0; c < m.cell_count; c++)
            hexes += m.cell_types[c] == TPK_CELL_HEXAHEDRON;
        int ok = m.point_count == files[f].points && m.cell_count == files[f].cells && hexes == m.cell_count &&
                 count_fields(&m, TPK_ASSOC_POINT, files[f].steps) == files[f].point_fields &&
                 count_fields(&m, TPK_ASSOC_TET, files[f].steps) == files[f].cell_fields &&
                 m.field_count == files[f].point_fields + files[f].cell_fields && m.step_count == files[f].steps &&
                 (files[f].steps == 1) == (m.times == NULL) && !strcmp(m.format, "cgns");
        printf("%s: %lld points %lld cells %d fields %d steps\n", files[f].path, (long long)m.point_count,
               (long long)m.cell_count, m.field_count, m.step_count);
        tpk_mesh_free(&m);
        CHECK_MSG(ok, "%s: counts, fields or steps differ", files[f].path);
        tpk_convert_report rep;
        CHECK_MSG(convert_file(tpk_data_path(files[f].path), files[f].bad_cells > 0, &rep, &d) == 0, "%s", d.message);
        printf("  tets %lld mirrored %lld inverted %lld bad %lld\n", (long long)rep.tets, (long long)rep.mirrored_cells,
               (long long)rep.inverted_fixed, (long long)rep.bad_cells_skipped);
        CHECK_MSG(rep.mirrored_cells == 0 && rep.inverted_fixed == 0 && rep.source_cells == files[f].cells &&
                      rep.step_count == files[f].steps && rep.bad_cells_skipped == files[f].bad_cells,
                  "%s: %lld mirrored cells, %lld inverted tets", files[f].path, (long long)rep.mirrored_cells,
                  (long long)rep.inverted_fixed);
    }
}

/* ---- Files written with the CGNS library ---- */

/* The SIDS reference cells (Elements_t figures): corners of TETRA_4, PYRA_5, PENTA_6, HEXA_8 in CGNS
 * order. The SIDS face tables call TETRA (1,3,2), PYRA (1,4,3,2), PENTA (1,3,2) and HEXA (1,4,3,2)
 * outward, i.e. the first face turns clockwise seen from outside: with these coordinates that face lies
 * in z = 0 with the rest of the cell above it. */
static const double ref_tetra[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const double ref_pyra[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
static const double ref_penta[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
static const double ref_hexa[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                      {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

typedef struct points_builder {
    double xyz[3][256];
    int count;
} points_builder;

/* Add a reference cell's corners moved by (dx, 0, 0), then `extra` higher-order nodes (at the
 * centroid: their place does not matter, only that the reader skips them); ids (1-based) into conn. */
static cgsize_t *add_cell(points_builder *p, const double (*ref)[3], int corners, int extra, double dx,
                          cgsize_t *conn)
{
    double centre[3] = {0, 0, 0};
    for (int k = 0; k < corners; k++) {
        for (int a = 0; a < 3; a++) {
            p->xyz[a][p->count] = ref[k][a] + (a == 0 ? dx : 0);
            centre[a] += p->xyz[a][p->count] / corners;
        }
        *conn++ = ++p->count;
    }
    for (int k = 0; k < extra; k++) {
        for (int a = 0; a < 3; a++)
            p->xyz[a][p->count] = centre[a];
        *conn++ = ++p->count;
    }
    return conn;
}

static int write_coords(int fn, int base, int zone, const double *x, const double *y, const double *z)
{
    int c;
    return cg_coord_write(fn, base, zone, RealDouble, "CoordinateX", x, &c) ||
           cg_coord_write(fn, base, zone, RealDouble, "CoordinateY", y, &c) ||
           cg_coord_write(fn, base, zone, RealDouble, "CoordinateZ", z, &c);
}

/* Zone "cells": one section per linear kind, higher-order sections (corners first, then the rest), a
 * boundary QUAD_4 section, and a MIXED section; 15 volume elements in element-number order:
 * TETRA_4, PYRA_5, PENTA_6, HEXA_8 (elements 1-4), QUAD_4 (5), TETRA_10, PYRA_14, PENTA_15, PENTA_18,
 * HEXA_20, HEXA_27 (6-11), MIXED: TETRA_4 PYRA_5 QUAD_4 PENTA_6 HEXA_8 TETRA_10 (12-17). Returns the
 * zone's point count, or -1. */
static int write_cells_zone(int fn, int base, int *zone_out)
{
    static const struct {
        ElementType_t type;
        const double (*ref)[3];
        int corners, extra;
    } fixed[] = {{TETRA_4, ref_tetra, 4, 0},   {PYRA_5, ref_pyra, 5, 0},     {PENTA_6, ref_penta, 6, 0},
                 {HEXA_8, ref_hexa, 8, 0},     {QUAD_4, ref_hexa, 4, 0},     {TETRA_10, ref_tetra, 4, 6},
                 {PYRA_14, ref_pyra, 5, 9},    {PENTA_15, ref_penta, 6, 9},  {PENTA_18, ref_penta, 6, 12},
                 {HEXA_20, ref_hexa, 8, 12},   {HEXA_27, ref_hexa, 8, 19}},
      mixed[] = {{TETRA_4, ref_tetra, 4, 0}, {PYRA_5, ref_pyra, 5, 0}, {QUAD_4, ref_hexa, 4, 0},
                 {PENTA_6, ref_penta, 6, 0}, {HEXA_8, ref_hexa, 8, 0}, {TETRA_10, ref_tetra, 4, 6}};
    static points_builder p;
    cgsize_t conn[11][32], mixed_conn[64], offsets[7] = {0}, *at = mixed_conn;
    int n_fixed = sizeof fixed / sizeof fixed[0], n_mixed = sizeof mixed / sizeof mixed[0], s;
    p.count = 0;
    for (int e = 0; e < n_fixed; e++)
        add_cell(&p, fixed[e].ref, fixed[e].corners, fixed[e].extra, 2.0 * e, conn[e]);
    for (int e = 0; e < n_mixed; e++) {
        *at++ = mixed[e].type;
        at = add_cell(&p, mixed[e].ref, mixed[e].corners, mixed[e].extra, 2.0 * (e + n_fixed), at);
        offsets[e + 1] = at - mixed_conn;
    }
    cgsize_t size[3] = {p.count, 15, 0};
    if (cg_zone_write(fn, base, "cells", size, Unstructured, zone_out) ||
        write_coords(fn, base, *zone_out, p.xyz[0], p.xyz[1], p.xyz[2]))
        return -1;
    for (int e = 0; e < n_fixed; e++)
        if (cg_section_write(fn, base, *zone_out, cg_ElementTypeName(fixed[e].type), fixed[e].type, e + 1, e + 1, 0,
                             conn[e], &s))
            return -1;
    if (cg_poly_section_write(fn, base, *zone_out, "mixed", MIXED, n_fixed + 1, n_fixed + n_mixed, 0, mixed_conn,
                              offsets, &s))
        return -1;
    return p.count;
}

/* Zone "poly": two unit cubes side by side as NFACE_n polyhedra over 11 NGON_n quads (elements 1-11,
 * cells 12-13). Faces are written with their normals along +x, +y or +z; each cell lists a face whose
 * normal points into it with a minus sign, as the SIDS ask. */
static int write_poly_zone(int fn, int base, int *zone_out)
{
    double x[12], y[12], z[12];
    for (int i = 0; i < 12; i++) /* point (i % 3, (i / 3) % 2, i / 6) */
        x[i] = i % 3, y[i] = (i / 3) % 2, z[i] = i / 6;
#define P(a, b, c) (1 + (a) + 3 * (b) + 6 * (c))
    static const cgsize_t quads[11][4] = {
        {P(0, 0, 0), P(0, 1, 0), P(0, 1, 1), P(0, 0, 1)}, {P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1)},
        {P(2, 0, 0), P(2, 1, 0), P(2, 1, 1), P(2, 0, 1)}, /* x = 0, 1, 2 (normal +x) */
        {P(0, 0, 0), P(0, 0, 1), P(1, 0, 1), P(1, 0, 0)}, {P(1, 0, 0), P(1, 0, 1), P(2, 0, 1), P(2, 0, 0)},
        {P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0)}, {P(1, 1, 0), P(1, 1, 1), P(2, 1, 1), P(2, 1, 0)}, /* y */
        {P(0, 0, 0), P(1, 0, 0), P(1, 1, 0), P(0, 1, 0)}, {P(1, 0, 0), P(2, 0, 0), P(2, 1, 0), P(1, 1, 0)},
        {P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1)}, {P(1, 0, 1), P(2, 0, 1), P(2, 1, 1), P(1, 1, 1)}}; /* z */
#undef P
    cgsize_t face_offsets[12], cells[12] = {-1, 2, -4, 6, -8, 10, -2, 3, -5, 7, -9, 11}, cell_offsets[3] = {0, 6, 12};
    for (int f = 0; f <= 11; f++)
        face_offsets[f] = 4 * f;
    cgsize_t size[3] = {12, 2, 0};
    int s;
    return cg_zone_write(fn, base, "poly", size, Unstructured, zone_out) || write_coords(fn, base, *zone_out, x, y, z) ||
           cg_poly_section_write(fn, base, *zone_out, "faces", NGON_n, 1, 11, 0, &quads[0][0], face_offsets, &s) ||
           cg_poly_section_write(fn, base, *zone_out, "cells", NFACE_n, 12, 13, 0, cells, cell_offsets, &s);
}

/* Zone "grid": 3 x 3 x 2 vertices with x decreasing along i, a left-handed (i, j, k) frame. */
static int write_grid_zone(int fn, int base, int *zone_out)
{
    double x[18], y[18], z[18];
    for (int v = 0; v < 18; v++)
        x[v] = 10 - v % 3, y[v] = (v / 3) % 3, z[v] = v / 9;
    cgsize_t size[9] = {3, 3, 2, 2, 2, 1, 0, 0, 0};
    return cg_zone_write(fn, base, "grid", size, Structured, zone_out) || write_coords(fn, base, *zone_out, x, y, z);
}

static int write_field(int fn, int base, int zone, const char *sol_name, GridLocation_t at, const char *field,
                       const double *values)
{
    int s, f;
    return cg_sol_write(fn, base, zone, sol_name, at, &s) || cg_field_write(fn, base, zone, s, RealDouble, field, values, &f);
}

/* Three steps at times 0.5, 1, 2: zone "cells" has Vertex solutions T1..T3 ("temperature" = 100 step +
 * vertex) named by its FlowSolutionPointers; every zone has a static CellCenter "material" (zone base
 * 0, 100, 200 + cell) and the other zones a static Vertex "temperature" (7 and -1). */
static int write_solutions(int fn, int base, const int *zones, int cells_points)
{
    static const double times[3] = {0.5, 1, 2};
    static const char *const material_base_names[3] = {"m0", "m100", "m200"};
    double values[256];
    char pointers[3][32];
    cgsize_t steps = 3, dims[2] = {32, 3};
    for (int s = 0; s < 3; s++) {
        char name[33];
        snprintf(name, sizeof name, "T%d", s + 1);
        memset(pointers[s], ' ', 32);
        memcpy(pointers[s], name, strlen(name));
        for (int v = 0; v < cells_points; v++)
            values[v] = 100.0 * s + v;
        if (write_field(fn, base, zones[0], name, Vertex, "temperature", values))
            return -1;
    }
    for (int z = 0; z < 3; z++) {
        for (int c = 0; c < 15; c++)
            values[c] = 100.0 * z + c;
        if (write_field(fn, base, zones[z], material_base_names[z], CellCenter, "material", values))
            return -1;
        for (int v = 0; z > 0 && v < 18; v++)
            values[v] = z == 1 ? 7 : -1;
        if (z > 0 && write_field(fn, base, zones[z], "static", Vertex, "temperature", values))
            return -1;
    }
    return cg_biter_write(fn, base, "TimeIterValues", 3) || cg_goto(fn, base, "BaseIterativeData_t", 1, "end") ||
           cg_array_write("TimeValues", RealDouble, 1, &steps, times) ||
           cg_ziter_write(fn, base, zones[0], "ZoneIterativeData") ||
           cg_goto(fn, base, "Zone_t", zones[0], "ZoneIterativeData_t", 1, "end") ||
           cg_array_write("FlowSolutionPointers", Character, 2, dims, pointers);
}

/* The whole test file; `file_type` CG_FILE_HDF5 or CG_FILE_ADF. Returns the "cells" zone's point count. */
static int write_test_file(const char *path, int file_type)
{
    int fn, base, zones[3];
    if (cg_set_file_type(file_type) || cg_open(path, CG_MODE_WRITE, &fn))
        return -1;
    int points = cg_base_write(fn, "Base", 3, 3, &base) ? -1 : write_cells_zone(fn, base, &zones[0]);
    int bad = points < 0 || write_poly_zone(fn, base, &zones[1]) || write_grid_zone(fn, base, &zones[2]) ||
              write_solutions(fn, base, zones, points);
    cg_close(fn);
    cg_set_file_type(CG_FILE_NONE);
    return bad ? -1 : points;
}

/* The cell kinds, in element-number order, each zone after the other in the order the library lists
 * them (by name: cells, grid, poly): what the reader must give. */
static const uint8_t expected_types[] = {10, 14, 13, 12, 10, 14, 13, 13, 12, 12, 10, 14, 13, 12, 10,
                                         12, 12, 12, 12, 42, 42};

TPK_TEST(written_file_reads_back)
{
    const char *path = tpk_temp_path("written.cgns");
    int points = write_test_file(path, CG_FILE_HDF5);
    CHECK_MSG(points > 0, "writing %s: %s", path, cg_get_error());
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(path, NULL, &m, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(m.point_count, points + 12 + 18);
    CHECK_EQ_INT(m.cell_count, sizeof expected_types);
    CHECK(!memcmp(m.cell_types, expected_types, sizeof expected_types));
    /* Higher-order cells keep their corners, the first ids of each element: the fourth cell (HEXA_8,
     * element 4) uses points 18..25 (after tetra 4, pyra 5, penta 6 and a skipped QUAD_4 of 4 after it). */
    for (int k = 0; k < 8; k++)
        CHECK_EQ_INT(m.cell_conn[m.cell_offsets[3] + k], 15 + k);
    CHECK_EQ_INT(m.cell_conn[m.cell_offsets[4]], 27); /* TETRA_10 after the QUAD_4's 4 points */
    CHECK(m.step_count == 3 && m.times && m.times[0] == 0.5 && m.times[1] == 1 && m.times[2] == 2);
    const tpk_src_field *temperature = NULL, *material = NULL;
    for (int i = 0; i < m.field_count; i++) {
        if (!strcmp(m.fields[i].name, "temperature") && m.fields[i].association == TPK_ASSOC_POINT)
            temperature = &m.fields[i];
        if (!strcmp(m.fields[i].name, "material") && m.fields[i].association == TPK_ASSOC_TET)
            material = &m.fields[i];
    }
    CHECK_MSG(m.field_count == 2 && temperature && material && temperature->step_count == 3 &&
                  material->step_count == 1, "%d fields", m.field_count);
    for (int s = 0; s < 3; s++)
        for (int64_t v = 0; v < m.point_count; v++) {
            float want = v < points ? 100.0f * s + v : v < points + 18 ? -1.0f : 7.0f;
            CHECK_MSG(temperature->values[s * m.point_count + v] == want, "step %d point %lld: %g, expected %g", s,
                      (long long)v, temperature->values[s * m.point_count + v], want);
        }
    for (int64_t c = 0; c < m.cell_count; c++)
        CHECK_EQ_INT(material->values[c], c < 15 ? c : c < 19 ? 200 + c - 15 : 100 + c - 19);
    /* The polyhedra's faces come out outward (NFACE_n's minus signs turned them). */
    for (int64_t c = 19; c < 21; c++) {
        tpk_polygons p;
        memset(&p, 0, sizeof p);
        CHECK(tpk_polygons_from_stream(&p, m.faces + m.face_offsets[c], m.face_offsets[c + 1] - m.face_offsets[c]) == 0);
        double volume6 = tpk_polygons_volume6(&p, m.points);
        tpk_polygons_free(&p);
        CHECK_MSG(fabs(volume6 - 6) < 1e-12, "polyhedron %lld: 6 x volume %g, expected 6", (long long)c, volume6);
    }
    tpk_mesh_free(&m);
    /* Converted: no cell mirrored (SIDS reference cells, a left-handed grid), the 6xx MUSTs hold. */
    tpk_convert_report rep;
    CHECK_MSG(convert_file(path, 0, &rep, &d) == 0, "%s", d.message);
    CHECK_MSG(rep.mirrored_cells == 0 && rep.inverted_fixed == 0 && rep.polyhedra == 2 && rep.step_count == 3 &&
                  rep.cells_into[1] == 4 && rep.cells_into[2] == 3 && rep.cells_into[3] == 4 &&
                  rep.cells_into[5] + rep.cells_into[6] == 8,
              "%lld mirrored, %lld polyhedra, tets %lld pyramids %lld wedges %lld", (long long)rep.mirrored_cells,
              (long long)rep.polyhedra, (long long)rep.cells_into[1], (long long)rep.cells_into[2],
              (long long)rep.cells_into[3]);
}
