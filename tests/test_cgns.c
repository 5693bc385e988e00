/* CGNS importer: SEACAS's three CGNS files, and files written here with the CGNS library itself (a mixed
 * unstructured zone, a MIXED section, higher-order elements, NGON_n/NFACE_n polyhedra, a structured zone,
 * Vertex and CellCenter solutions with iterative data), read back through tetpack; damaged files. */
#include <cgnslib.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "same_mesh.h"
#include "base/parallel.h"
#include "tpk_assert.h"
#include "import/importers.h"
#include "convert/pipeline.h"
#include "mesh/polyhedron.h"

/* Convert `path` (tpk_convert_checked: the 6xx MUSTs hold) and return the report; `corners`: higher-order
 * cells reduced to their corners (--higher-order corners). */
static int convert_file(const char *path, int skip_bad_cells, int corners, tpk_convert_report *rep, tpk_diag *d)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = path;
    o.higher_order_corners = corners;
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
 * within 1e-4 of each other, none exactly equal): decided on the float32 grid the file stores (origin 0,
 * spec §6.8), 67 of them have every tet of their split negative, so they read as mirrored and are turned
 * over (with no fold: the converted file passes the 6xx checks). The counts are pinned so that a change
 * in how they are read shows. */
TPK_TEST(seacas_files)
{
    static const struct {
        const char *path;
        int64_t points, cells;
        int point_fields, cell_fields, steps;
        int64_t bad_cells, mirrored_cells;
    } files[] = {{"seacas/BC_without_parents.cgns", 4505, 3840, 0, 0, 1, 0, 67},
                 {"seacas/generated.cgns", 27, 8, 2, 3, 2, 0, 0},
                 {"seacas/aero_blunt_wedge_test3.cgns", 50, 16, 0, 6, 5, 0, 0}};
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
        CHECK_MSG(convert_file(tpk_data_path(files[f].path), files[f].bad_cells > 0, 0, &rep, &d) == 0, "%s", d.message);
        printf("  tets %lld mirrored %lld inverted %lld bad %lld\n", (long long)rep.tets, (long long)rep.mirrored_cells,
               (long long)rep.inverted_fixed, (long long)rep.bad_cells_skipped);
        CHECK_MSG(rep.mirrored_cells == files[f].mirrored_cells && rep.inverted_fixed == 0 && rep.source_cells == files[f].cells &&
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
    /* tpk_import_any reduces higher-order cells to their corners, the first ids of each element: the fourth cell (HEXA_8,
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
    /* Converted: no cell mirrored (SIDS reference cells, a left-handed grid), the 6xx MUSTs hold. The
     * higher-order cells' other nodes sit at their centroids here: reduced to corners. */
    tpk_convert_report rep;
    CHECK_MSG(convert_file(path, 0, 1, &rep, &d) == 0, "%s", d.message);
    CHECK_MSG(rep.mirrored_cells == 0 && rep.inverted_fixed == 0 && rep.polyhedra == 2 && rep.step_count == 3 &&
                  rep.cells_into[1] == 4 && rep.cells_into[2] == 3 && rep.cells_into[3] == 4 &&
                  rep.cells_into[5] + rep.cells_into[6] == 8,
              "%lld mirrored, %lld polyhedra, tets %lld pyramids %lld wedges %lld", (long long)rep.mirrored_cells,
              (long long)rep.polyhedra, (long long)rep.cells_into[1], (long long)rep.cells_into[2],
              (long long)rep.cells_into[3]);
}

/* A field's step s equals what the CGNS library reads from the solution IOSS wrote for that step: in
 * aero_blunt_wedge_test3.cgns through CellCenterIndices, in generated.cgns (zeros in its index arrays,
 * pointers naming no solution) through each solution's "Step" descriptor. generated.cgns repeats its
 * values at both steps, so only the aero file's steps must differ. */
TPK_TEST(steps_take_the_right_solutions)
{
    static const struct {
        const char *path, *field, *solution_format;
        int location, steps, steps_differ;
    } cases[] = {{"seacas/aero_blunt_wedge_test3.cgns", "density", "CellCenterSolutionAtStep%05d", TPK_ASSOC_TET, 5, 1},
                 {"seacas/generated.cgns", "NodeBlock_1", "VertexSolutionAtStep%d", TPK_ASSOC_POINT, 2, 0},
                 {"seacas/generated.cgns", "ElementBlock_2", "CellSolutionAtStep%d", TPK_ASSOC_TET, 2, 0}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        tpk_mesh m;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        CHECK_MSG(tpk_import_any(tpk_data_path(cases[k].path), NULL, &m, &d) == 0, "%s", d.message);
        const tpk_src_field *field = NULL;
        for (int i = 0; i < m.field_count; i++)
            if (!strcmp(m.fields[i].name, cases[k].field) && m.fields[i].association == cases[k].location)
                field = &m.fields[i];
        CHECK(field && field->step_count == cases[k].steps);
        int64_t n = cases[k].location == TPK_ASSOC_TET ? m.cell_count : m.point_count;
        int fn, differ = 0;
        CHECK(cg_open(tpk_data_path(cases[k].path), CG_MODE_READ, &fn) == 0);
        for (int s = 0; s < cases[k].steps; s++) {
            char name[33];
            snprintf(name, sizeof name, cases[k].solution_format, s + 1);
            int sol = 0, count = 0;
            cg_nsols(fn, 1, 1, &count);
            for (int i = 1; i <= count && !sol; i++) {
                char found[33];
                GridLocation_t at;
                cg_sol_info(fn, 1, 1, i, found, &at);
                sol = !strcmp(found, name) ? i : 0;
            }
            float values[64];
            cgsize_t lo[3] = {1, 1, 1}, hi[3] = {(cgsize_t)n, 1, 1};
            if (!strcmp(cases[k].path, "seacas/aero_blunt_wedge_test3.cgns"))
                hi[0] = 4, hi[1] = 4, hi[2] = 1; /* its 4 x 4 x 1 structured cells */
            CHECK(n <= 64 && sol && cg_field_read(fn, 1, 1, sol, cases[k].field, RealSingle, lo, hi, values) == 0);
            CHECK_MSG(!memcmp(values, field->values + s * n, sizeof *values * (size_t)n), "%s step %d", cases[k].path, s);
            differ += s > 0 && memcmp(values, field->values, sizeof *values * (size_t)n) != 0;
        }
        cg_close(fn);
        tpk_mesh_free(&m);
        CHECK_MSG(!cases[k].steps_differ || differ == cases[k].steps - 1, "%s: the steps of '%s' are not all different", cases[k].path,
                  cases[k].field);
    }
}

/* ---- Errors: each names the file, the place, what was expected and what was found ---- */

static const double cube_x[8] = {0, 1, 1, 0, 0, 1, 1, 0}, cube_y[8] = {0, 0, 1, 1, 0, 0, 1, 1},
                    cube_z[8] = {0, 0, 0, 0, 1, 1, 1, 1};

/* A unit cube's 8 points in zone "z" of base "b" (cell dimension `cell_dim`), `cells` declared, then
 * one section "s" of `count` elements of `type` (offsets for MIXED/NGON_n/NFACE_n, else NULL), and
 * NGON_n faces first when `faces` is given. Returns the open file (CG_MODE_WRITE) or -1. */
static int write_cube_zone(const char *path, int cell_dim, cgsize_t cells, ElementType_t type, const cgsize_t *conn,
                           const cgsize_t *offsets, cgsize_t count, int *zone)
{
    int fn, base, s;
    cgsize_t size[3] = {8, cells, 0};
    if (cg_open(path, CG_MODE_WRITE, &fn) || cg_base_write(fn, "b", cell_dim, 3, &base) ||
        cg_zone_write(fn, base, "z", size, Unstructured, zone) || write_coords(fn, base, *zone, cube_x, cube_y, cube_z))
        return -1;
    if (type == NFACE_n) { /* the cube's six faces as NGON_n elements 1-6 */
        static const cgsize_t quads[24] = {1, 4, 3, 2, 5, 6, 7, 8, 1, 2, 6, 5, 2, 3, 7, 6, 3, 4, 8, 7, 4, 1, 5, 8};
        static const cgsize_t quad_offsets[7] = {0, 4, 8, 12, 16, 20, 24};
        if (cg_poly_section_write(fn, base, *zone, "faces", NGON_n, 1, 6, 0, quads, quad_offsets, &s))
            return -1;
    }
    cgsize_t start = type == NFACE_n ? 7 : 1;
    int bad = offsets ? cg_poly_section_write(fn, base, *zone, "s", type, start, start + count - 1, 0, conn, offsets, &s)
                      : cg_section_write(fn, base, *zone, "s", type, start, start + count - 1, 0, conn, &s);
    return bad ? -1 : fn;
}

/* Import `path`; it must fail with every piece of `expected` ('|'-separated) in the message. */
static int fails_with(const char *path, const char *expected)
{
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    if (tpk_import_any(path, NULL, &m, &d) == 0) {
        tpk_mesh_free(&m);
        fprintf(stderr, "%s: read, expected an error with '%s'\n", path, expected);
        return 0;
    }
    char pieces[512];
    snprintf(pieces, sizeof pieces, "%s", expected);
    for (char *piece = strtok(pieces, "|"); piece; piece = strtok(NULL, "|"))
        if (!strstr(d.message, piece)) {
            fprintf(stderr, "%s: message '%s' lacks '%s'\n", path, d.message, piece);
            return 0;
        }
    return m.points == NULL && m.cell_count == 0;
}

TPK_TEST(errors_name_the_place)
{
    static const cgsize_t hex_far[8] = {1, 2, 3, 4, 5, 6, 7, 99}, hex[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    static const cgsize_t quad[4] = {1, 2, 3, 4}, nface_missing[6] = {1, 2, 3, 4, 5, 50}, nface_three[3] = {1, 2, 3};
    static const cgsize_t six[2] = {0, 6}, three[2] = {0, 3}, mixed_bad[9] = {HEXA_8, 1, 2, 3, 4, 5, 6, 7, 0},
                          mixed_offsets[2] = {0, 9};
    static const struct {
        const char *file, *expected;
        int cell_dim;
        ElementType_t type;
        const cgsize_t *conn, *offsets;
    } cases[] = {
        {"far.cgns", "far.cgns: zone 'z' section 's' element 1 uses vertex 99, expected 1 to 8", 3, HEXA_8, hex_far, NULL},
        {"flat.cgns", "flat.cgns: expected a base of cell and physical dimension 3|'b' (cell dimension 2", 2, QUAD_4,
         quad, NULL},
        {"faces.cgns", "faces.cgns: no volume cells", 3, QUAD_4, quad, NULL},
        {"missing_face.cgns", "missing_face.cgns: zone 'z' section 's' element 7 uses face 50, which no NGON_n", 3,
         NFACE_n, nface_missing, six},
        {"three_faces.cgns", "three_faces.cgns: zone 'z' section 's' element 7: ", 3, NFACE_n, nface_three, three},
        {"mixed.cgns", "mixed.cgns: zone 'z' section 's' element 1 uses vertex 0, expected 1 to 8", 3, MIXED, mixed_bad,
         mixed_offsets}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const char *path = tpk_temp_path(cases[k].file);
        int zone, fn = write_cube_zone(path, cases[k].cell_dim, 1, cases[k].type, cases[k].conn, cases[k].offsets,
                                       1, &zone);
        CHECK_MSG(fn >= 0, "writing %s: %s", cases[k].file, cg_get_error());
        cg_close(fn);
        CHECK(fails_with(path, cases[k].expected));
    }
    /* Two cells declared, one volume element: a CellCenter field of 2 values fits no cell list. */
    const char *path = tpk_temp_path("field.cgns");
    int zone, fn = write_cube_zone(path, 3, 2, HEXA_8, hex, NULL, 1, &zone);
    static const double two[2] = {1, 2};
    CHECK(fn >= 0 && write_field(fn, 1, zone, "sol", CellCenter, "p", two) == 0);
    cg_close(fn);
    CHECK(fails_with(path, "field.cgns: zone 'z' FlowSolution 'sol' field 'p' has 2 values, expected 1 (one per cell)"));
    path = tpk_temp_path("text.cgns");
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    fputs("CGNS? no, text\n", f);
    fclose(f);
    CHECK(fails_with(path, "text.cgns: cannot open it as a CGNS file"));
    CHECK(fails_with(tpk_temp_path("absent.cgns"), "absent.cgns: cannot open the file"));
}

static size_t read_whole(const char *path, unsigned char *bytes, size_t cap)
{
    FILE *in = fopen(path, "rb");
    size_t n = in ? fread(bytes, 1, cap, in) : 0;
    if (in)
        fclose(in);
    return n;
}

static void write_whole(const char *path, const unsigned char *bytes, size_t n)
{
    FILE *out = fopen(path, "wb");
    if (out) {
        fwrite(bytes, 1, n, out);
        fclose(out);
    }
}

/* The library reads files, so there is no memory reader to fuzz: damaged files on disk instead. Cut
 * short, each SEACAS file is refused with its name (HDF5 checks the end-of-file address its superblock
 * records); with bytes overwritten at 16 places the import reads or fails cleanly, never crashes (the
 * ASan build runs this). */
TPK_TEST(damaged_files_fail_cleanly)
{
    static const char *const files[] = {"seacas/BC_without_parents.cgns", "seacas/aero_blunt_wedge_test3.cgns",
                                        "seacas/generated.cgns"};
    static unsigned char bytes[1 << 20];
    const char *path = tpk_temp_path("cut.cgns");
    for (int f = 0; f < 3; f++) {
        size_t n = read_whole(tpk_data_path(files[f]), bytes, sizeof bytes);
        CHECK(n > 1000 && n < sizeof bytes);
        const size_t cuts[4] = {n - 1, n / 2, n / 4, 10};
        for (int c = 0; c < 4; c++) {
            write_whole(path, bytes, cuts[c]);
            CHECK_MSG(fails_with(path, "cut.cgns: "), "%s cut to %zu bytes", files[f], cuts[c]);
        }
        int read = 0;
        for (int k = 1; k < 16; k++) {
            unsigned char saved[64];
            size_t at = n * (size_t)k / 16;
            memcpy(saved, bytes + at, sizeof saved);
            for (size_t i = 0; i < sizeof saved; i++)
                bytes[at + i] ^= 0xA5;
            write_whole(path, bytes, n);
            memcpy(bytes + at, saved, sizeof saved);
            tpk_mesh m;
            tpk_diag d;
            memset(&d, 0, sizeof d);
            if (tpk_import_any(path, NULL, &m, &d) == 0) {
                read++;
                tpk_mesh_free(&m);
            } else
                CHECK_MSG(strstr(d.message, "cut.cgns: ") != NULL, "%s damaged at %zu: '%s'", files[f], at, d.message);
        }
        printf("%s: %d of 15 damaged copies still read\n", files[f], read);
    }
}

/* .cgns is picked by extension although its HDF5 signature is also Exodus's (netCDF-4); an HDF5 file
 * with no telling extension stays Exodus's (the row before), and `--format cgns` reads it; a CGNS file
 * in the ADF format is told by its header. */
TPK_TEST(detection)
{
    const tpk_import_format *row = tpk_import_format_detect(tpk_data_path("seacas/generated.cgns"));
    CHECK(row && !strcmp(row->name, "cgns") && row->read_memory == NULL);
    static unsigned char bytes[1 << 16];
    size_t n = read_whole(tpk_data_path("seacas/generated.cgns"), bytes, sizeof bytes);
    const char *plain = tpk_temp_path("hdf5_without_extension");
    write_whole(plain, bytes, n);
    row = tpk_import_format_detect(plain);
    CHECK(row && !strcmp(row->name, "exodus"));
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(plain, "cgns", &m, &d) == 0 && m.cell_count == 8, "%s", d.message);
    tpk_mesh_free(&m);
    const char *adf = tpk_temp_path("adf_file");
    int points = write_test_file(adf, CG_FILE_ADF);
    CHECK_MSG(points > 0, "writing ADF: %s", cg_get_error());
    row = tpk_import_format_detect(adf);
    CHECK(row && !strcmp(row->name, "cgns"));
    CHECK_MSG(tpk_import_any(adf, NULL, &m, &d) == 0, "%s", d.message);
    CHECK(m.cell_count == (int64_t)sizeof expected_types && !memcmp(m.cell_types, expected_types, sizeof expected_types));
    tpk_mesh_free(&m);
}

typedef struct warnings {
    char text[512];
    int count;
} warnings;

static void keep_warning(void *user, const char *text)
{
    warnings *w = user;
    w->count++;
    snprintf(w->text + strlen(w->text), sizeof w->text - strlen(w->text), "%s\n", text);
}

/* Two static Vertex solutions of one zone both with "p": the second becomes "b/p". Two steps whose
 * FlowSolutionPointers name a solution the zone lacks: no step is trusted, the solutions stay static
 * and a warning says so. */
TPK_TEST(static_solutions_and_unresolved_pointers)
{
    static const cgsize_t hex[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    static const double ones[8] = {1, 1, 1, 1, 1, 1, 1, 1}, twos[8] = {2, 2, 2, 2, 2, 2, 2, 2}, times[2] = {0, 1};
    const char *path = tpk_temp_path("pointers.cgns");
    int zone, fn = write_cube_zone(path, 3, 1, HEXA_8, hex, NULL, 1, &zone);
    cgsize_t steps = 2, dims[2] = {32, 2};
    char pointers[65];
    snprintf(pointers, sizeof pointers, "%-32s%-32s", "a", "nowhere");
    CHECK(fn >= 0 && write_field(fn, 1, zone, "a", Vertex, "p", ones) == 0 &&
          write_field(fn, 1, zone, "b", Vertex, "p", twos) == 0 && cg_biter_write(fn, 1, "TimeIterValues", 2) == 0 &&
          cg_goto(fn, 1, "BaseIterativeData_t", 1, "end") == 0 &&
          cg_array_write("TimeValues", RealDouble, 1, &steps, times) == 0 &&
          cg_ziter_write(fn, 1, zone, "ZoneIterativeData") == 0 &&
          cg_goto(fn, 1, "Zone_t", zone, "ZoneIterativeData_t", 1, "end") == 0 &&
          cg_array_write("FlowSolutionPointers", Character, 2, dims, pointers) == 0);
    cg_close(fn);
    tpk_mesh m;
    tpk_diag d;
    warnings w;
    memset(&d, 0, sizeof d);
    memset(&w, 0, sizeof w);
    d.warn = keep_warning, d.warn_user = &w;
    CHECK_MSG(tpk_import_any(path, NULL, &m, &d) == 0, "%s", d.message);
    int ok = m.field_count == 2 && !strcmp(m.fields[0].name, "p") && !strcmp(m.fields[1].name, "b/p") &&
             m.fields[0].step_count == 1 && m.fields[1].step_count == 1 && m.fields[0].values[7] == 1 &&
             m.fields[1].values[7] == 2 && m.step_count == 2;
    tpk_mesh_free(&m);
    CHECK_MSG(ok, "fields or steps differ");
    CHECK_MSG(strstr(w.text, "pointers.cgns: zone 'z': its ZoneIterativeData points at no FlowSolution"), "%s", w.text);
}

/* A grid of n^3 hexahedra written with the CGNS library, large enough for the importer's passes to run on
 * several threads (64k items a worker): section "lower" the first n/4 layers, "upper" the rest (HEXA_8,
 * or with `mixed` a MIXED section of HEXA_8 elements), wavy coordinates, a Vertex and a CellCenter
 * solution. bad > 0: element `bad` of "upper" (counted from 1 within it) and the one 80000 further get a
 * vertex id of 0 and one past the end. */
static void write_hex_grid(const char *path, int n, int64_t bad, int mixed)
{
    int64_t nv = (int64_t)(n + 1) * (n + 1) * (n + 1), nc = (int64_t)n * n * n, first = (int64_t)n * n * (n / 4);
    double *x = malloc(sizeof *x * 3 * (size_t)nv), *val = malloc(sizeof *val * (size_t)(nv > nc ? nv : nc));
    double *y = x + nv, *z = x + 2 * nv;
    cgsize_t *conn = malloc(sizeof *conn * 8 * (size_t)nc);
    for (int64_t v = 0; v < nv; v++) {
        double p[3];
        tpk_warped_grid_point(n, v, p);
        x[v] = p[0], y[v] = p[1], z[v] = p[2];
    }
    for (int64_t c = 0; c < nc; c++) {
        int64_t q[8];
        tpk_warped_grid_cell(n, c, q);
        for (int h = 0; h < 8; h++)
            conn[8 * c + h] = (cgsize_t)q[h] + 1;
    }
    if (bad > 0)
        conn[8 * (first + bad - 1) + 2] = 0, conn[8 * (first + bad + 80000 - 1) + 2] = (cgsize_t)nv + 1;
    int fn, base, zone, s;
    cgsize_t size[3] = {(cgsize_t)nv, (cgsize_t)nc, 0};
    CHECK(cg_open(path, CG_MODE_WRITE, &fn) == 0);
    CHECK(cg_base_write(fn, "base", 3, 3, &base) == 0);
    CHECK(cg_zone_write(fn, base, "grid", size, Unstructured, &zone) == 0);
    CHECK(write_coords(fn, base, zone, x, y, z) == 0);
    CHECK(cg_section_write(fn, base, zone, "lower", HEXA_8, 1, (cgsize_t)first, 0, conn, &s) == 0);
    if (mixed) {
        cgsize_t *data = malloc(sizeof *data * 9 * (size_t)(nc - first)), *offsets = malloc(sizeof *offsets * (size_t)(nc - first + 1));
        for (int64_t c = 0; c < nc - first; c++) {
            offsets[c] = (cgsize_t)(9 * c), data[9 * c] = HEXA_8;
            memcpy(data + 9 * c + 1, conn + 8 * (first + c), 8 * sizeof *conn);
        }
        offsets[nc - first] = (cgsize_t)(9 * (nc - first));
        CHECK(cg_poly_section_write(fn, base, zone, "upper", MIXED, (cgsize_t)first + 1, (cgsize_t)nc, 0, data, offsets, &s) == 0);
        free(data), free(offsets);
    } else {
        CHECK(cg_section_write(fn, base, zone, "upper", HEXA_8, (cgsize_t)first + 1, (cgsize_t)nc, 0, conn + 8 * first, &s) == 0);
    }
    for (int64_t v = 0; v < nv; v++)
        val[v] = sin(1e-3 * (double)v);
    CHECK(write_field(fn, base, zone, "nodes", Vertex, "temperature", val) == 0);
    for (int64_t c = 0; c < nc; c++)
        val[c] = cos(1e-3 * (double)c);
    CHECK(write_field(fn, base, zone, "cells", CellCenter, "stress", val) == 0);
    CHECK(cg_close(fn) == 0);
    free(x), free(val), free(conn);
}

/* The passes after the library's reads run on all threads: the same mesh, bit for bit, on 1 and 3
 * threads, from a MIXED section as from a HEXA_8 one (and the cells written), and the same message
 * naming the first bad id where two are bad. */
TPK_TEST(same_mesh_on_any_thread_count)
{
    const int n = 64; /* "upper": 196,608 hexes, 3 workers */
    const int64_t nv = 65 * 65 * 65, nc = 64 * 64 * 64, first = 64 * 64 * 16;
    const char *path = tpk_temp_path("hex_grid.cgns");
    write_hex_grid(path, n, 0, 1);
    tpk_mesh one, three;
    tpk_diag d;
    CHECK_MSG(tpk_import_same_on_threads(tpk_import_cgns, path, 3, &three, &d) == 0, "%s", d.message);
    write_hex_grid(path, n, 0, 0); /* the same cells in a HEXA_8 section: the same mesh */
    CHECK_MSG(tpk_import_same_on_threads(tpk_import_cgns, path, 3, &one, &d) == 0, "%s", d.message);
    CHECK(tpk_same_mesh(&one, &three));
    int64_t c = first + 100000, b = c % n + 65 * (c / n % n) + 65 * 65 * (c / n / n);
    CHECK(three.point_count == nv && three.cell_count == nc && three.field_count == 2);
    CHECK(three.cell_types[c] == TPK_CELL_HEXAHEDRON && three.cell_offsets[c] == 8 * c &&
          three.cell_conn[8 * c] == b && three.cell_conn[8 * c + 6] == b + 1 + 65 + 65 * 65);
    CHECK(three.points[3 * 4000 + 1] == (double)(4000 / 65 % 65) + 0.1 * sin((double)(4000 / 65 / 65)));
    tpk_mesh_free(&one);
    tpk_mesh_free(&three);

    char expected[128], why[3 * sizeof d.message];
    snprintf(expected, sizeof expected, "section 'upper' element %lld uses vertex 0, expected 1 to %lld",
             (long long)(first + 70000), (long long)nv);
    for (int mixed = 0; mixed < 2; mixed++) {
        write_hex_grid(path, n, 70000, mixed);
        CHECK_MSG(tpk_import_fails_alike_on_threads(tpk_import_cgns, path, 3, expected, why, sizeof why) == 0,
                  "mixed %d: %s", mixed, why);
    }
    remove(path);
}
