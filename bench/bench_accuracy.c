/* Accuracy of conversion (bench/report part 3).
 * Splitting: inside a hexahedron the scalar is trilinear in its parametric coordinates, inside a wedge
 * linear in the triangle times linear along the axis, inside a pyramid VTK's collapsed-hexahedron basis;
 * inside the tets it is linear. For analytic fields sampled at the corners of every cell of a mesh, this
 * measures max and RMS |tet - cell interpolant| and |tet - true field| at random parametric points (as a
 * fraction of the field's range over the mesh), and |cell interpolant - true field| for comparison, for
 * the converter's split (diagonals through the smallest file id) and for the same rule on random ids,
 * which picks other diagonals (and 5-tet hexahedra) more often. Cells the plain split refuses (warped:
 * the converter adds a centre point) are counted, not measured.
 * Positions: the float32-relative-to-origin storage (spec §6.8, tpk_points_origin) against the float64
 * points of each file given with --positions, and float32 without the origin for comparison.
 * Usage: bench_accuracy [--split FILE...] [--positions FILE...]
 *   (no arguments: sfepy's cube_medium_hexa.mesh, and the jittered grids made here) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/cell_split.h"
#include "import/importers.h"
#include "mesh/cell_types.h"
#include "mesh/mesh.h"

#define SAMPLES_PER_CELL 64

typedef double (*field_fn)(const double *p, double scale);

static double f_bilinear(const double *p, double s) { return (p[0] / s) * (p[1] / s); }
static double f_quadratic(const double *p, double s) { return (p[0] * p[0] + 0.5 * p[1] * p[2]) / (s * s); }
static double f_wave(const double *p, double s) { return sin(3.0 * p[0] / s) * cos(2.0 * p[1] / s) + p[2] / s; }

static const struct {
    const char *name;
    field_fn f;
} fields[] = {{"x*y", f_bilinear}, {"x^2+yz/2", f_quadratic}, {"sin3x*cos2y+z", f_wave}};

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double uniform(void)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

/* Shape functions at a random parametric point of a VTK cell (12 hexahedron, 13 wedge, 14 pyramid). */
static void random_shape(int type, double n[8])
{
    double u = uniform(), v = uniform(), w = uniform();
    if (type == 12) {
        n[0] = (1 - u) * (1 - v) * (1 - w), n[1] = u * (1 - v) * (1 - w), n[2] = u * v * (1 - w);
        n[3] = (1 - u) * v * (1 - w), n[4] = (1 - u) * (1 - v) * w, n[5] = u * (1 - v) * w;
        n[6] = u * v * w, n[7] = (1 - u) * v * w;
    } else if (type == 13) {
        if (u + v > 1) /* uniform in the triangle */
            u = 1 - u, v = 1 - v;
        double l[3] = {1 - u - v, u, v};
        for (int i = 0; i < 3; i++)
            n[i] = l[i] * (1 - w), n[i + 3] = l[i] * w;
    } else { /* VTK's pyramid: the hexahedron with its top face collapsed onto the apex */
        n[0] = (1 - u) * (1 - v) * (1 - w), n[1] = u * (1 - v) * (1 - w), n[2] = u * v * (1 - w);
        n[3] = (1 - u) * v * (1 - w), n[4] = w;
    }
}

static int node_count(int type)
{
    return type == 12 ? 8 : type == 13 ? 6 : 5;
}

/* Barycentric coordinates of p in tet (a, b, c, d); returns 0 if p is inside (with tolerance). */
static int barycentric(const double *a, const double *b, const double *c, const double *d, const double *p,
                       double l[4])
{
    double m[3][3], r[3];
    for (int k = 0; k < 3; k++) {
        m[k][0] = b[k] - a[k], m[k][1] = c[k] - a[k], m[k][2] = d[k] - a[k];
        r[k] = p[k] - a[k];
    }
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (det == 0)
        return -1;
    double x[3];
    for (int col = 0; col < 3; col++) { /* Cramer */
        double q[3][3];
        memcpy(q, m, sizeof q);
        for (int k = 0; k < 3; k++)
            q[k][col] = r[k];
        x[col] = (q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
                  q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0])) / det;
    }
    l[1] = x[0], l[2] = x[1], l[3] = x[2], l[0] = 1 - x[0] - x[1] - x[2];
    const double eps = 1e-9;
    return l[0] >= -eps && l[1] >= -eps && l[2] >= -eps && l[3] >= -eps ? 0 : -1;
}

typedef struct err_stat {
    double max, sum2;
} err_stat;

