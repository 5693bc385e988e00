// Part of render.comp, included once, in the order it lists.
// Range culling of iso-only primary rays (libtetpack/range_bvh.c; render.h ISO-ONLY RAYS).

// ---- Range culling of iso-only primary rays (libtetpack/range_bvh.c; render.h ISO-ONLY RAYS) -------
// The TF is transparent, so only the pieces that hold an iso crossing change the pixel. They come from
// the range BVH (tpk_range_bvh_heap: heap order, node n's children 2n and 2n + 1, leaves of
// TPK_VK_RANGE_LEAF consecutive tets from node P.shell_info.z on), one query at a time: the first piece
// after the last one handed on in (t_in, t_out, tet) order, over the nodes whose range holds a value and
// whose box the ray meets before the best piece found, nearer child first. The walk needs no stack: the
// parent of n is n / 2 and a bit per depth says which child was entered first, so a query's whole state
// is a node, where it came from and those bits (CullTrace), and a sliced ray stops after any node. Each candidate tet's
// piece is computed as the marcher computes it (face_weights, hit_t, hit_scalar from each face's
// smallest id), so report() gets the same pieces, bit for bit, and the picture is the same.

struct CullTrace {
    float t_prev, t_out_prev; // the last piece handed on (-inf: none yet)
    int tet_prev;
    uint node;     // the query's node
    uint from;     // 0: node was entered from above (the ray meets its box); else the child the walk came up from
    uint trail;    // bit d: at depth d (node n's depth is findMSB(n)) the walk went right first
    int best;      // the best piece of the query so far (tet), -1: none
    float best_in, best_out;
    bool in_query, have_piece; // have_piece: `best` is to be handed on (again, after a pause)
};

const int TET_FACES[12] = int[12](TPK_VK_TET_FACES);

// An iso value in [lo, hi], widened by a few float ulps of the range: the marcher's interpolated
// scalars are float sums of the vertex scalars and may leave their range by that much. Empty: lo > hi.
bool range_holds(float lo, float hi)
{
    const float m = 1e-6 * max(abs(lo), abs(hi));
    bool holds = false;
    for (int j = 0; j < P.shell_info.y; j++)
        holds = holds || (P.iso[j] >= lo - m && P.iso[j] <= hi + m);
    return lo <= hi && holds;
}

// Where the ray enters range node n's box (widened as box_enter widens), if its range holds a value and
// the ray meets it within [t_low, t_high]; +inf otherwise.
float cull_node_enter(uint n, float t_low, float t_high)
{
    const vec4 a = fetch_range_nodes(2u * n), b = fetch_range_nodes(2u * n + 1u);
    if (!range_holds(a.w, b.w))
        return INF;
    const vec3 lo = a.xyz - P.up.w, hi = b.xyz + P.up.w;
    float tn = -INF, tf = t_high;
    bool meets = true;
    for (int k = 0; k < 3; k++) {
        if (ray_dir[k] == 0.0) {
            meets = meets && frame.org[k] >= lo[k] && frame.org[k] <= hi[k];
            continue;
        }
        const float t0 = (lo[k] - frame.org[k]) * inv_dir[k], t1 = (hi[k] - frame.org[k]) * inv_dir[k];
        tn = max(tn, min(t0, t1));
        tf = min(tf, max(t0, t1));
    }
    return meets && tn <= tf && tf >= t_low ? tn : INF;
}

