/* Exodus II importer on SEACAS's test files: blocks, dropped non-volume elements, nodal and element
 * variables over every time step, time values, hexahedra in VTK order, and the errors. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "harness.h"
#include "importers.h"
#include "netcdf_size.h"
#include "pipeline.h"

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
