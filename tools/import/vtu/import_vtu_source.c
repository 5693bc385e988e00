/* VTU importer: byte sources, raw bytes or base64 text decoded as it is read. Runs of whole groups are
 * decoded by table straight into the caller's buffer; a group with whitespace, padding or a bad
 * character goes through the careful path, which knows where the data ends and words the failures. */
#include <stdio.h>
#include <string.h>

#include "base/parallel.h"
#include "import_vtu_internal.h"

int vtu_src_fail(bsrc *s, const char *what)
{
    if (s->in_file)
        snprintf(s->error_buf, sizeof s->error_buf, "%s at byte %zu of the file", what, s->base + s->pos);
    else
        snprintf(s->error_buf, sizeof s->error_buf, "%s at character %zu of the array's text", what, s->base + s->pos);
    s->error = s->error_buf;
    return -1;
}

static int b64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z')
        return c - 'A';
    if (c >= 'a' && c <= 'z')
        return c - 'a' + 26;
    if (c >= '0' && c <= '9')
        return c - '0' + 52;
    if (c == '+')
        return 62;
    if (c == '/')
        return 63;
    if (c == '=')
        return -2;
    return -1;
}

/* A base64 digit's value + 1; 0 for every other byte (whitespace, '=', not base64). */
static const unsigned char b64_plus1[256] = {
    ['A'] = 1, ['B'] = 2, ['C'] = 3, ['D'] = 4, ['E'] = 5, ['F'] = 6, ['G'] = 7, ['H'] = 8, ['I'] = 9, ['J'] = 10,
    ['K'] = 11, ['L'] = 12, ['M'] = 13, ['N'] = 14, ['O'] = 15, ['P'] = 16, ['Q'] = 17, ['R'] = 18, ['S'] = 19,
    ['T'] = 20, ['U'] = 21, ['V'] = 22, ['W'] = 23, ['X'] = 24, ['Y'] = 25, ['Z'] = 26,
    ['a'] = 27, ['b'] = 28, ['c'] = 29, ['d'] = 30, ['e'] = 31, ['f'] = 32, ['g'] = 33, ['h'] = 34, ['i'] = 35,
    ['j'] = 36, ['k'] = 37, ['l'] = 38, ['m'] = 39, ['n'] = 40, ['o'] = 41, ['p'] = 42, ['q'] = 43, ['r'] = 44,
    ['s'] = 45, ['t'] = 46, ['u'] = 47, ['v'] = 48, ['w'] = 49, ['x'] = 50, ['y'] = 51, ['z'] = 52,
    ['0'] = 53, ['1'] = 54, ['2'] = 55, ['3'] = 56, ['4'] = 57, ['5'] = 58, ['6'] = 59, ['7'] = 60, ['8'] = 61,
    ['9'] = 62, ['+'] = 63, ['/'] = 64};

