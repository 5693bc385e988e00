/* The time budget of a frame (render --max-ms; spec §16's levels of detail): a cost model fitted on the
 * frames drawn, and the finest level it predicts to fit. Pure; owner: budget.c. */
#ifndef TPK_RENDER_BUDGET_H
#define TPK_RENDER_BUDGET_H

#include <stdint.h>

/* seconds = fixed + rate * pixels * tets^(1/3) (a ray crosses about tets^(1/3) tets; `fixed` is what a
 * frame costs whatever its size: the marcher's setup), fitted by least squares on the frames added. With
 * frames of one size only, fixed is 0 (the line through the origin). Both are kept >= 0. */
typedef struct tpk_cost_model {
    double n, sum_x, sum_t, sum_xx, sum_xt;
} tpk_cost_model;

void tpk_cost_model_add(tpk_cost_model *m, double pixels, double tets, double seconds);
/* The fitted fixed seconds and rate. */
void tpk_cost_model_fit(const tpk_cost_model *m, double *fixed, double *rate);
/* The predicted seconds of a frame; 0 before any frame was added. */
double tpk_cost_model_predict(const tpk_cost_model *m, double pixels, double tets);
/* The finest level (0 = the full mesh, tets[0]; levels coarser as the index grows, `count` in all) whose
 * predicted time is at most `budget` seconds; the coarsest when none is. Deterministic for a model. */
int tpk_cost_model_pick(const tpk_cost_model *m, double pixels, const int64_t *tets, int count, double budget);

#endif
