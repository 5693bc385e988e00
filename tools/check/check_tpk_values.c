/* Values that need no tets: finite positions and exact header bounds (TPK-M11, 611), exact field
 * min/max (M12, 612), finite TIME and TMAP/VMAP ranges (M13, 613), and the writer half of rule 15 (text
 * fields NUL-padded and valid UTF-8, spec §7.1), reported with the reader rules under 600. */
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "check_tpk_internal.h"
#include "base/strbuf.h"

typedef struct chunk_buffer {
    void *data;
    uint64_t capacity;
} chunk_buffer;

/* The decoded bytes of chunk (tag, index, step): a view when uncompressed, else a copy in buf.
 * Returns 1 when found, 0 when absent, -1 on error (diag set). */
static int read_chunk(tpkc *c, uint32_t tag, uint32_t index, uint32_t step, chunk_buffer *buf,
                      const void **out, uint64_t *count, tpk_diag *diag)
{
    uint64_t i, size;
    tpk_dir_entry e;
    if (tpk_find_chunk(c->file, tag, index, step, &i) != TPK_OK)
        return 0;
    if (tpk_get_chunk(c->file, i, &e) != TPK_OK)
        return tpk_diag_fail(diag, "chunk %" PRIu64 ": %s", i, tpk_error_text(c->file));
    *count = e.elem_count;
    if (e.codec == TPK_CODEC_NONE)
        return tpk_view_chunk(c->file, i, out, &size) == TPK_OK
                   ? 1 : tpk_diag_fail(diag, "chunk %" PRIu64 ": %s", i, tpk_error_text(c->file));
    if (e.raw_size > buf->capacity) {
        free(buf->data);
        buf->capacity = 0;
        if (!(buf->data = malloc(e.raw_size ? (size_t)e.raw_size : 1)))
            return tpk_diag_fail(diag, "out of memory decoding chunk %" PRIu64 " (%" PRIu64 " bytes)", i, e.raw_size);
        buf->capacity = e.raw_size;
    }
    if (tpk_read_chunk(c->file, i, buf->data, buf->capacity) != TPK_OK)
        return tpk_diag_fail(diag, "chunk %" PRIu64 ": %s", i, tpk_error_text(c->file));
    *out = buf->data;
    return 1;
}

static void check_positions(tpkc *c, tpkc_sink *sink)
{
    tpk_file_info info;
    tpk_get_info(c->file, &info);
    static const char axis[3] = {'x', 'y', 'z'};
    for (int a = 0; a < 3; a++)
        if (!isfinite(c->origin[a]))
            tpk_example_note(tpkc_hit(sink, 611, "header"), "origin %c is %g, must be finite", axis[a], c->origin[a]);
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int any = 0;
    for (int64_t i = 0; i < c->V; i++) {
        const float *p = c->pos + 3 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
            tpk_example *ex = tpkc_hit(sink, 611, "vertex");
            tpk_example_ids(ex, 1, &i);
            tpk_example_note(ex, "stored position (%g, %g, %g) is not finite", p[0], p[1], p[2]);
            continue;
        }
        for (int a = 0; a < 3; a++) {
            double w = c->origin[a] + (double)p[a];
            lo[a] = !any || w < lo[a] ? w : lo[a];
            hi[a] = !any || w > hi[a] ? w : hi[a];
        }
        any = 1;
    }
    for (int a = 0; a < 3; a++) {
        if (info.bounds_min[a] != lo[a])
            tpk_example_note(tpkc_hit(sink, 611, "header"), "bounds_min %c is %.17g, the stored positions give %.17g",
                             axis[a], info.bounds_min[a], lo[a]);
        if (info.bounds_max[a] != hi[a])
            tpk_example_note(tpkc_hit(sink, 611, "header"), "bounds_max %c is %.17g, the stored positions give %.17g",
                             axis[a], info.bounds_max[a], hi[a]);
    }
}

static int same_float(float a, float b)
{
    return a == b || (isnan(a) && isnan(b));
}

