/* The options of tetpack render and tetpack view: the option table and its parsers, the scene merge, and
 * render_args_to_options, the one place the parsed arguments become render options (render_args.h). */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "render_args.h"
#include "scene/option_table.h"

void render_args_default(render_args *a)
{
    memset(a, 0, sizeof *a);
    a->width = a->height = 512;
#define TPK_USE(init, ...) init
#define TPK_OPTION(ID, name, kind, R, A, S, rule, cli, key, use, vk) TPK_IF(A, a->name = use;)
#include "render/render_options.def"
#undef TPK_OPTION
#undef TPK_USE
}

/* The table's options that are fields of render_args (A = 1): where each one is, by row. */
#define TPK_OPTION(ID, name, kind, R, A, S, ...) TPK_IF(A, [TPK_OPT_##ID] = offsetof(render_args, name) + 1,)
static const size_t args_at[TPK_OPT_COUNT] = {
#include "render/render_options.def"
};
#undef TPK_OPTION

static int parse_size(const char *text, int *w, int *h)
{
    char *end;
    long x = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X'))
        return -1;
    const char *rest = end + 1;
    long y = strtol(rest, &end, 10);
    if (end == rest || *end || x < 1 || y < 1 || x > 16384 || y > 16384)
        return -1;
    *w = (int)x;
    *h = (int)y;
    return 0;
}

/* 1 to `max` comma-separated numbers. */
static int parse_list(const char *text, double *out, int max, int *count)
{
    char *end;
    for (int n = 0; n < max; n++) {
        out[n] = strtod(text, &end);
        if (end == text || !isfinite(out[n]))
            return -1;
        if (!*end) {
            *count = n + 1;
            return 0;
        }
        if (*end != ',')
            return -1;
        text = end + 1;
    }
    return -1;
}

/* ---- The option table: one parser per option; each returns 0 or -1 (then the table's `expects` is
 * printed with the value found). Ranges and choices are the table's (tpk_option_int_ok, _number_ok,
 * tpk_option_choice), which the scene reader checks too. */

static int int_option(tpk_option_id id, const char *v, int *out)
{
    const tpk_option_row *r = &tpk_option_table[id];
    return tpk_cli_parse_int(v, (int)r->lo, (int)r->hi, out) || !tpk_option_int_ok(id, *out) ? -1 : 0;
}

static int number_option(tpk_option_id id, const char *v, double *out)
{
    return tpk_cli_parse_doubles(v, out, 1) || !tpk_option_number_ok(id, *out) ? -1 : 0;
}

static int opt_output(const char *v, render_args *a) { a->output = v; return 0; }
static int opt_size(const char *v, render_args *a) { return parse_size(v, &a->width, &a->height); }
static int opt_tf(const char *v, render_args *a) { a->tf = v; return 0; }
static int opt_field(const char *v, render_args *a) { a->field = v; return 0; }

static int opt_camera(const char *v, render_args *a)
{
    a->have_camera = 1;
    return tpk_cli_parse_doubles(v, a->camera, 10) || !tpk_option_number_ok(TPK_OPT_CAMERA_FOVY, a->camera[9]) ? -1 : 0;
}

static int opt_step(const char *v, render_args *a)
{
    a->have_steps = 0;
    if (int_option(TPK_OPT_STEP, v, &a->step))
        return -1;
    a->step_last = a->step;
    return 0;
}

static int opt_steps(const char *v, render_args *a)
{
    char first[32];
    const char *colon = strchr(v, ':');
    if (!colon || (size_t)(colon - v) >= sizeof first)
        return -1;
    memcpy(first, v, (size_t)(colon - v));
    first[colon - v] = 0;
    if (int_option(TPK_OPT_STEP, first, &a->step) || int_option(TPK_OPT_STEP, colon + 1, &a->step_last) ||
        a->step_last < a->step || a->step_last - a->step >= 100000)
        return -1;
    a->have_steps = 1;
    return 0;
}

static int opt_range(const char *v, render_args *a)
{
    a->have_range = 1;
    return tpk_cli_parse_doubles(v, a->range, 2) || !(a->range[0] < a->range[1]) ? -1 : 0;
}

static int opt_layout(const char *v, render_args *a)
{
    a->layout = v;
    return tpk_option_choice(TPK_OPT_LAYOUT, v) < 0 ? -1 : 0;
}

