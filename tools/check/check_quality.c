/* Shape quality of one tet, in double precision (statistics and thresholds, not exact decisions).
 *
 * With u, v, w the edges from the first vertex, D = u . (v x w) = 6 V and n_i the area vectors of the
 * faces (|n_i| = twice the face's area, all outward or all inward):
 * - dihedral angle at the edge shared by faces i and j: acos(-n_i . n_j / (|n_i| |n_j|));
 * - radius ratio 3 r_in / r_circ with r_in = |D| / sum |n_i| and r_circ = |u^2 (v x w) + v^2 (w x u) +
 *   w^2 (u x v)| / (2 |D|): 1 for the regular tet, tending to 0 for every kind of degenerate tet;
 * - aspect ratio: longest edge over shortest altitude, times sqrt(2/3) so that the regular tet has 1
 *   (altitude over face i = |D| / |n_i|). It grows without bound for needles, slivers and caps alike. */
#include <math.h>

#include "check_cells_internal.h"

static void sub(const double *a, const double *b, double *out)
{
    out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}

static void cross(const double *a, const double *b, double *out)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void tpk_tet_quality_of(const double *a, const double *b, const double *c, const double *d,
                        tpk_tet_quality *q)
{
    double u[3], v[3], w[3], n[4][3];
    sub(b, a, u);
    sub(c, a, v);
    sub(d, a, w);
    cross(w, v, n[1]); /* opposite b */
    cross(u, w, n[2]); /* opposite c */
    cross(v, u, n[3]); /* opposite d */
    for (int k = 0; k < 3; k++)
        n[0][k] = -(n[1][k] + n[2][k] + n[3][k]); /* the four area vectors sum to zero */
    double len[4], area_sum = 0, largest = 0;
    for (int i = 0; i < 4; i++) {
        len[i] = sqrt(dot(n[i], n[i]));
        area_sum += len[i];
        largest = len[i] > largest ? len[i] : largest;
    }
    double cos_max = -1, cos_min = 1;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++) {
            double cs = -dot(n[i], n[j]) / (len[i] * len[j]);
            cos_max = cs > cos_max ? cs : cos_max;
            cos_min = cs < cos_min ? cs : cos_min;
        }
    cos_max = cos_max > 1 ? 1 : cos_max;
    cos_min = cos_min < -1 ? -1 : cos_min;
    q->min_dihedral_deg = acos(cos_max) * (180.0 / M_PI);
    q->max_dihedral_deg = acos(cos_min) * (180.0 / M_PI);

    double det = fabs(dot(u, n[1])) /* |u . (w x v)| = |D| */, vw[3], wu[3], uv[3], circ[3];
    cross(v, w, vw);
    cross(w, u, wu);
    cross(u, v, uv);
    double uu = dot(u, u), vv = dot(v, v), ww = dot(w, w);
    for (int k = 0; k < 3; k++)
        circ[k] = uu * vw[k] + vv * wu[k] + ww * uv[k];
    double circ_len = sqrt(dot(circ, circ));
    q->radius_ratio = circ_len > 0 ? 6.0 * det * det / (area_sum * circ_len) : 0;

    double e[3][3], longest = uu > vv ? uu : vv;
    longest = ww > longest ? ww : longest;
    sub(c, b, e[0]);
    sub(d, b, e[1]);
    sub(d, c, e[2]);
    for (int i = 0; i < 3; i++) {
        double l = dot(e[i], e[i]);
        longest = l > longest ? l : longest;
    }
    q->aspect_ratio = det > 0 ? sqrt(longest) * largest / det * sqrt(2.0 / 3.0) : INFINITY;
}
