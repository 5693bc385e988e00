/* tetpack iso's extraction (tools/iso/) on generated grids against closed forms: the case table's
 * orientation on the reference tet, a sphere of a radial field (area and volume), a plane of a linear
 * field (exact area, open edges only on the shell), watertightness, and outputs equal for any thread
 * count. The CLI, the writers and real meshes: tests/cli/iso.sh. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "iso/iso.h"

typedef struct grid {
    int64_t vertex_count, tet_count;
    float *positions, *scalars;
    int32_t *tets;
} grid;

static double det3(const float *p0, const float *p1, const float *p2, const float *p3)
{
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; k++)
        a[k] = p1[k] - p0[k], b[k] = p2[k] - p0[k], c[k] = p3[k] - p0[k];
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* n^3 cubes on [-1, 1]^3, each split into 6 tets along its main diagonal (Kuhn: conforming), turned
 * positive; field(x, y, z) at the vertices. */
static int make_grid(grid *g, int n, double (*field)(double, double, double))
{
    int64_t m = n + 1;
    g->vertex_count = m * m * m;
    g->tet_count = 6 * (int64_t)n * n * n;
    g->positions = malloc(sizeof(float) * 3 * (size_t)g->vertex_count);
    g->scalars = malloc(sizeof(float) * (size_t)g->vertex_count);
    g->tets = malloc(sizeof(int32_t) * 4 * (size_t)g->tet_count);
    if (!g->positions || !g->scalars || !g->tets)
        return -1;
    for (int64_t i = 0; i < m; i++)
        for (int64_t j = 0; j < m; j++)
            for (int64_t k = 0; k < m; k++) {
                int64_t v = (i * m + j) * m + k;
                float *p = g->positions + 3 * v;
                p[0] = (float)(-1 + 2.0 * i / n), p[1] = (float)(-1 + 2.0 * j / n), p[2] = (float)(-1 + 2.0 * k / n);
                g->scalars[v] = (float)field(p[0], p[1], p[2]);
            }
    static const int paths[6][4] = {{0, 4, 6, 7}, {0, 4, 5, 7}, {0, 2, 6, 7}, {0, 2, 3, 7}, {0, 1, 5, 7}, {0, 1, 3, 7}};
    int32_t *t = g->tets;
    for (int64_t i = 0; i < n; i++)
        for (int64_t j = 0; j < n; j++)
            for (int64_t k = 0; k < n; k++)
                for (int p = 0; p < 6; p++, t += 4) {
                    for (int c = 0; c < 4; c++) {
                        int b = paths[p][c];
                        t[c] = (int32_t)(((i + (b >> 2 & 1)) * m + j + (b >> 1 & 1)) * m + k + (b & 1));
                    }
                    const float *q = g->positions;
                    if (det3(q + 3 * t[0], q + 3 * t[1], q + 3 * t[2], q + 3 * t[3]) < 0) {
                        int32_t x = t[2];
                        t[2] = t[3];
                        t[3] = x;
                    }
                }
    return 0;
}

static void free_grid(grid *g)
{
    free(g->positions);
    free(g->scalars);
    free(g->tets);
}

static tpk_iso_input input_of(const grid *g)
{
    tpk_iso_input in = {.vertex_count = g->vertex_count, .tet_count = g->tet_count, .positions = g->positions,
                        .tets = g->tets, .scalars = g->scalars};
    return in;
}

static double radius(double x, double y, double z)
{
    return sqrt(x * x + y * y + z * z);
}

static double height(double x, double y, double z)
{
    (void)x, (void)y;
    return z;
}

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Surface edges (sorted vertex pairs) in triangle order, sorted: *count entries, each use once. */
static uint64_t *surface_edges(const tpk_iso_surface *s, int64_t *count)
{
    uint64_t *e = malloc(sizeof *e * 3 * (size_t)(s->triangle_count + 1));
    for (int64_t t = 0; t < s->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            e[3 * t + k] = a < b ? a << 32 | b : b << 32 | a;
        }
    *count = 3 * s->triangle_count;
    qsort(e, (size_t)*count, sizeof *e, compare_u64);
    return e;
}

