/* Scene files into tpk_scene: cJSON parses, then every key is checked against the schema of
 * spec/scene-json.md (type, range, unknown and repeated keys), and every message names the file, the
 * line and column of the key (scene_locate.c finds them; cJSON keeps no positions) and the key. */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "option_table.h"
#include "scene.h"
#include "scene_internal.h"

#define SCENE_MAX_BYTES (1u << 20) /* a scene with the largest TF is a few tens of KiB */

typedef struct parser {
    const char *name, *text, *base_dir;
    tpk_scene *out;
    tpk_diag *diag;
} parser;

/* "NAME:LINE:COL: key 'PATH': WHY", at the key's `nth` occurrence (or, for a key that is missing, at its
 * parent). */
static int fail_at(parser *p, const char *path, int nth, const char *why)
{
    char where[512];
    snprintf(where, sizeof where, "%s", path);
    long offset = -1;
    while (offset < 0 && where[0]) {
        offset = tpk_scene_key_offset(p->text, where, strcmp(where, path) ? 0 : nth);
        char *dot = strrchr(where, '.');
        if (offset < 0)
            *(dot ? dot : where) = 0;
    }
    int line = 1, col = 1;
    if (offset >= 0)
        tpk_scene_line_col(p->text, (size_t)offset, &line, &col);
    return tpk_diag_fail(p->diag, "%s:%d:%d: key '%s': %s", p->name, line, col, path, why);
}

static int fail_key(parser *p, const char *path, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail_key(parser *p, const char *path, const char *fmt, ...)
{
    char why[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    return fail_at(p, path, 0, why);
}

/* The value as JSON, cut to fit a message. */
static const char *shown(const cJSON *v, char buf[64])
{
    char *json = cJSON_PrintUnformatted(v);
    if (!json)
        return "(a value)";
    size_t n = strlen(json);
    if (n > 40)
        snprintf(buf, 64, "%.36s ...", json);
    else
        snprintf(buf, 64, "%s", json);
    free(json);
    return buf;
}

static int number(parser *p, const cJSON *v, const char *path, const char *expected, double *out)
{
    char buf[64];
    if (cJSON_IsNumber(v) && !isfinite(v->valuedouble))
        return fail_key(p, path, "expected %s, found a number beyond the range of a double", expected);
    if (!cJSON_IsNumber(v))
        return fail_key(p, path, "expected %s, found %s", expected, shown(v, buf));
    *out = v->valuedouble;
    return 0;
}

/* An integer by its option's rule (option_table.c, the command line's too). */
static int integer(parser *p, const cJSON *v, const char *path, tpk_option_id id, int *out)
{
    char buf[64];
    const tpk_option_row *r = &tpk_option_table[id];
    if (!cJSON_IsNumber(v) || !tpk_option_int_ok(id, v->valuedouble))
        return fail_key(p, path, "expected an integer in %.0f..%.0f, found %s", r->lo, r->hi, shown(v, buf));
    *out = (int)v->valuedouble;
    return 0;
}

/* A number by its option's rule; `expected` says it in words. */
static int ruled_number(parser *p, const cJSON *v, const char *path, tpk_option_id id, const char *expected,
                        double *out)
{
    if (number(p, v, path, expected, out))
        return -1;
    if (!tpk_option_number_ok(id, *out))
        return fail_key(p, path, "expected %s, found %g", expected, *out);
    return 0;
}

/* An array of exactly n finite numbers. */
static int numbers(parser *p, const cJSON *v, const char *path, int n, const char *expected, double *out)
{
    char buf[64];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n)
        return fail_key(p, path, "expected %s, found %s", expected, shown(v, buf));
    int k = 0;
    for (const cJSON *e = v->child; e; e = e->next, k++) {
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
            return fail_key(p, path, "expected %s, found %s (element %d is not a finite number)", expected,
                            shown(v, buf), k);
        out[k] = e->valuedouble;
    }
    return 0;
}

static int boolean(parser *p, const cJSON *v, const char *path, int *out)
{
    char buf[64];
    if (!cJSON_IsBool(v))
        return fail_key(p, path, "expected true or false, found %s", shown(v, buf));
    *out = cJSON_IsTrue(v);
    return 0;
}

/* One of its option's choices (option_table.c, the command line's too); *out is its index. */
static int choice(parser *p, const cJSON *v, const char *path, tpk_option_id id, int *out)
{
    char list[128] = "", buf[64], name[32];
    if (cJSON_IsString(v) && (*out = tpk_option_choice(id, v->valuestring)) >= 0)
        return 0;
    int n = 0;
    while (tpk_option_choice_name(id, n, name, sizeof name)[0])
        n++;
    for (int i = 0; i < n; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s\"%s\"", i ? (i + 1 < n ? ", " : " or ") : "",
                 tpk_option_choice_name(id, i, name, sizeof name));
    return fail_key(p, path, "expected %s, found %s", list, shown(v, buf));
}

/* ---- keys of an object: known, not repeated, with a suggestion for a typo ---------------------------- */

static int edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la > 31 || lb > 31)
        return 99;
    int row[32];
    for (size_t j = 0; j <= lb; j++)
        row[j] = (int)j;
    for (size_t i = 1; i <= la; i++) {
        int diag = row[0];
        row[0] = (int)i;
        for (size_t j = 1; j <= lb; j++) {
            int up = row[j], best = diag + (a[i - 1] != b[j - 1]);
            best = up + 1 < best ? up + 1 : best;
            best = row[j - 1] + 1 < best ? row[j - 1] + 1 : best;
            diag = up;
            row[j] = best;
        }
    }
    return row[lb];
}

