/* Error reporting for the tools: one message buffer that says file, place, expected and found. */
#ifndef TPK_DIAG_H
#define TPK_DIAG_H

#include <stdarg.h>

typedef struct tpk_diag {
    char message[1024]; /* "" when no error */
    int warning_count;
    void (*warn)(void *user, const char *text); /* NULL: warnings go to stderr */
    void *warn_user;
} tpk_diag;

/* Set the error message (printf-style); returns -1 so callers can `return tpk_diag_fail(...)`. */
int tpk_diag_fail(tpk_diag *diag, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Emit a warning (counted). */
void tpk_diag_warn(tpk_diag *diag, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