static void add_err(err_stat *e, double v)
{
    e->max = v > e->max ? v : e->max;
    e->sum2 += v * v;
}

typedef struct stats {
    err_stat vs_cell, vs_true, cell_vs_true;
    long samples, missed, fives, cells, refused;
} stats;

typedef struct cell_mesh {
    const char *name;
    int type;
    long count;
    double (*corners)[8][3];
    int32_t (*ids)[8];
    double scale;
} cell_mesh;

/* The tet of the split holding p, and the linear interpolant there; 0 if found. */
static int tet_value(const int32_t *tets, int n, const double pts[8][3], const int local[8], int nodes,
                     const double values[8], const double p[3], double *out)
{
    for (int t = 0; t < n; t++) {
        const int32_t *q = tets + 4 * t;
        double l[4];
        if (barycentric(pts[q[0]], pts[q[1]], pts[q[2]], pts[q[3]], p, l) != 0)
            continue;
        double lin = 0;
        for (int k = 0; k < 4; k++) /* tet corner q[k] has rank q[k]: find its corner */
            for (int i = 0; i < nodes; i++)
                if (local[i] == q[k])
                    lin += l[k] * values[i];
        *out = lin;
        return 0;
    }
    return -1;
}

/* One cell: split with the given ids (ranks of the given ids become local ids), sample. */
static void measure_cell(int type, const double corners[8][3], const int32_t ids[8], field_fn f, double scale,
                         double range, stats *st)
{
    int nodes = node_count(type), local[8];
    double pts[8][3];
    for (int i = 0; i < nodes; i++) {
        local[i] = 0;
        for (int j = 0; j < nodes; j++)
            local[i] += ids[j] < ids[i];
        memcpy(pts[local[i]], corners[i], sizeof pts[0]);
    }
    int32_t tets[6 * 4];
    int mirrored;
    int n = tpk_split_cell(type, local, &pts[0][0], tets, &mirrored);
    if (n < 0) {
        st->refused++;
        return;
    }
    st->cells++;
    st->fives += type == 12 && n == 5;
    double values[8];
    for (int i = 0; i < nodes; i++)
        values[i] = f(corners[i], scale);
    for (int s = 0; s < SAMPLES_PER_CELL; s++) {
        double N[8], p[3] = {0, 0, 0}, interp = 0, lin;
        random_shape(type, N);
        for (int i = 0; i < nodes; i++) {
            interp += N[i] * values[i];
            for (int k = 0; k < 3; k++)
                p[k] += N[i] * corners[i][k];
        }
        if (tet_value(tets, n, pts, local, nodes, values, p, &lin) != 0) {
            st->missed++; /* a point of a warped cell outside its tets: the two shapes differ */
            continue;
        }
        double truth = f(p, scale);
        add_err(&st->vs_cell, fabs(lin - interp) / range);
        add_err(&st->vs_true, fabs(lin - truth) / range);
        add_err(&st->cell_vs_true, fabs(interp - truth) / range);
        st->samples++;
    }
}

static void run(const cell_mesh *m)
{
    static const char *type_names[] = {[12] = "hexahedron", [13] = "wedge", [14] = "pyramid"};
    int nodes = node_count(m->type);
    for (size_t fi = 0; fi < sizeof fields / sizeof fields[0]; fi++) {
        double lo = INFINITY, hi = -INFINITY;
        for (long c = 0; c < m->count; c++)
            for (int i = 0; i < nodes; i++) {
                double v = fields[fi].f(m->corners[c][i], m->scale);
                lo = v < lo ? v : lo, hi = v > hi ? v : hi;
            }
        double range = hi > lo ? hi - lo : 1;
        for (int scheme = 0; scheme < 2; scheme++) {
            stats st;
            memset(&st, 0, sizeof st);
            for (long c = 0; c < m->count; c++) {
                int32_t ids[8];
                for (int i = 0; i < nodes; i++)
                    ids[i] = scheme == 0 ? m->ids[c][i] : (int32_t)(uniform() * 1e9);
                measure_cell(m->type, m->corners[c], ids, fields[fi].f, m->scale, range, &st);
            }
            double ns = st.samples ? (double)st.samples : 1;
            printf("{\"bench\":\"split_accuracy\",\"mesh\":\"%s\",\"cell\":\"%s\",\"cells\":%ld,\"refused\":%ld,"
                   "\"field\":\"%s\",\"diagonals\":\"%s\",\"hexes_in_5\":%ld,\"max_vs_cell\":%.3e,"
                   "\"rms_vs_cell\":%.3e,\"max_vs_true\":%.3e,\"rms_vs_true\":%.3e,\"cell_max_vs_true\":%.3e,"
                   "\"cell_rms_vs_true\":%.3e,\"samples\":%ld,\"outside_tets\":%ld}\n",
                   m->name, type_names[m->type], st.cells, st.refused, fields[fi].name,
                   scheme == 0 ? "smallest file id" : "smallest random id", st.fives, st.vs_cell.max,
                   sqrt(st.vs_cell.sum2 / ns), st.vs_true.max, sqrt(st.vs_true.sum2 / ns), st.cell_vs_true.max,
                   sqrt(st.cell_vs_true.sum2 / ns), st.samples, st.missed);
        }
    }
}

