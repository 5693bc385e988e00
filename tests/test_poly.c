/* Polyhedra (VTK type 42) and added points (tools/mesh/polyhedron.c, tools/convert/steiner.c): sfepy's hexahedra
 * rewritten as polyhedra in VTK legacy (old and 5.1 forms, ASCII and binary) and VTU read back and
 * convert to the same volume with no inner boundary; mixed meshes stay conforming; a non-convex
 * polyhedron converts when its centre sees every face and is refused by name when not; a warped
 * hexahedron gets a face point its neighbour shares; broken face streams are refused with their place. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/cell_split.h"
#include "mesh/cell_types.h"
#include "harness.h"
#include "import/importers.h"
#include "convert/pipeline.h"
#include "mesh/polyhedron.h"

/* ---- building and writing meshes ------------------------------------------------------------------ */

static int compare_ids(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Rewrite the hexahedra c with pick(c) != 0 as polyhedra (their six quads, turned inward when
 * pick(c) == 2); other cells stay. */
static void hexes_to_polyhedra(tpk_mesh *m, int (*pick)(int64_t c))
{
    int64_t n = m->cell_count;
    int64_t *offsets = malloc(sizeof *offsets * (size_t)(n + 1)), *face_offsets = malloc(sizeof *face_offsets * (size_t)(n + 1));
    int32_t *conn = malloc(sizeof *conn * (size_t)(m->cell_offsets[n] + 1));
    int32_t *faces = malloc(sizeof *faces * (size_t)(31 * n + 1)); /* 6 quads: 1 + 6 * 5 entries */
    offsets[0] = face_offsets[0] = 0;
    for (int64_t c = 0; c < n; c++) {
        const int32_t *nodes = m->cell_conn + m->cell_offsets[c];
        int64_t count = m->cell_offsets[c + 1] - m->cell_offsets[c], f_at = face_offsets[c];
        int how = m->cell_types[c] == TPK_CELL_HEXAHEDRON ? pick(c) : 0;
        memcpy(conn + offsets[c], nodes, sizeof *conn * (size_t)count);
        if (how) {
            int32_t ids[24];
            int starts[7];
            int face_count = tpk_cell_faces(TPK_CELL_HEXAHEDRON, nodes, ids, starts);
            faces[f_at++] = face_count;
            for (int f = 0; f < face_count; f++) {
                faces[f_at++] = starts[f + 1] - starts[f];
                for (int i = 0; i < starts[f + 1] - starts[f]; i++)
                    faces[f_at++] = ids[how == 2 ? starts[f + 1] - 1 - i : starts[f] + i];
            }
            qsort(conn + offsets[c], (size_t)count, sizeof *conn, compare_ids);
            m->cell_types[c] = TPK_CELL_POLYHEDRON;
        }
        offsets[c + 1] = offsets[c] + count;
        face_offsets[c + 1] = f_at;
    }
    free(m->cell_offsets), free(m->cell_conn), free(m->face_offsets), free(m->faces);
    m->cell_offsets = offsets, m->cell_conn = conn, m->face_offsets = face_offsets, m->faces = faces;
}

/* A cell's entries as VTK legacy stores them: a polyhedron's face stream, else its points. */
static const int32_t *legacy_entries(const tpk_mesh *m, int64_t c, int64_t *count)
{
    if (m->cell_types[c] == TPK_CELL_POLYHEDRON) {
        *count = m->face_offsets[c + 1] - m->face_offsets[c];
        return m->faces + m->face_offsets[c];
    }
    *count = m->cell_offsets[c + 1] - m->cell_offsets[c];
    return m->cell_conn + m->cell_offsets[c];
}

static void put_be32(FILE *f, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)(v >> 24), (unsigned char)(v >> 16), (unsigned char)(v >> 8), (unsigned char)v};
    fwrite(b, 1, 4, f);
}

static void put_be64(FILE *f, uint64_t v)
{
    put_be32(f, (uint32_t)(v >> 32));
    put_be32(f, (uint32_t)v);
}

