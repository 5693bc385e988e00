/* Range culling for iso rays (tpk_range_bvh_*, tpk_march_ray_values; tetpack.h): a BVH over the tets
 * whose nodes carry the box and the scalar range of their tets, after the CPU isosurface ray tracer of
 * the mission's reference 002 (a BVH with per-node value ranges, subtrees that cannot hold the value
 * skipped).
 *
 * Build: the tets come in the file's order (by smallest vertex, vertices along a Hilbert curve, spec
 * §6.4), so runs of TPK_RANGE_LEAF consecutive tets are compact; leaves are such runs and each level
 * pairs neighbours of the level below, up to one root (an implicit tree: level k node i has children
 * 2i and 2i + 1 of level k - 1). Boxes and ranges are rounded outward, so that no tet the exact tests
 * would report is culled.
 *
 * A ray: nodes in order of where the ray enters their box (a heap), pieces in order of t_in (a second
 * heap; ties by tpki_piece_before); a piece is handed on once no node left can hold one that starts
 * before it. range_packet.c walks the selected tree the same way for packets of rays. The piece of a tet is
 * what the marcher computes for it (march.c): the same watertight edge signs, the entry face the one
 * whose outward edges all read -1, the exit face the one whose outward edges all read +1, weights, t and
 * scalar summed from each face's smallest id (internal_ray.h: tpk_face_first), the same clipping to
 * [tmin, tmax]. So each piece is bit for bit the marcher's, except where rounding put a tet's exit
 * before its entry: the marcher clamps the exit to the entry it carried along its path, and here the
 * entry is the tet's own. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_range.h"
#include "tetpack_format.h"

#define TPK_RANGE_LEAF TPK_RANGE_BVH_LEAF
#define HEAP_STACK 64


/* The range of tet t from its vertices' scalars, outward by an ulp (the marcher's interpolated scalars
 * are sums in double of these floats). */
static void tet_range(tpk_range_bvh *b, const float *sc, int64_t t)
{
    float smin = INFINITY, smax = -INFINITY;
    for (int i = 0; i < 4; i++) {
        float s = sc[b->tets[4 * t + i]];
        smin = s < smin ? s : smin; /* a NaN scalar never joins a range: no crossing tests true */
        smax = s > smax ? s : smax;
    }
    b->tet_range[2 * t] = smin > -INFINITY ? nextafterf(smin, -INFINITY) : smin;
    b->tet_range[2 * t + 1] = smax < INFINITY ? nextafterf(smax, INFINITY) : smax;
}

/* The scalar ranges of every tet and node from the marcher's field (the boxes and the tree's shape
 * depend on the positions alone). */
static void read_ranges(tpk_range_bvh *b)
{
    const float *sc = b->marcher->mesh.scalars;
    const int64_t tet_count = (int64_t)b->marcher->mesh.tet_count;
    for (int64_t leaf = 0; b->levels > 0 && leaf < b->level_count[0]; leaf++) {
        float *range = &b->node_range[2 * leaf];
        range[0] = INFINITY, range[1] = -INFINITY;
        int64_t end = (leaf + 1) * TPK_RANGE_LEAF < tet_count ? (leaf + 1) * TPK_RANGE_LEAF : tet_count;
        for (int64_t t = leaf * TPK_RANGE_LEAF; t < end; t++) {
            tet_range(b, sc, t);
            range[0] = b->tet_range[2 * t] < range[0] ? b->tet_range[2 * t] : range[0];
            range[1] = b->tet_range[2 * t + 1] > range[1] ? b->tet_range[2 * t + 1] : range[1];
        }
    }
    for (int l = 1; l < b->levels; l++)
        for (int64_t i = 0; i < b->level_count[l]; i++) {
            int64_t at = b->level_start[l] + i, c = b->level_start[l - 1] + 2 * i;
            float *range = &b->node_range[2 * at];
            range[0] = b->node_range[2 * c], range[1] = b->node_range[2 * c + 1];
            if (2 * i + 1 < b->level_count[l - 1]) {
                range[0] = b->node_range[2 * c + 2] < range[0] ? b->node_range[2 * c + 2] : range[0];
                range[1] = b->node_range[2 * c + 3] > range[1] ? b->node_range[2 * c + 3] : range[1];
            }
        }
}

tpk_result tpk_range_bvh_create(tpk_range_bvh **out, const tpk_marcher *marcher)
{
    return tpk_range_bvh_create_threads(out, marcher, 1);
}

