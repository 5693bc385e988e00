/* Polyhedron face streams (checked for the importers, moved into tpk_mesh.faces) and cell boundaries as
 * consistently oriented polygons for the tetrahedralizer. */
#include "polyhedron.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cell_types.h"

int tpk_face_stream_check(const int32_t *stream, int64_t n, int64_t point_count, int64_t *bad_at, char *why,
                          size_t why_cap)
{
    *bad_at = 0;
    if (n < 1) {
        snprintf(why, why_cap, "expected a face count, found no entries");
        return -1;
    }
    int64_t faces = stream[0];
    if (faces < 4) {
        snprintf(why, why_cap, "expected a face count >= 4, found %lld", (long long)faces);
        return -1;
    }
    if (faces > (n - 1) / 4) { /* every face takes at least 4 entries: its count and 3 ids */
        snprintf(why, why_cap, "a face count of %lld needs at least %lld entries, found %lld", (long long)faces,
                 (long long)(1 + 4 * faces), (long long)n);
        return -1;
    }
    int64_t k = 1;
    for (int64_t f = 0; f < faces; f++) {
        *bad_at = k;
        if (k >= n) {
            snprintf(why, why_cap, "face %lld of %lld: expected a point count, found the end of the cell's %lld "
                     "entries", (long long)f, (long long)faces, (long long)n);
            return -1;
        }
        int64_t points = stream[k];
        if (points < 3 || points > n - k - 1) {
            snprintf(why, why_cap, "face %lld of %lld: expected a point count from 3 to %lld (the entries left), "
                     "found %lld", (long long)f, (long long)faces, (long long)(n - k - 1), (long long)points);
            return -1;
        }
        for (k++; points-- > 0; k++) {
            if (stream[k] < 0 || stream[k] >= point_count) {
                *bad_at = k;
                snprintf(why, why_cap, "face %lld: point id %d is out of range (expected 0 to %lld)", (long long)f,
                         stream[k], (long long)point_count - 1);
                return -1;
            }
        }
    }
    *bad_at = k;
    if (k != n) {
        snprintf(why, why_cap, "the %lld faces use %lld entries, but the cell has %lld", (long long)faces,
                 (long long)k, (long long)n);
        return -1;
    }
    return 0;
}

/* Distinct point ids of a checked face stream, ascending, into ids (room for n); returns their count. */
static int64_t stream_points(const int32_t *stream, int64_t n, int32_t *ids)
{
    int64_t count = 0;
    for (int64_t f = 0, k = 1; f < stream[0]; f++) {
        int32_t points = stream[k++];
        for (int32_t j = 0; j < points; j++)
            ids[count++] = stream[k++];
    }
    (void)n;
    qsort(ids, (size_t)count, sizeof *ids, tpk_compare_int32);
    int64_t distinct = 0;
    for (int64_t i = 0; i < count; i++)
        if (distinct == 0 || ids[i] != ids[distinct - 1])
            ids[distinct++] = ids[i];
    return distinct;
}

int tpk_mesh_take_face_streams(tpk_mesh *mesh)
{
    /* most meshes have none: one memchr (a loop over every cell's type and offsets was 0.2% of a 2-thread
     * convert of grid 120, on one core) */
    if (mesh->cell_count <= 0 || !memchr(mesh->cell_types, TPK_CELL_POLYHEDRON, (size_t)mesh->cell_count))
        return 0;
    int64_t stream_size = 0;
    for (int64_t c = 0; c < mesh->cell_count; c++)
        if (mesh->cell_types[c] == TPK_CELL_POLYHEDRON)
            stream_size += mesh->cell_offsets[c + 1] - mesh->cell_offsets[c];
    if (stream_size == 0)
        return 0;
    int64_t conn_size = mesh->cell_offsets[mesh->cell_count];
    int64_t *face_offsets = malloc(sizeof *face_offsets * (size_t)(mesh->cell_count + 1));
    int32_t *faces = malloc(sizeof *faces * (size_t)stream_size);
    int64_t *offsets = malloc(sizeof *offsets * (size_t)(mesh->cell_count + 1));
    int32_t *conn = malloc(sizeof *conn * (size_t)(conn_size ? conn_size : 1));
    if (!face_offsets || !faces || !offsets || !conn) {
        free(face_offsets), free(faces), free(offsets), free(conn);
        return -1;
    }
    face_offsets[0] = offsets[0] = 0;
    for (int64_t c = 0; c < mesh->cell_count; c++) {
        int64_t begin = mesh->cell_offsets[c], n = mesh->cell_offsets[c + 1] - begin;
        const int32_t *entries = mesh->cell_conn + begin;
        int64_t kept = n;
        face_offsets[c + 1] = face_offsets[c];
        if (mesh->cell_types[c] == TPK_CELL_POLYHEDRON) {
            memcpy(faces + face_offsets[c], entries, sizeof *faces * (size_t)n);
            face_offsets[c + 1] += n;
            kept = stream_points(entries, n, conn + offsets[c]); /* fewer ids than entries: fits */
        } else {
            memcpy(conn + offsets[c], entries, sizeof *conn * (size_t)n);
        }
        offsets[c + 1] = offsets[c] + kept;
    }
    free(mesh->cell_offsets);
    free(mesh->cell_conn);
    free(mesh->face_offsets);
    free(mesh->faces);
    mesh->cell_offsets = offsets;
    mesh->cell_conn = conn;
    mesh->face_offsets = face_offsets;
    mesh->faces = faces;
    return 0;
}

