/* Range culling for packets of iso rays from one origin (tpk_march_packet_values, tetpack.h): a camera's
 * primary rays through neighbouring pixels walk the selected tree together.
 *
 * A wide node's four children are tested once for the whole packet, by interval arithmetic over the
 * rays' 1/d (they share the origin, so only 1/d differs): float rounding is monotone, so the interval's
 * entry is at or before each ray's own float entry (range_bvh.c's wide_entry) and its exit at or after
 * each ray's exit; where the interval misses a child, every ray misses it. At a leaf, each tet is tested
 * in float, each test dropping only tets whose exact test (tpki_tet_piece) would find no crossing piece:
 * for the packet (its corners all on one side of every ray, in x or in y of the rays' sheared frames),
 * then four rays at a time (the same for each ray; then each face's 2-D edge functions, a face holding
 * a ray only where they share a sign; then, where two faces hold the ray for sure, the scalar at each,
 * against the values). Every float test keeps a margin well beyond its rounding and the exact test's.
 * What is left is tested exactly, ray by ray.
 *
 * Each ray keeps its own pieces, in tpki_piece_before's order, and hands the first on once no node left
 * can hold one that starts before it, as a ray alone does: a node's key is at or before each ray's, so
 * each ray makes the same calls, in the same order, as alone. As rays finish, the bounds of both float
 * tests (1/d, the shear, [tmin, tmax]) narrow to the rays still walking (packet_bounds): a finished ray
 * takes no more pieces, so what only it could meet need not be tested.
 *
 * Measured on the 998k-tet grid of bench/make_grid_vtk.py 55, iso 0.3, 1024^2, 4x4 packets, one thread:
 * 0.46M exact tet tests where rays alone make 7.8M, and about 2.5 times the rays per second. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_range.h"

#define NODE_STACK 64
#define PIECE_STACK 8

typedef struct packet_ray {
    tpk_ray_frame frame; /* made when the ray first needs it (framed) */
    const double *dir;
    int framed;
    double tmin, tmax;
    tpk_segment_fn fn;
    void *user;
    tpk_segment *pieces; /* found and not handed on: [first, count), in tpki_piece_before's order */
    int64_t first, count, cap;
    tpk_segment buf[PIECE_STACK];
    uint64_t tested;
    int active;
    double sx, sy;    /* the frame's shear */
    float t_lo, t_hi; /* tmin and tmax rounded outward */
} packet_ray;

typedef struct node_item {
    double key;
    int64_t ref; /* a wide node (>= 0) or a leaf (tpki_leaf_ref) */
} node_item;

typedef struct packet {
    const tpk_range_bvh *b;
    const double *values;
    int value_count;
    packet_ray *rays;
    int ray_count, active;
    int bounded; /* the rays still walking when the bounds below were last taken over them */
    int kx, ky, kz; /* every ray's frame has these axes */
    const double *org;
    /* the children test: the origin, 1/d's bounds over the rays, the largest widening, tmin and tmax */
    tpki_v4f o[3], inv_lo[3], inv_hi[3], pad_t[3], tmin, tmax;
    int near[3], far[3];
    double slack; /* the largest of the rays' (range_bvh.c: a node is due a little before its box) */
    double widen; /* tpki_box_widen's */
    /* the float tet test: the origin, the shear's bounds over the rays, the margin for rounding */
    tpki_v4f of[3];
    float sx_lo, sx_hi, sy_lo, sy_hi, margin;
    tpki_v4f sx[TPK_MARCH_PACKET / 4], sy[TPK_MARCH_PACKET / 4]; /* each ray's shear, four rays a vector */
    tpki_v4i live[TPK_MARCH_PACKET / 4]; /* -1 for each ray still walking */
    unsigned walking;                    /* the same, bit i for ray i */
    unsigned holding;                    /* bit i: ray i holds pieces not handed on */
    double piece_min; /* at or before the first piece of every ray that has one (+inf: none) */
    node_item *nodes, node_stack[NODE_STACK]; /* by key, then ref */
    int64_t node_count, node_cap;
    tpk_result r;
} packet;

static int node_before(const node_item *a, const node_item *b)
{
    return a->key < b->key || (a->key == b->key && a->ref < b->ref);
}

