/* The VTK cell type table (VTK's vtkCellType.h codes and node orders; higher-order cells list their
 * corner nodes first, in the order of the linear cell) and the shapes of the linear volume cells. */
#include <math.h>
#include "cell_types.h"

#include <stddef.h>
#include <stdio.h>

#include "mesh.h"
#include "tetpack_format.h"

static const tpk_cell_type_info cell_types[] = {
    {0, "empty cell", 0, 0, 0, 0},
    {1, "vertex", 0, 1, 1, 1},
    {2, "poly vertex", 0, 0, 2, 0},
    {3, "line", 1, 2, 3, 2},
    {4, "poly line", 1, 0, 4, 0},
    {5, "triangle", 2, 3, 5, 3},
    {6, "triangle strip", 2, 0, 6, 0},
    {7, "polygon", 2, 0, 7, 0},
    {8, "pixel", 2, 4, 8, 4},
    {9, "quad", 2, 4, 9, 4},
    {10, "tetra", 3, 4, 10, 4},
    {11, "voxel", 3, 8, 11, 8},
    {12, "hexahedron", 3, 8, 12, 8},
    {13, "wedge", 3, 6, 13, 6},
    {14, "pyramid", 3, 5, 14, 5},
    {15, "pentagonal prism", 3, 10, 15, 10},
    {16, "hexagonal prism", 3, 12, 16, 12},
    {21, "quadratic edge", 1, 3, 3, 2},
    {22, "quadratic triangle", 2, 6, 5, 3},
    {23, "quadratic quad", 2, 8, 9, 4},
    {24, "quadratic tetra", 3, 10, 10, 4},
    {25, "quadratic hexahedron", 3, 20, 12, 8},
    {26, "quadratic wedge", 3, 15, 13, 6},
    {27, "quadratic pyramid", 3, 13, 14, 5},
    {28, "biquadratic quad", 2, 9, 9, 4},
    {29, "triquadratic hexahedron", 3, 27, 12, 8},
    {30, "quadratic linear quad", 2, 6, 9, 4},
    {31, "quadratic linear wedge", 3, 12, 13, 6},
    {32, "biquadratic quadratic wedge", 3, 18, 13, 6},
    {33, "biquadratic quadratic hexahedron", 3, 24, 12, 8},
    {34, "biquadratic triangle", 2, 7, 5, 3},
    {35, "cubic line", 1, 4, 3, 2},
    {36, "quadratic polygon", 2, 0, 7, 0},
    {37, "triquadratic pyramid", 3, 19, 14, 5},
    {42, "polyhedron", 3, 0, 42, 0},
    {68, "Lagrange curve", 1, -2, 3, 2},
    {69, "Lagrange triangle", 2, -3, 5, 3},
    {70, "Lagrange quadrilateral", 2, -4, 9, 4},
    {71, "Lagrange tetra", 3, -4, 10, 4},
    {72, "Lagrange hexahedron", 3, -8, 12, 8},
    {73, "Lagrange wedge", 3, -6, 13, 6},
    {74, "Lagrange pyramid", 3, -5, 14, 5},
    {75, "Bezier curve", 1, -2, 3, 2},
    {76, "Bezier triangle", 2, -3, 5, 3},
    {77, "Bezier quadrilateral", 2, -4, 9, 4},
    {78, "Bezier tetra", 3, -4, 10, 4},
    {79, "Bezier hexahedron", 3, -8, 12, 8},
    {80, "Bezier wedge", 3, -6, 13, 6},
    {81, "Bezier pyramid", 3, -5, 14, 5},
};

const tpk_cell_type_info *tpk_cell_type(int type)
{
    /* Types 0 to 16 sit at their own index (the linear cells: every importer asks once per cell). */
    if (type >= 0 && type <= 16 && cell_types[type].type == type)
        return &cell_types[type];
    for (size_t i = 0; i < sizeof cell_types / sizeof cell_types[0]; i++)
        if (cell_types[i].type == type)
            return &cell_types[i];
    return NULL;
}

tpk_cell_rule tpk_cell_rule_for(int type)
{
    const tpk_cell_type_info *t = type == 41 ? NULL : tpk_cell_type(type);
    if (!t)
        return (tpk_cell_rule){TPK_RULE_UNKNOWN, 0, 0, type == 41 ? "convex point set" : "unknown"};
    if (t->dim < 3)
        return (tpk_cell_rule){TPK_RULE_DROP, 0, 0, t->name};
    return (tpk_cell_rule){TPK_RULE_KEEP, t->nodes, (unsigned char)t->type, t->name};
}

