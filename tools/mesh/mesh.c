/* Ownership helpers for the converter's in-memory meshes. */
#include "mesh.h"

#include <math.h>
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

void tpk_points_box_centre(const double *points, int64_t count, double centre[3])
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = 0; i < count; i++)
        for (int k = 0; k < 3; k++) {
            double x = points[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    for (int k = 0; k < 3; k++)
        centre[k] = count ? 0.5 * (lo[k] + hi[k]) : 0.0;
}