/* form 0: ASCII, CELLS lists; 1: ASCII, VTK 5.1 OFFSETS/CONNECTIVITY; 2: BINARY, CELLS lists. */
static void write_legacy(const tpk_mesh *m, const char *path, int form)
{
    FILE *f = fopen(path, "wb");
    int64_t total = 0, count;
    for (int64_t c = 0; c < m->cell_count; c++) {
        legacy_entries(m, c, &count);
        total += count;
    }
    fprintf(f, "# vtk DataFile Version %s\npolyhedra\n%s\nDATASET UNSTRUCTURED_GRID\nPOINTS %lld double\n",
            form == 1 ? "5.1" : "4.2", form == 2 ? "BINARY" : "ASCII", (long long)m->point_count);
    for (int64_t i = 0; i < 3 * m->point_count; i++) {
        if (form == 2) {
            uint64_t bits;
            memcpy(&bits, &m->points[i], 8);
            put_be64(f, bits);
        } else {
            fprintf(f, "%.17g%c", m->points[i], i % 3 == 2 ? '\n' : ' ');
        }
    }
    if (form == 1) {
        fprintf(f, "CELLS %lld %lld\nOFFSETS vtktypeint64\n", (long long)m->cell_count + 1, (long long)total);
        for (int64_t c = 0, at = 0; c <= m->cell_count; c++) {
            fprintf(f, "%lld\n", (long long)at);
            if (c < m->cell_count)
                legacy_entries(m, c, &count), at += count;
        }
        fprintf(f, "CONNECTIVITY vtktypeint64\n");
    } else {
        fprintf(f, "%sCELLS %lld %lld\n", form == 2 ? "\n" : "", (long long)m->cell_count,
                (long long)(total + m->cell_count));
    }
    for (int64_t c = 0; c < m->cell_count; c++) {
        const int32_t *e = legacy_entries(m, c, &count);
        if (form == 2)
            put_be32(f, (uint32_t)count);
        else if (form == 0)
            fprintf(f, "%lld", (long long)count);
        for (int64_t i = 0; i < count; i++) {
            if (form == 2)
                put_be32(f, (uint32_t)e[i]);
            else
                fprintf(f, form == 0 || i ? " %d" : "%d", e[i]);
        }
        if (form != 2)
            fprintf(f, "\n");
    }
    fprintf(f, "%sCELL_TYPES %lld\n", form == 2 ? "\n" : "", (long long)m->cell_count);
    for (int64_t c = 0; c < m->cell_count; c++) {
        if (form == 2)
            put_be32(f, m->cell_types[c]);
        else
            fprintf(f, "%d\n", m->cell_types[c]);
    }
    fclose(f);
}

