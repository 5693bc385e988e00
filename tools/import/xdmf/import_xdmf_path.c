/* XDMF importer: the XPath subset that XInclude xpointers and References use, evaluated on the tree.
 * Steps are '/' (children) or '//' (descendants), a name or '*', and predicates [@Name="v"] (or 'v'),
 * [N] (1-based position among the step's matches under one parent) and [self::A or self::B]. meshio
 * writes //Grid[@Name="mesh"]/ * [self::Topology or self::Geometry] (without the blanks); dolfinx
 * /Xdmf/Domain/Grid[@GridType='Uniform'][1]/ * [...] alike. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "import_xdmf_internal.h"

#define MAX_REFERENCE_CHAIN 16

typedef struct node_set {
    xdmf_node **at;
    size_t count, cap;
} node_set;

static int set_add(node_set *s, xdmf_node *n)
{
    if (s->count == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 16;
        xdmf_node **grown = realloc(s->at, sizeof *grown * cap);
        if (!grown)
            return -1;
        s->at = grown;
        s->cap = cap;
    }
    s->at[s->count++] = n;
    return 0;
}

/* The path text being read, for messages. */
typedef struct path_scan {
    xdmf_reader *r;
    const xdmf_node *at;
    const char *p, *end, *start;
} path_scan;

static int bad_path(path_scan *s, const char *expected)
{
    char found[8] = "its end";
    if (s->p < s->end)
        snprintf(found, sizeof found, "'%c'", *s->p >= 32 && *s->p < 127 ? *s->p : '?');
    return xdmf_fail(s->r, s->at, "path \"%.*s\": expected %s at character %d, found %s",
                     (int)(s->end - s->start < 200 ? s->end - s->start : 200), s->start, expected,
                     (int)(s->p - s->start) + 1, found);
}

static int is_name_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.' || c == ':';
}

static size_t name_len(path_scan *s)
{
    size_t n = 0;
    while (s->p + n < s->end && is_name_char(s->p[n]))
        n++;
    return n;
}

static void skip_blank(path_scan *s)
{
    while (s->p < s->end && (*s->p == ' ' || *s->p == '\t' || *s->p == '\n' || *s->p == '\r'))
        s->p++;
}

static int name_matches(const xdmf_node *n, const char *name, size_t len)
{
    if (len == 1 && name[0] == '*')
        return 1;
    const char *colon = strchr(n->name, ':');
    const char *local = colon ? colon + 1 : n->name;
    return strlen(local) == len && !strncasecmp(local, name, len);
}

/* One predicate's verdict for node n, the pos-th (1-based) match under its parent. Advances s->p past
 * the predicate; -1 on a malformed one. */
static int predicate(path_scan *s, const xdmf_node *n, size_t pos)
{
    skip_blank(s);
    if (s->p < s->end && *s->p >= '0' && *s->p <= '9') {
        size_t want = 0;
        while (s->p < s->end && *s->p >= '0' && *s->p <= '9' && want < 1000000000)
            want = want * 10 + (size_t)(*s->p++ - '0');
        return want == pos;
    }
    if (s->p < s->end && *s->p == '@') {
        s->p++;
        const char *key = s->p;
        size_t klen = name_len(s);
        s->p += klen;
        skip_blank(s);
        if (!klen || s->p >= s->end || *s->p != '=')
            return bad_path(s, "@Attribute=\"value\"");
        s->p++;
        skip_blank(s);
        if (s->p >= s->end || (*s->p != '"' && *s->p != '\''))
            return bad_path(s, "a quoted value");
        char quote = *s->p++;
        const char *value = s->p;
        while (s->p < s->end && *s->p != quote)
            s->p++;
        if (s->p >= s->end)
            return bad_path(s, "a closing quote");
        size_t vlen = (size_t)(s->p++ - value);
        for (int i = 0; n->attrs && n->attrs[i]; i += 2)
            if (strlen(n->attrs[i]) == klen && !memcmp(n->attrs[i], key, klen))
                return strlen(n->attrs[i + 1]) == vlen && !memcmp(n->attrs[i + 1], value, vlen);
        return 0;
    }
    int any = 0;
    for (;;) {
        skip_blank(s);
        if (s->end - s->p < 6 || memcmp(s->p, "self::", 6))
            return bad_path(s, "[N], [@Attribute=\"value\"] or [self::Name or ...]");
        s->p += 6;
        const char *name = s->p;
        size_t len = name_len(s);
        s->p += len;
        any |= len && name_matches(n, name, len);
        skip_blank(s);
        if (s->end - s->p >= 3 && !memcmp(s->p, "or", 2) && (s->p[2] == ' ' || s->p[2] == 's'))
            s->p += 2;
        else
            return any;
    }
}

/* Skip one predicate's text (for an empty node set, which never reads it). */
static void skip_predicate(path_scan *s)
{
    char quote = 0;
    while (s->p < s->end && (quote || *s->p != ']')) {
        if (*s->p == '"' || *s->p == '\'')
            quote = quote == *s->p ? 0 : quote ? quote : *s->p;
        s->p++;
    }
}

