/* Feeding a whole XML file held in memory to expat, with the message every XML importer gives for
 * malformed XML (VTU, DOLFIN). */
#ifndef TPK_XML_INPUT_H
#define TPK_XML_INPUT_H

#include <expat.h>
#include <stddef.h>

#include "base/diag.h"

/* Parse data[0..size) in pieces of at most 1 GiB (expat takes an int length); `final`: the document
 * ends there. On an expat error, unless *failed is set already (a handler failed first, stopping the
 * parser, and wrote its own message), set *failed and fail with "name: line L, column C: expected
 * well-formed XML, found an error: ..." (with "(truncated file?)" where it looks like one). Returns 0,
 * or -1 when *failed. */
int tpk_xml_parse(XML_Parser parser, const char *name, const char *data, size_t size, int final, int *failed,
                  tpk_diag *diag);

#endif