static int opt_scene(const char *v, render_args *a) { (void)v; (void)a; return 0; } /* read by render_args_merge_scene */
static int opt_save_scene(const char *v, render_args *a) { a->save_scene = v; return 0; }
static int opt_save_tpk(const char *v, render_args *a) { a->save_tpk = v; return 0; }
static int opt_backend(const char *v, render_args *a)
{
    a->backend = v;
    a->backend_from_scene = 0;
    return tpk_option_choice(TPK_OPT_BACKEND, v) < 0 ? -1 : 0;
}
static int opt_iso(const char *v, render_args *a)
{
    a->iso_auto = !strcmp(v, "auto");
    if (a->iso_auto) {
        a->iso_count = 0;
        return 0;
    }
    return parse_list(v, a->iso, TPK_RENDER_MAX_ISO, &a->iso_count);
}

static int opt_clip(const char *v, render_args *a)
{
    a->clip = 1;
    if (tpk_cli_parse_doubles(v, a->clip_box, 6))
        return -1;
    for (int k = 0; k < 3; k++)
        if (!(a->clip_box[k] <= a->clip_box[k + 3]))
            return -1;
    return 0;
}

static int opt_probe(const char *v, render_args *a)
{
    if (!a->probes_from_cli)
        a->probe_count = 0;
    a->probes_from_cli = 1;
    if (a->probe_count >= TPK_RENDER_MAX_PROBES || tpk_probe_parse(v, &a->probes[a->probe_count]))
        return -1;
    a->probe_count++;
    return 0;
}

static int opt_light(const char *v, render_args *a)
{
    a->have_light = 1;
    return tpk_cli_parse_doubles(v, a->light, 3);
}

/* A row of the table that is a field of render_args (args_at), by its kind and rule. */
static int table_option(tpk_option_id id, const char *v, render_args *a)
{
    char *field = (char *)a + args_at[id] - 1;
    switch (tpk_option_table[id].kind) {
    case TPK_OPT_KIND_INT:
        return int_option(id, v, (int *)field);
    case TPK_OPT_KIND_NUMBER:
        return number_option(id, v, (double *)field);
    case TPK_OPT_KIND_CHOICE: /* the index of the choice: the order of the values (TPK_INTEGRATION_*, ...) */
        return (*(int *)field = tpk_option_choice(id, v)) < 0 ? -1 : 0;
    case TPK_OPT_KIND_BOOL:
        *(int *)field = 1;
        return 0;
    default:
        return -1;
    }
}

/* The parser of each other row of the option table (scene/option_table.h) that has a flag. */
typedef int (*option_parser)(const char *value, render_args *a);
static const option_parser parsers[TPK_OPT_COUNT] = {
    [TPK_OPT_OUTPUT] = opt_output,
    [TPK_OPT_SIZE] = opt_size,
    [TPK_OPT_CAMERA] = opt_camera,
    [TPK_OPT_TF] = opt_tf,
    [TPK_OPT_FIELD] = opt_field,
    [TPK_OPT_STEP] = opt_step,
    [TPK_OPT_STEPS] = opt_steps,
    [TPK_OPT_RANGE] = opt_range,
    [TPK_OPT_LAYOUT] = opt_layout,
    [TPK_OPT_BACKEND] = opt_backend,
    [TPK_OPT_ISO] = opt_iso,
    [TPK_OPT_CLIP_BOX] = opt_clip,
    [TPK_OPT_PROBE] = opt_probe,
    [TPK_OPT_LIGHT] = opt_light,
    [TPK_OPT_SCENE] = opt_scene,
    [TPK_OPT_SAVE_SCENE] = opt_save_scene,
    [TPK_OPT_SAVE_TPK] = opt_save_tpk,
};

const tpk_option_row *render_args_find_option(const char *arg)
{
    for (int k = 0; k < TPK_OPT_COUNT; k++) {
        const tpk_option_row *o = &tpk_option_table[k];
        if (!o->flag)
            continue;
        size_t n = strlen(o->flag);
        if ((o->alias && !strcmp(arg, o->alias)) || !strcmp(arg, o->flag) ||
            (o->metavar && !strncmp(arg, o->flag, n) && arg[n] == '='))
            return o;
    }
    return NULL;
}