static int check_keys(parser *p, const cJSON *obj, const char *path, const char *const *known, int n)
{
    for (const cJSON *e = obj->child; e; e = e->next) {
        char key_path[256];
        snprintf(key_path, sizeof key_path, "%s%s%s", path, path[0] ? "." : "", e->string);
        int found = 0, near = -1;
        for (int i = 0; i < n && !found; i++) {
            found = !strcmp(e->string, known[i]);
            if (!found && near < 0 && edit_distance(e->string, known[i]) <= 2)
                near = i;
        }
        if (!found) {
            char list[512] = "";
            for (int i = 0; i < n; i++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", known[i]);
            if (near >= 0)
                return fail_key(p, key_path, "unknown key (did you mean '%s'?); known keys%s%s: %s", known[near],
                                path[0] ? " of " : "", path, list);
            return fail_key(p, key_path, "unknown key; known keys%s%s: %s", path[0] ? " of " : "", path, list);
        }
        for (const cJSON *f = obj->child; f != e; f = f->next)
            if (!strcmp(f->string, e->string))
                return fail_at(p, key_path, 1, "appears twice in the same object (remove one)"); /* at the second */
    }
    return 0;
}

static int need_object(parser *p, const cJSON *v, const char *path, const char *expected)
{
    char buf[64];
    if (!cJSON_IsObject(v))
        return fail_key(p, path, "expected %s, found %s", expected, shown(v, buf));
    return 0;
}

/* ---- the keys ---------------------------------------------------------------------------------------- */

static int key_version(parser *p, const cJSON *v)
{
    char buf[64];
    if (!cJSON_IsNumber(v) || v->valuedouble != TPK_SCENE_VERSION)
        return fail_key(p, "tetpack_scene", "expected %d (the scene format this tetpack reads), found %s",
                        TPK_SCENE_VERSION, shown(v, buf));
    return 0;
}

static int key_camera(parser *p, const cJSON *v)
{
    const char *keys[4]; /* eye, at, up, fovy */
    tpk_camera *c = &p->out->camera;
    if (need_object(p, v, "camera", "an object {\"eye\", \"at\", \"up\", \"fovy\"}") ||
        check_keys(p, v, "camera", keys, tpk_option_scene_keys("camera", keys, 4)))
        return -1;
    double *dst[3] = {c->eye, c->at, c->up};
    for (int k = 0; k < 3; k++) {
        char path[32];
        snprintf(path, sizeof path, "camera.%s", keys[k]);
        const cJSON *e = cJSON_GetObjectItemCaseSensitive(v, keys[k]);
        if (!e)
            return fail_key(p, path, "missing: a camera gives eye, at, up and fovy");
        if (numbers(p, e, path, 3, "[x, y, z]", dst[k]))
            return -1;
    }
    const cJSON *fovy = cJSON_GetObjectItemCaseSensitive(v, "fovy");
    if (!fovy)
        return fail_key(p, "camera.fovy", "missing: a camera gives eye, at, up and fovy");
    if (ruled_number(p, fovy, "camera.fovy", TPK_OPT_CAMERA_FOVY, "a number of degrees in (0, 180)", &c->fovy_deg))
        return -1;
    double d[3] = {c->at[0] - c->eye[0], c->at[1] - c->eye[1], c->at[2] - c->eye[2]};
    if (d[0] == 0 && d[1] == 0 && d[2] == 0)
        return fail_key(p, "camera.at", "equals camera.eye: the camera looks nowhere");
    double x[3] = {d[1] * c->up[2] - d[2] * c->up[1], d[2] * c->up[0] - d[0] * c->up[2], d[0] * c->up[1] - d[1] * c->up[0]};
    if (x[0] == 0 && x[1] == 0 && x[2] == 0)
        return fail_key(p, "camera.up", "is zero or parallel to the view direction (at - eye)");
    return 0;
}

static int tf_points(parser *p, const cJSON *v)
{
    tpk_transfer_function *tf = &p->out->tf;
    char buf[64];
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 0;
    if (n < 2 || n > TPK_TF_MAX_POINTS)
        return fail_key(p, "tf.points", "expected an array of 2..%d control points [s, r, g, b, a], found %s",
                        TPK_TF_MAX_POINTS, shown(v, buf));
    tf->count = 0;
    for (const cJSON *e = v->child; e; e = e->next) {
        double q[5];
        if (numbers(p, e, "tf.points", 5, "control points [s, r, g, b, a] of numbers in [0, 1]", q))
            return -1;
        for (int k = 0; k < 5; k++)
            if (!(q[k] >= 0 && q[k] <= 1))
                return fail_key(p, "tf.points", "point %d: every number of [s, r, g, b, a] must be in [0, 1], "
                                "found %s", tf->count, shown(e, buf));
        if (tf->count > 0 && !(q[0] > tf->points[tf->count - 1].s))
            return fail_key(p, "tf.points", "point %d: s must increase strictly, found %g after %g", tf->count, q[0],
                            tf->points[tf->count - 1].s);
        tf->points[tf->count++] = (tpk_tf_point){q[0], q[1], q[2], q[3], q[4]};
    }
    snprintf(tf->name, sizeof tf->name, "%s", "inline");
    return 0;
}

static int tf_file(parser *p, const cJSON *v)
{
    char buf[64];
    if (!cJSON_IsString(v) || !v->valuestring[0])
        return fail_key(p, "tf.file", "expected a file name, found %s", shown(v, buf));
    const char *name = v->valuestring;
    int relative = name[0] != '/' && p->base_dir && p->base_dir[0];
    int n = snprintf(p->out->tf_source, sizeof p->out->tf_source, "%s%s%s", relative ? p->base_dir : "",
                     relative ? "/" : "", name);
    if (n < 0 || (size_t)n >= sizeof p->out->tf_source)
        return fail_key(p, "tf.file", "the path is longer than %zu bytes", sizeof p->out->tf_source - 1);
    tpk_diag inner;
    memset(&inner, 0, sizeof inner);
    if (tpk_tf_load(p->out->tf_source, &p->out->tf, &inner) != 0)
        return fail_key(p, "tf.file", "%s", inner.message);
    return 0;
}

static int key_tf(parser *p, const cJSON *v)
{
    const char *keys[3]; /* preset, file, points */
    char buf[64];
    if (need_object(p, v, "tf", "an object with one of \"preset\", \"file\", \"points\"") ||
        check_keys(p, v, "tf", keys, tpk_option_scene_keys("tf", keys, 3)))
        return -1;
    if (cJSON_GetArraySize(v) != 1)
        return fail_key(p, "tf", "expected exactly one of \"preset\", \"file\", \"points\", found %s", shown(v, buf));
    const cJSON *e = v->child;
    if (!strcmp(e->string, tpk_option_scene_leaf(TPK_OPT_TF_PRESET))) {
        p->out->tf_kind = TPK_SCENE_TF_PRESET;
        if (!cJSON_IsString(e) || !tpk_tf_is_preset(e->valuestring))
            return fail_key(p, "tf.preset", "expected one of %s, found %s", tpk_tf_preset_names(), shown(e, buf));
        snprintf(p->out->tf_source, sizeof p->out->tf_source, "%s", e->valuestring);
        return tpk_tf_load(e->valuestring, &p->out->tf, p->diag);
    }
    if (!strcmp(e->string, tpk_option_scene_leaf(TPK_OPT_TF_FILE))) {
        p->out->tf_kind = TPK_SCENE_TF_FILE;
        return tf_file(p, e);
    }
    p->out->tf_kind = TPK_SCENE_TF_POINTS;
    return tf_points(p, e);
}

static int key_field(parser *p, const cJSON *v)
{
    char buf[64];
    if (!cJSON_IsString(v) || !v->valuestring[0] || strlen(v->valuestring) >= sizeof p->out->field)
        return fail_key(p, "field", "expected a field name (1..%zu bytes), found %s", sizeof p->out->field - 1,
                        shown(v, buf));
    snprintf(p->out->field, sizeof p->out->field, "%s", v->valuestring);
    return 0;
}

static int key_step(parser *p, const cJSON *v)
{
    if (integer(p, v, "step", TPK_OPT_STEP, &p->out->step_first))
        return -1;
    p->out->step_last = p->out->step_first;
    return 0;
}

static int key_steps(parser *p, const cJSON *v)
{
    double s[2];
    char buf[64];
    if (numbers(p, v, "steps", 2, "[first, last] steps", s))
        return -1;
    if (!tpk_option_int_ok(TPK_OPT_STEP, s[0]) || !tpk_option_int_ok(TPK_OPT_STEP, s[1]) || s[0] > s[1])
        return fail_key(p, "steps", "expected [first, last] with integers 0 <= first <= last <= %d, found %s",
                        1 << 30, shown(v, buf));
    p->out->step_first = (int)s[0];
    p->out->step_last = (int)s[1];
    p->out->step_range = 1;
    return 0;
}

static int key_range(parser *p, const cJSON *v)
{
    double *r = p->out->range;
    if (numbers(p, v, "range", 2, "[low, high] scalar values", r))
        return -1;
    if (!(r[0] < r[1]))
        return fail_key(p, "range", "expected low < high, found [%g, %g]", r[0], r[1]);
    return 0;
}

static int key_clip_box(parser *p, const cJSON *v)
{
    double b[6];
    if (numbers(p, v, "clip_box", 6, "[x0, y0, z0, x1, y1, z1]", b))
        return -1;
    for (int k = 0; k < 3; k++)
        if (!(b[k] <= b[k + 3])) /* the renderers' rule (tpk_render_check_options) and --clip-box's */
            return fail_key(p, "clip_box", "expected min <= max on every axis, found %g > %g on axis %c", b[k],
                            b[k + 3], "xyz"[k]);
    memcpy(p->out->clip_min, b, sizeof p->out->clip_min);
    memcpy(p->out->clip_max, b + 3, sizeof p->out->clip_max);
    return 0;
}

/* "probes": 1..TPK_RENDER_MAX_PROBES objects, each checked key by key and by tpk_probe_check. */
static int key_probes(parser *p, const cJSON *v)
{
    char buf[64];
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 0;
    if (n < 1 || n > TPK_RENDER_MAX_PROBES)
        return fail_key(p, "probes", "expected an array of 1 to %d probe objects, found %s", TPK_RENDER_MAX_PROBES,
                        shown(v, buf));
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, i++) {
        tpk_probe *q = &p->out->probes[i];
        memset(q, 0, sizeof *q);
        if (!cJSON_IsObject(e))
            return fail_key(p, "probes", "probe %d: expected an object, found %s", i + 1, shown(e, buf));
        const cJSON *shape = cJSON_GetObjectItemCaseSensitive(e, "shape");
        if (!cJSON_IsString(shape) || !(q->shape = tpk_probe_shape_of(shape->valuestring, strlen(shape->valuestring))))
            return fail_key(p, "probes", "probe %d: expected \"shape\": \"sphere\", \"plane\" or \"box\", found %s",
                            i + 1, shape ? shown(shape, buf) : "no shape");
        const char *ka = q->shape == TPK_PROBE_SPHERE ? "center" : q->shape == TPK_PROBE_PLANE ? "point" : "min";
        const char *kb = q->shape == TPK_PROBE_SPHERE ? "radius" : q->shape == TPK_PROBE_PLANE ? "normal" : "max";
        const char *known[] = {"shape", ka, kb, "mode"};
        for (const cJSON *f = e->child; f; f = f->next) {
            int k = 0;
            while (k < 4 && strcmp(f->string, known[k]))
                k++;
            if (k == 4)
                return fail_key(p, "probes", "probe %d (%s): unknown key '%s'; known keys: shape, %s, %s, mode", i + 1,
                                shape->valuestring, f->string, ka, kb);
            for (const cJSON *g = e->child; g != f; g = g->next)
                if (!strcmp(g->string, f->string))
                    return fail_key(p, "probes", "probe %d: key '%s' appears twice", i + 1, f->string);
        }
        const cJSON *a = cJSON_GetObjectItemCaseSensitive(e, ka), *b = cJSON_GetObjectItemCaseSensitive(e, kb);
        const cJSON *mode = cJSON_GetObjectItemCaseSensitive(e, "mode");
        if (!a || !b)
            return fail_key(p, "probes", "probe %d (%s): expected keys %s and %s", i + 1, shape->valuestring, ka, kb);
        char what[64];
        snprintf(what, sizeof what, "probe %d's %s: [x, y, z]", i + 1, ka);
        if (numbers(p, a, "probes", 3, what, q->a))
            return -1;
        snprintf(what, sizeof what, "probe %d's %s: %s", i + 1, kb, q->shape == TPK_PROBE_SPHERE ? "a number" : "[x, y, z]");
        if (q->shape == TPK_PROBE_SPHERE ? number(p, b, "probes", what, &q->radius) : numbers(p, b, "probes", 3, what, q->b))
            return -1;
        if (mode && !(cJSON_IsString(mode) && (!strcmp(mode->valuestring, "keep") || !strcmp(mode->valuestring, "cut"))))
            return fail_key(p, "probes", "probe %d: expected \"mode\": \"keep\" or \"cut\", found %s", i + 1,
                            shown(mode, buf));
        q->cut = mode && !strcmp(mode->valuestring, "cut");
        tpk_diag d = {0};
        if (tpk_probe_check(q, i + 1, &d) != 0) /* the renderers' rule, and --probe's */
            return fail_key(p, "probes", "%s", d.message + strlen("render: "));
    }
    p->out->probe_count = n;
    return 0;
}

