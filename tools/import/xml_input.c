/* Whole-buffer expat parsing shared by the XML importers (xml_input.h). */
#include "xml_input.h"

#include <string.h>

#define XML_PIECE ((size_t)1 << 30) /* expat takes an int length */

/* The message for an expat error, unless a handler failed first (it stopped the parser and wrote its
 * own); `column_shift`: columns of the error's line that expat did not see (taken over by the caller). */
static int report_error(XML_Parser parser, const char *name, int *failed, long column_shift, tpk_diag *diag)
{
    if (*failed)
        return -1;
    enum XML_Error e = XML_GetErrorCode(parser);
    *failed = 1;
    return tpk_diag_fail(diag, "%s: line %ld, column %ld: expected well-formed XML, found an error: %s%s", name,
                         (long)XML_GetCurrentLineNumber(parser),
                         (long)XML_GetCurrentColumnNumber(parser) + column_shift, XML_ErrorString(e),
                         e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN || e == XML_ERROR_PARTIAL_CHAR
                             ? " (truncated file?)"
                             : "");
}

/* data[0..size) to expat in pieces of at most XML_PIECE; `last`: nothing follows. 0 or -1. */
static int feed(XML_Parser parser, const char *data, size_t size, int last)
{
    size_t pos = 0;
    do {
        size_t n = size - pos < XML_PIECE ? size - pos : XML_PIECE;
        if (XML_Parse(parser, data + pos, (int)n, pos + n == size && last) == XML_STATUS_ERROR)
            return -1;
        pos += n;
    } while (pos < size);
    return 0;
}

int tpk_xml_parse(XML_Parser parser, const char *name, const char *data, size_t size, int final, int *failed,
                  tpk_diag *diag)
{
    if (feed(parser, data, size, final))
        return report_error(parser, name, failed, 0, diag);
    return *failed ? -1 : 0;
}

/* Lines as expat counts them: "\n", "\r\n" and a lone "\r" each end one. */
static long count_lines(const char *p, size_t n)
{
    long lines = 0;
    for (size_t i = 0; i < n; i++)
        lines += p[i] == '\n' || (p[i] == '\r' && (i + 1 == n || p[i + 1] != '\n'));
    return lines;
}

static const char *find_word(const char *p, const char *end, const char *word, size_t len)
{
    while ((size_t)(end - p) >= len) {
        const char *c = memchr(p, word[0], (size_t)(end - p) - len + 1);
        if (!c || !memcmp(c, word, len))
            return c;
        p = c + 1;
    }
    return NULL;
}

int tpk_xml_parse_taking(XML_Parser parser, const char *name, const char *data, size_t size, int final,
                         int *failed, tpk_diag *diag, const char *tag, tpk_xml_take_fn take, void *user)
{
    const char *end = data + size, *pos = data;
    size_t taken = 0, tag_len = strlen(tag);
    long line = 1, shift_line = 0, shift = 0; /* columns taken from line shift_line */
    int ended = 0;                            /* expat was told the document ends */
    while (pos < end) {
        const char *start = find_word(pos, end, tag, tag_len), *gt = start ? memchr(start, '>', (size_t)(end - start)) : NULL;
        const char *cut = gt ? gt + 1 : end;
        ended = cut == end && final;
        if (feed(parser, pos, (size_t)(cut - pos), ended))
            return report_error(parser, name, failed,
                                (long)XML_GetCurrentLineNumber(parser) == shift_line ? shift : 0, diag);
        if (*failed)
            return -1;
        line += count_lines(pos, (size_t)(cut - pos));
        pos = cut;
        /* Blanks before the text (a newline after the tag, indentation) go to expat first, so that its
         * lines stay right: they are text it hands over at once (no '\r', which it holds back). */
        size_t lead = 0;
        while (start && pos + lead < end && (pos[lead] == ' ' || pos[lead] == '\t' || pos[lead] == '\n'))
            lead++;
        if (lead && pos + lead < end) {
            if (feed(parser, pos, lead, 0))
                return report_error(parser, name, failed,
                                    (long)XML_GetCurrentLineNumber(parser) == shift_line ? shift : 0, diag);
            if (*failed)
                return -1;
            line += count_lines(pos, lead);
            pos += lead;
        } else {
            lead = 0;
        }
        size_t took = start && pos < end ? take(user, (size_t)(start - data) - taken, lead, pos, (size_t)(end - pos)) : 0;
        if (took) {
            if (shift_line != line)
                shift = 0;
            shift_line = line;
            shift += (long)took;
            taken += took;
            pos += took;
            ended = 0;
        }
    }
    /* An empty document, or one whose last bytes were taken: expat still has to hear where it ends. */
    if (final && !ended && feed(parser, end, 0, 1))
        return report_error(parser, name, failed, (long)XML_GetCurrentLineNumber(parser) == shift_line ? shift : 0,
                            diag);
    return *failed ? -1 : 0;
}
