/* The OpenFOAM dictionary reader: tokens, entries in scopes, includes and input modes while parsing;
 * macro expansion when an entry is asked for (foam_dict.h says what is supported and why it is lazy). */
#include <limits.h>
#include <regex.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "foam_dict.h"

#define MAX_INCLUDE_DEPTH 32
#define MAX_MACRO_DEPTH 64

enum { MODE_MERGE, MODE_OVERWRITE, MODE_PROTECT, MODE_WARN, MODE_ERROR };

typedef struct foam_entry {
    char *key;
    int pattern;        /* a quoted key: a regular expression */
    int scope;          /* the sub-dictionary's scope; -1 for a value or a removal */
    int removed;        /* #remove: hides the versions before it */
    int owner;          /* the scope it stands in, where its macros are looked up */
    int first, count;   /* a value's tokens in d->tokens */
    int seq;            /* reading order: a macro sees the entries read before its own */
} foam_entry;

typedef struct foam_scope {
    int parent;
    foam_entry *entries;
    int count, cap;
    char missing[600];  /* an include of this scope that could not be read, for lookup messages */
} foam_scope;

struct tpk_foam_dict {
    tpk_foam_file *files;
    int file_count, file_cap;
    tpk_foam_token *tokens;
    int token_count, token_cap;
    foam_scope *scopes;
    int scope_count, scope_cap;
    int seq, mode, include_depth;
    char case_dir[4096];
    tpk_diag *diag;
};

static int fail_at(tpk_foam_dict *d, int file, size_t pos, const char *fmt, va_list ap)
{
    char what[768];
    vsnprintf(what, sizeof what, fmt, ap);
    const tpk_foam_file *f = &d->files[file];
    return tpk_diag_fail(d->diag, "%s:%lld: %s", f->path, (long long)tpk_foam_line(f, pos), what);
}

int tpk_foam_dict_fail(tpk_foam_dict *d, const tpk_foam_token *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail_at(d, t->file, t->pos, fmt, ap);
    va_end(ap);
    return -1;
}