static void write_vtu(const tpk_mesh *m, const char *path)
{
    FILE *f = fopen(path, "w");
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
               "<UnstructuredGrid><Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n<Points><DataArray "
               "type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n", (long long)m->point_count,
            (long long)m->cell_count);
    for (int64_t i = 0; i < 3 * m->point_count; i++)
        fprintf(f, "%.17g ", m->points[i]);
    fprintf(f, "</DataArray></Points>\n<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for (int64_t i = 0; i < m->cell_offsets[m->cell_count]; i++)
        fprintf(f, "%d ", m->cell_conn[i]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for (int64_t c = 1; c <= m->cell_count; c++)
        fprintf(f, "%lld ", (long long)m->cell_offsets[c]);
    fprintf(f, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (int64_t c = 0; c < m->cell_count; c++)
        fprintf(f, "%d ", m->cell_types[c]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Int64\" Name=\"faces\" format=\"ascii\">\n");
    for (int64_t i = 0; i < m->face_offsets[m->cell_count]; i++)
        fprintf(f, "%d ", m->faces[i]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Int64\" Name=\"faceoffsets\" format=\"ascii\">\n");
    for (int64_t c = 0; c < m->cell_count; c++) /* VTK: the end of the cell's faces, -1 for other cells */
        fprintf(f, "%lld ", m->cell_types[c] == TPK_CELL_POLYHEDRON ? (long long)m->face_offsets[c + 1] : -1LL);
    fprintf(f, "</DataArray></Cells>\n</Piece></UnstructuredGrid></VTKFile>\n");
    fclose(f);
}

static int same_cells(const tpk_mesh *a, const tpk_mesh *b)
{
    int64_t n = a->cell_count;
    return a->point_count == b->point_count && n == b->cell_count &&
           !memcmp(a->points, b->points, sizeof(double) * 3 * (size_t)a->point_count) &&
           !memcmp(a->cell_types, b->cell_types, (size_t)n) &&
           !memcmp(a->cell_offsets, b->cell_offsets, sizeof(int64_t) * (size_t)(n + 1)) &&
           !memcmp(a->cell_conn, b->cell_conn, sizeof(int32_t) * (size_t)a->cell_offsets[n]) && b->face_offsets &&
           !memcmp(a->face_offsets, b->face_offsets, sizeof(int64_t) * (size_t)(n + 1)) &&
           !memcmp(a->faces, b->faces, sizeof(int32_t) * (size_t)a->face_offsets[n]);
}

/* ---- converting and measuring ---------------------------------------------------------------------- */

typedef struct result {
    int rc;
    char message[1100];
    int64_t tets, vertices, open, polyhedra, steiner, face_points, bad, mirrored, inverted;
    double volume6; /* sum of the tets' 6 x volumes */
} result;

static double tet_volume6(const double *p, const int32_t *t)
{
    const double *a = p + 3 * (int64_t)t[0], *b = p + 3 * (int64_t)t[1], *c = p + 3 * (int64_t)t[2];
    const double *d = p + 3 * (int64_t)t[3];
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++)
        u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = d[k] - a[k];
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Tetrahedralize, orient (every tet must come out positive already), connect; keep the tet mesh in
 * *keep when given. */
static void convert(const tpk_mesh *m, int flags, result *r, tpk_tetmesh *keep)
{
    tpk_tetmesh out;
    tpk_diag d;
    memset(r, 0, sizeof *r);
    memset(&d, 0, sizeof d);
    tpk_orient_stats os;
    int32_t *nb = NULL;
    r->rc = tpk_tetrahedralize(m, NULL, 0, flags, &out, &d);
    if (r->rc == 0)
        r->rc = tpk_orient(&out, 0, 1, &os, &d);
    if (r->rc == 0) {
        nb = malloc(sizeof *nb * 4 * (size_t)out.tet_count);
        r->rc = tpk_connect(out.tets, out.tet_count, out.vertex_count, nb, 1, &d);
    }
    snprintf(r->message, sizeof r->message, "%s", d.message);
    if (r->rc == 0) {
        r->tets = out.tet_count, r->vertices = out.vertex_count, r->polyhedra = out.polyhedra;
        r->steiner = out.steiner_cells, r->face_points = out.face_steiner_points, r->bad = out.bad_cells_skipped;
        r->mirrored = out.mirrored_cells, r->inverted = os.inverted_fixed;
        for (int64_t i = 0; i < 4 * out.tet_count; i++)
            r->open += nb[i] < 0;
        for (int64_t t = 0; t < out.tet_count; t++)
            r->volume6 += tet_volume6(out.points, out.tets + 4 * t);
    }
    free(nb);
    if (keep && r->rc == 0)
        *keep = out;
    else if (r->rc == 0)
        tpk_tetmesh_free(&out);
}

/* 6 x the volume of every cell from its faces (divergence theorem), faces fanned from their first point. */
static double cells_volume6(const tpk_mesh *m)
{
    tpk_polygons p;
    memset(&p, 0, sizeof p);
    double sum = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        if (m->cell_types[c] == TPK_CELL_POLYHEDRON)
            tpk_polygons_from_stream(&p, m->faces + m->face_offsets[c], m->face_offsets[c + 1] - m->face_offsets[c]);
        else
            tpk_polygons_from_cell(&p, m->cell_types[c], m->cell_conn + m->cell_offsets[c]);
        sum += fabs(tpk_polygons_volume6(&p, m->points));
    }
    tpk_polygons_free(&p);
    return sum;
}

static int relative_close(double a, double b)
{
    return fabs(a - b) <= 1e-12 * fabs(b);
}

static int every_cell(int64_t c)
{
    (void)c;
    return 1;
}

/* Every other cell; every third of those with its faces turned inward. */
static int checkerboard(int64_t c)
{
    return c % 2 == 0 ? 0 : c % 3 == 0 ? 2 : 1;
}

/* ---- tests ----------------------------------------------------------------------------------------- */

static void import_mesh(const char *path, tpk_mesh *m, char *message, size_t cap, int *rc)
{
    tpk_diag d;
    memset(&d, 0, sizeof d);
    *rc = tpk_import_any(path, NULL, m, &d);
    snprintf(message, cap, "%s", d.message);
}

/* sfepy's 1000 hexahedra, all as polyhedra, in four file forms: read back exactly; converted, the same
 * volume as the hexahedra (and as the cells' own), the same boundary (no inner faces), no point added:
 * each polyhedron becomes a cone from its smallest vertex. */
TPK_TEST(hexahedra_as_polyhedra_in_every_form)
{
    tpk_mesh hexes, polys;
    char message[1100];
    int rc;
    import_mesh(tpk_data_path("sfepy/cube_medium_hexa.mesh"), &hexes, message, sizeof message, &rc);
    CHECK_MSG(rc == 0, "%s", message);
    result h;
    convert(&hexes, 0, &h, NULL);
    CHECK_MSG(h.rc == 0, "%s", h.message);
    import_mesh(tpk_data_path("sfepy/cube_medium_hexa.mesh"), &polys, message, sizeof message, &rc);
    hexes_to_polyhedra(&polys, every_cell);
    const char *names[4] = {"old.vtk", "v51.vtk", "binary.vtk", "poly.vtu"};
    for (int form = 0; form < 4; form++) {
        const char *path = tpk_temp_path(names[form]);
        if (form < 3)
            write_legacy(&polys, path, form);
        else
            write_vtu(&polys, path);
        tpk_mesh back;
        import_mesh(path, &back, message, sizeof message, &rc);
        CHECK_MSG(rc == 0, "%s: %s", names[form], message);
        int same = same_cells(&polys, &back);
        result p;
        convert(&back, 0, &p, NULL);
        tpk_mesh_free(&back);
        CHECK_MSG(same, "%s: read back differently", names[form]);
        CHECK_MSG(p.rc == 0, "%s: %s", names[form], p.message);
        CHECK_MSG(relative_close(p.volume6, h.volume6) && relative_close(p.volume6, cells_volume6(&polys)),
                  "%s: volume %.17g, hexahedra %.17g", names[form], p.volume6 / 6, h.volume6 / 6);
        CHECK_MSG(p.open == h.open && p.polyhedra == 1000 && p.steiner == 0 && p.face_points == 0 &&
                      p.tets == 6000 && p.vertices == h.vertices && p.inverted == 0,
                  "%s: %lld open faces (hexahedra %lld), %lld polyhedra, %lld tets", names[form], (long long)p.open,
                  (long long)h.open, (long long)p.polyhedra, (long long)p.tets);
    }
    tpk_mesh_free(&hexes);
    tpk_mesh_free(&polys);
}

/* Half the cells polyhedra (a third of those with inward faces), sharing faces with hexahedra: the
 * same boundary and volume as all hexahedra; inward polyhedra are turned over and counted. */
TPK_TEST(mixed_hexahedra_and_polyhedra_conform)
{
    tpk_mesh m;
    char message[1100];
    int rc;
    import_mesh(tpk_data_path("sfepy/cube_medium_hexa.mesh"), &m, message, sizeof message, &rc);
    CHECK_MSG(rc == 0, "%s", message);
    result h, p;
    convert(&m, 0, &h, NULL);
    hexes_to_polyhedra(&m, checkerboard);
    convert(&m, 0, &p, NULL);
    double cells = cells_volume6(&m);
    tpk_mesh_free(&m);
    CHECK_MSG(h.rc == 0 && p.rc == 0, "%s %s", h.message, p.message);
    CHECK_EQ_INT(p.polyhedra, 500);
    CHECK_EQ_INT(p.mirrored, 167); /* odd c that 3 divides: 3, 9, ..., 999 */
    CHECK_EQ_INT(p.open, h.open);
    CHECK(p.steiner == 0 && p.inverted == 0);
    CHECK_MSG(relative_close(p.volume6, h.volume6) && relative_close(p.volume6, cells), "%.17g vs %.17g",
              p.volume6, h.volume6);
}

/* A prism over the polygon xy[0 .. n) (counter-clockwise), z from 0 to 1, as one polyhedron (points:
 * bottom 0 .. n-1, top n .. 2n-1), with a unit hexahedron glued to the side face over xy[glue],
 * xy[glue+1] when glue >= 0 (that side must be the x = 2 plane from y = 0 to 1). */
static void prism_mesh(const double (*xy)[2], int n, int glue, tpk_mesh *m)
{
    memset(m, 0, sizeof *m);
    int extra = glue >= 0 ? 4 : 0;
    m->point_count = 2 * n + extra;
    m->points = calloc(3 * (size_t)m->point_count, sizeof(double));
    for (int i = 0; i < 2 * n; i++) {
        m->points[3 * i] = xy[i % n][0], m->points[3 * i + 1] = xy[i % n][1];
        m->points[3 * i + 2] = i >= n;
    }
    const double far[4][3] = {{3, 0, 0}, {3, 1, 0}, {3, 0, 1}, {3, 1, 1}};
    memcpy(m->points + 6 * n, far, sizeof(double) * 3 * (size_t)extra);
    m->cell_count = glue >= 0 ? 2 : 1;
    m->cell_types = malloc(2);
    m->cell_offsets = malloc(3 * sizeof(int64_t));
    m->cell_conn = malloc(sizeof(int32_t) * (size_t)(2 * n + 8));
    m->face_offsets = malloc(3 * sizeof(int64_t));
    m->faces = malloc(sizeof(int32_t) * (size_t)(1 + 2 * (n + 1) + 5 * n));
    m->cell_types[0] = TPK_CELL_POLYHEDRON;
    int32_t *f = m->faces;
    *f++ = n + 2;
    *f++ = n;
    for (int i = n - 1; i >= 0; i--) /* bottom, outward: clockwise seen from above */
        *f++ = i;
    *f++ = n;
    for (int i = 0; i < n; i++)
        *f++ = n + i;
    for (int i = 0; i < n; i++) {
        int32_t side[5] = {4, i, (i + 1) % n, n + (i + 1) % n, n + i};
        memcpy(f, side, sizeof side);
        f += 5;
    }
    for (int i = 0; i < 2 * n; i++)
        m->cell_conn[i] = i;
    m->cell_offsets[0] = m->face_offsets[0] = 0;
    m->cell_offsets[1] = 2 * n;
    m->face_offsets[1] = f - m->faces;
    if (glue >= 0) {
        int32_t a = glue, b = (glue + 1) % n, p = 2 * n;
        int32_t hex[8] = {a, p, p + 1, b, n + a, p + 2, p + 3, n + b};
        memcpy(m->cell_conn + 2 * n, hex, sizeof hex);
        m->cell_types[1] = TPK_CELL_HEXAHEDRON;
        m->cell_offsets[2] = 2 * n + 8;
        m->face_offsets[2] = m->face_offsets[1];
    }
    m->step_count = 1;
}

/* An L-shaped prism whose points' mean lies in its kernel (the corner square: the extra points on two
 * edges pull the mean there) converts from that centre; its octagonal top and bottom, non-convex, are
 * fanned from their smallest id (0 and 8, in a corner, where the first triangle is flat), so each gets
 * a face point. A hexahedron glued to it shares its face conformingly. */
TPK_TEST(non_convex_polyhedron_seen_from_its_centre)
{
    const double l8[8][2] = {{0, 0}, {0.5, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}, {0, 0.5}};
    tpk_mesh m;
    prism_mesh(l8, 8, 2, &m);
    result r;
    convert(&m, 0, &r, NULL);
    tpk_mesh_free(&m);
    CHECK_MSG(r.rc == 0, "%s", r.message);
    CHECK(r.polyhedra == 1 && r.steiner == 1 && r.face_points == 2 && r.inverted == 0);
    CHECK_EQ_INT(r.vertices, 16 + 4 + 3);
    /* Open faces: 7 free sides x 2, top and bottom 8 each (split at their centre), the hexahedron's 5 x 2. */
    CHECK_EQ_INT(r.open, 14 + 16 + 10);
    CHECK_MSG(r.volume6 == 6 * (3 + 1), "6V = %.17g", r.volume6);
}

/* An L with long arms: its points' mean (5/3, 5/3) is outside the kernel (the unit corner square), so
 * it does not see the inner sides, nor does its smallest point (1, 4, 0), the tip of an arm, for a cone.
 * With TetGen it is tetrahedralized inside its fixed boundary once faces whose fans cross take a point
 * (the hexagons' at the midpoint of a diagonal through the reflex corner: their mean lies on an inner
 * side), keeping its volume; without TetGen it is refused by name. Either way, with
 * TPK_TETRA_SKIP_BAD_CELLS only a refused cell is left out. (Numbered from the corner (0, 0, 0), in
 * the kernel, it would be a valid cone.) */
TPK_TEST(non_convex_polyhedron_refused_by_name)
{
    const double l6[6][2] = {{1, 4}, {0, 4}, {0, 0}, {2, 0}, {2, 1}, {1, 1}};
    tpk_mesh m;
    prism_mesh(l6, 6, 3, &m);
    result r;
    convert(&m, 0, &r, NULL);
#ifdef TPK_WITH_TETGEN
    tpk_mesh_free(&m);
    CHECK_MSG(r.rc == 0, "%s", r.message);
    /* The L (5) and the hexahedron (1), no cell left out, whichever faces took a point to uncross. */
    CHECK_MSG(fabs(r.volume6 - 6 * (5 + 1)) < 1e-12, "6V = %.17g", r.volume6);
    CHECK(r.polyhedra == 1 && r.face_points >= 1 && r.bad == 0 && r.inverted == 0);
#else
    CHECK(r.rc != 0);
    CHECK_MSG(strstr(r.message, "cell 0 (a polyhedron) is too warped, non-convex or degenerate to split: a point "
                                "at its centre does not see face") && strstr(r.message, "no TetGen") &&
              strstr(r.message, "--skip-bad-cells"), "%s", r.message);
    convert(&m, TPK_TETRA_SKIP_BAD_CELLS, &r, NULL);
    tpk_mesh_free(&m);
    CHECK_MSG(r.rc == 0, "%s", r.message);
    CHECK(r.bad == 1 && r.polyhedra == 0 && (r.tets == 5 || r.tets == 6) && r.volume6 == 6);
#endif
    const double corner_first[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 4}, {0, 4}};
    prism_mesh(corner_first, 6, 1, &m);
    convert(&m, 0, &r, NULL);
    tpk_mesh_free(&m);
    CHECK_MSG(r.rc == 0, "%s", r.message);
    CHECK(r.polyhedra == 1 && r.steiner == 0 && r.vertices == 16 && r.volume6 == 6 * (5 + 1));
}