int vtu_is_space(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

uint64_t vtu_src_left(const bsrc *s)
{
    if (!s->b64)
        return s->len - s->pos;
    return (uint64_t)(s->len - s->pos) / 4 * 3 + 3 + (uint64_t)(s->npend - s->ipend);
}

/* Groups [begin, end) of `in` into `out`; the index of the first group that is not four plain digits, or
 * end. */
static size_t decode_groups(const unsigned char *in, unsigned char *out, size_t begin, size_t end)
{
    for (size_t g = begin; g < end; g++) {
        const unsigned char *p = in + 4 * g;
        unsigned a = b64_plus1[p[0]], b = b64_plus1[p[1]], c = b64_plus1[p[2]], d = b64_plus1[p[3]];
        if (!a || !b || !c || !d)
            return g;
        uint32_t bits = (a - 1) << 18 | (b - 1) << 12 | (c - 1) << 6 | (d - 1);
        out[3 * g] = (unsigned char)(bits >> 16);
        out[3 * g + 1] = (unsigned char)(bits >> 8);
        out[3 * g + 2] = (unsigned char)bits;
    }
    return end;
}

typedef struct groups_job {
    const unsigned char *in;
    unsigned char *out;
    size_t stop[TPK_MAX_THREADS]; /* per worker: its first group that is not plain, or its end */
} groups_job;

static void groups_range(void *ctx, int64_t begin, int64_t end, int w)
{
    groups_job *job = ctx;
    job->stop[w] = decode_groups(job->in, job->out, (size_t)begin, (size_t)end);
}

/* Many groups (a large array without line breaks, as VTK and meshio write it) on all cores: the run of
 * plain groups up to the first one that is not (later workers' bytes past it are written again by the
 * careful path). Returns the groups taken. */
static size_t plain_groups_parallel(const unsigned char *in, unsigned char *out, size_t groups)
{
    int threads = tpk_threads_for((int64_t)groups, tpk_thread_count(0), (int64_t)1 << 18);
    if (threads < 2)
        return 0;
    groups_job job = {in, out, {0}};
    tpk_parallel_for((int64_t)groups, threads, groups_range, &job);
    for (int w = 0; w < threads; w++) {
        int64_t begin, end;
        tpk_parallel_range((int64_t)groups, threads, w, &begin, &end);
        if (job.stop[w] < (size_t)end)
            return job.stop[w];
    }
    return groups;
}

/* Whole groups of four plain digits into 3 bytes each, while at least 3 bytes are wanted and nothing is
 * pending: exactly what the careful path below would do with them, in one tight loop. Returns the
 * bytes written. */
static size_t read_plain_groups(bsrc *s, unsigned char *out, size_t n)
{
    size_t groups = (n / 3 < (s->len - s->pos) / 4) ? n / 3 : (s->len - s->pos) / 4;
    if (groups >= ((size_t)1 << 19)) {
        size_t taken = plain_groups_parallel(s->p + s->pos, out, groups);
        s->pos += 4 * taken;
        if (taken == groups || taken > 0)
            return 3 * taken;
    }
    size_t done = 0, pos = s->pos;
    const unsigned char *p = s->p;
    while (n - done >= 3 && s->len - pos >= 4) {
        unsigned a = b64_plus1[p[pos]], b = b64_plus1[p[pos + 1]], c = b64_plus1[p[pos + 2]],
                 d = b64_plus1[p[pos + 3]];
        if (!a || !b || !c || !d)
            break;
        uint32_t bits = (a - 1) << 18 | (b - 1) << 12 | (c - 1) << 6 | (d - 1);
        out[done] = (unsigned char)(bits >> 16);
        out[done + 1] = (unsigned char)(bits >> 8);
        out[done + 2] = (unsigned char)bits;
        done += 3;
        pos += 4;
    }
    s->pos = pos;
    return done;
}

/* Base64 is decoded group by group, so streams concatenated with their own '=' padding (VTK encodes
 * the header and the data separately) decode as one. */
int vtu_src_read(bsrc *s, unsigned char *out, size_t n)
{
    if (!s->b64) {
        if (n > s->len - s->pos) {
            return vtu_src_fail(s, "found the end of the data");
        }
        memcpy(out, s->p + s->pos, n);
        s->pos += n;
        return 0;
    }
    while (n) {
        if (s->ipend < s->npend) {
            *out++ = s->pend[s->ipend++];
            n--;
            continue;
        }
        size_t fast = read_plain_groups(s, out, n);
        out += fast;
        n -= fast;
        if (!n)
            break;
        int v[4], k = 0;
        while (k < 4 && s->pos < s->len) {
            unsigned char c = s->p[s->pos++];
            if (vtu_is_space(c))
                continue;
            v[k] = b64_value(c);
            if (v[k] == -1) {
                s->pos--;
                return vtu_src_fail(s, "found a character that is not base64");
            }
            k++;
        }
        if (k == 0) {
            return vtu_src_fail(s, "found the end of the base64 data");
        }
        if (k < 4 || v[0] < 0 || v[1] < 0 || (v[2] == -2 && v[3] != -2)) {
            return vtu_src_fail(s, "found an incomplete or badly padded base64 group");
        }
        uint32_t bits = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 | (uint32_t)(v[2] < 0 ? 0 : v[2]) << 6 |
                        (uint32_t)(v[3] < 0 ? 0 : v[3]);
        s->pend[0] = (unsigned char)(bits >> 16);
        s->pend[1] = (unsigned char)(bits >> 8);
        s->pend[2] = (unsigned char)bits;
        s->npend = v[2] == -2 ? 1 : v[3] == -2 ? 2 : 3;
        s->ipend = 0;
    }
    return 0;
}
