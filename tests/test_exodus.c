/* Exodus II importer on SEACAS's test files: blocks, dropped non-volume elements, nodal and element
 * variables over every time step, time values, hexahedra in VTK order, and the errors. */
#include <exodusII.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "meshgen.h"
#include "same_mesh.h"
#include "base/parallel.h"
#include "import/importers.h"
#include "import/exodus/netcdf_size.h"
#include "convert/pipeline.h"

static int count_fields(const tpk_mesh *m, int association)
{
    int n = 0;
    for (int i = 0; i < m->field_count; i++)
        n += m->fields[i].association == association;
    return n;
}

TPK_TEST(seacas_files)
{
    static const struct {
        const char *path;
        int64_t cells;
        int nodal, steps;
    } files[] = {{"seacas/exomerge_unit_test.e", 1300, 8, 5}, {"seacas/8-block.g", 64, 12, 11},
                 {"seacas/8-block-omitted.g", 32, 12, 11},     {"seacas/block_crush_1.ex2", 131, 16, 11},
                 {"seacas/2block1.g", 64, 0, 1},               {"seacas/ADeDA.e", 2, 0, 1},
                 {"seacas/cube.g", 8, 3, 4},                   {"seacas/two-block.g", 16, 3, 4}};
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        tpk_mesh m;
        tpk_diag d;
        memset(&d, 0, sizeof d);
        d.warn = NULL;
        CHECK_MSG(tpk_import_any(tpk_data_path(files[f].path), NULL, &m, &d) == 0, "%s", d.message);
        int64_t bad = 0;
        static const int around[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                                         {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
        for (int64_t c = 0; c < m.cell_count; c++) { /* every hex corner right-handed in VTK order */
            const int32_t *h = m.cell_conn + m.cell_offsets[c];
            for (int k = 0; m.cell_types[c] == 12 && k < 8; k++)
                bad += tpk_orient3d_exact(m.points + 3 * h[k], m.points + 3 * h[around[k][0]],
                                          m.points + 3 * h[around[k][1]], m.points + 3 * h[around[k][2]]) <= 0;
        }
        int ok = m.cell_count == files[f].cells && count_fields(&m, TPK_ASSOC_POINT) == files[f].nodal &&
                 m.step_count == files[f].steps && (files[f].steps == 1 || m.times != NULL) &&
                 !strcmp(m.format, "exodus-ii");
        for (int i = 0; ok && i < m.field_count; i++)
            ok = m.fields[i].step_count == files[f].steps;
        tpk_mesh_free(&m);
        CHECK_MSG(ok && bad == 0, "%s: counts, fields or steps differ, or %lld hex corners not positive",
                  files[f].path, (long long)bad);
    }
}

/* exomerge_unit_test.e: its ~80 element variables come through as cell fields with 5 steps, and the
 * time values increase. */
TPK_TEST(element_variables_and_times)
{
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_exodus(tpk_data_path("seacas/exomerge_unit_test.e"), &m, &d) == 0, "%s", d.message);
    int cell_fields = count_fields(&m, TPK_ASSOC_TET), finite = 0;
    for (int i = 0; i < m.field_count; i++)
        if (m.fields[i].association == TPK_ASSOC_TET)
            for (int64_t k = 0; k < 5 * m.cell_count; k++)
                finite += isfinite(m.fields[i].values[k]) != 0;
    int increasing = m.times && m.step_count == 5;
    for (int s = 1; increasing && s < m.step_count; s++)
        increasing = m.times[s] > m.times[s - 1];
    tpk_mesh_free(&m);
    CHECK_MSG(cell_fields >= 70 && finite > 0 && increasing, "%d cell fields, %d finite values", cell_fields, finite);
}

TPK_TEST(errors)
{
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_any(tpk_data_path("seacas/aero_blunt_wedge_wall_test3.ex2"), NULL, &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "aero_blunt_wedge_wall_test3.ex2: no volume cells"), "%s", d.message);
    const char *text = tpk_temp_path("not_exodus.e");
    FILE *f = fopen(text, "w");
    CHECK(f != NULL);
    fputs("this is not a netCDF file\n", f);
    fclose(f);
    CHECK(tpk_import_any(text, NULL, &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "not_exodus.e: cannot open it as an Exodus II file"), "%s", d.message);
    CHECK(m.points == NULL && m.cell_count == 0);
}

