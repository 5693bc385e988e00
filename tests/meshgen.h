/* Generated tet meshes for tests and benchmarks (header-only): an N x N x N grid of unit cubes, each
 * split into the 6 Kuhn (Freudenthal) tets along the main diagonal, so neighboring cubes' faces conform.
 * Options relabel vertices, shuffle tets and rotate each tet's vertex order (which flips half of them
 * negative), all from a fixed seed. */
#ifndef TPK_TEST_MESHGEN_H
#define TPK_TEST_MESHGEN_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/cell_types.h"
#include "mesh/mesh.h"

typedef struct tpk_gen_options {
    double spacing;      /* cube edge (0: 1.0) */
    double origin[3];
    int relabel;         /* random vertex ids */
    int shuffle_tets;    /* random tet order */
    int scramble_order;  /* random vertex order inside each tet (half end up negative) */
    uint64_t seed;
} tpk_gen_options;

static inline uint64_t tpk_gen_next(uint64_t *state)
{
    /* splitmix64 */
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Fills `mesh` (points, tets, identity vertex_source and tet_source, no fields). Tets of cube
 * (i,j,k) in order; for an unscrambled mesh tet `6*cube + p` walks the axes in permutation p.
 * Returns 0, or -1 when out of memory. */
static inline int tpk_gen_kuhn_grid(int n, const tpk_gen_options *opt, tpk_tetmesh *mesh)
{
    static const int axis_orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    tpk_gen_options defaults = {0};
    if (!opt)
        opt = &defaults;
    double h = opt->spacing > 0 ? opt->spacing : 1.0;
    int64_t side = n + 1, nv = side * side * side, nt = 6 * (int64_t)n * n * n;
    uint64_t rng = opt->seed * 2654435761u + 1;
    memset(mesh, 0, sizeof *mesh);
    mesh->vertex_count = nv;
    mesh->tet_count = nt;
    mesh->step_count = 1;
    mesh->points = malloc(sizeof *mesh->points * 3 * (size_t)nv);
    mesh->vertex_source = malloc(sizeof *mesh->vertex_source * (size_t)nv);
    mesh->tets = malloc(sizeof *mesh->tets * 4 * (size_t)nt);
    mesh->tet_source = malloc(sizeof *mesh->tet_source * (size_t)nt);
    int32_t *label = malloc(sizeof *label * (size_t)nv);
    if (!mesh->points || !mesh->vertex_source || !mesh->tets || !mesh->tet_source || !label) {
        free(label);
        tpk_tetmesh_free(mesh);
        return -1;
    }
    for (int64_t v = 0; v < nv; v++)
        label[v] = (int32_t)v;
    if (opt->relabel)
        for (int64_t v = nv - 1; v > 0; v--) {
            int64_t j = (int64_t)(tpk_gen_next(&rng) % (uint64_t)(v + 1));
            int32_t s = label[v];
            label[v] = label[j];
            label[j] = s;
        }
    for (int64_t k = 0; k < side; k++)
        for (int64_t j = 0; j < side; j++)
            for (int64_t i = 0; i < side; i++) {
                int64_t id = label[i + side * (j + side * k)];
                mesh->points[3 * id + 0] = opt->origin[0] + h * (double)i;
                mesh->points[3 * id + 1] = opt->origin[1] + h * (double)j;
                mesh->points[3 * id + 2] = opt->origin[2] + h * (double)k;
                mesh->vertex_source[id] = (int32_t)id;
            }
    int64_t t = 0;
    for (int64_t k = 0; k < n; k++)
        for (int64_t j = 0; j < n; j++)
            for (int64_t i = 0; i < n; i++)
                for (int p = 0; p < 6; p++) {
                    int64_t c[3] = {i, j, k};
                    int32_t *v = mesh->tets + 4 * t;
                    v[0] = label[c[0] + side * (c[1] + side * c[2])];
                    for (int s = 0; s < 3; s++) {
                        c[axis_orders[p][s]]++;
                        v[s + 1] = label[c[0] + side * (c[1] + side * c[2])];
                    }
                    if (p == 1 || p == 2 || p == 5) { /* odd axis permutations are negative */
                        int32_t s = v[2];
                        v[2] = v[3];
                        v[3] = s;
                    }
                    mesh->tet_source[t] = (int32_t)t;
                    t++;
                }
    free(label);
    if (opt->scramble_order)
        for (int64_t i = 0; i < nt; i++) {
            int32_t *v = mesh->tets + 4 * i;
            for (int a = 3; a > 0; a--) {
                int b = (int)(tpk_gen_next(&rng) % (uint64_t)(a + 1));
                int32_t s = v[a];
                v[a] = v[b];
                v[b] = s;
            }
        }
    if (opt->shuffle_tets)
        for (int64_t i = nt - 1; i > 0; i--) {
            int64_t j = (int64_t)(tpk_gen_next(&rng) % (uint64_t)(i + 1));
            int32_t s[4];
            memcpy(s, mesh->tets + 4 * i, sizeof s);
            memcpy(mesh->tets + 4 * i, mesh->tets + 4 * j, sizeof s);
            memcpy(mesh->tets + 4 * j, s, sizeof s);
            int32_t src = mesh->tet_source[i];
            mesh->tet_source[i] = mesh->tet_source[j];
            mesh->tet_source[j] = src;
        }
    return 0;
}

/* Six pyramids filling the unit cube from its centre (point 8), in VTK node order: a pyramid's base is
 * an outward cube face reversed (VTK turns the base towards the apex). The mesh points at static
 * arrays: do not free it. */
static inline tpk_mesh tpk_gen_cube_pyramids(void)
{
    static double points[9][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1},
                                  {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0.5, 0.5, 0.5}};
    const int (*outward)[4] = tpk_cell_shape_of(TPK_CELL_HEXAHEDRON)->faces;
    static uint8_t types[6];
    static int64_t offsets[7];
    static int32_t conn[30];
    for (int f = 0; f < 6; f++) {
        types[f] = TPK_CELL_PYRAMID;
        offsets[f] = 5 * f;
        for (int k = 0; k < 4; k++)
            conn[5 * f + k] = outward[f][3 - k];
        conn[5 * f + 4] = 8;
    }
    offsets[6] = 30;
    tpk_mesh cube;
    memset(&cube, 0, sizeof cube);
    cube.point_count = 9;
    cube.points = &points[0][0];
    cube.cell_count = 6;
    cube.cell_types = types;
    cube.cell_offsets = offsets;
    cube.cell_conn = conn;
    return cube;
}

#endif
