/* render --legend: a colour bar of the transfer function with the field's name, units, range and ticks,
 * drawn with cairo onto a rendered image. Owner: legend.c. */
#ifndef TPK_RENDER_LEGEND_H
#define TPK_RENDER_LEGEND_H

#include <stdint.h>

#include "base/diag.h"
#include "transfer_function.h"

typedef struct tpk_legend {
    const tpk_transfer_function *tf;
    double range_min, range_max; /* the scalar range the TF spans (s = 0 at min, 1 at max) */
    const char *field;           /* the field's name; NULL or "": "(no field)" */
    const char *units;           /* the field's units; NULL or "": none shown */
} tpk_legend;

/* Where the bar is: pixel rows y0 (s = 1, the top) to y1 (s = 0), columns x0..x1, all inclusive. The
 * pixel at row y has s = (y1 - y) / (y1 - y0) and the TF's colour at s, opaque. Pure. */
typedef struct tpk_legend_bar {
    int x0, x1, y0, y1;
} tpk_legend_bar;
int tpk_legend_place(int width, int height, tpk_legend_bar *bar);

/* Draw the legend onto rgba (width * height * 4 bytes, straight alpha) at the right edge: a dark panel,
 * the bar (tpk_legend_place), the name and units above it and 5 ticks with their values beside it.
 * Returns 0, or -1 with a message (an image too small for a legend, a build without cairo). */
int tpk_legend_draw(uint8_t *rgba, int width, int height, const tpk_legend *legend, tpk_diag *diag);

#endif
