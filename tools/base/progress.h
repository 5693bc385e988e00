/* One progress bar on stderr for the long-running commands (check, convert): "TOOL: STAGE [###...] NN%",
 * redrawn in place on one terminal line. */
#ifndef TPK_PROGRESS_H
#define TPK_PROGRESS_H

/* Draw `stage` of `tool` at `fraction` (clamped to [0, 1]); at 1.0 the line is erased, so the next
 * output starts on a clean line. Callers decide whether to show progress at all (a terminal, or asked
 * for): this always draws. Not thread-safe: call it from one thread (worker 0, or the driver). */
void tpk_progress_draw(const char *tool, const char *stage, double fraction);

#endif
