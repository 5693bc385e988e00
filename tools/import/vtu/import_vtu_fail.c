/* VTU importer, lowest layer: failure messages. The first failure wins the diag message and stops
 * expat, whichever piece (XML handlers, decoding, mesh building) finds it. Calls no other
 * import_vtu*.c file. */
#include <stdarg.h>
#include <stdio.h>

#include "import/import_file.h"
#include "import_vtu_internal.h"

int vtu_fail_line(vtu_reader *r, long line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    tpk_import_vfail(r->diag, &r->failed, (tpk_import_place){r->name, line, -1, NULL}, fmt, ap);
    va_end(ap);
    if (r->parser)
        XML_StopParser(r->parser, XML_FALSE);
    return -1;
}

int vtu_fail_array(vtu_reader *r, const vtu_array *a, const char *fmt, ...)
{
    char array[160];
    snprintf(array, sizeof array, "DataArray '%s' (line %ld)", a->name, a->line);
    va_list ap;
    va_start(ap, fmt);
    tpk_import_vfail(r->diag, &r->failed, (tpk_import_place){r->name, 0, -1, array}, fmt, ap);
    va_end(ap);
    if (r->parser)
        XML_StopParser(r->parser, XML_FALSE);
    return -1;
}
