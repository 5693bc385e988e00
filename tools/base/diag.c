/* Error and warning messages for the tools. */
#include "diag.h"

#include <stdio.h>
#include <string.h>

int tpk_diag_fail(tpk_diag *diag, const char *fmt, ...)
{
    if (diag) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(diag->message, sizeof diag->message, fmt, ap);
        va_end(ap);
    }
    return -1;
}

void tpk_diag_warn(tpk_diag *diag, const char *fmt, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (diag) {
        diag->warning_count++;
        if (diag->warn) {
            diag->warn(diag->warn_user, text);
            return;
        }
    }
    fprintf(stderr, "warning: %s\n", text);
}

int tpk_diag_field_problem(tpk_diag *diag, const char *name, long long expected, long long found,
                           const char *place)
{
    if (!diag || !diag->lenient_fields)
        return -1;
    if (diag->field_problem_count < TPK_DIAG_MAX_FIELD_PROBLEMS) {
        tpk_field_problem *p = &diag->field_problems[diag->field_problem_count];
        snprintf(p->name, sizeof p->name, "%s", name);
        snprintf(p->place, sizeof p->place, "%s", place ? place : "");
        p->expected = expected;
        p->found = found;
    }
    diag->field_problem_count++;
    return 0;
}
