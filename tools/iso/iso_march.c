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

/* Edge ids (first-seen order) fit 31 bits: the vertex count is checked against 2^31 - 1 as they grow.
 * The top bit of a head marks a hub: a mesh vertex that is the lower end of more than HUB_CHAIN
 * crossed edges, whose edges are then found through a hash table instead of its chain. */
#define EDGE_NONE UINT32_MAX
#define HUB_BIT 0x80000000u
#define HUB_CHAIN 24

typedef struct hub_table {
    uint64_t *keys; /* 0: empty (no edge key is 0: its upper id is above its lower) */
    uint32_t *edges;
    int64_t count, cap;
} hub_table;

/* A crossed mesh edge: its upper vertex (the lower one is the chain's: head[a]) and the edge seen before
 * it at the same lower vertex; once ranked (rank_edges), its vertex instead. */
typedef struct edge_link {
    uint32_t upper;
    union {
        uint32_t next, vertex;
    };
} edge_link;

/* A worker's active tets from count_range, in tet order, cases 1 to 14 only: (tet << 4) | case (bit k:
 * corner k at or above the value), 8 bytes. The emission reads the tets again, prefetched, which costs
 * less than the fresh pages of a copy of them (16 bytes a tet; grid 120: 1.8M active tets). */
typedef struct active_list {
    uint64_t *tets;
    int64_t count, cap;
} active_list;

typedef struct march {
    const tpk_iso_input *in;
    double value;
    float threshold;                           /* the least float s with (double)s >= value */
    int threads;
    uint8_t crossed[16][4];                    /* per case: its crossed tet edges, ascending; the third twice
                                                  where 3 are crossed */
    uint8_t corner_edge[16][6];                /* per case: iso_cases' edges, the first triangle twice
                                                  where it makes one */
    uint8_t case_triangles[256];               /* per case with its NaN bits: 0 with a NaN, for 0 and 15 */
    int64_t worker_first[TPK_MAX_THREADS + 1]; /* first triangle of each worker's tets */
    uint8_t *side;                             /* per mesh vertex: 1 at or above the value, 16 for a NaN */
    active_list active[TPK_MAX_THREADS];       /* per worker; kept across values */
    int failed;                                /* a worker's active list could not grow */
    uint64_t *head;                            /* per mesh vertex: its newest edge as lower end (HEAD_EMPTY) */
    uint64_t *corner_key;                      /* from tpk_iso_corners: 3 per triangle, (a << 32) | b, a < b */
    edge_link *edges;                          /* first-seen order; this and below kept across values */
    int64_t edge_count, edge_cap;
    hub_table hubs;
    double *normal_sum;                        /* 3 per vertex: its triangles' normals, summed in corner order */
    int64_t normal_cap;                        /* its capacity: kept across values, like edges */
    struct key_edge *run;                      /* rank_edges: one lower vertex's edges */
    int64_t run_cap;
    tpk_iso_surface *out;
    int64_t vertex_base, triangle_base;
    const tpk_iso_corners *corners;            /* NULL: count_range and edges_of_tets find the triangles */
} march;

/* Each mesh vertex's side of the value: 1 at or above it, 0 below, 16 for a NaN. `threshold` is the
 * value rounded up to float, so comparing the floats decides as comparing them in double with the value
 * would. A tet's case is then its corners' sides shifted into place: bits 4 to 7 are set for a NaN. */
static void side_range(void *ctx, int64_t begin, int64_t end, int w)
{
    (void)w;
    march *m = ctx;
    const float *s = m->in->scalars;
    float thr = m->threshold;
    for (int64_t v = begin; v < end; v++)
        m->side[v] = (uint8_t)((s[v] >= thr) | (s[v] != s[v]) << 4);
}

#define COUNT_BLOCK 4096

