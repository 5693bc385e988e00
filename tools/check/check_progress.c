/* The progress bar of `tetpack check --progress` on stderr. Its own file below the driver (check.c) and
 * every group, so the groups, which call it from worker 0, never call back up into the driver. */
#include <stdio.h>

#include "check.h"

void tpk_check_progress(tpk_check_report *report, const char *stage, double fraction)
{
    if (!report->options.progress)
        return;
    int width = 30, filled = (int)(fraction * width + 0.5);
    filled = filled < 0 ? 0 : filled > width ? width : filled;
    char bar[32];
    for (int i = 0; i < width; i++)
        bar[i] = i < filled ? '#' : '.';
    bar[width] = 0;
    fprintf(stderr, "\rcheck: %-14s [%s] %3d%%", stage, bar, (int)(fraction * 100 + 0.5));
    if (fraction >= 1.0)
        fprintf(stderr, "\r%*s\r", 60, "");
    fflush(stderr);
}