static int cell_mesh_alloc(cell_mesh *m, long count)
{
    m->count = count;
    m->corners = malloc(sizeof *m->corners * (size_t)(count ? count : 1));
    m->ids = malloc(sizeof *m->ids * (size_t)(count ? count : 1));
    return m->corners && m->ids ? 0 : -1;
}

/* An n^3 grid of unit cubes with interior points jittered by up to `jitter` of a cell; each cube one
 * hexahedron, two wedges (cut along a diagonal plane) or six pyramids around its centre point. */
static int jittered_grid(cell_mesh *m, int type, int n, double jitter, char *name, size_t cap)
{
    static const char *kind[] = {[12] = "hexahedra", [13] = "wedges", [14] = "pyramids"};
    snprintf(name, cap, "grid %d^3 %s jitter %.2f", n, kind[type], jitter);
    m->name = name;
    m->type = type;
    m->scale = n;
    long per = type == 12 ? 1 : type == 13 ? 2 : 6, cubes = (long)n * n * n, grid = (long)(n + 1) * (n + 1) * (n + 1);
    if (cell_mesh_alloc(m, cubes * per) != 0)
        return -1;
    double (*p)[3] = malloc(sizeof *p * (size_t)grid);
    if (!p)
        return -1;
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                double *q = p[(k * (n + 1) + j) * (n + 1) + i];
                int inner = i > 0 && i < n && j > 0 && j < n && k > 0 && k < n;
                q[0] = i + (inner ? jitter * (2 * uniform() - 1) : 0);
                q[1] = j + (inner ? jitter * (2 * uniform() - 1) : 0);
                q[2] = k + (inner ? jitter * (2 * uniform() - 1) : 0);
            }
    static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    /* wedges: triangles (0,1,2) and (0,2,3) of the bottom face, extruded; pyramids: a face and the centre */
    static const int wedge[2][6] = {{0, 1, 2, 4, 5, 6}, {0, 2, 3, 4, 6, 7}};
    const int (*pyr)[4] = tpk_cell_shape_of(TPK_CELL_HEXAHEDRON)->faces; /* outward cube faces */
    long c = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                int id[8];
                double centre[3] = {0, 0, 0};
                for (int v = 0; v < 8; v++) {
                    id[v] = ((k + off[v][2]) * (n + 1) + (j + off[v][1])) * (n + 1) + (i + off[v][0]);
                    for (int a = 0; a < 3; a++)
                        centre[a] += p[id[v]][a] / 8;
                }
                for (int e = 0; e < per; e++, c++) {
                    int nodes = node_count(type);
                    for (int v = 0; v < nodes; v++) {
                        int corner = type == 12 ? v : type == 13 ? wedge[e][v] : v < 4 ? pyr[e][v] : -1;
                        if (corner < 0) { /* pyramid apex: the cube's centre, an id past the grid's */
                            memcpy(m->corners[c][v], centre, sizeof centre);
                            m->ids[c][v] = (int32_t)(grid + (long)((k * n + j) * n + i));
                        } else {
                            memcpy(m->corners[c][v], p[id[corner]], sizeof p[0]);
                            m->ids[c][v] = id[corner];
                        }
                    }
                }
            }
    free(p);
    return 0;
}