/* netCDF zero-fills reads past the end of a short file, so truncation must be caught before reading:
 * the size the header describes is exactly each real file's size, and one byte less is refused. */
TPK_TEST(truncated_files_are_refused)
{
    const char *files[] = {"seacas/exomerge_unit_test.e", "seacas/8-block.g", "seacas/cube.g", "seacas/ADeDA.e"};
    for (int f = 0; f < 4; f++) {
        FILE *in = fopen(tpk_data_path(files[f]), "rb");
        CHECK(in != NULL);
        static unsigned char bytes[4 << 20];
        size_t n = fread(bytes, 1, sizeof bytes, in);
        fclose(in);
        uint64_t expected = 0;
        CHECK(tpk_netcdf_classic_size(bytes, n, &expected) == 0);
        CHECK_MSG(expected == n, "%s: header describes %llu bytes, file has %zu", files[f],
                  (unsigned long long)expected, n);
        const size_t cuts[4] = {n - 1, n / 2, n / 4, 10};
        for (int c = 0; c < 4; c++) {
            const char *path = tpk_temp_path("cut.e");
            FILE *out = fopen(path, "wb");
            fwrite(bytes, 1, cuts[c], out);
            fclose(out);
            tpk_mesh m;
            tpk_diag d;
            memset(&d, 0, sizeof d);
            int rc = tpk_import_exodus(path, &m, &d);
            CHECK_MSG(rc != 0 && strstr(d.message, "cut.e: ") &&
                          (strstr(d.message, "truncated") || strstr(d.message, "malformed or cut short")),
                      "%s cut to %zu bytes: '%s'", files[f], cuts[c], d.message);
        }
    }
}

/* Writes `m`'s tets, wedges and pyramids as one Exodus block per type (1-based ids) with the Exodus
 * library itself, the writer every Exodus producer uses. */
static void write_exodus(const char *path, const tpk_mesh *m)
{
    static const struct {
        int vtk_type, nodes;
        const char *name;
    } kinds[] = {{10, 4, "TETRA"}, {13, 6, "WEDGE"}, {14, 5, "PYRAMID"}};
    int cpu_ws = 8, io_ws = 8, blocks = 0;
    int exoid = ex_create(path, EX_CLOBBER, &cpu_ws, &io_ws);
    CHECK(exoid >= 0);
    for (int k = 0; k < 3; k++)
        for (int64_t c = 0; c < m->cell_count; c++)
            if (m->cell_types[c] == kinds[k].vtk_type) {
                blocks++;
                break;
            }
    CHECK(ex_put_init(exoid, "tetpack test", 3, m->point_count, m->cell_count, blocks, 0, 0) == 0);
    double *xyz = malloc(sizeof *xyz * 3 * (size_t)m->point_count);
    for (int64_t p = 0; p < m->point_count; p++)
        for (int a = 0; a < 3; a++)
            xyz[a * m->point_count + p] = m->points[3 * p + a];
    CHECK(ex_put_coord(exoid, xyz, xyz + m->point_count, xyz + 2 * m->point_count) == 0);
    free(xyz);
    int *conn = malloc(sizeof *conn * (size_t)(m->cell_offsets[m->cell_count] + 1));
    for (int k = 0, id = 1; k < 3; k++) {
        int64_t count = 0, n = 0;
        for (int64_t c = 0; c < m->cell_count; c++)
            if (m->cell_types[c] == kinds[k].vtk_type) {
                for (int64_t i = m->cell_offsets[c]; i < m->cell_offsets[c + 1]; i++)
                    conn[n++] = m->cell_conn[i] + 1;
                count++;
            }
        if (!count)
            continue;
        CHECK(ex_put_elem_block(exoid, id, kinds[k].name, count, kinds[k].nodes, 0) == 0);
        CHECK(ex_put_elem_conn(exoid, id, conn) == 0);
        id++;
    }
    free(conn);
    CHECK(ex_close(exoid) == 0);
}

/* Reads `path` back and checks: cells of each type in the written order, then a split in which no cell
 * is mirrored or folds (the converter refuses mirrored cells with this flag). */
