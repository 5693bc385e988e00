/* Where things are in a scene's JSON text. cJSON parses the scene but records no positions, so a
 * message that must name a line and a key finds them here: a small scanner that follows strings,
 * objects and arrays (and nothing else: the text has already parsed, or failed to, in cJSON). */
#include <string.h>

#include "scene_internal.h"

#define MAX_DEPTH 32

typedef struct level {
    char kind;      /* '{' or '[' */
    int expect_key; /* in an object, after '{' or ',' */
    int has_key;
    size_t key_start, key_len;
} level;

typedef struct scan {
    const char *text;
    level stack[MAX_DEPTH];
    int depth; /* may exceed MAX_DEPTH: deeper levels are counted, not kept */
} scan;

/* The keys of the enclosing objects joined by '.'. */
static void join_path(const scan *s, char *path, size_t cap)
{
    size_t used = 0;
    path[0] = 0;
    int levels = s->depth < MAX_DEPTH ? s->depth : MAX_DEPTH;
    for (int l = 0; l < levels; l++) {
        const level *v = &s->stack[l];
        if (v->kind != '{' || !v->has_key || used + v->key_len + 2 > cap)
            continue;
        if (used)
            path[used++] = '.';
        memcpy(path + used, s->text + v->key_start, v->key_len);
        used += v->key_len;
        path[used] = 0;
    }
}

typedef int (*key_fn)(void *user, const scan *s, size_t quote);

/* Skip the string whose opening quote is at i; returns the index after its closing quote. */
static size_t skip_string(const char *text, size_t i, size_t end)
{
    for (i++; i < end && text[i] && text[i] != '"'; i++)
        if (text[i] == '\\' && i + 1 < end && text[i + 1])
            i++;
    return i < end && text[i] == '"' ? i + 1 : i;
}

/* Walk text[0, end) calling fn at every object key (fn returns nonzero to stop). */
static void walk(scan *s, size_t end, key_fn fn, void *user)
{
    const char *text = s->text;
    size_t i = 0;
    while (i < end && text[i]) {
        char c = text[i];
        level *top = s->depth > 0 && s->depth <= MAX_DEPTH ? &s->stack[s->depth - 1] : NULL;
        if (c == '"') {
            size_t next = skip_string(text, i, end);
            if (top && top->kind == '{' && top->expect_key) {
                top->expect_key = 0;
                top->has_key = 1;
                top->key_start = i + 1;
                top->key_len = next > i + 1 && text[next - 1] == '"' ? next - i - 2 : next - i - 1;
                if (fn && fn(user, s, i))
                    return;
            }
            i = next;
            continue;
        }
        if (c == '{' || c == '[') {
            if (s->depth < MAX_DEPTH)
                s->stack[s->depth] = (level){c, c == '{', 0, 0, 0};
            s->depth++;
        } else if ((c == '}' || c == ']') && s->depth > 0) {
            s->depth--;
        } else if (c == ',' && top && top->kind == '{') {
            top->expect_key = 1;
        }
        i++;
    }
}

void tpk_scene_line_col(const char *text, size_t offset, int *line, int *col)
{
    int l = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < offset && text[i]; i++)
        if (text[i] == '\n') {
            l++;
            line_start = i + 1;
        }
    *line = l;
    *col = (int)(offset - line_start) + 1;
}

typedef struct find {
    const char *target;
    int skip; /* occurrences still to pass */
    long offset;
} find;

static int match_key(void *user, const scan *s, size_t quote)
{
    find *f = user;
    char path[512];
    join_path(s, path, sizeof path);
    if (strcmp(path, f->target) || f->skip-- > 0)
        return 0;
    f->offset = (long)quote;
    return 1;
}

long tpk_scene_key_offset(const char *text, const char *path, int nth)
{
    scan s = {.text = text};
    find f = {path, nth, -1};
    walk(&s, strlen(text), match_key, &f);
    return f.offset;
}

void tpk_scene_key_at(const char *text, size_t offset, char *path, size_t cap)
{
    scan s = {.text = text};
    walk(&s, offset, NULL, NULL);
    join_path(&s, path, cap);
}
