/* Shared by the hard cases (tests/hard/test_hard_*.c, ctest label `hard`): adversarial meshes written as
 * small legacy VTK files in the test's temporary directory and converted by the real converter
 * (tpk_convert_checked: the 6xx checks on every file written), loaded back with libtetpack, and rays
 * marched with every tet piece recorded. Each case ends by printing one JSON line with the figures it
 * asserted on (`{"case":...,"passed":true,"outcome":...,"figures":{...}}`): bench/report collects them.
 * Header-only (static functions): each test file is its own executable. */
#ifndef TPK_HARD_COMMON_H
#define TPK_HARD_COMMON_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/convert.h"
#include "harness.h"
#include "tetpack.h"
#include "tpk_assert.h"

/* ---- input files ---------------------------------------------------------------------------------- */

/* Legacy VTK, ASCII, double points; cell c has VTK type types[c] and nodes conn[offsets[c]..[c+1]). */
static inline int hard_write_vtk(const char *path, const double *points, int64_t point_count, const int *types,
                                 const int64_t *offsets, const int32_t *conn, int64_t cell_count)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "# vtk DataFile Version 2.0\ntetpack hard case\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %lld double\n",
            (long long)point_count);
    for (int64_t p = 0; p < point_count; p++)
        fprintf(f, "%.17g %.17g %.17g\n", points[3 * p], points[3 * p + 1], points[3 * p + 2]);
    fprintf(f, "CELLS %lld %lld\n", (long long)cell_count, (long long)(offsets[cell_count] + cell_count));
    for (int64_t c = 0; c < cell_count; c++) {
        fprintf(f, "%lld", (long long)(offsets[c + 1] - offsets[c]));
        for (int64_t k = offsets[c]; k < offsets[c + 1]; k++)
            fprintf(f, " %d", conn[k]);
        fprintf(f, "\n");
    }
    fprintf(f, "CELL_TYPES %lld\n", (long long)cell_count);
    for (int64_t c = 0; c < cell_count; c++)
        fprintf(f, "%d\n", types[c]);
    return fclose(f) == 0 ? 0 : -1;
}

/* A mesh being built: points and cells appended, then written. */
typedef struct hard_mesh {
    double *points;
    int64_t point_count, point_cap;
    int *types;
    int64_t *offsets;
    int32_t *conn;
    int64_t cell_count, cell_cap, conn_cap;
} hard_mesh;

static inline void hard_mesh_free(hard_mesh *m)
{
    free(m->points), free(m->types), free(m->offsets), free(m->conn);
    memset(m, 0, sizeof *m);
}

static inline int32_t hard_add_point(hard_mesh *m, double x, double y, double z)
{
    if (m->point_count == m->point_cap) {
        m->point_cap = m->point_cap ? 2 * m->point_cap : 256;
        double *p = realloc(m->points, sizeof *p * 3 * (size_t)m->point_cap);
        if (!p)
            abort();
        m->points = p;
    }
    double *p = m->points + 3 * m->point_count;
    p[0] = x, p[1] = y, p[2] = z;
    return (int32_t)m->point_count++;
}

static inline void hard_add_cell(hard_mesh *m, int type, const int32_t *nodes, int n)
{
    if (m->cell_count + 1 >= m->cell_cap) {
        m->cell_cap = m->cell_cap ? 2 * m->cell_cap : 256;
        int *t = realloc(m->types, sizeof *t * (size_t)m->cell_cap);
        int64_t *o = realloc(m->offsets, sizeof *o * (size_t)(m->cell_cap + 1));
        if (!t || !o)
            abort();
        m->types = t, m->offsets = o;
        if (m->cell_count == 0)
            m->offsets[0] = 0;
    }
    int64_t at = m->offsets[m->cell_count];
    if (at + n > m->conn_cap) {
        m->conn_cap = m->conn_cap ? 2 * m->conn_cap + n : 1024;
        int32_t *c = realloc(m->conn, sizeof *c * (size_t)m->conn_cap);
        if (!c)
            abort();
        m->conn = c;
    }
    memcpy(m->conn + at, nodes, sizeof *nodes * (size_t)n);
    m->types[m->cell_count] = type;
    m->offsets[++m->cell_count] = at + n;
}

static inline int hard_mesh_write(const hard_mesh *m, const char *path)
{
    return hard_write_vtk(path, m->points, m->point_count, m->types, m->offsets, m->conn, m->cell_count);
}

