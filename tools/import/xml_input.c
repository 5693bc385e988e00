/* Whole-buffer expat parsing shared by the XML importers (xml_input.h). */
#include "xml_input.h"

int tpk_xml_parse(XML_Parser parser, const char *name, const char *data, size_t size, int final, int *failed,
                  tpk_diag *diag)
{
    const size_t chunk = (size_t)1 << 30;
    size_t pos = 0;
    do {
        size_t n = size - pos < chunk ? size - pos : chunk;
        int last = pos + n == size && final;
        if (XML_Parse(parser, data + pos, (int)n, last) == XML_STATUS_ERROR) {
            if (!*failed) {
                enum XML_Error e = XML_GetErrorCode(parser);
                *failed = 1;
                tpk_diag_fail(diag, "%s: line %ld, column %ld: expected well-formed XML, found an error: %s%s", name,
                              (long)XML_GetCurrentLineNumber(parser), (long)XML_GetCurrentColumnNumber(parser),
                              XML_ErrorString(e),
                              e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN || e == XML_ERROR_PARTIAL_CHAR
                                  ? " (truncated file?)"
                                  : "");
            }
            break;
        }
        pos += n;
    } while (pos < size);
    return *failed ? -1 : 0;
}