// The piece of tet `tet` (corners q, projected p, scalars s) as the marcher computes it (range_bvh.c's
// tet_piece): entry face the one whose outward edges all read -1, exit the one whose all read +1, each
// held with its edge values <= 0 as the marcher holds the faces it crosses. False: the ray misses it.
bool cull_piece(ivec4 q, vec4 p[4], float s[4], out float t_in, out float t_out, out float s_in,
                out float s_out, out ivec4 v)
{
    t_in = t_out = s_in = s_out = 0.0;
    v = ivec4(0);
    // edge i -> j for i < j at index (i, j): 01 02 03 12 13 23
    int sg[6];
    float val[6];
    sg[0] = edge_sign(q[0], p[0], q[1], p[1], val[0]);
    sg[1] = edge_sign(q[0], p[0], q[2], p[2], val[1]);
    sg[2] = edge_sign(q[0], p[0], q[3], p[3], val[2]);
    sg[3] = edge_sign(q[1], p[1], q[2], p[2], val[3]);
    sg[4] = edge_sign(q[1], p[1], q[3], p[3], val[4]);
    sg[5] = edge_sign(q[2], p[2], q[3], p[3], val[5]);
    Hit entry, exit;
    int opposite = -1;
    bool have_exit = false;
    for (int k = 0; k < 4; k++) {
        int g[3] = int[3](TET_FACES[3 * k], TET_FACES[3 * k + 1], TET_FACES[3 * k + 2]);
        int es[3];
        float ev[3];
        for (int i = 0; i < 3; i++) {
            const int a = g[i], b = g[i == 2 ? 0 : i + 1], lo = min(a, b), hi = max(a, b);
            const int e = lo == 0 ? hi - 1 : lo + hi; // 01 02 03 -> 0 1 2; 12 13 23 -> 3 4 5
            es[i] = a < b ? sg[e] : -sg[e];
            ev[i] = a < b ? val[e] : -val[e];
        }
        if (es[0] != es[1] || es[1] != es[2])
            continue;
        if (es[0] > 0) { // turned over: (g0, g2, g1), whose edges are the negated reversed ones
            g = int[3](g[0], g[2], g[1]);
            ev = float[3](-ev[2], -ev[1], -ev[0]);
        }
        const Hit h = Hit(ivec3(q[g[0]], q[g[1]], q[g[2]]), p[g[0]], p[g[1]], p[g[2]], vec3(ev[0], ev[1], ev[2]),
                          vec3(s[g[0]], s[g[1]], s[g[2]]), 0.0);
        if (es[0] < 0) {
            entry = h;
            opposite = k;
        } else {
            exit = h;
            have_exit = true;
        }
    }
    if (opposite < 0 || !have_exit)
        return false;
    vec3 w = face_weights(entry);
    t_in = hit_t(entry, w);
    s_in = hit_scalar(entry, w);
    v = face_from_first(entry, q[opposite]);
    w = face_weights(exit);
    t_out = hit_t(exit, w);
    if (!(t_out >= t_in))
        t_out = t_in; // rounding: as the marcher keeps its chain monotone
    s_out = hit_scalar(exit, w);
    return true;
}

// Tet `tet`'s corners, projected, and its scalars; false when its scalar range (widened as range_holds
// widens it) holds no iso value or the ray's point (0, 0) is off one side of all four.
bool cull_candidate(int tet, out ivec4 q, out vec4 p[4], out float s[4])
{
    q = fetch_range_tets(uint(tet));
    for (int i = 0; i < 4; i++)
        p[i] = project(q[i], s[i]);
    if (!range_holds(min(min(s[0], s[1]), min(s[2], s[3])), max(max(s[0], s[1]), max(s[2], s[3]))))
        return false;
    steps_taken++; // tets tested (tpk_march_ray_values' tet_steps)
    work++; // a tet tested is a few loops' worth: counted twice towards a slice
    const vec4 xs = vec4(p[0].x, p[1].x, p[2].x, p[3].x), ys = vec4(p[0].y, p[1].y, p[2].y, p[3].y);
    return !(all(greaterThan(xs, vec4(0.0))) || all(lessThan(xs, vec4(0.0))) || all(greaterThan(ys, vec4(0.0))) ||
             all(lessThan(ys, vec4(0.0))));
}

// The piece [t_in, t_out] cut to [t_min_clip, t_max_clip] as report() cuts it, holds an iso crossing.
bool cull_crosses(float t_in, float t_out, float s_in, float s_out)
{
    if (t_out < t_min_clip || t_in > t_max_clip)
        return false;
    const float len = t_out - t_in;
    float sa = s_in, sb = s_out;
    if (t_in < t_min_clip)
        sa = s_in + (s_out - s_in) * ((t_min_clip - t_in) / len);
    if (t_out > t_max_clip)
        sb = s_in + (s_out - s_in) * ((t_max_clip - t_in) / len);
    bool crosses = false;
    for (int j = 0; j < P.shell_info.y; j++) {
        const float value = P.iso[j];
        crosses = crosses || (sa < value && value <= sb) || (sa > value && value >= sb);
    }
    return crosses;
}

