/* Real snappyHexMesh meshes exported by OpenFOAM's foamToVTK (tests/data/openfoam/, made by
 * tests/openfoam/make_cases.sh; README.md there says how): hexahedra, prisms and polyhedra whose faces carry
 * points on their edges and are not planar. Each converts with no cell left out; every tet positive (exact)
 * and no face in three tets; every point of every cell used by that cell's tets; and the tets' volume equals
 * the sum of OpenFOAM's own cell volumes (writeCellVolumes, 17 digits) to 1e-6 relative, or differs by no
 * more than the triangulation of warped boundary faces explains, bounded here face by face. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/pipeline.h"
#include "harness.h"
#include "import/importers.h"
#include "mesh/polyhedron.h"

#define CASE_DIR TPK_SOURCE_DIR "/tests/data/openfoam/"

/* ---- OpenFOAM's numbers ------------------------------------------------------------------------- */

/* "NAME value" from a small text file (NAME.volumes.txt, NAME.checkMesh.txt); NAN when absent. */
static double read_number(const char *path, const char *name)
{
    FILE *f = fopen(path, "r");
    char line[256];
    double value = NAN;
    size_t len = strlen(name);
    while (f && fgets(line, sizeof line, f)) {
        const char *at = line + strspn(line, " ");
        if (!strncmp(at, name, len) && (at[len] == ' ' || at[len] == ':'))
            value = strtod(at + len + 1, NULL);
    }
    if (f)
        fclose(f);
    return value;
}

/* ---- faces and their volume terms ----------------------------------------------------------------- */

static void sub(const double *a, const double *b, double *out)
{
    out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}

static void cross(const double *u, const double *v, double *out)
{
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
}

