/* OpenFOAM case directories (tests/data/openfoam/cases/, made by tests/openfoam/make_cases.sh cavity): the
 * icoFoam cavity's polyMesh written by OpenFOAM as ASCII, binary and gzipped ASCII, with fields of known
 * values. The three read identically; every cell converts (6xx checks pass); the volume is the cavity's
 * and foamToVTK's export of the same mesh; broken cases are refused naming the file and what was wrong. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "check/check.h"
#include "convert/pipeline.h"
#include "harness.h"
#include "import/importers.h"
#include "tetpack_format.h"
#include "tpk_assert.h"

#define CASES TPK_SOURCE_DIR "/tests/data/openfoam/cases/"

static const tpk_src_field *field_named(const tpk_mesh *m, const char *name)
{
    for (int i = 0; i < m->field_count; i++)
        if (strcmp(m->fields[i].name, name) == 0)
            return &m->fields[i];
    return NULL;
}

static double tets_volume(const tpk_mesh *m, int64_t *tets, tpk_diag *d)
{
    tpk_tetmesh t;
    if (tpk_tetrahedralize(m, NULL, 0, 0, &t, d) != 0)
        return NAN;
    double volume = 0;
    for (int64_t i = 0; i < t.tet_count; i++) {
        const double *p = t.points;
        const int32_t *q = t.tets + 4 * i;
        double u[3], v[3], w[3];
        for (int k = 0; k < 3; k++) {
            u[k] = p[3 * q[1] + k] - p[3 * q[0] + k];
            v[k] = p[3 * q[2] + k] - p[3 * q[0] + k];
            w[k] = p[3 * q[3] + k] - p[3 * q[0] + k];
        }
        volume += (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                   u[2] * (v[0] * w[1] - v[1] * w[0])) / 6;
    }
    *tets = t.tet_count;
    tpk_tetmesh_free(&t);
    return volume;
}

static int same_mesh_and_fields(const tpk_mesh *a, const tpk_mesh *b)
{
    if (!tpk_mesh_same_cells(a, b) || a->field_count != b->field_count || a->step_count != b->step_count)
        return 0;
    if (a->face_offsets[a->cell_count] != b->face_offsets[b->cell_count] ||
        memcmp(a->faces, b->faces, sizeof *a->faces * (size_t)a->face_offsets[a->cell_count]) != 0)
        return 0;
    for (int i = 0; i < a->field_count; i++) {
        const tpk_src_field *fa = &a->fields[i], *fb = field_named(b, fa->name);
        int64_t n = fa->association == TPK_ASSOC_POINT ? a->point_count : a->cell_count;
        if (!fb || fb->components != fa->components || fb->step_count != fa->step_count ||
            memcmp(fa->values, fb->values, sizeof *fa->values * (size_t)(n * fa->components * fa->step_count)))
            return 0;
    }
    return 1;
}

TPK_TEST(cavity_ascii_binary_gzip_agree)
{
    static const char *const inputs[] = {CASES "cavity_binary", CASES "cavity_gzip", CASES "cavity_ascii/cavity.foam",
                                         CASES "cavity_ascii/constant/polyMesh"};
    tpk_mesh ascii, other;
    tpk_diag d = {0};
    CHECK_MSG(tpk_import_any(CASES "cavity_ascii", NULL, &ascii, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(ascii.cell_count, 400);
    CHECK_EQ_INT(ascii.point_count, 882);
    CHECK(strcmp(ascii.format, "openfoam-ascii") == 0);
    for (size_t i = 0; i < sizeof inputs / sizeof inputs[0]; i++) {
        CHECK_MSG(tpk_import_any(inputs[i], NULL, &other, &d) == 0, "%s: %s", inputs[i], d.message);
        int same = same_mesh_and_fields(&ascii, &other);
        tpk_mesh_free(&other);
        CHECK_MSG(same, "%s reads differently from cavity_ascii", inputs[i]);
    }
    tpk_mesh_free(&ascii);
}

TPK_TEST(cavity_fields_and_time_steps)
{
    tpk_mesh m;
    tpk_diag d = {0};
    CHECK_MSG(tpk_import_any(CASES "cavity_binary", NULL, &m, &d) == 0, "%s", d.message);
    const tpk_src_field *p = field_named(&m, "p"), *pp = field_named(&m, "pp"), *u = field_named(&m, "U");
    int ok = p && pp && u && u->components == 3 && u->association == TPK_ASSOC_TET && m.step_count == 2 && m.times && m.times[0] == 0.25 && m.times[1] == 0.5 &&
             p->association == TPK_ASSOC_TET && p->step_count == 2 && pp->association == TPK_ASSOC_POINT;
    /* make_cases.sh: at 0.25 p uniform 2 and pp uniform 1; at 0.5 p = 0.5 + cell / 1000, pp = point id. */
    for (int64_t c = 0; ok && c < m.cell_count; c++)
        ok = p->values[c] == 2.0f && p->values[m.cell_count + c] == (float)(0.5 + c / 1000.0);
    /* U: uniform (1 2 3) at 0.25; (cell, -cell, 0.25) at 0.5. */
    for (int64_t c = 0; ok && c < m.cell_count; c++) {
        const float *at25 = u->values + 3 * c, *at5 = u->values + 3 * (m.cell_count + c);
        ok = at25[0] == 1 && at25[1] == 2 && at25[2] == 3 && at5[0] == (float)c && at5[1] == (float)-c &&
             at5[2] == 0.25f;
    }
    for (int64_t i = 0; ok && i < m.point_count; i++)
        ok = pp->values[i] == 1.0f && pp->values[m.point_count + i] == (float)i;
    tpk_mesh_free(&m);
    CHECK_MSG(ok, "fields p, pp and U or their time steps differ from what make_cases.sh wrote");
}

