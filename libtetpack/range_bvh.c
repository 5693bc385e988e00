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
 * heap); a piece is handed on once no node left can hold one that starts before it. The piece of a tet is
 * what the marcher computes for it (march.c): the same watertight edge signs, the entry face the one
 * whose outward edges all read -1, the exit face the one whose outward edges all read +1, weights, t and
 * scalar summed from each face's smallest id (internal_ray.h: tpk_face_first), the same clipping to
 * [tmin, tmax]. So each piece is bit for bit the marcher's, except where rounding put a tet's exit
 * before its entry: the marcher clamps the exit to the entry it carried along its path, and here the
 * entry is the tet's own. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_march.h"
#include "tetpack_format.h"

#define TPK_RANGE_LEAF TPK_RANGE_BVH_LEAF
#define HEAP_STACK 64

typedef struct range_node {
    float lo[3], hi[3];
    float smin, smax;
} range_node;

struct tpk_range_bvh {
    const tpk_marcher *marcher;
    int32_t *tets;            /* 4 per tet, positive order (tpk_recover_tets) */
    float *tet_range;         /* 2 per tet: the vertex scalars' min and max, rounded outward */
    range_node *nodes;        /* every level, leaves first */
    int64_t level_start[40];  /* first node of each level */
    int64_t level_count[40];
    int levels;
    double pad;               /* added around boxes in the slab test: 1e-6 of the extent */
};

static int holds_value(double lo, double hi, const double *values, int count);

static float down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

static float up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

tpk_result tpk_range_bvh_create(tpk_range_bvh **out, const tpk_marcher *marcher)
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
    if (!b->tets || !b->tet_range || !b->nodes) {
        tpk_range_bvh_destroy(b);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    tpk_result r = tpk_recover_tets(mesh, b->tets);
    if (r != TPK_OK) {
        tpk_range_bvh_destroy(b);
        return r;
    }
    const float *pos = mesh->positions, *sc = mesh->scalars;
    for (int64_t leaf = 0; leaf < leaves; leaf++) {
        range_node *n = &b->nodes[leaf];
        for (int k = 0; k < 3; k++)
            n->lo[k] = INFINITY, n->hi[k] = -INFINITY;
        n->smin = INFINITY, n->smax = -INFINITY;
        int64_t end = (leaf + 1) * TPK_RANGE_LEAF < tet_count ? (leaf + 1) * TPK_RANGE_LEAF : tet_count;
        for (int64_t t = leaf * TPK_RANGE_LEAF; t < end; t++) {
            float smin = INFINITY, smax = -INFINITY;
            for (int i = 0; i < 4; i++) {
                int32_t v = b->tets[4 * t + i];
                for (int k = 0; k < 3; k++) {
                    float x = pos[3 * (int64_t)v + k];
                    n->lo[k] = x < n->lo[k] ? x : n->lo[k];
                    n->hi[k] = x > n->hi[k] ? x : n->hi[k];
                }
                float s = sc[v];
                smin = s < smin ? s : smin; /* a NaN scalar never joins a range: no crossing tests true */
                smax = s > smax ? s : smax;
            }
            /* outward by an ulp: the marcher's interpolated scalars are sums in double of these floats */
            b->tet_range[2 * t] = smin > -INFINITY ? nextafterf(smin, -INFINITY) : smin;
            b->tet_range[2 * t + 1] = smax < INFINITY ? nextafterf(smax, INFINITY) : smax;
            n->smin = b->tet_range[2 * t] < n->smin ? b->tet_range[2 * t] : n->smin;
            n->smax = b->tet_range[2 * t + 1] > n->smax ? b->tet_range[2 * t + 1] : n->smax;
        }
        for (int k = 0; k < 3; k++) {
            n->lo[k] = down((double)n->lo[k] - b->pad);
            n->hi[k] = up((double)n->hi[k] + b->pad);
        }
    }
    for (int l = 1; l < b->levels; l++)
        for (int64_t i = 0; i < b->level_count[l]; i++) {
            range_node *n = &b->nodes[b->level_start[l] + i];
            const range_node *c = &b->nodes[b->level_start[l - 1] + 2 * i];
            *n = c[0];
            if (2 * i + 1 < b->level_count[l - 1]) {
                for (int k = 0; k < 3; k++) {
                    n->lo[k] = c[1].lo[k] < n->lo[k] ? c[1].lo[k] : n->lo[k];
                    n->hi[k] = c[1].hi[k] > n->hi[k] ? c[1].hi[k] : n->hi[k];
                }
                n->smin = c[1].smin < n->smin ? c[1].smin : n->smin;
                n->smax = c[1].smax > n->smax ? c[1].smax : n->smax;
            }
        }
    *out = b;
    return TPK_OK;
}

