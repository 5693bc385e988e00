/* Blocks of whitespace-separated numbers in a tpk_scan read on all threads: the text is cut into pieces
 * at whitespace, each piece's tokens counted, their prefix sums giving each token's index, and each piece
 * parsed into its slots, by the same parsers as the serial readers (tpk_parse_double, tpk_parse_int64).
 * Only the fast path: anything it does not read exactly as count tpk_scan_token calls would (a token that
 * does not parse, too few tokens before the end, comments, one thread) is left to the caller's serial
 * loop, which then gives its own message. */
#ifndef TPK_TEXT_NUMBERS_H
#define TPK_TEXT_NUMBERS_H

#include <stdint.h>

#include "text_scan.h"

typedef enum tpk_number_kind {
    TPK_NUMBER_F64, /* double */
    TPK_NUMBER_F32, /* float, rounded from the double parsed */
    TPK_NUMBER_I64, /* int64_t */
    TPK_NUMBER_ID32 /* int32_t in [0, INT32_MAX] (point ids, counts): other values are not read here */
} tpk_number_kind;

/* Read `count` numbers of `kind` from s into dst on `threads` threads (tpk_thread_count's rule). Returns
 * 0 with s where count tpk_scan_token calls leave it (position, line, last token), or 1 with s unchanged
 * and dst's contents undefined: then read serially. */
int tpk_scan_numbers(tpk_scan *s, uint64_t count, tpk_number_kind kind, void *dst, int threads);
/* The same where blocks of min_count numbers or more are read this way (tpk_scan_numbers: 65536) in pieces
 * of at least grain bytes (tpk_scan_numbers: 1 MiB): for the fuzz target, which compares it with the serial
 * reading on small inputs (it returns 1 exactly when that fails). */
int tpk_scan_numbers_tuned(tpk_scan *s, uint64_t count, tpk_number_kind kind, void *dst, int threads,
                           uint64_t min_count, int64_t grain);

#endif