static inline uint64_t hard_rand(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull); /* splitmix64 */
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static inline double hard_uniform(uint64_t *state)
{
    return (double)(hard_rand(state) >> 11) * (1.0 / 9007199254740992.0);
}

/* Hexahedra of an n^3 grid of cubes of edge h at `shift`; keep(i,j,k) == 0 leaves a cube out. Point ids
 * are shuffled (seed) so the smallest-id diagonals, and so the 5- and 6-tet splits, vary from cube to
 * cube. */
static inline void hard_hex_grid(hard_mesh *m, int n, double h, const double shift[3],
                                 int (*keep)(int i, int j, int k), uint64_t seed)
{
    int64_t np = (int64_t)(n + 1) * (n + 1) * (n + 1);
    int32_t *id = malloc(sizeof *id * (size_t)np);
    if (!id)
        abort();
    for (int64_t i = 0; i < np; i++)
        id[i] = (int32_t)i;
    for (int64_t i = np - 1; seed && i > 0; i--) {
        int64_t j = (int64_t)(hard_rand(&seed) % (uint64_t)(i + 1));
        int32_t s = id[i];
        id[i] = id[j], id[j] = s;
    }
    int32_t base = (int32_t)m->point_count;
    double *xyz = malloc(sizeof *xyz * 3 * (size_t)np);
    if (!xyz)
        abort();
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                int64_t v = ((int64_t)k * (n + 1) + j) * (n + 1) + i;
                xyz[3 * id[v]] = shift[0] + i * h, xyz[3 * id[v] + 1] = shift[1] + j * h;
                xyz[3 * id[v] + 2] = shift[2] + k * h;
            }
    for (int64_t v = 0; v < np; v++)
        hard_add_point(m, xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
    static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                if (keep && !keep(i, j, k))
                    continue;
                int32_t nodes[8];
                for (int c = 0; c < 8; c++)
                    nodes[c] = base + id[((int64_t)(k + off[c][2]) * (n + 1) + j + off[c][1]) * (n + 1) + i + off[c][0]];
                hard_add_cell(m, 12, nodes, 8);
            }
    free(id);
    free(xyz);
}

/* ---- converting and loading --------------------------------------------------------------------- */

enum { HARD_STRICT = 1, HARD_DROP = 2, HARD_SKIP_BAD = 4, HARD_CUT_FOLDS = 8 };

static inline int hard_convert(const char *input, const char *output, unsigned repairs, tpk_convert_report *report,
                               tpk_diag *diag)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = input;
    o.output = output;
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET20 | TPK_LAYOUT_BIT_TET32;
    o.strict_orientation = (repairs & HARD_STRICT) != 0;
    o.drop_degenerate = (repairs & HARD_DROP) != 0;
    o.skip_bad_cells = (repairs & HARD_SKIP_BAD) != 0;
    o.cut_folds = (repairs & HARD_CUT_FOLDS) != 0;
    o.threads = 2;
    memset(report, 0, sizeof *report);
    memset(diag, 0, sizeof *diag);
    return tpk_convert_checked(&o, report, diag);
}

/* An opened file with one marcher per layout (Tet32, Tet20, Tet16). */
typedef struct hard_tpk {
    tpk_file *file;
    tpk_mesh_arrays arrays[3];
    tpk_marcher *marcher[3];
    tpk_file_info info;
} hard_tpk;

static inline void hard_tpk_close(hard_tpk *t)
{
    for (int l = 0; l < 3; l++)
        tpk_marcher_destroy(t->marcher[l]);
    tpk_close(t->file);
    memset(t, 0, sizeof *t);
}

static inline int hard_tpk_open(hard_tpk *t, const char *path)
{
    memset(t, 0, sizeof *t);
    const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    if (tpk_open_path(&t->file, path, NULL, NULL, 0) != TPK_OK || tpk_get_info(t->file, &t->info) != TPK_OK)
        return -1;
    for (int l = 0; l < 3; l++)
        if (tpk_load_arrays(t->file, layouts[l], NULL, 0, &t->arrays[l]) != TPK_OK ||
            tpk_marcher_create(&t->marcher[l], &t->arrays[l]) != TPK_OK)
            return -1;
    return 0;
}

/* ---- one ray -------------------------------------------------------------------------------------- */

#define HARD_MAX_PIECES 65536

typedef struct hard_ray {
    int32_t tets[HARD_MAX_PIECES];
    double t_in[HARD_MAX_PIECES], t_out[HARD_MAX_PIECES];
    double length; /* sum of t_out - t_in, in units of |dir| */
    int pieces, overflow, backwards, repeats;
    tpk_result marcher; /* what tpk_march_ray returned */
    double last_t, overlap; /* overlap: how far a piece started before the previous one ended */
} hard_ray;

