/* XDMF importer: a DataItem's values. Dimensions give the count; NumberType (XDMF 2) or DataType
 * (XDMF 3) with Precision the kind; Format XML holds the numbers as text, Format HDF names a dataset
 * as file.h5:/path/to/dataset (import_xdmf_hdf.c). Other formats and item types are refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "import_xdmf_internal.h"
#include "base/text_scan.h"

const xdmf_node *xdmf_first_item(xdmf_reader *r, const xdmf_node *parent)
{
    for (const xdmf_node *c = parent->first; c; c = c->next)
        if (xdmf_is(c, "DataItem"))
            return c;
    xdmf_fail(r, parent, "expected a <DataItem> inside, found none");
    return NULL;
}

static int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

static int parse_dimensions(xdmf_reader *r, const xdmf_node *item, xdmf_values *out, int64_t *count)
{
    const char *dims = xdmf_attr(item, "Dimensions");
    if (!dims)
        return xdmf_fail(r, item, "expected a Dimensions attribute, found none");
    double total = 1;
    out->rank = 0;
    for (const char *p = dims;;) {
        while (is_blank(*p))
            p++;
        if (!*p)
            break;
        size_t len = strcspn(p, " \t\n\r");
        int64_t d;
        if (out->rank == 8 || tpk_parse_int64(p, len, &d) || d < 0)
            return xdmf_fail(r, item, "expected Dimensions of 1 to 8 whole numbers >= 0, found \"%.60s\"", dims);
        out->dims[out->rank++] = d;
        total *= (double)d;
        p += len;
    }
    if (out->rank == 0 || total > (double)INT32_MAX * 8)
        return xdmf_fail(r, item, "expected Dimensions of 1 to 8 whole numbers (at most 2^34 values), found \"%.60s\"",
                         dims);
    *count = (int64_t)total;
    return 0;
}

/* NumberType or DataType: Float, Int, UInt, Char, UChar (Precision only changes the stored width). */
static int parse_number_type(xdmf_reader *r, const xdmf_node *item, xdmf_values *out)
{
    const char *type = xdmf_attr(item, "NumberType");
    if (!type)
        type = xdmf_attr(item, "DataType");
    if (!type || !strcasecmp(type, "Float") || !strcasecmp(type, "Double"))
        out->integer = 0;
    else if (!strcasecmp(type, "Int") || !strcasecmp(type, "UInt") || !strcasecmp(type, "Char") ||
             !strcasecmp(type, "UChar"))
        out->integer = 1;
    else
        return xdmf_fail(r, item, "expected NumberType Float, Int, UInt, Char or UChar, found \"%.40s\"", type);
    const char *precision = xdmf_attr(item, "Precision");
    if (precision && strcmp(precision, "1") && strcmp(precision, "2") && strcmp(precision, "4") &&
        strcmp(precision, "8"))
        return xdmf_fail(r, item, "expected Precision 1, 2, 4 or 8, found \"%.40s\"", precision);
    return 0;
}

/* The number of blank-separated words in p[0 .. len). */
static int64_t count_words(const char *p, size_t len)
{
    int64_t words = 0;
    for (size_t i = 0; i < len; i++)
        words += !is_blank(p[i]) && (i == 0 || is_blank(p[i - 1]));
    return words;
}

/* Format XML: exactly `want` numbers in the element's text (counted before allocating). */
static int read_text(xdmf_reader *r, const xdmf_node *item, int64_t want, xdmf_values *out)
{
    size_t len;
    const char *p = xdmf_trimmed(item, &len), *end = p + len;
    int64_t words = count_words(p, len);
    if (words != want)
        return xdmf_fail(r, item, "expected %lld numbers (Dimensions \"%.60s\"), found %lld", (long long)want,
                         xdmf_attr(item, "Dimensions"), (long long)words);
    out->v = malloc(sizeof *out->v * (size_t)(want ? want : 1));
    if (!out->v)
        return xdmf_fail(r, item, "out of memory for %lld values", (long long)want);
    for (int64_t got = 0; got < want; got++) {
        while (is_blank(*p))
            p++;
        size_t n = 0;
        while (p + n < end && !is_blank(p[n]))
            n++;
        char q[64];
        /* an integer: whole and within 2^53 (exact in a double; a cast beyond int64 is undefined) */
        if (tpk_parse_double(p, n, &out->v[got]) ||
            (out->integer && !(fabs(out->v[got]) <= 9007199254740992.0 && out->v[got] == floor(out->v[got]))))
            return xdmf_fail(r, item, "value %lld: expected %s, found '%s'", (long long)got,
                             out->integer ? "an integer" : "a number", tpk_scan_quote(p, n, q, sizeof q));
        p += n;
    }
    out->count = want;
    return 0;
}

/* Format HDF: "file.h5:/path/to/dataset". */
static int read_hdf_item(xdmf_reader *r, const xdmf_node *item, int64_t want, xdmf_values *out)
{
    size_t len, dataset_len;
    const char *text = xdmf_trimmed(item, &len), *dataset;
    char path[4096], name[4096];
    if (xdmf_hdf_source(r, item, path, sizeof path, &dataset, &dataset_len) || dataset_len >= sizeof name)
        return xdmf_fail(r, item, "Format HDF: expected file.h5:/path/to/dataset, found \"%.*s\"",
                         (int)(len < 80 ? len : 80), text);
    if (!r->allow_files)
        return xdmf_fail(r, item, "Format HDF (\"%.*s\"): HDF data is not read from memory, only from a file",
                         (int)(len < 80 ? len : 80), text);
    snprintf(name, sizeof name, "%.*s", (int)dataset_len, dataset);
    return xdmf_read_hdf(r, item, path, name, want, out);
}

int xdmf_read_item(xdmf_reader *r, const xdmf_node *item, xdmf_values *out)
{
    memset(out, 0, sizeof *out);
    if (xdmf_follow_reference(r, item, &item))
        return -1;
    const char *item_type = xdmf_attr(item, "ItemType");
    if (item_type && strcasecmp(item_type, "Uniform"))
        return xdmf_fail(r, item, "expected ItemType Uniform, found \"%.40s\" (HyperSlab, Function and other "
                         "computed items are not read)", item_type);
    int64_t want = 0;
    if (parse_dimensions(r, item, out, &want) || parse_number_type(r, item, out))
        return -1;
    const char *format = xdmf_attr(item, "Format");
    int rc;
    if (!format || !strcasecmp(format, "XML"))
        rc = read_text(r, item, want, out);
    else if (!strcasecmp(format, "HDF"))
        rc = read_hdf_item(r, item, want, out);
    else
        rc = xdmf_fail(r, item, "expected Format XML or HDF, found \"%.40s\" (not read)", format);
    if (rc) {
        free(out->v);
        out->v = NULL;
    }
    return rc;
}
