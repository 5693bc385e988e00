/* Two imported meshes compared bit for bit (header-only): for tests that read one file two ways (in a
 * child process or not, on one thread or several) and need the very same mesh. */
#ifndef TPK_TEST_SAME_MESH_H
#define TPK_TEST_SAME_MESH_H

#include <string.h>

#include "mesh/mesh.h"
#include "tetpack_format.h"

static inline int tpk_same_array(const void *a, const void *b, size_t bytes)
{
    return (!a && !b) || (a && b && memcmp(a, b, bytes) == 0);
}

/* Bit for bit the same mesh: counts, arrays, fields, steps, format, grid origin, global ids. */
static inline int tpk_same_mesh(const tpk_mesh *a, const tpk_mesh *b)
{
    if (a->point_count != b->point_count || a->cell_count != b->cell_count || a->field_count != b->field_count ||
        a->step_count != b->step_count || strcmp(a->format, b->format) != 0 ||
        a->has_grid_origin != b->has_grid_origin || memcmp(a->grid_origin, b->grid_origin, sizeof a->grid_origin))
        return 0;
    size_t p = (size_t)a->point_count, c = (size_t)a->cell_count;
    if (!tpk_same_array(a->points, b->points, 3 * p * sizeof(double)) || !tpk_same_array(a->cell_types, b->cell_types, c) ||
        !tpk_same_array(a->cell_offsets, b->cell_offsets, (c + 1) * sizeof(int64_t)) ||
        !tpk_same_array(a->face_offsets, b->face_offsets, (c + 1) * sizeof(int64_t)) ||
        !tpk_same_array(a->times, b->times, (size_t)a->step_count * sizeof(double)) ||
        !tpk_same_array(a->global_point_ids, b->global_point_ids, p * sizeof(int64_t)) ||
        !tpk_same_array(a->global_cell_ids, b->global_cell_ids, c * sizeof(int64_t)))
        return 0;
    if (a->cell_offsets && !tpk_same_array(a->cell_conn, b->cell_conn, (size_t)a->cell_offsets[c] * sizeof(int32_t)))
        return 0;
    if (a->face_offsets && !tpk_same_array(a->faces, b->faces, (size_t)a->face_offsets[c] * sizeof(int32_t)))
        return 0;
    for (int i = 0; i < a->field_count; i++) {
        const tpk_src_field *f = &a->fields[i], *g = &b->fields[i];
        size_t n = (size_t)f->step_count * (f->association == TPK_ASSOC_POINT ? p : c) * (size_t)f->components;
        if (strcmp(f->name, g->name) || f->association != g->association || f->components != g->components ||
            f->step_count != g->step_count || !tpk_same_array(f->values, g->values, n * sizeof(float)))
            return 0;
    }
    return 1;
}

#endif