static int key_iso(parser *p, const cJSON *v)
{
    char buf[64];
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 0;
    if (n < 1 || n > TPK_RENDER_MAX_ISO)
        return fail_key(p, "iso", "expected an array of 1..%d iso values, found %s", TPK_RENDER_MAX_ISO, shown(v, buf));
    p->out->iso_count = n;
    return numbers(p, v, "iso", n, "an array of finite iso values", p->out->iso);
}

/* A key of a row of the table that is a field of tpk_scene (in_scene): read by its kind and rule. */
static int table_value(parser *p, const cJSON *v, tpk_option_id id)
{
    const tpk_option_row *r = &tpk_option_table[id];
    char *field = (char *)p->out + r->scene_at;
    switch (r->kind) {
    case TPK_OPT_KIND_INT:
        return integer(p, v, r->scene_key, id, (int *)field);
    case TPK_OPT_KIND_NUMBER:
        return ruled_number(p, v, r->scene_key, id, r->scene_expects, (double *)field);
    case TPK_OPT_KIND_BOOL:
        return boolean(p, v, r->scene_key, (int *)field);
    case TPK_OPT_KIND_CHOICE: /* the index of the choice: the order of the values (TPK_INTEGRATION_*, ...) */
        return choice(p, v, r->scene_key, id, (int *)field);
    default:
        return fail_key(p, r->scene_key, "no reader for this key (tools/scene/scene_parse.c)");
    }
}

