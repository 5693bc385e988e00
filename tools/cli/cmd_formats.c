/* tetpack formats: the importer registry (import/importers.h) as a table or as JSON. */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "base/strbuf.h"
#include "import/importers.h"

static const char formats_help[] =
    "usage: tetpack formats [--json]\n"
    "\n"
    "Lists every input format convert and check read: the name --format takes, its extensions, the\n"
    "first bytes that identify it when the extension does not, and what it carries (cell kinds,\n"
    "point and cell fields, time steps; gzip: FILE.EXT.gz is read too, inflated in memory). Detection\n"
    "tries the extensions in this order, then the first bytes.\n"
    "\n"
    "  --json   one JSON object: {\"formats\": [{name, aliases, title, extensions, magic, supports,\n"
    "           reader (\"file\" or \"tetgen\"), fuzz_target (or null)}]}\n";

/* `list` split at `sep` as a JSON array of strings; a byte outside printable ASCII (binary magic) as the
 * code point of the same value, \u00XX. */
static void json_words(tpk_strbuf *sb, const char *list, char sep)
{
    tpk_strbuf_printf(sb, "[");
    int first = 1;
    for (const char *at = list; at && *at;) {
        size_t len = strcspn(at, (char[]){sep, 0});
        if (len) {
            tpk_strbuf_printf(sb, "%s\"", first ? "" : ", ");
            for (size_t k = 0; k < len; k++) {
                unsigned char c = (unsigned char)at[k];
                if (c < 32 || c >= 127 || c == '"' || c == '\\')
                    tpk_strbuf_printf(sb, "\\u%04x", c);
                else
                    tpk_strbuf_printf(sb, "%c", c);
            }
            tpk_strbuf_printf(sb, "\"");
            first = 0;
        }
        at += len + (at[len] == sep);
    }
    tpk_strbuf_printf(sb, "]");
}

static int print_json(const tpk_import_format *rows, size_t count)
{
    tpk_strbuf sb = {0};
    char words[256];
    tpk_strbuf_printf(&sb, "{\"formats\": [");
    for (size_t i = 0; i < count; i++) {
        const tpk_import_format *r = &rows[i];
        tpk_strbuf_printf(&sb, "%s\n  {\"name\": ", i ? "," : "");
        tpk_strbuf_json_string(&sb, r->name);
        tpk_strbuf_printf(&sb, ", \"aliases\": ");
        json_words(&sb, r->aliases, ' ');
        tpk_strbuf_printf(&sb, ", \"title\": ");
        tpk_strbuf_json_string(&sb, r->title);
        tpk_strbuf_printf(&sb, ", \"extensions\": ");
        json_words(&sb, r->extensions, ' ');
        tpk_strbuf_printf(&sb, ", \"magic\": ");
        json_words(&sb, r->magic, '|');
        tpk_strbuf_printf(&sb, ", \"supports\": ");
        json_words(&sb, tpk_import_format_supports(r->supports, words, sizeof words), ' ');
        tpk_strbuf_printf(&sb, ", \"reader\": \"%s\", \"fuzz_target\": ", r->read ? "file" : "tetgen");
        if (r->read_memory)
            tpk_strbuf_printf(&sb, "\"fuzz_%s\"}", r->name);
        else
            tpk_strbuf_printf(&sb, "null}");
    }
    tpk_strbuf_printf(&sb, "\n]}\n");
    int ok = !sb.failed;
    if (ok)
        fputs(sb.data, stdout);
    tpk_strbuf_free(&sb);
    return ok ? TPK_EXIT_OK : tpk_cli_fail("formats", "out of memory");
}

/* The magic prefixes for people, space-separated: printable bytes as they are, others as \xNN. */
static const char *magic_text(const char *magic, char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = 0;
    for (const unsigned char *c = (const unsigned char *)magic; c && *c && used + 5 < cap; c++) {
        if (*c == '|')
            buf[used++] = ' ';
        else if (*c >= 32 && *c < 127)
            buf[used++] = (char)*c;
        else
            used += (size_t)snprintf(buf + used, cap - used, "\\x%02x", *c);
        buf[used] = 0;
    }
    return buf;
}

void tpk_cli_print_formats(FILE *out)
{
    size_t count;
    const tpk_import_format *rows = tpk_import_formats(&count);
    for (size_t i = 0; i < count; i++) {
        char names[96];
        snprintf(names, sizeof names, "%s%s%s", rows[i].name, rows[i].aliases ? "|" : "",
                 rows[i].aliases ? rows[i].aliases : "");
        fprintf(out, "  %-12s %-28s %s\n", names, rows[i].extensions[0] ? rows[i].extensions : "(by name only)",
                rows[i].title);
    }
}

int tpk_cmd_formats(int argc, char **argv)
{
    int json = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(formats_help, stdout);
            return TPK_EXIT_OK;
        } else if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else {
            return tpk_cli_fail("formats", "unknown option '%s' (see tetpack formats --help)", argv[i]);
        }
    }
    size_t count;
    const tpk_import_format *rows = tpk_import_formats(&count);
    if (json)
        return print_json(rows, count);
    printf("%-12s %-28s %-24s %s\n", "FORMAT", "EXTENSIONS", "FIRST BYTES", "CARRIES");
    for (size_t i = 0; i < count; i++) {
        const tpk_import_format *r = &rows[i];
        char words[256];
        printf("%-12s %-28s ", r->name, r->extensions[0] ? r->extensions : "(by name only)");
        char magic[64];
        printf("%-24s %s\n", r->magic ? magic_text(r->magic, magic, sizeof magic) : "-",
               tpk_import_format_supports(r->supports, words, sizeof words));
        printf("%-12s %s%s%s\n", "", r->title, r->aliases ? "; --format also takes: " : "",
               r->aliases ? r->aliases : "");
    }
    return TPK_EXIT_OK;
}
