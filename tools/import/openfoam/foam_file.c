/* OpenFOAM's file container: the FoamFile dictionary header and the lists that follow it, ASCII or
 * binary (raw little-endian bytes between the list's parentheses), read whole into memory. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "foam_file.h"
#include "import/gzip_input.h"

/* The only binary layout read: 32-bit labels and 64-bit scalars, little-endian (OpenFOAM's default). */
#define FOAM_ARCH "LSB;label=32;scalar=64"

int64_t tpk_foam_line(const tpk_foam_file *f, size_t pos)
{
    int64_t line = 1;
    for (size_t i = 0; i < pos && i < f->size; i++)
        line += f->data[i] == '\n';
    return line;
}

int tpk_foam_fail(tpk_foam_file *f, const char *fmt, ...)
{
    char what[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    if (f->binary)
        return tpk_diag_fail(f->diag, "%s: byte %zu: %s", f->path, f->pos, what);
    return tpk_diag_fail(f->diag, "%s:%lld: %s", f->path, (long long)tpk_foam_line(f, f->pos), what);
}

static int read_plain(tpk_foam_file *f)
{
    FILE *in = fopen(f->path, "rb");
    if (!in)
        return tpk_diag_fail(f->diag, "%s: cannot open: %s", f->path, strerror(errno));
    struct stat st;
    if (fstat(fileno(in), &st) != 0 || (f->data = malloc((size_t)st.st_size + 1)) == NULL) {
        fclose(in);
        return tpk_diag_fail(f->diag, "%s: cannot read (size or out of memory)", f->path);
    }
    f->size = fread(f->data, 1, (size_t)st.st_size, in);
    fclose(in);
    f->data[f->size] = 0;
    return 0;
}

static int read_gzip(tpk_foam_file *f)
{
    char *inflated;
    size_t n;
    if (tpk_gzip_inflate_file(f->path, 0, &inflated, &n, f->diag) != 0)
        return -1;
    /* One more byte for the terminating NUL the number parsers rely on. */
    char *grown = realloc(inflated, n + 1);
    if (!grown) {
        free(inflated);
        return tpk_diag_fail(f->diag, "%s: out of memory", f->path);
    }
    grown[n] = 0;
    f->data = grown;
    f->size = n;
    return 0;
}

void tpk_foam_skip_space(tpk_foam_file *f)
{
    const char *d = f->data;
    while (f->pos < f->size) {
        char c = d[f->pos];
        if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f') {
            f->pos++;
        } else if (c == '/' && d[f->pos + 1] == '/') {
            while (f->pos < f->size && d[f->pos] != '\n')
                f->pos++;
        } else if (c == '/' && d[f->pos + 1] == '*') {
            const char *end = strstr(d + f->pos + 2, "*/");
            f->pos = end ? (size_t)(end - d) + 2 : f->size;
        } else {
            return;
        }
    }
}

size_t tpk_foam_word(tpk_foam_file *f, char *buf, size_t cap)
{
    tpk_foam_skip_space(f);
    size_t n = 0;
    while (f->pos < f->size && !strchr(" \t\r\n\f(){};", f->data[f->pos])) {
        if (n + 1 < cap)
            buf[n++] = f->data[f->pos];
        f->pos++;
    }
    buf[n] = 0;
    return n;
}

static int expect(tpk_foam_file *f, char c, const char *where)
{
    tpk_foam_skip_space(f);
    if (f->pos < f->size && f->data[f->pos] == c) {
        f->pos++;
        return 0;
    }
    char found[48];
    if (f->pos >= f->size)
        snprintf(found, sizeof found, "end of file");
    else
        snprintf(found, sizeof found, "'%.20s'", f->data + f->pos);
    for (char *p = found; *p; p++)
        if (*p == '\n' || *p == '\r' || (unsigned char)*p < 32)
            *p = ' ';
    return tpk_foam_fail(f, "expected '%c' %s, found %s", c, where, found);
}

/* A header entry's value: a word, or a quoted string (which may hold ';' and blanks) with its quotes. */
static void header_value(tpk_foam_file *f, char *buf, size_t cap)
{
    tpk_foam_skip_space(f);
    if (f->pos >= f->size || f->data[f->pos] != '"') {
        tpk_foam_word(f, buf, cap);
        return;
    }
    size_t n = 0;
    do {
        if (n + 1 < cap)
            buf[n++] = f->data[f->pos];
        f->pos++;
    } while (f->pos < f->size && f->data[f->pos] != '"');
    if (f->pos < f->size && n + 1 < cap)
        buf[n++] = '"';
    f->pos += f->pos < f->size;
    buf[n] = 0;
}

