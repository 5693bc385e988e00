/* Ownership helpers for the converter's in-memory meshes. */
#include "mesh.h"

#include <stdlib.h>
#include <string.h>

static void free_fields(tpk_src_field *fields, int count)
{
    for (int i = 0; i < count; i++)
        free(fields[i].values);
    free(fields);
}

void tpk_mesh_free(tpk_mesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->points);
    free(mesh->cell_types);
    free(mesh->cell_offsets);
    free(mesh->cell_conn);
    free(mesh->face_offsets);
    free(mesh->faces);
    free_fields(mesh->fields, mesh->field_count);
    free(mesh->times);
    memset(mesh, 0, sizeof *mesh);
}

int tpk_mesh_same_cells(const tpk_mesh *a, const tpk_mesh *b)
{
    return a->point_count == b->point_count && a->cell_count == b->cell_count &&
           !memcmp(a->points, b->points, sizeof *a->points * 3 * (size_t)a->point_count) &&
           !memcmp(a->cell_types, b->cell_types, (size_t)a->cell_count) &&
           !memcmp(a->cell_offsets, b->cell_offsets, sizeof *a->cell_offsets * (size_t)(a->cell_count + 1)) &&
           !memcmp(a->cell_conn, b->cell_conn, sizeof *a->cell_conn * (size_t)a->cell_offsets[a->cell_count]);
}

int tpk_mesh_add_field(tpk_mesh *mesh, const char *name, int association, int components,
                       int step_count, float *values)
{
    tpk_src_field *grown = realloc(mesh->fields, sizeof *grown * (size_t)(mesh->field_count + 1));
    if (!grown)
        return -1;
    mesh->fields = grown;
    tpk_src_field *f = &grown[mesh->field_count++];
    memset(f, 0, sizeof *f);
    strncpy(f->name, name, TPK_NAME_MAX - 1);
    f->association = association;
    f->components = components;
    f->step_count = step_count;
    f->values = values;
    return 0;
}

void tpk_tetmesh_free(tpk_tetmesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->points);
    free(mesh->vertex_source);
    free(mesh->tets);
    free(mesh->tet_source);
    free_fields(mesh->fields, mesh->field_count);
    free(mesh->times);
    memset(mesh, 0, sizeof *mesh);
}

int tpk_compare_int32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}
