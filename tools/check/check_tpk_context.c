/* What every 6xx pass shares (check_tpk_internal.h): the per-worker finding
 * sinks and their ordered merge into the report, and the parallel pass over the tets. Below check_tpk.c
 * and every check_tpk_*.c pass, so no pass calls back up into the entry file. */
#include <stdlib.h>
#include <string.h>

#include "check_tpk_internal.h"
#include "base/parallel.h"

tpk_example *tpkc_hit(tpkc_sink *sink, int id, const char *kind)
{
    tpkc_list *list = &sink->lists[id - TPKC_FIRST_ID];
    list->count++;
    return tpk_example_slot(&list->examples, &list->kept, sink->max_examples, kind);
}

void tpkc_merge(tpk_check_report *report, tpkc_sink *sinks, int count)
{
    for (int id = 0; id < TPKC_ID_COUNT; id++) {
        for (int w = 0; w < count; w++) {
            tpkc_list *list = &sinks[w].lists[id];
            for (int k = 0; k < list->kept; k++) {
                tpk_example *slot = tpk_check_hit(report, TPKC_FIRST_ID + id, list->examples[k].kind);
                if (slot)
                    *slot = list->examples[k];
            }
            tpk_check_count(report, TPKC_FIRST_ID + id, list->count - list->kept);
            free(list->examples);
            memset(list, 0, sizeof *list);
        }
    }
}

void tpkc_example_ids32(tpk_example *ex, int count, const int32_t *ids)
{
    int64_t wide[TPK_CHECK_MAX_IDS];
    count = count > TPK_CHECK_MAX_IDS ? TPK_CHECK_MAX_IDS : count;
    for (int k = 0; k < count; k++)
        wide[k] = ids[k];
    tpk_example_ids(ex, count, wide);
}

int tpkc_run_tet_pass(tpkc *c, void (*fn)(void *ctx, int64_t begin, int64_t end, int worker), tpk_diag *diag)
{
    return tpkc_run_pass(c, c->T, 1 << 14, fn, NULL, diag);
}

int tpkc_run_pass(tpkc *c, int64_t count, int64_t grain, void (*fn)(void *ctx, int64_t begin, int64_t end, int worker),
                  void *user, tpk_diag *diag)
{
    int threads = tpk_threads_for(count, c->threads, grain);
    tpkc_sink *sinks = calloc((size_t)threads, sizeof *sinks);
    if (!sinks)
        return tpk_diag_fail(diag, "out of memory");
    for (int w = 0; w < threads; w++)
        sinks[w].max_examples = c->report->options.max_examples;
    tpkc_pass pass = {c, sinks, user};
    tpk_parallel_for(count, threads, fn, &pass);
    tpkc_merge(c->report, sinks, threads);
    free(sinks);
    return 0;
}
