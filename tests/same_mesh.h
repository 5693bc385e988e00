/* Two imported meshes compared bit for bit (header-only): for tests that read one file two ways (in a
 * child process or not, on one thread or several) and need the very same mesh; and an importer's reads of
 * one file on one thread and on several, which must give the same mesh or the same error. */
#ifndef TPK_TEST_SAME_MESH_H
#define TPK_TEST_SAME_MESH_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "base/diag.h"
#include "base/parallel.h"
#include "mesh/mesh.h"
#include "tetpack_format.h"

/* The grid the importers' thread-count tests write (test_cgns.c, test_exodus.c): n^3 hexahedra over
 * (n + 1)^3 points, each coordinate moved by 0.1 sin of another, so that no two cells are alike. Point v's
 * position, and cell c's corners (0-based, in the hexahedron's order): */
static inline void tpk_warped_grid_point(int64_t n, int64_t v, double p[3])
{
    int64_t i = v % (n + 1), j = v / (n + 1) % (n + 1), k = v / (n + 1) / (n + 1);
    p[0] = (double)i + 0.1 * sin((double)j), p[1] = (double)j + 0.1 * sin((double)k);
    p[2] = (double)k + 0.1 * sin((double)i);
}

static inline void tpk_warped_grid_cell(int64_t n, int64_t c, int64_t q[8])
{
    const int64_t row = n + 1, layer = row * row, b = c % n + row * (c / n % n) + layer * (c / n / n);
    const int64_t corner[8] = {b, b + 1, b + 1 + row, b + row, b + layer, b + 1 + layer, b + 1 + row + layer,
                               b + row + layer};
    memcpy(q, corner, sizeof corner);
}

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

/* An importer of a file by path (import/importers.h: tpk_import_exodus, tpk_import_cgns, ...). */
typedef int (*tpk_path_importer)(const char *path, tpk_mesh *out, tpk_diag *diag);

/* `path` read by `import` on `threads` threads (the process default, restored after): its return, the
 * mesh and the message. */
static inline int tpk_import_on(tpk_path_importer import, const char *path, int threads, tpk_mesh *m, tpk_diag *d)
{
    int previous = tpk_set_default_threads(threads);
    memset(d, 0, sizeof *d);
    int rc = import(path, m, d);
    tpk_set_default_threads(previous);
    return rc;
}

/* `path` read on one thread and on `threads`: 0 when both reads give the very same mesh, which *out then
 * holds (the caller frees it); else -1, and d->message says which read failed or that the meshes differ. */
static inline int tpk_import_same_on_threads(tpk_path_importer import, const char *path, int threads, tpk_mesh *out,
                                             tpk_diag *d)
{
    tpk_mesh one;
    if (tpk_import_on(import, path, 1, &one, d) != 0)
        return -1;
    int rc = tpk_import_on(import, path, threads, out, d);
    int same = rc == 0 && tpk_same_mesh(&one, out);
    tpk_mesh_free(&one);
    if (rc == 0 && !same) {
        tpk_mesh_free(out);
        snprintf(d->message, sizeof d->message, "%s: the mesh read on %d threads differs from the one on one", path,
                 threads);
    }
    return same ? 0 : -1;
}

/* `path` read on one thread and on `threads`, both of which must fail: 0 when they fail with the same
 * message and it contains `expected`; else -1, with what happened in `why`. */
static inline int tpk_import_fails_alike_on_threads(tpk_path_importer import, const char *path, int threads,
                                                    const char *expected, char *why, size_t cap)
{
    char message[2][sizeof ((tpk_diag *)0)->message];
    for (int k = 0; k < 2; k++) {
        tpk_mesh m;
        tpk_diag d;
        if (tpk_import_on(import, path, k ? threads : 1, &m, &d) == 0) {
            tpk_mesh_free(&m);
            snprintf(why, cap, "%s: read on %d thread(s), expected to fail", path, k ? threads : 1);
            return -1;
        }
        memcpy(message[k], d.message, sizeof message[k]);
    }
    if (strcmp(message[0], message[1]) || !strstr(message[0], expected)) {
        snprintf(why, cap, "'%s' against '%s' (expected '%s')", message[0], message[1], expected);
        return -1;
    }
    return 0;
}

#endif
