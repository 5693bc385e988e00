/* XDMF importer: expat builds the element tree (names, attributes, text, lines) the other layers read.
 * Entity declarations are refused (XDMF has no use for them, and they could expand without bound);
 * a DOCTYPE without them, as dolfinx writes, is fine. */
#include <expat.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "import_xdmf_internal.h"

#define MAX_DEPTH 64

typedef struct tree_build {
    xdmf_reader *r;
    XML_Parser parser;
    xdmf_node *at;  /* the open element */
    int depth;
    size_t text_cap; /* room of at->text */
} tree_build;

static void node_free(xdmf_node *n)
{
    for (int i = 0; n->attrs && n->attrs[i]; i++)
        free(n->attrs[i]);
    free(n->attrs);
    free(n->name);
    free(n->text);
    free(n);
}

void xdmf_tree_free(xdmf_node *doc)
{
    /* Iterative, children before parents: a deep tree cannot exhaust the stack. */
    xdmf_node *n = doc;
    while (n) {
        if (n->first) {
            xdmf_node *child = n->first;
            n->first = child->next;
            n = child;
            continue;
        }
        xdmf_node *parent = n->parent;
        node_free(n);
        n = parent;
    }
}

static void stop(tree_build *b, const char *why)
{
    xdmf_node here = {.name = b->at ? b->at->name : "", .line = (long)XML_GetCurrentLineNumber(b->parser)};
    xdmf_fail(b->r, &here, "%s", why);
    XML_StopParser(b->parser, XML_FALSE);
}

static char **copy_attrs(const XML_Char **atts)
{
    int n = 0;
    while (atts[n])
        n++;
    char **copy = calloc((size_t)n + 1, sizeof *copy);
    for (int i = 0; copy && i < n; i++)
        if (!(copy[i] = strdup(atts[i]))) {
            for (int j = 0; j < i; j++)
                free(copy[j]);
            free(copy);
            return NULL;
        }
    return copy;
}

static void XMLCALL on_start(void *user, const XML_Char *el, const XML_Char **atts)
{
    tree_build *b = user;
    if (++b->depth > MAX_DEPTH) {
        stop(b, "elements nested more than 64 deep (not an XDMF file?)");
        return;
    }
    xdmf_node *n = calloc(1, sizeof *n);
    if (!n || !(n->name = strdup(el)) || !(n->attrs = copy_attrs(atts))) {
        if (n)
            node_free(n);
        stop(b, "out of memory");
        return;
    }
    n->line = (long)XML_GetCurrentLineNumber(b->parser);
    n->parent = b->at;
    if (b->at->last)
        b->at->last->next = n;
    else
        b->at->first = n;
    b->at->last = n;
    b->at = n;
    b->text_cap = 0;
}

static void XMLCALL on_end(void *user, const XML_Char *el)
{
    tree_build *b = user;
    (void)el;
    b->depth--;
    b->at = b->at->parent;
    b->text_cap = b->at->text ? b->at->text_len + 1 : 0;
}

static void XMLCALL on_text(void *user, const XML_Char *s, int len)
{
    tree_build *b = user;
    xdmf_node *n = b->at;
    if (len <= 0 || !n->parent)
        return;
    if (n->text_len + (size_t)len + 1 > b->text_cap) {
        size_t cap = b->text_cap ? b->text_cap : 256;
        while (cap < n->text_len + (size_t)len + 1)
            cap *= 2;
        char *grown = realloc(n->text, cap);
        if (!grown) {
            stop(b, "out of memory for the element's text");
            return;
        }
        n->text = grown;
        b->text_cap = cap;
    }
    memcpy(n->text + n->text_len, s, (size_t)len);
    n->text_len += (size_t)len;
    n->text[n->text_len] = 0;
}

static void XMLCALL on_entity(void *user, const XML_Char *name, int is_param, const XML_Char *value, int value_len,
                              const XML_Char *base, const XML_Char *sysid, const XML_Char *pubid,
                              const XML_Char *notation)
{
    (void)name, (void)is_param, (void)value, (void)value_len, (void)base, (void)sysid, (void)pubid, (void)notation;
    stop(user, "expected no entity declarations in an XDMF file, found one (not read)");
}

int xdmf_parse_tree(xdmf_reader *r)
{
    tree_build b = {.r = r};
    r->doc = calloc(1, sizeof *r->doc);
    if (!r->doc || !(r->doc->name = strdup("#document")))
        return xdmf_fail(r, NULL, "out of memory");
    b.at = r->doc;
    b.parser = XML_ParserCreate(NULL);
    if (!b.parser)
        return xdmf_fail(r, NULL, "out of memory for the XML parser");
    XML_SetUserData(b.parser, &b);
    XML_SetElementHandler(b.parser, on_start, on_end);
    XML_SetCharacterDataHandler(b.parser, on_text);
    XML_SetEntityDeclHandler(b.parser, on_entity);
    int ok = r->size <= (size_t)1 << 30 &&
             XML_Parse(b.parser, r->data ? r->data : "", (int)r->size, 1) == XML_STATUS_OK;
    if (!ok && !r->failed) {
        enum XML_Error e = XML_GetErrorCode(b.parser);
        xdmf_node here = {.name = "", .line = (long)XML_GetCurrentLineNumber(b.parser)};
        if (r->size > (size_t)1 << 30)
            xdmf_fail(r, NULL, "expected an XML file of at most 1 GiB (HDF5 holds the large data), found %zu bytes",
                      r->size);
        else
            xdmf_fail(r, &here, "not well-formed XML: %s at column %ld%s", XML_ErrorString(e),
                      (long)XML_GetCurrentColumnNumber(b.parser),
                      e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN || e == XML_ERROR_PARTIAL_CHAR
                          ? " (truncated file?)"
                          : "");
    }
    XML_ParserFree(b.parser);
    return r->failed ? -1 : 0;
}

const char *xdmf_attr(const xdmf_node *n, const char *key)
{
    for (int i = 0; n->attrs && n->attrs[i]; i += 2)
        if (!strcmp(n->attrs[i], key))
            return n->attrs[i + 1];
    return NULL;
}

int xdmf_is(const xdmf_node *n, const char *name)
{
    const char *colon = strchr(n->name, ':');
    return !strcasecmp(colon ? colon + 1 : n->name, name);
}

const char *xdmf_trimmed(const xdmf_node *n, size_t *len)
{
    const char *s = n->text ? n->text : "";
    size_t l = n->text ? n->text_len : 0;
    while (l && (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r'))
        s++, l--;
    while (l && (s[l - 1] == ' ' || s[l - 1] == '\t' || s[l - 1] == '\n' || s[l - 1] == '\r'))
        l--;
    *len = l;
    return s;
}

int xdmf_hdf_source(const xdmf_reader *r, const xdmf_node *item, char *path, size_t cap, const char **dataset,
                    size_t *dataset_len)
{
    size_t len;
    const char *text = xdmf_trimmed(item, &len);
    const char *sep = NULL;
    for (size_t i = 1; i + 1 < len && !sep; i++)
        if (text[i] == ':' && text[i + 1] == '/')
            sep = text + i;
    if (!sep)
        return -1;
    const char *slash = strrchr(r->name, '/');
    size_t dir = slash && text[0] != '/' ? (size_t)(slash - r->name) + 1 : 0;
    if ((size_t)snprintf(path, cap, "%.*s%.*s", (int)dir, r->name, (int)(sep - text), text) >= cap)
        return -1;
    *dataset = sep + 1;
    *dataset_len = (size_t)(text + len - sep - 1);
    return 0;
}
