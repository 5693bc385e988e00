/* Marching tetrahedra: triangles per tet from a fixed case table, one vertex per crossed tet edge and
 * value (numbered by the edge's two vertex ids), attributes per vertex. The rules are in iso.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "iso.h"

/* A tet's 6 edges as pairs of its corners. */
static const uint8_t tet_edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/* Triangles per case (bit k set: corner k is at or above the value), as edge triples, oriented so that
 * (b - a) x (c - a) points toward the corners above in any positively oriented tet (an affine map with
 * positive determinant keeps orientation, so the reference tet (0,0,0), (1,0,0), (0,1,0), (0,0,1)
 * decides). Two corners above: the quad cut along its first diagonal (inside the tet, so neighbours
 * need not agree). tests/test_iso.c checks every entry against that reference tet. */
static const struct {
    uint8_t count;
    uint8_t edge[6];
} iso_cases[16] = {
    {0, {0, 0, 0, 0, 0, 0}}, {1, {0, 2, 1, 0, 0, 0}}, {1, {0, 3, 4, 0, 0, 0}}, {2, {1, 3, 4, 1, 4, 2}},
    {1, {1, 5, 3, 0, 0, 0}}, {2, {0, 5, 3, 0, 2, 5}}, {2, {0, 1, 5, 0, 5, 4}}, {1, {2, 5, 4, 0, 0, 0}},
    {1, {2, 4, 5, 0, 0, 0}}, {2, {0, 4, 5, 0, 5, 1}}, {2, {0, 5, 2, 0, 3, 5}}, {1, {1, 3, 5, 0, 0, 0}},
    {2, {1, 2, 4, 1, 4, 3}}, {1, {0, 4, 3, 0, 0, 0}}, {1, {0, 1, 2, 0, 0, 0}}, {0, {0, 0, 0, 0, 0, 0}},
};

void tpk_iso_case_table(int mask, int *count, int edges[6], int corners[6][2])
{
    *count = iso_cases[mask & 15].count;
    for (int k = 0; k < 6; k++) {
        edges[k] = iso_cases[mask & 15].edge[k];
        corners[k][0] = tet_edges[k][0];
        corners[k][1] = tet_edges[k][1];
    }
}

typedef struct march {
    const tpk_iso_input *in;
    double value;
    int threads;
    int64_t worker_first[TPK_MAX_THREADS + 1]; /* first triangle of each worker's tets */
    uint64_t *corner_key;                      /* 3 per triangle: (a << 32) | b, a < b */
    int64_t *order;                            /* corners sorted by key */
    int64_t *vertex_first;                     /* per vertex + 1: its first corner in `order` */
    uint32_t *corner_vertex;                   /* per corner: its vertex (this value's numbering) */
    double *tri_normal;                        /* 3 per triangle, area-weighted */
    tpk_iso_surface *out;
    int64_t vertex_base, triangle_base;
    const tpk_iso_corners *corners;            /* NULL: count_range and emit_range make corner_key */
    uint8_t *cases;                            /* per tet: its case (count_range), 16 for none (a NaN) */
} march;

/* The case of tet t: bit k when corner k is at or above the value; -1 with a NaN. */
static inline int tet_case(const march *m, int64_t t)
{
    const int32_t *v = m->in->tets + 4 * t;
    const float *s = m->in->scalars;
    int mask = 0;
    for (int k = 0; k < 4; k++) {
        double x = s[v[k]];
        if (x != x)
            return -1;
        mask |= (x >= m->value) << k;
    }
    return mask;
}

static void count_range(void *ctx, int64_t begin, int64_t end, int w)
{
    march *m = ctx;
    int64_t n = 0;
    for (int64_t t = begin; t < end; t++) {
        int c = tet_case(m, t);
        m->cases[t] = (uint8_t)(c < 0 ? 16 : c); /* emit_range reads it, not the scalars again */
        n += c < 0 ? 0 : iso_cases[c].count;
    }
    m->worker_first[w + 1] = n;
}

