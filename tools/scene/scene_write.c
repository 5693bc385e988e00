/* tpk_scene back to JSON (cJSON builds and prints it) and to a file, atomically. Only the keys the
 * scene gives are written. */
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/output_file.h"
#include "option_table.h"
#include "scene.h"

#define KEY(id) tpk_option_scene_leaf(id) /* key names from the option table */

/* A number in the shortest form that reads back exactly. cJSON's own printer accepts a 15-digit form
 * that is only within an epsilon (0.30000000000000004 comes out as 0.3), so the text is made here. */
static cJSON *exact_number(double v)
{
    char text[40];
    for (int digits = 15; digits <= 17; digits++) {
        snprintf(text, sizeof text, "%.*g", digits, v);
        if (strtod(text, NULL) == v)
            break;
    }
    return cJSON_CreateRaw(text);
}

/* The value's name among its option's choices (option_table.c), as the scene reader takes it. */
static void add_choice(cJSON *obj, tpk_option_id id, int index)
{
    char name[32];
    cJSON_AddStringToObject(obj, tpk_option_scene_leaf(id), tpk_option_choice_name(id, index, name, sizeof name));
}

static void add_number(cJSON *obj, const char *key, double v)
{
    cJSON_AddItemToObject(obj, key, exact_number(v));
}

static void add_numbers(cJSON *obj, const char *key, const double *v, int n)
{
    cJSON *a = cJSON_AddArrayToObject(obj, key);
    for (int k = 0; a && k < n; k++)
        cJSON_AddItemToArray(a, exact_number(v[k]));
}

static void add_camera(cJSON *root, const tpk_camera *c)
{
    cJSON *cam = cJSON_AddObjectToObject(root, KEY(TPK_OPT_CAMERA));
    if (!cam)
        return;
    add_numbers(cam, KEY(TPK_OPT_CAMERA_EYE), c->eye, 3);
    add_numbers(cam, KEY(TPK_OPT_CAMERA_AT), c->at, 3);
    add_numbers(cam, KEY(TPK_OPT_CAMERA_UP), c->up, 3);
    add_number(cam, KEY(TPK_OPT_CAMERA_FOVY), c->fovy_deg);
}

/* A preset by name; a TF from a file or inline as its points, so the scene needs no other file. */
static void add_tf(cJSON *root, const tpk_scene *s)
{
    cJSON *tf = cJSON_AddObjectToObject(root, KEY(TPK_OPT_TF));
    if (!tf)
        return;
    if (s->tf_kind == TPK_SCENE_TF_PRESET) {
        cJSON_AddStringToObject(tf, KEY(TPK_OPT_TF_PRESET), s->tf_source);
        return;
    }
    cJSON *points = cJSON_AddArrayToObject(tf, KEY(TPK_OPT_TF_POINTS));
    for (int i = 0; points && i < s->tf.count; i++) {
        const tpk_tf_point *q = &s->tf.points[i];
        double row[5] = {q->s, q->r, q->g, q->b, q->a};
        cJSON *a = cJSON_CreateArray();
        for (int k = 0; a && k < 5; k++)
            cJSON_AddItemToArray(a, exact_number(row[k]));
        cJSON_AddItemToArray(points, a);
    }
}

/* A row of the table that is a field of tpk_scene (in_scene), by its kind. */
static void add_table_value(cJSON *obj, const tpk_scene *s, tpk_option_id id)
{
    const tpk_option_row *r = &tpk_option_table[id];
    const char *field = (const char *)s + r->scene_at;
    switch (r->kind) {
    case TPK_OPT_KIND_NUMBER:
        add_number(obj, KEY(id), *(const double *)field);
        break;
    case TPK_OPT_KIND_INT:
        cJSON_AddNumberToObject(obj, KEY(id), *(const int *)field);
        break;
    case TPK_OPT_KIND_BOOL:
        cJSON_AddBoolToObject(obj, KEY(id), *(const int *)field);
        break;
    case TPK_OPT_KIND_CHOICE: /* the index of the choice (TPK_INTEGRATION_*, TPK_OCCLUSION_* order) */
        add_choice(obj, id, *(const int *)field);
        break;
    default:
        break;
    }
}

/* The rows of "effects" (keys "effects.*"), in the table's order. */
static int is_effect(int id)
{
    const char *key = tpk_option_table[id].scene_key;
    return key && !strncmp(key, "effects.", 8);
}

static int any_effect(const tpk_scene *s)
{
    for (int i = 0; i < TPK_OPT_COUNT; i++)
        if (is_effect(i) && (s->given & TPK_SCENE_GIVEN(i)))
            return 1;
    return 0;
}

static void add_effects(cJSON *root, const tpk_scene *s)
{
    cJSON *fx = any_effect(s) ? cJSON_AddObjectToObject(root, KEY(TPK_OPT_EFFECTS)) : NULL;
    for (int i = 0; fx && i < TPK_OPT_COUNT; i++) {
        if (!is_effect(i) || !(s->given & TPK_SCENE_GIVEN(i)))
            continue;
        if (tpk_option_table[i].in_scene)
            add_table_value(fx, s, (tpk_option_id)i);
        else if (i == TPK_OPT_LIGHT)
            add_numbers(fx, KEY(TPK_OPT_LIGHT), s->light, 3);
    }
}