/* Append to out those of cand (the matches under one parent) that pass the predicates from s->p on,
 * applied in turn: positions count among the nodes that passed the predicates before, as in XPath. */
static int filter(path_scan *s, node_set *cand, node_set *out)
{
    node_set passed = *cand;
    *cand = (node_set){0};
    int rc = 0;
    while (rc == 0 && s->p < s->end && *s->p == '[') {
        const char *pred = ++s->p;
        node_set next = {0};
        if (passed.count == 0)
            skip_predicate(s);
        for (size_t j = 0; rc == 0 && j < passed.count; j++) {
            s->p = pred;
            int v = predicate(s, passed.at[j], j + 1);
            rc = v < 0 ? -1 : v && set_add(&next, passed.at[j]) ? xdmf_fail(s->r, s->at, "out of memory") : 0;
        }
        free(passed.at);
        passed = next;
        skip_blank(s);
        if (rc == 0 && (s->p >= s->end || *s->p != ']'))
            rc = bad_path(s, "']'");
        s->p++;
    }
    for (size_t j = 0; rc == 0 && j < passed.count; j++)
        if (set_add(out, passed.at[j]))
            rc = xdmf_fail(s->r, s->at, "out of memory");
    free(passed.at);
    return rc;
}

/* The candidates of one step under `parent`: children, or all descendants for '//'. */
static int candidates(xdmf_node *parent, int deep, const char *name, size_t len, node_set *out)
{
    for (xdmf_node *c = parent->first; c; c = c->next) {
        if (name_matches(c, name, len) && set_add(out, c))
            return -1;
        if (deep && candidates(c, 1, name, len, out))
            return -1;
    }
    return 0;
}

int xdmf_select(xdmf_reader *r, const xdmf_node *at, const char *path, size_t len, xdmf_node ***found,
                size_t *count)
{
    path_scan s = {.r = r, .at = at, .p = path, .end = path + len, .start = path};
    node_set cur = {0};
    *found = NULL;
    *count = 0;
    if (set_add(&cur, r->doc))
        return xdmf_fail(r, at, "out of memory");
    skip_blank(&s);
    if (s.p >= s.end || *s.p != '/') {
        free(cur.at);
        return bad_path(&s, "an absolute path starting with '/'");
    }
    int rc = 0;
    while (rc == 0 && s.p < s.end && *s.p == '/') {
        int deep = s.end - s.p >= 2 && s.p[1] == '/';
        s.p += deep ? 2 : 1;
        const char *name = s.p;
        size_t nlen = *s.p == '*' ? 1 : name_len(&s);
        if (!nlen) {
            rc = bad_path(&s, "an element name or '*'");
            break;
        }
        s.p += nlen;
        node_set next = {0};
        const char *preds = s.p;
        for (size_t i = 0; rc == 0 && i < cur.count; i++) {
            node_set cand = {0};
            s.p = preds;
            rc = candidates(cur.at[i], deep, name, nlen, &cand) ? xdmf_fail(r, at, "out of memory")
                                                                : filter(&s, &cand, &next);
            free(cand.at);
        }
        if (cur.count == 0) { /* nothing to filter: still step over the predicates */
            node_set none = {0};
            rc = filter(&s, &none, &next);
        }
        free(cur.at);
        cur = next;
        skip_blank(&s);
    }
    if (rc == 0 && s.p < s.end)
        rc = bad_path(&s, "'/' or the end of the path");
    if (rc) {
        free(cur.at);
        return -1;
    }
    *found = cur.at;
    *count = cur.count;
    return 0;
}

int xdmf_follow_reference(xdmf_reader *r, const xdmf_node *n, const xdmf_node **out)
{
    for (int hop = 0; hop < MAX_REFERENCE_CHAIN; hop++) {
        const char *ref = xdmf_attr(n, "Reference");
        if (!ref) {
            *out = n;
            return 0;
        }
        size_t len = strlen(ref);
        if (!strcasecmp(ref, "XML"))
            ref = xdmf_trimmed(n, &len);
        xdmf_node **found;
        size_t count;
        if (xdmf_select(r, n, ref, len, &found, &count))
            return -1;
        const xdmf_node *target = count == 1 ? found[0] : NULL;
        free(found);
        if (count != 1)
            return xdmf_fail(r, n, "Reference \"%.*s\": expected it to name one element, found %zu", (int)len, ref,
                             count);
        const char *colon = strchr(n->name, ':');
        if (!xdmf_is(target, colon ? colon + 1 : n->name))
            return xdmf_fail(r, n, "Reference \"%.*s\": expected a <%s>, found <%s> (line %ld)", (int)len, ref,
                             n->name, target->name, target->line);
        if (target == n)
            break;
        n = target;
    }
    return xdmf_fail(r, n, "References form a chain longer than %d or a loop", MAX_REFERENCE_CHAIN);
}