/* The FoamFile { key value; ... } dictionary: format, class and (binary) arch. */
static int parse_header(tpk_foam_file *f)
{
    char key[64], value[128];
    if (tpk_foam_word(f, key, sizeof key) == 0 || strcmp(key, "FoamFile") != 0)
        return tpk_foam_fail(f, "expected the 'FoamFile' header dictionary, found '%s'", key);
    if (expect(f, '{', "after FoamFile") != 0)
        return -1;
    char format[128] = "", arch[128] = "";
    for (;;) {
        tpk_foam_skip_space(f);
        if (f->pos < f->size && f->data[f->pos] == '}')
            break;
        if (tpk_foam_word(f, key, sizeof key) == 0)
            return tpk_foam_fail(f, "expected a FoamFile entry or '}', found %s",
                                 f->pos < f->size ? "a delimiter" : "end of file");
        header_value(f, value, sizeof value);
        if (expect(f, ';', "after a FoamFile entry") != 0)
            return -1;
        if (strcmp(key, "format") == 0)
            snprintf(format, sizeof format, "%s", value);
        else if (strcmp(key, "class") == 0)
            snprintf(f->class_name, sizeof f->class_name, "%s", value);
        else if (strcmp(key, "arch") == 0)
            snprintf(arch, sizeof arch, "%s", value);
    }
    f->pos++;
    if (strcmp(format, "binary") == 0) {
        /* No arch: the writer's own, which OpenFOAM's default build makes this one (tutorials ship so). */
        if (arch[0] && strcmp(arch, "\"" FOAM_ARCH "\"") != 0)
            return tpk_foam_fail(f, "binary file with arch %s: only \"%s\" is read", arch, FOAM_ARCH);
        f->binary = 1;
    } else if (strcmp(format, "ascii") != 0) {
        return tpk_foam_fail(f, "expected format ascii or binary in the FoamFile header, found '%s'", format);
    }
    return 0;
}

/* Read `path` (or path.gz when only that exists) into f. 0, 1 when neither exists, -1 with a message. */
static int load(tpk_foam_file *f, const char *path, tpk_diag *diag)
{
    memset(f, 0, sizeof *f);
    f->diag = diag;
    struct stat st;
    snprintf(f->path, sizeof f->path, "%s", path);
    if (stat(f->path, &st) == 0)
        return read_plain(f);
    snprintf(f->path, sizeof f->path, "%s.gz", path);
    if (stat(f->path, &st) != 0)
        return 1;
    return read_gzip(f);
}

int tpk_foam_open(tpk_foam_file *f, const char *dir, const char *name, tpk_diag *diag)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    int rc = load(f, path, diag);
    if (rc == 0)
        rc = parse_header(f);
    if (rc != 0)
        tpk_foam_close(f);
    return rc;
}

int tpk_foam_read_any(tpk_foam_file *f, const char *path, tpk_diag *diag)
{
    int rc = load(f, path, diag);
    if (rc != 0) {
        tpk_foam_close(f);
        return rc;
    }
    tpk_foam_skip_space(f);
    size_t at = f->pos;
    char word[16];
    tpk_foam_word(f, word, sizeof word);
    f->pos = at;
    if (strcmp(word, "FoamFile") == 0 && parse_header(f) != 0) {
        tpk_foam_close(f);
        return -1;
    }
    return 0;
}

void tpk_foam_close(tpk_foam_file *f)
{
    free(f->data);
    f->data = NULL;
}

/* The list's item count, checked against the bytes left (each item takes at least `min_bytes`). */
static int list_count(tpk_foam_file *f, size_t min_bytes, int64_t *count, const char *what)
{
    tpk_foam_skip_space(f);
    char *end;
    errno = 0;
    long long n = strtoll(f->data + f->pos, &end, 10);
    if (end == f->data + f->pos || errno || n < 0)
        return tpk_foam_fail(f, "expected the number of %s, found '%.20s'", what, f->data + f->pos);
    f->pos = (size_t)(end - f->data);
    if (n > INT32_MAX || (uint64_t)n > (f->size - f->pos) / min_bytes)
        return tpk_foam_fail(f, "%lld %s cannot fit in the %zu bytes left", n, what, f->size - f->pos);
    *count = n;
    return 0;
}

static int ascii_number(tpk_foam_file *f, double *v, const char *what)
{
    tpk_foam_skip_space(f);
    char *end;
    *v = strtod(f->data + f->pos, &end);
    if (end == f->data + f->pos)
        return tpk_foam_fail(f, "expected %s, found '%.20s'", what, f->data + f->pos);
    f->pos = (size_t)(end - f->data);
    return 0;
}

