/* The check report: findings per registry entry, examples, histograms; text, JSON and --list output. */
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

void tpk_check_options_default(tpk_check_options *options)
{
    memset(options, 0, sizeof *options);
    options->tol = 1e-9;
    /* Measured on the real meshes in shared/data: the smallest dihedral angle of a clean mesh is 0.297 deg
     * (refine's ONERA M6 boundary layer), the largest quad warp 17.x deg (gmsh t3's twisted wedges). */
    options->sliver_deg = 0.1;
    options->warp_deg = 20.0;
    options->radius_ratio_min = 0.1;
    options->max_examples = 5;
}

int tpk_check_report_init(tpk_check_report *report, const tpk_check_options *options)
{
    int count;
    const tpk_check_def *defs = tpk_check_registry(&count);
    memset(report, 0, sizeof *report);
    report->options = *options;
    if (report->options.max_examples < 0)
        report->options.max_examples = 0;
    report->findings = calloc((size_t)count, sizeof *report->findings);
    if (!report->findings)
        return -1;
    report->finding_count = count;
    for (int i = 0; i < count; i++)
        report->findings[i].check = &defs[i];
    return 0;
}

void tpk_check_report_free(tpk_check_report *report)
{
    for (int i = 0; i < report->finding_count; i++)
        free(report->findings[i].examples);
    free(report->findings);
    report->findings = NULL;
    report->finding_count = 0;
}

tpk_finding *tpk_check_finding(tpk_check_report *report, int id)
{
    for (int i = 0; i < report->finding_count; i++)
        if (report->findings[i].check->id == id)
            return &report->findings[i];
    fprintf(stderr, "tetpack check: internal error: no check with id %d\n", id);
    abort();
}

tpk_example *tpk_check_hit(tpk_check_report *report, int id, const char *kind)
{
    tpk_finding *f = tpk_check_finding(report, id);
    f->count++;
    return tpk_example_slot(&f->examples, &f->example_count, report->options.max_examples, kind);
}

tpk_example *tpk_example_slot(tpk_example **examples, int *kept, int max, const char *kind)
{
    if (*kept >= max)
        return NULL;
    if (!*examples) {
        *examples = calloc((size_t)max, sizeof **examples);
        if (!*examples)
            return NULL;
    }
    tpk_example *ex = &(*examples)[(*kept)++];
    memset(ex, 0, sizeof *ex);
    ex->kind = kind;
    return ex;
}

void tpk_check_count(tpk_check_report *report, int id, int64_t n)
{
    tpk_check_finding(report, id)->count += n;
}

void tpk_example_ids(tpk_example *ex, int count, const int64_t *ids)
{
    if (!ex)
        return;
    if (count > TPK_CHECK_MAX_IDS)
        count = TPK_CHECK_MAX_IDS;
    ex->id_count = count;
    memcpy(ex->ids, ids, (size_t)count * sizeof *ids);
}

void tpk_example_point(tpk_example *ex, const double p[3])
{
    if (!ex)
        return;
    ex->has_point = 1;
    memcpy(ex->point, p, sizeof ex->point);
}

void tpk_example_note(tpk_example *ex, const char *fmt, ...)
{
    if (!ex)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ex->note, sizeof ex->note, fmt, ap);
    va_end(ap);
}

tpk_histogram *tpk_check_histogram(tpk_check_report *report, const char *name, double lo, double hi)
{
    for (int i = 0; i < report->histogram_count; i++)
        if (!strcmp(report->histograms[i].name, name))
            return &report->histograms[i];
    if (report->histogram_count >= TPK_CHECK_MAX_HISTOGRAMS)
        return NULL;
    tpk_histogram *h = &report->histograms[report->histogram_count++];
    memset(h, 0, sizeof *h);
    h->name = name;
    h->lo = lo;
    h->hi = hi;
    h->min = INFINITY;
    h->max = -INFINITY;
    return h;
}

void tpk_histogram_add(tpk_histogram *h, double value)
{
    if (!h || !isfinite(value))
        return;
    /* clamped as a double: a value far outside [lo, hi] (a radius ratio of a nearly flat tet) does not
     * fit an int (found by fuzz_tpk_struct) */
    double at = (value - h->lo) / (h->hi - h->lo) * TPK_HIST_BINS;
    int b = !(at >= 0) ? 0 : at >= TPK_HIST_BINS ? TPK_HIST_BINS - 1 : (int)at;
    h->bins[b]++;
    h->count++;
    h->sum += value;
    if (value < h->min)
        h->min = value;
    if (value > h->max)
        h->max = value;
}

int tpk_check_has_problems(const tpk_check_report *report, int warnings_as_errors)
{
    for (int i = 0; i < report->finding_count; i++) {
        const tpk_finding *f = &report->findings[i];
        if (f->count > 0 && (f->check->severity == TPK_SEV_ERROR ||
                             (warnings_as_errors && f->check->severity == TPK_SEV_WARNING)))
            return 1;
    }
    return 0;
}

