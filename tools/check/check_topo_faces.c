/* Faces of the volume cells for the connectivity and shell checks, in outward order, and which cells
 * take part (tpk_check_cell_usable). The tables are mesh/cell_types.c's (outward on VTK's parametric
 * corners, so a positive cell's faces point out); tests/test_check_topology.c checks each face against
 * its cell's centre exactly. */
#include "check_topo.h"
#include "convert/pipeline.h"
#include "mesh/cell_types.h"
#include "base/predicates.h"

/* The shape of a tet, voxel, hexahedron, wedge or pyramid with its node count, else NULL. */
static const tpk_cell_shape *table_for(int type, int64_t nodes)
{
    const tpk_cell_shape *s = tpk_cell_shape_of(type); /* NULL for polyhedra: poly_faces */
    return s && nodes == s->corners ? s : NULL;
}

/* A polyhedron's explicit faces (its VTK face stream, which VTK asks to be outward), when it has at most
 * TPK_TOPO_MAX_CELL_FACES faces of 3 to TPK_TOPO_MAX_FACE_VERTS points each; otherwise 0 and the checks leave the cell out
 * (the rest of the mesh is still checked: its boundary against the cell stays closed). The importers
 * checked the stream's structure and ids. */
static int poly_faces(const tpk_mesh *mesh, int64_t cell, tpk_topo_face *faces)
{
    if (mesh->cell_types[cell] != TPK_CELL_POLYHEDRON || !mesh->faces || !mesh->face_offsets)
        return 0;
    const int32_t *stream = mesh->faces + mesh->face_offsets[cell];
    int64_t length = mesh->face_offsets[cell + 1] - mesh->face_offsets[cell];
    if (length < 1 || stream[0] < 4 || stream[0] > TPK_TOPO_MAX_CELL_FACES)
        return 0;
    int count = stream[0];
    int64_t at = 1;
    for (int f = 0; f < count; f++) {
        if (at >= length || stream[at] < 3 || stream[at] > TPK_TOPO_MAX_FACE_VERTS || at + stream[at] >= length)
            return 0;
        if (faces) {
            faces[f].n = stream[at];
            for (int i = 0; i < stream[at]; i++)
                faces[f].v[i] = stream[at + 1 + i];
        }
        at += 1 + stream[at];
    }
    return count;
}

/* Declared in check.h; it lives here, beside the faces it guards and below the face matching that calls
 * it, so the connectivity checks never call back up into the driver (check.c). */
int tpk_check_cell_usable(const tpk_mesh *mesh, int64_t cell)
{
    int64_t b = mesh->cell_offsets[cell], e = mesh->cell_offsets[cell + 1];
    if (e < b || e - b > 64)
        return 0;
    for (int64_t i = b; i < e; i++) {
        if (mesh->cell_conn[i] < 0 || mesh->cell_conn[i] >= mesh->point_count)
            return 0;
        for (int64_t j = b; j < i; j++)
            if (mesh->cell_conn[j] == mesh->cell_conn[i])
                return 0;
    }
    return 1;
}

int tpk_topo_face_count(const tpk_mesh *mesh, int64_t cell)
{
    int64_t begin = mesh->cell_offsets[cell];
    const tpk_cell_shape *t = table_for(mesh->cell_types[cell], mesh->cell_offsets[cell + 1] - begin);
    return t ? t->face_count : poly_faces(mesh, cell, NULL);
}

int tpk_topo_cell_faces(const tpk_mesh *mesh, int64_t cell, tpk_topo_face *faces)
{
    int64_t begin = mesh->cell_offsets[cell];
    const tpk_cell_shape *t = table_for(mesh->cell_types[cell], mesh->cell_offsets[cell + 1] - begin);
    if (!t)
        return poly_faces(mesh, cell, faces);
    const int32_t *nodes = mesh->cell_conn + begin;
    for (int f = 0; f < t->face_count; f++) {
        faces[f].n = t->face_size[f];
        for (int i = 0; i < t->face_size[f]; i++)
            faces[f].v[i] = nodes[t->faces[f][i]];
    }
    return t->face_count;
}

void tpk_topo_cell_face(const tpk_mesh *mesh, int64_t cell, int local, tpk_topo_face *face)
{
    int64_t begin = mesh->cell_offsets[cell];
    const tpk_cell_shape *t = table_for(mesh->cell_types[cell], mesh->cell_offsets[cell + 1] - begin);
    if (!t) {
        tpk_topo_face all[TPK_TOPO_MAX_CELL_FACES];
        poly_faces(mesh, cell, all);
        *face = all[local];
        return;
    }
    const int32_t *nodes = mesh->cell_conn + begin;
    face->n = t->face_size[local];
    for (int i = 0; i < t->face_size[local]; i++)
        face->v[i] = nodes[t->faces[local][i]];
}

void tpk_topo_face_triangle(const tpk_topo_face *f, int t, int32_t tri[3])
{
    int m = tpk_topo_min_index(f), n = f->n;
    tri[0] = f->v[m];
    tri[1] = f->v[(m + 1 + t) % n];
    tri[2] = f->v[(m + 2 + t) % n];
}

void tpk_topo_face_centre(const double *points, const tpk_topo_face *f, double out[3])
{
    for (int k = 0; k < 3; k++) {
        double sum = 0;
        for (int i = 0; i < f->n; i++)
            sum += points[3 * (int64_t)f->v[i] + k];
        out[k] = sum / f->n;
    }
}

int tpk_topo_orient(const double *points, int32_t a, int32_t b, int32_t c, int32_t d)
{
    const double *pa = points + 3 * (int64_t)a, *pb = points + 3 * (int64_t)b;
    const double *pc = points + 3 * (int64_t)c, *pd = points + 3 * (int64_t)d;
    int s = tpk_orient3d_filter(pa, pb, pc, pd);
    return s ? s : tpk_orient3d_exact(pa, pb, pc, pd);
}

uint32_t tpk_uf_find(uint32_t *parent, uint32_t x)
{
    for (;;) {
        uint32_t p = __atomic_load_n(&parent[x], __ATOMIC_RELAXED);
        if (p == x)
            return x;
        uint32_t g = __atomic_load_n(&parent[p], __ATOMIC_RELAXED);
        if (g != p) /* path halving; a lost race only leaves a longer path */
            __atomic_compare_exchange_n(&parent[x], &p, g, 0, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
        x = g;
    }
}

void tpk_uf_union(uint32_t *parent, uint32_t a, uint32_t b)
{
    /* Most unions of a connected mesh find both cells already under one parent: no walk needed. */
    if (__atomic_load_n(&parent[a], __ATOMIC_RELAXED) == __atomic_load_n(&parent[b], __ATOMIC_RELAXED))
        return;
    for (;;) {
        a = tpk_uf_find(parent, a);
        b = tpk_uf_find(parent, b);
        if (a == b)
            return;
        if (a < b) {
            uint32_t t = a;
            a = b;
            b = t;
        }
        uint32_t expected = a; /* a is still a root: link it under the smaller root b */
        if (__atomic_compare_exchange_n(&parent[a], &expected, b, 0, __ATOMIC_RELAXED, __ATOMIC_RELAXED))
            return;
    }
}