static void emit_range(void *ctx, int64_t begin, int64_t end, int w)
{
    march *m = ctx;
    uint64_t *key = m->corner_key + 3 * m->worker_first[w];
    for (int64_t t = begin; t < end; t++) {
        int c = m->cases[t];
        if (c == 0 || c >= 15)
            continue;
        const int32_t *v = m->in->tets + 4 * t;
        for (int k = 0; k < 3 * iso_cases[c].count; k++) {
            const uint8_t *e = tet_edges[iso_cases[c].edge[k]];
            uint32_t a = (uint32_t)v[e[0]], b = (uint32_t)v[e[1]];
            *key++ = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
    }
}

typedef struct key_corner {
    uint64_t key;
    int64_t corner;
} key_corner;

static int compare_key_corner(const void *pa, const void *pb)
{
    const key_corner *a = pa, *b = pb;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return (a->corner > b->corner) - (a->corner < b->corner);
}

/* Sort one bucket of (key, corner) pairs by key, keeping corners ascending within a key (they arrive
 * ascending): insertion sort on the contiguous pairs for the usual few dozen, qsort on (key, corner)
 * for a vertex of many tets. */
static void sort_bucket(key_corner *b, int64_t count)
{
    if (count > 48) {
        qsort(b, (size_t)count, sizeof *b, compare_key_corner);
        return;
    }
    for (int64_t i = 1; i < count; i++) {
        key_corner x = b[i];
        int64_t j = i;
        for (; j > 0 && b[j - 1].key > x.key; j--)
            b[j] = b[j - 1];
        b[j] = x;
    }
}

/* Sort corners by (edge key, corner): a counting sort of (key, corner) pairs on the lower vertex, then
 * each bucket (the corners at one mesh vertex, a few dozen) by the upper; the pairs carry their keys,
 * so the sort reads no key through an index. Returns the number of distinct edges, -1 without memory. */
static int64_t number_vertices(march *m, int64_t corners)
{
    int64_t n = m->in->vertex_count;
    int64_t *start = calloc((size_t)n + 1, sizeof *start);
    key_corner *pairs = malloc(sizeof *pairs * (size_t)(corners ? corners : 1));
    if (!start || !pairs) {
        free(start);
        free(pairs);
        return -1;
    }
    for (int64_t c = 0; c < corners; c++)
        start[(m->corner_key[c] >> 32) + 1]++;
    for (int64_t a = 0; a < n; a++)
        start[a + 1] += start[a];
    for (int64_t c = 0; c < corners; c++) {
        uint64_t key = m->corner_key[c];
        pairs[start[key >> 32]++] = (key_corner){key, c};
    }
    /* start[a] is now the end of bucket a, the start of bucket a + 1 */
    for (int64_t a = 0, begin = 0; a < n; begin = start[a], a++)
        sort_bucket(pairs + begin, start[a] - begin);
    free(start);
    int64_t vertices = 0;
    for (int64_t i = 0; i < corners; i++) {
        int64_t c = pairs[i].corner;
        m->order[i] = c;
        if (i == 0 || pairs[i].key != pairs[i - 1].key)
            m->vertex_first[vertices++] = i;
        m->corner_vertex[c] = (uint32_t)(vertices - 1);
    }
    m->vertex_first[vertices] = corners;
    free(pairs);
    return vertices;
}

static void position_of(const march *m, uint64_t key, double *t_out, double p[3])
{
    const float *pos = m->in->positions, *s = m->in->scalars;
    uint32_t a = (uint32_t)(key >> 32), b = (uint32_t)key;
    double t = (m->value - s[a]) / ((double)s[b] - s[a]);
    for (int k = 0; k < 3; k++)
        p[k] = pos[3 * a + k] + t * ((double)pos[3 * b + k] - pos[3 * a + k]);
    *t_out = t;
}

static void triangle_range(void *ctx, int64_t begin, int64_t end, int w)
{
    (void)w;
    march *m = ctx;
    for (int64_t f = begin; f < end; f++) {
        double p[3][3], t;
        for (int k = 0; k < 3; k++)
            position_of(m, m->corner_key[3 * f + k], &t, p[k]);
        double e1[3], e2[3], *n = m->tri_normal + 3 * f;
        for (int k = 0; k < 3; k++)
            e1[k] = p[1][k] - p[0][k], e2[k] = p[2][k] - p[0][k];
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        uint32_t *tri = m->out->tri + 3 * (m->triangle_base + f);
        for (int k = 0; k < 3; k++)
            tri[k] = (uint32_t)(m->vertex_base + m->corner_vertex[3 * f + k]);
    }
}

static void vertex_range(void *ctx, int64_t begin, int64_t end, int w)
{
    (void)w;
    march *m = ctx;
    tpk_iso_surface *o = m->out;
    const float *pos = m->in->positions, *s = m->in->scalars;
    for (int64_t v = begin; v < end; v++) {
        int64_t out = m->vertex_base + v;
        uint64_t key = m->corner_key[m->order[m->vertex_first[v]]];
        uint32_t a = (uint32_t)(key >> 32), b = (uint32_t)key;
        double p[3], t, n[3] = {0, 0, 0};
        position_of(m, key, &t, p);
        for (int64_t i = m->vertex_first[v]; i < m->vertex_first[v + 1]; i++)
            for (int k = 0; k < 3; k++)
                n[k] += m->tri_normal[3 * (m->order[i] / 3) + k];
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0) || !isfinite(len)) { /* only zero-area triangles here: the edge, toward higher */
            double up = s[b] > s[a] ? 1 : -1;
            for (int k = 0; k < 3; k++)
                n[k] = up * ((double)pos[3 * b + k] - pos[3 * a + k]);
            len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
        for (int k = 0; k < 3; k++) {
            o->xyz[3 * out + k] = m->in->origin[k] + p[k];
            o->normal[3 * out + k] = len > 0 ? (float)(n[k] / len) : 0.0f;
        }
        o->value[out] = (float)m->value;
        if (o->color)
            o->color[out] = (float)(m->in->colors[a] + t * ((double)m->in->colors[b] - m->in->colors[a]));
        o->edge[2 * out] = (int32_t)a;
        o->edge[2 * out + 1] = (int32_t)b;
    }
}