static void check_read_back(const char *path, const tpk_mesh *src, int64_t wedges, int64_t pyramids)
{
    tpk_mesh back;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(path, NULL, &back, &d) == 0, "%s", d.message);
    CHECK(back.point_count == src->point_count && back.cell_count == src->cell_count);
    int64_t c = 0;
    for (int type = 10; type <= 14; type++)
        for (int64_t s = 0; s < src->cell_count; s++) {
            if (src->cell_types[s] != type)
                continue;
            CHECK(back.cell_types[c] == type);
            int64_t n = src->cell_offsets[s + 1] - src->cell_offsets[s];
            CHECK(back.cell_offsets[c + 1] - back.cell_offsets[c] == n);
            CHECK(!memcmp(back.cell_conn + back.cell_offsets[c], src->cell_conn + src->cell_offsets[s],
                          sizeof *src->cell_conn * (size_t)n));
            c++;
        }
    tpk_tetmesh tets;
    CHECK_MSG(tpk_tetrahedralize(&back, NULL, 0, TPK_TETRA_REFUSE_MIRRORED, &tets, &d) == 0, "%s", d.message);
    CHECK(tets.mirrored_cells == 0 && tets.steiner_cells == 0);
    CHECK(tets.cells_into[3] == wedges && tets.cells_into[2] == pyramids);
    tpk_tetmesh_free(&tets);
    tpk_mesh_free(&back);
}

/* Wedge and pyramid blocks. Exodus numbers WEDGE6 and PYRAMID5 nodes as VTK does: its side tables
 * (SEACAS exodus-element-types.md) give the outward faces wedge (1,3,2), (4,5,6), (1,2,5,4), (2,3,6,5),
 * (1,4,6,3) and pyramid (1,2,5) ... (4,1,5), (1,4,3,2), exactly VTK's. Written with the Exodus library:
 * gmsh tutorial t3's 12,308 prisms and 21,720 tets (real data; Gmsh prisms are in VTK order, checked in
 * test_gmsh), and six pyramids filling a cube from its centre. */
TPK_TEST(wedge_and_pyramid_blocks)
{
    tpk_mesh t3;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(tpk_data_path("gmsh/t3_hex_prism_ascii41.msh"), NULL, &t3, &d) == 0, "%s", d.message);
    const char *path = tpk_temp_path("t3_wedges.e");
    write_exodus(path, &t3);
    check_read_back(path, &t3, 12308, 0);
    tpk_mesh_free(&t3);

    tpk_mesh cube = tpk_gen_cube_pyramids(); /* VTK and Exodus turn a pyramid's base towards its apex */
    path = tpk_temp_path("cube_pyramids.e");
    write_exodus(path, &cube);
    check_read_back(path, &cube, 0, 6);
}