int render_args_parse_option(const char *cmd, int argc, char **argv, int *i, render_args *a)
{
    const char *arg = argv[*i];
    const tpk_option_row *o = render_args_find_option(arg);
    if (o) {
        const char *v = o->metavar ? tpk_cli_value(argc, argv, i, o->alias && !strcmp(arg, o->alias) ? o->alias : o->flag)
                                   : NULL;
        if (o->metavar && !v)
            return tpk_cli_fail(cmd, "%s expects %s", o->flag, o->expects);
        if (!args_at[o->id] && !parsers[o->id]) /* a row given a flag but no parser here: a bug, said as such */
            return tpk_cli_fail(cmd, "%s: no parser for this option (tools/cli/render_args.c)", o->flag);
        if (args_at[o->id] ? table_option(o->id, v, a) : parsers[o->id](v, a))
            return tpk_cli_fail(cmd, "%s expects %s, found '%s'", o->flag, o->expects, v ? v : "");
    } else if (arg[0] == '-' && arg[1]) {
        return tpk_cli_fail(cmd, "unknown option '%s' (see tetpack %s --help)", arg, cmd);
    } else if (!a->path) {
        a->path = arg;
    } else {
        return tpk_cli_fail(cmd, "expected one FILE, found a second argument '%s'", arg);
    }
    return 0;
}

/* The rows with a flag in --help order. */
static int help_rows(const tpk_option_row *rows[TPK_OPT_COUNT])
{
    int n = 0;
    for (int rank = 1; rank <= TPK_OPT_COUNT; rank++)
        for (int k = 0; k < TPK_OPT_COUNT; k++)
            if (tpk_option_table[k].flag && tpk_option_table[k].help_rank == rank)
                rows[n++] = &tpk_option_table[k];
    return n;
}

void render_args_help(FILE *out)
{
    const tpk_option_row *rows[TPK_OPT_COUNT];
    int n = help_rows(rows);
    for (int k = 0; k < n; k++) {
        const tpk_option_row *o = rows[k];
        char left[128];
        snprintf(left, sizeof left, "%s%s%s%s%s", o->alias ? o->alias : "", o->alias ? ", " : "", o->flag,
                 o->metavar ? " " : "", o->metavar ? o->metavar : "");
        if (strlen(left) <= 28)
            fprintf(out, "  %-28s ", left);
        else
            fprintf(out, "  %s\n%31s", left, "");
        for (const char *line = o->help; *line;) {
            size_t len = strcspn(line, "\n");
            fprintf(out, "%.*s\n", (int)len, line);
            line += len;
            if (*line && *++line)
                fprintf(out, "%31s", "");
        }
        if (o->effect && (k + 1 == n || !rows[k + 1]->effect))
            fputs("Effect definitions: docs/ARCHITECTURE.md, \"Render effects\".\n", out);
    }
}

void render_args_view_list(FILE *out)
{
    const tpk_option_row *rows[TPK_OPT_COUNT];
    int n = help_rows(rows);
    const char *start = "Options: those of tetpack render that say what to show (";
    fputs(start, out);
    size_t column = strlen(start);
    int first = 1;
    for (int k = 0; k < n; k++) {
        if (rows[k]->render_only)
            continue;
        int last = 1;
        for (int j = k + 1; j < n; j++)
            last = last && rows[j]->render_only;
        size_t len = strlen(rows[k]->flag) + 1; /* and its ',' or ')' */
        if (!first && column + 1 + len > 100) {
            fputs("\n", out);
            column = 0;
        } else if (!first) {
            fputs(" ", out);
            column++;
        }
        fprintf(out, "%s%s", rows[k]->flag, last ? ")" : ",");
        column += len;
        first = 0;
    }
    fputs(", and:\n", out);
}

tpk_layout render_args_layout(tpk_file *file, const char *name)
{
    if (name)
        return !strcmp(name, "tet16") ? TPK_LAYOUT_TET16 : !strcmp(name, "tet20") ? TPK_LAYOUT_TET20 : TPK_LAYOUT_TET32;
    uint64_t i;
    if (tpk_find_chunk(file, TPK_TAG_TT16, 0, 0, &i) == TPK_OK)
        return TPK_LAYOUT_TET16;
    if (tpk_find_chunk(file, TPK_TAG_TT20, 0, 0, &i) == TPK_OK)
        return TPK_LAYOUT_TET20;
    return TPK_LAYOUT_TET32;
}

/* The range of the field being rendered, from its descriptor (min and max over all steps, so frames
 * of a step range share one colour scale): the named field, or the first point field. */
void render_args_field_range(tpk_file *file, const char *name, double range[2])
{
    range[0] = 0.0;
    range[1] = 1.0;
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) != TPK_OK)
            continue;
        if (name ? strcmp(name, d.name) != 0 : d.association != TPK_ASSOC_POINT)
            continue;
        if (d.min_value < d.max_value) {
            range[0] = d.min_value;
            range[1] = d.max_value;
        }
        return;
    }
}