/* The keys of "effects", by their rows of the option table. */
static const cJSON *effect(const cJSON *effects, tpk_option_id id)
{
    return cJSON_GetObjectItemCaseSensitive(effects, tpk_option_scene_leaf(id));
}

/* "effects": the table's rows (table_value), and the light. */
static int key_effects(parser *p, const cJSON *v)
{
    const char *keys[TPK_OPT_COUNT];
    if (need_object(p, v, "effects", "an object of effects") ||
        check_keys(p, v, "effects", keys, tpk_option_scene_keys("effects", keys, TPK_OPT_COUNT)))
        return -1;
    int rc = 0;
    for (int i = 0; i < TPK_OPT_COUNT && !rc; i++) {
        const char *key = tpk_option_table[i].scene_key;
        const cJSON *e = key && !strncmp(key, "effects.", 8) ? effect(v, (tpk_option_id)i) : NULL;
        if (!e)
            continue;
        if (tpk_option_table[i].in_scene)
            rc = table_value(p, e, (tpk_option_id)i);
        else if (i == TPK_OPT_LIGHT)
            rc = numbers(p, e, key, 3, "a point [x, y, z]", p->out->light);
        else
            rc = fail_key(p, key, "no reader for this key (tools/scene/scene_parse.c)");
        if (!rc)
            p->out->given |= TPK_SCENE_GIVEN(i);
    }
    return rc;
}