static inline int hard_on_piece(void *user, const tpk_segment *s)
{
    hard_ray *r = user;
    /* Pieces come in increasing t; where a ray leaves the shell and re-enters at the same point (a
     * touching vertex or edge), the entry's t, computed from another face, may fall a few ulps before
     * the exit's: measured (overlap) and allowed up to 8 ulps. */
    double slack = 8 * ldexp(fabs(r->last_t) > 1 ? fabs(r->last_t) : 1.0, -52);
    if (s->t_out < s->t_in || s->t_in < r->last_t - slack)
        r->backwards++;
    if (s->t_in < r->last_t)
        r->overlap = fmax(r->overlap, r->last_t - s->t_in);
    r->last_t = s->t_out;
    r->length += s->t_out - s->t_in;
    if (r->pieces < HARD_MAX_PIECES) {
        r->t_in[r->pieces] = s->t_in, r->t_out[r->pieces] = s->t_out;
        r->tets[r->pieces++] = s->tet;
    } else {
        r->overflow = 1;
    }
    return 0;
}

static inline int hard_cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* March org + t dir from tmin on marcher l; the pieces and their length in r. Returns the marcher's
 * result, or TPK_ERR_MESH when a tet repeats or t goes backwards (a loop the marcher missed). */
static inline tpk_result hard_march(const hard_tpk *t, int l, const double org[3], const double dir[3], double tmin,
                                    hard_ray *r, tpk_march_stats *st)
{
    r->length = 0, r->pieces = 0, r->overflow = 0, r->backwards = 0, r->last_t = -INFINITY, r->overlap = 0;
    r->repeats = 0;
    tpk_result res = r->marcher = tpk_march_ray(t->marcher[l], org, dir, tmin, INFINITY, hard_on_piece, r, st);
    if (res != TPK_OK)
        return res;
    int32_t *sorted = malloc(sizeof *sorted * (size_t)(r->pieces ? r->pieces : 1));
    if (!sorted)
        abort();
    memcpy(sorted, r->tets, sizeof *sorted * (size_t)r->pieces);
    qsort(sorted, (size_t)r->pieces, sizeof *sorted, hard_cmp_i32);
    int repeat = 0;
    for (int i = 1; i < r->pieces; i++)
        repeat |= sorted[i] == sorted[i - 1];
    free(sorted);
    r->repeats = repeat;
    return repeat || r->overflow || r->backwards ? TPK_ERR_MESH : TPK_OK;
}

/* Chord of org + t dir (t >= tmin) through the axis-aligned box [lo, hi], in units of |dir|. */
static inline double hard_box_chord(const double lo[3], const double hi[3], const double org[3], const double dir[3],
                                    double tmin)
{
    double tn = tmin, tf = INFINITY;
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0) {
            if (org[k] < lo[k] || org[k] > hi[k])
                return 0;
            continue;
        }
        double t0 = (lo[k] - org[k]) / dir[k], t1 = (hi[k] - org[k]) / dir[k];
        if (t0 > t1) {
            double s = t0;
            t0 = t1, t1 = s;
        }
        tn = fmax(tn, t0), tf = fmin(tf, t1);
    }
    return tf > tn ? tf - tn : 0;
}

/* ---- the case's figures ---------------------------------------------------------------------------- */

/* A refusal's first clause (up to its first ':'), safe inside a JSON string: for the figures. */
static inline void hard_clause(char *dst, size_t cap, const char *message)
{
    size_t n = 0;
    for (const char *c = message; *c && *c != ':' && n + 1 < cap; c++)
        dst[n++] = *c == '"' || *c == '\\' || *c == '\n' ? '\'' : *c;
    dst[n] = 0;
}

/* Prints {"case":NAME,"passed":true,"outcome":OUTCOME,"figures":{FIGURES}}: FIGURES is a printf format
 * of "key":value pairs. Called at the end of a case, after every CHECK passed. */
static inline void hard_report(const char *name, const char *outcome, const char *figures, ...)
{
    char buf[2048];
    va_list ap;
    va_start(ap, figures);
    vsnprintf(buf, sizeof buf, figures, ap);
    va_end(ap);
    printf("{\"case\":\"%s\",\"passed\":true,\"outcome\":\"%s\",\"figures\":{%s}}\n", name, outcome, buf);
    fflush(stdout);
}

#endif
