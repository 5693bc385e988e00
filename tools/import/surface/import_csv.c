/* CSV point clouds: a header line of comma-separated column names (x, y and z required, any case),
 * then one point per line; the other columns become point fields. Blank lines and lines starting
 * with '#' are skipped. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "surface.h"
#include "tetpack_format.h"
#include "surface_build.h"
#include "base/text_scan.h"

#define CSV_MAX_COLUMNS 256

typedef struct csv_line {
    const char *text;
    size_t len;
    int64_t number; /* 1-based */
} csv_line;

/* Next line that is neither blank nor a comment; 0 at end of input. */
static int next_line(const char *data, size_t size, size_t *pos, int64_t *line_no, csv_line *out)
{
    while (*pos < size) {
        const char *start = data + *pos, *nl = memchr(start, '\n', size - *pos);
        size_t len = nl ? (size_t)(nl - start) : size - *pos;
        *pos += len + (nl != NULL);
        int64_t number = ++*line_no;
        while (len && (start[len - 1] == '\r' || start[len - 1] == ' ' || start[len - 1] == '\t'))
            len--;
        size_t lead = 0;
        while (lead < len && (start[lead] == ' ' || start[lead] == '\t'))
            lead++;
        if (lead == len || start[lead] == '#')
            continue;
        *out = (csv_line){start, len, number};
        return 1;
    }
    return 0;
}

/* Cell `col` of a line split at commas: start and length, blanks trimmed. Returns the cells found. */
static int split_cells(const csv_line *l, const char **cell, size_t *cell_len, int max)
{
    int n = 0;
    size_t at = 0;
    for (;;) {
        const char *c = memchr(l->text + at, ',', l->len - at);
        size_t end = c ? (size_t)(c - l->text) : l->len, b = at;
        while (b < end && (l->text[b] == ' ' || l->text[b] == '\t'))
            b++;
        size_t e = end;
        while (e > b && (l->text[e - 1] == ' ' || l->text[e - 1] == '\t'))
            e--;
        if (n < max) {
            cell[n] = l->text + b;
            cell_len[n] = e - b;
        }
        n++;
        if (!c)
            return n;
        at = end + 1;
    }
}

typedef struct csv_columns {
    int count;
    int axis[CSV_MAX_COLUMNS]; /* 0, 1, 2 for x, y, z, else -1 */
    char names[CSV_MAX_COLUMNS][TPK_NAME_MAX];
    float *values[CSV_MAX_COLUMNS];
} csv_columns;

static int read_csv_header(tpk_scan *s, const csv_line *l, csv_columns *cols)
{
    const char *cell[CSV_MAX_COLUMNS];
    size_t len[CSV_MAX_COLUMNS];
    int n = split_cells(l, cell, len, CSV_MAX_COLUMNS), found[3] = {0, 0, 0};
    if (n > CSV_MAX_COLUMNS)
        return tpk_scan_fail_at(s, 0, l->number, "expected at most %d columns, found %d", CSV_MAX_COLUMNS, n);
    cols->count = n;
    for (int i = 0; i < n; i++) {
        if (len[i] >= 2 && cell[i][0] == '"' && cell[i][len[i] - 1] == '"')
            cell[i]++, len[i] -= 2;
        char q[64];
        if (!len[i] || len[i] >= TPK_NAME_MAX)
            return tpk_scan_fail_at(s, 0, l->number, "expected a column name of 1 to %d characters in the header, "
                                    "found '%s' (column %d)", TPK_NAME_MAX - 1, tpk_scan_quote(cell[i], len[i], q, sizeof q), i + 1);
        memcpy(cols->names[i], cell[i], len[i]);
        cols->names[i][len[i]] = 0;
        cols->axis[i] = -1;
        for (int k = 0; k < 3; k++)
            if (!strcasecmp(cols->names[i], (const char *[]){"x", "y", "z"}[k]) && !found[k])
                cols->axis[i] = k, found[k] = 1;
    }
    if (!found[0] || !found[1] || !found[2])
        return tpk_scan_fail_at(s, 0, l->number, "expected a header line naming columns x, y and z, found '%.*s'",
                                (int)(l->len < 200 ? l->len : 200), l->text);
    return 0;
}

static int read_csv_point(tpk_scan *s, const csv_line *l, csv_columns *cols, tpk_mesh *m, int64_t i)
{
    const char *cell[CSV_MAX_COLUMNS];
    size_t len[CSV_MAX_COLUMNS];
    int n = split_cells(l, cell, len, CSV_MAX_COLUMNS);
    if (n != cols->count)
        return tpk_scan_fail_at(s, 0, l->number, "expected %d comma-separated values, found %d", cols->count, n);
    for (int c = 0; c < n; c++) {
        double v;
        char q[64];
        if (tpk_parse_double(cell[c], len[c], &v) != 0)
            return tpk_scan_fail_at(s, 0, l->number, "expected a number in column '%s', found '%s'", cols->names[c],
                                    tpk_scan_quote(cell[c], len[c], q, sizeof q));
        if (cols->axis[c] >= 0 && !isfinite(v))
            return tpk_scan_fail_at(s, 0, l->number, "expected a finite %s coordinate, found '%s'", cols->names[c],
                                    tpk_scan_quote(cell[c], len[c], q, sizeof q));
        if (cols->axis[c] >= 0)
            m->points[3 * i + cols->axis[c]] = v;
        else
            cols->values[c][i] = (float)v;
    }
    return 0;
}

static int read_csv_body(tpk_scan *s, csv_columns *cols, tpk_mesh *out)
{
    size_t pos = 0;
    int64_t line_no = 0, lines = 1;
    csv_line l;
    for (size_t i = 0; i < s->size; i++)
        lines += s->data[i] == '\n';
    if (!next_line((const char *)s->data, s->size, &pos, &line_no, &l))
        return tpk_scan_fail_at(s, 0, 1, "expected a header line naming columns x, y and z, found an empty file");
    if (read_csv_header(s, &l, cols))
        return -1;
    if (lines > INT32_MAX || tpk_surf_alloc(out, lines, 0, 0) != 0)
        return tpk_scan_fail_at(s, 0, 1, "out of memory for %lld points", (long long)lines);
    for (int c = 0; c < cols->count; c++)
        if (cols->axis[c] < 0 && !(cols->values[c] = malloc(sizeof(float) * (size_t)lines)))
            return tpk_scan_fail_at(s, 0, 1, "out of memory for column '%s'", cols->names[c]);
    int64_t count = 0;
    while (next_line((const char *)s->data, s->size, &pos, &line_no, &l))
        if (read_csv_point(s, &l, cols, out, count++))
            return -1;
    out->point_count = count;
    for (int c = 0; c < cols->count; c++) {
        if (!cols->values[c])
            continue;
        if (tpk_mesh_add_field(out, cols->names[c], TPK_ASSOC_POINT, 1, 1, cols->values[c]))
            return tpk_scan_fail_at(s, 0, 1, "out of memory for column '%s'", cols->names[c]);
        cols->values[c] = NULL;
    }
    strcpy(out->format, "csv-points");
    return 0;
}

int tpk_read_csv_points(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    tpk_scan s;
    tpk_scan_init(&s, name, data, size, diag);
    memset(out, 0, sizeof *out);
    csv_columns *cols = calloc(1, sizeof *cols);
    if (!cols)
        return tpk_diag_fail(diag, "%s: out of memory", name);
    int rc = read_csv_body(&s, cols, out);
    for (int c = 0; c < CSV_MAX_COLUMNS; c++)
        free(cols->values[c]);
    free(cols);
    if (rc)
        tpk_mesh_free(out);
    return rc;
}