/* A case and foamToVTK's .vtk of the same cells, both imported and tetrahedralized: cell counts, tets and
 * volumes (NaN volume, with d's message, when a split fails). Returns 0, or -1 when an import fails. */
typedef struct case_and_vtk {
    int64_t cells, tets, vtk_cells, vtk_tets;
    double volume, vtk_volume;
} case_and_vtk;

static int import_case_and_vtk(const char *case_path, const char *vtk_path, case_and_vtk *out, tpk_diag *d)
{
    tpk_mesh foam, vtk;
    memset(out, 0, sizeof *out);
    if (tpk_import_any(case_path, NULL, &foam, d) != 0)
        return -1;
    if (tpk_import_vtk_legacy(vtk_path, &vtk, d) != 0) {
        tpk_mesh_free(&foam);
        return -1;
    }
    out->cells = foam.cell_count, out->vtk_cells = vtk.cell_count;
    out->volume = tets_volume(&foam, &out->tets, d);
    out->vtk_volume = tets_volume(&vtk, &out->vtk_tets, d);
    tpk_mesh_free(&foam);
    tpk_mesh_free(&vtk);
    return 0;
}

TPK_TEST(cavity_volume_and_conversion)
{
    tpk_diag d = {0};
    case_and_vtk c;
    CHECK_MSG(import_case_and_vtk(CASES "cavity_gzip", TPK_SOURCE_DIR "/tests/data/openfoam/cavity.vtk", &c, &d) == 0,
              "%s", d.message);
    int64_t foam_cells = c.cells, vtk_cells = c.vtk_cells, foam_tets = c.tets;
    double foam_volume = c.volume, vtk_volume = c.vtk_volume;
    printf("cavity: %lld cells, %lld tets, volume %.17g; foamToVTK's: %lld cells, volume %.17g\n",
           (long long)foam_cells, (long long)foam_tets, foam_volume, (long long)vtk_cells, vtk_volume);
    CHECK_EQ_INT(foam_cells, vtk_cells);
    /* The cavity is the box 0.1 x 0.1 x 0.01 (blockMeshDict, checkMesh's bounding box). */
    CHECK_MSG(fabs(foam_volume - 1e-4) <= 1e-12 * 1e-4, "volume %.17g, the cavity's is 1e-4", foam_volume);
    /* foamToVTK writes float32 points: 0.1 rounds by 1.5e-8 relative. */
    CHECK_MSG(fabs(foam_volume - vtk_volume) <= 1e-7 * foam_volume, "%.17g vs foamToVTK's %.17g", foam_volume,
              vtk_volume);

    tpk_convert_options o = {0};
    tpk_convert_report r;
    o.input = CASES "cavity_ascii";
    o.output = tpk_temp_path("cavity.tpk");
    o.cell_to_point = 1;
    CHECK_MSG(tpk_convert_checked(&o, &r, &d) == 0, "%s", d.message);
    CHECK_EQ_INT(r.source_cells, 400);
    CHECK_EQ_INT(r.tets, foam_tets);
}

