/* tetpack check: validate a mesh (any input format) or a .tpk file; exit 0 clean, 1 problems, 2 unusable. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check/check.h"
#include "check/check_against.h"
#include "cli.h"
#include "base/strbuf.h"

static const char check_help[] =
    "usage: tetpack check INPUT [options]\n"
    "       tetpack check --list\n"
    "\n"
    "Validates a mesh in any format `tetpack convert` reads, or a .tpk file: vertices (1xx), cells (2xx),\n"
    "connectivity (3xx), shell (4xx), fields (5xx) and, for .tpk files, every MUST of the format spec\n"
    "(6xx). Geometric decisions are exact; tolerances only apply where you set them. Prints one line per\n"
    "finding: id, severity, name, count, first example. Exit 0 when nothing of severity error was found\n"
    "(warnings too with --warnings-as-errors), 1 when something was, 2 when the input cannot be read.\n"
    "\n"
    "  --list                  print every check id, severity, name and what it means\n"
    "  --json                  one JSON object (schema \"tetpack-check/1\", see spec/check-json.md)\n"
    "  --format NAME           force the input format (as for convert, or tpk)\n"
    "  --max-examples N        examples kept per finding (default 5)\n"
    "  --tol T                 near-duplicate vertices: closer than T times the bounding-box diagonal\n"
    "                          (default 1e-9; 0 turns the check off)\n"
    "  --sliver-deg D          tets with a dihedral angle below D degrees are slivers (default 0.1)\n"
    "  --radius-ratio R        tets with radius ratio below R are reported as info (default 0.1)\n"
    "  --warp-deg D            quad faces warped by more than D degrees are non-planar (default 20)\n"
    "  --no-self-intersections skip the shell self-intersection test (the slowest check)\n"
    "  --warnings-as-errors    exit 1 on warnings too\n"
    "  --threads N             worker threads (default: all cores)\n"
    "  --progress / --no-progress  progress bar on stderr (default: when stderr is a terminal)\n"
    "  --against SOURCE        instead: measure the converted INPUT.tpk against the mesh it came from. Points\n"
    "                          sampled in every source cell through the cell's own map are found in the\n"
    "                          file's tets (TMAP first); per point field shared by name (scalar): the max\n"
    "                          and RMS difference between the file's linear interpolant and the source\n"
    "                          cell's own, as a fraction of the field's range, and the share of points in\n"
    "                          no tet. Exit 1 when META records a bound (\"max_error\", convert --max-error)\n"
    "                          that a field exceeds (of those \"max_error_fields\" names, if it names any);\n"
    "                          --json prints the report as one JSON object\n"
    "  --samples N             with --against: N samples per parametric axis (1-8; default 4)\n"
    "\n"
    "Input formats (--format NAME, or tpk; tetpack formats says what each carries):\n";

static int parse_double(const char *cmd, const char *opt, const char *text, double lo, double hi, double *out)
{
    char *end = NULL;
    double v = text ? strtod(text, &end) : 0;
    if (!text || !*text || *end || !(v >= lo && v <= hi))
        return tpk_cli_fail(cmd, "%s expects a number in [%g, %g], got '%s'", opt, lo, hi, text ? text : "");
    *out = v;
    return 0;
}

/* The --against report as one JSON object (fractions of each field's range; null where not a number). */
static void print_against_json(const tpk_against_report *r, const char *input, const char *source, int samples)
{
    tpk_strbuf sb = {0};
    tpk_strbuf_printf(&sb, "{\"file\":");
    tpk_strbuf_json_string(&sb, input);
    tpk_strbuf_printf(&sb, ",\"source\":");
    tpk_strbuf_json_string(&sb, source);
    tpk_strbuf_printf(&sb, ",\"samples_per_axis\":%d,\"samples\":%lld,\"cells\":%lld,\"cells_skipped\":%lld,"
                      "\"outside\":%lld,\"fields\":[", samples, (long long)r->samples, (long long)r->cells,
                      (long long)r->cells_skipped, (long long)r->outside);
    for (int f = 0; f < r->field_count; f++) {
        tpk_strbuf_printf(&sb, "%s{\"name\":", f ? "," : "");
        tpk_strbuf_json_string(&sb, r->fields[f].name);
        tpk_strbuf_printf(&sb, ",\"steps\":%d,\"range\":", r->fields[f].steps);
        tpk_strbuf_json_number(&sb, r->fields[f].range);
        tpk_strbuf_printf(&sb, ",\"max_error\":");
        tpk_strbuf_json_number(&sb, r->fields[f].max_error);
        tpk_strbuf_printf(&sb, ",\"rms_error\":");
        tpk_strbuf_json_number(&sb, r->fields[f].rms_error);
        tpk_strbuf_printf(&sb, "}");
    }
    tpk_strbuf_printf(&sb, "],\"bound\":");
    if (r->has_bound)
        tpk_strbuf_json_number(&sb, r->bound);
    else
        tpk_strbuf_printf(&sb, "null");
    tpk_strbuf_printf(&sb, ",\"bound_exceeded\":%s}\n", r->bound_exceeded ? "true" : "false");
    fputs(sb.data ? sb.data : "{}\n", stdout);
    tpk_strbuf_free(&sb);
}