static const char *severity_name(tpk_severity s)
{
    return s == TPK_SEV_ERROR ? "error" : s == TPK_SEV_WARNING ? "warning" : "info";
}

static void example_text(const tpk_example *ex, char *out, size_t cap)
{
    size_t used = 0;
    int n = snprintf(out, cap, "%s", ex->kind ? ex->kind : "item");
    used = n > 0 ? (size_t)n : 0;
    for (int k = 0; k < ex->id_count && used < cap; k++) {
        n = snprintf(out + used, cap - used, k == 0 ? " %lld" : k == 1 ? " (%lld" : " %lld",
                     (long long)ex->ids[k]);
        used += n > 0 ? (size_t)n : 0;
    }
    if (ex->id_count > 1 && used < cap) {
        n = snprintf(out + used, cap - used, ")");
        used += n > 0 ? (size_t)n : 0;
    }
    if (ex->has_point && used < cap) {
        n = snprintf(out + used, cap - used, " at (%.9g, %.9g, %.9g)", ex->point[0], ex->point[1],
                     ex->point[2]);
        used += n > 0 ? (size_t)n : 0;
    }
    if (ex->note[0] && used < cap)
        snprintf(out + used, cap - used, ": %s", ex->note);
}

void tpk_check_print_text(const tpk_check_report *report, FILE *out)
{
    fprintf(out, "%s: %s, %lld vertices, %lld cells", report->input, report->format,
            (long long)report->vertices, (long long)report->cells);
    if (report->tets)
        fprintf(out, " (%lld tets)", (long long)report->tets);
    fprintf(out, "\n");
    int shown = 0;
    for (int i = 0; i < report->finding_count; i++) {
        const tpk_finding *f = &report->findings[i];
        if (f->count == 0)
            continue;
        char ex[400] = "";
        if (f->summary[0])
            snprintf(ex, sizeof ex, "%s", f->summary);
        else if (f->example_count)
            example_text(&f->examples[0], ex, sizeof ex);
        fprintf(out, "  %3d %-7s %-26s %10lld  %s\n", f->check->id, severity_name(f->check->severity),
                f->check->name, (long long)f->count, ex);
        shown++;
    }
    for (int i = 0; i < report->histogram_count; i++) {
        const tpk_histogram *h = &report->histograms[i];
        if (h->count)
            fprintf(out, "  quality %-22s min %.4g  mean %.4g  max %.4g  (%lld tets)\n", h->name, h->min,
                    h->sum / (double)h->count, h->max, (long long)h->count);
    }
    int problems = tpk_check_has_problems(report, 0);
    int warnings = 0;
    for (int i = 0; i < report->finding_count; i++)
        if (report->findings[i].count && report->findings[i].check->severity == TPK_SEV_WARNING)
            warnings++;
    if (!problems && !warnings)
        fprintf(out, "  no problems found\n");
    else
        fprintf(out, "  %s\n", problems ? "problems found (see ids above; tetpack check --list explains them)"
                                          : "warnings only");
    (void)shown;
}

static void json_example(tpk_strbuf *sb, const tpk_example *ex)
{
    tpk_strbuf_printf(sb, "{\"kind\":");
    tpk_strbuf_json_string(sb, ex->kind ? ex->kind : "item");
    tpk_strbuf_printf(sb, ",\"ids\":[");
    for (int k = 0; k < ex->id_count; k++)
        tpk_strbuf_printf(sb, "%s%lld", k ? "," : "", (long long)ex->ids[k]);
    tpk_strbuf_printf(sb, "]");
    if (ex->has_point) {
        tpk_strbuf_printf(sb, ",\"at\":[");
        for (int k = 0; k < 3; k++) {
            if (k)
                tpk_strbuf_printf(sb, ",");
            tpk_strbuf_json_number(sb, ex->point[k]);
        }
        tpk_strbuf_printf(sb, "]");
    }
    if (ex->note[0]) {
        tpk_strbuf_printf(sb, ",\"note\":");
        tpk_strbuf_json_string(sb, ex->note);
    }
    tpk_strbuf_printf(sb, "}");
}