/* Fail at file's current position. */
static int fail_here(tpk_foam_dict *d, int file, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail_here(tpk_foam_dict *d, int file, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail_at(d, file, d->files[file].pos, fmt, ap);
    va_end(ap);
    return -1;
}

tpk_foam_file *tpk_foam_dict_file(tpk_foam_dict *d, const tpk_foam_token *t)
{
    return &d->files[t->file];
}

static const char *text(tpk_foam_dict *d, const tpk_foam_token *t)
{
    return d->files[t->file].data + t->pos;
}

int tpk_foam_token_is(tpk_foam_dict *d, const tpk_foam_token *t, const char *s)
{
    return t->len == strlen(s) && memcmp(text(d, t), s, t->len) == 0;
}

static int is_punct(tpk_foam_dict *d, const tpk_foam_token *t, char c)
{
    return t->kind == TPK_FOAM_PUNCT && text(d, t)[0] == c;
}

/* ---- tokens ---- */

static int word_char(char c)
{
    return c && !strchr(" \t\r\n\f()[]{};\"", c);
}

/* The next token of file `fi`: 1, 0 at its end, -1 on an unterminated string or block. */
static int next_token(tpk_foam_dict *d, int fi, tpk_foam_token *t)
{
    tpk_foam_file *f = &d->files[fi];
    tpk_foam_skip_space(f);
    if (f->pos >= f->size)
        return 0;
    const char *s = f->data;
    size_t p = f->pos, e = p + 1;
    t->file = fi;
    t->pos = p;
    if (strchr("()[]{};", s[p])) {
        t->kind = TPK_FOAM_PUNCT;
    } else if (s[p] == '"') {
        t->kind = TPK_FOAM_STRING;
        while (e < f->size && s[e] != '"')
            e += s[e] == '\\' ? 2 : 1;
        if (e >= f->size)
            return fail_here(d, fi, "a string opened here is never closed");
        e++;
    } else if (s[p] == '#' && s[p + 1] == '{') {
        t->kind = TPK_FOAM_VERBATIM;
        const char *end = strstr(s + p + 2, "#}");
        if (!end)
            return fail_here(d, fi, "a #{ verbatim block opened here is never closed by #}");
        e = (size_t)(end - s) + 2;
    } else if (s[p] == '$' && s[p + 1] == '{') {
        t->kind = TPK_FOAM_VARIABLE;
        int depth = 0;
        for (e = p + 1; e < f->size; e++) {
            depth += (s[e] == '{') - (s[e] == '}');
            if (depth == 0)
                break;
        }
        if (e >= f->size)
            return fail_here(d, fi, "a ${ opened here is never closed by }");
        e++;
    } else {
        t->kind = s[p] == '$' ? TPK_FOAM_VARIABLE : s[p] == '#' ? TPK_FOAM_DIRECTIVE : TPK_FOAM_WORD;
        while (e < f->size && word_char(s[e]))
            e++;
    }
    t->len = e - p;
    f->pos = e;
    return 1;
}

static int push_token(tpk_foam_dict *d, const tpk_foam_token *t)
{
    if (d->token_count == d->token_cap) {
        int cap = 2 * d->token_cap + 64;
        tpk_foam_token *grown = realloc(d->tokens, (size_t)cap * sizeof *grown);
        if (!grown)
            return tpk_diag_fail(d->diag, "%s: out of memory", d->files[0].path);
        d->tokens = grown;
        d->token_cap = cap;
    }
    d->tokens[d->token_count++] = *t;
    return 0;
}

/* Bytes per item of a binary List<T>, 0 for a type whose size is not known. */
static size_t binary_item_size(tpk_foam_dict *d, const tpk_foam_token *type)
{
    static const struct {
        const char *name;
        size_t size;
    } sizes[] = {{"List<scalar>", 8}, {"List<vector>", 24}, {"List<symmTensor>", 48}, {"List<tensor>", 72},
                 {"List<sphericalTensor>", 8}, {"List<label>", 4}, {"scalarList", 8}, {"vectorList", 24},
                 {"labelList", 4}};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        if (tpk_foam_token_is(d, type, sizes[i].name))
            return sizes[i].size;
    return 0;
}

/* After a List<T> word, `count` (a number) followed by ( or { makes one LIST token of the whole list: its
 * bytes are skipped here (matching parentheses in ASCII, count items in binary). 1 when it did, 0 when
 * the token is not a list's size, -1 on a list that does not close. */
static int take_list(tpk_foam_dict *d, const tpk_foam_token *type, tpk_foam_token *count)
{
    const char *s = text(d, count);
    for (size_t i = 0; i < count->len; i++)
        if (s[i] < '0' || s[i] > '9')
            return 0;
    tpk_foam_file *f = &d->files[count->file];
    size_t p = f->pos;
    while (p < f->size && strchr(" \t\r\n", f->data[p]))
        p++;
    if (p >= f->size || (f->data[p] != '(' && f->data[p] != '{'))
        return 0;
    if (f->data[p] == '{') {
        const char *end = memchr(f->data + p, '}', f->size - p);
        if (!end)
            return fail_here(d, count->file, "a uniform list %.*s{ is never closed by }", (int)count->len, s);
        p = (size_t)(end - f->data) + 1;
    } else if (f->binary) {
        size_t item = binary_item_size(d, type);
        unsigned long long n = strtoull(s, NULL, 10);
        if (!item)
            return tpk_foam_dict_fail(d, type, "a binary %.*s: its item size is not known, so it cannot be skipped",
                                      (int)type->len, text(d, type));
        if (n > (f->size - p - 1) / item || f->data[p + 1 + n * item] != ')')
            return tpk_foam_dict_fail(d, count, "a binary list of %llu items of %zu bytes does not fit or is not "
                                      "closed by ')' in the %zu bytes left", n, item, f->size - p - 1);
        p += 1 + n * item + 1;
    } else {
        int depth = 0;
        for (; p < f->size; p++) {
            depth += (f->data[p] == '(') - (f->data[p] == ')');
            if (depth == 0)
                break;
        }
        if (p >= f->size)
            return tpk_foam_dict_fail(d, count, "a list of %.*s items is never closed by ')'", (int)count->len, s);
        p++;
    }
    count->kind = TPK_FOAM_LIST;
    count->len = p - count->pos;
    f->pos = p;
    return 1;
}

/* A value's tokens up to the ';' that ends it, outside brackets, appended to d->tokens. */
static int parse_value(tpk_foam_dict *d, int fi, const char *key, int *first, int *count)
{
    *first = d->token_count;
    int depth = 0;
    tpk_foam_token t, prev = {.kind = -1};
    for (;;) {
        size_t at = d->files[fi].pos;
        int rc = next_token(d, fi, &t);
        if (rc < 0)
            return -1;
        if (rc == 0)
            return fail_here(d, fi, "expected ';' to end entry '%s', found end of file", key);
        if (t.kind == TPK_FOAM_PUNCT) {
            char c = text(d, &t)[0];
            if (c == ';' && depth == 0)
                break;
            if (c == '}' && depth == 0) {
                d->files[fi].pos = at;
                return tpk_foam_dict_fail(d, &t, "expected ';' to end entry '%s', found '}'", key);
            }
            depth += c == '(' || c == '[' || c == '{';
            depth -= c == ')' || c == ']' || c == '}';
        }
        if (t.kind == TPK_FOAM_WORD && prev.kind == TPK_FOAM_WORD && memcmp(text(d, &prev), "List<", 5) == 0 &&
            take_list(d, &prev, &t) < 0)
            return -1;
        if (push_token(d, &t) != 0)
            return -1;
        prev = t;
    }
    *count = d->token_count - *first;
    return 0;
}

/* ---- scopes and entries ---- */

static int new_scope(tpk_foam_dict *d, int parent)
{
    if (d->scope_count == d->scope_cap) {
        int cap = 2 * d->scope_cap + 8;
        foam_scope *grown = realloc(d->scopes, (size_t)cap * sizeof *grown);
        if (!grown)
            return tpk_diag_fail(d->diag, "%s: out of memory", d->files[0].path);
        d->scopes = grown;
        d->scope_cap = cap;
    }
    memset(&d->scopes[d->scope_count], 0, sizeof d->scopes[0]);
    d->scopes[d->scope_count].parent = parent;
    return d->scope_count++;
}

static foam_entry *add_entry(tpk_foam_dict *d, int scope, const char *key, size_t key_len, int pattern)
{
    foam_scope *s = &d->scopes[scope];
    char *copy = malloc(key_len + 1);
    if (copy && s->count == s->cap) {
        int cap = 2 * s->cap + 8;
        foam_entry *grown = realloc(s->entries, (size_t)cap * sizeof *grown);
        if (grown) {
            s->entries = grown;
            s->cap = cap;
        }
    }
    if (!copy || s->count == s->cap) {
        free(copy);
        tpk_diag_fail(d->diag, "%s: out of memory", d->files[0].path);
        return NULL;
    }
    memcpy(copy, key, key_len);
    copy[key_len] = 0;
    foam_entry *e = &s->entries[s->count++];
    memset(e, 0, sizeof *e);
    e->key = copy;
    e->pattern = pattern;
    e->scope = -1;
    e->owner = scope;
    e->seq = d->seq++;
    return e;
}

static int pattern_matches(const char *pattern, const char *name)
{
    char anchored[600];
    regex_t re;
    snprintf(anchored, sizeof anchored, "^(%s)$", pattern);
    if (regcomp(&re, anchored, REG_EXTENDED | REG_NOSUB) != 0)
        return 0;
    int hit = regexec(&re, name, 0, NULL, 0) == 0;
    regfree(&re);
    return hit;
}

/* The latest version of `name` read before `seq` in `scope` (an exact key first, then patterns, the
 * latest first), then in its parents when `upward`. NULL when none, or when it was #removed. */
static const foam_entry *lookup(tpk_foam_dict *d, int scope, const char *name, int seq, int upward)
{
    for (; scope >= 0; scope = upward ? d->scopes[scope].parent : -1) {
        const foam_scope *s = &d->scopes[scope];
        for (int i = s->count - 1; i >= 0; i--)
            if (s->entries[i].seq < seq && !s->entries[i].pattern && strcmp(s->entries[i].key, name) == 0)
                return s->entries[i].removed ? NULL : &s->entries[i];
        for (int i = s->count - 1; i >= 0; i--)
            if (s->entries[i].seq < seq && s->entries[i].pattern && !s->entries[i].removed &&
                pattern_matches(s->entries[i].key, name))
                return &s->entries[i];
    }
    return NULL;
}

/* A scoped macro name: ":a.b" from the top, "..a" from the parent, "a.b" into sub-dictionaries (the
 * whole name first, since keys such as alpha.water hold dots), "/a/b" and "a/b" likewise with slashes. */
static const foam_entry *resolve(tpk_foam_dict *d, int scope, const char *name, int seq)
{
    int upward = 1;
    if (name[0] == ':' || name[0] == '/') {
        scope = 0;
        name++;
        upward = 0;
    } else if (name[0] == '.') {
        name++;
        while (name[0] == '.' && d->scopes[scope].parent >= 0) {
            scope = d->scopes[scope].parent;
            name++;
        }
        upward = 0;
    }
    const foam_entry *e = lookup(d, scope, name, seq, upward);
    if (e || !name[0])
        return e;
    for (const char *sep = name; (sep = strpbrk(sep + 1, "./")) != NULL;) {
        char head[512];
        if ((size_t)(sep - name) >= sizeof head)
            break;
        memcpy(head, name, (size_t)(sep - name));
        head[sep - name] = 0;
        const foam_entry *sub = lookup(d, scope, head, seq, upward);
        if (sub && sub->scope >= 0) {
            const foam_entry *inner = resolve(d, sub->scope, sep + 1, INT_MAX);
            if (inner)
                return inner;
        }
    }
    return NULL;
}

/* "NAME" of $NAME, ${NAME} or $..NAME into buf. */
static void macro_name(tpk_foam_dict *d, const tpk_foam_token *t, char *buf, size_t cap)
{
    const char *s = text(d, t) + 1;
    size_t n = t->len - 1;
    if (n >= 2 && s[0] == '{') {
        s++;
        n -= 2;
    }
    snprintf(buf, cap, "%.*s", (int)n, s);
}

static const char *missing_note(tpk_foam_dict *d, int scope, char *buf, size_t cap)
{
    buf[0] = 0;
    for (; scope >= 0; scope = d->scopes[scope].parent)
        if (d->scopes[scope].missing[0]) {
            snprintf(buf, cap, " (%s)", d->scopes[scope].missing);
            break;
        }
    return buf;
}

static int refused_directive(tpk_foam_dict *d, const tpk_foam_token *t)
{
    if (tpk_foam_token_is(d, t, "#calc") || tpk_foam_token_is(d, t, "#codeStream") || tpk_foam_token_is(d, t, "#eval"))
        return tpk_foam_dict_fail(d, t, "%.*s is not evaluated: it compiles C++ code (OpenFOAM's dynamic code)",
                                  (int)t->len, text(d, t));
    return tpk_foam_dict_fail(d, t, "unsupported directive %.*s", (int)t->len, text(d, t));
}

typedef struct token_list {
    tpk_foam_token *items;
    int count, cap;
} token_list;

/* Append an entry's tokens with its macros replaced, each looked up from the entry's own place. */
static int expand(tpk_foam_dict *d, const foam_entry *e, token_list *out, int depth)
{
    for (int i = 0; i < e->count; i++) {
        const tpk_foam_token *t = &d->tokens[e->first + i];
        if (t->kind == TPK_FOAM_DIRECTIVE)
            return refused_directive(d, t);
        if (t->kind == TPK_FOAM_VARIABLE) {
            char name[512], note[640];
            macro_name(d, t, name, sizeof name);
            const foam_entry *v = resolve(d, e->owner, name, e->seq);
            if (!v)
                return tpk_foam_dict_fail(d, t, "$%s is not defined above its use%s", name,
                                          missing_note(d, e->owner, note, sizeof note));
            if (v->scope >= 0)
                return tpk_foam_dict_fail(d, t, "$%s names a dictionary where a value is expected", name);
            if (depth >= MAX_MACRO_DEPTH)
                return tpk_foam_dict_fail(d, t, "$%s: macros nested deeper than %d (a macro that uses itself?)",
                                          name, MAX_MACRO_DEPTH);
            if (expand(d, v, out, depth + 1) != 0)
                return -1;
            continue;
        }
        if (out->count == out->cap) {
            int cap = 2 * out->cap + 16;
            tpk_foam_token *grown = realloc(out->items, (size_t)cap * sizeof *grown);
            if (!grown)
                return tpk_diag_fail(d->diag, "%s: out of memory", d->files[0].path);
            out->items = grown;
            out->cap = cap;
        }
        out->items[out->count++] = *t;
    }
    return 0;
}

int tpk_foam_dict_value(tpk_foam_dict *d, const char *key, tpk_foam_token **tokens, int *count)
{
    *tokens = NULL;
    *count = 0;
    const foam_entry *e = lookup(d, 0, key, INT_MAX, 0);
    char note[640];
    if (!e)
        return tpk_diag_fail(d->diag, "%s: no entry '%s'%s", d->files[0].path, key,
                             missing_note(d, 0, note, sizeof note));
    if (e->scope >= 0)
        return tpk_diag_fail(d->diag, "%s: '%s' is a dictionary, expected a value", d->files[0].path, key);
    token_list out = {0};
    if (expand(d, e, &out, 0) != 0) {
        free(out.items);
        return -1;
    }
    if (out.count == 0)
        return tpk_diag_fail(d->diag, "%s: entry '%s' has no value", d->files[0].path, key);
    *tokens = out.items;
    *count = out.count;
    return 0;
}

/* ---- includes ---- */

static int add_file(tpk_foam_dict *d, const tpk_foam_file *f)
{
    if (d->file_count == d->file_cap) {
        int cap = 2 * d->file_cap + 4;
        tpk_foam_file *grown = realloc(d->files, (size_t)cap * sizeof *grown);
        if (!grown)
            return tpk_diag_fail(d->diag, "%s: out of memory", f->path);
        d->files = grown;
        d->file_cap = cap;
    }
    d->files[d->file_count] = *f;
    return d->file_count++;
}

/* An include's file name with $FOAM_CASE, <case>, <system>, <constant>, ~ and environment variables
 * replaced; relative to the including file's folder. */
static void include_path(tpk_foam_dict *d, int fi, const char *name, char *out, size_t cap)
{
    char expanded[4096] = "";
    size_t n = 0;
    for (const char *p = name; *p && n + 1 < sizeof expanded;) {
        const char *repl = NULL;
        size_t skip = 0;
        char var[4200];
        if (p == name && *p == '~' && (p[1] == '/' || !p[1])) {
            repl = getenv("HOME"), skip = 1;
        } else if (p == name && *p == '<') {
            const char *end = strchr(p, '>');
            static const char *const tags[] = {"<case>", "", "<system>", "/system", "<constant>", "/constant"};
            for (int k = 0; end && k < 6; k += 2)
                if ((size_t)(end + 1 - p) == strlen(tags[k]) && strncmp(p, tags[k], strlen(tags[k])) == 0) {
                    snprintf(var, sizeof var, "%s%s", d->case_dir, tags[k + 1]);
                    repl = var, skip = strlen(tags[k]);
                }
        } else if (*p == '$') {
            int braced = p[1] == '{';
            const char *s = p + 1 + braced, *e = s;
            while (*e == '_' || (*e >= 'A' && *e <= 'Z') || (*e >= 'a' && *e <= 'z') || (*e >= '0' && *e <= '9'))
                e++;
            snprintf(var, sizeof var, "%.*s", (int)(e - s), s);
            skip = (size_t)(e - p) + (braced && *e == '}');
            repl = strcmp(var, "FOAM_CASE") == 0 ? d->case_dir : getenv(var);
            if (!repl)
                repl = "";
        }
        if (skip) {
            n += (size_t)snprintf(expanded + n, sizeof expanded - n, "%s", repl ? repl : "");
            n = n < sizeof expanded ? n : sizeof expanded - 1;
            p += skip;
        } else {
            expanded[n++] = *p++;
        }
    }
    expanded[n] = 0;
    const char *including = d->files[fi].path, *slash = strrchr(including, '/');
    size_t dir = expanded[0] == '/' || !slash ? 0 : (size_t)(slash - including) + 1, len = strlen(expanded);
    if (dir + len + 1 > cap) /* too long to name a file: left to fail as a missing one */
        dir = 0, len = len < cap ? len : cap - 1;
    memcpy(out, including, dir);
    memcpy(out + dir, expanded, len);
    out[dir + len] = 0;
}

/* #includeEtc: the user's, the site's and the installation's etc folders, as OpenFOAM searches them. */
static int etc_path(const char *name, char *out, size_t cap)
{
    const char *home = getenv("HOME"), *site = getenv("WM_PROJECT_SITE"), *project = getenv("WM_PROJECT_DIR");
    char dirs[4][2048];
    int n = 0;
    if (home)
        snprintf(dirs[n++], sizeof dirs[0], "%s/.OpenFOAM", home);
    if (site)
        snprintf(dirs[n++], sizeof dirs[0], "%s/etc", site);
    if (project)
        snprintf(dirs[n++], sizeof dirs[0], "%s/etc", project);
    snprintf(dirs[n++], sizeof dirs[0], "/usr/share/openfoam/etc"); /* Debian's openfoam */
    for (int i = 0; i < n; i++) {
        snprintf(out, cap, "%.2000s/%.2000s", dirs[i], name);
        FILE *f = fopen(out, "rb");
        if (f) {
            fclose(f);
            return 0;
        }
    }
    snprintf(out, cap, "%s", name);
    return 1;
}

static int parse_body(tpk_foam_dict *d, int fi, int scope, int inside);

static int include(tpk_foam_dict *d, int fi, int scope, const tpk_foam_token *directive)
{
    tpk_foam_token name;
    int rc = next_token(d, fi, &name);
    if (rc < 0)
        return -1;
    if (rc == 0 || (name.kind != TPK_FOAM_STRING && name.kind != TPK_FOAM_WORD))
        return tpk_foam_dict_fail(d, directive, "expected a file name after %.*s", (int)directive->len,
                                  text(d, directive));
    char raw[4096], path[8192];
    int quoted = name.kind == TPK_FOAM_STRING;
    snprintf(raw, sizeof raw, "%.*s", (int)(name.len - 2 * quoted), text(d, &name) + quoted);
    int etc = tpk_foam_token_is(d, directive, "#includeEtc"), optional = tpk_foam_token_is(d, directive, "#includeIfPresent") ||
                                                                tpk_foam_token_is(d, directive, "#sinclude");
    if (etc)
        etc_path(raw, path, sizeof path);
    else
        include_path(d, fi, raw, path, sizeof path);
    if (d->include_depth >= MAX_INCLUDE_DEPTH)
        return tpk_foam_dict_fail(d, directive, "includes nested deeper than %d (a file that includes itself?)",
                                  MAX_INCLUDE_DEPTH);
    tpk_foam_file f;
    rc = tpk_foam_read_any(&f, path, d->diag);
    if (rc < 0)
        return -1;
    if (rc == 1) {
        if (optional)
            return 0;
        /* OpenFOAM stops here; tetpack reads no boundary conditions, so an include missing inside a
         * sub-dictionary (#includeEtc "caseDicts/setConstraintTypes" on a machine without OpenFOAM) only
         * matters when a value looked up needs it. At the top it may define anything: an error. */
        char why[600];
        snprintf(why, sizeof why, "%.*s \"%.160s\" at %.240s:%lld: no such file%s", (int)directive->len,
                 text(d, directive), raw, d->files[fi].path, (long long)tpk_foam_line(&d->files[fi], directive->pos),
                 etc ? " in the OpenFOAM etc folders (set WM_PROJECT_DIR)" : "");
        if (scope == 0)
            return tpk_diag_fail(d->diag, "%s", why);
        snprintf(d->scopes[scope].missing, sizeof d->scopes[scope].missing, "%s", why);
        return 0;
    }
    int file = add_file(d, &f);
    if (file < 0) {
        tpk_foam_close(&f);
        return -1;
    }
    d->include_depth++;
    rc = parse_body(d, file, scope, 0);
    d->include_depth--;
    return rc;
}

/* Copy the entries of `from` (read before seq) into `to`, sub-dictionaries deeply: `$dict` where an entry
 * belongs. */
static int merge_scope(tpk_foam_dict *d, int to, int from, int seq)
{
    int count = d->scopes[from].count;
    for (int i = 0; i < count; i++) {
        foam_entry src = d->scopes[from].entries[i];
        if (src.seq >= seq)
            continue;
        foam_entry *e = add_entry(d, to, src.key, strlen(src.key), src.pattern);
        if (!e)
            return -1;
        e->removed = src.removed;
        e->first = src.first;
        e->count = src.count;
        if (src.scope >= 0) {
            int sub = new_scope(d, to);
            if (sub < 0)
                return -1;
            d->scopes[to].entries[d->scopes[to].count - 1].scope = sub;
            if (merge_scope(d, sub, src.scope, seq) != 0)
                return -1;
        }
    }
    return 0;
}

static int directive(tpk_foam_dict *d, int fi, int scope, const tpk_foam_token *t)
{
    if (tpk_foam_token_is(d, t, "#include") || tpk_foam_token_is(d, t, "#includeEtc") || tpk_foam_token_is(d, t, "#includeIfPresent") ||
        tpk_foam_token_is(d, t, "#sinclude"))
        return include(d, fi, scope, t);
    if (tpk_foam_token_is(d, t, "#inputMode")) {
        static const char *const modes[] = {"merge", "overwrite", "protect", "warn", "error", "default"};
        tpk_foam_token m;
        if (next_token(d, fi, &m) > 0)
            for (int k = 0; k < 6; k++)
                if (tpk_foam_token_is(d, &m, modes[k])) {
                    d->mode = k == 5 ? MODE_MERGE : k;
                    return 0;
                }
        return tpk_foam_dict_fail(d, t, "expected merge, overwrite, protect, warn, error or default after #inputMode");
    }
    if (tpk_foam_token_is(d, t, "#remove")) {
        tpk_foam_token k;
        int rc = next_token(d, fi, &k), list = rc > 0 && is_punct(d, &k, '(');
        for (;;) {
            if (list && (rc = next_token(d, fi, &k)) > 0 && is_punct(d, &k, ')'))
                return 0;
            if (rc < 0)
                return -1;
            if (rc == 0 || (k.kind != TPK_FOAM_WORD && k.kind != TPK_FOAM_STRING))
                return tpk_foam_dict_fail(d, t, "expected a keyword or a list of keywords after #remove");
            int q = k.kind == TPK_FOAM_STRING;
            foam_entry *e = add_entry(d, scope, text(d, &k) + q, k.len - 2 * q, 0);
            if (!e)
                return -1;
            e->removed = 1;
            if (!list)
                return 0;
        }
    }
    if (tpk_foam_token_is(d, t, "#includeFunc") || tpk_foam_token_is(d, t, "#includeFuncIfPresent")) {
        /* A function object for controlDict's functions: nothing a mesh or a field needs. */
        tpk_foam_file *f = &d->files[fi];
        while (f->pos < f->size && f->data[f->pos] != '\n')
            f->pos++;
        return 0;
    }
    return refused_directive(d, t);
}

/* A keyword's entry: a sub-dictionary when '{' follows, else a value; #inputMode decides what a second
 * entry of the same keyword does. */
static int keyword_entry(tpk_foam_dict *d, int fi, int scope, const tpk_foam_token *key)
{
    int q = key->kind == TPK_FOAM_STRING;
    char name[512];
    snprintf(name, sizeof name, "%.*s", (int)(key->len - 2 * q), text(d, key) + q);
    const foam_entry *old = lookup(d, scope, name, INT_MAX, 0);
    if (old && old->pattern != q)
        old = NULL;
    int keep = !old || d->mode == MODE_MERGE || d->mode == MODE_OVERWRITE;
    if (old && d->mode == MODE_ERROR)
        return tpk_foam_dict_fail(d, key, "'%s' is defined a second time under #inputMode error", name);
    if (old && d->mode == MODE_WARN)
        tpk_diag_warn(d->diag, "%s:%lld: '%s' is defined a second time; the first is kept (#inputMode warn)",
                      d->files[fi].path, (long long)tpk_foam_line(&d->files[fi], key->pos), name);
    tpk_foam_file *f = &d->files[fi];
    size_t at = f->pos;
    tpk_foam_token next;
    int rc = next_token(d, fi, &next);
    if (rc < 0)
        return -1;
    if (rc > 0 && is_punct(d, &next, '{')) {
        int sub;
        if (keep && old && old->scope >= 0 && d->mode == MODE_MERGE) {
            sub = old->scope;
        } else {
            if ((sub = new_scope(d, scope)) < 0)
                return -1;
            if (keep) {
                foam_entry *e = add_entry(d, scope, name, strlen(name), q);
                if (!e)
                    return -1;
                e->scope = sub;
            }
        }
        return parse_body(d, fi, sub, 1);
    }
    d->files[fi].pos = at;
    int first = 0, count = 0;
    if (parse_value(d, fi, name, &first, &count) != 0)
        return -1;
    if (!keep)
        return 0;
    foam_entry *e = add_entry(d, scope, name, strlen(name), q);
    if (!e)
        return -1;
    e->first = first;
    e->count = count;
    return 0;
}

/* Entries up to the end of file `fi`, or up to the '}' that closes the scope when `inside`. */
static int parse_body(tpk_foam_dict *d, int fi, int scope, int inside)
{
    for (;;) {
        tpk_foam_token t;
        int rc = next_token(d, fi, &t);
        if (rc < 0)
            return -1;
        if (rc == 0)
            return inside ? fail_here(d, fi, "expected '}' to close a dictionary, found end of file") : 0;
        if (is_punct(d, &t, ';'))
            continue;
        if (is_punct(d, &t, '}')) {
            if (inside)
                return 0;
            return tpk_foam_dict_fail(d, &t, "found '}' with no dictionary open");
        }
        if (t.kind == TPK_FOAM_DIRECTIVE) {
            if (directive(d, fi, scope, &t) != 0)
                return -1;
        } else if (t.kind == TPK_FOAM_VARIABLE) {
            char name[512], note[640];
            macro_name(d, &t, name, sizeof name);
            const foam_entry *v = resolve(d, scope, name, d->seq);
            if (!v)
                return tpk_foam_dict_fail(d, &t, "$%s is not defined above its use%s", name,
                                          missing_note(d, scope, note, sizeof note));
            if (v->scope < 0)
                return tpk_foam_dict_fail(d, &t, "$%s stands where an entry belongs but names a value, not a "
                                          "dictionary", name);
            if (merge_scope(d, scope, v->scope, d->seq) != 0)
                return -1;
        } else if (t.kind == TPK_FOAM_WORD || t.kind == TPK_FOAM_STRING) {
            if (keyword_entry(d, fi, scope, &t) != 0)
                return -1;
        } else {
            return tpk_foam_dict_fail(d, &t, "expected a keyword, found '%.*s'", (int)(t.len > 20 ? 20 : t.len),
                                      text(d, &t));
        }
    }
}

tpk_foam_dict *tpk_foam_dict_parse(tpk_foam_file *top, const char *case_dir, tpk_diag *diag)
{
    tpk_foam_dict *d = calloc(1, sizeof *d);
    if (!d) {
        tpk_foam_close(top);
        tpk_diag_fail(diag, "%s: out of memory", top->path);
        return NULL;
    }
    d->diag = diag;
    snprintf(d->case_dir, sizeof d->case_dir, "%s", case_dir);
    if (add_file(d, top) < 0) {
        tpk_foam_close(top);
        free(d);
        return NULL;
    }
    if (new_scope(d, -1) < 0 || parse_body(d, 0, 0, 0) != 0) {
        tpk_foam_dict_free(d);
        return NULL;
    }
    return d;
}

void tpk_foam_dict_free(tpk_foam_dict *d)
{
    if (!d)
        return;
    for (int i = 0; i < d->file_count; i++)
        tpk_foam_close(&d->files[i]);
    for (int s = 0; s < d->scope_count; s++) {
        for (int i = 0; i < d->scopes[s].count; i++)
            free(d->scopes[s].entries[i].key);
        free(d->scopes[s].entries);
    }
    free(d->files);
    free(d->tokens);
    free(d->scopes);
    free(d);
}