/* 6 x the volume enclosed, each cell's faces fanned from their smallest id (as the split cuts them:
 * faces inside cancel, so only how the boundary is cut matters). */
static double fanned_volume6(const tpk_mesh *m)
{
    tpk_polygons p;
    memset(&p, 0, sizeof p);
    double sum = 0;
    for (int64_t c = 0; c < m->cell_count; c++) {
        tpk_polygons_from_cell(&p, m->cell_types[c], m->cell_conn + m->cell_offsets[c]);
        for (int64_t f = 0; f < p.face_count; f++) {
            int32_t *v = p.ids + p.starts[f], rotated[8];
            int64_t n = p.starts[f + 1] - p.starts[f], m0 = 0;
            for (int64_t i = 1; i < n; i++)
                m0 = v[i] < v[m0] ? i : m0;
            for (int64_t i = 0; i < n; i++)
                rotated[i] = v[(m0 + i) % n];
            memcpy(v, rotated, sizeof *v * (size_t)n);
        }
        sum += tpk_polygons_volume6(&p, m->points);
    }
    tpk_polygons_free(&p);
    return sum;
}

/* Two unit hexahedra A | B sharing the face x = 1; its corner (1,1,1) moved by (3/8, -3/4, 0): out of
 * that face's plane, into B. B's plain split folds, and so does a star from its centre with the face cut
 * along its smallest-id diagonal; a point at the face's centre makes B's star valid. A's plain split was
 * valid, but A shares the face: it is starred from its centre with the same face point, so the mesh
 * stays conforming (20 open faces: the 10 outer squares, 2 triangles each). */