static void area_volume(const tpk_iso_surface *s, double *area, double *volume)
{
    *area = *volume = 0;
    for (int64_t t = 0; t < s->triangle_count; t++) {
        const double *a = s->xyz + 3 * s->tri[3 * t], *b = s->xyz + 3 * s->tri[3 * t + 1], *c = s->xyz + 3 * s->tri[3 * t + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        *area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        *volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                    a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    }
}

/* Every entry of the case table crosses only edges with one corner on each side, and its triangles face
 * the corners above on the reference tet (0,0,0), (1,0,0), (0,1,0), (0,0,1): n . gradient > 0. */
TPK_TEST(case_table)
{
    static const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int mask = 0; mask < 16; mask++) {
        int count, edges[6], corners[6][2];
        tpk_iso_case_table(mask, &count, edges, corners);
        int above = __builtin_popcount((unsigned)mask);
        CHECK_EQ_INT(count, above == 0 || above == 4 ? 0 : above == 2 ? 2 : 1);
        double g[3] = {(mask >> 1 & 1) - (mask & 1), (mask >> 2 & 1) - (mask & 1), (mask >> 3 & 1) - (mask & 1)};
        for (int t = 0; t < count; t++) {
            double q[3][3];
            for (int k = 0; k < 3; k++) {
                const int *c = corners[edges[3 * t + k]];
                CHECK((mask >> c[0] & 1) != (mask >> c[1] & 1));
                for (int d = 0; d < 3; d++)
                    q[k][d] = 0.5 * (p[c[0]][d] + p[c[1]][d]);
            }
            double u[3], v[3];
            for (int d = 0; d < 3; d++)
                u[d] = q[1][d] - q[0][d], v[d] = q[2][d] - q[0][d];
            double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
            CHECK(n[0] * g[0] + n[1] * g[1] + n[2] * g[2] > 0);
        }
    }
}

/* r = 0.7 in |x| on a 40^3 grid (h = 0.05): closed (every edge in exactly two triangles), outward
 * (positive enclosed volume), area and volume within 1% of 4 pi r^2 and 4/3 pi r^3 (linear interpolation
 * of r on tets cuts slightly inside the sphere: -0.13% area, -0.25% volume measured). */
TPK_TEST(sphere_closed_form)
{
    grid g;
    CHECK(make_grid(&g, 40, radius) == 0);
    tpk_iso_input in = input_of(&g);
    tpk_iso_surface s;
    tpk_diag diag = {0};
    double r = 0.7;
    CHECK(tpk_iso_extract(&in, &r, 1, 0, &s, &diag) == 0);
    CHECK(s.triangle_count > 1000);
    int64_t count;
    uint64_t *e = surface_edges(&s, &count);
    int closed = 1;
    for (int64_t i = 0; i < count; i += 2)
        closed &= i + 1 < count && e[i] == e[i + 1] && (i + 2 >= count || e[i + 2] != e[i]);
    free(e);
    double area, volume;
    area_volume(&s, &area, &volume);
    double a0 = 4 * M_PI * r * r, v0 = 4.0 / 3 * M_PI * r * r * r;
    printf("sphere: %lld triangles, area %.6f (%.3e), volume %.6f (%.3e)\n", (long long)s.triangle_count, area,
           area / a0 - 1, volume, volume / v0 - 1);
    tpk_iso_surface_free(&s);
    free_grid(&g);
    CHECK(closed);
    CHECK(fabs(area / a0 - 1) < 0.01);
    CHECK(fabs(volume / v0 - 1) < 0.01);
}

/* z = 0.3 on the grid: a linear field is interpolated exactly, so the area is the box's section, 4, to
 * rounding; open edges (in one triangle) lie on the box's sides x = +-1 or y = +-1; normals are +z. */
