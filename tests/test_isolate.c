/* Reading in a child process (tools/import/isolate.c): the mesh, message, warnings and field problems come
 * back as the reader made them; a reader that dies is an error naming its signal; the registry isolates
 * the rows that say so (Exodus here, on SEACAS's files, read both ways). */
#define _GNU_SOURCE
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "same_mesh.h"
#include "import/importers.h"
#include "import/isolate.h"
#include "tetpack_format.h"

/* Every array of tpk_mesh set, with values that tell elements apart. */
static int full_reader(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    tpk_diag_warn(diag, "%s: first warning", path);
    tpk_diag_field_problem(diag, "short", 9, 4, "byte 77");
    tpk_mesh *m = out;
    m->point_count = 5;
    m->points = malloc(15 * sizeof *m->points);
    for (int i = 0; i < 15; i++)
        m->points[i] = 0.25 * i - 1.0 / 3.0;
    m->cell_count = 2;
    m->cell_types = malloc(2);
    m->cell_types[0] = TPK_CELL_TETRA, m->cell_types[1] = TPK_CELL_POLYHEDRON;
    m->cell_offsets = malloc(3 * sizeof *m->cell_offsets);
    m->cell_offsets[0] = 0, m->cell_offsets[1] = 4, m->cell_offsets[2] = 9;
    m->cell_conn = malloc(9 * sizeof *m->cell_conn);
    for (int i = 0; i < 9; i++)
        m->cell_conn[i] = i % 5;
    m->face_offsets = malloc(3 * sizeof *m->face_offsets);
    m->face_offsets[0] = 0, m->face_offsets[1] = 0, m->face_offsets[2] = 7;
    m->faces = malloc(7 * sizeof *m->faces);
    for (int i = 0; i < 7; i++)
        m->faces[i] = 30 + i;
    float *pv = malloc(2 * 5 * sizeof *pv), *cv = malloc(3 * 2 * sizeof *cv);
    for (int i = 0; i < 10; i++)
        pv[i] = (float)i / 7.0f;
    for (int i = 0; i < 6; i++)
        cv[i] = -(float)i;
    tpk_mesh_add_field(m, "pressure", TPK_ASSOC_POINT, 1, 2, pv);
    tpk_mesh_add_field(m, "velocity", TPK_ASSOC_TET, 3, 1, cv);
    m->step_count = 2;
    m->times = malloc(2 * sizeof *m->times);
    m->times[0] = 0.5, m->times[1] = 1.5;
    snprintf(m->format, sizeof m->format, "made-up-1.0");
    m->has_grid_origin = 1;
    m->grid_origin[0] = 1, m->grid_origin[1] = 2, m->grid_origin[2] = 3;
    m->global_point_ids = malloc(5 * sizeof *m->global_point_ids);
    for (int i = 0; i < 5; i++)
        m->global_point_ids[i] = 1000000000000LL + i;
    m->global_cell_ids = malloc(2 * sizeof *m->global_cell_ids);
    m->global_cell_ids[0] = 7, m->global_cell_ids[1] = 8;
    tpk_diag_warn(diag, "%s: second warning", path);
    return 0;
}

typedef struct warnings {
    int count;
    char last[256];
} warnings;

static void keep_warning(void *user, const char *text)
{
    warnings *w = user;
    w->count++;
    snprintf(w->last, sizeof w->last, "%s", text);
}

TPK_TEST(every_array_comes_back)
{
    tpk_mesh here, there;
    tpk_diag dh, dt;
    warnings wh = {0}, wt = {0};
    memset(&dh, 0, sizeof dh), memset(&dt, 0, sizeof dt);
    dh.lenient_fields = dt.lenient_fields = 1;
    dh.warn = dt.warn = keep_warning;
    dh.warn_user = &wh, dt.warn_user = &wt;
    CHECK(full_reader("made.up", &here, &dh) == 0);
    CHECK_MSG(tpk_isolated_read(full_reader, "made-up", "made.up", &there, &dt) == 0, "%s", dt.message);
    CHECK(tpk_same_mesh(&here, &there));
    CHECK_MSG(wt.count == 2 && dt.warning_count == 2 && strcmp(wt.last, "made.up: second warning") == 0,
              "%d warnings, last '%s'", wt.count, wt.last);
    CHECK(dt.field_problem_count == 1 && strcmp(dt.field_problems[0].name, "short") == 0 &&
          dt.field_problems[0].expected == 9 && dt.field_problems[0].found == 4 &&
          strcmp(dt.field_problems[0].place, "byte 77") == 0);
    tpk_mesh_free(&here);
    tpk_mesh_free(&there);
}

