/* ParaView series (.pvd): three VTU steps written by meshio (listed out of time order), merged into one
 * mesh with 3-step fields and sorted times; a step with another mesh, a missing file, broken XML. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "import/importers.h"

/* Steps at t = 0.5, 0.0, 1.5 (in that order in the .pvd) of a 2-tet mesh with point field p = 10*t + id
 * and cell field c = t. `moved` moves a point in the last file. */
static int write_series(const char *dir, int moved)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "/usr/bin/python3 - <<'PY'\n"
             "import meshio, numpy as np\n"
             "pts = np.array([[0,0,0],[1,0,0],[0,1,0],[0,0,1],[0,0,-1]], dtype=float)\n"
             "cells = [('tetra', np.array([[0,1,2,3],[0,2,1,4]]))]\n"
             "entries = []\n"
             "for i, t in enumerate([0.5, 0.0, 1.5]):\n"
             "    p = pts.copy()\n"
             "    if %d and i == 2: p[4, 2] = -2\n"
             "    m = meshio.Mesh(p, cells, point_data={'p': 10 * t + np.arange(5.0)}, cell_data={'c': [np.full(2, t)]})\n"
             "    meshio.write('%s/step%%d.vtu' %% i, m, binary=True)\n"
             "    entries.append('<DataSet timestep=\"%%g\" part=\"0\" file=\"step%%d.vtu\"/>' %% (t, i))\n"
             "open('%s/series.pvd', 'w').write('<?xml version=\"1.0\"?>\\n<VTKFile type=\"Collection\" version=\"0.1\">\\n"
             "<Collection>\\n' + '\\n'.join(entries) + '\\n</Collection>\\n</VTKFile>\\n')\n"
             "PY",
             moved, dir, dir);
    return system(cmd);
}

TPK_TEST(series_becomes_steps)
{
    const char *dir = tpk_temp_dir();
    CHECK(write_series(dir, 0) == 0);
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_any(tpk_temp_path("series.pvd"), NULL, &m, &d) == 0, "%s", d.message);
    int ok = m.step_count == 3 && m.times && m.times[0] == 0.0 && m.times[1] == 0.5 && m.times[2] == 1.5 &&
             m.cell_count == 2 && m.point_count == 5 && !strcmp(m.format, "pvd");
    for (int f = 0; ok && f < m.field_count; f++) {
        const tpk_src_field *fl = &m.fields[f];
        ok = fl->step_count == 3;
        if (ok && !strcmp(fl->name, "p")) /* step s, point i: 10 * t_s + i */
            ok = fl->values[0 * 5 + 3] == 3.0f && fl->values[1 * 5 + 3] == 8.0f && fl->values[2 * 5 + 3] == 18.0f;
        else if (ok && !strcmp(fl->name, "c"))
            ok = fl->values[0] == 0.0f && fl->values[2] == 0.5f && fl->values[5] == 1.5f;
    }
    ok = ok && m.field_count == 2;
    tpk_mesh_free(&m);
    CHECK(ok);
}

TPK_TEST(bad_series)
{
    const char *dir = tpk_temp_dir();
    CHECK(write_series(dir, 1) == 0);
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK(tpk_import_pvd(tpk_temp_path("series.pvd"), &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "series.pvd: step 2") && strstr(d.message, "holds a different mesh"), "%s", d.message);
    remove(tpk_temp_path("step0.vtu"));
    CHECK(tpk_import_pvd(tpk_temp_path("series.pvd"), &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "step0.vtu"), "%s", d.message);
    FILE *f = fopen(tpk_temp_path("broken.pvd"), "w");
    fputs("<VTKFile><Collection><DataSet file=\"a.vtu\"></Collection>", f);
    fclose(f);
    CHECK(tpk_import_pvd(tpk_temp_path("broken.pvd"), &m, &d) != 0);
    CHECK_MSG(strstr(d.message, "broken.pvd:1: not a valid ParaView series"), "%s", d.message);
    CHECK(m.points == NULL && m.field_count == 0);
}
