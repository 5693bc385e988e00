/* The piece list of an Exodus mesh decomposed per processor, in the SEACAS convention (nem_slice /
 * nem_spread, decomp): BASE.N.K for K = 0 .. N-1, K zero-padded to the digits of N (mesh.e.4.0 ..
 * mesh.e.4.3, mesh.e.16.00 .. mesh.e.16.15). Each is a whole Exodus file with its own numbering; its node
 * number map gives the global node ids (read by the importer). */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "pvtu.h"

/* The digits at s up to the end or `stop`: their count, the value in *value (< 2^31), 0 when none or too many. */
static int digits(const char *s, char stop, long *value)
{
    int n = 0;
    *value = 0;
    for (; s[n] >= '0' && s[n] <= '9'; n++)
        if (n >= 9)
            return 0;
        else
            *value = *value * 10 + (s[n] - '0');
    return n > 0 && s[n] == stop ? n : 0;
}

/* `name` is BASE.N.K (K < N): base length, N, K's width; 0 when not. */
static size_t piece_name(const char *name, long *n, int *width)
{
    size_t len = strlen(name);
    for (size_t dot = len; dot-- > 1;) { /* the ".N." before K: the second-to-last dot */
        if (name[dot] != '.')
            continue;
        long k = 0;
        int wn = digits(name + dot + 1, '.', n);
        if (!wn || dot + 1 + (size_t)wn >= len)
            continue;
        *width = digits(name + dot + 2 + wn, 0, &k);
        return *width && *n > 0 && k < *n ? dot : 0;
    }
    return 0;
}

/* The N of the files BASE.N.K beside `path` (= BASE) and K's width: 0 when there are none, -1 (diag set)
 * when two processor counts are found. */
static long count_beside(const char *path, int *width, tpk_diag *diag)
{
    const char *slash = strrchr(path, '/');
    char dir[4096];
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path + (slash == path)) : 1, slash ? path : ".");
    const char *base = slash ? slash + 1 : path;
    size_t base_len = strlen(base);
    DIR *d = opendir(dir);
    long found = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;) {
        long n = 0;
        int w = 0;
        if (strncmp(e->d_name, base, base_len) || piece_name(e->d_name, &n, &w) != base_len)
            continue;
        if (found && n != found) {
            closedir(d);
            tpk_diag_fail(diag, "%s: expected Exodus files for one processor count beside it, found %s.%ld.* and "
                          "%s.%ld.* (name one piece to choose)", path, path, found, path, n);
            return -1;
        }
        found = n, *width = w;
    }
    if (d)
        closedir(d);
    return found;
}

static int list_pieces(const char *base, size_t base_len, long n, int width, tpk_piece_list *out, tpk_diag *diag)
{
    out->paths = calloc((size_t)n, sizeof *out->paths);
    if (!out->paths)
        return tpk_diag_fail(diag, "%.*s: out of memory for %ld pieces", (int)base_len, base, n);
    for (long k = 0; k < n; k++) {
        size_t need = base_len + 2 * 12 + 3;
        out->paths[k] = malloc(need);
        if (!out->paths[k])
            return tpk_diag_fail(diag, "%.*s: out of memory for %ld pieces", (int)base_len, base, n);
        out->count++;
        snprintf(out->paths[k], need, "%.*s.%ld.%0*ld", (int)base_len, base, n, width, k);
        struct stat st;
        if (stat(out->paths[k], &st) != 0 || !S_ISREG(st.st_mode))
            return tpk_diag_fail(diag, "%s: missing: expected piece %ld of the %ld Exodus files per processor "
                                 "%.*s.%ld.*, found no such file", out->paths[k], k, n, (int)base_len, base, n);
    }
    return 0;
}

/* Not tpk_piece_list_free: pvtu.c calls this file, and files must not call each other both ways. */
static void drop(tpk_piece_list *list)
{
    for (int i = 0; i < list->count; i++)
        free(list->paths[i]);
    free(list->paths);
    memset(list, 0, sizeof *list);
}

int tpk_exodus_pieces(const char *path, tpk_piece_list *out, tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    out->format = "exodus";
    const char *slash = strrchr(path, '/');
    size_t dir_len = slash ? (size_t)(slash - path + 1) : 0;
    long n = 0;
    int width = 0;
    size_t piece_base = piece_name(path + dir_len, &n, &width), base_len = 0;
    long beside = 0;
    int piece_width = width;
    struct stat st;
    if (piece_base && stat(path, &st) == 0)
        base_len = dir_len + piece_base; /* one of the pieces named */
    else if ((beside = count_beside(path, &width, diag)) > 0)
        base_len = strlen(path), n = beside;
    else if (beside == 0 && piece_base) /* a piece named that does not exist: list_pieces names it */
        base_len = dir_len + piece_base, width = piece_width;
    else {
        if (beside == 0)
            tpk_diag_fail(diag, "%s: expected a .pvtu, an OpenFOAM case folder, or Exodus files per processor "
                          "(%s.N.K, K = 0 .. N-1, as nem_slice writes them), found none", path, path);
        return -1;
    }
    if (list_pieces(path, base_len, n, width, out, diag) != 0) {
        drop(out);
        return -1;
    }
    return 0;
}
