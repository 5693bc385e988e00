/* The cost model of render --max-ms and its pixel step (budget.h). */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>

#include "budget.h"

static double work(double pixels, double tets)
{
    return pixels * cbrt(tets > 1 ? tets : 1);
}

void tpk_cost_model_add(tpk_cost_model *m, double pixels, double tets, double seconds)
{
    double x = work(pixels, tets);
    if (!(x > 0) || !isfinite(x) || !isfinite(seconds) || seconds < 0)
        return;
    m->n += 1;
    m->sum_x += x;
    m->sum_t += seconds;
    m->sum_xx += x * x;
    m->sum_xt += x * seconds;
}

void tpk_cost_model_fit(const tpk_cost_model *m, double *fixed, double *rate)
{
    *fixed = 0;
    *rate = 0;
    if (!(m->sum_xx > 0))
        return;
    double den = m->n * m->sum_xx - m->sum_x * m->sum_x;
    if (m->n >= 2 && den > 1e-12 * m->n * m->sum_xx) {
        *rate = (m->n * m->sum_xt - m->sum_x * m->sum_t) / den;
        *fixed = (m->sum_t - *rate * m->sum_x) / m->n;
    }
    if (!(*rate > 0) || !(*fixed >= 0)) { /* one size, or a fit that would go negative: through the origin */
        *fixed = 0;
        *rate = m->sum_xt / m->sum_xx;
    }
}

double tpk_cost_model_predict(const tpk_cost_model *m, double pixels, double tets)
{
    double fixed, rate;
    tpk_cost_model_fit(m, &fixed, &rate);
    return m->n > 0 ? fixed + rate * work(pixels, tets) : 0;
}

int tpk_cost_model_pick(const tpk_cost_model *m, double pixels, const int64_t *tets, int count, double budget)
{
    for (int k = 0; k < count; k++)
        if (tpk_cost_model_predict(m, pixels, (double)tets[k]) <= budget)
            return k;
    return count > 0 ? count - 1 : 0;
}

void tpk_pixel_step_size(int width, int height, int step, int *w, int *h)
{
    step = step < 1 ? 1 : step;
    *w = (int)lround((double)width / step);
    *h = (int)lround((double)height / step);
    *w = *w < 1 ? 1 : *w;
    *h = *h < 1 ? 1 : *h;
}

int tpk_cost_model_pixel_step(const tpk_cost_model *m, double pixels, double tets, double budget, int max_step)
{
    if (m->n == 0 || tpk_cost_model_predict(m, pixels, tets) <= budget)
        return 1;
    for (int d = 2; d < max_step; d++)
        if (tpk_cost_model_predict(m, pixels / ((double)d * d), tets) <= budget)
            return d;
    return max_step > 1 ? max_step : 1;
}

static uint8_t byte_of(float v)
{
    return (uint8_t)(v <= 0 ? 0 : v >= 255 ? 255 : (int)(v + 0.5f));
}

/* Where a pixel's center of one image falls in the other, along one axis: its two neighbours there and
 * the weight of the second. `at` is the first pixel's center (in the source's pixels), `step` apart. */
static void taps(double at, double step, int n, int src_n, int32_t *i0, int32_t *i1, float *w)
{
    for (int i = 0; i < n; i++) {
        double f = at + i * step;
        f = f < 0 ? 0 : f > src_n - 1 ? src_n - 1 : f;
        i0[i] = (int32_t)f;
        i1[i] = i0[i] + 1 < src_n ? i0[i] + 1 : i0[i];
        w[i] = (float)(f - i0[i]);
    }
}

int tpk_image_upscale(const uint8_t *src, int sw, int sh, uint8_t *dst, int dw, int dh)
{
    /* a pixel's direction: x - w/2 and y - h/2 (at its center) over h, the same in both images */
    const double s = (double)sh / dh;
    int32_t *x0 = malloc(sizeof *x0 * 2 * ((size_t)dw + dh)), *x1 = x0 + dw, *y0 = x1 + dw, *y1 = y0 + dh;
    float *u = malloc(sizeof *u * ((size_t)dw + dh + 4 * (size_t)sw * sh)), *v = u + dw, *pre = v + dh;
    if (!x0 || !u) {
        free(x0);
        free(u);
        return -1;
    }
    taps((0.5 - 0.5 * dw) * s + 0.5 * sw - 0.5, s, dw, sw, x0, x1, u);
    taps((0.5 - 0.5 * dh) * s + 0.5 * sh - 0.5, s, dh, sh, y0, y1, v);
    for (size_t i = 0; i < (size_t)sw * sh; i++) { /* premultiplied color in 0..255, and alpha */
        float a = src[4 * i + 3] * (1.0f / 255);
        for (int k = 0; k < 3; k++)
            pre[4 * i + k] = src[4 * i + k] * a;
        pre[4 * i + 3] = src[4 * i + 3];
    }
    for (int y = 0; y < dh; y++) {
        const float *r0 = pre + 4 * (size_t)y0[y] * sw, *r1 = pre + 4 * (size_t)y1[y] * sw;
        const float wy = v[y];
        uint8_t *out = dst + 4 * (size_t)y * dw;
        for (int x = 0; x < dw; x++, out += 4) {
            const float *a = r0 + 4 * x0[x], *b = r0 + 4 * x1[x], *c = r1 + 4 * x0[x], *d = r1 + 4 * x1[x];
            const float wx = u[x];
            float sum[4];
            for (int k = 0; k < 4; k++) {
                float top = a[k] + wx * (b[k] - a[k]), bottom = c[k] + wx * (d[k] - c[k]);
                sum[k] = top + wy * (bottom - top);
            }
            float inv = sum[3] > 0 ? 255.0f / sum[3] : 0;
            for (int k = 0; k < 3; k++)
                out[k] = byte_of(sum[k] * inv);
            out[3] = byte_of(sum[3]);
        }
    }
    free(x0);
    free(u);
    return 0;
}
