/* Hilbert-curve reordering (pipeline stage 3): vertices sorted by the 3-D Hilbert index of their position,
 * quantized to 21 bits per axis in the mesh's bounding box (63-bit keys), then tets by their smallest
 * vertex id. Both sorts are stable (equal keys keep their old order), so the result depends on the input
 * only. Fields, vertex_source and tet_source follow. */
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "base/spread_bits.h"
#include "pipeline.h"

#define HILBERT_BITS 21
#define RADIX_BITS 11
#define RADIX_SIZE (1 << RADIX_BITS)

/* ---- Hilbert index ------------------------------------------------------------------------------ */

/* Hilbert index by a state machine over octants (Hamilton's formulation, "Compact Hilbert indices",
 * Dalhousie CS-2006-07): the state is an entry corner e (3 bits) and a direction d (0..2); at each level
 * the octant bits l are transformed to T(l) = rotr(l ^ e, d + 1), the digit is the inverse Gray code of
 * T(l), and (e, d) move on. `hilbert_table` tabulates that for all 24 states and 8 octants, so a key
 * costs one lookup per level; tests check that consecutive keys are adjacent cells. */
typedef struct hilbert_table {
    uint8_t digit[24][8];
    uint8_t next[24][8];
    /* Three levels at once (9 octant bits): digits << 5 | next state. 24 KB, stays in L1. */
    uint16_t step3[24][512];
} hilbert_table;

static unsigned rotr3(unsigned b, unsigned r)
{
    r %= 3;
    return ((b >> r) | (b << (3 - r))) & 7;
}

static unsigned gray(unsigned i)
{
    return i ^ (i >> 1);
}

static unsigned gray_inverse(unsigned g)
{
    return g ^ (g >> 1) ^ (g >> 2);
}

static unsigned trailing_ones(unsigned i)
{
    unsigned n = 0;
    while (i & 1) {
        i >>= 1;
        n++;
    }
    return n;
}

static unsigned entry_corner(unsigned w)
{
    return w == 0 ? 0 : gray(2 * ((w - 1) / 2));
}

static unsigned entry_direction(unsigned w)
{
    return w == 0 ? 0 : (w % 2 == 0 ? trailing_ones(w - 1) : trailing_ones(w)) % 3;
}

static void build_hilbert_table(hilbert_table *table)
{
    for (unsigned e = 0; e < 8; e++)
        for (unsigned d = 0; d < 3; d++)
            for (unsigned l = 0; l < 8; l++) {
                unsigned w = gray_inverse(rotr3(l ^ e, d + 1));
                unsigned rot = (d + 1) % 3, ew = entry_corner(w);
                unsigned e2 = e ^ (((ew << rot) | (ew >> (3 - rot))) & 7);
                unsigned d2 = (d + entry_direction(w) + 1) % 3;
                table->digit[e * 3 + d][l] = (uint8_t)w;
                table->next[e * 3 + d][l] = (uint8_t)(e2 * 3 + d2);
            }
    for (unsigned state = 0; state < 24; state++)
        for (unsigned bits = 0; bits < 512; bits++) {
            unsigned s = state, digits = 0;
            for (int level = 2; level >= 0; level--) {
                unsigned l = (bits >> (3 * level)) & 7;
                digits = digits << 3 | table->digit[s][l];
                s = table->next[s][l];
            }
            table->step3[state][bits] = (uint16_t)(digits << 5 | s);
        }
}

static uint64_t hilbert_key_with(const hilbert_table *table, uint32_t x, uint32_t y, uint32_t z)
{
    /* Interleave once (x bits at 3i+2, y at 3i+1, z at 3i), then walk 9 bits per lookup. */
    uint64_t octants = tpk_spread_bits3(x) << 2 | tpk_spread_bits3(y) << 1 | tpk_spread_bits3(z), key = 0;
    unsigned state = 0;
    for (int shift = 3 * HILBERT_BITS - 9; shift >= 0; shift -= 9) {
        unsigned entry = table->step3[state][(octants >> shift) & 511];
        key = key << 9 | entry >> 5;
        state = entry & 31;
    }
    return key;
}

