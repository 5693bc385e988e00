/* .pvtu piece lists through expat: only the PUnstructuredGrid's Piece elements matter here; the P*Data
 * declarations are checked by the importer on each piece instead. */
#include "pvtu.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "import/xml_input.h"

typedef struct pvtu_state {
    const char *path;
    size_t dir_length;
    tpk_piece_list *list;
    int grid_seen, failed;
    tpk_diag *diag;
    XML_Parser parser;
} pvtu_state;

static int safe_source(const char *s)
{
    if (!s[0] || s[0] == '/')
        return 0;
    for (const char *p = s; (p = strstr(p, "..")) != NULL; p += 2)
        if ((p == s || p[-1] == '/') && (p[2] == 0 || p[2] == '/'))
            return 0;
    return 1;
}

static void add_piece(pvtu_state *st, const char *source)
{
    long line = (long)XML_GetCurrentLineNumber(st->parser);
    if (!safe_source(source)) {
        st->failed = 1;
        tpk_diag_fail(st->diag, "%s: line %ld: expected a piece Source beside or below the .pvtu, found '%s'",
                      st->path, line, source);
        return;
    }
    char **grown = realloc(st->list->paths, sizeof *grown * (size_t)(st->list->count + 1));
    size_t need = st->dir_length + strlen(source) + 1;
    char *full = malloc(need);
    if (!grown || !full) {
        free(full);
        if (grown)
            st->list->paths = grown;
        st->failed = 1;
        tpk_diag_fail(st->diag, "%s: out of memory for the piece list", st->path);
        return;
    }
    snprintf(full, need, "%.*s%s", (int)st->dir_length, st->path, source);
    st->list->paths = grown;
    st->list->paths[st->list->count++] = full;
}

static void XMLCALL on_start(void *user, const XML_Char *name, const XML_Char **attrs)
{
    pvtu_state *st = user;
    if (st->failed)
        return;
    if (!strcmp(name, "PUnstructuredGrid"))
        st->grid_seen = 1;
    if (strcmp(name, "Piece") || !st->grid_seen)
        return;
    for (int i = 0; attrs[i]; i += 2)
        if (!strcmp(attrs[i], "Source")) {
            add_piece(st, attrs[i + 1]);
            return;
        }
    st->failed = 1;
    tpk_diag_fail(st->diag, "%s: line %ld: expected a Source attribute on <Piece>, found none", st->path,
                  (long)XML_GetCurrentLineNumber(st->parser));
}

static char *read_all(const char *path, size_t *size, tpk_diag *diag)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        tpk_diag_fail(diag, "%s: cannot open: %s", path, "no such file or not readable");
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = n >= 0 && n < (1L << 26) ? malloc((size_t)n + 1) : NULL;
    if (!data || fread(data, 1, (size_t)n, f) != (size_t)n) {
        free(data);
        fclose(f);
        tpk_diag_fail(diag, "%s: expected a .pvtu of less than 64 MiB, could not read it", path);
        return NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return data;
}

int tpk_pvtu_pieces(const char *path, tpk_piece_list *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    size_t size = 0;
    char *data = read_all(path, &size, diag);
    if (!data)
        return -1;
    const char *slash = strrchr(path, '/');
    out->format = "pvtu";
    pvtu_state st = {path, slash ? (size_t)(slash - path + 1) : 0, out, 0, 0, diag, XML_ParserCreate(NULL)};
    if (!st.parser) {
        free(data);
        return tpk_diag_fail(diag, "%s: out of memory for the XML parser", path);
    }
    XML_SetUserData(st.parser, &st);
    XML_SetStartElementHandler(st.parser, on_start);
    int rc = tpk_xml_parse(st.parser, path, data, size, 1, &st.failed, diag);
    XML_ParserFree(st.parser);
    free(data);
    if (rc == 0 && !st.failed && (!st.grid_seen || out->count == 0))
        rc = tpk_diag_fail(diag, "%s: expected a PUnstructuredGrid with at least one <Piece Source=...>, found %s",
                           path, st.grid_seen ? "no piece" : "no PUnstructuredGrid");
    if (rc != 0 || st.failed) {
        tpk_piece_list_free(out);
        return -1;
    }
    return 0;
}

void tpk_piece_list_free(tpk_piece_list *list)
{
    for (int i = 0; i < list->count; i++)
        free(list->paths[i]);
    free(list->paths);
    memset(list, 0, sizeof *list);
}

/* A decomposed OpenFOAM case: CASE/processor<k>, k = 0, 1, ... while they exist. */
static int processor_dirs(const char *path, tpk_piece_list *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    out->openfoam = 1;
    out->format = "openfoam";
    for (;;) {
        char dir[4096];
        struct stat st;
        snprintf(dir, sizeof dir, "%s/processor%d", path, out->count);
        if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
            break;
        char **grown = realloc(out->paths, sizeof *grown * (size_t)(out->count + 1));
        char *copy = strdup(dir);
        if (!grown || !copy) {
            free(copy);
            if (grown)
                out->paths = grown;
            tpk_piece_list_free(out);
            return tpk_diag_fail(diag, "%s: out of memory for the processor folders", path);
        }
        out->paths = grown;
        out->paths[out->count++] = copy;
    }
    if (out->count == 0) {
        tpk_piece_list_free(out);
        return tpk_diag_fail(diag, "%s: expected a .pvtu, or an OpenFOAM case decomposed by decomposePar "
                             "(processor0, processor1, ...), found a folder without processor0", path);
    }
    return 0;
}

int tpk_input_pieces(const char *path, tpk_piece_list *out, tpk_diag *diag)
{
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return processor_dirs(path, out, diag);
    size_t len = strlen(path);
    if (len >= 5 && !strcmp(path + len - 5, ".pvtu"))
        return tpk_pvtu_pieces(path, out, diag);
    return tpk_exodus_pieces(path, out, diag);
}