TPK_TEST(warped_hexahedron_gets_a_shared_face_point)
{
    static const int32_t label[12] = {3, 2, 1, 9, 8, 0, 5, 6, 10, 7, 4, 11}; /* grid node -> point id */
#define NODE(x, y, z) label[(z) * 6 + (y) * 3 + (x)]
    const int32_t a[8] = {NODE(0, 0, 0), NODE(1, 0, 0), NODE(1, 1, 0), NODE(0, 1, 0),
                          NODE(0, 0, 1), NODE(1, 0, 1), NODE(1, 1, 1), NODE(0, 1, 1)};
    const int32_t b[8] = {NODE(1, 0, 0), NODE(2, 0, 0), NODE(2, 1, 0), NODE(1, 1, 0),
                          NODE(1, 0, 1), NODE(2, 0, 1), NODE(2, 1, 1), NODE(1, 1, 1)};
    const int32_t shared[4] = {NODE(1, 0, 0), NODE(1, 1, 0), NODE(1, 1, 1), NODE(1, 0, 1)};
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = 12;
    m.points = malloc(sizeof(double) * 36);
    for (int z = 0; z < 2; z++)
        for (int y = 0; y < 2; y++)
            for (int x = 0; x < 3; x++) {
                double *p = m.points + 3 * NODE(x, y, z);
                p[0] = x, p[1] = y, p[2] = z;
            }
    double *moved = m.points + 3 * NODE(1, 1, 1);
    moved[0] += 0.375, moved[1] -= 0.75;
#undef NODE
    m.cell_count = 2;
    m.cell_types = malloc(2);
    m.cell_types[0] = m.cell_types[1] = TPK_CELL_HEXAHEDRON;
    m.cell_offsets = malloc(3 * sizeof(int64_t));
    m.cell_offsets[0] = 0, m.cell_offsets[1] = 8, m.cell_offsets[2] = 16;
    m.cell_conn = malloc(16 * sizeof(int32_t));
    memcpy(m.cell_conn, a, sizeof a);
    memcpy(m.cell_conn + 8, b, sizeof b);
    m.step_count = 1;
    float *linear = malloc(12 * sizeof(float));
    for (int i = 0; i < 12; i++)
        linear[i] = (float)(m.points[3 * i] + 2 * m.points[3 * i + 1] + 4 * m.points[3 * i + 2]);
    tpk_mesh_add_field(&m, "linear", TPK_ASSOC_POINT, 1, 1, linear);

    int32_t tets[48];
    int mirrored;
    double centre[3] = {0, 0, 0};
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            centre[k] += m.points[3 * b[i] + k] / 8;
    int plain_a = tpk_split_cell(12, a, m.points, tets, &mirrored), plain_b = tpk_split_cell(12, b, m.points, tets, &mirrored);
    int star_b = tpk_star_cell(12, b, m.points, centre, 12, tets, &mirrored);
    double expected = fanned_volume6(&m);
    tpk_tetmesh out;
    result r;
    convert(&m, 0, &r, &out);
    tpk_mesh_free(&m);
    CHECK_MSG(plain_a > 0 && plain_b < 0 && star_b < 0, "plain A %d, plain B %d, star B %d", plain_a, plain_b, star_b);
    CHECK_MSG(r.rc == 0, "%s", r.message);
    /* Added in cell order: A's centre (12), the face point (13), B's centre (14). */
    int ok = r.steiner == 2 && r.face_points == 1 && r.vertices == 15 && r.tets == 14 + 14 && r.open == 20 &&
             r.inverted == 0 && out.vertex_source[13] == -1;
    for (int k = 0; ok && k < 3; k++) {
        double mean = 0;
        for (int i = 0; i < 4; i++)
            mean += out.points[3 * shared[i] + k];
        ok = out.points[3 * 13 + k] == mean / 4;
    }
    for (int v = 12; ok && v < 15; v++) { /* a linear field: its value at an added point is exact */
        const double *p = out.points + 3 * v;
        ok = fabs(out.fields[0].values[v] - (p[0] + 2 * p[1] + 4 * p[2])) < 1e-5;
    }
    tpk_tetmesh_free(&out);
    CHECK(ok);
    CHECK_MSG(relative_close(r.volume6, expected), "6V %.17g, expected %.17g", r.volume6, expected);
}