/* check INPUT.tpk --against SOURCE (check/check_against.h): text or JSON report, exit 1 over a recorded
 * bound. */
static int check_against(const char *cmd, const char *input, const char *source, const char *format, int samples,
                         int json)
{
    tpk_against_report r;
    tpk_diag diag = {0};
    if (tpk_check_against(input, source, format, samples, &r, &diag) != 0)
        return tpk_cli_fail(cmd, "%s", diag.message);
    if (json) {
        print_against_json(&r, input, source, samples);
        return r.bound_exceeded ? TPK_EXIT_PROBLEMS : TPK_EXIT_OK;
    }
    printf("%s against %s: %lld samples in %lld source cells (%d per axis), %lld in no tet of the file (%.4g%%)\n",
           input, source, (long long)r.samples, (long long)r.cells, samples, (long long)r.outside,
           r.samples ? 100.0 * (double)r.outside / (double)r.samples : 0.0);
    if (r.cells_skipped)
        printf("  %lld volume cells of kinds without a map here (polyhedra, Lagrange cells...) not sampled\n",
               (long long)r.cells_skipped);
    if (!r.field_count)
        printf("  no scalar point field in both to compare\n");
    for (int f = 0; f < r.field_count; f++)
        printf("  field %-24s %d step(s)  max error %.6g  RMS %.6g  (fractions of its range %.6g)%s\n", r.fields[f].name,
               r.fields[f].steps, r.fields[f].max_error, r.fields[f].rms_error, r.fields[f].range,
               r.has_bound && !r.fields[f].bounded ? "  not bounded" : "");
    if (r.has_bound)
        printf("  bound recorded in META: %.6g: %s\n", r.bound, r.bound_exceeded ? "EXCEEDED" : "met");
    else
        printf("  no bound recorded in META\n");
    return r.bound_exceeded ? TPK_EXIT_PROBLEMS : TPK_EXIT_OK;
}