void tpk_check_write_json(const tpk_check_report *report, tpk_strbuf *sb)
{
    static const char *group_names[7] = {"", "vertices", "cells", "connectivity", "shell", "fields", "file"};
    tpk_strbuf_printf(sb, "{\"schema\":\"tetpack-check/1\",\"input\":");
    tpk_strbuf_json_string(sb, report->input);
    tpk_strbuf_printf(sb, ",\"format\":");
    tpk_strbuf_json_string(sb, report->format);
    tpk_strbuf_printf(sb, ",\"vertices\":%lld,\"cells\":%lld", (long long)report->vertices,
                      (long long)report->cells);
    if (report->tets)
        tpk_strbuf_printf(sb, ",\"tets\":%lld", (long long)report->tets);
    tpk_strbuf_printf(sb, ",\"problems\":%s", tpk_check_has_problems(report, 0) ? "true" : "false");
    tpk_strbuf_printf(sb, ",\"groups\":[");
    int first = 1;
    for (int g = 1; g <= 6; g++)
        if (report->ran[g]) {
            tpk_strbuf_printf(sb, "%s{\"name\":\"%s\",\"seconds\":", first ? "" : ",", group_names[g]);
            tpk_strbuf_json_number(sb, report->seconds[g]);
            tpk_strbuf_printf(sb, "}");
            first = 0;
        }
    tpk_strbuf_printf(sb, "],\"findings\":[");
    first = 1;
    for (int i = 0; i < report->finding_count; i++) {
        const tpk_finding *f = &report->findings[i];
        if (f->count == 0)
            continue;
        tpk_strbuf_printf(sb, "%s{\"id\":%d,\"name\":\"%s\",\"severity\":\"%s\",\"count\":%lld",
                          first ? "" : ",", f->check->id, f->check->name, severity_name(f->check->severity),
                          (long long)f->count);
        first = 0;
        if (f->summary[0]) {
            tpk_strbuf_printf(sb, ",\"summary\":");
            tpk_strbuf_json_string(sb, f->summary);
        }
        tpk_strbuf_printf(sb, ",\"examples\":[");
        for (int k = 0; k < f->example_count; k++) {
            if (k)
                tpk_strbuf_printf(sb, ",");
            json_example(sb, &f->examples[k]);
        }
        tpk_strbuf_printf(sb, "]}");
    }
    tpk_strbuf_printf(sb, "],\"components\":{\"count\":%lld,\"largest_sizes\":[",
                      (long long)report->component_count);
    for (int i = 0; i < 16 && i < report->component_count; i++)
        tpk_strbuf_printf(sb, "%s%lld", i ? "," : "", (long long)report->component_sizes[i]);
    tpk_strbuf_printf(sb, "]},\"quality\":[");
    for (int i = 0; i < report->histogram_count; i++) {
        const tpk_histogram *h = &report->histograms[i];
        tpk_strbuf_printf(sb, "%s{\"name\":", i ? "," : "");
        tpk_strbuf_json_string(sb, h->name);
        tpk_strbuf_printf(sb, ",\"count\":%lld,\"min\":", (long long)h->count);
        tpk_strbuf_json_number(sb, h->count ? h->min : NAN);
        tpk_strbuf_printf(sb, ",\"mean\":");
        tpk_strbuf_json_number(sb, h->count ? h->sum / (double)h->count : NAN);
        tpk_strbuf_printf(sb, ",\"max\":");
        tpk_strbuf_json_number(sb, h->count ? h->max : NAN);
        tpk_strbuf_printf(sb, ",\"lo\":");
        tpk_strbuf_json_number(sb, h->lo);
        tpk_strbuf_printf(sb, ",\"hi\":");
        tpk_strbuf_json_number(sb, h->hi);
        tpk_strbuf_printf(sb, ",\"bins\":[");
        for (int b = 0; b < TPK_HIST_BINS; b++)
            tpk_strbuf_printf(sb, "%s%lld", b ? "," : "", (long long)h->bins[b]);
        tpk_strbuf_printf(sb, "]}");
    }
    tpk_strbuf_printf(sb, "],\"fields\":[");
    for (int i = 0; i < report->field_stat_count; i++) {
        const tpk_field_stat *s = &report->field_stats[i];
        tpk_strbuf_printf(sb, "%s{\"name\":", i ? "," : "");
        tpk_strbuf_json_string(sb, s->name);
        tpk_strbuf_printf(sb, ",\"association\":\"%s\",\"components\":%d,\"step\":%d,\"min\":",
                          s->association == 0 ? "point" : "cell", s->components, s->step);
        tpk_strbuf_json_number(sb, s->min);
        tpk_strbuf_printf(sb, ",\"max\":");
        tpk_strbuf_json_number(sb, s->max);
        tpk_strbuf_printf(sb, ",\"nonfinite\":%lld}", (long long)s->nonfinite);
    }
    tpk_strbuf_printf(sb, "]}\n");
}

void tpk_check_print_list(FILE *out)
{
    int count;
    const tpk_check_def *defs = tpk_check_registry(&count);
    const char *group = "";
    for (int i = 0; i < count; i++) {
        if (strcmp(group, defs[i].group)) {
            group = defs[i].group;
            fprintf(out, "%s%s:\n", i ? "\n" : "", group);
        }
        fprintf(out, "  %3d %-7s %-26s %s\n", defs[i].id, severity_name(defs[i].severity), defs[i].name,
                defs[i].explanation);
    }
}