/* For tests: the key of one grid cell (builds the table each call). */
uint64_t tpk_hilbert_key(uint32_t x, uint32_t y, uint32_t z);
uint64_t tpk_hilbert_key(uint32_t x, uint32_t y, uint32_t z)
{
    hilbert_table table;
    build_hilbert_table(&table);
    return hilbert_key_with(&table, x, y, z);
}

typedef struct box {
    double lo[3];
    double scale; /* grid cells per unit length, the same on every axis */
} box;

static uint32_t quantize(double v, double lo, double scale)
{
    double q = (v - lo) * scale;
    if (!(q > 0)) /* also NaN */
        return 0;
    if (q >= (double)((1u << HILBERT_BITS) - 1))
        return (1u << HILBERT_BITS) - 1;
    return (uint32_t)q;
}

/* The bounds of the points that are not NaN, per worker over a contiguous range, merged in worker order
 * by the same rule (the first value seen, then strictly smaller or larger ones): one pass's bounds. */
typedef struct bounds_job {
    const double *points;
    double lo[TPK_MAX_THREADS][3], hi[TPK_MAX_THREADS][3];
    int seen[TPK_MAX_THREADS];
} bounds_job;

static void bounds_range(void *ctx, int64_t begin, int64_t end, int w)
{
    bounds_job *job = ctx;
    double *lo = job->lo[w], *hi = job->hi[w];
    int seen = 0;
    for (int64_t v = begin; v < end; v++) {
        const double *p = job->points + 3 * v;
        if (!(p[0] == p[0] && p[1] == p[1] && p[2] == p[2]))
            continue;
        for (int a = 0; a < 3; a++) {
            if (!seen || p[a] < lo[a])
                lo[a] = p[a];
            if (!seen || p[a] > hi[a])
                hi[a] = p[a];
        }
        seen = 1;
    }
    job->seen[w] = seen;
}

static box bounding_box(const double *points, int64_t count, int threads)
{
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int seen = 0;
    bounds_job *job = malloc(sizeof *job);
    threads = job ? tpk_threads_for(count, threads, 65536) : 1;
    if (job) {
        job->points = points;
        tpk_parallel_for(count, threads, bounds_range, job);
    }
    for (int w = 0; job && w < threads; w++) {
        if (!job->seen[w])
            continue;
        for (int a = 0; a < 3; a++) {
            if (!seen || job->lo[w][a] < lo[a])
                lo[a] = job->lo[w][a];
            if (!seen || job->hi[w][a] > hi[a])
                hi[a] = job->hi[w][a];
        }
        seen = 1;
    }
    free(job);
    double extent = 0;
    for (int a = 0; a < 3; a++)
        if (hi[a] - lo[a] > extent)
            extent = hi[a] - lo[a];
    box b = {{lo[0], lo[1], lo[2]}, extent > 0 ? (double)((1u << HILBERT_BITS) - 1) / extent : 0};
    return b;
}

/* ---- keys, in parallel --------------------------------------------------------------------------- */

typedef struct key_job {
    const hilbert_table *table;
    const double *points;
    box bounds;
    uint64_t *keys;
    uint32_t *order;
} key_job;

static void key_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    key_job *job = ctx;
    const box *b = &job->bounds;
    (void)worker;
    for (int64_t i = begin; i < end; i++) {
        const double *p = job->points + 3 * i;
        job->keys[i] = hilbert_key_with(job->table, quantize(p[0], b->lo[0], b->scale),
                                        quantize(p[1], b->lo[1], b->scale), quantize(p[2], b->lo[2], b->scale));
        job->order[i] = (uint32_t)i;
    }
}

/* ---- stable parallel LSD radix sort of (key, index) pairs ---------------------------------------- */

typedef struct radix_job {
    uint64_t *keys, *keys_out;
    uint32_t *vals, *vals_out;
    int shift;
    int threads;
    int64_t (*counts)[RADIX_SIZE]; /* [threads][RADIX_SIZE]: counts, then start offsets */
} radix_job;

