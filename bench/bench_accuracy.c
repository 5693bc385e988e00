/* Accuracy of splitting hexahedra into tets: the scalar inside a hexahedron is trilinear in its
 * parametric coordinates, inside the tets it is linear. For analytic fields sampled at the corners of
 * every hexahedron of a mesh, this measures max and RMS |tet - trilinear| at random points (as a fraction
 * of the field's range over the mesh), for the converter's split (diagonals through the smallest file id)
 * and for the same rule on random ids, which picks other diagonals and 5-tet splits more often.
 * Usage: bench_accuracy [mesh.mesh|mesh.vtk ...]   (default: sfepy's cube_medium_hexa.mesh and warped
 * grids made here) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/cell_split.h"
#include "import/importers.h"

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

/* Trilinear map of a VTK-ordered hexahedron: shape functions at parametric (u, v, w). */
static void shape(double u, double v, double w, double n[8])
{
    n[0] = (1 - u) * (1 - v) * (1 - w), n[1] = u * (1 - v) * (1 - w), n[2] = u * v * (1 - w);
    n[3] = (1 - u) * v * (1 - w), n[4] = (1 - u) * (1 - v) * w, n[5] = u * (1 - v) * w;
    n[6] = u * v * w, n[7] = (1 - u) * v * w;
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

typedef struct stats {
    double max, sum2;
    long samples, missed, fives, cells;
} stats;

/* One hexahedron: split with the given ids (a permutation of the corners' ranks), sample. */
static void measure_cell(const double corners[8][3], const int32_t ids[8], field_fn f, double scale, double range,
                         stats *st)
{
    double pts[8][3];
    int32_t local[8];
    for (int i = 0; i < 8; i++) { /* local ids 0..7 carry the ranks of the given ids */
        local[i] = 0;
        for (int j = 0; j < 8; j++)
            local[i] += ids[j] < ids[i];
        memcpy(pts[local[i]], corners[i], sizeof pts[0]);
    }
    int32_t tets[6 * 4];
    int mirrored;
    int n = tpk_split_cell(12, local, &pts[0][0], tets, &mirrored);
    if (n < 0)
        return; /* warped beyond a plain split: those cells get a centre point, not measured here */
    st->cells++;
    st->fives += n == 5;
    double values[8];
    for (int i = 0; i < 8; i++)
        values[i] = f(corners[i], scale);
    for (int s = 0; s < SAMPLES_PER_CELL; s++) {
        double N[8], p[3] = {0, 0, 0}, tri = 0;
        shape(uniform(), uniform(), uniform(), N);
        for (int i = 0; i < 8; i++) {
            tri += N[i] * values[i];
            for (int k = 0; k < 3; k++)
                p[k] += N[i] * corners[i][k];
        }
        int found = 0;
        for (int t = 0; t < n && !found; t++) {
            const int32_t *q = tets + 4 * t;
            double l[4];
            if (barycentric(pts[q[0]], pts[q[1]], pts[q[2]], pts[q[3]], p, l) == 0) {
                double lin = 0;
                for (int k = 0; k < 4; k++) { /* tet corner q[k] has rank q[k]: find its corner */
                    for (int i = 0; i < 8; i++)
                        if (local[i] == q[k])
                            lin += l[k] * values[i];
                }
                double e = fabs(lin - tri) / range;
                st->max = e > st->max ? e : st->max;
                st->sum2 += e * e;
                st->samples++;
                found = 1;
            }
        }
        st->missed += !found; /* a point of a warped hexahedron outside its tets: the two shapes differ */
    }
}

typedef struct hex_mesh {
    const char *name;
    long count;
    double (*corners)[8][3];
    int32_t (*ids)[8];
    double scale;
} hex_mesh;

static void run(const hex_mesh *m)
{
    for (size_t fi = 0; fi < sizeof fields / sizeof fields[0]; fi++) {
        double lo = INFINITY, hi = -INFINITY;
        for (long c = 0; c < m->count; c++)
            for (int i = 0; i < 8; i++) {
                double v = fields[fi].f(m->corners[c][i], m->scale);
                lo = v < lo ? v : lo, hi = v > hi ? v : hi;
            }
        double range = hi > lo ? hi - lo : 1;
        for (int scheme = 0; scheme < 2; scheme++) {
            stats st = {0};
            for (long c = 0; c < m->count; c++) {
                int32_t ids[8];
                for (int i = 0; i < 8; i++)
                    ids[i] = scheme == 0 ? m->ids[c][i] : (int32_t)(uniform() * 1e9);
                measure_cell(m->corners[c], ids, fields[fi].f, m->scale, range, &st);
            }
            printf("{\"mesh\":\"%s\",\"cells\":%ld,\"field\":\"%s\",\"diagonals\":\"%s\",\"hexes_in_5\":%ld,"
                   "\"max_error\":%.3e,\"rms_error\":%.3e,\"samples\":%ld,\"outside_tets\":%ld}\n",
                   m->name, st.cells, fields[fi].name, scheme == 0 ? "smallest file id" : "smallest random id",
                   st.fives, st.max, st.samples ? sqrt(st.sum2 / st.samples) : 0.0, st.samples, st.missed);
        }
    }
}

/* An n^3 grid of unit cubes with interior points jittered by up to `jitter` of a cell. */
static void warped_grid(hex_mesh *m, int n, double jitter, char *name, size_t cap)
{
    snprintf(name, cap, "grid %d^3 jitter %.2f", n, jitter);
    m->name = name;
    m->count = (long)n * n * n;
    m->scale = n;
    m->corners = malloc(sizeof *m->corners * (size_t)m->count);
    m->ids = malloc(sizeof *m->ids * (size_t)m->count);
    double (*p)[3] = malloc(sizeof *p * (size_t)(n + 1) * (n + 1) * (n + 1));
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
    long c = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++, c++)
                for (int v = 0; v < 8; v++) {
                    int id = ((k + off[v][2]) * (n + 1) + (j + off[v][1])) * (n + 1) + (i + off[v][0]);
                    memcpy(m->corners[c][v], p[id], sizeof p[0]);
                    m->ids[c][v] = id;
                }
    free(p);
}