static int failing_reader(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    return tpk_diag_fail(diag, "%s: expected a header, found none at byte 0", path);
}

static int dying_reader(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    tpk_diag_warn(diag, "%s: about to fail", path);
    raise(SIGSEGV);
    return 0;
}

static int aborting_reader(const char *path, tpk_mesh *out, tpk_diag *diag)
{
    (void)path, (void)diag;
    memset(out, 0, sizeof *out);
    abort();
}

static int probe_yes(const char *path)
{
    return path[0] == 'y';
}

static int probe_dies(const char *path)
{
    (void)path;
    raise(SIGSEGV);
    return 1;
}

TPK_TEST(failures_and_deaths_are_errors)
{
    tpk_mesh m;
    tpk_diag d;
    warnings w = {0};
    memset(&d, 0, sizeof d);
    CHECK(tpk_isolated_read(failing_reader, "X", "in.x", &m, &d) == -1);
    CHECK_MSG(strcmp(d.message, "in.x: expected a header, found none at byte 0") == 0, "'%s'", d.message);
    CHECK(!m.points && !m.cell_count);

    memset(&d, 0, sizeof d);
    d.warn = keep_warning, d.warn_user = &w;
    CHECK(tpk_isolated_read(dying_reader, "HDF5", "in.h5", &m, &d) == -1);
    CHECK_MSG(strstr(d.message, "in.h5: the HDF5 library failed reading this file (its process ended with "
                                "signal 11, SIGSEGV)") == d.message, "'%s'", d.message);
    CHECK(w.count == 1 && strcmp(w.last, "in.h5: about to fail") == 0); /* what came before the crash */
    CHECK(!m.points && !m.fields && !m.cell_count);

    memset(&d, 0, sizeof d);
    CHECK(tpk_isolated_read(aborting_reader, "netCDF", "in.nc", &m, &d) == -1);
    CHECK_MSG(strstr(d.message, "signal 6, SIGABRT"), "'%s'", d.message);

    CHECK(tpk_isolated_probe(probe_yes, "yes") == 1);
    CHECK(tpk_isolated_probe(probe_yes, "no") == 0);
    CHECK(tpk_isolated_probe(probe_dies, "yes") == 0);

    /* TETPACK_ISOLATE=0: in process, as a debugger wants it */
    setenv("TETPACK_ISOLATE", "0", 1);
    CHECK(!tpk_isolate_enabled());
    CHECK(tpk_isolated_probe(probe_yes, "yes") == 1);
    unsetenv("TETPACK_ISOLATE");
    CHECK(tpk_isolate_enabled());
}

/* The registry reads Exodus in a child: the same mesh as in process, time steps, fields and global ids. */
TPK_TEST(exodus_through_the_registry)
{
    const char *files[] = {"seacas/exomerge_unit_test.e", "seacas/8-block.g", "seacas/block_crush_1.ex2"};
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        tpk_mesh here, there;
        tpk_diag dh, dt;
        memset(&dh, 0, sizeof dh), memset(&dt, 0, sizeof dt);
        setenv("TETPACK_ISOLATE", "0", 1);
        CHECK_MSG(tpk_import_any(tpk_data_path(files[f]), NULL, &here, &dh) == 0, "%s", dh.message);
        unsetenv("TETPACK_ISOLATE");
        CHECK_MSG(tpk_import_any(tpk_data_path(files[f]), NULL, &there, &dt) == 0, "%s", dt.message);
        CHECK_MSG(tpk_same_mesh(&here, &there), "%s: the isolated read differs", files[f]);
        CHECK(there.field_count > 0 && there.global_point_ids && dh.warning_count == dt.warning_count);
        tpk_mesh_free(&here);
        tpk_mesh_free(&there);
    }
}