static void node_push(packet *p, double key, int64_t ref)
{
    if (p->node_count == p->node_cap) {
        void *nodes = p->nodes;
        if (tpki_grow(&nodes, p->node_stack, p->node_count, &p->node_cap, sizeof *p->nodes) != 0) {
            p->r = TPK_ERR_OUT_OF_MEMORY;
            return;
        }
        p->nodes = nodes;
    }
    const node_item item = {key, ref};
    int64_t i = p->node_count++;
    while (i > 0 && node_before(&item, &p->nodes[(i - 1) / 2])) {
        p->nodes[i] = p->nodes[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    p->nodes[i] = item;
}

static int64_t node_pop(packet *p)
{
    int64_t top = p->nodes[0].ref, i = 0;
    node_item last = p->nodes[--p->node_count];
    for (;;) {
        int64_t c = 2 * i + 1;
        if (c >= p->node_count)
            break;
        if (c + 1 < p->node_count && node_before(&p->nodes[c + 1], &p->nodes[c]))
            c++;
        if (!node_before(&p->nodes[c], &last))
            break;
        p->nodes[i] = p->nodes[c];
        i = c;
    }
    p->nodes[i] = last;
    return top;
}

/* The children test's and the float tet test's bounds over the rays still walking: 1/d, the shear and
 * [tmin, tmax]. A ray that is done needs nothing more, so the walk narrows them as rays finish. */
static void packet_bounds(packet *p)
{
    double d_lo[3] = {INFINITY, INFINITY, INFINITY}, d_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double sx_lo = INFINITY, sx_hi = -INFINITY, sy_lo = INFINITY, sy_hi = -INFINITY;
    float t_lo = INFINITY, t_hi = -INFINITY;
    for (unsigned w = p->walking; w != 0; w &= w - 1) {
        const packet_ray *r = &p->rays[__builtin_ctz(w)];
        for (int k = 0; k < 3; k++) {
            d_lo[k] = r->dir[k] < d_lo[k] ? r->dir[k] : d_lo[k];
            d_hi[k] = r->dir[k] > d_hi[k] ? r->dir[k] : d_hi[k];
        }
        sx_lo = r->sx < sx_lo ? r->sx : sx_lo, sx_hi = r->sx > sx_hi ? r->sx : sx_hi;
        sy_lo = r->sy < sy_lo ? r->sy : sy_lo, sy_hi = r->sy > sy_hi ? r->sy : sy_hi;
        t_lo = r->t_lo < t_lo ? r->t_lo : t_lo;
        t_hi = r->t_hi > t_hi ? r->t_hi : t_hi;
    }
    /* d of one sign: 1/d falls as d rises, and the divisions round monotonely, so these bound each ray's
     * 1/d (and its float) */
    for (int k = 0; k < 3; k++) {
        double inv_lo = 1.0 / d_hi[k], inv_hi = 1.0 / d_lo[k];
        double pad_t = p->widen * (fabs(inv_lo) > fabs(inv_hi) ? fabs(inv_lo) : fabs(inv_hi));
        float lo = (float)inv_lo, hi = (float)inv_hi, pt = (float)pad_t;
        p->inv_lo[k] = (tpki_v4f){lo, lo, lo, lo};
        p->inv_hi[k] = (tpki_v4f){hi, hi, hi, hi};
        p->pad_t[k] = (tpki_v4f){pt, pt, pt, pt};
    }
    p->tmin = (tpki_v4f){t_lo, t_lo, t_lo, t_lo};
    p->tmax = (tpki_v4f){t_hi, t_hi, t_hi, t_hi};
    p->sx_lo = (float)sx_lo, p->sx_hi = (float)sx_hi, p->sy_lo = (float)sy_lo, p->sy_hi = (float)sy_hi;
    p->bounded = p->active;
}

/* Hand on each ray's pieces that start before `due`, as a ray alone does (range_bvh.c's walk_hand). */
static void hand_due(packet *p, double due)
{
    if (!(p->piece_min < due))
        return;
    p->piece_min = INFINITY;
    for (unsigned h = p->walking & p->holding; h != 0; h &= h - 1) { /* in ray order */
        const int i = __builtin_ctz(h);
        packet_ray *r = &p->rays[i];
        while (r->first < r->count && r->pieces[r->first].t_in < due) {
            tpk_segment seg = r->pieces[r->first++];
            if ((r->fn && r->fn(r->user, &seg)) || seg.t_out >= r->tmax) {
                r->active = 0;
                p->active--;
                p->live[i / 4][i % 4] = 0;
                p->walking &= ~(1u << i);
                break;
            }
        }
        if (r->active && r->first < r->count && r->pieces[r->first].t_in < p->piece_min)
            p->piece_min = r->pieces[r->first].t_in;
        if (!r->active || r->first == r->count)
            p->holding &= ~(1u << i);
    }
    if (p->active > 0 && p->active < p->bounded)
        packet_bounds(p);
}

/* Something queued, a node or a ray's piece, comes before `key`. */
static int due_before(const packet *p, double key)
{
    return (p->node_count > 0 && p->nodes[0].key < key) || p->piece_min < key;
}

/* Tet t (slot: its copy) for ray r, exactly: its piece queued if it crosses a value. */
static void ray_tet(packet *p, packet_ray *r, int64_t t, const tpki_active_slot *slot)
{
    r->tested++;
    if (!r->framed) {
        tpki_ray_frame_init(&r->frame, p->b->marcher->mesh.origin, p->org, r->dir); /* as the first ray's */
        r->framed = 1;
    }
    tpk_segment seg;
    if (!tpki_tet_piece(p->b, &r->frame, t, slot, &seg) || !tpki_clip_piece(&seg, r->tmin, r->tmax) ||
        !tpki_crosses(seg.scalar_in, seg.scalar_out, p->values, p->value_count))
        return;
    if (r->count == r->cap && r->first > 0) {
        memmove(r->pieces, r->pieces + r->first, sizeof *r->pieces * (size_t)(r->count - r->first));
        r->count -= r->first;
        r->first = 0;
    } else if (r->count == r->cap) {
        void *pieces = r->pieces;
        if (tpki_grow(&pieces, r->buf, r->count, &r->cap, sizeof *r->pieces) != 0) {
            p->r = TPK_ERR_OUT_OF_MEMORY;
            return;
        }
        r->pieces = pieces;
    }
    int64_t at = r->count++;
    for (; at > r->first && tpki_piece_before(&seg, &r->pieces[at - 1]); at--)
        r->pieces[at] = r->pieces[at - 1];
    r->pieces[at] = seg;
    p->holding |= 1u << (r - p->rays);
    p->piece_min = seg.t_in < p->piece_min ? seg.t_in : p->piece_min;
}

static inline int all4(tpki_v4i m)
{
    return tpki_v4_bits(m) == 15;
}

/* The four corners (x or y in a frame) all beyond the margin on one side. */
static inline int one_side(tpki_v4f lo, tpki_v4f hi, float margin)
{
    return all4(lo > margin) || all4(hi < -margin);
}

static inline tpki_v4f v4_abs(tpki_v4f a)
{
    return (tpki_v4f)((tpki_v4i)a & (tpki_v4i){INT32_MAX, INT32_MAX, INT32_MAX, INT32_MAX});
}

/* A tet's edges 01, 02, 03, 12, 13, 23. */
static const int8_t edge_from[6] = {0, 0, 0, 1, 1, 2}, edge_to[6] = {1, 2, 3, 2, 3, 3};

/* The scalar of a face's crossing against v, four rays at once: up and down get the lanes where it lies
 * above or below v for sure. The crossing's weights are the face's edge functions, corner c's the
 * function of the edge opposite it (|e ab| for c, |e bc| for a, |e ac| for b, all of one sign there and
 * each off by at most err): the scalar minus v has the sign of sum = the weighted sum of d = s - v at
 * the corners. Computed in float, sum is off by at most (1.01 err + 2^-21 reach) spread (reach the sum
 * of the weights, spread that of |d|); the exact test's own scalar, summed in doubles, is off by at
 * most 2^-49 of the largest |s|. The bound holds each twice over or more. */
static inline void face_scalar(tpki_v4f w_a, tpki_v4f w_b, tpki_v4f w_c, float d_a, float d_b, float d_c,
                               tpki_v4f err, float s_max, tpki_v4i *up, tpki_v4i *down)
{
    tpki_v4f sum = w_a * d_a + w_b * d_b + w_c * d_c, reach = w_a + w_b + w_c;
    float spread = fabsf(d_a) + fabsf(d_b) + fabsf(d_c);
    tpki_v4f bound = (2 * err + 0x1p-17f * reach) * spread + 0x1p-45f * s_max * reach;
    *up = sum > bound;
    *down = sum < -bound;
}

/* Lanes of `two` (exactly two faces, the piece's entry and exit, hold the ray for sure) whose piece
 * crosses none of the values: both faces' scalars on one side of each. */
static tpki_v4i crosses_none(const packet *p, tpki_v4i two, const tpki_v4i possible[4], const tpki_v4f e[6],
                             tpki_v4f err, tpki_v4f sc)
{
    const double s[4] = {sc[0], sc[1], sc[2], sc[3]};
    float s_max = 0;
    for (int c = 0; c < 4; c++)
        s_max = fabsf((float)s[c]) > s_max ? fabsf((float)s[c]) : s_max;
    tpki_v4f w[6];
    for (int k = 0; k < 6; k++)
        w[k] = v4_abs(e[k]);
    tpki_v4i none = two;
    for (int j = 0; j < p->value_count; j++) {
        const float d[4] = {(float)(s[0] - p->values[j]), (float)(s[1] - p->values[j]), (float)(s[2] - p->values[j]),
                            (float)(s[3] - p->values[j])};
        tpki_v4i up[4], down[4];
        /* faces 012, 013, 023, 123: corner a weighs |e bc|, b |e ac|, c |e ab| */
        face_scalar(w[3], w[1], w[0], d[0], d[1], d[2], err, s_max, &up[0], &down[0]);
        face_scalar(w[4], w[2], w[0], d[0], d[1], d[3], err, s_max, &up[1], &down[1]);
        face_scalar(w[5], w[2], w[1], d[0], d[2], d[3], err, s_max, &up[2], &down[2]);
        face_scalar(w[5], w[4], w[3], d[1], d[2], d[3], err, s_max, &up[3], &down[3]);
        tpki_v4i all_up = (~possible[0] | up[0]) & (~possible[1] | up[1]) & (~possible[2] | up[2]) &
                          (~possible[3] | up[3]);
        tpki_v4i all_down = (~possible[0] | down[0]) & (~possible[1] | down[1]) & (~possible[2] | down[2]) &
                            (~possible[3] | down[3]);
        none &= all_up | all_down;
    }
    return none;
}

/* A face's edge functions ab, bc (as they are) and ac (backwards), beyond the margin up (p) or down (n),
 * four rays at once: the face may hold the ray unless two lie on opposite sides; it surely does when
 * all three lie on one side. */
static inline void face_test(tpki_v4i p_ab, tpki_v4i p_bc, tpki_v4i p_ac, tpki_v4i n_ab, tpki_v4i n_bc,
                             tpki_v4i n_ac, tpki_v4i *possible, tpki_v4i *sure)
{
    tpki_v4i up = p_ab | p_bc | n_ac, down = n_ab | n_bc | p_ac;
    *possible = ~(up & down);
    *sure = (p_ab & p_bc & n_ac) | (n_ab & n_bc & p_ac);
}

/* A tet (slot) for four rays (group g), their corners' x and y in their frames in float, each off by at
 * most d / 8: queue it for the exact test in the rays for which it may hold a crossing piece.
 * A face (a, b, c) holds a ray, the point (0, 0), when its edge functions x_a y_b - y_a x_b,
 * x_b y_c - y_b x_c and -(x_a y_c - y_a x_c) share a sign; it cannot when two of them are beyond the
 * margin on opposite sides. The margin holds the floats' rounding of the products and of the corners
 * (four times over), so what this drops the exact test drops too. Where two faces hold the ray for
 * sure and no other may, they are the piece's entry and exit (crosses_none). */
static void group_tet(packet *p, int g, const tpki_v4f x[4], const tpki_v4f y[4], tpki_v4i off, float d,
                      int64_t slot)
{
    tpki_v4f big = tpki_v4_max(tpki_v4_max(v4_abs(x[0]), v4_abs(y[0])), tpki_v4_max(v4_abs(x[1]), v4_abs(y[1])));
    big = tpki_v4_max(big, tpki_v4_max(tpki_v4_max(v4_abs(x[2]), v4_abs(y[2])), tpki_v4_max(v4_abs(x[3]), v4_abs(y[3]))));
    tpki_v4f margin = 2 * d * big + 0x1p-19f * big * big + d * d;
    tpki_v4f e[6];
    tpki_v4i pos[6], neg[6], possible[4], sure[4];
    for (int k = 0; k < 6; k++) {
        int a = edge_from[k], b = edge_to[k];
        e[k] = x[a] * y[b] - y[a] * x[b];
        pos[k] = e[k] > margin;
        neg[k] = e[k] < -margin;
    }
    face_test(pos[0], pos[3], pos[1], neg[0], neg[3], neg[1], &possible[0], &sure[0]);
    face_test(pos[0], pos[4], pos[2], neg[0], neg[4], neg[2], &possible[1], &sure[1]);
    face_test(pos[1], pos[5], pos[2], neg[1], neg[5], neg[2], &possible[2], &sure[2]);
    face_test(pos[3], pos[5], pos[4], neg[3], neg[5], neg[4], &possible[3], &sure[3]);
    tpki_v4i go = (possible[0] | possible[1] | possible[2] | possible[3]) & ~off & p->live[g];
    int go_bits = tpki_v4_bits(go);
    if (go_bits == 0)
        return;
    /* lanes where exactly two faces may hold the ray, both for sure: the piece's scalars decide */
    tpki_v4i faces = -(possible[0] + possible[1] + possible[2] + possible[3]);
    tpki_v4i sure_faces = -(sure[0] + sure[1] + sure[2] + sure[3]);
    tpki_v4i two = (faces == 2) & (sure_faces == 2);
    const tpki_active_slot *s = &p->b->active_slots[slot];
    if (tpki_v4_bits(two) != 0)
        go_bits &= ~tpki_v4_bits(crosses_none(p, two, possible, e, margin, p->b->active_scalars[slot]));
    for (; go_bits != 0; go_bits &= go_bits - 1)
        ray_tet(p, &p->rays[4 * g + __builtin_ctz((unsigned)go_bits)], p->b->active_tets[slot], s);
}

/* A leaf's tets: for the packet, then four rays at a time in float, then exactly. */
static void packet_leaf(packet *p, int64_t first, int64_t count)
{
    const tpk_range_bvh *b = p->b;
    const int kx = p->kx, ky = p->ky, kz = p->kz;
    const float m = p->margin;
    for (int64_t s = first; s < first + count && p->r == TPK_OK; s++) {
        const tpki_active_slot *slot = &b->active_slots[s];
        tpki_v4f qx = slot->pos[kx] - p->of[kx], qy = slot->pos[ky] - p->of[ky], qz = slot->pos[kz] - p->of[kz];
        /* x = qx - sx qz is linear in sx: between its values at the shear's bounds */
        tpki_v4f xa = qx - p->sx_lo * qz, xb = qx - p->sx_hi * qz;
        tpki_v4f ya = qy - p->sy_lo * qz, yb = qy - p->sy_hi * qz;
        if (one_side(tpki_v4_min(xa, xb), tpki_v4_max(xa, xb), m) ||
            one_side(tpki_v4_min(ya, yb), tpki_v4_max(ya, yb), m))
            continue;
        /* four rays at a time: their x and y at each corner */
        tpki_v4f cx[4], cy[4], cz[4];
        for (int c = 0; c < 4; c++) {
            cx[c] = (tpki_v4f){qx[c], qx[c], qx[c], qx[c]};
            cy[c] = (tpki_v4f){qy[c], qy[c], qy[c], qy[c]};
            cz[c] = (tpki_v4f){qz[c], qz[c], qz[c], qz[c]};
        }
        for (int g = 0; 4 * g < p->ray_count && p->r == TPK_OK; g++) {
            tpki_v4f x[4], y[4];
            for (int c = 0; c < 4; c++)
                x[c] = cx[c] - p->sx[g] * cz[c], y[c] = cy[c] - p->sy[g] * cz[c];
            tpki_v4f x_lo = tpki_v4_min(tpki_v4_min(x[0], x[1]), tpki_v4_min(x[2], x[3]));
            tpki_v4f x_hi = tpki_v4_max(tpki_v4_max(x[0], x[1]), tpki_v4_max(x[2], x[3]));
            tpki_v4f y_lo = tpki_v4_min(tpki_v4_min(y[0], y[1]), tpki_v4_min(y[2], y[3]));
            tpki_v4f y_hi = tpki_v4_max(tpki_v4_max(y[0], y[1]), tpki_v4_max(y[2], y[3]));
            tpki_v4i off = (x_lo > m) | (x_hi < -m) | (y_lo > m) | (y_hi < -m);
            if (all4(off))
                continue;
            group_tet(p, g, x, y, off, m, s);
        }
    }
}

/* The children of a wide node that some ray of the packet may meet (bit i: child i), and their entries
 * (near: before each ray's). */
static inline int packet_children(const packet *p, const tpki_wide_node *n, tpki_v4f *near_out)
{
    tpki_v4f near, far;
    for (int k = 0; k < 3; k++) {
        tpki_v4f a = n->box[p->near[k]] - p->o[k], c = n->box[p->far[k]] - p->o[k];
        tpki_v4f lo = tpki_v4_min(a * p->inv_lo[k], a * p->inv_hi[k]) - p->pad_t[k];
        tpki_v4f hi = tpki_v4_max(c * p->inv_lo[k], c * p->inv_hi[k]) + p->pad_t[k];
        near = k ? tpki_v4_max(near, lo) : lo;
        far = k ? tpki_v4_min(far, hi) : hi;
    }
    *near_out = near;
    return tpki_v4_bits((near <= far) & (far >= p->tmin) & (near <= p->tmax));
}

/* The walk: range_bvh.c's walk_selected, for the packet. */
static void packet_walk(packet *p)
{
    const tpk_range_bvh *b = p->b;
    node_push(p, -INFINITY, 0);
    while (p->r == TPK_OK && p->active > 0) {
        hand_due(p, p->node_count > 0 ? p->nodes[0].key : INFINITY);
        if (p->node_count == 0 || p->active == 0)
            break;
        int64_t ref = node_pop(p);
        while (ref >= 0 && p->r == TPK_OK) {
            const tpki_wide_node *n = &b->wide[ref];
            double key[4];
            int64_t child[4];
            int found = 0;
            tpki_v4f near;
            for (int hit = packet_children(p, n, &near); hit != 0; hit &= hit - 1) {
                const int i = __builtin_ctz((unsigned)hit); /* the children met, in order */
                const double t0 = (double)near[i] - p->slack;
                if (t0 == INFINITY)
                    continue;
                int64_t c = n->count[i] == 0 ? n->child[i] : tpki_leaf_ref(n->child[i], n->count[i]);
                int at = found++;
                for (; at > 0 && key[at - 1] > t0; at--) /* nearest first */
                    key[at] = key[at - 1], child[at] = child[at - 1];
                key[at] = t0, child[at] = c;
            }
            for (int i = 1; i < found; i++)
                node_push(p, key[i], child[i]);
            if (found == 0 || due_before(p, key[0])) {
                if (found > 0)
                    node_push(p, key[0], child[0]);
                ref = 0; /* the root is no one's child: nothing to test here */
                break;
            }
            ref = child[0];
        }
        if (ref < 0)
            packet_leaf(p, tpki_leaf_first(ref), tpki_leaf_count(ref));
    }
}

/* Set the packet up; 0 when its rays cannot walk together (axes, signs or magnitudes that differ or
 * that floats cannot hold, an empty span): then they walk in halves (packet_or_halves). */
static int packet_init(packet *p, const tpk_range_bvh *b, const double org[3], int ray_count,
                       const double (*dirs)[3], const double *tmin, const double *tmax)
{
    const tpk_marcher *marcher = b->marcher;
    double d2_min = INFINITY;
    for (int g = 0; g < TPK_MARCH_PACKET / 4; g++)
        p->sx[g] = p->sy[g] = (tpki_v4f){0, 0, 0, 0}, p->live[g] = (tpki_v4i){0, 0, 0, 0};
    /* the first ray's frame gives the axes; the others' frames, made when they first need one, must have
     * the same: kz their largest axis as tpki_ray_frame_init picks it, and the same sign along it */
    if (tpki_ray_frame_init(&p->rays[0].frame, marcher->mesh.origin, org, dirs[0]) != 0)
        return 0;
    p->kx = p->rays[0].frame.kx, p->ky = p->rays[0].frame.ky, p->kz = p->rays[0].frame.kz;
    const int kx = p->kx, ky = p->ky, kz = p->kz;
    double d_lo[3] = {INFINITY, INFINITY, INFINITY}, d_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    int bad = 0; /* bitwise, not short-circuit: one branch for the packet, not several per ray */
    for (int i = 0; i < ray_count; i++) {
        packet_ray *r = &p->rays[i];
        const double *d = dirs[i];
        double a0 = fabs(d[0]), a1 = fabs(d[1]), a2 = fabs(d[2]);
        /* tpki_ray_frame_init takes axis 1 over 0 and 2 over both only where strictly larger */
        bad |= !(tmin[i] <= tmax[i]);
        bad |= kz == 0 ? !((a1 <= a0) & (a2 <= a0)) : kz == 1 ? !((a1 > a0) & (a2 <= a1)) : !((a2 > a0) & (a2 > a1));
        for (int k = 0; k < 3; k++) {
            /* 1/d finite and not 0 in floats, of the first ray's sign (a NaN is bad: the bounds below
             * are then unused) */
            bad |= !((fabs(d[k]) > 1e-30) & (fabs(d[k]) < 1e30)) | ((d[k] > 0) != (dirs[0][k] > 0));
            d_lo[k] = d[k] < d_lo[k] ? d[k] : d_lo[k];
            d_hi[k] = d[k] > d_hi[k] ? d[k] : d_hi[k];
        }
        double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        d2_min = d2 < d2_min ? d2 : d2_min;
        r->t_lo = tmin[i] > -1e30 ? tpki_round_down(tmin[i]) : -INFINITY;
        r->t_hi = tmax[i] < 1e30 ? tpki_round_up(tmax[i]) : INFINITY;
        /* the frame's shear, as tpki_ray_frame_init computes it */
        r->sx = d[kx] / d[kz], r->sy = d[ky] / d[kz];
        p->sx[i / 4][i % 4] = (float)r->sx, p->sy[i / 4][i % 4] = (float)r->sy;
        r->dir = d;
        r->framed = i == 0;
        r->active = 1;
    }
    if (bad)
        return 0;
    p->org = org;
    const double *o = p->rays[0].frame.org;
    p->slack = 1e-9 * (marcher->extent + fabs(o[0]) + fabs(o[1]) + fabs(o[2])) / sqrt(d2_min);
    double o_max = fmax(fabs(o[0]), fmax(fabs(o[1]), fabs(o[2])));
    if (!(o_max < 1e30))
        return 0;
    p->widen = tpki_box_widen(b->pad, marcher->extent, o_max);
    for (int k = 0; k < 3; k++) {
        /* 1/d of the ray nearest 0 along k: the largest */
        double pad_t = p->widen * fmax(fabs(1.0 / d_lo[k]), fabs(1.0 / d_hi[k]));
        if (!(pad_t < 1e30))
            return 0;
        float ok = (float)o[k];
        p->o[k] = (tpki_v4f){ok, ok, ok, ok};
        p->near[k] = d_lo[k] > 0 ? k : k + 3;
        p->far[k] = d_lo[k] > 0 ? k + 3 : k;
        p->of[k] = p->o[k];
    }
    /* the float tet test: a corner's x, qx - sx qz with q = corner - origin, is off by at most
     * 2^-24 (3 + 5 |sx|) S, S the largest |corner| plus the largest |origin|, and |sx| <= 1 (kz is the
     * direction's largest axis): the margin is 8 times that */
    double corner_max = b->active_corner_max;
    double margin = ldexp(corner_max + o_max, -18);
    if (!(corner_max + o_max < 1e15))
        return 0; /* the edge test squares the margin in float */
    p->margin = (float)margin;
    p->active = ray_count;
    p->walking = (1u << ray_count) - 1;
    p->holding = 0;
    packet_bounds(p);
    return 1;
}

/* The rays as one packet, its result into *result: 0 when they cannot walk together (packet_init). Not
 * inlined, so that packet_or_halves's frames stay small (its halves take turns with this one's arrays). */
__attribute__((noinline)) static int packet_march(const tpk_range_bvh *b, const double org[3], int ray_count,
                                                  const double (*dirs)[3], const double *tmin, const double *tmax,
                                                  const double *values, int value_count, const tpk_segment_fn *fns,
                                                  void *const *users, tpk_march_stats *stats, tpk_result *result)
{
    packet_ray rays[TPK_MARCH_PACKET];
    packet state;
    packet *p = &state;
    p->b = b, p->values = values, p->value_count = value_count, p->rays = rays, p->ray_count = ray_count;
    if (!packet_init(p, b, org, ray_count, dirs, tmin, tmax))
        return 0;
    for (int i = 0; i < ray_count; i++) {
        packet_ray *r = &rays[i];
        r->tmin = tmin[i], r->tmax = tmax[i], r->fn = fns[i], r->user = users[i];
        r->pieces = r->buf, r->first = r->count = 0, r->cap = PIECE_STACK;
        r->tested = 0;
        p->live[i / 4][i % 4] = -1;
    }
    p->piece_min = INFINITY;
    p->nodes = p->node_stack, p->node_count = 0, p->node_cap = NODE_STACK;
    p->r = TPK_OK;
    packet_walk(p);
    for (int i = 0; i < ray_count; i++) {
        if (rays[i].pieces != rays[i].buf)
            free(rays[i].pieces);
        if (stats) {
            memset(&stats[i], 0, sizeof stats[i]);
            stats[i].tet_steps = rays[i].tested;
        }
    }
    if (p->nodes != p->node_stack)
        free(p->nodes);
    *result = p->r;
    return 1;
}

/* The rays as one packet or, where they cannot walk together, as two packets of half of them each, down
 * to one ray alone: the pixels along the lines where a direction's sign or largest axis changes walk in
 * smaller packets, not one by one. The first ray's error (in order), as alone. */
static tpk_result packet_or_halves(const tpk_range_bvh *b, const double org[3], int ray_count,
                                   const double (*dirs)[3], const double *tmin, const double *tmax,
                                   const double *values, int value_count, const tpk_segment_fn *fns,
                                   void *const *users, tpk_march_stats *stats)
{
    tpk_result r;
    if (packet_march(b, org, ray_count, dirs, tmin, tmax, values, value_count, fns, users, stats, &r))
        return r;
    if (ray_count == 1)
        return tpk_march_ray_values(b, org, dirs[0], tmin[0], tmax[0], values, value_count, fns[0], users[0], stats);
    int half = ray_count / 2;
    tpk_result first = packet_or_halves(b, org, half, dirs, tmin, tmax, values, value_count, fns, users, stats);
    tpk_result second = packet_or_halves(b, org, ray_count - half, dirs + half, tmin + half, tmax + half, values,
                                         value_count, fns + half, users + half, stats ? stats + half : NULL);
    return first != TPK_OK ? first : second;
}

tpk_result tpk_march_packet_values(const tpk_range_bvh *b, const double org[3], int ray_count,
                                   const double (*dirs)[3], const double *tmin, const double *tmax,
                                   const double *values, int value_count, const tpk_segment_fn *fns,
                                   void *const *users, tpk_march_stats *stats)
{
    if (!b || !org || !dirs || !tmin || !tmax || !fns || !users || ray_count < 0 ||
        ray_count > TPK_MARCH_PACKET || value_count < 0 || (value_count > 0 && !values))
        return TPK_ERR_INVALID_ARGUMENT;
    if (ray_count > 0 && (b->levels > 0 || b->culled) && value_count > 0 && b->wide_count > 0 &&
        tpki_range_selected(b, values, value_count))
        return packet_or_halves(b, org, ray_count, dirs, tmin, tmax, values, value_count, fns, users, stats);
    tpk_result first = TPK_OK;
    for (int i = 0; i < ray_count; i++) {
        tpk_result r = tpk_march_ray_values(b, org, dirs[i], tmin[i], tmax[i], values, value_count, fns[i], users[i],
                                            stats ? &stats[i] : NULL);
        first = first == TPK_OK ? r : first;
    }
    return first;
}