/* Room for `first` tets (first a quarter of the tets, on huge pages: tpk_alloc_large), then twice as many. */
static int grow_active(active_list *list, int64_t first)
{
    int64_t cap = list->cap ? 2 * list->cap : first;
    uint64_t *tets = list->tets ? realloc(list->tets, (size_t)cap * sizeof *tets)
                                : tpk_alloc_large((size_t)cap * sizeof *tets);
    if (!tets)
        return -1;
    list->tets = tets;
    list->cap = cap;
    return 0;
}

/* Count the triangles of the tets in [begin, end) and list the tets that make some. Compaction without
 * branches: every tet is written, the count advances past the active ones only, so inactive tets cost
 * four byte loads from `side` and no mispredicted branch. */
static void count_range(void *ctx, int64_t begin, int64_t end, int w)
{
    march *m = ctx;
    const int32_t *tets = m->in->tets;
    const uint8_t *side = m->side;
    active_list *list = &m->active[w];
    int64_t n = 0, triangles = 0;
    for (int64_t b = begin; b < end; b += COUNT_BLOCK) {
        int64_t e = end - b < COUNT_BLOCK ? end : b + COUNT_BLOCK;
        if (n + COUNT_BLOCK > list->cap && grow_active(list, (end - begin) / 4 + COUNT_BLOCK)) {
            m->failed = 1;
            break;
        }
        uint64_t *out = list->tets;
        for (int64_t t = b; t < e; t++) {
            const int32_t *v = tets + 4 * t;
            __builtin_prefetch(v + 4 * 64);
            unsigned c = side[v[0]] | side[v[1]] << 1 | side[v[2]] << 2 | side[v[3]] << 3;
            unsigned count = m->case_triangles[c];
            out[n] = (uint64_t)t << 4 | (c & 15);
            n += count != 0;
            triangles += count;
        }
    }
    list->count = n;
    m->worker_first[w + 1] = triangles;
}

/* ---- Vertices shared by edge ---------------------------------------------------------------------- */

static uint64_t hub_slot(const hub_table *h, uint64_t key)
{
    return (key * 0x9E3779B97F4A7C15ull >> 17) & (uint64_t)(h->cap - 1);
}

static uint32_t hub_find(const hub_table *h, uint64_t key)
{
    for (uint64_t i = hub_slot(h, key);; i = (i + 1) & (uint64_t)(h->cap - 1)) {
        if (h->keys[i] == key)
            return h->edges[i];
        if (!h->keys[i])
            return EDGE_NONE;
    }
}

static int hub_insert(hub_table *h, uint64_t key, uint32_t edge)
{
    if (2 * (h->count + 1) > h->cap) {
        hub_table g = {NULL, NULL, 0, h->cap ? 2 * h->cap : 1024};
        g.keys = calloc((size_t)g.cap, sizeof *g.keys);
        g.edges = malloc((size_t)g.cap * sizeof *g.edges);
        if (!g.keys || !g.edges) {
            free(g.keys);
            free(g.edges);
            return -1;
        }
        for (int64_t i = 0; i < h->cap; i++)
            if (h->keys[i])
                hub_insert(&g, h->keys[i], h->edges[i]);
        free(h->keys);
        free(h->edges);
        *h = g;
    }
    uint64_t i = hub_slot(h, key);
    while (h->keys[i])
        i = (i + 1) & (uint64_t)(h->cap - 1);
    h->keys[i] = key;
    h->edges[i] = edge;
    h->count++;
    return 0;
}

/* A head: its chain's newest edge (or EDGE_NONE, and HUB_BIT) in the low 32 bits, and above them one bit
 * per upper vertex of its edges by a hash of its id: a clear bit tells that an edge is new without the
 * walk down the chain, which the lookup of most new edges then skips. */
#define HEAD_EMPTY ((uint64_t)EDGE_NONE)

static inline uint64_t upper_bit(uint32_t upper)
{
    return (uint64_t)1 << (32 + ((upper * 0x9E3779B1u) >> 27));
}