TPK_TEST(plane_exact)
{
    grid g;
    CHECK(make_grid(&g, 12, height) == 0);
    tpk_iso_input in = input_of(&g);
    tpk_iso_surface s;
    tpk_diag diag = {0};
    double z = 0.3;
    CHECK(tpk_iso_extract(&in, &z, 1, 2, &s, &diag) == 0);
    double area, volume;
    area_volume(&s, &area, &volume);
    CHECK(fabs(area - 4) < 1e-5);
    int64_t count;
    uint64_t *e = surface_edges(&s, &count);
    int64_t open = 0, bad = 0;
    for (int64_t i = 0; i < count;) {
        int64_t j = i;
        while (j < count && e[j] == e[i])
            j++;
        if (j - i == 1) {
            open++;
            const double *a = s.xyz + 3 * (e[i] >> 32), *b = s.xyz + 3 * (e[i] & 0xffffffffu);
            int side = (fabs(a[0]) == 1 && a[0] == b[0]) || (fabs(a[1]) == 1 && a[1] == b[1]);
            bad += !side;
        }
        bad += j - i > 2;
        i = j;
    }
    free(e);
    int up = 1;
    for (int64_t v = 0; v < s.vertex_count; v++)
        up &= s.normal[3 * v + 2] > 0.999f && fabsf(s.value[v] - 0.3f) == 0;
    tpk_iso_surface_free(&s);
    free_grid(&g);
    CHECK(open == 4 * 12 * 2); /* each box side: 12 cubes, 2 tet faces each */
    CHECK_EQ_INT(bad, 0);
    CHECK(up);
}

static int same_surface(const tpk_iso_surface *a, const tpk_iso_surface *b)
{
    size_t v = (size_t)a->vertex_count, t = (size_t)a->triangle_count;
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           !memcmp(a->xyz, b->xyz, 24 * v) && !memcmp(a->normal, b->normal, 12 * v) &&
           !memcmp(a->value, b->value, 4 * v) && !memcmp(a->edge, b->edge, 8 * v) && !memcmp(a->tri, b->tri, 12 * t) &&
           !memcmp(a->value_triangles, b->value_triangles, sizeof a->value_triangles);
}

/* Three values, 1, 2, 3 and 7 threads: the same arrays bit for bit. */
TPK_TEST(threads_deterministic)
{
    grid g;
    CHECK(make_grid(&g, 24, radius) == 0);
    tpk_iso_input in = input_of(&g);
    double values[3] = {0.3, 0.55, 0.9};
    tpk_iso_surface one, other;
    tpk_diag diag = {0};
    CHECK(tpk_iso_extract(&in, values, 3, 1, &one, &diag) == 0);
    int same = 1;
    for (int threads = 2; threads <= 7; threads += threads == 3 ? 4 : 1) {
        CHECK(tpk_iso_extract(&in, values, 3, threads, &other, &diag) == 0);
        same &= same_surface(&one, &other);
        tpk_iso_surface_free(&other);
    }
    int64_t sum = one.value_triangles[0] + one.value_triangles[1] + one.value_triangles[2];
    CHECK_EQ_INT(sum, one.triangle_count);
    tpk_iso_surface_free(&one);
    free_grid(&g);
    CHECK(same);
}

/* A value beyond the field's range: an empty surface, no error. A NaN at a vertex: its tets make no
 * triangles. Bad value lists are refused. */
