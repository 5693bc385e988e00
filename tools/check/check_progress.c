/* The progress bar of `tetpack check --progress` on stderr. Its own file below the driver (check.c) and
 * every group, so the groups, which call it from worker 0, never call back up into the driver. */
#include "base/progress.h"
#include "check.h"

void tpk_check_progress(tpk_check_report *report, const char *stage, double fraction)
{
    if (report->options.progress)
        tpk_progress_draw("check", stage, fraction);
}
