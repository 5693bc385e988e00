/* tpk_assert.h: convert -> open -> the 6xx checks (tools/check/check_tpk*.c), for every test. */
#include "tpk_assert.h"

#include <stdio.h>
#include <string.h>

#include "check/check.h"
#include "tetpack.h"

/* "606 tpk_m06_fold: 2 (tet 7 4 9 2 ...: note)" for the first 6xx finding with a count. */
static int describe_first_finding(tpk_check_report *report, char *msg, size_t cap)
{
    for (int id = 600; id <= 613; id++) {
        const tpk_finding *f = tpk_check_finding(report, id);
        if (f->count == 0)
            continue;
        int used = snprintf(msg, cap, "check %d %s: %lld", id, f->check->name, (long long)f->count);
        if (f->example_count > 0 && used > 0 && (size_t)used < cap) {
            const tpk_example *ex = &f->examples[0];
            used += snprintf(msg + used, cap - (size_t)used, " (first: %s", ex->kind);
            for (int i = 0; i < ex->id_count && used > 0 && (size_t)used < cap; i++)
                used += snprintf(msg + used, cap - (size_t)used, " %lld", (long long)ex->ids[i]);
            if (used > 0 && (size_t)used < cap)
                snprintf(msg + used, cap - (size_t)used, "%s%s)", ex->note[0] ? ": " : "", ex->note);
        }
        return 1;
    }
    return 0;
}

int tpk_assert_file_valid(const char *path, char *msg, size_t cap)
{
    tpk_check_options o;
    tpk_check_options_default(&o);
    o.threads = 2;
    tpk_check_report report;
    if (tpk_check_report_init(&report, &o)) {
        snprintf(msg, cap, "%s: out of memory for a check report", path);
        return 1;
    }
    tpk_file *file = NULL;
    char open_error[256] = "";
    int rc = 1;
    if (tpk_open_path(&file, path, NULL, open_error, sizeof open_error) != TPK_OK) {
        snprintf(msg, cap, "%s does not open: %s", path, open_error);
    } else {
        tpk_diag diag;
        memset(&diag, 0, sizeof diag);
        if (tpk_check_tpk_file(path, file, &report, &diag) != 0)
            snprintf(msg, cap, "%s: the checks could not run: %s", path, diag.message);
        else
            rc = describe_first_finding(&report, msg, cap);
    }
    tpk_close(file);
    tpk_check_report_free(&report);
    return rc;
}

int tpk_convert_checked(const tpk_convert_options *options, tpk_convert_report *report, tpk_diag *diag)
{
    int rc = tpk_convert(options, report, NULL, NULL, diag);
    if (rc != 0)
        return rc;
    char finding[sizeof diag->message - 128];
    if (tpk_assert_file_valid(options->output, finding, sizeof finding) == 0)
        return 0;
    snprintf(diag->message, sizeof diag->message, "the converter wrote %s from %s, which breaks a MUST: %s",
             options->output, options->input, finding);
    return 1;
}