/* ---- Boundaries as polygons ------------------------------------------------------------------------ */

void tpk_polygons_free(tpk_polygons *p)
{
    free(p->starts);
    free(p->ids);
    free(p->scratch);
    memset(p, 0, sizeof *p);
}

static int reserve(tpk_polygons *p, int64_t faces, int64_t ids)
{
    if (faces + 1 > p->face_cap) {
        int64_t cap = 2 * (faces + 1);
        int64_t *grown = realloc(p->starts, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        p->starts = grown;
        p->face_cap = cap;
    }
    if (ids > p->id_cap) {
        int64_t cap = 2 * ids;
        int32_t *grown = realloc(p->ids, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        p->ids = grown;
        p->id_cap = cap;
    }
    return 0;
}

int tpk_polygons_from_stream(tpk_polygons *p, const int32_t *stream, int64_t n)
{
    int64_t faces = stream[0];
    if (reserve(p, faces, n))
        return -1;
    p->face_count = faces;
    p->starts[0] = 0;
    for (int64_t f = 0, k = 1; f < faces; f++) {
        int32_t points = stream[k++];
        memcpy(p->ids + p->starts[f], stream + k, sizeof *p->ids * (size_t)points);
        p->starts[f + 1] = p->starts[f] + points;
        k += points;
    }
    return 0;
}

int tpk_polygons_from_cell(tpk_polygons *p, int type, const int32_t *nodes)
{
    int32_t ids[24];
    int starts[7];
    int faces = tpk_cell_faces(type, nodes, ids, starts);
    if (reserve(p, faces, faces ? starts[faces] : 0))
        return -1;
    p->face_count = faces;
    for (int f = 0; f <= faces; f++)
        p->starts[f] = starts[f];
    if (faces)
        memcpy(p->ids, ids, sizeof *ids * (size_t)starts[faces]);
    return 0;
}

static void reverse_face(tpk_polygons *p, int64_t f)
{
    for (int64_t a = p->starts[f], b = p->starts[f + 1] - 1; a < b; a++, b--) {
        int32_t t = p->ids[a];
        p->ids[a] = p->ids[b];
        p->ids[b] = t;
    }
}

void tpk_polygons_flip(tpk_polygons *p)
{
    for (int64_t f = 0; f < p->face_count; f++)
        reverse_face(p, f);
}

double tpk_polygons_volume6(const tpk_polygons *p, const double *points)
{
    if (p->face_count == 0)
        return 0;
    const double *r = points + 3 * (int64_t)p->ids[0]; /* near the cell: less cancellation than the origin */
    double sum = 0;
    for (int64_t f = 0; f < p->face_count; f++) {
        const int32_t *v = p->ids + p->starts[f];
        int64_t n = p->starts[f + 1] - p->starts[f];
        const double *a = points + 3 * (int64_t)v[0];
        for (int64_t i = 1; i + 1 < n; i++) {
            const double *b = points + 3 * (int64_t)v[i], *c = points + 3 * (int64_t)v[i + 1];
            double u[3], w[3], x[3];
            for (int k = 0; k < 3; k++) {
                u[k] = a[k] - r[k];
                w[k] = b[k] - r[k];
                x[k] = c[k] - r[k];
            }
            sum += u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0]) +
                   u[2] * (w[0] * x[1] - w[1] * x[0]);
        }
    }
    return sum;
}

/* One side of an edge as a face walks it; also (face, point) pairs when looking for repeated points. */
typedef struct edge_use {
    int32_t lo, hi, face, forward;
} edge_use;

static int compare_uses(const void *a, const void *b)
{
    const edge_use *x = a, *y = b;
    if (x->lo != y->lo)
        return (x->lo > y->lo) - (x->lo < y->lo);
    if (x->hi != y->hi)
        return (x->hi > y->hi) - (x->hi < y->hi);
    return (x->face > y->face) - (x->face < y->face);
}

