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
/* The keys of "effects". */
#define EFFECT_BITS                                                                                            \
    (TPK_SCENE_SHADING | TPK_SCENE_SHADOWS | TPK_SCENE_LIGHT | TPK_SCENE_AO_RAYS | TPK_SCENE_AO_RADIUS |        \
     TPK_SCENE_OCCLUSION)

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

static void add_effects(cJSON *root, const tpk_scene *s)
{
    if (!(s->given & EFFECT_BITS))
        return;
    cJSON *fx = cJSON_AddObjectToObject(root, KEY(TPK_OPT_EFFECTS));
    if (!fx)
        return;
    if (s->given & TPK_SCENE_SHADING)
        cJSON_AddBoolToObject(fx, KEY(TPK_OPT_SHADING), s->shading);
    if (s->given & TPK_SCENE_SHADOWS)
        cJSON_AddBoolToObject(fx, KEY(TPK_OPT_SHADOWS), s->shadows);
    if (s->given & TPK_SCENE_LIGHT)
        add_numbers(fx, KEY(TPK_OPT_LIGHT), s->light, 3);
    if (s->given & TPK_SCENE_AO_RAYS)
        cJSON_AddNumberToObject(fx, KEY(TPK_OPT_AO_RAYS), s->ao_rays);
    if (s->given & TPK_SCENE_AO_RADIUS)
        add_number(fx, KEY(TPK_OPT_AO_RADIUS), s->ao_radius);
    if (s->given & TPK_SCENE_OCCLUSION)
        add_choice(fx, TPK_OPT_OCCLUSION, s->occlusion); /* TPK_OCCLUSION_* order */
}

/* The layout's place among the table's choices (tet16, tet20, tet32). */
static int layout_index(tpk_layout layout)
{
    return layout == TPK_LAYOUT_TET16 ? 0 : layout == TPK_LAYOUT_TET20 ? 1 : 2;
}

static void add_selection(cJSON *root, const tpk_scene *s)
{
    if (s->given & TPK_SCENE_FIELD)
        cJSON_AddStringToObject(root, KEY(TPK_OPT_FIELD), s->field);
    if ((s->given & TPK_SCENE_STEP) && !s->step_range)
        cJSON_AddNumberToObject(root, KEY(TPK_OPT_STEP), s->step_first);
    if ((s->given & TPK_SCENE_STEP) && s->step_range) {
        double steps[2] = {s->step_first, s->step_last};
        add_numbers(root, KEY(TPK_OPT_STEPS), steps, 2);
    }
    if (s->given & TPK_SCENE_RANGE)
        add_numbers(root, KEY(TPK_OPT_RANGE), s->range, 2);
    if (s->given & TPK_SCENE_UNIT_DISTANCE)
        add_number(root, KEY(TPK_OPT_UNIT_DISTANCE), s->unit_distance);
    if (s->given & TPK_SCENE_CLIP) {
        double box[6] = {s->clip_min[0], s->clip_min[1], s->clip_min[2], s->clip_max[0], s->clip_max[1], s->clip_max[2]};
        add_numbers(root, KEY(TPK_OPT_CLIP_BOX), box, 6);
    }
    if (s->given & TPK_SCENE_PROBES) {
        cJSON *list = cJSON_AddArrayToObject(root, KEY(TPK_OPT_PROBE));
        for (int i = 0; list && i < s->probe_count; i++) {
            const tpk_probe *q = &s->probes[i];
            cJSON *o = cJSON_CreateObject();
            if (!o || !cJSON_AddItemToArray(list, o)) {
                cJSON_Delete(o);
                break;
            }
            cJSON_AddStringToObject(o, "shape", tpk_probe_shape_name(q->shape));
            add_numbers(o, q->shape == TPK_PROBE_SPHERE ? "center" : q->shape == TPK_PROBE_PLANE ? "point" : "min",
                        q->a, 3);
            if (q->shape == TPK_PROBE_SPHERE)
                add_number(o, "radius", q->radius);
            else
                add_numbers(o, q->shape == TPK_PROBE_PLANE ? "normal" : "max", q->b, 3);
            cJSON_AddStringToObject(o, "mode", q->cut ? "cut" : "keep");
        }
    }
    if (s->given & TPK_SCENE_ISO)
        add_numbers(root, KEY(TPK_OPT_ISO), s->iso, s->iso_count);
    if (s->given & TPK_SCENE_ISO_OPACITY)
        add_number(root, KEY(TPK_OPT_ISO_OPACITY), s->iso_opacity);
}

static void add_output(cJSON *root, const tpk_scene *s)
{
    if (s->given & TPK_SCENE_LAYOUT)
        add_choice(root, TPK_OPT_LAYOUT, layout_index(s->layout));
    if (s->given & TPK_SCENE_SIZE) {
        double size[2] = {s->width, s->height};
        add_numbers(root, KEY(TPK_OPT_SIZE), size, 2);
    }
    if (s->given & TPK_SCENE_BACKEND)
        add_choice(root, TPK_OPT_BACKEND, s->backend == TPK_SCENE_BACKEND_VULKAN ? 1 : 0); /* cpu, vulkan */
    if (s->given & TPK_SCENE_INTEGRATION)
        add_choice(root, TPK_OPT_INTEGRATION, s->integration); /* TPK_INTEGRATION_* order */
}

/* Top-level keys the text must have: the version, one per given bit, and one "effects" for five bits. */
static int expected_keys(const tpk_scene *s)
{
    const unsigned effects = EFFECT_BITS;
    int n = 1 + ((s->given & effects) != 0);
    for (unsigned bit = 1; bit; bit <<= 1)
        n += (s->given & bit & ~effects) != 0;
    return n;
}

char *tpk_scene_to_json(const tpk_scene *s)
{
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return NULL;
    cJSON_AddNumberToObject(root, KEY(TPK_OPT_VERSION), TPK_SCENE_VERSION);
    if (s->given & TPK_SCENE_CAMERA)
        add_camera(root, &s->camera);
    if (s->given & TPK_SCENE_TF)
        add_tf(root, s);
    add_selection(root, s);
    add_effects(root, s);
    add_output(root, s);
    /* cJSON adds nothing after a failed allocation, so a short tree would print silently: count the
     * keys that should be there, and parse the text back. */
    char *text = cJSON_Print(root);
    cJSON *back = text ? cJSON_Parse(text) : NULL;
    int same = back && cJSON_GetArraySize(back) == cJSON_GetArraySize(root) && cJSON_GetArraySize(root) == expected_keys(s);
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