tpk_result tpk_range_bvh_create_threads(tpk_range_bvh **out, const tpk_marcher *marcher, int threads)
{
    if (!out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!marcher || !marcher->mesh.scalars)
        return TPK_ERR_INVALID_ARGUMENT;
    const tpk_mesh_arrays *mesh = &marcher->mesh;
    int64_t tet_count = (int64_t)mesh->tet_count;
    tpk_range_bvh *b = calloc(1, sizeof *b);
    if (!b)
        return TPK_ERR_OUT_OF_MEMORY;
    b->marcher = marcher;
    b->pad = 1e-6 * marcher->extent;
    int64_t leaves = (tet_count + TPK_RANGE_LEAF - 1) / TPK_RANGE_LEAF, total = 0;
    for (int64_t n = leaves; n > 0 && b->levels < 40; n = n > 1 ? (n + 1) / 2 : 0) {
        b->level_start[b->levels] = total;
        b->level_count[b->levels++] = n;
        total += n;
    }
    b->tets = malloc(sizeof *b->tets * 4 * (size_t)(tet_count ? tet_count : 1));
    b->tet_range = malloc(sizeof *b->tet_range * 2 * (size_t)(tet_count ? tet_count : 1));
    b->nodes = malloc(sizeof *b->nodes * (size_t)(total ? total : 1));
    b->node_range = malloc(sizeof *b->node_range * 2 * (size_t)(total ? total : 1));
    if (!b->tets || !b->tet_range || !b->nodes || !b->node_range) {
        tpk_range_bvh_destroy(b);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    b->threads = threads > 1 ? threads : 1;
    tpk_result r = tpk_recover_tets_threads(mesh, b->tets, b->threads);
    if (r != TPK_OK) {
        tpk_range_bvh_destroy(b);
        return r;
    }
    const float *pos = mesh->positions;
    for (int64_t leaf = 0; leaf < leaves; leaf++) {
        tpk_bvh_node *n = &b->nodes[leaf];
        for (int k = 0; k < 3; k++)
            n->lo[k] = INFINITY, n->hi[k] = -INFINITY;
        int64_t end = (leaf + 1) * TPK_RANGE_LEAF < tet_count ? (leaf + 1) * TPK_RANGE_LEAF : tet_count;
        n->first = (int32_t)(leaf * TPK_RANGE_LEAF);
        n->count = (int32_t)(end - leaf * TPK_RANGE_LEAF);
        for (int64_t t = leaf * TPK_RANGE_LEAF; t < end; t++)
            for (int i = 0; i < 4; i++) {
                int32_t v = b->tets[4 * t + i];
                for (int k = 0; k < 3; k++) {
                    float x = pos[3 * (int64_t)v + k];
                    n->lo[k] = x < n->lo[k] ? x : n->lo[k];
                    n->hi[k] = x > n->hi[k] ? x : n->hi[k];
                }
            }
        for (int k = 0; k < 3; k++) {
            n->lo[k] = tpki_round_down((double)n->lo[k] - b->pad);
            n->hi[k] = tpki_round_up((double)n->hi[k] + b->pad);
        }
    }
    for (int l = 1; l < b->levels; l++)
        for (int64_t i = 0; i < b->level_count[l]; i++) {
            int64_t at = b->level_start[l] + i, c = b->level_start[l - 1] + 2 * i;
            tpk_bvh_node *n = &b->nodes[at];
            *n = b->nodes[c];
            if (2 * i + 1 < b->level_count[l - 1]) {
                const tpk_bvh_node *d = &b->nodes[c + 1];
                for (int k = 0; k < 3; k++) {
                    n->lo[k] = d->lo[k] < n->lo[k] ? d->lo[k] : n->lo[k];
                    n->hi[k] = d->hi[k] > n->hi[k] ? d->hi[k] : n->hi[k];
                }
                n->first = (int32_t)c;
                n->count = 0;
            }
        }
    read_ranges(b);
    *out = b;
    return TPK_OK;
}

/* ---- Culling blocks (spec §17) ------------------------------------------------------------------ */

#define BLOCK_WALKED 1
#define BLOCK_RANGED 2

/* Each block's scalar range over its intervals (a superset of its tets' vertices), outward as a tet's. */
static void read_block_ranges(tpk_range_bvh *b)
{
    const float *sc = b->marcher->mesh.scalars;
    const tpk_cull *c = &b->cull;
    for (uint64_t k = 0; k < c->block_count; k++) {
        float smin = INFINITY, smax = -INFINITY;
        for (int32_t i = c->interval_start[k]; i < c->interval_start[k + 1]; i++)
            for (int32_t v = c->intervals[2 * (int64_t)i]; v < c->intervals[2 * (int64_t)i + 1]; v++) {
                float x = sc[v];
                smin = x < smin ? x : smin;
                smax = x > smax ? x : smax;
            }
        b->block_range[2 * k] = smin > -INFINITY ? nextafterf(smin, -INFINITY) : smin;
        b->block_range[2 * k + 1] = smax < INFINITY ? nextafterf(smax, INFINITY) : smax;
        b->block_state[k] &= (unsigned char)~BLOCK_RANGED;
    }
}

tpk_result tpk_range_bvh_create_cull(tpk_range_bvh **out, const tpk_marcher *marcher, const tpk_cull *cull,
                                     int threads)
{
    if (!out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!marcher || !marcher->mesh.scalars || !cull || cull->block_tets == 0)
        return TPK_ERR_INVALID_ARGUMENT;
    const tpk_mesh_arrays *mesh = &marcher->mesh;
    int64_t tet_count = (int64_t)mesh->tet_count;
    if (cull->block_count != (uint64_t)((tet_count + cull->block_tets - 1) / cull->block_tets))
        return TPK_ERR_INVALID_ARGUMENT; /* another mesh's blocks */
    tpk_range_bvh *b = calloc(1, sizeof *b);
    if (!b)
        return TPK_ERR_OUT_OF_MEMORY;
    b->marcher = marcher;
    b->pad = 1e-6 * marcher->extent;
    b->culled = 1;
    b->cull = *cull;
    /* filled block by block as blocks are walked: pages never touched cost nothing */
    b->tets = malloc(sizeof *b->tets * 4 * (size_t)(tet_count ? tet_count : 1));
    b->tet_range = malloc(sizeof *b->tet_range * 2 * (size_t)(tet_count ? tet_count : 1));
    b->block_range = malloc(sizeof *b->block_range * 2 * (size_t)(cull->block_count ? cull->block_count : 1));
    b->block_state = calloc((size_t)(cull->block_count ? cull->block_count : 1), 1);
    if (!b->tets || !b->tet_range || !b->block_range || !b->block_state) {
        tpk_range_bvh_destroy(b);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    b->threads = threads > 1 ? threads : 1;
    read_block_ranges(b);
    *out = b;
    return TPK_OK;
}

int tpki_range_block_holds(const tpk_range_bvh *b, uint64_t k, const double *values, int count)
{
    return tpki_range_holds(b->block_range[2 * k], b->block_range[2 * k + 1], values, count);
}

tpk_result tpki_range_ready_block(tpk_range_bvh *b, uint64_t k)
{
    const int64_t B = b->cull.block_tets, t0 = (int64_t)k * B;
    const int64_t t1 = t0 + B < (int64_t)b->marcher->mesh.tet_count ? t0 + B : (int64_t)b->marcher->mesh.tet_count;
    if (!(b->block_state[k] & BLOCK_WALKED)) {
        tpk_result r = tpk_recover_block(&b->marcher->mesh, &b->cull, k, b->tets + 4 * t0);
        if (r != TPK_OK)
            return r;
        b->block_state[k] |= BLOCK_WALKED;
    }
    if (!(b->block_state[k] & BLOCK_RANGED)) {
        const float *sc = b->marcher->mesh.scalars;
        for (int64_t t = t0; t < t1; t++)
            tet_range(b, sc, t);
        b->block_state[k] |= BLOCK_RANGED;
    }
    return TPK_OK;
}

void tpki_range_drop_selection(tpk_range_bvh *b)
{
    free(b->wide);
    free(b->active_tets);
    free(b->active_slots);
    free(b->active_scalars);
    free(b->active_values);
    b->wide = NULL, b->active_tets = NULL, b->active_slots = NULL, b->active_scalars = NULL, b->active_values = NULL;
    b->active_value_count = 0, b->wide_count = 0;
}

void tpk_range_bvh_destroy(tpk_range_bvh *b)
{
    if (!b)
        return;
    free(b->tets);
    free(b->tet_range);
    free(b->nodes);
    free(b->node_range);
    free(b->block_range);
    free(b->block_state);
    tpki_range_drop_selection(b);
    free(b);
}

tpk_result tpk_range_bvh_set_scalars(tpk_range_bvh *b)
{
    if (!b || !b->marcher->mesh.scalars)
        return TPK_ERR_INVALID_ARGUMENT;
    tpki_range_drop_selection(b); /* it holds the old field's tets */
    if (b->culled)
        read_block_ranges(b); /* the walked blocks keep their tets; their ranges are read again */
    else
        read_ranges(b);
    return TPK_OK;
}

tpk_result tpk_range_bvh_set_threads(tpk_range_bvh *b, int threads)
{
    if (!b)
        return TPK_ERR_INVALID_ARGUMENT;
    b->threads = threads > 1 ? threads : 1;
    return TPK_OK;
}

double tpk_range_bvh_active(const tpk_range_bvh *b, const double *values, int count)
{
    if (b && b->culled && b->cull.block_count > 0 && count > 0 && values) {
        int64_t active = 0;
        for (uint64_t k = 0; k < b->cull.block_count; k++)
            active += tpki_range_block_holds(b, k, values, count);
        return (double)active / (double)b->cull.block_count;
    }
    if (!b || b->levels == 0 || count <= 0 || !values)
        return 0.0;
    int64_t active = 0;
    for (int64_t i = 0; i < b->level_count[0]; i++)
        active += tpki_range_holds(b->node_range[2 * i], b->node_range[2 * i + 1], values, count);
    return (double)active / (double)b->level_count[0];
}

int64_t tpk_range_bvh_heap(const tpk_range_bvh *b, float *nodes)
{
    if (!b || b->culled)
        return 0;
    int64_t leaves = b->levels ? b->level_count[0] : 0, base = 1;
    while (base < leaves)
        base *= 2;
    if (!nodes)
        return base;
    static const float empty[8] = {INFINITY, INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (int64_t n = 0; n < 2 * base; n++)
        memcpy(nodes + 8 * n, empty, sizeof empty);
    /* level l of the implicit tree (leaves l = 0) starts at heap node base >> l: the same pairs */
    for (int l = 0; l < b->levels; l++)
        for (int64_t i = 0; i < b->level_count[l]; i++) {
            int64_t at = b->level_start[l] + i;
            const tpk_bvh_node *r = &b->nodes[at];
            float *d = nodes + 8 * ((base >> l) + i);
            d[0] = r->lo[0], d[1] = r->lo[1], d[2] = r->lo[2], d[3] = b->node_range[2 * at];
            d[4] = r->hi[0], d[5] = r->hi[1], d[6] = r->hi[2], d[7] = b->node_range[2 * at + 1];
        }
    return base;
}

const int32_t *tpk_range_bvh_tets(const tpk_range_bvh *b)
{
    return b && !b->culled ? b->tets : NULL;
}

int tpki_range_selected(const tpk_range_bvh *b, const double *values, int count)
{
    return b->active_value_count > 0 && count == b->active_value_count &&
           !memcmp(values, b->active_values, sizeof *values * (size_t)count);
}

/* ---- One ray ------------------------------------------------------------------------------------- */

int tpki_range_holds(double lo, double hi, const double *values, int count)
{
    for (int j = 0; j < count; j++)
        if (values[j] >= lo && values[j] <= hi)
            return 1;
    return 0;
}

typedef struct heap_item {
    double key;
    int64_t index; /* node: its index in the tree; piece: index into the pieces */
} heap_item;

typedef struct heap {
    heap_item *items, *stack_items;
    int64_t count, cap;
    tpk_segment *const *pieces; /* a heap of pieces: the pieces its indices point into, for their order */
} heap;

/* Item a comes out before item b: nodes by key, then index; pieces in tpki_piece_before's order. */
static inline int heap_before(const heap *h, const heap_item *a, const heap_item *b)
{
    if (h->pieces)
        return tpki_piece_before(&(*h->pieces)[a->index], &(*h->pieces)[b->index]);
    return a->key < b->key || (a->key == b->key && a->index < b->index);
}

static int heap_push(heap *h, double key, int64_t index)
{
    if (h->count == h->cap) {
        void *items = h->items;
        if (tpki_grow(&items, h->stack_items, h->count, &h->cap, sizeof *h->items) != 0)
            return -1;
        h->items = items;
    }
    int64_t i = h->count++;
    const heap_item item = {key, index};
    while (i > 0) {
        int64_t parent = (i - 1) / 2;
        const heap_item *p = &h->items[parent];
        if (!heap_before(h, &item, p))
            break;
        h->items[i] = *p;
        i = parent;
    }
    h->items[i] = item;
    return 0;
}

static heap_item heap_pop(heap *h)
{
    heap_item top = h->items[0], last = h->items[--h->count];
    int64_t i = 0;
    for (;;) {
        int64_t c = 2 * i + 1;
        if (c >= h->count)
            break;
        if (c + 1 < h->count && heap_before(h, &h->items[c + 1], &h->items[c]))
            c++;
        if (!heap_before(h, &h->items[c], &last))
            break;
        h->items[i] = h->items[c];
        i = c;
    }
    h->items[i] = last;
    return top;
}

static void heap_free(heap *h)
{
    if (h->items != h->stack_items)
        free(h->items);
}

/* Where the ray (local origin o, direction d, 1/d) enters a padded box, or +inf when it misses it or
 * enters after tmax. */
static double box_entry(const tpk_bvh_node *n, const double o[3], const double inv[3], double pad, double tmin,
                        double tmax)
{
    double t0 = -INFINITY, t1 = INFINITY;
    for (int k = 0; k < 3; k++) {
        double lo = ((double)n->lo[k] - pad - o[k]) * inv[k], hi = ((double)n->hi[k] + pad - o[k]) * inv[k];
        if (lo > hi) {
            double s = lo;
            lo = hi;
            hi = s;
        }
        if (lo != lo || hi != hi) { /* 0 * inf: the ray runs in the slab's plane */
            if (o[k] < (double)n->lo[k] - pad || o[k] > (double)n->hi[k] + pad)
                return INFINITY;
            continue;
        }
        t0 = lo > t0 ? lo : t0;
        t1 = hi < t1 ? hi : t1;
    }
    if (t0 > t1 || t1 < tmin || t0 > tmax)
        return INFINITY;
    return t0;
}

/* A ray's box test set up once: the near plane of each slab (by the sign of the direction), 1/d, and the
 * padding in t (pad |1/d|), so that a box costs six multiply-adds. A ray with a direction component 0
 * (1/d infinite) takes box_entry's general test. */
typedef struct ray_box {
    double o[3], inv[3], pad_t[3], pad;
    int near[3], far[3]; /* offsets into a node's six floats (lo[3], hi[3]) */
    int general;
} ray_box;

static void ray_box_init(ray_box *rb, const double o[3], const double inv[3], double pad)
{
    rb->general = 0;
    rb->pad = pad;
    for (int k = 0; k < 3; k++) {
        rb->o[k] = o[k];
        rb->inv[k] = inv[k];
        rb->pad_t[k] = pad * fabs(inv[k]);
        rb->near[k] = inv[k] >= 0 ? k : k + 3;
        rb->far[k] = inv[k] >= 0 ? k + 3 : k;
        rb->general |= !isfinite(inv[k]) || !isfinite(rb->pad_t[k]);
    }
}

/* box_entry, by the ray's set-up test. */
static inline double ray_box_entry(const tpk_bvh_node *n, const ray_box *rb, double tmin, double tmax)
{
    if (rb->general)
        return box_entry(n, rb->o, rb->inv, rb->pad, tmin, tmax);
    const float *box = n->lo; /* lo[3] then hi[3] (tpk_shell_bvh_node) */
    double t0 = -INFINITY, t1 = INFINITY;
    for (int k = 0; k < 3; k++) {
        double a = ((double)box[rb->near[k]] - rb->o[k]) * rb->inv[k] - rb->pad_t[k];
        double c = ((double)box[rb->far[k]] - rb->o[k]) * rb->inv[k] + rb->pad_t[k];
        t0 = a > t0 ? a : t0;
        t1 = c < t1 ? c : t1;
    }
    return t0 > t1 || t1 < tmin || t0 > tmax ? INFINITY : t0;
}

/* The same test for the four children of a wide node at once, in float: a lane's entry t, or +inf where
 * the ray misses that child or meets it outside [tmin, tmax]. Floats round (the box minus the origin,
 * times 1/d), by at most 2^-21 (|box| + |origin|) |1/d| all told, so each slab is widened by 2^-20
 * (extent + |origin|) |1/d| on top of the padding: no child that the double test would enter is
 * missed. A ray whose 1/d or origin floats cannot hold takes box_entry lane by lane. */
typedef struct wide_ray {
    tpki_v4f o[3], inv[3], pad_t[3], tmin, tmax;
    int near[3], far[3]; /* which of a node's six box rows is the near and the far plane per axis */
    int general;
} wide_ray;

static void wide_ray_init(wide_ray *wr, const ray_box *rb, double extent, double tmin, double tmax)
{
    double o_max = fmax(fabs(rb->o[0]), fmax(fabs(rb->o[1]), fabs(rb->o[2])));
    double widen = tpki_box_widen(rb->pad, extent, o_max);
    wr->general = rb->general || !(o_max < 1e30);
    for (int k = 0; k < 3; k++) {
        double pad_t = widen * fabs(rb->inv[k]);
        wr->general |= !(fabs(rb->inv[k]) < 1e30) || !(pad_t < 1e30);
        float o = (float)rb->o[k], inv = (float)rb->inv[k], p = (float)pad_t;
        wr->o[k] = (tpki_v4f){o, o, o, o};
        wr->inv[k] = (tpki_v4f){inv, inv, inv, inv};
        wr->pad_t[k] = (tpki_v4f){p, p, p, p};
        wr->near[k] = rb->near[k];
        wr->far[k] = rb->far[k];
    }
    float lo = tmin > -1e30 ? tpki_round_down(tmin) : -INFINITY, hi = tmax < 1e30 ? tpki_round_up(tmax) : INFINITY;
    wr->tmin = (tpki_v4f){lo, lo, lo, lo};
    wr->tmax = (tpki_v4f){hi, hi, hi, hi};
}

/* Entry t of each lane (+inf: missed) into t0[4]. */
static inline void wide_entry(const tpki_wide_node *n, const wide_ray *wr, const ray_box *rb, double tmin,
                              double tmax, double t0[4])
{
    if (wr->general) {
        for (int i = 0; i < 4; i++) {
            tpk_bvh_node box;
            for (int k = 0; k < 3; k++)
                box.lo[k] = n->box[k][i], box.hi[k] = n->box[k + 3][i];
            t0[i] = n->count[i] < 0 ? INFINITY : box_entry(&box, rb->o, rb->inv, rb->pad, tmin, tmax);
        }
        return;
    }
    tpki_v4f near = tpki_v4_max(tpki_v4_max((n->box[wr->near[0]] - wr->o[0]) * wr->inv[0] - wr->pad_t[0],
                                  (n->box[wr->near[1]] - wr->o[1]) * wr->inv[1] - wr->pad_t[1]),
                           (n->box[wr->near[2]] - wr->o[2]) * wr->inv[2] - wr->pad_t[2]);
    tpki_v4f far = tpki_v4_min(tpki_v4_min((n->box[wr->far[0]] - wr->o[0]) * wr->inv[0] + wr->pad_t[0],
                                 (n->box[wr->far[1]] - wr->o[1]) * wr->inv[1] + wr->pad_t[1]),
                          (n->box[wr->far[2]] - wr->o[2]) * wr->inv[2] + wr->pad_t[2]);
    tpki_v4i hit = (near <= far) & (far >= wr->tmin) & (near <= wr->tmax);
    for (int i = 0; i < 4; i++)
        t0[i] = hit[i] ? (double)near[i] : INFINITY;
}

/* The piece of tet `t` (positive order q) the ray crosses, as the marcher computes it; 0 when the ray
 * misses the tet. slot: the tet's copy in the selected tree, or NULL. */
int tpki_tet_piece(const tpk_range_bvh *b, const tpk_ray_frame *frame, int64_t t, const tpki_active_slot *slot,
                   tpk_segment *seg)
{
    const tpk_mesh_arrays *mesh = &b->marcher->mesh;
    const int32_t *q = slot ? slot->v : b->tets + 4 * t;
    tpk_proj p[4];
    for (int i = 0; i < 4; i++) {
        if (slot) {
            const float corner[3] = {slot->pos[0][i], slot->pos[1][i], slot->pos[2][i]};
            p[i] = tpk_project_point(corner, frame);
        } else {
            p[i] = tpk_project(mesh->positions, frame, q[i]);
        }
    }
    /* The ray is the point (0,0) of the frame, perturbed to (eps, eps^2) (internal_ray.h): a tet whose
     * corners all lie strictly on one side of x = 0 or of y = 0 cannot hold it, whatever the edge signs
     * say, and most tets of a leaf are such. */
    int right = 1, left = 1, above = 1, below = 1; /* bitwise: one branch, not sixteen */
    for (int i = 0; i < 4; i++)
        right &= p[i].x > 0, left &= p[i].x < 0, above &= p[i].y > 0, below &= p[i].y < 0;
    if (right | left | above | below)
        return 0;
    /* edge i->j for i < j: its sign and value (j->i: both negated) */
    int sign[4][4];
    double value[4][4];
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++) {
            sign[i][j] = tpk_edge_sign(q[i], &p[i], q[j], &p[j], &value[i][j]);
            sign[j][i] = -sign[i][j];
            value[j][i] = -value[i][j];
        }
    /* the entry face: outward edges all -1; the exit face: all +1 (the last such, if more); found by
     * selects, as the faces' signs come at random, and only then copied out */
    int opposite = -1, exit_k = -1;
    for (int k = 0; k < 4; k++) {
        const int *f = tpk_tet_faces[k]; /* outward order */
        int s0 = sign[f[0]][f[1]], s1 = sign[f[1]][f[2]], s2 = sign[f[2]][f[0]];
        int same = (s0 == s1) & (s1 == s2);
        opposite ^= (opposite ^ k) & -(same & (s0 < 0));
        exit_k ^= (exit_k ^ k) & -(same & (s0 > 0));
    }
    if (opposite < 0 || exit_k < 0)
        return 0;
    /* held as the marcher holds the faces it crosses: all edge values <= 0 */
    const int *fe = tpk_tet_faces[opposite], *fx = tpk_tet_faces[exit_k];
    const int entry_c[3] = {fe[0], fe[1], fe[2]}, exit_c[3] = {fx[0], fx[2], fx[1]};
    tpk_face_hit entry, exit;
    for (int i = 0; i < 3; i++) {
        entry.v[i] = q[entry_c[i]];
        entry.p[i] = p[entry_c[i]];
        entry.e[i] = value[entry_c[i]][entry_c[(i + 1) % 3]];
        exit.v[i] = q[exit_c[i]];
        exit.p[i] = p[exit_c[i]];
        exit.e[i] = value[exit_c[i]][exit_c[(i + 1) % 3]];
    }
    /* the corners' scalars: the slot's copy, read from one run of memory, or the mesh's */
    double s[4];
    if (slot) {
        const tpki_v4f copy = b->active_scalars[slot - b->active_slots];
        for (int c = 0; c < 4; c++)
            s[c] = copy[c];
    } else {
        for (int c = 0; c < 4; c++)
            s[c] = mesh->scalars[q[c]];
    }
    double w[3];
    int first = tpk_face_first(&entry);
    tpk_face_weights(&entry, first, w);
    double t_in = tpk_face_sum(first, w, (const double[3]){entry.p[0].z, entry.p[1].z, entry.p[2].z});
    double s_in = tpk_face_sum(first, w, (const double[3]){s[entry_c[0]], s[entry_c[1]], s[entry_c[2]]});
    int c1 = tpk_face_corner[first + 1], c2 = tpk_face_corner[first + 2];
    *seg = (tpk_segment){(int32_t)t, t_in, 0, s_in, 0, {entry.v[first], entry.v[c1], entry.v[c2], q[opposite]}};
    first = tpk_face_first(&exit);
    tpk_face_weights(&exit, first, w);
    double t_out = tpk_face_sum(first, w, (const double[3]){exit.p[0].z, exit.p[1].z, exit.p[2].z});
    seg->t_out = t_out >= t_in ? t_out : t_in;
    seg->scalar_out = tpk_face_sum(first, w, (const double[3]){s[exit_c[0]], s[exit_c[1]], s[exit_c[2]]});
    return 1;
}

/* One ray's walk: the queued nodes (by entry t) and the pieces found but not yet handed on (by t_in). */
typedef struct walk {
    const tpk_range_bvh *b;
    tpk_ray_frame frame;
    ray_box rb;
    double tmin, tmax, slack;
    const double *values;
    int value_count;
    tpk_segment_fn fn;
    void *user;
    heap nodes, pieces_heap;
    heap_item node_stack[HEAP_STACK], piece_stack[HEAP_STACK];
    tpk_segment piece_buf[HEAP_STACK];
    tpk_segment *pieces;
    int64_t piece_count, piece_cap;
    uint64_t tested;
    int stop;
    tpk_result r;
} walk;

/* Hand on the first piece found if it starts before any node left can hold one; 1 if it did. */
static int walk_hand(walk *w)
{
    if (w->pieces_heap.count == 0 || (w->nodes.count > 0 && w->pieces_heap.items[0].key >= w->nodes.items[0].key))
        return 0;
    heap_item it = heap_pop(&w->pieces_heap);
    tpk_segment seg = w->pieces[it.index];
    if (w->fn && w->fn(w->user, &seg))
        w->stop = 1;
    if (seg.t_out >= w->tmax)
        w->stop = 1;
    return 1;
}

/* Something queued comes before `key`. */
static int walk_due_before(const walk *w, double key)
{
    return (w->nodes.count > 0 && w->nodes.items[0].key < key) ||
           (w->pieces_heap.count > 0 && w->pieces_heap.items[0].key < key);
}

static void walk_push_node(walk *w, double key, int64_t index)
{
    if (heap_push(&w->nodes, key, index))
        w->r = TPK_ERR_OUT_OF_MEMORY;
}

/* Test tet t (slot: its copy in the selected tree, or NULL) and queue its piece if it crosses a value. */
static void walk_tet(walk *w, int64_t t, const tpki_active_slot *slot)
{
    w->tested++;
    tpk_segment seg;
    if (!tpki_tet_piece(w->b, &w->frame, t, slot, &seg) || !tpki_clip_piece(&seg, w->tmin, w->tmax) ||
        !tpki_crosses(seg.scalar_in, seg.scalar_out, w->values, w->value_count))
        return;
    if (w->piece_count == w->piece_cap) {
        void *pieces = w->pieces;
        if (tpki_grow(&pieces, w->piece_buf, w->piece_count, &w->piece_cap, sizeof *w->pieces) != 0) {
            w->r = TPK_ERR_OUT_OF_MEMORY;
            return;
        }
        w->pieces = pieces;
    }
    w->pieces[w->piece_count] = seg;
    if (heap_push(&w->pieces_heap, seg.t_in, w->piece_count++))
        w->r = TPK_ERR_OUT_OF_MEMORY;
}

/* The file-order tree: ranges checked at every node and tet. */
static void walk_file_order(walk *w)
{
    const tpk_range_bvh *b = w->b;
    const tpk_bvh_node *tree = b->nodes;
    const float *range = b->node_range;
    int64_t root = b->level_start[b->levels - 1];
    double t_root = tpki_range_holds(range[2 * root], range[2 * root + 1], w->values, w->value_count)
                        ? ray_box_entry(&tree[root], &w->rb, w->tmin, w->tmax) : INFINITY;
    if (t_root < INFINITY)
        walk_push_node(w, t_root - w->slack, root);
    while (w->r == TPK_OK && !w->stop && (w->nodes.count > 0 || w->pieces_heap.count > 0)) {
        if (walk_hand(w))
            continue;
        int64_t i = heap_pop(&w->nodes).index;
        /* down the tree: the nearer child straight on while nothing queued comes before it, the other
         * child queued */
        while (tree[i].count == 0 && w->r == TPK_OK) {
            double key[2] = {INFINITY, INFINITY};
            int64_t child[2] = {-1, -1};
            int found = 0;
            for (int64_t c = tree[i].first; c <= tree[i].first + 1; c++) {
                if (!tpki_range_holds(range[2 * c], range[2 * c + 1], w->values, w->value_count))
                    continue;
                double t0 = ray_box_entry(&tree[c], &w->rb, w->tmin, w->tmax);
                if (t0 < INFINITY)
                    key[found] = t0 - w->slack, child[found++] = c;
            }
            if (found == 2 && key[1] < key[0]) {
                double k = key[0];
                int64_t c = child[0];
                key[0] = key[1], child[0] = child[1];
                key[1] = k, child[1] = c;
            }
            if (found == 2)
                walk_push_node(w, key[1], child[1]);
            if (found == 0)
                break;
            if (walk_due_before(w, key[0])) {
                walk_push_node(w, key[0], child[0]);
                break;
            }
            i = child[0];
        }
        if (tree[i].count == 0)
            continue;
        for (int64_t t = tree[i].first; t < tree[i].first + tree[i].count && w->r == TPK_OK; t++)
            if (tpki_range_holds(b->tet_range[2 * t], b->tet_range[2 * t + 1], w->values, w->value_count))
                walk_tet(w, t, NULL);
    }
}

/* The selected tree: every tet holds a value, four children tested at once. */
static void walk_selected(walk *w)
{
    const tpk_range_bvh *b = w->b;
    wide_ray wr;
    wide_ray_init(&wr, &w->rb, b->marcher->extent, w->tmin, w->tmax);
    walk_push_node(w, -INFINITY, 0);
    while (w->r == TPK_OK && !w->stop && (w->nodes.count > 0 || w->pieces_heap.count > 0)) {
        if (walk_hand(w))
            continue;
        int64_t ref = heap_pop(&w->nodes).index;
        /* down the tree: the nearest child straight on while nothing queued comes before it, the others
         * queued */
        while (ref >= 0 && w->r == TPK_OK) {
            const tpki_wide_node *n = &b->wide[ref];
            double t0[4], key[4];
            int64_t child[4];
            int found = 0;
            wide_entry(n, &wr, &w->rb, w->tmin, w->tmax, t0);
            for (int i = 0; i < 4; i++) {
                if (t0[i] == INFINITY)
                    continue;
                int64_t c = n->count[i] == 0 ? n->child[i] : tpki_leaf_ref(n->child[i], n->count[i]);
                int at = found++;
                for (; at > 0 && key[at - 1] > t0[i] - w->slack; at--) /* nearest first */
                    key[at] = key[at - 1], child[at] = child[at - 1];
                key[at] = t0[i] - w->slack, child[at] = c;
            }
            for (int i = 1; i < found; i++)
                walk_push_node(w, key[i], child[i]);
            if (found == 0) {
                ref = 0;
                break;
            }
            if (walk_due_before(w, key[0])) {
                walk_push_node(w, key[0], child[0]);
                ref = 0;
                break;
            }
            ref = child[0];
        }
        if (ref >= 0)
            continue;
        int64_t first = tpki_leaf_first(ref), count = tpki_leaf_count(ref);
        for (int64_t slot = first; slot < first + count && w->r == TPK_OK; slot++)
            walk_tet(w, b->active_tets[slot], &b->active_slots[slot]);
    }
}

tpk_result tpk_march_ray_values(const tpk_range_bvh *b, const double org[3], const double dir[3], double tmin,
                                double tmax, const double *values, int value_count, tpk_segment_fn fn,
                                void *user, tpk_march_stats *stats)
{
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!b || !org || !dir || isnan(tmin) || isnan(tmax) || value_count < 0 || (value_count > 0 && !values))
        return TPK_ERR_INVALID_ARGUMENT;
    walk walk_state; /* not zeroed: its stack buffers are large and fill as they are used */
    walk *w = &walk_state;
    w->b = b, w->tmin = tmin, w->tmax = tmax, w->values = values, w->value_count = value_count;
    w->fn = fn, w->user = user, w->r = TPK_OK, w->tested = 0, w->stop = 0, w->piece_count = 0;
    if (tpki_ray_frame_init(&w->frame, b->marcher->mesh.origin, org, dir) != 0)
        return TPK_ERR_INVALID_ARGUMENT;
    int use_selected = tpki_range_selected(b, values, value_count);
    if (b->culled && value_count > 0 && !use_selected)
        return TPK_ERR_INVALID_ARGUMENT; /* culling blocks hold no file-order tree: select the values first */
    if (tmax < tmin || (b->levels == 0 && !b->culled) || value_count == 0 || (use_selected && b->wide_count == 0))
        return TPK_OK;
    double inv[3];
    for (int k = 0; k < 3; k++)
        inv[k] = 1.0 / dir[k];
    ray_box_init(&w->rb, w->frame.org, inv, b->pad);
    /* t of the box tests and of the pieces differ by rounding: a node is due a little before its box */
    double dir_len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    w->slack = 1e-9 * (b->marcher->extent + fabs(w->frame.org[0]) + fabs(w->frame.org[1]) + fabs(w->frame.org[2])) /
               dir_len;
    w->nodes = (heap){w->node_stack, w->node_stack, 0, HEAP_STACK, NULL};
    w->pieces_heap = (heap){w->piece_stack, w->piece_stack, 0, HEAP_STACK, &w->pieces};
    w->pieces = w->piece_buf;
    w->piece_cap = HEAP_STACK;
    if (use_selected)
        walk_selected(w);
    else
        walk_file_order(w);
    if (w->pieces != w->piece_buf)
        free(w->pieces);
    heap_free(&w->nodes);
    heap_free(&w->pieces_heap);
    if (stats)
        stats->tet_steps = w->tested;
    return w->r;
}