/* One hexahedron with the given node and element number maps (as a decomposer writes them per processor). */
static void write_mapped_hex(const char *path, const int *node_map, int elem_id)
{
    static const double x[8] = {0, 1, 1, 0, 0, 1, 1, 0}, y[8] = {0, 0, 1, 1, 0, 0, 1, 1}, z[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    static const int conn[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    int cpu_ws = 8, io_ws = 8;
    int exoid = ex_create(path, EX_CLOBBER, &cpu_ws, &io_ws);
    CHECK(exoid >= 0);
    CHECK(ex_put_init(exoid, "mapped", 3, 8, 1, 1, 0, 0) == 0);
    CHECK(ex_put_coord(exoid, x, y, z) == 0);
    CHECK(ex_put_elem_block(exoid, 7, "HEX8", 1, 8, 0) == 0);
    CHECK(ex_put_elem_conn(exoid, 7, conn) == 0);
    CHECK(ex_put_id_map(exoid, EX_NODE_MAP, node_map) == 0);
    CHECK(ex_put_id_map(exoid, EX_ELEM_MAP, &elem_id) == 0);
    CHECK(ex_close(exoid) == 0);
}

/* Node and element number maps become exact 0-based global ids (tetpack-mpi's vertex identity), ids past
 * 2^24 included; without maps they count 0, 1, ...; an id below 1 is refused with the node named. */
TPK_TEST(number_maps)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/exodus_maps.e", TPK_BINARY_DIR);
    const int map[8] = {40000003, 12, 7, 40000001, 5, 99, 3, 16777217};
    write_mapped_hex(path, map, 42);
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(path, NULL, &m, &d) == 0, "%s", d.message);
    CHECK(m.global_point_ids && m.global_cell_ids && m.cell_count == 1);
    for (int i = 0; m.global_point_ids && i < 8; i++)
        CHECK_MSG(m.global_point_ids[i] == map[i] - 1, "node %d: %lld", i, (long long)m.global_point_ids[i]);
    CHECK(m.global_cell_ids && m.global_cell_ids[0] == 41);
    tpk_mesh_free(&m);
    CHECK_MSG(tpk_import_any(tpk_data_path("seacas/8-block.g"), NULL, &m, &d) == 0, "%s", d.message);
    int64_t off = 0;
    for (int64_t i = 0; i < m.point_count; i++)
        off += m.global_point_ids[i] != i;
    CHECK_MSG(off == 0, "8-block.g: %lld nodes with an id other than their index", (long long)off);
    tpk_mesh_free(&m);
    const int bad[8] = {1, 2, 3, 0, 5, 6, 7, 8};
    write_mapped_hex(path, bad, 1);
    CHECK(tpk_import_any(path, NULL, &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "node number map: node 4 has id 0") != NULL, "%s", d.message);
    remove(path);
}

/* A grid of n^3 hexahedra written with the Exodus library, large enough for the importer's passes to run
 * on several threads (64k items a worker): block 1 the first n/4 layers, block 2 the rest; wavy
 * coordinates; node and element number maps (ids reversed, so none equals its index); a nodal and an
 * element variable over 2 steps. bad_node (1-based within block 2) > 0: that element's third node, and
 * the one of element 80000 more, set to 0 and past the end; bad_map > 0: that node's map entry, and the
 * one of node 90000 more, set to 0 and -5. */
static void write_hex_grid(const char *path, int n, int64_t bad_node, int64_t bad_map)
{
    int64_t nv = (int64_t)(n + 1) * (n + 1) * (n + 1), nc = (int64_t)n * n * n, first = (int64_t)n * n * (n / 4);
    double *xyz = malloc(sizeof *xyz * 3 * (size_t)nv), *val = malloc(sizeof *val * (size_t)(nv > nc ? nv : nc));
    int *conn = malloc(sizeof *conn * 8 * (size_t)nc), *map = malloc(sizeof *map * (size_t)(nv > nc ? nv : nc));
    for (int64_t v = 0; v < nv; v++) {
        double p[3];
        tpk_warped_grid_point(n, v, p);
        xyz[v] = p[0], xyz[nv + v] = p[1], xyz[2 * nv + v] = p[2];
    }
    for (int64_t c = 0; c < nc; c++) {
        int64_t q[8];
        tpk_warped_grid_cell(n, c, q);
        for (int h = 0; h < 8; h++)
            conn[8 * c + h] = (int)q[h] + 1;
    }
    if (bad_node > 0) {
        conn[8 * (first + bad_node - 1) + 2] = 0;
        conn[8 * (first + bad_node + 80000 - 1) + 2] = (int)nv + 1;
    }
    int cpu_ws = 8, io_ws = 8;
    int exoid = ex_create(path, EX_CLOBBER, &cpu_ws, &io_ws);
    CHECK(exoid >= 0);
    CHECK(ex_put_init(exoid, "hex grid", 3, nv, nc, 2, 0, 0) == 0);
    CHECK(ex_put_coord(exoid, xyz, xyz + nv, xyz + 2 * nv) == 0);
    CHECK(ex_put_block(exoid, EX_ELEM_BLOCK, 1, "HEX8", first, 8, 0, 0, 0) == 0);
    CHECK(ex_put_block(exoid, EX_ELEM_BLOCK, 2, "HEX8", nc - first, 8, 0, 0, 0) == 0);
    CHECK(ex_put_conn(exoid, EX_ELEM_BLOCK, 1, conn, NULL, NULL) == 0);
    CHECK(ex_put_conn(exoid, EX_ELEM_BLOCK, 2, conn + 8 * first, NULL, NULL) == 0);
    for (int64_t v = 0; v < nv; v++)
        map[v] = (int)(nv - v);
    if (bad_map > 0)
        map[bad_map - 1] = 0, map[bad_map + 90000 - 1] = -5;
    CHECK(ex_put_id_map(exoid, EX_NODE_MAP, map) == 0);
    for (int64_t c = 0; c < nc; c++)
        map[c] = (int)(nc - c);
    CHECK(ex_put_id_map(exoid, EX_ELEM_MAP, map) == 0);
    CHECK(ex_put_variable_param(exoid, EX_NODAL, 1) == 0 && ex_put_variable_param(exoid, EX_ELEM_BLOCK, 1) == 0);
    CHECK(ex_put_variable_name(exoid, EX_NODAL, 1, "temperature") == 0);
    CHECK(ex_put_variable_name(exoid, EX_ELEM_BLOCK, 1, "stress") == 0);
    for (int s = 1; s <= 2; s++) {
        double t = 0.5 * s;
        CHECK(ex_put_time(exoid, s, &t) == 0);
        for (int64_t v = 0; v < nv; v++)
            val[v] = sin(1e-3 * (double)v + s);
        CHECK(ex_put_var(exoid, s, EX_NODAL, 1, 1, nv, val) == 0);
        for (int64_t c = 0; c < nc; c++)
            val[c] = cos(1e-3 * (double)c + s);
        CHECK(ex_put_var(exoid, s, EX_ELEM_BLOCK, 1, 1, first, val) == 0);
        CHECK(ex_put_var(exoid, s, EX_ELEM_BLOCK, 1, 2, nc - first, val + first) == 0);
    }
    CHECK(ex_close(exoid) == 0);
    free(xyz), free(val), free(conn), free(map);
}