static int key_layout(parser *p, const cJSON *v)
{
    static const tpk_layout layouts[] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32}; /* the choices' order */
    int i;
    if (choice(p, v, "layout", TPK_OPT_LAYOUT, &i))
        return -1;
    p->out->layout = layouts[i];
    return 0;
}

static int key_size(parser *p, const cJSON *v)
{
    double s[2];
    char buf[64];
    if (numbers(p, v, "size", 2, "[width, height] in pixels", s))
        return -1;
    if (s[0] != floor(s[0]) || s[1] != floor(s[1]) || s[0] < 1 || s[1] < 1 || s[0] > 16384 || s[1] > 16384)
        return fail_key(p, "size", "expected [width, height] with integers in 1..16384, found %s", shown(v, buf));
    p->out->width = (int)s[0];
    p->out->height = (int)s[1];
    return 0;
}

static int key_backend(parser *p, const cJSON *v)
{
    int i;
    if (choice(p, v, "backend", TPK_OPT_BACKEND, &i)) /* cpu, vulkan */
        return -1;
    p->out->backend = i == 0 ? TPK_SCENE_BACKEND_CPU : TPK_SCENE_BACKEND_VULKAN;
    return 0;
}

typedef int (*key_fn)(parser *p, const cJSON *v);

/* The parser of each top-level key of the option table that is not a field of tpk_scene (those are read
 * by table_value), and the TPK_SCENE_* bit it sets (0: none of its own; effects sets one per effect). */