/* Lower vertex a's chain is long: its edges go to the hub table, and its lookups too from now on. */
static int make_hub(march *m, uint32_t a)
{
    for (uint32_t e = (uint32_t)m->head[a]; e != EDGE_NONE; e = m->edges[e].next)
        if (hub_insert(&m->hubs, (uint64_t)a << 32 | m->edges[e].upper, e))
            return -1;
    m->head[a] |= HUB_BIT;
    return 0;
}

/* The edge of `key`, made when new. EDGE_NONE when out of memory or at 2^31 - 1 edges. */
static __attribute__((noinline)) uint32_t edge_of_slow(march *m, uint64_t key)
{
    uint32_t a = (uint32_t)(key >> 32), head = (uint32_t)m->head[a];
    int chain = 0;
    if (head != EDGE_NONE && (head & HUB_BIT)) {
        uint32_t e = hub_find(&m->hubs, key);
        if (e != EDGE_NONE)
            return e;
    } else {
        for (uint32_t e = head; e != EDGE_NONE; e = m->edges[e].next, chain++)
            if (m->edges[e].upper == (uint32_t)key)
                return e;
    }
    if (m->edge_count == m->edge_cap) {
        int64_t cap = 2 * m->edge_cap < (int64_t)HUB_BIT - 1 ? 2 * m->edge_cap : (int64_t)HUB_BIT - 1;
        edge_link *grown = m->edge_count < cap ? realloc(m->edges, (size_t)cap * sizeof *grown) : NULL;
        if (!grown)
            return EDGE_NONE;
        m->edges = grown;
        m->edge_cap = cap;
    }
    uint32_t e = (uint32_t)m->edge_count++;
    int hub = head != EDGE_NONE && (head & HUB_BIT);
    m->edges[e] = (edge_link){(uint32_t)key, {head == EDGE_NONE ? EDGE_NONE : head & ~HUB_BIT}};
    m->head[a] = (m->head[a] >> 32 << 32 | upper_bit((uint32_t)key)) | e | (hub ? HUB_BIT : 0);
    if (hub ? hub_insert(&m->hubs, key, e) : chain >= HUB_CHAIN && make_hub(m, a))
        return EDGE_NONE;
    return e;
}

/* edge_of_slow, its common case inline: a vertex that is no hub, an edge array with room. */
static inline uint32_t edge_of(march *m, uint64_t key)
{
    uint32_t a = (uint32_t)(key >> 32);
    uint64_t h = m->head[a], bit = upper_bit((uint32_t)key);
    uint32_t head = (uint32_t)h;
    if ((head != EDGE_NONE && (head & HUB_BIT)) || m->edge_count == m->edge_cap)
        return edge_of_slow(m, key);
    if (h & bit) {
        int chain = 0;
        for (uint32_t e = head; e != EDGE_NONE; e = m->edges[e].next, chain++)
            if (m->edges[e].upper == (uint32_t)key)
                return e;
        if (chain >= HUB_CHAIN)
            return edge_of_slow(m, key);
    }
    uint32_t e = (uint32_t)m->edge_count++;
    m->edges[e] = (edge_link){(uint32_t)key, {head}};
    m->head[a] = (h >> 32 << 32 | bit) | e;
    return e;
}

/* The edges looked up last, by a hash of their key. Every active tet around a crossed edge looks it up
 * (5 times per edge on grid 55 at 0.3), mostly close together in tet order, so 1024 slots (12 KB, in L1)
 * answer 97% of the repeated lookups (442,740 of 456,088) without the head and chain reads, which miss
 * the cache. */
#define RECENT_BITS 10

typedef struct recent_edges {
    uint64_t key[1 << RECENT_BITS]; /* 0: empty (no edge key is 0) */
    uint32_t edge[1 << RECENT_BITS];
} recent_edges;

