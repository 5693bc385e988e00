/* The progress bar shared by `tetpack check` and `tetpack convert` (progress.h). */
#include <stdio.h>

#include "progress.h"

void tpk_progress_draw(const char *tool, const char *stage, double fraction)
{
    int width = 30, filled = (int)(fraction * width + 0.5);
    filled = filled < 0 ? 0 : filled > width ? width : filled;
    char bar[32];
    for (int i = 0; i < width; i++)
        bar[i] = i < filled ? '#' : '.';
    bar[width] = 0;
    int drawn = fprintf(stderr, "\r%s: %-14s [%s] %3d%%", tool, stage, bar, (int)(fraction * 100 + 0.5));
    /* At least 60 blanks: what check has always erased with; longer lines (convert's) are erased whole. */
    if (fraction >= 1.0)
        fprintf(stderr, "\r%*s\r", drawn > 60 ? drawn : 60, "");
    fflush(stderr);
}
