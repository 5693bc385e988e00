/* The option table (scene/option_table.h) against what comes from it: the scene spec's key table
 * (spec/scene-json.md §2) row by row, the scene reader's known keys, and the command line's flags. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "scene/option_table.h"
#include "scene/scene.h"

#define SPEC_PATH TPK_SOURCE_DIR "/spec/scene-json.md"
#define SPEC_HEADER "| Key | Type | Meaning | Default (key absent) | Constraint |"

/* The spec's row of a table row: "| `key` | type | meaning | default | constraint |", an empty cell
 * as "| |". */
static void spec_row(const tpk_option_row *o, char *out, size_t cap)
{
    const char *cells[4] = {o->scene_type, o->meaning, o->scene_default, o->constraint};
    size_t n = (size_t)snprintf(out, cap, "| `%s` |", o->scene_key);
    for (int k = 0; k < 4 && n < cap; k++)
        n += (size_t)snprintf(out + n, cap - n, cells[k][0] ? " %s |" : " |", cells[k]);
}

static char *read_spec(void)
{
    FILE *f = fopen(SPEC_PATH, "rb");
    if (!f)
        return NULL;
    char *text = calloc(1, 1 << 20);
    size_t n = text ? fread(text, 1, (1 << 20) - 1, f) : 0;
    fclose(f);
    if (text)
        text[n] = 0;
    return text;
}

/* Each row of the spec's table is the table's row of the same key, in the same order, and no more. */
TPK_TEST(spec_table_matches)
{
    char *spec = read_spec();
    CHECK(spec != NULL);
    const char *line = strstr(spec, SPEC_HEADER "\n|---|---|---|---|---|\n");
    CHECK(line != NULL);
    line = strchr(strchr(line, '\n') + 1, '\n') + 1;
    int rows = 0;
    for (int i = 0; i < TPK_OPT_COUNT; i++) {
        const tpk_option_row *o = &tpk_option_table[i];
        if (!o->scene_key)
            continue;
        char want[2048];
        spec_row(o, want, sizeof want);
        size_t len = strcspn(line, "\n");
        CHECK_MSG(len == strlen(want) && !strncmp(line, want, len),
                  "spec/scene-json.md §2, row %d:\n  found:    %.*s\n  expected: %s", rows + 1, (int)len, line, want);
        line += len + (line[len] == '\n');
        rows++;
    }
    CHECK_MSG(line[0] != '|', "spec/scene-json.md §2 has a row the option table lacks: %.*s",
              (int)strcspn(line, "\n"), line);
    free(spec);
}

/* A scene with an unknown key lists the keys the reader knows: those of the table, in its order. */
TPK_TEST(reader_keys_are_the_table)
{
    const char *parents[] = {"", "camera", "tf", "effects"};
    for (int p = 0; p < 4; p++) {
        const char *names[TPK_OPT_COUNT];
        int n = tpk_option_scene_keys(parents[p], names, TPK_OPT_COUNT);
        CHECK(n > 0);
        char text[256], want[1024] = "";
        if (parents[p][0])
            snprintf(text, sizeof text, "{\"%s\": {\"zzzzzz\": 1}}", parents[p]);
        else
            snprintf(text, sizeof text, "{\"zzzzzz\": 1}");
        for (int k = 0; k < n; k++)
            snprintf(want + strlen(want), sizeof want - strlen(want), "%s%s", k ? ", " : "", names[k]);
        tpk_scene scene;
        tpk_diag diag = {0};
        CHECK(tpk_scene_parse("s.json", text, NULL, &scene, &diag) == -1);
        const char *list = strstr(diag.message, ": ");
        list = list ? strrchr(diag.message, ':') : NULL;
        CHECK_MSG(list && !strcmp(list + 2, want), "%s: '%s', table '%s'", parents[p], diag.message, want);
    }
}

/* Flags and aliases are unique, each option with a value says what it expects, and every row with a
 * flag has a --help rank of its own. */
TPK_TEST(flags_unique)
{
    int ranks[TPK_OPT_COUNT + 1] = {0};
    for (int i = 0; i < TPK_OPT_COUNT; i++) {
        const tpk_option_row *o = &tpk_option_table[i];
        CHECK_EQ_INT(o->id, i);
        CHECK(o->flag || o->scene_key);
        if (!o->flag)
            continue;
        CHECK_MSG(o->help && o->help[0], "%s has no help", o->flag);
        CHECK_MSG(!o->metavar || o->expects, "%s takes a value but says nothing it expects", o->flag);
        CHECK_MSG(o->help_rank >= 1 && o->help_rank <= TPK_OPT_COUNT && !ranks[o->help_rank]++,
                  "%s: help rank %d", o->flag, o->help_rank);
        for (int j = 0; j < i; j++) {
            const tpk_option_row *q = &tpk_option_table[j];
            CHECK_MSG(!q->flag || strcmp(q->flag, o->flag), "%s twice", o->flag);
            CHECK_MSG(!o->alias || !q->alias || strcmp(q->alias, o->alias), "%s twice", o->alias);
        }
    }
}

