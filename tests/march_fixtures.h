/* Test meshes for the marcher and the CPU renderer: hex grids (optionally with cubes removed, for
 * non-convex shells) split into 6 tets per cube (Kuhn split, conforming), random vertex relabeling, and
 * the Tet32/20/16 layouts and shell from the converter pipeline (tools/convert/pipeline.h). Header-only; used
 * by tests/test_march.c, tests/test_render.c and bench/bench_march.c. */
#ifndef TPK_MARCH_FIXTURES_H
#define TPK_MARCH_FIXTURES_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "tetpack.h"
#include "convert/pipeline.h"

typedef struct fx_mesh {
    int64_t vertex_count, tet_count, shell_count;
    double origin[3];
    double *points;        /* absolute, 3 per vertex */
    float *positions;      /* relative to origin */
    float *scalars;        /* per vertex, or NULL */
    int32_t *tets;         /* 4 per tet, positively oriented */
    int32_t *neighbors;    /* 4 per tet, opposite tets[4t+k] */
    tpk_tet32 *tet32;
    tpk_tet20 *tet20;
    tpk_tet16 *tet16;
    tpk_shell_face *shell;
} fx_mesh;

static inline void fx_free(fx_mesh *m)
{
    free(m->points);
    free(m->positions);
    free(m->scalars);
    free(m->tets);
    free(m->neighbors);
    free(m->tet32);
    free(m->tet20);
    free(m->tet16);
    free(m->shell);
    memset(m, 0, sizeof *m);
}

static inline uint64_t fx_rand(uint64_t *state)
{
    /* splitmix64 */
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static inline double fx_uniform(uint64_t *state)
{
    return (double)(fx_rand(state) >> 11) * (1.0 / 9007199254740992.0);
}

static inline double fx_orient(const double *a, const double *b, const double *c, const double *d)
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Grid of nx*ny*nz unit cubes with corner (0,0,0) scaled by `scale` and shifted by `shift`;
 * keep[i + nx*(j + ny*k)] == 0 removes a cube (keep NULL: all). 6 tets per cube around the diagonal
 * (0,0,0)-(1,1,1) of each cube, which conforms across cubes. origin = shift. */
static inline int fx_grid(fx_mesh *m, int nx, int ny, int nz, const unsigned char *keep, double scale,
                          const double shift[3])
{
    memset(m, 0, sizeof *m);
    int64_t vx = nx + 1, vy = ny + 1, vz = nz + 1;
    m->vertex_count = vx * vy * vz;
    int64_t cubes = 0;
    for (int64_t c = 0; c < (int64_t)nx * ny * nz; c++)
        cubes += keep ? keep[c] != 0 : 1;
    m->tet_count = 6 * cubes;
    m->points = malloc((size_t)m->vertex_count * 3 * sizeof(double));
    m->positions = malloc((size_t)m->vertex_count * 3 * sizeof(float));
    m->tets = malloc((size_t)m->tet_count * 4 * sizeof(int32_t));
    if (!m->points || !m->positions || !m->tets)
        return -1;
    for (int k = 0; k < 3; k++)
        m->origin[k] = shift ? shift[k] : 0.0;
    for (int64_t k = 0; k < vz; k++)
        for (int64_t j = 0; j < vy; j++)
            for (int64_t i = 0; i < vx; i++) {
                int64_t v = i + vx * (j + vy * k);
                double rel[3] = {i * scale, j * scale, k * scale};
                for (int a = 0; a < 3; a++) {
                    m->positions[3 * v + a] = (float)rel[a];
                    m->points[3 * v + a] = m->origin[a] + (double)m->positions[3 * v + a];
                }
            }
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int64_t t = 0;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                if (keep && !keep[i + nx * (j + ny * k)])
                    continue;
                for (int p = 0; p < 6; p++) {
                    int c[3] = {i, j, k};
                    int32_t *tet = &m->tets[4 * t];
                    tet[0] = (int32_t)(c[0] + vx * (c[1] + vy * c[2]));
                    for (int s = 0; s < 3; s++) {
                        c[perms[p][s]]++;
                        tet[s + 1] = (int32_t)(c[0] + vx * (c[1] + vy * c[2]));
                    }
                    t++;
                }
            }
    for (t = 0; t < m->tet_count; t++) {
        int32_t *tet = &m->tets[4 * t];
        if (fx_orient(&m->points[3 * tet[0]], &m->points[3 * tet[1]], &m->points[3 * tet[2]],
                      &m->points[3 * tet[3]]) < 0) {
            int32_t s = tet[2];
            tet[2] = tet[3];
            tet[3] = s;
        }
    }
    return 0;
}