void tpk_range_bvh_destroy(tpk_range_bvh *b)
{
    if (!b)
        return;
    free(b->tets);
    free(b->tet_range);
    free(b->nodes);
    free(b);
}

double tpk_range_bvh_active(const tpk_range_bvh *b, const double *values, int count)
{
    if (!b || b->levels == 0 || count <= 0 || !values)
        return 0.0;
    int64_t active = 0;
    for (int64_t i = 0; i < b->level_count[0]; i++)
        active += holds_value(b->nodes[i].smin, b->nodes[i].smax, values, count);
    return (double)active / (double)b->level_count[0];
}

int64_t tpk_range_bvh_heap(const tpk_range_bvh *b, float *nodes)
{
    if (!b)
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
            const range_node *r = &b->nodes[b->level_start[l] + i];
            float *d = nodes + 8 * ((base >> l) + i);
            d[0] = r->lo[0], d[1] = r->lo[1], d[2] = r->lo[2], d[3] = r->smin;
            d[4] = r->hi[0], d[5] = r->hi[1], d[6] = r->hi[2], d[7] = r->smax;
        }
    return base;
}

const int32_t *tpk_range_bvh_tets(const tpk_range_bvh *b)
{
    return b ? b->tets : NULL;
}

/* ---- One ray ------------------------------------------------------------------------------------- */

/* A value of `values` in [lo, hi]. */
static int holds_value(double lo, double hi, const double *values, int count)
{
    for (int j = 0; j < count; j++)
        if (values[j] >= lo && values[j] <= hi)
            return 1;
    return 0;
}

/* A crossing by the renderers' rule (render_integrate.c's ri_point_crossings): s_in < v <= s_out or
 * s_in > v >= s_out. */
static int crosses(double s_in, double s_out, const double *values, int count)
{
    for (int j = 0; j < count; j++) {
        double v = values[j];
        if ((s_in < v && v <= s_out) || (s_in > v && v >= s_out))
            return 1;
    }
    return 0;
}

typedef struct heap_item {
    double key;
    int64_t index; /* node: level << 40 | i; piece: index into the pieces */
} heap_item;

typedef struct heap {
    heap_item *items, *stack_items;
    int64_t count, cap;
} heap;

