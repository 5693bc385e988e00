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

/* Past the coarsest level: the pixel step of a frame of `pixels` on a level of `tets`, 1 where the model
 * predicts that the frame fits `budget` (or has no frame yet), else the smallest step d in 2..max_step
 * whose frame of about pixels / d^2 rays it predicts to fit (max_step when none does). Rays are cast at
 * every d-th pixel and the picture between them interpolated (tpk_image_upscale), as VTK's volume mappers
 * trade their image sample distance for a frame rate. Deterministic for a model. */
int tpk_cost_model_pixel_step(const tpk_cost_model *m, double pixels, double tets, double budget, int max_step);
/* The size of a frame of width x height drawn at pixel step d: each side divided by d, rounded, >= 1. */
void tpk_pixel_step_size(int width, int height, int step, int *w, int *h);
/* Fill dst (dw x dh RGBA8, straight alpha) from src (sw x sh), both drawn by one perspective camera (the
 * horizontal field of view follows the aspect ratio): each pixel of dst takes src at the point that sees
 * the same direction, bilinear in premultiplied color, clamped at the edges. 0, or -1 out of memory. */
int tpk_image_upscale(const uint8_t *src, int sw, int sh, uint8_t *dst, int dw, int dh);

#endif
