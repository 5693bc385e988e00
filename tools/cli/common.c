/* Helpers shared by the tetpack subcommands: errors, number parsing, option values. */
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "tetpack.h"

int tpk_cli_fail(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "tetpack %s: error: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return TPK_EXIT_USAGE;
}

int tpk_cli_parse_doubles(const char *text, double *out, int count)
{
    const char *p = text;
    for (int i = 0; i < count; i++) {
        char *end;
        errno = 0;
        out[i] = strtod(p, &end);
        if (end == p || errno == ERANGE)
            return -1;
        p = end;
        if (i + 1 < count) {
            if (*p != ',')
                return -1;
            p++;
        }
    }
    return *p == 0 ? 0 : -1;
}

int tpk_cli_parse_int(const char *text, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end || errno == ERANGE || v < lo || v > hi)
        return -1;
    *out = (int)v;
    return 0;
}

const char *tpk_cli_value(int argc, char **argv, int *i, const char *name)
{
    const char *arg = argv[*i];
    size_t n = strlen(name);
    if (strncmp(arg, name, n) == 0 && arg[n] == '=')
        return arg + n + 1;
    if (*i + 1 >= argc)
        return NULL;
    (*i)++;
    return argv[*i];
}

const char *tpk_cli_joined(int argc, char **argv, const char *skip)
{
    static char joined[4096];
    size_t used = 0;
    snprintf(joined, sizeof joined, "tetpack");
    used = strlen(joined);
    for (int i = 0; i < argc && used + 2 < sizeof joined; i++) {
        if (skip && argv[i] == skip)
            continue;
        /* The thread count does not change the output; leave it out so the file does not depend on it. */
        if (!strncmp(argv[i], "--threads", 9)) {
            i += argv[i][9] == '=' ? 0 : 1;
            continue;
        }
        /* Nor does progress on stderr: a file converted on a terminal equals one converted in a script. */
        if (!strcmp(argv[i], "--progress") || !strcmp(argv[i], "--no-progress"))
            continue;
        int n = snprintf(joined + used, sizeof joined - used, " %s", argv[i]);
        if (n < 0)
            break;
        used += (size_t)n;
    }
    if (used >= sizeof joined)
        joined[sizeof joined - 1] = 0;
    return joined;
}

int tpk_cli_open(const char *cmd, const char *path, tpk_file **out)
{
    char err[1024] = "";
    tpk_result r = tpk_open_path(out, path, NULL, err, sizeof err);
    if (r == TPK_OK)
        return 0;
    return tpk_cli_fail_file(cmd, path, err[0] ? err : tpk_result_string(r));
}

int tpk_cli_fail_file(const char *cmd, const char *path, const char *why)
{
    if (strstr(why, path))
        return tpk_cli_fail(cmd, "%s", why);
    return tpk_cli_fail(cmd, "%s: %s", path, why);
}
