/* libtetpack private declarations of the ray side of the marcher: the ray-centric 2-D frame and the
 * watertight edge test that every tet and shell face crossed by a ray is decided with. Not installed.
 * Owners: ray.c defines tpki_ray_frame_init, tpki_det2_sign_exact and tpki_edge_weights; the static
 * inline functions below (tpk_project, tpk_edge_sign, tpk_face_weights) live here so the marcher's
 * inner loop inlines them. Used by march.c and shell_bvh.c; ray.c calls nothing else in libtetpack. */
#ifndef TPK_INTERNAL_RAY_H
#define TPK_INTERNAL_RAY_H

#include <math.h>
#include <stdint.h>

/* The ray in the mesh's local frame (positions relative to mesh.origin), sheared so that the ray runs
 * along +z through (0,0): a point p maps to x = q[kx] - sx q[kz], y = q[ky] - sy q[kz], z = sz q[kz]
 * with q = p - org. z of a point on the ray is its ray parameter t. kx,ky are swapped when dir[kz] < 0,
 * so a face whose 2-D winding is counter-clockwise (all edge functions > 0) has a normal along dir. */
typedef struct tpk_ray_frame {
    double org[3];
    double sx, sy, sz;
    int kx, ky, kz;
} tpk_ray_frame;

typedef struct tpk_proj {
    double x, y, z;
} tpk_proj;

/* Set up the frame; returns 0, or -1 for a zero or non-finite direction / non-finite origin. */
int tpki_ray_frame_init(tpk_ray_frame *frame, const double origin[3], const double org[3],
                       const double dir[3]);

/* Project the point p (a vertex's three floats). Every decision about a vertex uses this one function,
 * so the same vertex always gets bit-identical 2-D coordinates whichever tet or shell face asks, and
 * from whichever copy of its floats. */
static inline tpk_proj tpk_project_point(const float *p, const tpk_ray_frame *f)
{
    double q[3] = {(double)p[0] - f->org[0], (double)p[1] - f->org[1], (double)p[2] - f->org[2]};
    tpk_proj r;
    r.x = q[f->kx] - f->sx * q[f->kz];
    r.y = q[f->ky] - f->sy * q[f->kz];
    r.z = f->sz * q[f->kz];
    return r;
}

/* The same for vertex v (a valid id) of positions. */
static inline tpk_proj tpk_project(const float *positions, const tpk_ray_frame *f, int32_t v)
{
    return tpk_project_point(positions + 3 * (int64_t)v, f);
}

/* Exact sign (-1, 0, +1) of a*d - b*c for doubles (error-free products and sums; correct unless the
 * products underflow). The slow path of tpk_edge_sign. */
int tpki_det2_sign_exact(double a, double b, double c, double d);

/* The 2-D edge function of the directed edge i -> j: orient(P_i, P_j, o), o the ray's point (0,0)
 * symbolically perturbed to (eps, eps^2). It is evaluated in the canonical order (lower id first) and
 * negated for the other direction, so every face sharing the edge sees the same decision. Returns the
 * sign, never 0 (exact, from the rounded 2-D coordinates); *value gets the double value, set to 0 when
 * its sign disagrees with the exact one, and exactly 0 when the exact value is 0 (it is used as a
 * barycentric weight).
 * Perturbation: orient(P_i, P_j, o) = (x_i y_j - y_i x_j) + eps (y_i - y_j) + eps^2 (x_j - x_i), so
 * ties fall to the sign of y_i - y_j, then x_j - x_i. Only when P_i == P_j (an edge parallel to the
 * ray) do the ids decide (+1 for the canonical order): every triangle with such an edge has its other
 * two edges on one line in opposite directions, so it is never crossed and the choice is harmless. */