void render_args_to_options(const render_args *a, tpk_file *file, const tpk_transfer_function *tf,
                            tpk_render_options *opt)
{
    tpk_file_info info;
    tpk_get_info(file, &info);
    opt->width = a->width;
    opt->height = a->height;
    if (a->have_camera) {
        memcpy(opt->camera.eye, a->camera, sizeof opt->camera.eye);
        memcpy(opt->camera.at, a->camera + 3, sizeof opt->camera.at);
        memcpy(opt->camera.up, a->camera + 6, sizeof opt->camera.up);
        opt->camera.fovy_deg = a->camera[9];
    } else {
        tpk_camera_default(info.bounds_min, info.bounds_max, &opt->camera);
    }
    opt->tf = tf;
    double range[2] = {a->range[0], a->range[1]};
    if (!a->have_range)
        render_args_field_range(file, a->field, range);
    opt->range_min = range[0];
    opt->range_max = range[1];
    opt->iso_count = a->iso_count;
    memcpy(opt->iso, a->iso, sizeof opt->iso);
    opt->clip = a->clip;
    memcpy(opt->clip_min, a->clip_box, sizeof opt->clip_min);
    memcpy(opt->clip_max, a->clip_box + 3, sizeof opt->clip_max);
    opt->probe_count = a->probe_count;
    memcpy(opt->probes, a->probes, sizeof opt->probes);
    opt->have_light = a->have_light;
    memcpy(opt->light, a->light, sizeof opt->light);
#define TPK_OPTION(ID, name, kind, R, A, ...) TPK_IF(R, TPK_IF(A, opt->name = a->name;))
#include "render/render_options.def"
#undef TPK_OPTION
    opt->unit_distance = a->unit_distance > 0 ? a->unit_distance
                                              : render_args_default_unit(info.bounds_min, info.bounds_max);
}

double render_args_default_unit(const double bounds_min[3], const double bounds_max[3])
{
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (bounds_max[k] - bounds_min[k]) * (bounds_max[k] - bounds_min[k]);
    return isfinite(d2) && d2 > 0 ? sqrt(d2) / TPK_CLI_UNIT_DIVISOR : 0; /* 0: the renderer's fallback */
}

int render_args_field_desc(tpk_file *file, const char *name, tpk_field_desc *out)
{
    for (uint32_t i = 0; i < tpk_field_count(file); i++)
        if (tpk_get_field(file, i, out) == TPK_OK && (name ? !strcmp(name, out->name) : out->association == TPK_ASSOC_POINT))
            return 0;
    memset(out, 0, sizeof *out);
    return -1;
}

static int compare_floats(const void *x, const void *y)
{
    float a = *(const float *)x, b = *(const float *)y;
    return a < b ? -1 : a > b;
}

int render_args_iso_auto(const char *cmd, const render_args *a, tpk_file *file, tpk_render_options *opt,
                         double *value)
{
    tpk_field_desc d;
    if (render_args_field_desc(file, a->field, &d) != 0)
        return tpk_cli_fail(cmd, "%s: --iso auto needs a field, and this file has no point field", a->path);
    tpk_mesh_arrays mesh;
    const float *values = NULL;
    uint64_t count = 0;
    tpk_result r = tpk_load_arrays(file, render_args_layout(file, a->layout),
                                   d.association == TPK_ASSOC_POINT ? d.name : NULL, (uint32_t)a->step, &mesh);
    if (r == TPK_OK && d.association == TPK_ASSOC_POINT)
        values = mesh.scalars, count = mesh.vertex_count;
    else if (r == TPK_OK)
        r = tpk_load_tet_field(file, d.name, (uint32_t)a->step, &values), count = mesh.tet_count;
    if (r != TPK_OK)
        return tpk_cli_fail_file(cmd, a->path, tpk_error_text(file));
    float *sorted = malloc((count ? count : 1) * sizeof *sorted);
    if (!sorted)
        return tpk_cli_fail(cmd, "out of memory for --iso auto over %llu values", (unsigned long long)count);
    size_t finite = 0;
    for (uint64_t i = 0; values && i < count; i++)
        if (isfinite(values[i]))
            sorted[finite++] = values[i];
    qsort(sorted, finite, sizeof *sorted, compare_floats);
    double median = finite ? (finite % 2 ? sorted[finite / 2] : 0.5 * ((double)sorted[finite / 2 - 1] + sorted[finite / 2])) : 0;
    free(sorted);
    if (!finite)
        return tpk_cli_fail(cmd, "%s: --iso auto: field '%s' has no finite value at step %d", a->path, d.name, a->step);
    opt->iso_count = 1;
    opt->iso[0] = median;
    *value = median;
    return 0;
}

/* The association of the named field (-1 when there is none), or a usage error naming the fields the
 * file has. */