/* edge_of through `recent`. */
static inline uint32_t recent_edge_of(march *m, recent_edges *recent, uint64_t key)
{
    unsigned slot = (unsigned)((key * 0x9E3779B97F4A7C15ull) >> (64 - RECENT_BITS));
    if (recent->key[slot] == key)
        return recent->edge[slot];
    uint32_t e = edge_of(m, key);
    recent->key[slot] = key;
    recent->edge[slot] = e;
    return e;
}

typedef struct key_edge {
    uint32_t key, edge; /* key: the upper vertex */
} key_edge;

/* *p holds at least `count` elements of `size` bytes (*cap of them), its contents kept. */
static int reserve(void **p, int64_t *cap, int64_t count, size_t size)
{
    if (*p && count <= *cap)
        return 0;
    int64_t want = count > 2 * *cap ? count : 2 * *cap;
    void *q = *p ? realloc(*p, (size_t)want * size) : tpk_alloc_large((size_t)want * size);
    if (!q)
        return -1;
    *p = q;
    *cap = want;
    return 0;
}

static int compare_key_edge(const void *pa, const void *pb)
{
    uint32_t a = ((const key_edge *)pa)->key, b = ((const key_edge *)pb)->key;
    return (a > b) - (a < b);
}

/* Number the edges by key: every lower vertex in order, its chain's edges sorted by upper vertex, their
 * ids written to the vertices' out->edge. Frees the heads for the next value, also when it fails
 * (`failed` set). Returns the vertex count, -1 without memory. */
static int64_t rank_edges(march *m, int failed)
{
    int32_t *out_edge = failed ? NULL : m->out->edge + 2 * m->vertex_base;
    int64_t vertices = 0;
    for (int64_t a = 0; a < m->in->vertex_count && vertices < m->edge_count; a++) {
        if ((uint32_t)m->head[a] == EDGE_NONE)
            continue;
        int64_t count = 0;
        for (uint32_t e = (uint32_t)m->head[a] & ~HUB_BIT; e != EDGE_NONE && !failed; e = m->edges[e].next) {
            if (count == m->run_cap && reserve((void **)&m->run, &m->run_cap, count + 64, sizeof *m->run))
                failed = 1;
            else
                m->run[count++] = (key_edge){m->edges[e].upper, e};
        }
        m->head[a] = HEAD_EMPTY;
        if (failed)
            continue;
        key_edge *run = m->run;
        if (count > HUB_CHAIN) {
            qsort(run, (size_t)count, sizeof *run, compare_key_edge);
        } else {
            for (int64_t i = 1; i < count; i++) {
                key_edge x = run[i];
                int64_t j = i;
                for (; j > 0 && run[j - 1].key > x.key; j--)
                    run[j] = run[j - 1];
                run[j] = x;
            }
        }
        for (int64_t i = 0; i < count; i++) {
            m->edges[run[i].edge].vertex = (uint32_t)vertices;
            out_edge[2 * vertices] = (int32_t)a;
            out_edge[2 * vertices++ + 1] = (int32_t)run[i].key;
        }
    }
    if (m->hubs.count) {
        memset(m->hubs.keys, 0, (size_t)m->hubs.cap * sizeof *m->hubs.keys);
        m->hubs.count = 0;
    }
    return failed ? -1 : vertices;
}

/* Each corner's edge into `corner` (3 per triangle), from the workers' active tets in tet order: a tet's
 * crossed edges are looked up once each, most of them found in `recent` (tets near each other in the file
 * share edges). */
#define ACTIVE_AHEAD 16