static void expect_import_failure(const char *name, const char *text, const char *want1, const char *want2, int line)
{
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    int rc = strstr(name, ".vtu") ? tpk_import_vtu_memory(name, text, strlen(text), &m, &d)
                                  : tpk_import_vtk_legacy_memory(name, text, strlen(text), &m, &d);
    if (rc == 0)
        tpk_mesh_free(&m);
    if (rc == 0 || !strstr(d.message, want1) || !strstr(d.message, want2)) {
        fprintf(stderr, "%s:%d: %s: expected an error with '%s' and '%s', got '%s'\n", __FILE__, line, name, want1,
                want2, rc ? d.message : "success");
        tpk_test_failures++;
    }
}

#define TET_POINTS "POINTS 4 float\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
#define VTU_HEAD                                                                                                 \
    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\"><UnstructuredGrid><Piece NumberOfPoints=\"4\" "          \
    "NumberOfCells=\"1\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 " \
    "0 1 0 0 0 1</DataArray></Points><Cells>"
#define VTU_CELLS(conn, faces)                                                                                    \
    "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">" conn "</DataArray><DataArray "          \
    "type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray><DataArray type=\"UInt8\" Name=\"types\" "    \
    "format=\"ascii\">42</DataArray><DataArray type=\"Int64\" Name=\"faces\" format=\"ascii\">" faces            \
    "</DataArray><DataArray type=\"Int64\" Name=\"faceoffsets\" format=\"ascii\">17</DataArray></Cells></Piece>" \
    "</UnstructuredGrid></VTKFile>"

