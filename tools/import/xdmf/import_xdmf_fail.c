/* XDMF importer, lowest layer: failure messages. The first failure wins the diag message, whichever
 * layer (tree, paths, data, grids) finds it. Calls no other import_xdmf*.c file. */
#include <stdarg.h>
#include <stdio.h>

#include "import/import_file.h"
#include "import_xdmf_internal.h"

int xdmf_fail(xdmf_reader *r, const xdmf_node *at, const char *fmt, ...)
{
    char element[48];
    tpk_import_place place = {r->name, at && at->line > 0 ? at->line : 0, -1, NULL};
    if (place.line > 0 && at->name[0]) {
        snprintf(element, sizeof element, "<%.40s>", at->name);
        place.context = element;
    }
    va_list ap;
    va_start(ap, fmt);
    tpk_import_vfail(r->diag, &r->failed, place, fmt, ap);
    va_end(ap);
    return -1;
}