/* Renumber vertices and tets randomly and rotate each tet's vertex list (keeping orientation). */
static inline int fx_relabel(fx_mesh *m, uint64_t seed)
{
    int64_t nv = m->vertex_count, nt = m->tet_count;
    int32_t *vperm = malloc((size_t)nv * sizeof *vperm);
    int32_t *tperm = malloc((size_t)nt * sizeof *tperm);
    double *points = malloc((size_t)nv * 3 * sizeof *points);
    float *positions = malloc((size_t)nv * 3 * sizeof *positions);
    int32_t *tets = malloc((size_t)nt * 4 * sizeof *tets);
    if (!vperm || !tperm || !points || !positions || !tets)
        return -1;
    for (int64_t i = 0; i < nv; i++)
        vperm[i] = (int32_t)i;
    for (int64_t i = 0; i < nt; i++)
        tperm[i] = (int32_t)i;
    for (int64_t i = nv - 1; i > 0; i--) {
        int64_t j = (int64_t)(fx_rand(&seed) % (uint64_t)(i + 1));
        int32_t s = vperm[i];
        vperm[i] = vperm[j];
        vperm[j] = s;
    }
    for (int64_t i = nt - 1; i > 0; i--) {
        int64_t j = (int64_t)(fx_rand(&seed) % (uint64_t)(i + 1));
        int32_t s = tperm[i];
        tperm[i] = tperm[j];
        tperm[j] = s;
    }
    for (int64_t i = 0; i < nv; i++)
        for (int a = 0; a < 3; a++) {
            points[3 * vperm[i] + a] = m->points[3 * i + a];
            positions[3 * vperm[i] + a] = m->positions[3 * i + a];
        }
    for (int64_t t = 0; t < nt; t++) {
        const int32_t *src = &m->tets[4 * t];
        int32_t *dst = &tets[4 * tperm[t]];
        /* even permutations keep the orientation: rotate the last three by a random amount */
        int r = (int)(fx_rand(&seed) % 3);
        dst[0] = vperm[src[0]];
        for (int s = 0; s < 3; s++)
            dst[1 + s] = vperm[src[1 + (s + r) % 3]];
    }
    free(m->points);
    free(m->positions);
    free(m->tets);
    m->points = points;
    m->positions = positions;
    m->tets = tets;
    free(vperm);
    free(tperm);
    return 0;
}

/* Neighbors, the three layouts and the shell. */
static inline int fx_build(fx_mesh *m)
{
    int64_t nt = m->tet_count;
    m->neighbors = malloc((size_t)nt * 4 * sizeof(int32_t));
    m->tet32 = malloc((size_t)nt * sizeof(tpk_tet32));
    m->tet20 = malloc((size_t)nt * sizeof(tpk_tet20));
    m->tet16 = malloc((size_t)nt * sizeof(tpk_tet16));
    if (!m->neighbors || !m->tet32 || !m->tet20 || !m->tet16)
        return -1;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_connect(m->tets, nt, m->vertex_count, m->neighbors, 1, &diag) != 0)
        return -1;
    tpk_build_tet32(m->tets, m->neighbors, nt, m->tet32);
    tpk_build_tet20(m->tets, m->neighbors, nt, m->tet20);
    tpk_build_tet16(m->tets, m->neighbors, nt, m->tet16);
    m->shell_count = tpk_count_shell_faces(m->neighbors, nt);
    m->shell = malloc((size_t)(m->shell_count ? m->shell_count : 1) * sizeof *m->shell);
    if (!m->shell)
        return -1;
    tpk_build_shell(m->tets, m->neighbors, nt, m->shell);
    return 0;
}

/* The render tests' mesh: an 8^3 grid of unit cubes, built, with scalar = x (0..8) when with_scalars. */
static inline int fx_render_grid(fx_mesh *m, int with_scalars)
{
    if (fx_grid(m, 8, 8, 8, NULL, 1.0, NULL) != 0 || fx_build(m) != 0)
        return -1;
    if (!with_scalars)
        return 0;
    m->scalars = malloc((size_t)m->vertex_count * sizeof(float));
    if (!m->scalars)
        return -1;
    for (int64_t v = 0; v < m->vertex_count; v++)
        m->scalars[v] = m->positions[3 * v];
    return 0;
}

static inline tpk_mesh_arrays fx_arrays(const fx_mesh *m, tpk_layout layout)
{
    tpk_mesh_arrays a;
    memset(&a, 0, sizeof a);
    a.vertex_count = (uint64_t)m->vertex_count;
    a.tet_count = (uint64_t)m->tet_count;
    a.shell_face_count = (uint64_t)m->shell_count;
    memcpy(a.origin, m->origin, sizeof a.origin);
    a.positions = m->positions;
    a.layout = layout;
    a.tet32 = layout == TPK_LAYOUT_TET32 ? m->tet32 : NULL;
    a.tet20 = layout == TPK_LAYOUT_TET20 ? m->tet20 : NULL;
    a.tet16 = layout == TPK_LAYOUT_TET16 ? m->tet16 : NULL;
    a.shell = m->shell;
    a.scalars = m->scalars;
    return a;
}

#endif