TPK_TEST(empty_nan_and_bad_values)
{
    grid g;
    CHECK(make_grid(&g, 6, radius) == 0);
    tpk_iso_input in = input_of(&g);
    tpk_iso_surface s;
    tpk_diag diag = {0};
    double far = 10;
    CHECK(tpk_iso_extract(&in, &far, 1, 0, &s, &diag) == 0);
    CHECK_EQ_INT(s.triangle_count, 0);
    CHECK_EQ_INT(s.vertex_count, 0);
    tpk_iso_surface_free(&s);
    double inf = INFINITY;
    CHECK(tpk_iso_extract(&in, &inf, 1, 0, &s, &diag) == -1);
    CHECK(strstr(diag.message, "finite"));
    CHECK(tpk_iso_extract(&in, &far, 0, 0, &s, &diag) == -1);
    double r = 0.5;
    CHECK(tpk_iso_extract(&in, &r, 1, 0, &s, &diag) == 0);
    int64_t full = s.triangle_count;
    tpk_iso_surface_free(&s);
    for (int64_t v = 0; v < g.vertex_count; v++) /* NaN at the vertices just outside r along +x */
        if (g.positions[3 * v] > 0.4f && g.positions[3 * v] < 0.7f && fabsf(g.positions[3 * v + 1]) < 0.01f &&
            fabsf(g.positions[3 * v + 2]) < 0.01f)
            g.scalars[v] = NAN;
    CHECK(tpk_iso_extract(&in, &r, 1, 0, &s, &diag) == 0);
    CHECK(s.triangle_count > 0 && s.triangle_count < full);
    for (int64_t v = 0; v < 3 * s.vertex_count; v++)
        CHECK(isfinite(s.xyz[v]));
    tpk_iso_surface_free(&s);
    free_grid(&g);
}

/* A vertex that is the lower end of many crossed edges (the centre of a star of 2n tets around a
 * bipyramid, n = 100): its edges are found through the hub table and numbered by a sort, not its chain.
 * One vertex per spoke, at its middle, in the order of the spokes' upper ids; a closed surface. */
TPK_TEST(hub_vertex)
{
    enum { N = 100 };
    float pos[3 * (N + 3)] = {0}, sc[N + 3];
    int32_t tets[4 * 2 * N];
    sc[0] = 0;
    for (int i = 0; i < N; i++) {
        pos[3 * (1 + i)] = (float)cos(2 * M_PI * i / N);
        pos[3 * (1 + i) + 1] = (float)sin(2 * M_PI * i / N);
    }
    pos[3 * (N + 1) + 2] = 1, pos[3 * (N + 2) + 2] = -1;
    for (int v = 1; v < N + 3; v++)
        sc[v] = 1;
    for (int i = 0; i < N; i++)
        for (int h = 0; h < 2; h++) {
            int32_t *t = tets + 4 * (2 * i + h);
            t[0] = 0, t[1] = 1 + i, t[2] = 1 + (i + 1) % N, t[3] = h ? N + 2 : N + 1;
            if (det3(pos + 3 * t[0], pos + 3 * t[1], pos + 3 * t[2], pos + 3 * t[3]) < 0) {
                int32_t x = t[2];
                t[2] = t[3];
                t[3] = x;
            }
        }
    tpk_iso_input in = {.vertex_count = N + 3, .tet_count = 2 * N, .positions = pos, .tets = tets, .scalars = sc};
    double value = 0.5;
    tpk_iso_surface s;
    tpk_diag diag = {0};
    CHECK(tpk_iso_extract(&in, &value, 1, 1, &s, &diag) == 0);
    CHECK_EQ_INT(s.vertex_count, N + 2);
    CHECK_EQ_INT(s.triangle_count, 2 * N);
    int bad = 0;
    for (int64_t v = 0; v < s.vertex_count; v++) {
        bad += s.edge[2 * v] != 0 || s.edge[2 * v + 1] != v + 1;
        for (int k = 0; k < 3; k++)
            bad += s.xyz[3 * v + k] != 0.5 * pos[3 * (v + 1) + k];
    }
    int64_t count;
    uint64_t *e = surface_edges(&s, &count);
    for (int64_t i = 0; i < count; i += 2)
        bad += i + 1 >= count || e[i] != e[i + 1] || (i + 2 < count && e[i + 2] == e[i]);
    free(e);
    double area, volume;
    area_volume(&s, &area, &volume);
    tpk_iso_surface_free(&s);
    CHECK_EQ_INT(bad, 0);
    CHECK(volume > 0);
}
