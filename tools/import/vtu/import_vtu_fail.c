/* VTU importer, lowest layer: failure messages. The first failure wins the diag message and stops
 * expat, whichever piece (XML handlers, decoding, mesh building) finds it. Calls no other
 * import_vtu*.c file. */
#include <stdarg.h>
#include <stdio.h>

#include "import_vtu_internal.h"

int vtu_fail_line(vtu_reader *r, long line, const char *fmt, ...)
{
    char text[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (!r->failed) {
        r->failed = 1;
        if (line > 0)
            tpk_diag_fail(r->diag, "%s: line %ld: %s", r->name, line, text);
        else
            tpk_diag_fail(r->diag, "%s: %s", r->name, text);
    }
    if (r->parser)
        XML_StopParser(r->parser, XML_FALSE);
    return -1;
}

int vtu_fail_array(vtu_reader *r, const vtu_array *a, const char *fmt, ...)
{
    char text[700];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (!r->failed) {
        r->failed = 1;
        tpk_diag_fail(r->diag, "%s: DataArray '%s' (line %ld): %s", r->name, a->name, a->line, text);
    }
    if (r->parser)
        XML_StopParser(r->parser, XML_FALSE);
    return -1;
}