/* A scene giving key `key` ("a" or "a.b") the JSON value `value`; a camera gets its other keys. */
static int scene_with(const char *key, const char *value, tpk_diag *diag)
{
    char text[512];
    const char *dot = strchr(key, '.');
    if (!strcmp(key, "camera.fovy"))
        snprintf(text, sizeof text, "{\"camera\": {\"eye\": [0, 0, 5], \"at\": [0, 0, 0], \"up\": [0, 1, 0], "
                                    "\"fovy\": %s}}", value);
    else if (dot)
        snprintf(text, sizeof text, "{\"%.*s\": {\"%s\": %s}}", (int)(dot - key), key, dot + 1, value);
    else
        snprintf(text, sizeof text, "{\"%s\": %s}", key, value);
    tpk_scene scene;
    memset(diag, 0, sizeof *diag);
    return tpk_scene_parse("s.json", text, NULL, &scene, diag);
}

/* The value rules of the table (kind, range, choices), which the command line checks through the same
 * functions (tools/cli/render_args.c): the scene reader takes exactly the values they allow, at the ends
 * of every range and for every choice. */
TPK_TEST(value_rules_are_the_table)
{
    int ruled = 0;
    for (int i = 0; i < TPK_OPT_COUNT; i++) {
        const tpk_option_row *r = &tpk_option_table[i];
        tpk_diag d;
        char v[64];
        if (r->kind == TPK_OPT_KIND_OTHER)
            continue;
        ruled++;
        CHECK_MSG(r->flag || r->scene_key, "row %d has a rule but neither a flag nor a key", i);
        if (!r->scene_key)
            continue;
        if (r->kind == TPK_OPT_KIND_INT) {
            CHECK(tpk_option_int_ok(r->id, r->lo) && tpk_option_int_ok(r->id, r->hi));
            CHECK(!tpk_option_int_ok(r->id, r->lo - 1) && !tpk_option_int_ok(r->id, r->hi + 1) &&
                  !tpk_option_int_ok(r->id, r->lo + 0.5));
            snprintf(v, sizeof v, "%.0f", r->lo);
            CHECK_MSG(scene_with(r->scene_key, v, &d) == 0, "%s = %s: %s", r->scene_key, v, d.message);
            snprintf(v, sizeof v, "%.0f", r->hi);
            CHECK_MSG(scene_with(r->scene_key, v, &d) == 0, "%s = %s: %s", r->scene_key, v, d.message);
            snprintf(v, sizeof v, "%.0f", r->hi + 1);
            CHECK_MSG(scene_with(r->scene_key, v, &d) == -1, "%s = %s accepted", r->scene_key, v);
            snprintf(v, sizeof v, "%.0f", r->lo - 1);
            CHECK_MSG(scene_with(r->scene_key, v, &d) == -1, "%s = %s accepted", r->scene_key, v);
        } else if (r->kind == TPK_OPT_KIND_NUMBER) {
            double inside = isfinite(r->hi) ? 0.5 * (r->lo + r->hi) : r->lo + 1;
            snprintf(v, sizeof v, "%.17g", inside);
            CHECK_MSG(tpk_option_number_ok(r->id, inside) && scene_with(r->scene_key, v, &d) == 0, "%s = %s: %s",
                      r->scene_key, v, d.message);
            snprintf(v, sizeof v, "%.17g", r->lo);
            CHECK_MSG((scene_with(r->scene_key, v, &d) == 0) == !r->lo_open && tpk_option_number_ok(r->id, r->lo) == !r->lo_open,
                      "%s = %s: the low end's rule", r->scene_key, v);
            if (isfinite(r->hi)) {
                snprintf(v, sizeof v, "%.17g", r->hi);
                CHECK_MSG((scene_with(r->scene_key, v, &d) == 0) == !r->hi_open, "%s = %s: the high end's rule",
                          r->scene_key, v);
            }
            CHECK(!tpk_option_number_ok(r->id, NAN) && !tpk_option_number_ok(r->id, r->lo - 1));
        } else if (r->kind == TPK_OPT_KIND_BOOL) { /* a switch on the command line, true or false in a scene */
            CHECK_MSG(r->flag && !r->metavar, "%s: a switch takes no value", r->flag ? r->flag : r->scene_key);
            CHECK(scene_with(r->scene_key, "true", &d) == 0 && scene_with(r->scene_key, "false", &d) == 0);
            CHECK(scene_with(r->scene_key, "1", &d) == -1 && strstr(d.message, "expected true or false"));
        } else {
            char name[32];
            int n = 0;
            for (; tpk_option_choice_name(r->id, n, name, sizeof name)[0]; n++) {
                CHECK(tpk_option_choice(r->id, name) == n);
                snprintf(v, sizeof v, "\"%s\"", name);
                CHECK_MSG(scene_with(r->scene_key, v, &d) == 0, "%s = %s: %s", r->scene_key, v, d.message);
            }
            CHECK_MSG(n >= 2, "%s: %d choices", r->scene_key, n);
            CHECK(tpk_option_choice(r->id, "nope") == -1 && tpk_option_choice(r->id, "") == -1);
            CHECK(scene_with(r->scene_key, "\"nope\"", &d) == -1 && strstr(d.message, "expected \""));
        }
    }
    CHECK(ruled >= 10);
}