static inline int tpk_edge_sign(int32_t i, const tpk_proj *pi, int32_t j, const tpk_proj *pj,
                                double *value)
{
    /* picked by index, not by a branch: a tet's edges take the ids' order at random */
    const int swap = i > j;
    const tpk_proj *ends[2] = {pi, pj};
    const tpk_proj *lo = ends[swap], *hi = ends[1 - swap];
    const int flip = 1 - 2 * swap;
    double p = lo->x * hi->y, q = lo->y * hi->x;
    double det = p - q;
    double bound = 4.440892098500626e-16 * (fabs(p) + fabs(q));
    int sign = (det > bound) - (det < -bound);
    if (sign == 0) {
        sign = tpki_det2_sign_exact(lo->x, lo->y, hi->x, hi->y);
        if (sign == 0 || (det > 0 && sign < 0) || (det < 0 && sign > 0) || det != det)
            det = 0.0; /* exactly 0 when the point is exactly on the edge's line */
        if (sign == 0) {
            double dy = lo->y - hi->y, dx = hi->x - lo->x;
            sign = dy > 0 ? 1 : dy < 0 ? -1 : dx > 0 ? 1 : dx < 0 ? -1 : 1;
        }
    }
    *value = flip * det;
    return flip * sign;
}

/* State of the face a ray crosses: vertex ids, their projections, and the three directed edge values
 * e[0] = (v0->v1), e[1] = (v1->v2), e[2] = (v2->v0), each of the face's common sign (or 0). */
typedef struct tpk_face_hit {
    int32_t v[3];
    tpk_proj p[3];
    double e[3];
    double t;
} tpk_face_hit;

/* Weights for a crossing on the line of one edge of the face (edge value exactly 0): interpolated
 * along that edge from its two endpoints only, in canonical order, so every face sharing the edge
 * gives a bit-identical t (ties between shell entries at one point are then exact). */
void tpki_edge_weights(const tpk_face_hit *h, int zero_edge, double w[3]);

/* The corner (0..2) of a face's smallest id. Every sum over a face's corners (of the edge values in
 * tpk_face_weights, of t and of the scalar in tpk_face_sum) starts there, so a face gives bit-identical
 * weights, t and scalar in whatever rotation it is held: the marcher holds a face in the rotation its
 * path gave it, and the range culling of iso rays (range_bvh.c) meets a tet without that path. */
static inline int tpk_face_first(const tpk_face_hit *h)
{
    return h->v[1] < h->v[0] ? (h->v[2] < h->v[1] ? 2 : 1) : (h->v[2] < h->v[0] ? 2 : 0);
}

static const int8_t tpk_face_corner[5] = {0, 1, 2, 0, 1}; /* corner first + k (k < 3) is [first + k] */

/* w[0..2] x[0..2] summed from corner `first` (tpk_face_first) on. */
static inline double tpk_face_sum(int first, const double w[3], const double x[3])
{
    int a = first, b = tpk_face_corner[first + 1], c = tpk_face_corner[first + 2];
    return w[a] * x[a] + w[b] * x[b] + w[c] * x[c];
}

/* Barycentric weights of the crossing point: the edge values (the same weights give t and the scalar).
 * A crossing through a vertex gets weights (1,0,0) exactly; through an edge, see tpki_edge_weights.
 * `first`: tpk_face_first(h). */
static inline void tpk_face_weights(const tpk_face_hit *h, int first, double w[3])
{
    int zeros = (h->e[0] == 0.0) + (h->e[1] == 0.0) + (h->e[2] == 0.0);
    if (zeros == 1) {
        tpki_edge_weights(h, h->e[0] == 0.0 ? 0 : h->e[1] == 0.0 ? 1 : 2, w);
        return;
    }
    double sum = h->e[first] + h->e[tpk_face_corner[first + 1]] + h->e[tpk_face_corner[first + 2]];
    if (sum != 0.0 && sum == sum) {
        double inv = 1.0 / sum;
        w[0] = h->e[1] * inv;
        w[1] = h->e[2] * inv;
        w[2] = h->e[0] * inv;
    } else {
        w[0] = w[1] = w[2] = 1.0 / 3.0;
    }
}

#endif
