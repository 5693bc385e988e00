/* Array helpers for the surface readers: allocation, STL corner merging, and byte-order reads. */
#include "surface_build.h"

#include <stdlib.h>
#include <string.h>

#include "surface.h"

int tpk_surf_alloc(tpk_mesh *m, int64_t point_count, int64_t face_count, int64_t conn_count)
{
    m->points = malloc(sizeof(double) * 3 * (size_t)(point_count ? point_count : 1));
    m->cell_types = malloc((size_t)(face_count ? face_count : 1));
    m->cell_offsets = malloc(sizeof(int64_t) * (size_t)(face_count + 1));
    m->cell_conn = malloc(sizeof(int32_t) * (size_t)(conn_count ? conn_count : 1));
    if (!m->points || !m->cell_types || !m->cell_offsets || !m->cell_conn)
        return -1;
    m->point_count = point_count;
    m->cell_count = face_count;
    m->cell_offsets[0] = 0;
    return 0;
}

typedef struct corner_key {
    double xyz[3];
    int64_t index;
} corner_key;

/* Order corners by coordinates, then by index, so equal points sit together, first use first. */
static int corner_cmp(const void *pa, const void *pb)
{
    const corner_key *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->xyz[k] != b->xyz[k])
            return a->xyz[k] < b->xyz[k] ? -1 : 1;
    return a->index < b->index ? -1 : a->index > b->index;
}

int tpk_surf_from_corners(tpk_mesh *m, const double *corners, int64_t triangle_count)
{
    int64_t n = 3 * triangle_count;
    corner_key *order = malloc(sizeof(corner_key) * (size_t)(n ? n : 1));
    int32_t *first_of = malloc(sizeof(int32_t) * (size_t)(n ? n : 1)); /* corner -> its first twin */
    if (!order || !first_of || tpk_surf_alloc(m, n, triangle_count, n) != 0) {
        free(order);
        free(first_of);
        return -1;
    }
    for (int64_t i = 0; i < n; i++) {
        memcpy(order[i].xyz, corners + 3 * i, sizeof order[i].xyz);
        order[i].index = i;
    }
    qsort(order, (size_t)n, sizeof *order, corner_cmp);
    for (int64_t i = 0; i < n; i++) {
        const corner_key *k = &order[i], *prev = &order[i - (i > 0)];
        int same = i > 0 && k->xyz[0] == prev->xyz[0] && k->xyz[1] == prev->xyz[1] && k->xyz[2] == prev->xyz[2];
        first_of[k->index] = same ? first_of[prev->index] : (int32_t)k->index;
    }
    /* Number points in order of first use; a corner's first twin is always seen before it. */
    int64_t points = 0;
    for (int64_t i = 0; i < n; i++) {
        if (first_of[i] == i) {
            memcpy(m->points + 3 * points, corners + 3 * i, 3 * sizeof(double));
            m->cell_conn[i] = (int32_t)points++;
        } else {
            m->cell_conn[i] = m->cell_conn[first_of[i]];
        }
    }
    m->point_count = points;
    double *fitted = realloc(m->points, sizeof(double) * 3 * (size_t)(points ? points : 1));
    m->points = fitted ? fitted : m->points;
    for (int64_t f = 0; f < triangle_count; f++) {
        m->cell_types[f] = TPK_CELL_SURF_TRIANGLE;
        m->cell_offsets[f + 1] = 3 * (f + 1);
    }
    free(order);
    free(first_of);
    return 0;
}

uint32_t tpk_surf_u32(const unsigned char *p, int big_endian)
{
    if (big_endian)
        return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
    return (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

float tpk_surf_f32(const unsigned char *p, int big_endian)
{
    uint32_t bits = tpk_surf_u32(p, big_endian);
    float v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

double tpk_surf_f64(const unsigned char *p, int big_endian)
{
    uint64_t hi = tpk_surf_u32(p + (big_endian ? 0 : 4), big_endian);
    uint64_t lo = tpk_surf_u32(p + (big_endian ? 4 : 0), big_endian);
    uint64_t bits = hi << 32 | lo;
    double v;
    memcpy(&v, &bits, sizeof v);
    return v;
}
