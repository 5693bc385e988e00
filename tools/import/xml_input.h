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

/* What the caller takes over instead of expat, called after each piece that ends with a start tag
 * beginning with `tag` and the blanks after it (`lead` bytes of ' ', '\t', '\n', which expat was given
 * as text): `at` (left bytes) is what follows, `fed_offset` where the tag began in the bytes expat has
 * been given (XML_GetCurrentByteIndex in the start handler says the same for the element it saw). Returns how many bytes of character data from `at` it took (0: none); they must hold
 * no newline and nothing expat would refuse or change in character data (no '<', '&', '\r'), so that
 * expat, given the rest, sees the same document, and lines stay the same. */
typedef size_t (*tpk_xml_take_fn)(void *user, size_t fed_offset, size_t lead, const char *at, size_t left);

/* tpk_xml_parse, letting `take` read the character data after the start tags named `tag` itself (the
 * VTU reader decodes long base64 runs without expat scanning them). Messages are those of
 * tpk_xml_parse, columns counting what was taken. */
int tpk_xml_parse_taking(XML_Parser parser, const char *name, const char *data, size_t size, int final,
                         int *failed, tpk_diag *diag, const char *tag, tpk_xml_take_fn take, void *user);

#endif
