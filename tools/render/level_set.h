/* The levels of detail of an open file (spec §16), as render and view choose among them. Owner:
 * level_set.c. */
#ifndef TPK_RENDER_LEVEL_SET_H
#define TPK_RENDER_LEVEL_SET_H

#include <stdint.h>

#include "base/diag.h"
#include "convert/convert.h" /* TPK_MAX_LEVELS */
#include "render/budget.h"
#include "tetpack.h"

/* files[0] is the file itself (the caller's), files[k] its level k opened over it, up to TPK_MAX_LEVELS;
 * with each one's tet count and the figures the converter wrote for it in META ("levels": error_max,
 * error_rms, shell_distance): 0 for the full mesh, NaN where META gives no number. */
typedef struct tpk_level_set {
    int count; /* the full mesh and its levels */
    tpk_file *files[TPK_MAX_LEVELS + 1];
    int64_t tets[TPK_MAX_LEVELS + 1];
    double error_max[TPK_MAX_LEVELS + 1], error_rms[TPK_MAX_LEVELS + 1], shell_distance[TPK_MAX_LEVELS + 1];
} tpk_level_set;

/* Open the levels of `file` (named `path` in messages) into *ls. 0, or -1 with a message (then the levels
 * opened so far stay in ls for tpk_level_set_close). */
int tpk_level_set_open(tpk_level_set *ls, tpk_file *file, const char *path, tpk_diag *diag);
/* Close the levels (not files[0], the caller's). */
void tpk_level_set_close(tpk_level_set *ls);
/* The level to draw a frame of `pixels` at within `budget` seconds: the finest the cost model predicts to
 * fit (tpk_cost_model_pick), the coarsest before the model has a frame. */
int tpk_level_set_choose(const tpk_level_set *ls, const tpk_cost_model *model, double pixels, double budget);

#endif
