/* XDMF importer, lowest layer: failure messages. The first failure wins the diag message, whichever
 * layer (tree, paths, data, grids) finds it. Calls no other import_xdmf*.c file. */
#include <stdarg.h>
#include <stdio.h>

#include "import_xdmf_internal.h"

int xdmf_fail(xdmf_reader *r, const xdmf_node *at, const char *fmt, ...)
{
    char text[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (r->failed)
        return -1;
    r->failed = 1;
    if (at && at->line > 0 && at->name[0])
        tpk_diag_fail(r->diag, "%s: line %ld: <%.40s>: %s", r->name, at->line, at->name, text);
    else if (at && at->line > 0)
        tpk_diag_fail(r->diag, "%s: line %ld: %s", r->name, at->line, text);
    else
        tpk_diag_fail(r->diag, "%s: %s", r->name, text);
    return -1;
}
