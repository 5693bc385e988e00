/* Differential fuzz target for base/text_numbers.h: a block of numbers read on 3 threads in pieces of a
 * few bytes must give exactly what the serial token loop gives (values, position, line, last token), and
 * must decline (1, the scan unchanged) exactly when that loop fails. Input: byte 0 picks the kind (low 2
 * bits) and byte 1 the count (0-255); the rest is the text. A mismatch aborts. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "base/text_numbers.h"

/* The serial readers' loop: count tokens, each parsed as the kind says. 0 when all parse. */
static int serial(tpk_scan *s, uint64_t count, tpk_number_kind kind, unsigned char *dst)
{
    for (uint64_t i = 0; i < count; i++) {
        const char *tok;
        size_t len = tpk_scan_token(s, &tok);
        double d;
        int64_t v;
        if (!len)
            return -1;
        switch (kind) {
        case TPK_NUMBER_F64:
            if (tpk_parse_double(tok, len, &d))
                return -1;
            memcpy(dst + 8 * i, &d, 8);
            break;
        case TPK_NUMBER_F32: {
            if (tpk_parse_double(tok, len, &d))
                return -1;
            float f = (float)d;
            memcpy(dst + 4 * i, &f, 4);
            break;
        }
        case TPK_NUMBER_I64:
            if (tpk_parse_int64(tok, len, &v))
                return -1;
            memcpy(dst + 8 * i, &v, 8);
            break;
        case TPK_NUMBER_ID32: {
            if (tpk_parse_int64(tok, len, &v) || v < 0 || v > INT32_MAX)
                return -1;
            int32_t id = (int32_t)v;
            memcpy(dst + 4 * i, &id, 4);
            break;
        }
        }
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2)
        return 0;
    tpk_number_kind kind = (tpk_number_kind)(data[0] & 3);
    uint64_t count = data[1];
    size_t width = kind == TPK_NUMBER_F64 || kind == TPK_NUMBER_I64 ? 8 : 4;
    unsigned char *a = calloc(256, 8), *b = calloc(256, 8);
    if (!a || !b)
        abort();
    tpk_scan fast, slow;
    tpk_scan_init(&fast, "fuzz", data + 2, size - 2, NULL);
    tpk_scan_init(&slow, "fuzz", data + 2, size - 2, NULL);
    tpk_scan before = fast;
    int rf = tpk_scan_numbers_tuned(&fast, count, kind, a, 3, 1, 1);
    int rs = serial(&slow, count, kind, b);
    if (count > 0 && size > 2 && (rf == 0) != (rs == 0))
        abort(); /* declines exactly when the serial loop fails */
    if (rf != 0 && (fast.pos != before.pos || fast.line != before.line || fast.tok_pos != before.tok_pos ||
                    fast.tok_line != before.tok_line))
        abort(); /* declining leaves the scan as it was */
    if (rf == 0 && (memcmp(a, b, width * count) != 0 || fast.pos != slow.pos || fast.line != slow.line ||
                    fast.tok_pos != slow.tok_pos || fast.tok_line != slow.tok_line))
        abort();
    free(a);
    free(b);
    return 0;
}