static void radix_count(void *ctx, int64_t begin, int64_t end, int worker)
{
    radix_job *job = ctx;
    int64_t *count = job->counts[worker];
    memset(count, 0, sizeof job->counts[0]);
    for (int64_t i = begin; i < end; i++)
        count[(job->keys[i] >> job->shift) & (RADIX_SIZE - 1)]++;
}

static void radix_scatter(void *ctx, int64_t begin, int64_t end, int worker)
{
    radix_job *job = ctx;
    int64_t *next = job->counts[worker];
    for (int64_t i = begin; i < end; i++) {
        int64_t at = next[(job->keys[i] >> job->shift) & (RADIX_SIZE - 1)]++;
        job->keys_out[at] = job->keys[i];
        job->vals_out[at] = job->vals[i];
    }
}

/* Sorts keys (< 2^63) with vals; tmp arrays of the same size. Result ends in keys/vals. */
static int radix_sort(uint64_t *keys, uint32_t *vals, uint64_t *keys_tmp, uint32_t *vals_tmp,
                      int64_t count, int threads)
{
    radix_job job = {keys, keys_tmp, vals, vals_tmp, 0, threads, NULL};
    job.counts = malloc(sizeof *job.counts * (size_t)threads);
    if (!job.counts)
        return -1;
    for (int shift = 0; shift < 3 * HILBERT_BITS; shift += RADIX_BITS) {
        job.shift = shift;
        tpk_parallel_for(count, threads, radix_count, &job);
        int64_t running = 0, largest = 0;
        for (int d = 0; d < RADIX_SIZE; d++) {
            int64_t in_digit = 0;
            for (int w = 0; w < threads; w++) {
                int64_t c = job.counts[w][d];
                job.counts[w][d] = running;
                running += c;
                in_digit += c;
            }
            if (in_digit > largest)
                largest = in_digit;
        }
        if (largest == count) /* one digit for all: this pass would not move anything */
            continue;
        tpk_parallel_for(count, threads, radix_scatter, &job);
        uint64_t *k = job.keys;
        uint32_t *v = job.vals;
        job.keys = job.keys_out;
        job.vals = job.vals_out;
        job.keys_out = k;
        job.vals_out = v;
    }
    if (job.keys != keys) {
        memcpy(keys, job.keys, sizeof *keys * (size_t)count);
        memcpy(vals, job.vals, sizeof *vals * (size_t)count);
    }
    free(job.counts);
    return 0;
}

/* order[new] = old, by Hilbert key; keys/tmp sized for count. */
static int hilbert_order(const hilbert_table *table, const double *points, int64_t count, box bounds,
                         uint32_t *order, int threads)
{
    uint64_t *keys = tpk_alloc_large(sizeof *keys * 2 * (size_t)(count ? count : 1));
    uint32_t *vals_tmp = tpk_alloc_large(sizeof *vals_tmp * (size_t)(count ? count : 1));
    int rc = -1;
    if (keys && vals_tmp) {
        key_job job = {table, points, bounds, keys, order};
        int key_threads = tpk_threads_for(count, threads, 16384);
        tpk_parallel_for(count, key_threads, key_range, &job);
        rc = radix_sort(keys, order, keys + count, vals_tmp, count, tpk_threads_for(count, threads, 65536));
    }
    tpk_free_large(keys, sizeof *keys * 2 * (size_t)(count ? count : 1));
    tpk_free_large(vals_tmp, sizeof *vals_tmp * (size_t)(count ? count : 1));
    return rc;
}

/* ---- applying the vertex permutation ------------------------------------------------------------- */

typedef struct permute_job {
    const uint32_t *order;   /* order[new] = old */
    const void *src;
    void *dst;
    size_t elem_size;        /* 4, 8, 12, 16 or 24 bytes */
} permute_job;

/* Element types of the sizes permuted here, so each copy is a plain load and store rather than a
 * memcpy call with a run-time size (23M calls on a 10M-tet mesh). */