static const struct {
    key_fn parse;
    uint64_t bit;
} top_keys[TPK_OPT_COUNT] = {
    [TPK_OPT_VERSION] = {key_version, 0},
    [TPK_OPT_CAMERA] = {key_camera, TPK_SCENE_CAMERA},
    [TPK_OPT_TF] = {key_tf, TPK_SCENE_TF},
    [TPK_OPT_FIELD] = {key_field, TPK_SCENE_FIELD},
    [TPK_OPT_STEP] = {key_step, TPK_SCENE_STEP},
    [TPK_OPT_STEPS] = {key_steps, TPK_SCENE_STEP},
    [TPK_OPT_RANGE] = {key_range, TPK_SCENE_RANGE},
    [TPK_OPT_CLIP_BOX] = {key_clip_box, TPK_SCENE_CLIP},
    [TPK_OPT_PROBE] = {key_probes, TPK_SCENE_PROBES},
    [TPK_OPT_ISO] = {key_iso, TPK_SCENE_ISO},
    [TPK_OPT_EFFECTS] = {key_effects, 0},
    [TPK_OPT_LAYOUT] = {key_layout, TPK_SCENE_LAYOUT},
    [TPK_OPT_SIZE] = {key_size, TPK_SCENE_SIZE},
    [TPK_OPT_BACKEND] = {key_backend, TPK_SCENE_BACKEND},
};