static int heap_push(heap *h, double key, int64_t index)
{
    if (h->count == h->cap) {
        int64_t cap = 2 * h->cap;
        heap_item *grown = malloc(sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        memcpy(grown, h->items, sizeof *grown * (size_t)h->count);
        if (h->items != h->stack_items)
            free(h->items);
        h->items = grown;
        h->cap = cap;
    }
    int64_t i = h->count++;
    while (i > 0) {
        int64_t parent = (i - 1) / 2;
        const heap_item *p = &h->items[parent];
        if (p->key < key || (p->key == key && p->index <= index))
            break;
        h->items[i] = *p;
        i = parent;
    }
    h->items[i] = (heap_item){key, index};
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
        if (c + 1 < h->count &&
            (h->items[c + 1].key < h->items[c].key ||
             (h->items[c + 1].key == h->items[c].key && h->items[c + 1].index < h->items[c].index)))
            c++;
        if (last.key < h->items[c].key || (last.key == h->items[c].key && last.index <= h->items[c].index))
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
static double box_entry(const range_node *n, const double o[3], const double inv[3], double pad, double tmin,
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

/* The piece of tet `t` (positive order q) the ray crosses, as the marcher computes it; 0 when the ray
 * misses the tet. */
static int tet_piece(const tpk_range_bvh *b, const tpk_ray_frame *frame, int64_t t, tpk_segment *seg)
{
    const tpk_mesh_arrays *mesh = &b->marcher->mesh;
    const int32_t *q = b->tets + 4 * t;
    tpk_proj p[4];
    for (int i = 0; i < 4; i++)
        p[i] = tpk_project(mesh->positions, frame, q[i]);
    /* The ray is the point (0,0) of the frame, perturbed to (eps, eps^2) (internal_ray.h): a tet whose
     * corners all lie strictly on one side of x = 0 or of y = 0 cannot hold it, whatever the edge signs
     * say, and most tets of a leaf are such. */
    if ((p[0].x > 0 && p[1].x > 0 && p[2].x > 0 && p[3].x > 0) || (p[0].x < 0 && p[1].x < 0 && p[2].x < 0 && p[3].x < 0) ||
        (p[0].y > 0 && p[1].y > 0 && p[2].y > 0 && p[3].y > 0) || (p[0].y < 0 && p[1].y < 0 && p[2].y < 0 && p[3].y < 0))
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
    tpk_face_hit entry, exit;
    int have_entry = 0, have_exit = 0, opposite = 0;
    for (int k = 0; k < 4; k++) {
        const int *f = tpk_tet_faces[k]; /* outward order */
        int s0 = sign[f[0]][f[1]], s1 = sign[f[1]][f[2]], s2 = sign[f[2]][f[0]];
        if (s0 != s1 || s1 != s2)
            continue;
        /* held as the marcher holds the faces it crosses: all edge values <= 0 */
        int g[3] = {f[0], f[1], f[2]};
        if (s0 > 0)
            g[1] = f[2], g[2] = f[1];
        tpk_face_hit *h = s0 < 0 ? &entry : &exit;
        for (int i = 0; i < 3; i++) {
            h->v[i] = q[g[i]];
            h->p[i] = p[g[i]];
            h->e[i] = value[g[i]][g[(i + 1) % 3]];
        }
        if (s0 < 0)
            have_entry = 1, opposite = k;
        else
            have_exit = 1;
    }
    if (!have_entry || !have_exit)
        return 0;
    const float *sc = mesh->scalars;
    double w[3];
    int first = tpk_face_first(&entry);
    tpk_face_weights(&entry, first, w);
    double t_in = tpk_face_sum(first, w, (const double[3]){entry.p[0].z, entry.p[1].z, entry.p[2].z});
    double s_in = tpk_face_sum(first, w, (const double[3]){sc[entry.v[0]], sc[entry.v[1]], sc[entry.v[2]]});
    int c1 = tpk_face_corner[first + 1], c2 = tpk_face_corner[first + 2];
    *seg = (tpk_segment){(int32_t)t, t_in, 0, s_in, 0, {entry.v[first], entry.v[c1], entry.v[c2], q[opposite]}};
    first = tpk_face_first(&exit);
    tpk_face_weights(&exit, first, w);
    double t_out = tpk_face_sum(first, w, (const double[3]){exit.p[0].z, exit.p[1].z, exit.p[2].z});
    seg->t_out = t_out >= t_in ? t_out : t_in;
    seg->scalar_out = tpk_face_sum(first, w, (const double[3]){sc[exit.v[0]], sc[exit.v[1]], sc[exit.v[2]]});
    return 1;
}

/* The marcher's clipping of a piece to [tmin, tmax] (march.c's report); 0 when nothing is left. */
static int clip_piece(tpk_segment *seg, double tmin, double tmax)
{
    double t_in = seg->t_in, t_out = seg->t_out, s_in = seg->scalar_in, s_out = seg->scalar_out;
    if (t_out < tmin || t_in > tmax)
        return 0;
    double len = t_out - t_in;
    if (t_in < tmin) {
        seg->t_in = tmin;
        seg->scalar_in = s_in + (s_out - s_in) * ((tmin - t_in) / len);
    }
    if (t_out > tmax) {
        seg->t_out = tmax;
        seg->scalar_out = s_in + (s_out - s_in) * ((tmax - t_in) / len);
    }
    return 1;
}

tpk_result tpk_march_ray_values(const tpk_range_bvh *b, const double org[3], const double dir[3], double tmin,
                                double tmax, const double *values, int value_count, tpk_segment_fn fn,
                                void *user, tpk_march_stats *stats)
{
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!b || !org || !dir || isnan(tmin) || isnan(tmax) || value_count < 0 || (value_count > 0 && !values))
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_ray_frame frame;
    if (tpki_ray_frame_init(&frame, b->marcher->mesh.origin, org, dir) != 0)
        return TPK_ERR_INVALID_ARGUMENT;
    if (tmax < tmin || b->levels == 0 || value_count == 0)
        return TPK_OK;
    double inv[3];
    for (int k = 0; k < 3; k++)
        inv[k] = 1.0 / dir[k];
    /* t of the box tests and of the pieces differ by rounding: a node is due a little before its box */
    double dir_len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double slack = 1e-9 * (b->marcher->extent + fabs(frame.org[0]) + fabs(frame.org[1]) + fabs(frame.org[2])) / dir_len;

    heap_item node_stack[HEAP_STACK], piece_stack[HEAP_STACK];
    tpk_segment piece_buf[HEAP_STACK];
    heap nodes = {node_stack, node_stack, 0, HEAP_STACK}, pieces_heap = {piece_stack, piece_stack, 0, HEAP_STACK};
    tpk_segment *pieces = piece_buf;
    int64_t piece_count = 0, piece_cap = HEAP_STACK;
    tpk_result r = TPK_OK;
    uint64_t tested = 0;
    int stop = 0;

    int top = b->levels - 1;
    const range_node *root = &b->nodes[b->level_start[top]];
    double t_root = holds_value(root->smin, root->smax, values, value_count)
                        ? box_entry(root, frame.org, inv, b->pad, tmin, tmax) : INFINITY;
    if (t_root < INFINITY && heap_push(&nodes, t_root - slack, (int64_t)top << 40))
        r = TPK_ERR_OUT_OF_MEMORY;
    while (r == TPK_OK && !stop && (nodes.count > 0 || pieces_heap.count > 0)) {
        /* hand on every piece that starts before any node left can */
        if (pieces_heap.count > 0 && (nodes.count == 0 || pieces_heap.items[0].key < nodes.items[0].key)) {
            heap_item it = heap_pop(&pieces_heap);
            tpk_segment seg = pieces[it.index];
            if (fn && fn(user, &seg))
                stop = 1;
            if (seg.t_out >= tmax)
                stop = 1;
            continue;
        }
        heap_item it = heap_pop(&nodes);
        int level = (int)(it.index >> 40);
        int64_t i = it.index & (((int64_t)1 << 40) - 1);
        /* down the tree: the nearer child straight on while nothing queued comes before it, the other
         * child queued */
        while (level > 0 && r == TPK_OK) {
            double key[2] = {INFINITY, INFINITY};
            int64_t child[2] = {-1, -1};
            int found = 0;
            for (int64_t c = 2 * i; c <= 2 * i + 1 && c < b->level_count[level - 1]; c++) {
                const range_node *n = &b->nodes[b->level_start[level - 1] + c];
                if (!holds_value(n->smin, n->smax, values, value_count))
                    continue;
                double t0 = box_entry(n, frame.org, inv, b->pad, tmin, tmax);
                if (t0 < INFINITY)
                    key[found] = t0 - slack, child[found++] = c;
            }
            if (found == 2 && key[1] < key[0]) {
                double k = key[0];
                int64_t c = child[0];
                key[0] = key[1], child[0] = child[1];
                key[1] = k, child[1] = c;
            }
            if (found == 2 && heap_push(&nodes, key[1], (int64_t)(level - 1) << 40 | child[1]))
                r = TPK_ERR_OUT_OF_MEMORY;
            if (found == 0)
                break;
            if ((nodes.count > 0 && nodes.items[0].key < key[0]) ||
                (pieces_heap.count > 0 && pieces_heap.items[0].key < key[0])) {
                if (heap_push(&nodes, key[0], (int64_t)(level - 1) << 40 | child[0]))
                    r = TPK_ERR_OUT_OF_MEMORY;
                break;
            }
            level--;
            i = child[0];
        }
        if (level > 0)
            continue;
        int64_t tet_count = (int64_t)b->marcher->mesh.tet_count;
        int64_t end = (i + 1) * TPK_RANGE_LEAF < tet_count ? (i + 1) * TPK_RANGE_LEAF : tet_count;
        for (int64_t t = i * TPK_RANGE_LEAF; t < end && r == TPK_OK; t++) {
            if (!holds_value(b->tet_range[2 * t], b->tet_range[2 * t + 1], values, value_count))
                continue;
            tested++;
            tpk_segment seg;
            if (!tet_piece(b, &frame, t, &seg) || !clip_piece(&seg, tmin, tmax) ||
                !crosses(seg.scalar_in, seg.scalar_out, values, value_count))
                continue;
            if (piece_count == piece_cap) {
                tpk_segment *grown = malloc(sizeof *grown * (size_t)(2 * piece_cap));
                if (!grown) {
                    r = TPK_ERR_OUT_OF_MEMORY;
                    break;
                }
                memcpy(grown, pieces, sizeof *grown * (size_t)piece_count);
                if (pieces != piece_buf)
                    free(pieces);
                pieces = grown;
                piece_cap *= 2;
            }
            pieces[piece_count] = seg;
            if (heap_push(&pieces_heap, seg.t_in, piece_count++))
                r = TPK_ERR_OUT_OF_MEMORY;
        }
    }
    if (pieces != piece_buf)
        free(pieces);
    heap_free(&nodes);
    heap_free(&pieces_heap);
    if (stats)
        stats->tet_steps = tested;
    return r;
}