typedef struct bytes12 {
    uint32_t w[3];
} bytes12;
typedef struct bytes16 {
    uint32_t w[4];
} bytes16;
typedef struct bytes24 {
    uint64_t w[3];
} bytes24;

#define GATHER(type)                                                          \
    for (int64_t i = begin; i < end; i++)                                     \
        ((type *)job->dst)[i] = ((const type *)job->src)[job->order[i]]

static void permute_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const permute_job *job = ctx;
    (void)worker;
    switch (job->elem_size) {
    case 4: GATHER(uint32_t); break;
    case 8: GATHER(uint64_t); break;
    case 12: GATHER(bytes12); break;
    case 16: GATHER(bytes16); break;
    case 24: GATHER(bytes24); break;
    default:
        for (int64_t i = begin; i < end; i++)
            memcpy((char *)job->dst + (size_t)i * job->elem_size,
                   (const char *)job->src + (size_t)job->order[i] * job->elem_size, job->elem_size);
    }
}

/* Replaces *array (count elements of elem_size) by its permutation; frees the old array. */
static int permute_array(void **array, int64_t count, size_t elem_size, const uint32_t *order, int threads)
{
    void *permuted = tpk_alloc_large(elem_size * (size_t)(count ? count : 1));
    if (!permuted)
        return -1;
    permute_job job = {order, *array, permuted, elem_size};
    tpk_parallel_for(count, tpk_threads_for(count, threads, 65536), permute_range, &job);
    tpk_free_large(*array, elem_size * (size_t)count);
    *array = permuted;
    return 0;
}

static int permute_fields(tpk_tetmesh *mesh, int association, int64_t count, const uint32_t *order,
                          int threads)
{
    float *tmp = tpk_alloc_large(sizeof *tmp * (size_t)(count ? count : 1));
    if (!tmp)
        return -1;
    for (int f = 0; f < mesh->field_count; f++) {
        if (mesh->fields[f].association != association)
            continue;
        for (int s = 0; s < mesh->fields[f].step_count; s++) {
            float *step = mesh->fields[f].values + (size_t)s * (size_t)count;
            permute_job job = {order, step, tmp, sizeof *tmp};
            tpk_parallel_for(count, tpk_threads_for(count, threads, 65536), permute_range, &job);
            memcpy(step, tmp, sizeof *tmp * (size_t)count);
        }
    }
    tpk_free_large(tmp, sizeof *tmp * (size_t)(count ? count : 1));
    return 0;
}

static int ensure_identity(int32_t **source, int64_t count)
{
    if (*source)
        return 0;
    *source = tpk_alloc_large(sizeof **source * (size_t)(count ? count : 1));
    if (!*source)
        return -1;
    for (int64_t i = 0; i < count; i++)
        (*source)[i] = (int32_t)i;
    return 0;
}

/* new_id[order[i]] = i: order is a permutation, so every slot is written once, by one worker. */
typedef struct invert_job {
    const uint32_t *order;
    int32_t *new_id;
} invert_job;

static void invert_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    const invert_job *job = ctx;
    (void)worker;
    for (int64_t i = begin; i < end; i++)
        job->new_id[job->order[i]] = (int32_t)i;
}

/* Points, vertex sources and point fields in the new order; new_id[old] = new for the tets. */
static int apply_vertex_order(tpk_tetmesh *mesh, const uint32_t *order, int32_t *new_id, int threads)
{
    int64_t n = mesh->vertex_count;
    if (ensure_identity(&mesh->vertex_source, n) ||
        permute_array((void **)&mesh->points, n, 3 * sizeof *mesh->points, order, threads) ||
        permute_array((void **)&mesh->vertex_source, n, sizeof *mesh->vertex_source, order, threads) ||
        permute_fields(mesh, TPK_ASSOC_POINT, n, order, threads))
        return -1;
    invert_job inv = {order, new_id};
    tpk_parallel_for(n, tpk_threads_for(n, threads, 65536), invert_range, &inv);
    return 0;
}

/* ---- the tets: renumbered, then by their smallest vertex ----------------------------------------- */

