/* Growable string with JSON helpers. */
#include "strbuf.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int reserve(tpk_strbuf *sb, size_t extra)
{
    if (sb->failed)
        return -1;
    if (sb->length + extra + 1 <= sb->capacity)
        return 0;
    size_t cap = sb->capacity ? sb->capacity : 256;
    while (cap < sb->length + extra + 1)
        cap *= 2;
    char *grown = realloc(sb->data, cap);
    if (!grown) {
        sb->failed = 1;
        return -1;
    }
    sb->data = grown;
    sb->capacity = cap;
    return 0;
}

void tpk_strbuf_printf(tpk_strbuf *sb, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || reserve(sb, (size_t)n) != 0)
        return;
    va_start(ap, fmt);
    vsnprintf(sb->data + sb->length, (size_t)n + 1, fmt, ap);
    va_end(ap);
    sb->length += (size_t)n;
}

void tpk_strbuf_json_string(tpk_strbuf *sb, const char *text)
{
    tpk_strbuf_printf(sb, "\"");
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p == '"' || *p == '\\')
            tpk_strbuf_printf(sb, "\\%c", *p);
        else if (*p == '\n')
            tpk_strbuf_printf(sb, "\\n");
        else if (*p < 0x20)
            tpk_strbuf_printf(sb, "\\u%04x", *p);
        else
            tpk_strbuf_printf(sb, "%c", *p);
    }
    tpk_strbuf_printf(sb, "\"");
}

void tpk_strbuf_json_number(tpk_strbuf *sb, double value)
{
    if (!isfinite(value)) {
        tpk_strbuf_printf(sb, "null");
        return;
    }
    char text[64];
    for (int precision = 15; precision <= 17; precision++) {
        snprintf(text, sizeof text, "%.*g", precision, value);
        if (strtod(text, NULL) == value)
            break;
    }
    tpk_strbuf_printf(sb, "%s", text);
}

void tpk_strbuf_free(tpk_strbuf *sb)
{
    free(sb->data);
    memset(sb, 0, sizeof *sb);
}

int tpk_utf8_sequence(const unsigned char *s, size_t n)
{
    int len = s[0] < 0x80 ? 1 : s[0] >= 0xC2 && s[0] <= 0xDF ? 2 : s[0] >= 0xE0 && s[0] <= 0xEF ? 3
                              : s[0] >= 0xF0 && s[0] <= 0xF4 ? 4 : 0;
    if (!len || (size_t)len > n)
        return 0;
    for (int k = 1; k < len; k++)
        if ((s[k] & 0xC0) != 0x80)
            return 0;
    if ((s[0] == 0xE0 && s[1] < 0xA0) || (s[0] == 0xED && s[1] > 0x9F) || (s[0] == 0xF0 && s[1] < 0x90) ||
        (s[0] == 0xF4 && s[1] > 0x8F))
        return 0; /* overlong, surrogate, above U+10FFFF */
    return len;
}

int tpk_utf8_valid(const char *s, size_t n)
{
    for (size_t i = 0; i < n;) {
        int len = tpk_utf8_sequence((const unsigned char *)s + i, n - i);
        if (!len)
            return 0;
        i += (size_t)len;
    }
    return 1;
}