static int grow(void **p, int64_t count, size_t size)
{
    void *q = realloc(*p, (size_t)(count ? count : 1) * size);
    if (!q)
        return -1;
    *p = q;
    return 0;
}

static int grow_surface(tpk_iso_surface *o, int64_t vertices, int64_t triangles)
{
    return grow((void **)&o->xyz, 3 * vertices, sizeof(double)) || grow((void **)&o->normal, 3 * vertices, sizeof(float)) ||
           grow((void **)&o->value, vertices, sizeof(float)) ||
           (o->color && grow((void **)&o->color, vertices, sizeof(float))) ||
           grow((void **)&o->edge, 2 * vertices, sizeof(int32_t)) || grow((void **)&o->tri, 3 * triangles, sizeof(uint32_t));
}

static void free_scratch(march *m)
{
    free(m->corner_key);
    free(m->order);
    free(m->vertex_first);
    free(m->corner_vertex);
    free(m->tri_normal);
    m->corner_key = NULL, m->order = NULL, m->vertex_first = NULL, m->corner_vertex = NULL, m->tri_normal = NULL;
}

/* One value's surface, appended to m->out. */
static int extract_value(march *m, tpk_diag *diag)
{
    tpk_iso_surface *o = m->out;
    int64_t tets = m->in->tet_count, triangles;
    if (m->corners) { /* the triangles from elsewhere (the GPU) */
        if (m->corners->emit(m->corners->user, m->in, m->value, &m->corner_key, &triangles, diag) != 0)
            return -1;
    } else {
        memset(m->worker_first, 0, sizeof m->worker_first);
        tpk_parallel_for(tets, m->threads, count_range, m);
        for (int w = 0; w < m->threads; w++)
            m->worker_first[w + 1] += m->worker_first[w];
        triangles = m->worker_first[m->threads];
    }
    int64_t corners = 3 * triangles;
    if (o->triangle_count + triangles > INT32_MAX) {
        free_scratch(m);
        return tpk_diag_fail(diag, "the isosurface of %g has %lld triangles; more than 2^31 - 1 triangles or vertices "
                             "in all do not fit the outputs' 32-bit indices", m->value, (long long)triangles);
    }
    size_t c1 = (size_t)(corners ? corners : 1);
    if (!m->corners)
        m->corner_key = malloc(c1 * sizeof *m->corner_key);
    m->order = malloc(c1 * sizeof *m->order);
    m->vertex_first = malloc((c1 + 1) * sizeof *m->vertex_first);
    m->corner_vertex = malloc(c1 * sizeof *m->corner_vertex);
    m->tri_normal = malloc(c1 * sizeof *m->tri_normal);
    if (!m->corner_key || !m->order || !m->vertex_first || !m->corner_vertex || !m->tri_normal)
        goto fail;
    if (!m->corners)
        tpk_parallel_for(tets, m->threads, emit_range, m);
    int64_t vertices = number_vertices(m, corners);
    if (vertices < 0 || o->vertex_count + vertices > INT32_MAX)
        goto fail;
    if (grow_surface(o, o->vertex_count + vertices, o->triangle_count + triangles))
        goto fail;
    m->vertex_base = o->vertex_count;
    m->triangle_base = o->triangle_count;
    tpk_parallel_for(triangles, tpk_threads_for(triangles, m->threads, 4096), triangle_range, m);
    tpk_parallel_for(vertices, tpk_threads_for(vertices, m->threads, 4096), vertex_range, m);
    o->vertex_count += vertices;
    o->triangle_count += triangles;
    o->value_triangles[o->value_count] = triangles;
    o->value_vertices[o->value_count] = vertices;
    o->values[o->value_count++] = m->value;
    free_scratch(m);
    return 0;
fail:
    free_scratch(m);
    return tpk_diag_fail(diag, "out of memory (or beyond 2^31 - 1 vertices) for the isosurface of %g: %lld triangles",
                         m->value, (long long)triangles);
}