static int edges_of_tets(march *m, recent_edges *recent, uint32_t *corner)
{
    for (int w = 0; w < m->threads; w++) {
        const active_list *list = &m->active[w];
        for (int64_t i = 0; i < list->count; i++) {
            if (i + ACTIVE_AHEAD < list->count)
                __builtin_prefetch(m->in->tets + 4 * (list->tets[i + ACTIVE_AHEAD] >> 4));
            const int32_t *v = m->in->tets + 4 * (list->tets[i] >> 4);
            int c = (int)(list->tets[i] & 15);
            uint32_t edge[6];
            /* Four lookups and six corners whatever the case, so no branch on it is mispredicted: a tet
             * with 3 crossed edges looks its third up again (found in `recent`, just put there), one with
             * one triangle writes it twice (the second copy overwritten by the next tet's, or in the
             * array's slack at the end). */
            for (int j = 0; j < 4; j++) {
                int k = m->crossed[c][j];
                uint32_t a = (uint32_t)v[tet_edges[k][0]], b = (uint32_t)v[tet_edges[k][1]];
                uint32_t lo = a < b ? a : b, hi = a < b ? b : a; /* selects, not a mispredicted branch */
                if ((edge[k] = recent_edge_of(m, recent, (uint64_t)lo << 32 | hi)) == EDGE_NONE)
                    return -1;
            }
            for (int k = 0; k < 6; k++)
                corner[k] = edge[m->corner_edge[c][k]];
            corner += 3 * iso_cases[c].count;
        }
    }
    return 0;
}

static int grow_surface(tpk_iso_surface *o, int64_t vertices, int64_t triangles);

/* Share the corners' vertices: each corner's edge into `corner` (3 per triangle), the surface's arrays
 * grown for one vertex per edge, then the edges numbered by key. Returns the vertex count, -1 without
 * memory or at 2^31 - 1 edges or vertices in all. */
static int64_t number_vertices(march *m, int64_t triangles, uint32_t *corner)
{
    int64_t corners = 3 * triangles;
    m->edge_count = 0;
    if (reserve((void **)&m->edges, &m->edge_cap, corners / 4 + 64, sizeof *m->edges))
        return -1;
    int failed = 0;
    recent_edges recent;
    memset(recent.key, 0, sizeof recent.key);
    if (m->corners) {
        for (int64_t c = 0; c < corners && !failed; c++)
            failed = (corner[c] = recent_edge_of(m, &recent, m->corner_key[c])) == EDGE_NONE;
    } else {
        failed = edges_of_tets(m, &recent, corner);
    }
    tpk_iso_surface *o = m->out;
    failed = failed || o->vertex_count + m->edge_count > INT32_MAX ||
             reserve((void **)&m->normal_sum, &m->normal_cap, 3 * m->edge_count, sizeof *m->normal_sum) ||
             grow_surface(o, o->vertex_count + m->edge_count, o->triangle_count + triangles);
    int64_t vertices = rank_edges(m, failed); /* also when failed: it frees the heads */
    return failed ? -1 : vertices;
}

static void position_of(const march *m, uint32_t a, uint32_t b, double *t_out, double p[3])
{
    const float *pos = m->in->positions, *s = m->in->scalars;
    double t = (m->value - s[a]) / ((double)s[b] - s[a]);
    for (int k = 0; k < 3; k++)
        p[k] = pos[3 * a + k] + t * ((double)pos[3 * b + k] - pos[3 * a + k]);
    *t_out = t;
}

/* Positions relative to the origin (in xyz until normal_range adds it: the normals need them), values
 * and colours of the vertices from their edges; their normal sums cleared. */
static void vertex_range(void *ctx, int64_t begin, int64_t end, int w)
{
    (void)w;
    march *m = ctx;
    tpk_iso_surface *o = m->out;
    for (int64_t v = begin; v < end; v++) {
        int64_t out = m->vertex_base + v;
        uint32_t a = (uint32_t)o->edge[2 * out], b = (uint32_t)o->edge[2 * out + 1];
        double t;
        position_of(m, a, b, &t, o->xyz + 3 * out);
        for (int k = 0; k < 3; k++)
            m->normal_sum[3 * v + k] = 0.0;
        o->value[out] = (float)m->value;
        if (o->color)
            o->color[out] = (float)(m->in->colors[a] + t * ((double)m->in->colors[b] - m->in->colors[a]));
    }
}

/* The triangles' corners from edges to vertices, and each vertex's sum of its triangles' area-weighted
 * normals in the order of its corners (triangle order: a vertex is in a triangle once), on one thread,
 * so the sums do not depend on the thread count. */