/* ---- broken cases: the ASCII cavity copied with one file changed ------------------------------------ */

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *data = NULL;
    struct stat st;
    if (f && fstat(fileno(f), &st) == 0 && (data = malloc((size_t)st.st_size + 1)) != NULL)
        *size = fread(data, 1, (size_t)st.st_size, f);
    if (f)
        fclose(f);
    return data;
}

/* A copy of cavity_ascii's polyMesh under the temp dir, with `name` cut to `keep` bytes (SIZE_MAX: whole)
 * after replacing the first `from` by `to` (NULL: unchanged), or left out when keep is 0. */
static const char *broken_case(const char *tag, const char *name, size_t keep, const char *from, const char *to)
{
    static const char *const files[] = {"points", "faces", "owner", "neighbour"};
    static char dir[600];
    char mesh[700];
    snprintf(dir, sizeof dir, "%s", tpk_temp_path(tag));
    snprintf(mesh, sizeof mesh, "%s/constant", dir);
    mkdir(dir, 0777), mkdir(mesh, 0777);
    snprintf(mesh, sizeof mesh, "%s/constant/polyMesh", dir);
    mkdir(mesh, 0777);
    for (int i = 0; i < 4; i++) {
        char src[600], dst[800];
        size_t size = 0;
        snprintf(src, sizeof src, CASES "cavity_ascii/constant/polyMesh/%s", files[i]);
        snprintf(dst, sizeof dst, "%s/%s", mesh, files[i]);
        char *data = slurp(src, &size);
        int edited = strcmp(files[i], name) == 0;
        if (edited && keep == 0) {
            free(data);
            continue;
        }
        char *at = edited && from && data ? strstr(data, from) : NULL;
        FILE *f = fopen(dst, "wb");
        if (at) {
            fwrite(data, 1, (size_t)(at - data), f);
            fputs(to, f);
            fwrite(at + strlen(from), 1, size - (size_t)(at - data) - strlen(from), f);
        } else if (f && data) {
            fwrite(data, 1, edited && keep < size ? keep : size, f);
        }
        if (f)
            fclose(f);
        free(data);
    }
    return dir;
}

/* Import `dir` and require an error message holding every one of the words. */
static int refused_with(const char *dir, const char *w1, const char *w2)
{
    tpk_mesh m;
    tpk_diag d = {0};
    if (tpk_import_any(dir, NULL, &m, &d) == 0) {
        tpk_mesh_free(&m);
        fprintf(stderr, "%s: read, expected a refusal\n", dir);
        return 0;
    }
    printf("%s\n", d.message);
    return strstr(d.message, w1) && strstr(d.message, w2);
}

TPK_TEST(broken_cases_refused)
{
    CHECK(refused_with(broken_case("no_owner", "owner", 0, NULL, NULL), "constant/polyMesh/owner", "missing"));
    CHECK(refused_with(broken_case("short_faces", "faces", 3000, NULL, NULL), "polyMesh/faces:", "cannot fit"));
    CHECK(refused_with(broken_case("cut_faces", "faces", 20000, NULL, NULL), "polyMesh/faces:1064:",
                       "face points cannot fit"));
    CHECK(refused_with(broken_case("bad_header", "points", SIZE_MAX, "FoamFile", "FoamFiel"), "polyMesh/points:",
                       "expected the 'FoamFile' header"));
    CHECK(refused_with(broken_case("arch", "points", SIZE_MAX, "format      ascii;\n",
                                   "format binary; arch \"LSB;label=64;scalar=64\";"),
                       "polyMesh/points:", "label=64"));
    CHECK(refused_with(broken_case("huge", "owner", SIZE_MAX, "\n1640\n", "\n999999999\n"), "polyMesh/owner:",
                       "cannot fit"));
    CHECK(refused_with(broken_case("bad_id", "faces", SIZE_MAX, "4(1 22 463 442)", "4(1 22 463 9999)"),
                       "polyMesh/faces", "9999"));
}