static double dot(const double *u, const double *v)
{
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

/* 3 x the volume term of triangle (a, b, c) relative to o: det[a-o, b-o, c-o] / 2. */
static double triangle_term3(const double *a, const double *b, const double *c, const double *o)
{
    double u[3], v[3], w[3], n[3];
    sub(a, o, u), sub(b, o, v), sub(c, o, w);
    cross(v, w, n);
    return dot(u, n) / 2;
}

/* 3 x a face's volume term as OpenFOAM computes it (primitiveMeshFaceCentresAndAreas, v1912): Sf . (Cf - o),
 * Sf and Cf from the triangles fanned from the mean of its points, Cf weighted by their areas. */
static double openfoam_term3(const double *p, const int32_t *v, int64_t n, const double *o)
{
    if (n == 3)
        return triangle_term3(p + 3 * (int64_t)v[0], p + 3 * (int64_t)v[1], p + 3 * (int64_t)v[2], o);
    double mean[3] = {0, 0, 0}, sum_n[3] = {0, 0, 0}, sum_ac[3] = {0, 0, 0}, sum_a = 0;
    for (int64_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            mean[k] += p[3 * (int64_t)v[i] + k] / (double)n;
    for (int64_t i = 0; i < n; i++) {
        const double *a = p + 3 * (int64_t)v[i], *b = p + 3 * (int64_t)v[(i + 1) % n];
        double e[3], f[3], tn[3];
        sub(b, a, e), sub(mean, a, f);
        cross(e, f, tn);
        double area = sqrt(dot(tn, tn));
        for (int k = 0; k < 3; k++) {
            sum_n[k] += tn[k];
            sum_ac[k] += area * (a[k] + b[k] + mean[k]);
        }
        sum_a += area;
    }
    double cf_o[3];
    for (int k = 0; k < 3; k++)
        cf_o[k] = (sum_a > 0 ? sum_ac[k] / (3 * sum_a) : mean[k]) - o[k];
    return 0.5 * dot(sum_n, cf_o);
}

/* 3 x the volume term of the fan from q over the face. */
static double fan_term3(const double *p, const int32_t *v, int64_t n, const double *q, const double *o)
{
    double sum = 0;
    for (int64_t i = 0; i < n; i++)
        sum += triangle_term3(p + 3 * (int64_t)v[i], p + 3 * (int64_t)v[(i + 1) % n], q, o);
    return sum;
}

/* The most a face's volume term can differ from OpenFOAM's under the triangulations the converter may give
 * it: a fan from any corner (the smallest id's, either quad diagonal), from its mean, or from the midpoint of
 * any diagonal (tools/convert/steiner.c). Zero for triangles and planar faces. */
static double warp_bound3(const double *p, const int32_t *v, int64_t n, const double *o)
{
    if (n == 3)
        return 0;
    double of = openfoam_term3(p, v, n, o), worst = 0, mean[3] = {0, 0, 0};
    for (int64_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            mean[k] += p[3 * (int64_t)v[i] + k] / (double)n;
    worst = fabs(fan_term3(p, v, n, mean, o) - of);
    for (int64_t i = 0; i < n; i++) {
        double d = fabs(fan_term3(p, v, n, p + 3 * (int64_t)v[i], o) - of);
        worst = d > worst ? d : worst;
        for (int64_t j = i + 2; j < n && j - i < n - 1; j++) {
            const double *a = p + 3 * (int64_t)v[i], *b = p + 3 * (int64_t)v[j];
            double mid[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
            d = fabs(fan_term3(p, v, n, mid, o) - of);
            worst = d > worst ? d : worst;
        }
    }
    return worst;
}

/* Every cell's faces, outward (as tools/convert/steiner.c loads them), with their sorted ids as a key. */
typedef struct face_list {
    int64_t count, id_count;
    int64_t *starts; /* count + 1, into ids and sorted */
    int32_t *ids, *sorted;
} face_list;

static int compare_ids(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

static const face_list *sort_faces_by; /* qsort has no user pointer */

static int compare_faces(const void *a, const void *b)
{
    const face_list *l = sort_faces_by;
    int64_t f = *(const int64_t *)a, g = *(const int64_t *)b;
    int64_t nf = l->starts[f + 1] - l->starts[f], ng = l->starts[g + 1] - l->starts[g];
    if (nf != ng)
        return nf < ng ? -1 : 1;
    for (int64_t i = 0; i < nf; i++) {
        int c = compare_ids(l->sorted + l->starts[f] + i, l->sorted + l->starts[g] + i);
        if (c)
            return c;
    }
    return f < g ? -1 : f > g;
}

static int same_face(const face_list *l, int64_t f, int64_t g)
{
    int64_t n = l->starts[f + 1] - l->starts[f];
    return n == l->starts[g + 1] - l->starts[g] &&
           !memcmp(l->sorted + l->starts[f], l->sorted + l->starts[g], sizeof(int32_t) * (size_t)n);
}

static void collect_faces(const tpk_mesh *m, face_list *l)
{
    tpk_polygons p;
    char why[200];
    memset(&p, 0, sizeof p);
    memset(l, 0, sizeof *l);
    int64_t cap = 64, id_cap = 256;
    l->starts = malloc(sizeof *l->starts * (size_t)(cap + 1));
    l->ids = malloc(sizeof *l->ids * (size_t)id_cap);
    l->starts[0] = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        if (m->cell_types[c] == TPK_CELL_POLYHEDRON)
            tpk_polygons_from_stream(&p, m->faces + m->face_offsets[c], m->face_offsets[c + 1] - m->face_offsets[c]);
        else
            tpk_polygons_from_cell(&p, m->cell_types[c], m->cell_conn + m->cell_offsets[c]);
        if (tpk_polygons_orient(&p, why, sizeof why) == 0 && tpk_polygons_volume6(&p, m->points) < 0)
            tpk_polygons_flip(&p);
        for (int64_t f = 0; f < p.face_count; f++) {
            int64_t n = p.starts[f + 1] - p.starts[f];
            if (l->count + 1 >= cap)
                l->starts = realloc(l->starts, sizeof *l->starts * (size_t)((cap *= 2) + 1));
            if (l->id_count + n >= id_cap)
                l->ids = realloc(l->ids, sizeof *l->ids * (size_t)(id_cap *= 2));
            memcpy(l->ids + l->id_count, p.ids + p.starts[f], sizeof *l->ids * (size_t)n);
            l->id_count += n;
            l->starts[++l->count] = l->id_count;
        }
    }
    tpk_polygons_free(&p);
    l->sorted = malloc(sizeof *l->sorted * (size_t)(l->id_count + 1));
    memcpy(l->sorted, l->ids, sizeof *l->sorted * (size_t)l->id_count);
    for (int64_t f = 0; f < l->count; f++)
        qsort(l->sorted + l->starts[f], (size_t)(l->starts[f + 1] - l->starts[f]), sizeof *l->sorted, compare_ids);
}

/* OpenFOAM's volume from the boundary faces (a face of one cell only) of the file's (float32) points,
 * and the bound on how far a triangulation of those faces can move it; relative to the first point. */
static void boundary_volume(const tpk_mesh *m, double *openfoam, double *bound, int64_t *boundary_faces)
{
    face_list l;
    collect_faces(m, &l);
    int64_t *order = malloc(sizeof *order * (size_t)(l.count + 1));
    for (int64_t f = 0; f < l.count; f++)
        order[f] = f;
    sort_faces_by = &l;
    qsort(order, (size_t)l.count, sizeof *order, compare_faces);
    double sum = 0, worst = 0;
    *boundary_faces = 0;
    for (int64_t i = 0; i < l.count;) {
        int64_t end = i + 1;
        while (end < l.count && same_face(&l, order[i], order[end]))
            end++;
        if (end - i == 1) {
            const int32_t *v = l.ids + l.starts[order[i]];
            int64_t n = l.starts[order[i] + 1] - l.starts[order[i]];
            sum += openfoam_term3(m->points, v, n, m->points);
            worst += warp_bound3(m->points, v, n, m->points);
            ++*boundary_faces;
        }
        i = end;
    }
    *openfoam = sum / 3;
    *bound = worst / 3;
    free(order), free(l.starts), free(l.ids), free(l.sorted);
}

/* ---- the cases ------------------------------------------------------------------------------------ */

static double tet_volume(const double *p, const int32_t *t)
{
    double u[3], v[3], w[3], n[3];
    sub(p + 3 * (int64_t)t[1], p + 3 * (int64_t)t[0], u);
    sub(p + 3 * (int64_t)t[2], p + 3 * (int64_t)t[0], v);
    sub(p + 3 * (int64_t)t[3], p + 3 * (int64_t)t[0], w);
    cross(v, w, n);
    return dot(u, n) / 6;
}

/* Does every cell's tets use every point of the cell (its corners; a polyhedron's every face point)?
 * Returns the first cell that leaves one out, or -1. */
static int64_t cell_leaving_out_a_point(const tpk_mesh *m, const tpk_tetmesh *t)
{
    int64_t *start = calloc((size_t)m->cell_count + 1, sizeof *start), *stamp = malloc(sizeof *stamp *
                                                                                         (size_t)t->vertex_count);
    int64_t *by_cell = malloc(sizeof *by_cell * (size_t)(t->tet_count + 1)), bad = -1;
    for (int64_t i = 0; i < t->tet_count; i++)
        start[t->tet_source[i] + 1]++;
    for (int64_t c = 0; c < m->cell_count; c++)
        start[c + 1] += start[c];
    int64_t *fill = malloc(sizeof *fill * (size_t)(m->cell_count + 1));
    memcpy(fill, start, sizeof *fill * (size_t)(m->cell_count + 1));
    for (int64_t i = 0; i < t->tet_count; i++)
        by_cell[fill[t->tet_source[i]]++] = i;
    for (int64_t v = 0; v < t->vertex_count; v++)
        stamp[v] = -1;
    for (int64_t c = 0; c < m->cell_count && bad < 0; c++) {
        for (int64_t k = start[c]; k < start[c + 1]; k++)
            for (int j = 0; j < 4; j++)
                stamp[t->tets[4 * by_cell[k] + j]] = c;
        for (int64_t k = m->cell_offsets[c]; k < m->cell_offsets[c + 1] && bad < 0; k++)
            if (stamp[m->cell_conn[k]] != c)
                bad = c;
    }
    free(start), free(stamp), free(by_cell), free(fill);
    return bad;
}

static void run_case(const char *name)
{
    char path[512], numbers[512], summary[512];
    snprintf(path, sizeof path, CASE_DIR "%s.vtk", name);
    snprintf(numbers, sizeof numbers, CASE_DIR "%s.volumes.txt", name);
    snprintf(summary, sizeof summary, CASE_DIR "%s.checkMesh.txt", name);
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    CHECK_MSG(tpk_import_vtk_legacy(path, &m, &d) == 0, "%s: %s", path, d.message);

    /* The cells OpenFOAM counted: hexahedra stay hexahedra; prisms, tet wedges and polyhedra come as
     * wedges or polyhedra. */
    int64_t hexes = 0, wedges = 0, polyhedra = 0;
    for (int64_t c = 0; c < m.cell_count; c++) {
        hexes += m.cell_types[c] == TPK_CELL_HEXAHEDRON;
        wedges += m.cell_types[c] == TPK_CELL_WEDGE;
        polyhedra += m.cell_types[c] == TPK_CELL_POLYHEDRON;
    }
    double of_cells = read_number(numbers, "cells"), of_sum = read_number(numbers, "openfoam_volume_sum");
    CHECK_MSG(of_cells == (double)m.cell_count && isfinite(of_sum), "%s: %lld cells, OpenFOAM's V lists %.0f",
              name, (long long)m.cell_count, of_cells);
    CHECK_EQ_INT(hexes, read_number(summary, "hexahedra"));
    CHECK_EQ_INT(wedges + polyhedra, read_number(summary, "prisms") + read_number(summary, "tet wedges") +
                                         read_number(summary, "polyhedra") + read_number(summary, "pyramids") +
                                         read_number(summary, "tetrahedra"));
    CHECK_EQ_INT(hexes + wedges + polyhedra, m.cell_count);

    double of_boundary, bound;
    int64_t boundary_faces;
    boundary_volume(&m, &of_boundary, &bound, &boundary_faces);

    tpk_tetmesh t;
    tpk_orient_stats os;
    int split = tpk_tetrahedralize(&m, NULL, 0, 0, &t, &d);
#ifndef TPK_WITH_TETGEN
    /* Some of these cells only TetGen can tetrahedralize inside their boundary: refused by name. */
    if (split != 0) {
        tpk_mesh_free(&m);
        CHECK_MSG(strstr(d.message, "too warped") && strstr(d.message, "no TetGen"), "%s: %s", name, d.message);
        return;
    }
#endif
    CHECK_MSG(split == 0, "%s: %s", name, d.message);
    int rc = tpk_orient(&t, TPK_ORIENT_REFUSE_INVERTED, 1, &os, &d);
    int32_t *nb = rc == 0 ? malloc(sizeof *nb * 4 * (size_t)t.tet_count) : NULL;
    if (rc == 0)
        rc = tpk_connect(t.tets, t.tet_count, t.vertex_count, nb, 1, &d);
    free(nb);
    int64_t leaving_out = rc == 0 ? cell_leaving_out_a_point(&m, &t) : -1;
    double volume = 0;
    for (int64_t i = 0; rc == 0 && i < t.tet_count; i++)
        volume += tet_volume(t.points, t.tets + 4 * i);
    double error = fabs(volume - of_sum) / of_sum, explained = (bound + fabs(of_boundary - of_sum)) / of_sum;
    printf("%s: %lld cells (%lld hexahedra, %lld wedges, %lld polyhedra), %lld tets, %lld points added (%lld at "
           "face centres), %lld cells from a centre point, %lld inside their boundary (TetGen); volume %.17g vs "
           "OpenFOAM's %.17g: relative error %.3g (OpenFOAM's formula on the file's float32 points: %.3g; warped "
           "boundary faces (%lld) can explain %.3g)\n",
           name, (long long)m.cell_count, (long long)hexes, (long long)wedges, (long long)polyhedra,
           (long long)t.tet_count, (long long)(t.vertex_count - m.point_count), (long long)t.face_steiner_points,
           (long long)t.steiner_cells, (long long)t.fixed_boundary_cells, volume, of_sum, error,
           fabs(of_boundary - of_sum) / of_sum, (long long)boundary_faces, bound / of_sum);
    int64_t skipped = t.bad_cells_skipped, mirrored = t.mirrored_cells;
    tpk_tetmesh_free(&t);
    tpk_mesh_free(&m);
    CHECK_MSG(rc == 0, "%s: %s", name, d.message);
    CHECK_EQ_INT(skipped, 0);
    CHECK_EQ_INT(os.inverted_fixed, 0);
    /* foamToVTK (v1912) writes every prism with its first triangle facing away from the second, VTK's
     * documented face order; tetpack reads wedges by VTK's parametric coordinates, where it faces the
     * second: each prism counts as mirrored (and is turned over, without TPK_TETRA_REFUSE_MIRRORED). */
    CHECK_EQ_INT(mirrored, wedges);
    CHECK_MSG(leaving_out < 0, "%s: the tets of cell %lld leave out one of its points", name, (long long)leaving_out);
    CHECK_MSG(fabs(of_boundary - of_sum) <= 1e-6 * of_sum, "%s: OpenFOAM's formula gives %.17g on the file, "
              "OpenFOAM wrote %.17g", name, of_boundary, of_sum);
    CHECK_MSG(error <= 1e-6 || error <= explained * (1 + 1e-9) + 1e-12, "%s: volume %.17g, OpenFOAM's %.17g: "
              "relative error %.3g, more than warped boundary faces explain (%.3g)", name, volume, of_sum, error,
              explained);
}

TPK_TEST(wind_around_buildings)
{
    run_case("wind");
}

TPK_TEST(igloo_with_fridges)
{
    run_case("igloo");
}

TPK_TEST(flange)
{
    run_case("flange");
}
