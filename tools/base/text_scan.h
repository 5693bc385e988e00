/* Bounded scanning of text (and mixed text/binary) input files held in memory: tokens, fast number
 * parsing, and error messages that name the file and the line (text) or byte offset (binary). */
#ifndef TPK_TEXT_SCAN_H
#define TPK_TEXT_SCAN_H

#include <stddef.h>
#include <stdint.h>

#include "diag.h"

typedef struct tpk_scan {
    const char *name;            /* file name used in messages */
    const unsigned char *data;
    size_t size;
    size_t pos;
    int64_t line;                /* 1-based line of `pos` */
    int byte_places;             /* 1: messages give byte offsets instead of lines (binary files) */
    int hash_comments;           /* 1: '#' starts a comment running to the end of the line */
    size_t tok_pos;              /* start of the last token read, for messages */
    int64_t tok_line;
    tpk_diag *diag;
    int mapped;                  /* data is a tpk_map_file mapping: consumed pages may be dropped */
    size_t released;             /* bytes before this were dropped from the mapping */
} tpk_scan;

void tpk_scan_init(tpk_scan *s, const char *name, const void *data, size_t size, tpk_diag *diag);

/* Fail with "name:LINE: " (or "name: byte N: ") + message, placed at the last token. Returns -1. */
int tpk_scan_fail(tpk_scan *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Same, placed at an explicit byte offset / line. */
int tpk_scan_fail_at(tpk_scan *s, size_t pos, int64_t line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Skip whitespace (and comments when enabled), counting lines. */
void tpk_scan_skip_space(tpk_scan *s);
/* Skip spaces, tabs and CRs (and a comment when enabled) but stop at a newline. */
void tpk_scan_skip_blank(tpk_scan *s);
/* Next whitespace-delimited token; returns its length, 0 at end of input. *tok points into data. */
size_t tpk_scan_token(tpk_scan *s, const char **tok);
/* Next token on the current line only; 0 when the line (or input) ends first. */
size_t tpk_scan_line_token(tpk_scan *s, const char **tok);
/* Require the rest of the line to be blank, then consume its newline (or reach end of input).
 * `after` names what the line held, for the message. Returns 0 or -1. */
int tpk_scan_end_line(tpk_scan *s, const char *after);
/* Skip to just after the next newline (or to the end). */
void tpk_scan_skip_line(tpk_scan *s);

/* Printable, quoted-safe rendering of a token (at most about 40 characters) for messages. */
const char *tpk_scan_quote(const char *tok, size_t len, char *buf, size_t cap);

/* Parse a whole token as a number. Return 0, or -1 if the token is not (entirely) a number. */
int tpk_parse_int64(const char *tok, size_t len, int64_t *out);
int tpk_parse_double(const char *tok, size_t len, double *out);

/* Read the next token as a number; on failure the message says "expected <what>, found '<tok>'"
 * (or "found end of file"). `what` is like "a point coordinate". */
int tpk_scan_int64(tpk_scan *s, int64_t *out, const char *what);
int tpk_scan_double(tpk_scan *s, double *out, const char *what);
/* Same, but the number must be on the current line. */
int tpk_scan_line_int64(tpk_scan *s, int64_t *out, const char *what);
int tpk_scan_line_double(tpk_scan *s, double *out, const char *what);

/* Case-insensitive comparison of a token with a NUL-terminated word. */
int tpk_token_is(const char *tok, size_t len, const char *word);

/* For a mapped file: drop the pages before the current position from memory (they are re-read from
 * the file if touched again), so a large input does not stay resident next to the arrays parsed from
 * it. Does nothing for other buffers. */
void tpk_scan_release_consumed(tpk_scan *s);

/* Who watches the import: the readers call tpk_scan_release_consumed after each section or block, and it
 * then reports fn(user, bytes read / bytes of the input). One watcher for the process (the converter
 * sets it around its import and clears it with NULL); not for concurrent imports. */
void tpk_scan_watch(void (*fn)(void *user, double fraction), void *user);

/* Map a whole file read-only (the bytes are not NUL-terminated). Returns 0, or -1 with
 * "path: cannot ...: reason". Release with tpk_unmap_file(data, size). */
int tpk_map_file(const char *path, const char **data, size_t *size, tpk_diag *diag);
void tpk_unmap_file(const char *data, size_t size);

#endif