/* The cells of one type in a file; 0 when there is at least one. */
static int load_cells(const tpk_mesh *src, const char *path, int type, cell_mesh *m)
{
    m->name = path;
    m->type = type;
    if (cell_mesh_alloc(m, 0) != 0 || cell_mesh_alloc(m, src->cell_count) != 0)
        return -1;
    m->count = 0;
    double lo = INFINITY, hi = -INFINITY;
    for (int64_t c = 0; c < src->cell_count; c++) {
        if (src->cell_types[c] != type)
            continue;
        for (int i = 0; i < node_count(type); i++) {
            int32_t id = src->cell_conn[src->cell_offsets[c] + i];
            memcpy(m->corners[m->count][i], src->points + 3 * id, sizeof m->corners[0][0]);
            m->ids[m->count][i] = id;
            for (int k = 0; k < 3; k++)
                lo = fmin(lo, src->points[3 * id + k]), hi = fmax(hi, src->points[3 * id + k]);
        }
        m->count++;
    }
    m->scale = hi > lo ? (hi - lo) / 4 : 1;
    return m->count ? 0 : -1;
}

static void split_file(const char *path)
{
    tpk_mesh src;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    if (tpk_import_any(path, NULL, &src, &d) != 0) {
        fprintf(stderr, "%s\n", d.message);
        return;
    }
    for (int type = 12; type <= 14; type++) {
        cell_mesh m;
        memset(&m, 0, sizeof m);
        if (load_cells(&src, path, type, &m) == 0)
            run(&m);
        free(m.corners), free(m.ids);
    }
    tpk_mesh_free(&src);
}

/* float32 relative to the file's origin against the float64 source, and float32 without an origin. */
static void positions_file(const char *path)
{
    tpk_mesh src;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    if (tpk_import_any(path, NULL, &src, &d) != 0) {
        fprintf(stderr, "%s\n", d.message);
        return;
    }
    double origin[3], lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    tpk_points_origin(src.points, src.point_count, origin);
    double max_rel = 0, max_abs = 0, max_plain = 0, sum2 = 0;
    for (int64_t i = 0; i < src.point_count; i++)
        for (int k = 0; k < 3; k++) {
            double p = src.points[3 * i + k];
            double e = fabs(origin[k] + (double)(float)(p - origin[k]) - p);
            max_abs = fmax(max_abs, e), sum2 += e * e;
            max_plain = fmax(max_plain, fabs((double)(float)p - p));
            lo[k] = fmin(lo[k], p), hi[k] = fmax(hi[k], p);
        }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double min_edge = INFINITY; /* shortest cell edge (consecutive corners): the scale an error must stay under */
    for (int64_t c = 0; c < src.cell_count; c++) {
        int64_t a = src.cell_offsets[c], b = src.cell_offsets[c + 1];
        for (int64_t i = a; i < b && b - a <= 8; i++) {
            const double *p = src.points + 3 * src.cell_conn[i], *q = src.points + 3 * src.cell_conn[i + 1 < b ? i + 1 : a];
            double e = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
            if (e > 0)
                min_edge = fmin(min_edge, e);
        }
    }
    for (int k = 0; k < 3; k++)
        max_rel = fmax(max_rel, max_abs / (diag > 0 ? diag : 1));
    printf("{\"bench\":\"position_accuracy\",\"mesh\":\"%s\",\"points\":%lld,\"origin\":[%.17g,%.17g,%.17g],"
           "\"diagonal\":%.6g,\"shortest_edge\":%.6g,\"max_abs_error\":%.3e,\"rms_abs_error\":%.3e,"
           "\"max_error_over_diagonal\":%.3e,\"max_error_over_shortest_edge\":%.3e,"
           "\"max_abs_error_float32_no_origin\":%.3e,\"no_origin_over_shortest_edge\":%.3e}\n",
           path, (long long)src.point_count, origin[0], origin[1], origin[2], diag, min_edge, max_abs,
           sqrt(sum2 / (3.0 * (double)(src.point_count ? src.point_count : 1))), max_rel, max_abs / min_edge,
           max_plain, max_plain / min_edge);
    tpk_mesh_free(&src);
}

int main(int argc, char **argv)
{
    int mode = 0; /* 1: --split files, 2: --positions files */
    int any_file = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--split") == 0)
            mode = 1;
        else if (strcmp(argv[i], "--positions") == 0)
            mode = 2;
        else if (mode == 2)
            positions_file(argv[i]), any_file = 1;
        else
            split_file(argv[i]), any_file = 1;
    }
    if (!any_file)
        split_file("../shared/data/sfepy/cube_medium_hexa.mesh");
    const double jitters[3] = {0.0, 0.15, 0.3};
    for (int type = 12; type <= 14; type++)
        for (int j = 0; j < 3; j++) {
            cell_mesh m;
            char name[64];
            memset(&m, 0, sizeof m);
            if (jittered_grid(&m, type, 10, jitters[j], name, sizeof name) == 0)
                run(&m);
            free(m.corners), free(m.ids);
        }
    return 0;
}