/* Each face lists a point at most once. */
static int check_repeats(const tpk_polygons *p, edge_use *uses, char *why, size_t why_cap)
{
    int64_t m = p->starts[p->face_count];
    for (int64_t f = 0; f < p->face_count; f++)
        for (int64_t k = p->starts[f]; k < p->starts[f + 1]; k++)
            uses[k] = (edge_use){(int32_t)f, p->ids[k], 0, 0};
    qsort(uses, (size_t)m, sizeof *uses, compare_uses);
    for (int64_t k = 1; k < m; k++)
        if (uses[k].lo == uses[k - 1].lo && uses[k].hi == uses[k - 1].hi) {
            snprintf(why, why_cap, "face %d repeats point %d", uses[k].lo, uses[k].hi);
            return 1;
        }
    return 0;
}

/* Every edge on exactly two faces; adjacency (other face * 2 + walked the same way) in CSR form. */
static int build_adjacency(const tpk_polygons *p, edge_use *uses, int64_t *adj_start, int64_t *adj, char *why,
                           size_t why_cap)
{
    int64_t m = p->starts[p->face_count];
    for (int64_t f = 0; f < p->face_count; f++) {
        int64_t begin = p->starts[f], n = p->starts[f + 1] - begin;
        for (int64_t i = 0; i < n; i++) {
            int32_t a = p->ids[begin + i], b = p->ids[begin + (i + 1) % n];
            uses[begin + i] = (edge_use){a < b ? a : b, a < b ? b : a, (int32_t)f, a < b};
        }
    }
    qsort(uses, (size_t)m, sizeof *uses, compare_uses);
    memset(adj_start, 0, sizeof *adj_start * (size_t)(p->face_count + 1));
    for (int64_t k = 0; k < m;) {
        int64_t end = k;
        while (end < m && uses[end].lo == uses[k].lo && uses[end].hi == uses[k].hi)
            end++;
        if (end - k != 2) {
            snprintf(why, why_cap, "edge %d-%d lies on %lld face%s; a closed surface has every edge on 2",
                     uses[k].lo, uses[k].hi, (long long)(end - k), end - k == 1 ? "" : "s");
            return 1;
        }
        adj_start[uses[k].face + 1]++;
        adj_start[uses[k + 1].face + 1]++;
        k = end;
    }
    for (int64_t f = 0; f < p->face_count; f++)
        adj_start[f + 1] += adj_start[f];
    for (int64_t k = 0; k < m; k += 2) { /* fill, using adj_start[f] as a cursor, then shift back */
        int64_t same = uses[k].forward == uses[k + 1].forward;
        adj[adj_start[uses[k].face]++] = 2 * (int64_t)uses[k + 1].face + same;
        adj[adj_start[uses[k + 1].face]++] = 2 * (int64_t)uses[k].face + same;
    }
    for (int64_t f = p->face_count; f > 0; f--)
        adj_start[f] = adj_start[f - 1];
    adj_start[0] = 0;
    return 0;
}

int tpk_polygons_orient(tpk_polygons *p, char *why, size_t why_cap)
{
    int64_t faces = p->face_count, m = p->starts[faces];
    size_t bytes = sizeof(edge_use) * (size_t)m + sizeof(int64_t) * (size_t)(faces + 1 + m + faces) + (size_t)faces;
    if (bytes > p->scratch_bytes) {
        void *grown = realloc(p->scratch, bytes);
        if (!grown)
            return -1;
        p->scratch = grown;
        p->scratch_bytes = bytes;
    }
    edge_use *uses = p->scratch;
    int64_t *adj_start = (int64_t *)(uses + m), *adj = adj_start + faces + 1, *queue = adj + m;
    signed char *flip = (signed char *)(queue + faces);
    if (check_repeats(p, uses, why, why_cap) || build_adjacency(p, uses, adj_start, adj, why, why_cap))
        return 1;
    memset(flip, -1, (size_t)faces);
    int64_t head = 0, tail = 0;
    flip[0] = 0;
    queue[tail++] = 0;
    while (head < tail) { /* neighbours across an edge walked the same way must differ in flip */
        int64_t f = queue[head++];
        for (int64_t k = adj_start[f]; k < adj_start[f + 1]; k++) {
            int64_t g = adj[k] / 2;
            signed char want = (signed char)(flip[f] ^ (adj[k] & 1));
            if (flip[g] < 0) {
                flip[g] = want;
                queue[tail++] = g;
            } else if (flip[g] != want) {
                snprintf(why, why_cap, "its faces cannot be oriented consistently (faces %lld and %lld)", (long long)f,
                         (long long)g);
                return 1;
            }
        }
    }
    if (tail != faces) {
        for (int64_t f = 0; f < faces; f++)
            if (flip[f] < 0) {
                snprintf(why, why_cap, "its faces form more than one closed surface (face %lld does not connect to "
                         "face 0)", (long long)f);
                break;
            }
        return 1;
    }
    for (int64_t f = 0; f < faces; f++)
        if (flip[f])
            reverse_face(p, f);
    return 0;
}