/* snappyHexMesh's flange (cases/flange_binary: the polyMesh of flange.vtk, binary, gzipped): every cell a
 * polyhedron here, split with points at face and cell centres where needed. Its cells are OpenFOAM's
 * (flange.volumes.txt); the volume is that of foamToVTK's export of the same cells (float32 points; hexahedra
 * and prisms split there as such, so warped faces take other diagonals). */
TPK_TEST(flange_binary_volume)
{
    tpk_diag d = {0};
    case_and_vtk c;
    CHECK_MSG(import_case_and_vtk(CASES "flange_binary/flange.foam", TPK_SOURCE_DIR "/tests/data/openfoam/flange.vtk",
                                  &c, &d) == 0, "%s", d.message);
    int64_t cells = c.cells, vtk_cells = c.vtk_cells, tets = c.tets;
    double volume = c.volume, vtk_volume = c.vtk_volume;
#ifndef TPK_WITH_TETGEN
    /* 4 of its cells only TetGen splits inside their boundary: refused by name. */
    CHECK_MSG(isnan(volume) && strstr(d.message, "TetGen"), "%s", d.message);
    return;
#endif
    printf("flange: %lld cells, %lld tets, volume %.17g; foamToVTK's %.17g: relative %.3g\n", (long long)cells,
           (long long)tets, volume, vtk_volume, fabs(volume - vtk_volume) / vtk_volume);
    CHECK_EQ_INT(cells, 2764);
    CHECK_EQ_INT(cells, vtk_cells);
    /* 8e-9 measured: float32 points there. */
    CHECK_MSG(fabs(volume - vtk_volume) <= 1e-7 * vtk_volume, "volume %.17g, foamToVTK's %.17g", volume, vtk_volume);
}

/* The converted flange passes check with no error and few flat tets: faces whose fan from the smallest id
 * left a near-flat triangle (a corner on a straight edge, kept from a finer neighbour) are cut along the
 * other diagonal or at a point. Before, 5 tets of the file were slivers (209); windAroundBuildings'
 * file had 2209 and a shell self-intersection (406) from one such face. */
TPK_TEST(snapped_faces_cut_without_flat_triangles)
{
    tpk_convert_options o = {0};
    tpk_convert_report r;
    tpk_diag d = {0};
    o.input = CASES "flange_binary";
    o.output = tpk_temp_path("flange.tpk");
    CHECK_MSG(tpk_convert_checked(&o, &r, &d) == 0, "%s", d.message);
#ifdef TPK_WITH_TETGEN
    printf("flange: %lld tets, %lld faces recut, %lld flat tets\n", (long long)r.tets, (long long)r.thin_faces_recut,
           (long long)r.flat_tets);
    CHECK(r.thin_faces_recut > 0);
    CHECK(r.flat_tets <= 3);
    tpk_check_options options;
    tpk_check_options_default(&options);
    tpk_check_report report;
    CHECK(tpk_check_report_init(&report, &options) == 0);
    CHECK_MSG(tpk_check_path(o.output, NULL, &report, &d) == 0, "%s", d.message);
    for (int i = 0; i < report.finding_count; i++) {
        const tpk_finding *f = &report.findings[i];
        CHECK_MSG(f->count == 0 || f->check->severity != TPK_SEV_ERROR, "%d %s: %lld", f->check->id,
                  f->check->name, (long long)f->count);
    }
    CHECK(tpk_check_finding(&report, 209)->count <= 3);
    tpk_check_report_free(&report);
#endif
}