static int parse_root(parser *p, const cJSON *root)
{
    const char *names[TPK_OPT_COUNT];
    int count = tpk_option_scene_keys("", names, TPK_OPT_COUNT);
    char buf[64];
    if (!cJSON_IsObject(root))
        return tpk_diag_fail(p->diag, "%s:1:1: expected a JSON object at the top of a scene, found %s", p->name,
                             shown(root, buf));
    if (check_keys(p, root, "", names, count))
        return -1;
    if (cJSON_GetObjectItemCaseSensitive(root, "step") && cJSON_GetObjectItemCaseSensitive(root, "steps"))
        return fail_key(p, "steps", "a scene gives either 'step' (one) or 'steps' (a range), not both");
    for (int i = 0; i < TPK_OPT_COUNT; i++) {
        const char *key = tpk_option_table[i].scene_key;
        const cJSON *v = key && !strchr(key, '.') ? cJSON_GetObjectItemCaseSensitive(root, key) : NULL;
        if (!v)
            continue;
        if (tpk_option_table[i].in_scene) {
            if (table_value(p, v, (tpk_option_id)i) != 0)
                return -1;
            p->out->given |= TPK_SCENE_GIVEN(i);
            continue;
        }
        if (!top_keys[i].parse) /* a key of the table this reader has no parser for: a bug, said as such */
            return fail_key(p, key, "no reader for this key (tools/scene/scene_parse.c)");
        if (top_keys[i].parse(p, v) != 0)
            return -1;
        p->out->given |= top_keys[i].bit;
    }
    return 0;
}

static int syntax_error(parser *p, size_t offset)
{
    int line, col;
    tpk_scene_line_col(p->text, offset, &line, &col);
    char key[256], near[24];
    tpk_scene_key_at(p->text, offset, key, sizeof key);
    size_t n = 0;
    for (const char *s = p->text + offset; *s && *s != '\n' && n < 16; s++)
        near[n++] = *s;
    near[n] = 0;
    if (!p->text[offset])
        return tpk_diag_fail(p->diag, "%s:%d:%d: JSON syntax error%s%s%s: the text ends too early", p->name, line, col,
                             key[0] ? " in key '" : "", key, key[0] ? "'" : "");
    return tpk_diag_fail(p->diag, "%s:%d:%d: JSON syntax error%s%s%s at '%s'", p->name, line, col,
                         key[0] ? " in key '" : "", key, key[0] ? "'" : "", near);
}

int tpk_scene_parse(const char *name, const char *text, const char *base_dir, tpk_scene *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    parser p = {name, text, base_dir, out, diag};
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    if (!root)
        return syntax_error(&p, end && end >= text ? (size_t)(end - text) : 0);
    int rc = parse_root(&p, root);
    cJSON_Delete(root);
    if (rc != 0)
        memset(out, 0, sizeof *out);
    return rc;
}

/* The whole file as a NUL-terminated string; NUL bytes inside are refused (cJSON would stop there). */
static char *read_text(const char *path, tpk_diag *diag)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        tpk_diag_fail(diag, "%s: cannot open the scene file: %s", path, strerror(errno));
        return NULL;
    }
    char *text = malloc(SCENE_MAX_BYTES + 1);
    size_t n = text ? fread(text, 1, SCENE_MAX_BYTES + 1, f) : 0;
    int failed = text && ferror(f);
    fclose(f);
    if (!text || failed || n > SCENE_MAX_BYTES) {
        tpk_diag_fail(diag, !text ? "%s: out of memory" : failed ? "%s: read error" :
                      "%s: larger than %u bytes, too large for a scene file", path, SCENE_MAX_BYTES);
        free(text);
        return NULL;
    }
    text[n] = 0;
    if (strlen(text) != n) {
        int line, col;
        tpk_scene_line_col(text, strlen(text), &line, &col);
        tpk_diag_fail(diag, "%s:%d:%d: a NUL byte: a scene file is UTF-8 JSON text", path, line, col);
        free(text);
        return NULL;
    }
    return text;
}

int tpk_scene_load(const char *path, tpk_scene *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    char *text = read_text(path, diag);
    if (!text)
        return -1;
    char dir[1024] = ".";
    const char *slash = strrchr(path, '/');
    if (slash && (size_t)(slash - path) < sizeof dir)
        snprintf(dir, sizeof dir, "%.*s", slash == path ? 1 : (int)(slash - path), path);
    int rc = tpk_scene_parse(path, text, slash ? dir : NULL, out, diag);
    free(text);
    return rc;
}
