/* The cost model of render --max-ms (budget.h). */
#include <math.h>

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