int tpk_cmd_check(int argc, char **argv)
{
    const char *cmd = "check";
    const char *input = NULL, *format = NULL, *against = NULL;
    int samples = 4;
    int json = 0, warnings_as_errors = 0, progress = -1;
    tpk_check_options opt;
    tpk_check_options_default(&opt);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(check_help, stdout);
            tpk_cli_print_formats(stdout);
            return TPK_EXIT_OK;
        } else if (!strncmp(a, "--against", 9) && (a[9] == 0 || a[9] == '=')) {
            if (!(against = tpk_cli_value(argc, argv, &i, "--against")))
                return tpk_cli_fail(cmd, "--against needs the source mesh");
        } else if (!strncmp(a, "--samples", 9) && (a[9] == 0 || a[9] == '=')) {
            v = tpk_cli_value(argc, argv, &i, "--samples");
            if (!v || tpk_cli_parse_int(v, 1, 8, &samples))
                return tpk_cli_fail(cmd, "--samples expects an integer in [1, 8], got '%s'", v ? v : "");
        } else if (!strcmp(a, "--list")) {
            tpk_check_print_list(stdout);
            return TPK_EXIT_OK;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--warnings-as-errors")) {
            warnings_as_errors = 1;
        } else if (!strcmp(a, "--no-self-intersections")) {
            opt.skip_shell_intersections = 1;
        } else if (!strcmp(a, "--progress")) {
            progress = 1;
        } else if (!strcmp(a, "--no-progress")) {
            progress = 0;
        } else if (!strncmp(a, "--format", 8) && (a[8] == 0 || a[8] == '=')) {
            if (!(format = tpk_cli_value(argc, argv, &i, "--format")))
                return tpk_cli_fail(cmd, "--format needs a value");
        } else if (!strncmp(a, "--max-examples", 14) && (a[14] == 0 || a[14] == '=')) {
            v = tpk_cli_value(argc, argv, &i, "--max-examples");
            if (!v || tpk_cli_parse_int(v, 0, 100000, &opt.max_examples))
                return tpk_cli_fail(cmd, "--max-examples expects an integer in [0, 100000], got '%s'", v ? v : "");
        } else if (!strncmp(a, "--threads", 9) && (a[9] == 0 || a[9] == '=')) {
            v = tpk_cli_value(argc, argv, &i, "--threads");
            if (!v || tpk_cli_parse_int(v, 1, 64, &opt.threads))
                return tpk_cli_fail(cmd, "--threads expects an integer in [1, 64], got '%s'", v ? v : "");
        } else if (!strncmp(a, "--tol", 5) && (a[5] == 0 || a[5] == '=')) {
            if (parse_double(cmd, "--tol", tpk_cli_value(argc, argv, &i, "--tol"), 0, 1, &opt.tol))
                return TPK_EXIT_USAGE;
        } else if (!strncmp(a, "--sliver-deg", 12) && (a[12] == 0 || a[12] == '=')) {
            if (parse_double(cmd, "--sliver-deg", tpk_cli_value(argc, argv, &i, "--sliver-deg"), 0, 90,
                             &opt.sliver_deg))
                return TPK_EXIT_USAGE;
        } else if (!strncmp(a, "--radius-ratio", 14) && (a[14] == 0 || a[14] == '=')) {
            if (parse_double(cmd, "--radius-ratio", tpk_cli_value(argc, argv, &i, "--radius-ratio"), 0, 1,
                             &opt.radius_ratio_min))
                return TPK_EXIT_USAGE;
        } else if (!strncmp(a, "--warp-deg", 10) && (a[10] == 0 || a[10] == '=')) {
            if (parse_double(cmd, "--warp-deg", tpk_cli_value(argc, argv, &i, "--warp-deg"), 0, 180,
                             &opt.warp_deg))
                return TPK_EXIT_USAGE;
        } else if (a[0] == '-' && a[1]) {
            return tpk_cli_fail(cmd, "unknown option '%s' (tetpack check --help lists them)", a);
        } else if (!input) {
            input = a;
        } else {
            return tpk_cli_fail(cmd, "one input expected; got '%s' and '%s'", input, a);
        }
    }
    if (!input)
        return tpk_cli_fail(cmd, "no input given (tetpack check --help)");
    if (against)
        return check_against(cmd, input, against, format, samples, json);
    opt.progress = progress >= 0 ? progress : isatty(2);
    tpk_check_report report;
    if (tpk_check_report_init(&report, &opt))
        return tpk_cli_fail(cmd, "out of memory");
    tpk_diag diag = {0};
    if (tpk_check_path(input, format, &report, &diag) != 0) {
        tpk_check_report_free(&report);
        return tpk_cli_fail(cmd, "%s", diag.message);
    }
    int status = tpk_check_has_problems(&report, warnings_as_errors) ? TPK_EXIT_PROBLEMS : TPK_EXIT_OK;
    if (json) {
        tpk_strbuf sb = {0};
        tpk_check_write_json(&report, &sb);
        if (sb.failed) {
            tpk_strbuf_free(&sb);
            tpk_check_report_free(&report);
            return tpk_cli_fail(cmd, "out of memory");
        }
        fwrite(sb.data, 1, sb.length, stdout);
        tpk_strbuf_free(&sb);
    } else {
        tpk_check_print_text(&report, stdout);
    }
    tpk_check_report_free(&report);
    return status;
}