static void sum_normals(march *m, int64_t triangles)
{
    uint32_t *tri = m->out->tri + 3 * m->triangle_base;
    const double *rel = m->out->xyz + 3 * m->vertex_base;
    for (int64_t f = 0; f < triangles; f++, tri += 3) {
        const double *p[3];
        uint32_t v[3];
        for (int k = 0; k < 3; k++) {
            v[k] = m->edges[tri[k]].vertex;
            tri[k] = (uint32_t)(m->vertex_base + v[k]);
            p[k] = rel + 3 * v[k];
        }
        double ax = p[1][0] - p[0][0], ay = p[1][1] - p[0][1], az = p[1][2] - p[0][2];
        double bx = p[2][0] - p[0][0], by = p[2][1] - p[0][1], bz = p[2][2] - p[0][2];
        double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
        for (int k = 0; k < 3; k++) {
            double *sum = m->normal_sum + 3 * v[k];
            sum[0] += nx;
            sum[1] += ny;
            sum[2] += nz;
        }
    }
}

/* The unit normals, and the origin added to the positions. */
static void normal_range(void *ctx, int64_t begin, int64_t end, int w)
{
    (void)w;
    march *m = ctx;
    const float *pos = m->in->positions, *s = m->in->scalars;
    for (int64_t v = begin; v < end; v++) {
        int64_t out = m->vertex_base + v;
        double *n = m->normal_sum + 3 * v, *xyz = m->out->xyz + 3 * out;
        for (int k = 0; k < 3; k++)
            xyz[k] = m->in->origin[k] + xyz[k];
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0) || !isfinite(len)) { /* only zero-area triangles here: the edge, toward higher */
            uint32_t a = (uint32_t)m->out->edge[2 * out], b = (uint32_t)m->out->edge[2 * out + 1];
            double up = s[b] > s[a] ? 1 : -1;
            for (int k = 0; k < 3; k++)
                n[k] = up * ((double)pos[3 * b + k] - pos[3 * a + k]);
            len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
        float *normal = m->out->normal + 3 * out;
        for (int k = 0; k < 3; k++)
            normal[k] = len > 0 ? (float)(n[k] / len) : 0.0f;
    }
}

/* Fresh arrays through tpk_alloc_large: on huge pages, their first touch faults far less often. */
static int grow(void **p, int64_t count, size_t size)
{
    size_t bytes = (size_t)(count ? count : 1) * size;
    void *q = *p ? realloc(*p, bytes) : tpk_alloc_large(bytes);
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
           grow((void **)&o->edge, 2 * vertices, sizeof(int32_t)) || grow((void **)&o->tri, 3 * triangles + 3, sizeof(uint32_t));
}

/* The GPU's corner keys of one value. The rest of the scratch is kept for the next value (free_march). */
static void free_scratch(march *m)
{
    free(m->corner_key);
    m->corner_key = NULL;
}