/* Broken face streams are refused with the cell, the entry and its place in the file; a stream that
 * parses but does not close is refused by the tetrahedralizer, naming the cell and the open edge. */
TPK_TEST(broken_face_streams_refused_with_their_place)
{
    const char *head = "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n" TET_POINTS;
    char text[1024];
    snprintf(text, sizeof text, "%sCELLS 2 11\n4 0 1 2 3\n5 4 3 0 1 2\nCELL_TYPES 2\n10\n42\n", head);
    expect_import_failure("old.vtk", text, "CELLS: cell 1 (polyhedron): a face count of 4 needs at least 17 entries",
                          "face stream entry 0, CELLS value 6", __LINE__);
    snprintf(text, sizeof text, "%sCELLS 3 21\nOFFSETS vtktypeint64\n0 4 21\nCONNECTIVITY vtktypeint64\n0 1 2 3\n"
             "4 3 0 1 2 3 0 1 3 3 1 2 3 9 0 2 3\nCELL_TYPES 2\n10\n42\n", head);
    expect_import_failure("v51.vtk", text, "cell 1 (polyhedron): face 3 of 4: expected a point count from 3 to 3",
                          "found 9 (face stream entry 13, CONNECTIVITY value 17)", __LINE__);
    expect_import_failure("bad.vtu", VTU_HEAD VTU_CELLS("0 1 2 3", "4 3 0 2 1 3 0 1 3 3 1 2 3 3 0 3 7"),
                          "DataArray 'faces'", "face 3: point id 7 is out of range (expected 0 to 3) (face stream entry 16, value 16 of the array)", __LINE__);
    expect_import_failure("lists.vtu", VTU_HEAD VTU_CELLS("0 1 2 2", "4 3 0 2 1 3 0 1 3 3 1 2 3 3 0 3 2"),
                          "DataArray 'connectivity'", "cell 0 (polyhedron): its faces use point 3, which its "
                          "connectivity does not list", __LINE__);
    /* A tetrahedron with one face given twice and one left out: parses, but edge 2-3 is open. */
    tpk_mesh m;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    const char *open_tet = VTU_HEAD VTU_CELLS("0 1 2 3", "4 3 0 2 1 3 0 1 3 3 0 1 3 3 0 3 2");
    CHECK_MSG(tpk_import_vtu_memory("open.vtu", open_tet, strlen(open_tet), &m, &d) == 0, "%s", d.message);
    result r;
    convert(&m, 0, &r, NULL);
    tpk_mesh_free(&m);
    CHECK(r.rc != 0);
    CHECK_MSG(strstr(r.message, "cell 0 (a polyhedron) is too warped, non-convex or degenerate to split: edge "),
              "%s", r.message);
}

/* sfepy's hexahedra with every inner point moved (up to 0.4 of a cell along each axis, seeded): as
 * hexahedra and as polyhedra they give the same tets, points added at cell and face centres (78 and
 * 54 here), and boundary, and keep the cube's volume (its boundary does not move). */
