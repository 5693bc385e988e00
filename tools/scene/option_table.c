/* The option table (option_table.h): the rows of render/render_options.def, with their flags, scene
 * keys and the texts of --help and of the scene spec. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "option_table.h"
#include "render/render.h"
#include "scene.h"

#define TPK_RULE(lo_, hi_, lo_open_, hi_open_, choices_)                                                      \
    .lo = lo_, .hi = hi_, .lo_open = lo_open_, .hi_open = hi_open_, .choices = choices_
#define TPK_CLI(flag_, alias_, metavar_, rank_, effect_, render_only_, expects_, help_)                          \
    .flag = flag_, .alias = alias_, .metavar = metavar_, .help_rank = rank_, .effect = effect_,               \
    .render_only = render_only_, .expects = expects_, .help = help_
#define TPK_KEY(key_, type_, default_, scene_expects_, meaning_, constraint_)                                   \
    .scene_key = key_, .scene_type = type_, .scene_default = default_, .scene_expects = scene_expects_,       \
    .meaning = meaning_, .constraint = constraint_
#define TPK_USE(init_, when_, always_, ...) .init = init_, .save_always = always_
#define TPK_OPTION(ID, name, kind_, R, A, S, rule, cli, key, use, vk) \
    {TPK_OPT_##ID, .kind = TPK_OPT_KIND_##kind_, .in_render = R, .in_args = A, .in_scene = S, rule, cli, key, use  \
     TPK_IF(S, , .scene_at = offsetof(tpk_scene, name))},
const tpk_option_row tpk_option_table[TPK_OPT_COUNT] = {
#include "render/render_options.def"
};
#undef TPK_OPTION
#undef TPK_RULE
#undef TPK_CLI
#undef TPK_KEY
#undef TPK_USE

const char *tpk_option_scene_leaf(tpk_option_id id)
{
    const char *key = tpk_option_table[id].scene_key;
    const char *dot = key ? strchr(key, '.') : NULL;
    return dot ? dot + 1 : key;
}

int tpk_option_scene_keys(const char *parent, const char **names, int cap)
{
    size_t n = strlen(parent);
    int count = 0;
    for (int i = 0; i < TPK_OPT_COUNT && count < cap; i++) {
        const char *key = tpk_option_table[i].scene_key;
        if (!key)
            continue;
        const char *dot = strchr(key, '.');
        if (n == 0 ? dot == NULL : (dot && (size_t)(dot - key) == n && !strncmp(key, parent, n)))
            names[count++] = n == 0 ? key : dot + 1;
    }
    return count;
}

int tpk_option_int_ok(tpk_option_id id, double v)
{
    const tpk_option_row *r = &tpk_option_table[id];
    return r->kind == TPK_OPT_KIND_INT && v == floor(v) && v >= r->lo && v <= r->hi;
}

int tpk_option_number_ok(tpk_option_id id, double v)
{
    const tpk_option_row *r = &tpk_option_table[id];
    return r->kind == TPK_OPT_KIND_NUMBER && isfinite(v) && (r->lo_open ? v > r->lo : v >= r->lo) &&
           (r->hi_open ? v < r->hi : v <= r->hi);
}

int tpk_option_choice(tpk_option_id id, const char *text)
{
    const tpk_option_row *r = &tpk_option_table[id];
    if (r->kind != TPK_OPT_KIND_CHOICE || !text)
        return -1;
    size_t n = strlen(text);
    int index = 0;
    for (const char *at = r->choices; *at; index++) {
        size_t len = strcspn(at, " ");
        if (len == n && n > 0 && !strncmp(at, text, n))
            return index;
        at += len;
        at += strspn(at, " ");
    }
    return -1;
}

const char *tpk_option_choice_name(tpk_option_id id, int index, char *buf, size_t cap)
{
    const tpk_option_row *r = &tpk_option_table[id];
    buf[0] = 0;
    if (r->kind != TPK_OPT_KIND_CHOICE || index < 0)
        return buf;
    const char *at = r->choices;
    for (int i = 0; *at; i++) {
        size_t len = strcspn(at, " ");
        if (i == index) {
            snprintf(buf, cap, "%.*s", (int)len, at);
            return buf;
        }
        at += len;
        at += strspn(at, " ");
    }
    return buf;
}