/* The least float at or above `value` (finite). */
static float float_at_or_above(double value)
{
    float f = (float)value;
    if ((double)f < value)
        return nextafterf(f, INFINITY);
    float below = nextafterf(f, -INFINITY);
    return (double)below >= value ? below : f;
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
        m->threshold = float_at_or_above(m->value);
        memset(m->worker_first, 0, sizeof m->worker_first);
        int64_t verts = m->in->vertex_count;
        tpk_parallel_for(verts, tpk_threads_for(verts, m->threads, 65536), side_range, m);
        tpk_parallel_for(tets, m->threads, count_range, m);
        if (m->failed)
            return tpk_diag_fail(diag, "out of memory for the active tets of the isosurface of %g", m->value);
        for (int w = 0; w < m->threads; w++)
            m->worker_first[w + 1] += m->worker_first[w];
        triangles = m->worker_first[m->threads];
    }
    if (o->triangle_count + triangles > INT32_MAX) {
        free_scratch(m);
        return tpk_diag_fail(diag, "the isosurface of %g has %lld triangles; more than 2^31 - 1 triangles or vertices "
                             "in all do not fit the outputs' 32-bit indices", m->value, (long long)triangles);
    }
    if (grow((void **)&o->tri, 3 * (o->triangle_count + triangles) + 3, sizeof(uint32_t))) /* + edges_of_tets' slack */
        goto fail;
    m->vertex_base = o->vertex_count;
    m->triangle_base = o->triangle_count;
    int64_t vertices = number_vertices(m, triangles, o->tri + 3 * o->triangle_count);
    if (vertices < 0)
        goto fail;
    tpk_parallel_for(vertices, tpk_threads_for(vertices, m->threads, 4096), vertex_range, m);
    sum_normals(m, triangles);
    tpk_parallel_for(vertices, tpk_threads_for(vertices, m->threads, 4096), normal_range, m);
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

static void free_march(march *m)
{
    free_scratch(m);
    free(m->edges);
    free(m->normal_sum);
    free(m->run);
    free(m->side);
    for (int w = 0; w < TPK_MAX_THREADS; w++)
        free(m->active[w].tets);
    free(m->head);
    free(m->hubs.keys);
    free(m->hubs.edges);
}

int tpk_iso_extract_from(const tpk_iso_input *in, const double *values, int value_count, int threads,
                         const tpk_iso_corners *corners, tpk_iso_surface *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    if (value_count < 1 || value_count > TPK_ISO_MAX_VALUES)
        return tpk_diag_fail(diag, "iso: %d values given; 1 to %d are allowed", value_count, TPK_ISO_MAX_VALUES);
    if (in->vertex_count > UINT32_MAX)
        return tpk_diag_fail(diag, "iso: %lld vertices; at most 2^32 - 1", (long long)in->vertex_count);
    for (int i = 0; i < value_count; i++)
        if (!isfinite(values[i]))
            return tpk_diag_fail(diag, "iso: value %g is not a finite number", values[i]);
    if (in->colors && !(out->color = malloc(sizeof *out->color)))
        return tpk_diag_fail(diag, "out of memory");
    march m;
    memset(&m, 0, sizeof m);
    m.in = in;
    m.out = out;
    m.corners = corners;
    m.head = tpk_alloc_large(sizeof *m.head * (size_t)(in->vertex_count ? in->vertex_count : 1));
    for (int64_t v = 0; m.head && v < in->vertex_count; v++)
        m.head[v] = HEAD_EMPTY;
    if (!m.head || (!corners && !(m.side = malloc((size_t)(in->vertex_count ? in->vertex_count : 1))))) {
        free_march(&m);
        tpk_iso_surface_free(out);
        return tpk_diag_fail(diag, "out of memory for the sides of %lld vertices", (long long)in->vertex_count);
    }
    m.threads = tpk_threads_for(in->tet_count, tpk_thread_count(threads), 65536);
    for (int c = 0; c < 16; c++)
        for (int k = 0, j = 0; k < 6; k++)
            if (((c >> tet_edges[k][0]) ^ (c >> tet_edges[k][1])) & 1)
                m.crossed[c][j++] = (uint8_t)k;
    for (int c = 0; c < 16; c++) {
        if (iso_cases[c].count == 1)
            m.crossed[c][3] = m.crossed[c][2];
        for (int k = 0; k < 6; k++)
            m.corner_edge[c][k] = iso_cases[c].edge[iso_cases[c].count == 1 ? k % 3 : k];
    }
    for (int c = 0; c < 256; c++)
        m.case_triangles[c] = c < 16 ? iso_cases[c].count : 0;
    for (int i = 0; i < value_count; i++) {
        m.value = values[i];
        if (extract_value(&m, diag) != 0) {
            free_march(&m);
            tpk_iso_surface_free(out);
            return -1;
        }
    }
    free_march(&m);
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
