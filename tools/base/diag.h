/* Error reporting for the tools: one message buffer that says file, place, expected and found. */
#ifndef TPK_DIAG_H
#define TPK_DIAG_H

#include <stdarg.h>

/* A field whose value count does not match its points or cells, recorded instead of failing when the
 * caller asks for it (tetpack check reports them as findings; convert still refuses them). */
typedef struct tpk_field_problem {
    char name[64];
    char place[96];          /* "line 1234", "byte 5678" */
    long long expected, found;
} tpk_field_problem;

#define TPK_DIAG_MAX_FIELD_PROBLEMS 8

typedef struct tpk_diag {
    char message[1024]; /* "" when no error */
    int warning_count;
    void (*warn)(void *user, const char *text); /* NULL: warnings go to stderr */
    void *warn_user;
    /* Set by the caller: importers that support it skip a field of the wrong length and record it here
     * instead of failing (tpk_diag_field_problem returns 0 then, -1 otherwise). */
    int lenient_fields;
    /* Set by the caller (convert --strict-fields): a field an importer cannot read is an error; by default
     * importers that support it leave the field out with a warning saying where and why. */
    int strict_fields;
    long long field_problem_count;                       /* all recorded, may exceed the array */
    tpk_field_problem field_problems[TPK_DIAG_MAX_FIELD_PROBLEMS];
} tpk_diag;

/* Set the error message (printf-style); returns -1 so callers can `return tpk_diag_fail(...)`. */
int tpk_diag_fail(tpk_diag *diag, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Emit a warning (counted). */
void tpk_diag_warn(tpk_diag *diag, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* An importer found field `name` with `found` values where `expected` belong. Lenient: record it and
 * return 0 (the importer drops the field and goes on); otherwise return -1 (the importer fails with
 * its own message). */
int tpk_diag_field_problem(tpk_diag *diag, const char *name, long long expected, long long found,
                           const char *place);

#endif
