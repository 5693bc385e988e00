/* Error and warning messages for the tools. */
#include "diag.h"

#include <stdio.h>

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