TPK_TEST(warped_polyhedra_convert_like_warped_hexahedra)
{
    tpk_mesh m;
    char message[1100];
    int rc;
    import_mesh(tpk_data_path("sfepy/cube_medium_hexa.mesh"), &m, message, sizeof message, &rc);
    CHECK_MSG(rc == 0, "%s", message);
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (int64_t v = 0; v < m.point_count; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], m.points[3 * v + a]);
            hi[a] = fmax(hi[a], m.points[3 * v + a]);
        }
    double before = cells_volume6(&m);
    uint64_t seed = 12345;
    for (int64_t v = 0; v < m.point_count; v++) {
        double *p = m.points + 3 * v;
        int inner = 1;
        for (int a = 0; a < 3; a++)
            inner &= p[a] > lo[a] && p[a] < hi[a];
        for (int a = 0; inner && a < 3; a++) { /* cells are (hi - lo) / 10 wide */
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            p[a] += 0.4 * (hi[a] - lo[a]) / 10 * (double)((int)((seed >> 33) % 129) - 64) / 64;
        }
    }
    result h, p;
    convert(&m, TPK_TETRA_SKIP_BAD_CELLS, &h, NULL);
    hexes_to_polyhedra(&m, every_cell);
    convert(&m, TPK_TETRA_SKIP_BAD_CELLS, &p, NULL);
    tpk_mesh_free(&m);
    CHECK_MSG(h.rc == 0 && p.rc == 0, "%s %s", h.message, p.message);
    fprintf(stderr, "warped: %lld tets, %lld cells from a centre point, %lld face points, %lld bad cells\n",
            (long long)p.tets, (long long)p.steiner, (long long)p.face_points, (long long)p.bad);
    CHECK(h.steiner > 0 && h.face_points > 0 && h.bad == 0 && p.inverted == 0);
    CHECK(p.tets == h.tets && p.vertices == h.vertices && p.steiner == h.steiner && p.face_points == h.face_points &&
          p.open == h.open && p.bad == h.bad && p.polyhedra == 1000 - p.bad);
    CHECK_MSG(relative_close(p.volume6, h.volume6), "%.17g vs %.17g", p.volume6, h.volume6);
    CHECK_MSG(relative_close(h.volume6, before), "%.17g vs %.17g", h.volume6, before);
}

/* The cell (OpenFOAM, 6 points, 4 faces): a tet A B C D with a point on edge AB and one on AC,
 * both pushed out of their faces' planes, as a refined neighbour's snapped points are. A cone from A
 * would skip every face touching A and give the single tet ABCD, leaving both points out (and the
 * volume they bulge). Each fan diagonal along those edges gets a face point instead: all 6 points are
 * used, and the volume is that of the faces fanned from their mean (the converter's face points). */
TPK_TEST(edge_points_of_a_tet_kept_with_their_volume)
{
    const double p[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.5, -0.1, -0.1}, {-0.1, 0.5, -0.1}};
    const int32_t stream[] = {4, 4, 0, 3, 1, 4, 4, 0, 5, 2, 3, 5, 0, 4, 1, 2, 5, 3, 1, 3, 2};
    tpk_mesh m;
    memset(&m, 0, sizeof m);
    m.point_count = 6, m.cell_count = 1;
    m.points = malloc(sizeof p), m.cell_types = malloc(1), m.cell_offsets = malloc(2 * sizeof(int64_t));
    m.cell_conn = malloc(6 * sizeof(int32_t)), m.face_offsets = malloc(2 * sizeof(int64_t));
    m.faces = malloc(sizeof stream);
    memcpy(m.points, p, sizeof p), memcpy(m.faces, stream, sizeof stream);
    m.cell_types[0] = TPK_CELL_POLYHEDRON;
    m.cell_offsets[0] = m.face_offsets[0] = 0, m.cell_offsets[1] = 6, m.face_offsets[1] = sizeof stream / sizeof *stream;
    for (int i = 0; i < 6; i++)
        m.cell_conn[i] = i;
    m.step_count = 1;
    /* 6V of the faces fanned from their mean (BCD, a triangle, as it is), relative to A (the origin). */
    double want6 = 0;
    const int32_t *f = stream + 1;
    for (int face = 0; face < 4; face++, f += 1 + f[0]) {
        int n = f[0];
        double q[3] = {0, 0, 0};
        for (int i = 0; i < n; i++)
            for (int k = 0; k < 3; k++)
                q[k] += p[f[1 + i]][k] / n;
        for (int i = 0; n > 3 && i < n; i++) {
            const double *a = p[f[1 + i]], *b = p[f[1 + (i + 1) % n]];
            want6 += a[0] * (b[1] * q[2] - b[2] * q[1]) - a[1] * (b[0] * q[2] - b[2] * q[0]) + a[2] * (b[0] * q[1] - b[1] * q[0]);
        }
        if (n == 3) {
            const double *a = p[f[1]], *b = p[f[2]], *c = p[f[3]];
            want6 += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
    }
    tpk_tetmesh out;
    result r;
    convert(&m, 0, &r, &out);
    tpk_mesh_free(&m);
    CHECK_MSG(r.rc == 0, "%s", r.message);
    int used[6] = {0};
    for (int64_t i = 0; i < 4 * out.tet_count; i++)
        if (out.tets[i] < 6)
            used[out.tets[i]] = 1;
    tpk_tetmesh_free(&out);
    for (int i = 0; i < 6; i++)
        CHECK_MSG(used[i], "point %d is left out", i);
    CHECK(r.face_points == 3 && r.steiner == 1 && r.inverted == 0);
    CHECK_MSG(fabs(fabs(want6) - r.volume6) < 1e-12 && r.volume6 > 1.0 + 1e-3, "6V = %.17g, faces enclose %.17g",
              r.volume6, want6);
}