static int load_hex_mesh(const char *path, hex_mesh *m)
{
    tpk_mesh src;
    tpk_diag d;
    memset(&d, 0, sizeof d);
    if (tpk_import_any(path, NULL, &src, &d) != 0) {
        fprintf(stderr, "%s\n", d.message);
        return -1;
    }
    m->name = path;
    m->count = 0;
    m->corners = malloc(sizeof *m->corners * (size_t)(src.cell_count ? src.cell_count : 1));
    m->ids = malloc(sizeof *m->ids * (size_t)(src.cell_count ? src.cell_count : 1));
    double lo = INFINITY, hi = -INFINITY;
    for (int64_t c = 0; c < src.cell_count; c++) {
        if (src.cell_types[c] != 12)
            continue;
        for (int i = 0; i < 8; i++) {
            int32_t id = src.cell_conn[src.cell_offsets[c] + i];
            memcpy(m->corners[m->count][i], src.points + 3 * id, sizeof m->corners[0][0]);
            m->ids[m->count][i] = id;
            for (int k = 0; k < 3; k++)
                lo = src.points[3 * id + k] < lo ? src.points[3 * id + k] : lo,
                hi = src.points[3 * id + k] > hi ? src.points[3 * id + k] : hi;
        }
        m->count++;
    }
    m->scale = hi > lo ? (hi - lo) / 4 : 1;
    tpk_mesh_free(&src);
    return m->count ? 0 : -1;
}

int main(int argc, char **argv)
{
    hex_mesh m;
    char names[3][64];
    const char *defaults[] = {"../shared/data/sfepy/cube_medium_hexa.mesh"};
    int nfiles = argc > 1 ? argc - 1 : 1;
    for (int i = 0; i < nfiles; i++) {
        if (load_hex_mesh(argc > 1 ? argv[i + 1] : defaults[0], &m) == 0) {
            run(&m);
            free(m.corners), free(m.ids);
        }
    }
    const double jitters[3] = {0.0, 0.15, 0.3};
    for (int j = 0; j < 3; j++) {
        warped_grid(&m, 10, jitters[j], names[j], sizeof names[j]);
        run(&m);
        free(m.corners), free(m.ids);
    }
    return 0;
}