/* The layout's place among the table's choices (tet16, tet20, tet32). */
static int layout_index(tpk_layout layout)
{
    return layout == TPK_LAYOUT_TET16 ? 0 : layout == TPK_LAYOUT_TET20 ? 1 : 2;
}

static void add_probes(cJSON *root, const tpk_scene *s)
{
    cJSON *list = cJSON_AddArrayToObject(root, KEY(TPK_OPT_PROBE));
    for (int i = 0; list && i < s->probe_count; i++) {
        const tpk_probe *q = &s->probes[i];
        cJSON *o = cJSON_CreateObject();
        if (!o || !cJSON_AddItemToArray(list, o)) {
            cJSON_Delete(o);
            break;
        }
        cJSON_AddStringToObject(o, "shape", tpk_probe_shape_name(q->shape));
        add_numbers(o, q->shape == TPK_PROBE_SPHERE ? "center" : q->shape == TPK_PROBE_PLANE ? "point" : "min", q->a,
                    3);
        if (q->shape == TPK_PROBE_SPHERE)
            add_number(o, "radius", q->radius);
        else
            add_numbers(o, q->shape == TPK_PROBE_PLANE ? "normal" : "max", q->b, 3);
        cJSON_AddStringToObject(o, "mode", q->cut ? "cut" : "keep");
    }
}

/* A top-level key that is not a field of tpk_scene, given in s. */
static void add_key(cJSON *root, const tpk_scene *s, tpk_option_id id)
{
    double steps[2] = {s->step_first, s->step_last}, size[2] = {s->width, s->height};
    double box[6] = {s->clip_min[0], s->clip_min[1], s->clip_min[2], s->clip_max[0], s->clip_max[1], s->clip_max[2]};
    switch (id) {
    case TPK_OPT_CAMERA:
        add_camera(root, &s->camera);
        break;
    case TPK_OPT_TF:
        add_tf(root, s);
        break;
    case TPK_OPT_FIELD:
        cJSON_AddStringToObject(root, KEY(id), s->field);
        break;
    case TPK_OPT_STEP: /* "step" or "steps", one bit */
        if (!s->step_range)
            cJSON_AddNumberToObject(root, KEY(id), s->step_first);
        else
            add_numbers(root, KEY(TPK_OPT_STEPS), steps, 2);
        break;
    case TPK_OPT_RANGE:
        add_numbers(root, KEY(id), s->range, 2);
        break;
    case TPK_OPT_CLIP_BOX:
        add_numbers(root, KEY(id), box, 6);
        break;
    case TPK_OPT_PROBE:
        add_probes(root, s);
        break;
    case TPK_OPT_ISO:
        add_numbers(root, KEY(id), s->iso, s->iso_count);
        break;
    case TPK_OPT_LAYOUT:
        add_choice(root, id, layout_index(s->layout));
        break;
    case TPK_OPT_SIZE:
        add_numbers(root, KEY(id), size, 2);
        break;
    case TPK_OPT_BACKEND:
        add_choice(root, id, s->backend == TPK_SCENE_BACKEND_VULKAN ? 1 : 0); /* cpu, vulkan */
        break;
    default:
        break;
    }
}

/* The top-level rows of the table, in its order: the version, then each key the scene gives. */
static int add_keys(cJSON *root, const tpk_scene *s)
{
    int keys = 0;
    for (int i = 0; i < TPK_OPT_COUNT; i++) {
        const char *key = tpk_option_table[i].scene_key;
        if (!key || strchr(key, '.') || i == TPK_OPT_STEPS)
            continue;
        if (i == TPK_OPT_VERSION)
            cJSON_AddNumberToObject(root, key, TPK_SCENE_VERSION), keys++;
        else if (i == TPK_OPT_EFFECTS)
            add_effects(root, s), keys += any_effect(s);
        else if (!(s->given & TPK_SCENE_GIVEN(i)))
            continue;
        else if (tpk_option_table[i].in_scene)
            add_table_value(root, s, (tpk_option_id)i), keys++;
        else
            add_key(root, s, (tpk_option_id)i), keys++;
    }
    return keys;
}

char *tpk_scene_to_json(const tpk_scene *s)
{
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return NULL;
    int keys = add_keys(root, s);
    /* cJSON adds nothing after a failed allocation, so a short tree would print silently: count the
     * keys that should be there, and parse the text back. */
    char *text = cJSON_Print(root);
    cJSON *back = text ? cJSON_Parse(text) : NULL;
    int same = back && cJSON_GetArraySize(back) == cJSON_GetArraySize(root) && cJSON_GetArraySize(root) == keys;
    cJSON_Delete(back);
    cJSON_Delete(root);
    if (!same) {
        free(text);
        return NULL;
    }
    return text;
}
int tpk_scene_write(const char *path, const tpk_scene *scene, tpk_diag *diag)
{
    char *text = tpk_scene_to_json(scene);
    if (!text)
        return tpk_diag_fail(diag, "%s: out of memory for the scene text", path);
    tpk_output out;
    int rc = tpk_output_open(&out, path, diag);
    FILE *f = rc == 0 ? tpk_output_stream(&out, diag) : NULL;
    if (rc == 0 && !f)
        rc = -1;
    if (rc == 0 && (fputs(text, f) < 0 || fputc('\n', f) == EOF))
        rc = tpk_diag_fail(diag, "%s: write error", path);
    if (rc == 0)
        rc = tpk_output_commit(&out, diag);
    else
        tpk_output_abort(&out); /* safe after a failed open too */
    free(text);
    return rc;
}