// The leaf's tets whose piece crosses a value and comes after the last piece handed on: the first one in
// (t_in, t_out, tet) order becomes the query's best.
void cull_leaf(uint leaf, inout CullTrace c)
{
    const int first = int(leaf - uint(P.shell_info.z)) * TPK_VK_RANGE_LEAF;
    const int end = min(first + TPK_VK_RANGE_LEAF, P.mode.x);
    for (int tet = first; tet < end; tet++) {
        work++;
        ivec4 q, v;
        vec4 p[4];
        float s[4], t_in, t_out, s_in, s_out;
        if (!cull_candidate(tet, q, p, s) || !cull_piece(q, p, s, t_in, t_out, s_in, s_out, v) ||
            !cull_crosses(t_in, t_out, s_in, s_out))
            continue;
        const bool after = t_in > c.t_prev ||
                           (t_in == c.t_prev && (t_out > c.t_out_prev || (t_out == c.t_out_prev && tet > c.tet_prev)));
        const bool better = c.best < 0 || t_in < c.best_in ||
                            (t_in == c.best_in && (t_out < c.best_out || (t_out == c.best_out && tet < c.best)));
        if (after && better) {
            c.best = tet;
            c.best_in = t_in;
            c.best_out = t_out;
        }
    }
}

CullTrace cull_start()
{
    CullTrace c;
    c.t_prev = c.t_out_prev = -INF;
    c.tet_prev = -1;
    c.node = 1u;
    c.from = 0u;
    c.trail = 0u;
    c.best = -1;
    c.best_in = c.best_out = INF;
    c.in_query = false;
    c.have_piece = false;
    return c;
}

// One node of the query, whose box the ray meets: a leaf's tets tested, or the children's boxes tested
// and the one the ray enters first entered (the left on a tie); coming up from the first child, the
// other one tested again (the best piece may have moved closer) and entered, else further up. Returns
// false when the query is over.
bool cull_query_step(inout CullTrace c)
{
    const float margin = P.up.w; // boxes against float t: the box padding again
    const float t_low = max(c.t_prev, t_min_clip) - margin;
    const float t_high = min(t_max_clip, c.best >= 0 ? c.best_in : INF) + margin;
    const uint n = c.node, leaf_base = uint(P.shell_info.z), depth_bit = 1u << uint(findMSB(n));
    bool up = true;
    if (c.from == 0u) {
        if (n >= leaf_base)
            cull_leaf(n, c);
        else {
            const float t0 = cull_node_enter(2u * n, t_low, t_high), t1 = cull_node_enter(2u * n + 1u, t_low, t_high);
            if (min(t0, t1) != INF) {
                const bool right = t1 < t0;
                c.trail = right ? c.trail | depth_bit : c.trail & ~depth_bit;
                c.node = right ? 2u * n + 1u : 2u * n;
                up = false;
            }
        }
    } else if (((c.from & 1u) != 0u) == ((c.trail & depth_bit) != 0u)) { // came up from the first child
        const uint other = c.from ^ 1u;
        if (cull_node_enter(other, t_low, t_high) != INF) {
            c.node = other;
            c.from = 0u;
            up = false;
        }
    }
    if (up) {
        c.from = n;
        c.node = n >> 1;
    }
    return c.node != 0u;
}

// The ray's pieces from where c stands, each to report(). Returns false when paused (casts asked, or a
// sliced ray out of work: call again), true when the ray is done.
bool cull_trace(inout CullTrace c)
{
    bool paused = false;
    for (;;) {
        if (SLICED && work >= TPK_VK_SLICE_WORK) {
            paused = true;
            break;
        }
        if (c.have_piece) {
            ivec4 q, v;
            vec4 p[4];
            float s[4], t_in, t_out, s_in, s_out;
            q = fetch_range_tets(uint(c.best)); // cull_candidate's work, not counted again
            for (int i = 0; i < 4; i++)
                p[i] = project(q[i], s[i]);
            cull_piece(q, p, s, t_in, t_out, s_in, s_out, v);
            const int said = report(t_in, t_out, s_in, s_out, v);
            if (said == MARCH_PAUSE) {
                paused = true;
                break;
            }
            c.have_piece = false;
            c.t_prev = t_in;
            c.t_out_prev = t_out;
            c.tet_prev = c.best;
            if (said == MARCH_STOP)
                break;
            continue;
        }
        work++;
        if (!c.in_query) { // the root first (node 0: the ray misses it, the query is over)
            c.in_query = true;
            c.from = 0u;
            c.best = -1;
            c.node = cull_node_enter(1u, max(c.t_prev, t_min_clip) - P.up.w, t_max_clip + P.up.w) != INF ? 1u : 0u;
            if (c.node != 0u)
                continue;
        }
        if (c.node != 0u && cull_query_step(c))
            continue;
        c.in_query = false;
        if (c.best < 0)
            break; // no piece left
        c.have_piece = true;
    }
    return !paused;
}