void tpk_warn_cell_counts(tpk_diag *diag, const char *name, const int64_t *by_type, int64_t total,
                          const char *what)
{
    char list[600];
    size_t o = 0;
    list[0] = 0;
    for (int t = 0; t < 256; t++) {
        if (!by_type[t] || o + 60 > sizeof list)
            continue;
        o += (size_t)snprintf(list + o, sizeof list - o, "%s%lld %s", o ? ", " : "", (long long)by_type[t],
                              tpk_cell_rule_for(t).name);
    }
    tpk_diag_warn(diag, "%s: %s %lld cells (%s)", name, what, (long long)total, list);
}

/* Indexed by VTK code - 10 (tpk_cell_shape_of). Faces are outward on `ref` (tests/test_split.c checks
 * the volume they enclose, exactly, and that each edge bounds two faces); a voxel is a hexahedron with
 * corners 2,3 and 6,7 swapped (x fastest, then y, then z). */
static const tpk_cell_shape shapes[] = {
    {TPK_CELL_TETRA, 4, 4, {3, 3, 3, 3}, TPK_TET_FACE_LIST,
     6, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
     {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
    {TPK_CELL_VOXEL, 8, 6, {4, 4, 4, 4, 4, 4},
     {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {1, 3, 7, 5}, {3, 2, 6, 7}, {2, 0, 4, 6}},
     12, {{0, 1}, {1, 3}, {2, 3}, {0, 2}, {4, 5}, {5, 7}, {6, 7}, {4, 6}, {0, 4}, {1, 5}, {2, 6}, {3, 7}},
     {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}},
    {TPK_CELL_HEXAHEDRON, 8, 6, {4, 4, 4, 4, 4, 4},
     {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}},
     12, {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}},
     {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}},
    {TPK_CELL_WEDGE, 6, 5, {3, 3, 4, 4, 4},
     {{0, 2, 1}, {3, 4, 5}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}},
     9, {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}},
     {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}}},
    {TPK_CELL_PYRAMID, 5, 5, {4, 3, 3, 3, 3},
     {{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}},
     8, {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
     {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}}},
};

const tpk_cell_shape *tpk_cell_shape_of(int type)
{
    /* The shapes in the order of their VTK codes, 10 to 14: the checks ask once per cell. */
    return type >= TPK_CELL_TETRA && type <= TPK_CELL_PYRAMID ? &shapes[type - TPK_CELL_TETRA] : NULL;
}

int tpk_cell_faces(int type, const int32_t *nodes, int32_t *ids, int *starts)
{
    const tpk_cell_shape *s = type == TPK_CELL_TETRA ? NULL : tpk_cell_shape_of(type);
    if (!s)
        return 0;
    starts[0] = 0;
    for (int f = 0; f < s->face_count; f++) {
        for (int i = 0; i < s->face_size[f]; i++)
            ids[starts[f] + i] = nodes[s->faces[f][i]];
        starts[f + 1] = starts[f] + s->face_size[f];
    }
    return s->face_count;
}

/* The faces' normals in one winding are all outward or all inward, so the angle at the edge between
 * faces k and l is acos(-n_k.n_l). */
int tpk_tet_is_flat(const double *points, const int32_t v[4])
{
    static const int face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    double n[4][3], len[4];
    for (int k = 0; k < 4; k++) {
        const double *a = points + 3 * (int64_t)v[face[k][0]], *b = points + 3 * (int64_t)v[face[k][1]],
                     *c = points + 3 * (int64_t)v[face[k][2]];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        n[k][0] = u[1] * w[2] - u[2] * w[1];
        n[k][1] = u[2] * w[0] - u[0] * w[2];
        n[k][2] = u[0] * w[1] - u[1] * w[0];
        len[k] = sqrt(n[k][0] * n[k][0] + n[k][1] * n[k][1] + n[k][2] * n[k][2]);
        if (!(len[k] > 0))
            return 1;
    }
    double most = cos(TPK_FLAT_TET_DEG * M_PI / 180);
    for (int k = 0; k < 4; k++)
        for (int l = k + 1; l < 4; l++)
            if (-(n[k][0] * n[l][0] + n[k][1] * n[l][1] + n[k][2] * n[l][2]) / (len[k] * len[l]) > most)
                return 1;
    return 0;
}