/* Tets in order of their smallest vertex id (the vertices are in curve order by now), ties in input
 * order. One counting sort instead of centroid keys and a 64-bit radix sort: tets that share a vertex end
 * up together and follow the vertex curve, which is the locality marching and face matching need, at a
 * fraction of the cost (bench/README "Figures behind code comments"). */
static int32_t min_vertex(const int32_t *v)
{
    int32_t a = v[0] < v[1] ? v[0] : v[1], b = v[2] < v[3] ? v[2] : v[3];
    return a < b ? a : b;
}

/* Stable parallel counting sort: worker w counts its range of tets per coarse bucket (COARSE_BUCKETS runs
 * of consecutive vertices), the offsets put worker 0's tets of a bucket before worker 1's, and each worker
 * moves its range in order, so the result is the same for any thread count. The count pass checks and
 * renumbers each tet's vertices first (in place).
 *
 * The move goes in two steps where the buckets allow: each tet and its old index into the range of its
 * coarse bucket, written as that many sequential streams, then each coarse range through a worker's
 * scratch into its vertices' places, counted there, stores that stay in the cache. One step, a tet's 16
 * bytes stored at a random place, missed the cache on nearly every tet and took most of the stage (issue
 * 37); so did a count per vertex in the first pass (an array of 4 bytes per vertex and worker, one random
 * increment per tet: 9% of a one-thread grid 120 convert). A coarse range larger than FINE_MOST tets (a
 * vertex in that many tets) takes the one step, counted per vertex in a pass of its own. Either way the
 * tets end in the same order. */
#define COARSE_BUCKETS 2048
#define FINE_MOST (INT64_C(1) << 18)

typedef struct min_sort_job {
    int32_t *tets;          /* renumbered in place by the count pass */
    const int32_t *new_id;  /* new_id[old vertex] */
    const int32_t *source;  /* tet_source, or NULL for the identity */
    bytes16 *tets_out;
    int32_t *source_out;
    uint32_t *order;        /* order[new] = old, or NULL where no cell field needs it */
    uint32_t **next;        /* one step: [worker][nv]: counts, then positions */
    int64_t nv, nt;
    int shift;              /* coarse bucket of vertex v: v >> shift */
    int64_t coarse;         /* coarse buckets */
    uint32_t **coarse_next; /* [worker][coarse]: counts, then positions */
    int64_t *coarse_start;  /* [coarse + 1]: where each coarse range starts */
    int64_t bad[TPK_MAX_THREADS]; /* the count pass: first id out of range (4 * tet + k), or -1 */
    int64_t fine_begin[TPK_MAX_THREADS + 1];
    bytes16 *scratch[TPK_MAX_THREADS];
    int32_t *scratch_source[TPK_MAX_THREADS];
    uint32_t *scratch_index[TPK_MAX_THREADS], *cursor[TPK_MAX_THREADS];
} min_sort_job;

/* Checks and renumbers the tets, counting them per coarse bucket (where there are coarse counts). A worker
 * stops at its first tet with an id out of range, before renumbering it. */
static void min_count(void *ctx, int64_t begin, int64_t end, int worker)
{
    min_sort_job *job = ctx;
    uint32_t *coarse = job->coarse_next ? job->coarse_next[worker] : NULL;
    const int32_t *new_id = job->new_id;
    uint32_t nv = (uint32_t)job->nv;
    int shift = job->shift;
    job->bad[worker] = -1;
    for (int64_t t = begin; t < end; t++) {
        int32_t *v = job->tets + 4 * t;
        if (((uint32_t)v[0] >= nv) | ((uint32_t)v[1] >= nv) | ((uint32_t)v[2] >= nv) | ((uint32_t)v[3] >= nv)) {
            int k = 0;
            while ((uint32_t)v[k] < nv)
                k++;
            job->bad[worker] = 4 * t + k;
            return;
        }
        v[0] = new_id[v[0]], v[1] = new_id[v[1]], v[2] = new_id[v[2]], v[3] = new_id[v[3]];
        if (coarse)
            coarse[min_vertex(v) >> shift]++;
    }
}