/* Items of `width` numbers (in parentheses when width > 1) into values (doubles) or labels. */
static int read_items(tpk_foam_file *f, int64_t n, int width, double *values, int32_t *labels, const char *what)
{
    size_t item = labels ? 4 : 8;
    if (expect(f, '(', "opening the list") != 0)
        return -1;
    if (f->binary) {
        size_t bytes = (size_t)n * (size_t)width * item;
        if (bytes > f->size - f->pos)
            return tpk_foam_fail(f, "%lld %s need %zu bytes, %zu left", (long long)n, what, bytes, f->size - f->pos);
        memcpy(labels ? (void *)labels : (void *)values, f->data + f->pos, bytes);
        f->pos += bytes;
        return expect(f, ')', "closing the binary list");
    }
    for (int64_t i = 0; i < n; i++) {
        if (width > 1 && expect(f, '(', "opening an item") != 0)
            return -1;
        for (int k = 0; k < width; k++) {
            double v;
            if (ascii_number(f, &v, what) != 0)
                return -1;
            /* Range first: converting an out-of-range double to int32 is undefined. */
            if (labels && !(v >= INT32_MIN && v <= INT32_MAX && v == floor(v)))
                return tpk_foam_fail(f, "expected a label (32-bit integer), found %.17g", v);
            if (!labels && !isfinite(v))
                return tpk_foam_fail(f, "expected a finite number, found %.17g", v);
            if (labels)
                labels[i * width + k] = (int32_t)v;
            else
                values[i * width + k] = v;
        }
        if (width > 1 && expect(f, ')', "closing an item") != 0)
            return -1;
    }
    return expect(f, ')', "closing the list");
}

/* A list of count * width labels (4 bytes each in binary) or scalars (8) into a malloc'ed *out. */
static int read_list(tpk_foam_file *f, int width, int labels, int64_t *count, void **out, const char *what)
{
    size_t item = labels ? 4 : 8;
    *out = NULL;
    if (list_count(f, (size_t)width * (f->binary ? item : 2), count, what) != 0)
        return -1;
    if ((*out = malloc((size_t)(*count ? *count : 1) * (size_t)width * item)) == NULL)
        return tpk_foam_fail(f, "out of memory for %lld %s", (long long)*count, what);
    if (read_items(f, *count, width, labels ? NULL : *out, labels ? *out : NULL, what) == 0)
        return 0;
    free(*out);
    *out = NULL;
    return -1;
}

int tpk_foam_labels(tpk_foam_file *f, int64_t *count, int32_t **out, const char *what)
{
    void *list;
    int rc = read_list(f, 1, 1, count, &list, what);
    *out = list;
    return rc;
}

int tpk_foam_scalars(tpk_foam_file *f, int width, int64_t *count, double **out, const char *what)
{
    void *list;
    int rc = read_list(f, width, 0, count, &list, what);
    *out = list;
    return rc;
}

int tpk_foam_face_list(tpk_foam_file *f, int64_t *count, int64_t **starts, int32_t **ids)
{
    *ids = NULL;
    /* A face is at least "3(0 1 2)": 8 bytes, and 3 ids of at least 2 bytes. */
    if (list_count(f, 8, count, "faces") != 0 || expect(f, '(', "opening the face list") != 0)
        return -1;
    int64_t n = *count;
    size_t id_cap = (size_t)n * 4 + 1;
    if ((*starts = malloc((size_t)(n + 1) * sizeof **starts)) == NULL || (*ids = malloc(id_cap * sizeof **ids)) == NULL)
        goto oom;
    (*starts)[0] = 0;
    for (int64_t i = 0; i < n; i++) {
        int64_t k;
        int32_t *face_ids;
        if (list_count(f, 2, &k, "face points") != 0)
            goto fail;
        if (k < 3) {
            tpk_foam_fail(f, "face %lld has %lld points; a face needs at least 3", (long long)i, (long long)k);
            goto fail;
        }
        if ((size_t)((*starts)[i] + k) > id_cap) {
            id_cap = 2 * id_cap + (size_t)k;
            int32_t *grown = realloc(*ids, id_cap * sizeof **ids);
            if (!grown)
                goto oom;
            *ids = grown;
        }
        face_ids = *ids + (*starts)[i];
        if (read_items(f, k, 1, NULL, face_ids, "face point ids") != 0)
            goto fail;
        (*starts)[i + 1] = (*starts)[i] + k;
    }
    if (expect(f, ')', "closing the face list") == 0)
        return 0;
    goto fail;
oom:
    tpk_foam_fail(f, "out of memory for %lld faces", (long long)n);
fail:
    free(*starts);
    free(*ids);
    *starts = NULL;
    *ids = NULL;
    return -1;
}