int render_args_check_field(const char *cmd, const render_args *a, tpk_file *file, int *association)
{
    *association = TPK_ASSOC_POINT;
    if (!a->field)
        return 0;
    char names[512] = "";
    size_t used = 0;
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) != TPK_OK)
            continue;
        if (!strcmp(d.name, a->field)) {
            *association = (int)d.association;
            return 0;
        }
        if (used + strlen(d.name) + 3 < sizeof names)
            used += (size_t)snprintf(names + used, sizeof names - used, "%s%s", used ? ", " : "", d.name);
    }
    return tpk_cli_fail(cmd, "%s: no field named '%s' (this file has %s%s)", a->path, a->field,
                        used ? "fields: " : "no fields", names);
}

/* The steps of the field rendered (the named one, or the first point field; 1 without a field), so a
 * step range past them is refused before any frame is written. */
uint32_t render_args_field_steps(tpk_file *file, const char *name, char found[80])
{
    snprintf(found, 80, "(no field)");
    for (uint32_t i = 0; i < tpk_field_count(file); i++) {
        tpk_field_desc d;
        if (tpk_get_field(file, i, &d) == TPK_OK && (name ? !strcmp(name, d.name) : d.association == TPK_ASSOC_POINT)) {
            snprintf(found, 80, "field '%s'", d.name);
            return d.step_count;
        }
    }
    return 1;
}

/* Scene values first (--scene): they fill the arguments, and the options parsed after this override
 * them; render_args_to_options then turns both into render options in one place. */
int render_args_merge_scene(const char *cmd, int argc, char **argv, render_args *a)
{
    for (int i = 1; i < argc; i++)
        if (!strncmp(argv[i], "--scene", 7) && (!argv[i][7] || argv[i][7] == '='))
            a->scene_path = tpk_cli_value(argc, argv, &i, "--scene");
    if (!a->scene_path)
        return 0;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    const tpk_scene *s = &a->scene;
    if (tpk_scene_load(a->scene_path, &a->scene, &diag) != 0)
        return tpk_cli_fail(cmd, "%s", diag.message);
    if (s->given & TPK_SCENE_BACKEND) { /* --backend, parsed after this, still overrides it */
        a->backend = s->backend == TPK_SCENE_BACKEND_VULKAN ? "vulkan" : "cpu";
        a->backend_from_scene = 1;
    }
    if (s->given & TPK_SCENE_SIZE)
        a->width = s->width, a->height = s->height;
    if (s->given & TPK_SCENE_CAMERA) {
        const tpk_camera *c = &s->camera;
        double v[10] = {c->eye[0], c->eye[1], c->eye[2], c->at[0], c->at[1], c->at[2], c->up[0], c->up[1], c->up[2],
                        c->fovy_deg};
        memcpy(a->camera, v, sizeof v);
        a->have_camera = 1;
    }
    if (s->given & TPK_SCENE_RANGE)
        a->range[0] = s->range[0], a->range[1] = s->range[1], a->have_range = 1;
    a->field = s->given & TPK_SCENE_FIELD ? s->field : NULL;
    a->step = s->step_first;
    a->step_last = s->step_last;
    a->have_steps = s->step_range;
    a->layout = !(s->given & TPK_SCENE_LAYOUT) ? NULL : s->layout == TPK_LAYOUT_TET16 ? "tet16"
                                               : s->layout == TPK_LAYOUT_TET20 ? "tet20" : "tet32";
    a->clip = (s->given & TPK_SCENE_CLIP) != 0;
    memcpy(a->clip_box, s->clip_min, sizeof s->clip_min);
    memcpy(a->clip_box + 3, s->clip_max, sizeof s->clip_max);
    a->probe_count = s->probe_count;
    memcpy(a->probes, s->probes, sizeof a->probes);
    a->iso_count = s->iso_count;
    memcpy(a->iso, s->iso, sizeof a->iso);
    a->have_light = (s->given & TPK_SCENE_LIGHT) != 0;
    memcpy(a->light, s->light, sizeof a->light);
#define TPK_OPTION(ID, name, kind, R, A, S, ...) TPK_IF(A, TPK_IF(S, a->name = s->name;))
#include "render/render_options.def"
#undef TPK_OPTION
    return 0;
}

/* The transfer function: --tf, else the scene's, else viridis. */
int render_args_load_tf(const char *cmd, const render_args *a, tpk_transfer_function *tf)
{
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (!a->tf && (a->scene.given & TPK_SCENE_TF))
        *tf = a->scene.tf;
    else if (tpk_tf_load(a->tf ? a->tf : "viridis", tf, &diag) != 0)
        return tpk_cli_fail(cmd, "%s", diag.message);
    return 0;
}