/* One step: the renumbered tets counted per smallest vertex. */
static void min_count_fine(void *ctx, int64_t begin, int64_t end, int worker)
{
    min_sort_job *job = ctx;
    uint32_t *count = job->next[worker];
    for (int64_t t = begin; t < end; t++)
        count[min_vertex(job->tets + 4 * t)]++;
}

/* Tets [begin, end), each with its source and its index (where asked), to next[its smallest vertex >>
 * shift]++, in input order. */
static void scatter_by(const min_sort_job *job, uint32_t *next, int shift, int64_t begin, int64_t end)
{
    const bytes16 *tets = (const bytes16 *)job->tets;
    for (int64_t t = begin; t < end; t++) {
        uint32_t at = next[min_vertex(job->tets + 4 * t) >> shift]++;
        job->tets_out[at] = tets[t];
        job->source_out[at] = job->source ? job->source[t] : (int32_t)t;
        if (job->order)
            job->order[at] = (uint32_t)t;
    }
}

/* One step: every tet straight to its place. */
static void min_scatter(void *ctx, int64_t begin, int64_t end, int worker)
{
    const min_sort_job *job = ctx;
    scatter_by(job, job->next[worker], 0, begin, end);
}

/* Two steps, the first: every tet, its source and its index (where asked) to its coarse range, in input
 * order. */
static void coarse_scatter(void *ctx, int64_t begin, int64_t end, int worker)
{
    const min_sort_job *job = ctx;
    scatter_by(job, job->coarse_next[worker], job->shift, begin, end);
}

/* The second: worker's coarse ranges [begin, end), each copied out, counted per vertex and put in vertex
 * order. A range holds worker 0's tets in input order, then worker 1's, so each vertex's tets come in
 * input order. */
static void fine_sort(void *ctx, int64_t begin, int64_t end, int worker)
{
    min_sort_job *job = ctx;
    bytes16 *scratch = job->scratch[worker];
    int32_t *source = job->scratch_source[worker];
    uint32_t *index = job->scratch_index[worker], *cursor = job->cursor[worker];
    (void)begin, (void)end;
    for (int64_t c = job->fine_begin[worker]; c < job->fine_begin[worker + 1]; c++) {
        int64_t a = job->coarse_start[c], b = job->coarse_start[c + 1], v0 = c << job->shift;
        int64_t v1 = (c + 1) << job->shift < job->nv ? (c + 1) << job->shift : job->nv;
        memcpy(scratch, job->tets_out + a, sizeof *scratch * (size_t)(b - a));
        memcpy(source, job->source_out + a, sizeof *source * (size_t)(b - a));
        if (job->order)
            memcpy(index, job->order + a, sizeof *index * (size_t)(b - a));
        memset(cursor, 0, sizeof *cursor * (size_t)(v1 - v0));
        for (int64_t i = 0; i < b - a; i++)
            cursor[min_vertex((const int32_t *)(scratch + i)) - v0]++;
        uint32_t running = (uint32_t)a;
        for (int64_t v = 0; v < v1 - v0; v++) {
            uint32_t n = cursor[v];
            cursor[v] = running;
            running += n;
        }
        for (int64_t i = 0; i < b - a; i++) {
            uint32_t at = cursor[min_vertex((const int32_t *)(scratch + i)) - v0]++;
            job->tets_out[at] = scratch[i];
            job->source_out[at] = source[i];
            if (job->order)
                job->order[at] = index[i];
        }
    }
}

static int has_field(const tpk_tetmesh *mesh, int association)
{
    for (int f = 0; f < mesh->field_count; f++)
        if (mesh->fields[f].association == association)
            return 1;
    return 0;
}

/* After the count: the per-coarse-bucket counts become positions (workers in order within each bucket).
 * Returns the tets of the largest coarse range. */
