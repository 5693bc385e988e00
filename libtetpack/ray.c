/* The ray side of the marcher: the ray-centric frame, the exact 2x2 determinant sign behind the
 * watertight edge test, and the edge weights of a crossing on an edge. march.c and shell_bvh.c both
 * decide crossings with these, so they sit below both and call nothing else in libtetpack. */
#include <math.h>

#include "internal_ray.h"

/* ---- Exact 2x2 determinant sign ---------------------------------------------------------------- */

static double two_prod(double a, double b, double *err)
{
    double p = a * b;
    *err = fma(a, b, -p);
    return p;
}

static double two_sum(double a, double b, double *err)
{
    double s = a + b;
    double bv = s - a;
    double av = s - bv;
    *err = (a - av) + (b - bv);
    return s;
}

/* (a1 + a0) - b as a three-term nonoverlapping expansion x2 > x1 > x0 (by magnitude). */
static void two_one_diff(double a1, double a0, double b, double *x2, double *x1, double *x0)
{
    double i = two_sum(a0, -b, x0);
    *x2 = two_sum(a1, i, x1);
}

int tpki_det2_sign_exact(double a, double b, double c, double d)
{
    double ad_lo, bc_lo;
    double ad = two_prod(a, d, &ad_lo);
    double bc = two_prod(b, c, &bc_lo);
    /* (ad + ad_lo) - (bc + bc_lo), exactly, as four nonoverlapping terms x3..x0; the sign of such an
     * expansion is the sign of its most significant nonzero term. */
    double j, m0, x0, x1, x2, x3;
    two_one_diff(ad, ad_lo, bc_lo, &j, &m0, &x0);
    two_one_diff(j, m0, bc, &x3, &x2, &x1);
    const double terms[4] = {x3, x2, x1, x0};
    for (int k = 0; k < 4; k++) {
        if (terms[k] > 0)
            return 1;
        if (terms[k] < 0)
            return -1;
    }
    return 0;
}

/* ---- Ray frame ----------------------------------------------------------------------------------- */

int tpki_ray_frame_init(tpk_ray_frame *f, const double origin[3], const double org[3], const double dir[3])
{
    for (int k = 0; k < 3; k++) {
        if (!isfinite(org[k]) || !isfinite(dir[k]))
            return -1;
        f->org[k] = org[k] - origin[k];
    }
    int kz = 0;
    if (fabs(dir[1]) > fabs(dir[kz]))
        kz = 1;
    if (fabs(dir[2]) > fabs(dir[kz]))
        kz = 2;
    if (dir[kz] == 0.0)
        return -1;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (dir[kz] < 0) {
        int swap = kx;
        kx = ky;
        ky = swap;
    }
    f->kx = kx;
    f->ky = ky;
    f->kz = kz;
    f->sx = dir[kx] / dir[kz];
    f->sy = dir[ky] / dir[kz];
    f->sz = 1.0 / dir[kz];
    return 0;
}

void tpki_edge_weights(const tpk_face_hit *h, int zero_edge, double w[3])
{
    int i = zero_edge, j = (zero_edge + 1) % 3, other = (zero_edge + 2) % 3;
    int lo = h->v[i] < h->v[j] ? i : j, hi = lo == i ? j : i;
    const tpk_proj *a = &h->p[lo], *b = &h->p[hi];
    double ex = b->x - a->x, ey = b->y - a->y;
    double len2 = ex * ex + ey * ey;
    double u = len2 > 0 ? -(a->x * ex + a->y * ey) / len2 : 0.5;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    w[lo] = 1.0 - u;
    w[hi] = u;
    w[other] = 0.0;
}
