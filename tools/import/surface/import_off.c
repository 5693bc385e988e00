/* OFF reader (Geomview Object File Format, "OFF" or "COFF"): counts, vertices, then polygons as
 * "n i1 ... in" with 0-based indices; '#' comments; colors after a face's indices are ignored. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surface.h"
#include "surface_build.h"
#include "base/text_scan.h"

static int read_off_counts(tpk_scan *s, int64_t *nv, int64_t *nf)
{
    int64_t ne;
    if (tpk_scan_int64(s, nv, "the vertex count") || tpk_scan_int64(s, nf, "the face count") ||
        tpk_scan_line_int64(s, &ne, "the edge count"))
        return -1;
    if (*nv < 0 || *nf < 0 || ne < 0)
        return tpk_scan_fail(s, "expected counts >= 0 in the header, found %lld %lld %lld", (long long)*nv,
                             (long long)*nf, (long long)ne);
    size_t left = s->size - s->pos;
    /* A vertex line holds at least "0 0 0\n", a face line "3 0 1 2\n". */
    if ((uint64_t)*nv > left / 6 + 1 || (uint64_t)*nf > left / 8 + 1 || *nv > INT32_MAX)
        return tpk_scan_fail(s, "%lld vertices and %lld faces cannot fit in the %zu bytes left in the file "
                             "(wrong counts or truncated file)", (long long)*nv, (long long)*nf, left);
    return tpk_scan_end_line(s, "the counts");
}

static int read_off_vertices(tpk_scan *s, tpk_mesh *m, int colored)
{
    for (int64_t i = 0; i < m->point_count; i++) {
        double *p = m->points + 3 * i;
        char what[128];
        snprintf(what, sizeof what, "a coordinate of vertex %lld", (long long)i);
        if (tpk_scan_double(s, &p[0], what) || tpk_scan_line_double(s, &p[1], what) ||
            tpk_scan_line_double(s, &p[2], what))
            return -1;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            return tpk_scan_fail(s, "expected finite coordinates of vertex %lld", (long long)i);
        const char *tok;
        size_t len = colored ? 0 : tpk_scan_line_token(s, &tok);
        char q[64];
        if (len)
            return tpk_scan_fail(s, "expected end of line after the 3 coordinates of vertex %lld, found '%s' (is "
                                 "the vertex count in the header too large?)", (long long)i,
                                 tpk_scan_quote(tok, len, q, sizeof q));
        tpk_scan_skip_line(s);
    }
    return 0;
}

static int grow_conn(tpk_mesh *m, int64_t *cap, int64_t need)
{
    if (need <= *cap)
        return 0;
    while (*cap < need)
        *cap *= 2;
    int32_t *grown = realloc(m->cell_conn, sizeof(int32_t) * (size_t)*cap);
    if (!grown)
        return -1;
    m->cell_conn = grown;
    return 0;
}

static int read_off_faces(tpk_scan *s, tpk_mesh *m, int64_t conn_cap)
{
    for (int64_t f = 0; f < m->cell_count; f++) {
        int64_t n, id, at = m->cell_offsets[f];
        char what[128];
        snprintf(what, sizeof what, "the corner count of face %lld", (long long)f);
        if (tpk_scan_int64(s, &n, what))
            return -1;
        if (n < 3 || n > 1000000 || (uint64_t)n > s->size - s->pos)
            return tpk_scan_fail(s, "expected a corner count from 3 to %zu for face %lld, found %lld",
                                 s->size - s->pos < 1000000 ? s->size - s->pos : (size_t)1000000, (long long)f,
                                 (long long)n);
        if (grow_conn(m, &conn_cap, at + n))
            return tpk_scan_fail(s, "out of memory for the corners of face %lld", (long long)f);
        snprintf(what, sizeof what, "a vertex index of face %lld", (long long)f);
        for (int64_t k = 0; k < n; k++) {
            if (tpk_scan_line_int64(s, &id, what))
                return -1;
            if (id < 0 || id >= m->point_count)
                return tpk_scan_fail(s, "expected a vertex index of face %lld from 0 to %lld, found %lld",
                                     (long long)f, (long long)m->point_count - 1, (long long)id);
            m->cell_conn[at + k] = (int32_t)id;
        }
        tpk_scan_skip_line(s); /* an optional color */
        m->cell_types[f] = n == 3 ? TPK_CELL_SURF_TRIANGLE : TPK_CELL_SURF_POLYGON;
        m->cell_offsets[f + 1] = at + n;
    }
    return 0;
}

static int read_off_body(tpk_scan *s, tpk_mesh *out)
{
    const char *tok;
    size_t len = tpk_scan_token(s, &tok);
    int colored = len == 4 && !memcmp(tok, "COFF", 4);
    char q[64];
    if (!colored && !(len == 3 && !memcmp(tok, "OFF", 3)))
        return tpk_scan_fail(s, "expected 'OFF' or 'COFF' at the start, found '%s'", tpk_scan_quote(tok, len, q, sizeof q));
    int64_t nv, nf;
    if (read_off_counts(s, &nv, &nf))
        return -1;
    int64_t conn_cap = 3 * nf + 16;
    if (tpk_surf_alloc(out, nv, nf, conn_cap) != 0)
        return tpk_scan_fail(s, "out of memory for %lld vertices and %lld faces", (long long)nv, (long long)nf);
    if (read_off_vertices(s, out, colored) || read_off_faces(s, out, conn_cap))
        return -1;
    len = tpk_scan_token(s, &tok);
    if (len)
        return tpk_scan_fail(s, "expected end of file after the %lld faces the header announces, found '%s' "
                             "(wrong face count?)", (long long)nf, tpk_scan_quote(tok, len, q, sizeof q));
    strcpy(out->format, "off");
    return 0;
}

int tpk_read_off(const char *name, const char *data, size_t size, tpk_mesh *out, tpk_diag *diag)
{
    tpk_scan s;
    tpk_scan_init(&s, name, data, size, diag);
    s.hash_comments = 1;
    memset(out, 0, sizeof *out);
    int rc = read_off_body(&s, out);
    if (rc)
        tpk_mesh_free(out);
    return rc;
}