static int64_t prefix_coarse(min_sort_job *job, int threads)
{
    int64_t largest = 0;
    uint32_t running = 0;
    for (int64_t c = 0; c < job->coarse; c++) {
        job->coarse_start[c] = running;
        for (int w = 0; w < threads; w++) {
            uint32_t n = job->coarse_next[w][c];
            job->coarse_next[w][c] = running;
            running += n;
        }
        if (running - job->coarse_start[c] > largest)
            largest = running - job->coarse_start[c];
    }
    job->coarse_start[job->coarse] = running;
    return largest;
}

/* The two-step move, where its scratch fits; 1 when the one step must do. */
static int move_in_two_steps(min_sort_job *job, int threads, int64_t largest)
{
    int rc = largest > FINE_MOST ? 1 : 0;
    for (int w = 0; w < threads && rc == 0; w++)
        if (!(job->scratch[w] = malloc(sizeof *job->scratch[w] * (size_t)(largest ? largest : 1))) ||
            !(job->scratch_source[w] = malloc(sizeof *job->scratch_source[w] * (size_t)(largest ? largest : 1))) ||
            (job->order &&
             !(job->scratch_index[w] = malloc(sizeof *job->scratch_index[w] * (size_t)(largest ? largest : 1)))) ||
            !(job->cursor[w] = malloc(sizeof *job->cursor[w] << job->shift)))
            rc = 1;
    if (rc == 0) {
        tpk_parallel_for(job->nt, threads, coarse_scatter, job);
        tpk_split_prefix(job->coarse_start, job->coarse, job->nt, threads, job->fine_begin);
        tpk_parallel_for(threads, threads, fine_sort, job);
    }
    for (int w = 0; w < threads; w++) {
        free(job->scratch[w]);
        free(job->scratch_source[w]);
        free(job->scratch_index[w]);
        free(job->cursor[w]);
    }
    return rc;
}

/* The one-step move: counted per vertex (per worker), then every tet to its place. */
static int move_in_one_step(min_sort_job *job, int threads)
{
    uint32_t *next[TPK_MAX_THREADS] = {NULL};
    int64_t nv = job->nv;
    int rc = 0;
    for (int w = 0; w < threads && rc == 0; w++)
        if (!(next[w] = tpk_calloc_large((size_t)nv + 1, sizeof *next[w])))
            rc = -1;
    if (rc == 0) {
        job->next = next;
        tpk_parallel_for(job->nt, threads, min_count_fine, job);
        uint32_t running = 0;
        for (int64_t v = 0; v < nv; v++)
            for (int w = 0; w < threads; w++) {
                uint32_t c = next[w][v];
                next[w][v] = running;
                running += c;
            }
        tpk_parallel_for(job->nt, threads, min_scatter, job);
        job->next = NULL;
    }
    for (int w = 0; w < threads; w++)
        tpk_free_large(next[w], ((size_t)nv + 1) * sizeof *next[w]);
    return rc;
}

/* The tets renumbered by new_id and put in order of their smallest vertex. Returns 0, -1 when out of
 * memory, or 1 with *bad the first id out of range (4 * tet + k; the mesh then is partly renumbered). */