/* The passes after the library's reads run on all threads: the same mesh, bit for bit, on 1 and 3
 * threads (and the values written), and the same message naming the first bad id where two are bad. */
TPK_TEST(same_mesh_on_any_thread_count)
{
    const int n = 64; /* block 2: 196,608 hexes, 3 workers */
    const int64_t nv = 65 * 65 * 65, nc = 64 * 64 * 64, first = 64 * 64 * 16;
    const char *path = tpk_temp_path("hex_grid.e");
    write_hex_grid(path, n, 0, 0);
    tpk_mesh three;
    tpk_diag d;
    CHECK_MSG(tpk_import_same_on_threads(tpk_import_exodus, path, 3, &three, &d) == 0, "%s", d.message);
    /* what was written: hex c's corners, the reversed maps, the values of step 2 */
    int64_t c = first + 100000, b = c % n + 65 * (c / n % n) + 65 * 65 * (c / n / n);
    CHECK(three.point_count == nv && three.cell_count == nc && three.field_count == 2 && three.step_count == 2);
    CHECK(three.cell_types[c] == TPK_CELL_HEXAHEDRON && three.cell_offsets[c] == 8 * c &&
          three.cell_conn[8 * c] == b && three.cell_conn[8 * c + 6] == b + 1 + 65 + 65 * 65);
    CHECK(three.points[3 * 4000 + 1] == (double)(4000 / 65 % 65) + 0.1 * sin((double)(4000 / 65 / 65)));
    CHECK(three.global_point_ids[5] == nv - 5 - 1 && three.global_cell_ids[c] == nc - c - 1);
    CHECK(three.fields[1].values[nc + c] == (float)cos(1e-3 * (double)c + 2));
    tpk_mesh_free(&three);

    char why[3 * sizeof d.message];
    const char *bad_node = "block 2 element 70000 uses node 0, expected 1";
    const char *bad_id = "node number map: node 100000 has id 0";
    write_hex_grid(path, n, 70000, 0);
    CHECK_MSG(tpk_import_fails_alike_on_threads(tpk_import_exodus, path, 3, bad_node, why, sizeof why) == 0, "%s", why);
    write_hex_grid(path, n, 0, 100000);
    CHECK_MSG(tpk_import_fails_alike_on_threads(tpk_import_exodus, path, 3, bad_id, why, sizeof why) == 0, "%s", why);
    remove(path);
}
