// Part of render.comp, included once, in the order it lists.
// Shell entries through the shell BVH, one at a time in (t, face) order (libtetpack/shell_bvh.c).

// ---- Shell entries through the BVH (shell_bvh.c): found one at a time, in (t, face) order ----------

vec3 inv_dir;

// The t at which the line enters node n's box, if it meets the box for some t in [t_low, t_high];
// +inf otherwise. Boxes are widened by P.up.w on top of the builder's padding, for the float slab test.
float box_enter(uint n, float t_low, float t_high)
{
    uvec4 a = fetch_nodes(2u * n), b = fetch_nodes(2u * n + 1u);
    vec3 lo = uintBitsToFloat(a.xyz) - P.up.w, hi = uintBitsToFloat(b.xyz) + P.up.w;
    float tn = -1.0 / 0.0, tf = t_high;
    bool meets = true;
    for (int k = 0; k < 3; k++) {
        if (ray_dir[k] == 0.0) {
            meets = meets && frame.org[k] >= lo[k] && frame.org[k] <= hi[k];
            continue;
        }
        float t0 = (lo[k] - frame.org[k]) * inv_dir[k], t1 = (hi[k] - frame.org[k]) * inv_dir[k];
        tn = max(tn, min(t0, t1));
        tf = min(tf, max(t0, t1));
    }
    return meets && tn <= tf && tf >= t_low ? tn : 1.0 / 0.0;
}

#define STACK_SIZE 96 // TPK_SHELL_BVH_STACK
#define INF (1.0 / 0.0)

// Shell BVH traversal, nearer child first, over boxes met within [t_low, t_high]; t_high shrinks as
// the query finds better entries. mode 0: the last entry before t_high (the ray's start); mode 1: the
// first entry after (t_prev, face_prev) in (t, face) order.
int bvh_query(int mode, float t_low, float t_high, float t_prev, int face_prev, out Hit best_hit)
{
    int best = -1;
    float best_t = mode == 0 ? -INF : INF;
    uint stack[STACK_SIZE];
    float stack_t[STACK_SIZE];
    int top = 0;
    float t_root = box_enter(0u, t_low, t_high);
    if (t_root == INF)
        return -1;
    stack[top] = 0u;
    stack_t[top++] = t_root;
    while (top > 0) {
        --top;
        work++;
        uint n = stack[top];
        if (mode == 1 && stack_t[top] > best_t)
            continue; // every face in it is after the best entry found since it was pushed
        uvec4 a = fetch_nodes(2u * n), b = fetch_nodes(2u * n + 1u);
        uint first = a.w, count = b.w;
        if (count == 0u) {
            float hi_t = mode == 1 ? best_t : t_high;
            float lo_t = mode == 0 ? max(t_low, best_t) : t_low;
            float t0 = box_enter(first, lo_t, hi_t), t1 = box_enter(first + 1u, lo_t, hi_t);
            uint near = t0 <= t1 ? first : first + 1u, far = t0 <= t1 ? first + 1u : first;
            float near_t = min(t0, t1), far_t = max(t0, t1);
            if (far_t != INF) {
                stack[top] = far;
                stack_t[top++] = far_t;
            }
            if (near_t != INF) {
                stack[top] = near;
                stack_t[top++] = near_t;
            }
            continue;
        }
        for (uint i = first; i < first + count; i++) {
            Hit h;
            int f = int(i);
            if (!shell_face_entry(fetch_shell(i), h))
                continue;
            if (mode == 0) {
                if (h.t < t_high && h.t > best_t) {
                    best_t = h.t;
                    best = f;
                }
            } else {
                bool after = h.t > t_prev || (h.t == t_prev && f > face_prev);
                bool better = best < 0 || h.t < best_t || (h.t == best_t && f < best);
                if (after && better) {
                    best = f;
                    best_t = h.t;
                    best_hit = h;
                }
            }
        }
    }
    if (mode == 0)
        best_hit.t = best_t;
    return best;
}