static int apply_tet_order(tpk_tetmesh *mesh, const int32_t *new_id, int threads, int64_t *bad)
{
    int64_t nt = mesh->tet_count, nv = mesh->vertex_count;
    size_t n = (size_t)(nt ? nt : 1);
    int sort_threads = tpk_threads_for(nt, threads, 1 << 16), cell_fields = has_field(mesh, TPK_ASSOC_TET);
    uint32_t *coarse_next[TPK_MAX_THREADS] = {NULL};
    min_sort_job *job = calloc(1, sizeof *job);
    bytes16 *tets_out = tpk_alloc_large(sizeof *tets_out * n);
    int32_t *source_out = tpk_alloc_large(sizeof *source_out * n);
    uint32_t *order = cell_fields ? tpk_alloc_large(sizeof *order * n) : NULL;
    int rc = job && tets_out && source_out && (order || !cell_fields) ? 0 : -1;
    *bad = -1;
    if (rc == 0) {
        job->tets = mesh->tets, job->new_id = new_id, job->source = mesh->tet_source;
        job->tets_out = tets_out, job->source_out = source_out, job->order = order;
        job->nv = nv, job->nt = nt;
        while ((nv - 1) >> job->shift >= COARSE_BUCKETS)
            job->shift++;
        job->coarse = nv > 0 ? ((nv - 1) >> job->shift) + 1 : 0;
        job->coarse_start = malloc(sizeof *job->coarse_start * (size_t)(job->coarse + 1));
        int coarse_ok = job->coarse_start != NULL;
        for (int w = 0; w < sort_threads && coarse_ok; w++)
            coarse_ok = (coarse_next[w] = calloc((size_t)job->coarse + 1, sizeof *coarse_next[w])) != NULL;
        job->coarse_next = coarse_ok ? coarse_next : NULL; /* without them, the one step */
        tpk_parallel_for(nt, sort_threads, min_count, job);
        for (int w = 0; w < sort_threads && *bad < 0; w++) /* ranges in order: the first worker's is first */
            *bad = job->bad[w];
        if (*bad >= 0)
            rc = 1;
        else if (!job->coarse_next || move_in_two_steps(job, sort_threads, prefix_coarse(job, sort_threads)))
            rc = move_in_one_step(job, sort_threads);
        free(job->coarse_start);
    }
    for (int w = 0; w < sort_threads; w++)
        free(coarse_next[w]);
    free(job);
    if (rc == 0) {
        tpk_free_large(mesh->tets, sizeof *mesh->tets * 4 * n);
        tpk_free_large(mesh->tet_source, sizeof *mesh->tet_source * n);
        mesh->tets = (int32_t *)tets_out;
        mesh->tet_source = source_out;
        tets_out = NULL, source_out = NULL;
        if (order)
            rc = permute_fields(mesh, TPK_ASSOC_TET, nt, order, threads);
    }
    tpk_free_large(order, sizeof *order * n);
    tpk_free_large(source_out, sizeof *source_out * n);
    tpk_free_large(tets_out, sizeof *tets_out * n);
    return rc;
}

int tpk_reorder(tpk_tetmesh *mesh, int threads_requested, tpk_diag *diag)
{
    if (!mesh || mesh->vertex_count > INT32_MAX || mesh->tet_count > INT32_MAX ||
        (mesh->vertex_count > 0 && !mesh->points) || (mesh->tet_count > 0 && !mesh->tets))
        return tpk_diag_fail(diag, "reorder: invalid tet mesh");
    int threads = tpk_thread_count(threads_requested);
    int64_t nv = mesh->vertex_count, nt = mesh->tet_count, bad = -1;
    hilbert_table table;
    build_hilbert_table(&table);
    box bounds = bounding_box(mesh->points, nv, threads);
    /* Vertices along the curve first; tets then follow their smallest vertex (their ids checked as they
     * are renumbered: one pass over them fewer than a check of its own). */
    size_t vertex_bytes = sizeof(uint32_t) * (size_t)(nv ? nv : 1);
    uint32_t *order = tpk_alloc_large(vertex_bytes);
    int32_t *new_id = tpk_alloc_large(vertex_bytes);
    int rc = -1;
    if (order && new_id && !hilbert_order(&table, mesh->points, nv, bounds, order, threads) &&
        !apply_vertex_order(mesh, order, new_id, threads)) {
        tpk_free_large(order, vertex_bytes); /* before the tets' arrays: a kept block they may reuse */
        order = NULL;
        rc = apply_tet_order(mesh, new_id, threads, &bad);
    }
    tpk_free_large(order, vertex_bytes);
    tpk_free_large(new_id, vertex_bytes);
    if (rc == 1)
        return tpk_diag_fail(diag, "reorder: tet %lld names vertex %d; the mesh has %lld vertices",
                             (long long)(bad / 4), mesh->tets[bad], (long long)nv);
    if (rc)
        return tpk_diag_fail(diag, "reorder: out of memory (%lld vertices, %lld tets)", (long long)nv,
                             (long long)nt);
    return 0;
}
