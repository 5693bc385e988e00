/* A growable string for building JSON and reports; a failed allocation sets `failed` and later
 * appends do nothing, so callers check once at the end. */
#ifndef TPK_STRBUF_H
#define TPK_STRBUF_H

#include <stddef.h>

typedef struct tpk_strbuf {
    char *data;
    size_t length, capacity;
    int failed;
} tpk_strbuf;

void tpk_strbuf_printf(tpk_strbuf *sb, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Append `text` as a JSON string literal, quotes included. */
void tpk_strbuf_json_string(tpk_strbuf *sb, const char *text);
/* Append a double as JSON (null for NaN/Inf, shortest round-trip form otherwise). */
void tpk_strbuf_json_number(tpk_strbuf *sb, double value);
void tpk_strbuf_free(tpk_strbuf *sb);

/* Length of the valid UTF-8 sequence at s (at most n bytes, n >= 1), 0 when invalid (RFC 3629: no
 * overlong forms, surrogates or code points above U+10FFFF). The one rule for the writer's and the
 * validator's text fields (spec §7.1). */
int tpk_utf8_sequence(const unsigned char *s, size_t n);
/* 1 when the n bytes at s are valid UTF-8. */
int tpk_utf8_valid(const char *s, size_t n);

#endif