int tpk_iso_extract(const tpk_iso_input *in, const double *values, int value_count, int threads,
                    tpk_iso_surface *out, tpk_diag *diag)
{
    return tpk_iso_extract_from(in, values, value_count, threads, NULL, out, diag);
}

int tpk_iso_extract_from(const tpk_iso_input *in, const double *values, int value_count, int threads,
                         const tpk_iso_corners *corners, tpk_iso_surface *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    if (value_count < 1 || value_count > TPK_ISO_MAX_VALUES)
        return tpk_diag_fail(diag, "iso: %d values given; 1 to %d are allowed", value_count, TPK_ISO_MAX_VALUES);
    if (in->vertex_count > UINT32_MAX)
        return tpk_diag_fail(diag, "iso: %lld vertices; at most 2^32 - 1", (long long)in->vertex_count);
    if (in->colors && !(out->color = malloc(sizeof *out->color)))
        return tpk_diag_fail(diag, "out of memory");
    march m;
    memset(&m, 0, sizeof m);
    m.in = in;
    m.out = out;
    m.corners = corners;
    if (!corners && !(m.cases = malloc((size_t)(in->tet_count ? in->tet_count : 1)))) {
        tpk_iso_surface_free(out);
        return tpk_diag_fail(diag, "out of memory for the cases of %lld tets", (long long)in->tet_count);
    }
    m.threads = tpk_threads_for(in->tet_count, tpk_thread_count(threads), 65536);
    for (int i = 0; i < value_count; i++) {
        m.value = values[i];
        if (!isfinite(values[i])) {
            free(m.cases);
            tpk_iso_surface_free(out);
            return tpk_diag_fail(diag, "iso: value %g is not a finite number", values[i]);
        }
        if (extract_value(&m, diag) != 0) {
            free(m.cases);
            tpk_iso_surface_free(out);
            return -1;
        }
    }
    free(m.cases);
    return 0;
}

void tpk_iso_surface_free(tpk_iso_surface *s)
{
    free(s->xyz);
    free(s->normal);
    free(s->value);
    free(s->color);
    free(s->edge);
    free(s->tri);
    memset(s, 0, sizeof *s);
}