static int check_field_range(tpkc *c, tpkc_sink *sink, uint32_t f, chunk_buffer *buf, tpk_diag *diag)
{
    tpk_field_desc d;
    tpk_get_field(c->file, f, &d);
    float lo = NAN, hi = NAN;
    for (uint32_t s = 0; s < d.step_count; s++) {
        const void *data;
        uint64_t count;
        int found = read_chunk(c, TPK_TAG_FDAT, f, s, buf, &data, &count, diag);
        if (found < 0)
            return -1;
        const float *values = data;
        for (uint64_t i = 0; found && i < count; i++) {
            float x = values[i];
            lo = !isnan(x) && (isnan(lo) || x < lo) ? x : lo;
            hi = !isnan(x) && (isnan(hi) || x > hi) ? x : hi;
        }
    }
    if (!same_float(d.min_value, lo) || !same_float(d.max_value, hi)) {
        tpk_example *ex = tpkc_hit(sink, 612, "field");
        tpk_example_ids(ex, 1, (const int64_t[]){f});
        tpk_example_note(ex, "'%s': min_value %.9g, max_value %.9g; its values (all steps, NaN ignored) give "
                         "%.9g, %.9g", d.name, d.min_value, d.max_value, lo, hi);
    }
    return 0;
}

static void value_hit(tpkc_sink *sink, const char *kind, uint64_t id, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* One 613 item: `id` is the step, tet or vertex. */
static void value_hit(tpkc_sink *sink, const char *kind, uint64_t id, const char *fmt, ...)
{
    tpk_example *ex = tpkc_hit(sink, 613, kind);
    if (!ex)
        return;
    tpk_example_ids(ex, 1, (const int64_t[]){(int64_t)id});
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ex->note, sizeof ex->note, fmt, ap);
    va_end(ap);
}

static int check_maps(tpkc *c, tpkc_sink *sink, chunk_buffer *buf, tpk_diag *diag)
{
    const void *data;
    uint64_t count;
    int found = read_chunk(c, TPK_TAG_TIME, 0, 0, buf, &data, &count, diag);
    for (uint64_t s = 0; found > 0 && s < count; s++)
        if (!isfinite(((const double *)data)[s]))
            value_hit(sink, "step", s, "TIME[%" PRIu64 "] = %g, must be finite", s, ((const double *)data)[s]);
    if (found >= 0)
        found = read_chunk(c, TPK_TAG_TMAP, 0, 0, buf, &data, &count, diag);
    for (uint64_t t = 0; found > 0 && t < count; t++)
        if (((const int32_t *)data)[t] < 0)
            value_hit(sink, "tet", t, "TMAP[%" PRIu64 "] = %d, must be >= 0", t, ((const int32_t *)data)[t]);
    if (found >= 0)
        found = read_chunk(c, TPK_TAG_VMAP, 0, 0, buf, &data, &count, diag);
    for (uint64_t v = 0; found > 0 && v < count; v++)
        if (((const int32_t *)data)[v] < -1)
            value_hit(sink, "vertex", v, "VMAP[%" PRIu64 "] = %d, must be >= -1", v, ((const int32_t *)data)[v]);
    return found < 0 ? -1 : 0;
}

/* "" when the text field is valid UTF-8 followed by NUL bytes only, else what is wrong. */
static const char *text_problem(const char *field, size_t size)
{
    const unsigned char *s = (const unsigned char *)field;
    size_t len = strnlen(field, size);
    for (size_t i = len; i < size; i++)
        if (s[i])
            return "has a non-zero byte after its terminating NUL";
    return tpk_utf8_valid(field, len) ? "" : "is not valid UTF-8";
}

static void check_field_text(tpkc *c, tpkc_sink *sink, uint32_t f)
{
    tpk_field_desc d;
    tpk_get_field(c->file, f, &d);
    const char *name = text_problem(d.name, sizeof d.name), *units = text_problem(d.units, sizeof d.units);
    if (!*name && !*units)
        return;
    tpk_example *ex = tpkc_hit(sink, 600, "field");
    tpk_example_ids(ex, 1, (const int64_t[]){f});
    tpk_example_note(ex, "TPK-R15 (writer part, spec 7.1): field %u's %s %s", f, *name ? "name" : "units",
                     *name ? name : units);
}

int tpkc_check_values(tpkc *c, tpk_diag *diag)
{
    tpkc_sink sink = {.max_examples = c->report->options.max_examples};
    chunk_buffer buf = {NULL, 0};
    int rc = 0;
    uint32_t fields = tpk_field_count(c->file);
    for (uint32_t f = 0; f < fields; f++)
        check_field_text(c, &sink, f);
    check_positions(c, &sink);
    for (uint32_t f = 0; f < fields && !rc; f++)
        rc = check_field_range(c, &sink, f, &buf, diag);
    if (!rc)
        rc = check_maps(c, &sink, &buf, diag);
    free(buf.data);
    tpkc_merge(c->report, &sink, 1);
    return rc;
}
