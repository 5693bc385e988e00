/* The decisions of the Steiner stage (steiner_internal.h): per cell a cone from its smallest vertex, a
 * star from its centre with points on the faces it does not see, or TetGen inside its fixed boundary,
 * each checked with the exact predicate; faces are cut alike from both sides through the face table,
 * in rounds until no cell asks for a change. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixed_boundary.h"
#include "steiner_internal.h"
#include "mesh/cell_types.h"

static const double *point_at(const stage *st, int32_t id)
{
    return st->out->points + 3 * (int64_t)id;
}

/* q moved onto the grid the file stores (TPK_TETRA_FILE_GRID: float32 relative to grid_origin, as
 * tools/convert/convert.c's quantize_points stores it) before anything is decided on it, so that tets
 * found positive here stay positive in the file. */
void steiner_to_file_grid(const stage *st, double q[3])
{
    for (int a = 0; st->out->on_grid && a < 3; a++)
        q[a] = st->out->grid_origin[a] + (double)(float)(q[a] - st->out->grid_origin[a]);
}

/* Is the outward triangle (a, b, c) seen from inside by `apex`: det[a, c, b, apex] > 0, exactly. */
static int sees(const stage *st, int32_t a, int32_t b, int32_t c, const double *apex)
{
    return tpk_orient3d_exact(point_at(st, a), point_at(st, c), point_at(st, b), apex) > 0;
}

int64_t steiner_face_size(const cell_work *w, int64_t f)
{
    return w->faces.starts[f + 1] - w->faces.starts[f];
}

/* Position within face f of its smallest id: fans start there, so both cells on a face cut it alike. */
static int64_t smallest_at(const cell_work *w, int64_t f)
{
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t best = 0;
    for (int64_t i = 1; i < steiner_face_size(w, f); i++)
        if (v[i] < v[best])
            best = i;
    return best;
}

/* Fan triangle i (0 .. n-3) of face f from its smallest id, outward. */
void steiner_fan_triangle(const cell_work *w, int64_t f, int64_t m, int64_t i, int32_t tri[3])
{
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t n = steiner_face_size(w, f);
    tri[0] = v[m];
    tri[1] = v[(m + i + 1) % n];
    tri[2] = v[(m + i + 2) % n];
}

/* "points 3 8 9 12" (the first few) for messages. */
static const char *face_points(const cell_work *w, int64_t f, char *text, size_t cap)
{
    size_t used = (size_t)snprintf(text, cap, "points");
    int64_t n = steiner_face_size(w, f);
    for (int64_t i = 0; i < n && i < 8 && used < cap; i++)
        used += (size_t)snprintf(text + used, cap - used, " %d", w->faces.ids[w->faces.starts[f] + i]);
    if (n > 8 && used < cap)
        snprintf(text + used, cap - used, " ...");
    return text;
}

static int grow(void **array, int64_t *cap, int64_t need, size_t size)
{
    if (need <= *cap)
        return 0;
    int64_t wanted = need > 2 * *cap ? need : 2 * *cap;
    void *grown = realloc(*array, size * (size_t)wanted);
    if (!grown)
        return -1;
    *array = grown;
    *cap = wanted;
    return 0;
}

/* Face f's ids, ascending, into w->key; returns their hash. */
static uint64_t face_key(cell_work *w, const int32_t *ids, int64_t n)
{
    int32_t *k = w->key;
    memcpy(k, ids, sizeof *k * (size_t)n);
    for (int64_t i = 1; i < n; i++) /* faces are short: insertion sort */
        for (int64_t j = i; j > 0 && k[j - 1] > k[j]; j--) {
            int32_t t = k[j];
            k[j] = k[j - 1];
            k[j - 1] = t;
        }
    return tpk_face_hash(k, (int32_t)n);
}

/* Face f's corners in an order both cells on it share, into w->ring: from its smallest id, towards the
 * smaller of that corner's two neighbours. */
static const int32_t *canonical_ring(cell_work *w, int64_t f)
{
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t n = steiner_face_size(w, f), m = smallest_at(w, f);
    int64_t step = v[(m + 1) % n] < v[(m + n - 1) % n] ? 1 : n - 1;
    for (int64_t i = 0; i < n; i++)
        w->ring[i] = v[(m + i * step) % n];
    return w->ring;
}

/* Does the fan from q over the ring fold: a triangle (r_i, r_i+1, q) facing against the ring's (Newell)
 * normal, or flat? q may be one of the corners' own point. */
static int fan_folds(const stage *st, const int32_t *ring, int64_t n, const double q[3])
{
    double normal[3] = {0, 0, 0}, (*t)[3] = malloc(sizeof *t * (size_t)n);
    if (!t)
        return 1; /* only costs the better place */
    for (int64_t i = 0; i < n; i++) {
        const double *a = point_at(st, ring[i]), *b = point_at(st, ring[(i + 1) % n]);
        double u[3] = {a[0] - q[0], a[1] - q[1], a[2] - q[2]}, v[3] = {b[0] - q[0], b[1] - q[1], b[2] - q[2]};
        t[i][0] = u[1] * v[2] - u[2] * v[1];
        t[i][1] = u[2] * v[0] - u[0] * v[2];
        t[i][2] = u[0] * v[1] - u[1] * v[0];
        for (int k = 0; k < 3; k++)
            normal[k] += t[i][k];
    }
    int folds = 0;
    for (int64_t i = 0; i < n; i++) /* from a corner (q is then that point), its own two are empty */
        folds |= point_at(st, ring[i]) != q && point_at(st, ring[(i + 1) % n]) != q &&
                 t[i][0] * normal[0] + t[i][1] * normal[1] + t[i][2] * normal[2] <= 0;
    free(t);
    return folds;
}

/* Does face f's fan from its smallest id fold: a triangle facing against the face's (Newell) normal? */
static int corner_fan_folds(stage *st, int64_t f)
{
    cell_work *w = &st->w;
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    return fan_folds(st, v, steiner_face_size(w, f), point_at(st, v[smallest_at(w, f)]));
}

/* Where face f's point goes, the same from both cells (it is computed from the canonical ring, in the
 * same order, so in floating point too): at the mean of its corners, OpenFOAM's face centre, unless the
 * fan from there folds (a non-convex face whose mean lies outside its kernel, the part of it that sees
 * every corner); then at the midpoint of the first diagonal, in ring order, whose fan does not (for a
 * quad, the diagonal through its reflex corner). pair: that diagonal's ends, or -1 for the mean (also
 * when no diagonal helps: tools/convert/fixed_boundary.c then finds the fold). */
static void place_face_point(stage *st, int64_t f, double q[3], int32_t pair[2])
{
    cell_work *w = &st->w;
    const int32_t *ring = canonical_ring(w, f);
    int64_t n = steiner_face_size(w, f);
    pair[0] = pair[1] = -1;
    q[0] = q[1] = q[2] = 0;
    for (int64_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++)
            q[a] += point_at(st, ring[i])[a] / (double)n;
    steiner_to_file_grid(st, q);
    if (!fan_folds(st, ring, n, q))
        return;
    for (int64_t i = 0; i < n; i++)
        for (int64_t j = i + 2; j < n && j - i < n - 1; j++) {
            const double *a = point_at(st, ring[i]), *b = point_at(st, ring[j]);
            double mid[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
            steiner_to_file_grid(st, mid);
            if (!fan_folds(st, ring, n, mid)) {
                memcpy(q, mid, sizeof mid);
                pair[0] = ring[i], pair[1] = ring[j];
                return;
            }
        }
}

/* A new vertex at q, the mean of `corners`, serving `cell`. Returns its id, or -1 (out of memory or
 * past the 2^31-1 vertex limit). */
int32_t steiner_push_point(stage *st, const double q[3], const int32_t *corners, int64_t count, int64_t cell)
{
    tpk_tetmesh *out = st->out;
    tpk_added_points *ad = st->added;
    if (out->vertex_count >= INT32_MAX)
        return -1;
    if (out->vertex_count == st->point_capacity) {
        int64_t cap = 2 * st->point_capacity + 64;
        double *points = realloc(out->points, sizeof *points * 3 * (size_t)cap);
        if (points)
            out->points = points;
        int32_t *source = realloc(out->vertex_source, sizeof *source * (size_t)cap);
        if (source)
            out->vertex_source = source;
        if (!points || !source)
            return -1;
        st->point_capacity = cap;
    }
    int64_t old_cap = ad->cap;
    if (grow((void **)&ad->corner_start, &ad->cap, ad->count + 2, sizeof *ad->corner_start))
        return -1;
    if (ad->cap != old_cap) { /* two cells per point, in step with corner_start */
        int32_t *cells = realloc(ad->cells, sizeof *cells * 2 * (size_t)ad->cap);
        if (!cells)
            return -1;
        ad->cells = cells;
    }
    if (grow((void **)&ad->corners, &ad->corner_cap, (ad->count ? ad->corner_start[ad->count] : 0) + count,
             sizeof *ad->corners))
        return -1;
    if (ad->count == 0)
        ad->corner_start[0] = 0;
    memcpy(ad->corners + ad->corner_start[ad->count], corners, sizeof *corners * (size_t)count);
    ad->corner_start[ad->count + 1] = ad->corner_start[ad->count] + count;
    ad->cells[2 * ad->count] = (int32_t)cell;
    ad->cells[2 * ad->count + 1] = -1;
    ad->count++;
    int32_t id = (int32_t)out->vertex_count++;
    memcpy(out->points + 3 * (int64_t)id, q, sizeof(double) * 3);
    out->vertex_source[id] = -1;
    return id;
}

/* The face point of face-table entry `at`, numbered when cell c is the first to use it. */
int32_t steiner_face_point(stage *st, int64_t at, int64_t c)
{
    tpk_face_entry *e = &st->table.entries[at];
    if (e->point >= 0) {
        int64_t added = e->point - st->src->point_count;
        if (e->cells[0] != c)
            e->cells[1] = st->added->cells[2 * added + 1] = (int32_t)c;
        return e->point;
    }
    double q[3];
    memcpy(q, e->at, sizeof q);
    int32_t pair[2] = {e->pair[0], e->pair[1]};
    int32_t id = pair[0] >= 0 ? steiner_push_point(st, q, pair, 2, c)
                              : steiner_push_point(st, q, st->table.keys + e->key_at, e->size, c);
    e = &st->table.entries[at];
    if (id >= 0) {
        e->point = id;
        e->cells[0] = (int32_t)c;
        st->out->face_steiner_points++;
    }
    return id;
}

/* ---- One cell ------------------------------------------------------------------------------------ */

static int is_split_type(int type)
{
    return type == TPK_CELL_VOXEL || type == TPK_CELL_HEXAHEDRON || type == TPK_CELL_WEDGE ||
           type == TPK_CELL_PYRAMID || type == TPK_CELL_POLYHEDRON;
}

/* The cell's faces as they are stored (not yet oriented). Returns 0 or -1 (out of memory). */
static int raw_faces(const stage *st, int64_t c, tpk_polygons *faces)
{
    const tpk_mesh *src = st->src;
    if (src->cell_types[c] == TPK_CELL_POLYHEDRON)
        return tpk_polygons_from_stream(faces, src->faces + src->face_offsets[c],
                                        src->face_offsets[c + 1] - src->face_offsets[c]);
    return tpk_polygons_from_cell(faces, src->cell_types[c], src->cell_conn + src->cell_offsets[c]);
}

/* Boundary (outward), centre and scratch of cell c. Returns 0, 1 for a cell with no valid boundary
 * (w->why says why), -1 when out of memory. */
int steiner_load_cell(stage *st, int64_t c)
{
    cell_work *w = &st->w;
    const tpk_mesh *src = st->src;
    if (raw_faces(st, c, &w->faces))
        return -1;
    int rc = tpk_polygons_orient(&w->faces, w->why, sizeof w->why);
    if (rc)
        return rc;
    double volume6 = tpk_polygons_volume6(&w->faces, st->out->points);
    if (!(volume6 != 0) || !isfinite(volume6)) {
        snprintf(w->why, sizeof w->why, "its faces enclose no volume");
        return 1;
    }
    w->mirrored = volume6 < 0; /* faces given inward (a mirrored node order): turn them out */
    if (w->mirrored)
        tpk_polygons_flip(&w->faces);
    int64_t begin = src->cell_offsets[c], corners = src->cell_offsets[c + 1] - begin;
    w->centre[0] = w->centre[1] = w->centre[2] = 0;
    for (int64_t k = 0; k < corners; k++)
        for (int a = 0; a < 3; a++)
            w->centre[a] += point_at(st, src->cell_conn[begin + k])[a] / (double)corners;
    steiner_to_file_grid(st, w->centre);
    int64_t longest = 0;
    for (int64_t f = 0; f < w->faces.face_count; f++)
        longest = steiner_face_size(w, f) > longest ? steiner_face_size(w, f) : longest;
    if (grow((void **)&w->entry, &w->entry_cap, w->faces.face_count, sizeof *w->entry) ||
        grow((void **)&w->key, &w->key_cap, longest, sizeof *w->key) ||
        grow((void **)&w->ring, &w->ring_cap, longest, sizeof *w->ring))
        return -1;
    return 0;
}

/* w->entry per face from the face table; returns how many faces carry a centre point. */
/* An entry recut_faces made for a plain face and left as it was (along the smallest-id diagonal): the
 * same as no entry. */
static int is_void(const tpk_face_entry *x)
{
    return x->diagonal && !x->changed;
}

int64_t steiner_lookup_faces(stage *st)
{
    cell_work *w = &st->w;
    int64_t found = 0;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        int64_t n = steiner_face_size(w, f);
        w->entry[f] = -1;
        if (n >= 4 && st->table.count) {
            uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], n);
            w->entry[f] = tpk_face_table_find(&st->table, w->key, (int32_t)n, hash);
            if (w->entry[f] >= 0 && is_void(&st->table.entries[w->entry[f]]))
                w->entry[f] = -1;
            found += w->entry[f] >= 0;
        }
    }
    return found;
}

/* Do corners a and b both lie on a face of the cell other than f? */
static int share_another_face(const cell_work *w, int64_t f, int32_t a, int32_t b)
{
    for (int64_t g = 0; g < w->faces.face_count; g++) {
        int hits = 0;
        for (int64_t i = 0; g != f && i < steiner_face_size(w, g); i++)
            hits += w->faces.ids[w->faces.starts[g] + i] == a || w->faces.ids[w->faces.starts[g] + i] == b;
        if (hits == 2)
            return 1;
    }
    return 0;
}

/* Does face f need a point at its centre, whatever sees it? Its fan from the smallest id triangulates it
 * only when no fan diagonal joins two corners that another face of the cell also holds: such a diagonal
 * runs along an edge that carries points (a refined neighbour's, as on OpenFOAM's split faces), and the
 * fan would lay flat or doubled triangles along it, leaving those points out and the two cells on the
 * face disagreeing about it. */
static int face_needs_point(const cell_work *w, int64_t f)
{
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t n = steiner_face_size(w, f), m = smallest_at(w, f);
    for (int64_t k = 2; k <= n - 2; k++)
        if (share_another_face(w, f, v[m], v[(m + k) % n]))
            return 1;
    return 0;
}

/* Face f's entry in the face table, with a point: added (tagged `round`, counted in *added_faces) when it
 * is not there yet or is void. Returns its index, or -1 when out of memory. */
static int64_t add_face_point(stage *st, int64_t f, int32_t round, int64_t *added_faces)
{
    cell_work *w = &st->w;
    int64_t n = steiner_face_size(w, f);
    uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], n);
    int64_t at = tpk_face_table_find(&st->table, w->key, (int32_t)n, hash);
    if (at >= 0 && !is_void(&st->table.entries[at]))
        return at;
    *added_faces += 1;
    if (at < 0 && (at = tpk_face_table_add(&st->table, w->key, (int32_t)n, hash, round)) < 0)
        return -1;
    tpk_face_entry *x = &st->table.entries[at];
    x->diagonal = 0;
    x->round = round;
    place_face_point(st, f, x->at, x->pair);
    return at;
}

/* Every tet of the cone from the smallest corner to the face triangles not touching it positive: then
 * the cone fills the cell exactly once, convex or not. (A ray from the corner into the cell must leave
 * it; every triangle it can cross faces the corner, so it crosses one, and none outside the cell.) */
static int cone_is_valid(stage *st, int64_t c)
{
    cell_work *w = &st->w;
    const int32_t *corners = st->src->cell_conn + st->src->cell_offsets[c];
    int64_t corner_count = st->src->cell_offsets[c + 1] - st->src->cell_offsets[c];
    int32_t apex = corners[0];
    for (int64_t k = 1; k < corner_count; k++)
        apex = corners[k] < apex ? corners[k] : apex;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        int64_t m = smallest_at(w, f), touches = 0;
        for (int64_t i = 0; i < steiner_face_size(w, f); i++)
            touches |= w->faces.ids[w->faces.starts[f] + i] == apex;
        for (int64_t i = 0; !touches && i + 2 < steiner_face_size(w, f); i++) {
            int32_t t[3];
            steiner_fan_triangle(w, f, m, i, t);
            if (!sees(st, t[0], t[1], t[2], point_at(st, apex)))
                return 0;
        }
    }
    return 1;
}

/* Face f split at its centre q: is every triangle (v_i, v_i+1, q) seen from the cell centre? */
static int centre_split_seen(stage *st, int64_t f, const double q[3])
{
    cell_work *w = &st->w;
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t n = steiner_face_size(w, f);
    for (int64_t i = 0; i < n; i++) {
        const double *a = point_at(st, v[i]), *b = point_at(st, v[(i + 1) % n]);
        if (tpk_orient3d_exact(a, q, b, w->centre) <= 0)
            return 0;
    }
    return 1;
}

/* Does face-table entry e (or -1) give its face a point? (A diagonal entry cuts a quad without one.) */
int steiner_has_point(const stage *st, int64_t e)
{
    return e >= 0 && !st->table.entries[e].diagonal;
}

/* Where face f's fan starts: at the smallest id, or at the first end of its entry's diagonal. */
int64_t steiner_fan_start(const stage *st, int64_t f)
{
    const cell_work *w = &st->w;
    int64_t e = w->entry[f];
    for (int64_t i = 0; e >= 0 && st->table.entries[e].diagonal && i < steiner_face_size(w, f); i++)
        if (w->faces.ids[w->faces.starts[f] + i] == st->table.entries[e].pair[0])
            return i;
    return smallest_at(w, f);
}

static int fan_seen(stage *st, int64_t f)
{
    cell_work *w = &st->w;
    int64_t m = steiner_fan_start(st, f);
    for (int64_t i = 0; i + 2 < steiner_face_size(w, f); i++) {
        int32_t t[3];
        steiner_fan_triangle(w, f, m, i, t);
        if (!sees(st, t[0], t[1], t[2], w->centre))
            return 0;
    }
    return 1;
}

/* A star from the cell centre: faces with a centre point are split there; others are fanned, or (with
 * may_add, 4 corners or more) marked NEEDS_CENTRE when only a centre split makes them visible. Returns 0,
 * or 1 with w->why. */
static int star_is_valid(stage *st, int may_add)
{
    cell_work *w = &st->w;
    char text[120];
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        int64_t n = steiner_face_size(w, f);
        double q[3];
        int32_t pair[2];
        if (steiner_has_point(st, w->entry[f])) {
            memcpy(q, st->table.entries[w->entry[f]].at, sizeof q);
        } else if (fan_seen(st, f)) {
            continue;
        } else if (n >= 4 && may_add && w->entry[f] < 0) {
            place_face_point(st, f, q, pair);
            w->entry[f] = NEEDS_CENTRE;
        } else {
            snprintf(w->why, sizeof w->why, "a point at its centre does not see face %lld (%s) from inside",
                     (long long)f, face_points(w, f, text, sizeof text));
            return 1;
        }
        if (!centre_split_seen(st, f, q)) {
            snprintf(w->why, sizeof w->why, "a point at its centre does not see face %lld (%s) from inside, "
                     "even with the face split at its own centre", (long long)f, face_points(w, f, text, sizeof text));
            return 1;
        }
    }
    return 0;
}


void steiner_local_boundary_free(local_boundary *b)
{
    free(b->triangles), free(b->ids), free(b->points);
    memset(b, 0, sizeof *b);
}

static int compare_ids(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Cell c's (loaded, looked up) boundary triangles: faces with a face point split at it, the others fanned
 * from their smallest id, exactly as the cells on their other side cut them. With `number`, face points
 * get their vertex ids (steiner_face_point). Returns 0 or -1 (out of memory). */
int steiner_local_boundary_build(stage *st, int64_t c, int number, local_boundary *b)
{
    cell_work *w = &st->w;
    int64_t count = 0, slots = 3 * (w->faces.starts[w->faces.face_count] + 1);
    memset(b, 0, sizeof *b);
    b->triangles = malloc(sizeof *b->triangles * (size_t)slots);
    b->ids = malloc(sizeof *b->ids * (size_t)slots);
    if (!b->triangles || !b->ids)
        return -1;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        const int32_t *v = w->faces.ids + w->faces.starts[f];
        int64_t n = steiner_face_size(w, f), m = steiner_fan_start(st, f), e = w->entry[f];
        int point = steiner_has_point(st, e);
        int32_t q = !point ? 0 : number ? steiner_face_point(st, e, c) : (int32_t)(-2 - e);
        if (number && q < 0)
            return -1;
        for (int64_t i = 0; i < (point ? n : n - 2); i++, count++) {
            int32_t *t = b->triangles + 3 * count;
            if (point)
                t[0] = v[i], t[1] = v[(i + 1) % n], t[2] = q;
            else
                steiner_fan_triangle(w, f, m, i, t);
        }
    }
    b->triangle_count = count;
    memcpy(b->ids, b->triangles, sizeof *b->ids * 3 * (size_t)count);
    qsort(b->ids, (size_t)(3 * count), sizeof *b->ids, compare_ids);
    for (int64_t i = 0; i < 3 * count; i++)
        if (i == 0 || b->ids[i] != b->ids[b->id_count - 1])
            b->ids[b->id_count++] = b->ids[i];
    if (!(b->points = malloc(sizeof *b->points * 3 * (size_t)b->id_count)))
        return -1;
    for (int64_t k = 0; k < b->id_count; k++) {
        const tpk_face_entry *e = b->ids[k] < 0 ? &st->table.entries[-2 - b->ids[k]] : NULL;
        if (e)
            memcpy(b->points + 3 * k, e->at, sizeof e->at);
        else
            memcpy(b->points + 3 * k, point_at(st, b->ids[k]), sizeof *b->points * 3);
    }
    for (int64_t i = 0; i < 3 * count; i++)
        b->triangles[i] = (int32_t)((int32_t *)bsearch(&b->triangles[i], b->ids, (size_t)b->id_count, sizeof *b->ids,
                                                        compare_ids) - b->ids);
    return 0;
}

/* Do cell c's (loaded, looked up) boundary triangles cross? 0, 1 with w->why, -1 when out of memory. With
 * `quick`, two that surely cross (tpk_fixed_boundary_surely_crosses, in-process) answer 1 without TetGen's
 * child process and without a why: for the search of cuts, which only goes on to the next. */
static int boundary_crosses(stage *st, int64_t c, int quick)
{
    cell_work *w = &st->w;
    local_boundary b;
    int rc = steiner_local_boundary_build(st, c, 0, &b);
    if (rc == 0 && quick &&
        tpk_fixed_boundary_surely_crosses(b.points, (int32_t)b.id_count, b.triangles, (int32_t)b.triangle_count))
        rc = 1;
    else if (rc == 0)
        rc = tpk_fixed_boundary_crossing(b.points, (int32_t)b.id_count, b.triangles, (int32_t)b.triangle_count,
                                         w->why, sizeof w->why);
    steiner_local_boundary_free(&b);
    return rc;
}

enum { RECUT_MAX = 6 }; /* quad faces searched together: 3^6 cuts at most, for a rare cell */

/* Cut o of quad face f on its entry x: 0 along the smallest-id diagonal, 1 along the other, 2 at a point. */
static void set_cut(stage *st, int64_t f, tpk_face_entry *x, int o)
{
    const cell_work *w = &st->w;
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t m = smallest_at(w, f);
    x->diagonal = o < 2;
    if (o < 2)
        x->pair[0] = v[(m + o) % 4], x->pair[1] = v[(m + o + 2) % 4];
    else
        place_face_point(st, f, x->at, x->pair);
}

static int cut_of(const stage *st, int64_t f, const tpk_face_entry *x)
{
    const cell_work *w = &st->w;
    return !x->diagonal ? 2 : x->pair[0] == w->faces.ids[w->faces.starts[f] + smallest_at(w, f)] ? 0 : 1;
}

/* Cell c's boundary triangles cross (a snapped cell folded along an edge): cut its quad faces otherwise
 * (along either diagonal, or at a point), fewest changes first, each choice checked with TetGen -d. A
 * face is recut at most once, so the rounds end; its entry is tagged with `round`, so every cell on it is
 * decided again with the new cut (a plain cut becomes an entry cutting along the smallest-id diagonal,
 * the same cut). Returns 1 when a recut uncrosses them, 0 when none does, -1 when out of memory. */
static int recut_faces(stage *st, int64_t c, int32_t round, int64_t *added_faces)
{
    cell_work *w = &st->w;
    int64_t face[RECUT_MAX], entry[RECUT_MAX];
    tpk_face_entry saved[RECUT_MAX];
    int now[RECUT_MAX], cut[RECUT_MAX], k = 0, combos = 1;
    for (int64_t f = 0; f < w->faces.face_count && k < RECUT_MAX; f++) {
        int64_t e = w->entry[f];
        if (steiner_face_size(w, f) != 4 || face_needs_point(w, f) || (e >= 0 && st->table.entries[e].changed))
            continue;
        if (e < 0) { /* a plain face: a void entry to try cuts on */
            uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], 4);
            if ((e = tpk_face_table_find(&st->table, w->key, 4, hash)) < 0 &&
                (e = tpk_face_table_add(&st->table, w->key, 4, hash, round)) < 0)
                return -1;
            set_cut(st, f, &st->table.entries[e], 0);
            w->entry[f] = e;
        }
        face[k] = f, entry[k] = e, saved[k] = st->table.entries[e];
        now[k] = cut_of(st, f, &saved[k]);
        k++, combos *= 3;
    }
    for (int changes = 1; changes <= k; changes++)
        for (int code = 0; code < combos; code++) {
            int differ = 0;
            for (int i = 0, rest = code; i < k; i++, rest /= 3)
                differ += (cut[i] = rest % 3) != now[i];
            if (differ != changes)
                continue;
            for (int i = 0; i < k; i++)
                set_cut(st, face[i], &st->table.entries[entry[i]], cut[i]);
            int crossing = boundary_crosses(st, c, 1); /* up to 3^6 - 1 of them: TetGen's fork each */
            if (crossing < 0)
                return -1;
            if (crossing)
                continue;
            for (int i = 0; i < k; i++) {
                tpk_face_entry *x = &st->table.entries[entry[i]];
                if (cut[i] == now[i]) {
                    *x = saved[i];
                    continue;
                }
                x->changed = 1;
                x->round = round;
                *added_faces += 1;
            }
            return 1;
        }
    for (int i = 0; i < k; i++)
        st->table.entries[entry[i]] = saved[i];
    return 0;
}

/* A cell no star fits is tetrahedralized inside its boundary (S_FIXED) when its boundary triangles do not
 * cross. When they do, the fans of its warped or non-convex faces are what cross: those faces whose fan
 * from the smallest id folds get a face point (registered as decide does), or if none does, every face of
 * 4 corners or more; the cell is decided again with them in the next round. When all have one already,
 * it is bad. Returns the mode, or -1 when out of memory. */
static int fixed_or_bad(stage *st, int64_t c, int32_t round, int may_add, int64_t *added_faces)
{
    cell_work *w = &st->w;
    size_t used = strlen(w->why);
    if (!tpk_fixed_boundary_available()) {
        snprintf(w->why + used, sizeof w->why - used, "; this build has no TetGen (TETPACK_WITH_TETGEN=OFF) to "
                 "tetrahedralize it inside its boundary");
        return S_BAD;
    }
    steiner_lookup_faces(st); /* drop star_is_valid's NEEDS_CENTRE marks */
    int rc = boundary_crosses(st, c, 0);
    if (rc == 1 && may_add) {
        char why[sizeof w->why]; /* the cell's own crossing, not the last cut's the search tried */
        memcpy(why, w->why, sizeof why);
        int recut = recut_faces(st, c, round, added_faces);
        rc = recut < 0 ? -1 : !recut;
        if (rc == 1)
            memcpy(w->why, why, sizeof why);
    }
    if (rc <= 0)
        return rc < 0 ? -1 : S_FIXED;
    int64_t added = 0;
    for (int pass = 0; pass < 2 && added == 0; pass++) /* the faces whose own fan folds first, then all */
        for (int64_t f = 0; may_add && f < w->faces.face_count; f++)
            if (w->entry[f] < 0 && steiner_face_size(w, f) >= 4 && (pass || corner_fan_folds(st, f)) &&
                add_face_point(st, f, round, &added) < 0)
                return -1;
    *added_faces += added;
    return added ? S_FIXED : S_BAD;
}

/* Shape of the triangle (a, b, c): 4 sqrt(3) area over the sum of its squared edges, 1 when equilateral,
 * 0 when flat. */
static double triangle_shape(const double *a, const double *b, const double *c)
{
    double u[3], v[3], w[3], n[3];
    for (int k = 0; k < 3; k++)
        u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = c[k] - b[k];
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    double edges = 0;
    for (int k = 0; k < 3; k++)
        edges += u[k] * u[k] + v[k] * v[k] + w[k] * w[k];
    return edges > 0 ? 2 * sqrt(3.0) * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / edges : 0;
}

/* The worst triangle shape of face f cut by `cut`: 0 the fan from its smallest id (a quad: along the
 * smallest-id diagonal), 1 a quad's other diagonal, 2 at the point place_face_point puts. */
static double cut_shape(stage *st, int64_t f, int cut)
{
    cell_work *w = &st->w;
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t n = steiner_face_size(w, f), m = smallest_at(w, f);
    double worst = 1;
    if (cut == 2) {
        double q[3];
        int32_t pair[2];
        place_face_point(st, f, q, pair);
        for (int64_t i = 0; i < n; i++)
            worst = fmin(worst, triangle_shape(point_at(st, v[i]), point_at(st, v[(i + 1) % n]), q));
        return worst;
    }
    int64_t from = (m + cut) % n;
    for (int64_t i = 0; i + 2 < n; i++)
        worst = fmin(worst, triangle_shape(point_at(st, v[from]), point_at(st, v[(from + i + 1) % n]),
                                           point_at(st, v[(from + i + 2) % n])));
    return worst;
}

/* A face whose plain cut leaves a triangle flatter than this is cut otherwise when that is clearly
 * better: a corner on a straight edge (a snapped face that kept a point of its finer neighbour) fanned
 * from the wrong corner gives a zero-area triangle, and near-flat tets on it. */
#define THIN_SHAPE 0.05

/* Face f (no entry yet) cut along the quad's other diagonal or at a point when its plain cut is thin and
 * the other is at least twice as good; both cells on the face decide alike (the shapes depend on the face
 * alone), and the entry tags `round` so the other is decided again. Returns the entry, -1 for none, -2
 * when out of memory. */
static int64_t recut_thin(stage *st, int64_t f, int32_t round, int64_t *added_faces)
{
    cell_work *w = &st->w;
    int64_t n = steiner_face_size(w, f);
    double plain = cut_shape(st, f, 0);
    if (plain >= THIN_SHAPE)
        return -1;
    double other = n == 4 ? cut_shape(st, f, 1) : 0, point = cut_shape(st, f, 2);
    if (fmax(other, point) < 2 * plain)
        return -1;
    st->out->thin_faces_recut++;
    if (point > other) {
        int64_t at = add_face_point(st, f, round, added_faces);
        return at < 0 ? -2 : at;
    }
    uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], 4);
    int64_t at = tpk_face_table_find(&st->table, w->key, 4, hash);
    if (at < 0 && (at = tpk_face_table_add(&st->table, w->key, 4, hash, round)) < 0)
        return -2;
    tpk_face_entry *x = &st->table.entries[at];
    set_cut(st, f, x, 1);
    x->changed = 1;
    x->round = round;
    *added_faces += 1;
    return at;
}

/* Decide cell c's split against the face table; with may_add, register the face points it needs
 * (counted in *added_faces, tagged with `round`). A cell that no star fits is tetrahedralized inside its
 * boundary (S_FIXED) when the build can, else it is bad. Returns 0 or -1 (out of memory). */
static int decide(stage *st, int64_t c, int32_t round, int may_add, int64_t *added_faces)
{
    cell_work *w = &st->w;
    uint8_t keep = st->state[c] & S_FORCED;
    int rc = steiner_load_cell(st, c);
    if (rc < 0)
        return -1;
    if (rc > 0) {
        st->state[c] = keep | S_BAD;
        return 0;
    }
    keep |= w->mirrored ? S_MIRRORED : 0;
    int64_t centred = steiner_lookup_faces(st);
    for (int64_t f = 0; may_add && f < w->faces.face_count; f++) {
        if (w->entry[f] >= 0 || steiner_face_size(w, f) < 4)
            continue;
        int64_t at = recut_thin(st, f, round, added_faces);
        if (at < -1)
            return -1;
        w->entry[f] = at;
        centred += at >= 0; /* a recut face, like a point, rules out the cone (it fans from its apex) */
    }
    for (int64_t f = 0; may_add && f < w->faces.face_count; f++) {
        if (w->entry[f] >= 0 || !face_needs_point(w, f))
            continue;
        if ((w->entry[f] = add_face_point(st, f, round, added_faces)) < 0)
            return -1;
        centred++;
    }
    if (st->src->cell_types[c] == TPK_CELL_POLYHEDRON && centred == 0 && cone_is_valid(st, c)) {
        st->state[c] = keep | S_CONE;
        return 0;
    }
    if (star_is_valid(st, may_add)) {
        int mode = fixed_or_bad(st, c, round, may_add, added_faces);
        if (mode < 0)
            return -1;
        st->state[c] = keep | (uint8_t)mode;
        return 0;
    }
    for (int64_t f = 0; f < w->faces.face_count; f++)
        if (w->entry[f] == NEEDS_CENTRE && add_face_point(st, f, round, added_faces) < 0)
            return -1;
    st->state[c] = keep | S_STAR;
    return 0;
}

/* ---- Rounds ---------------------------------------------------------------------------------------- */

/* Does cell c have a face that was given a centre point in `round`? */
static int touches_round(stage *st, int64_t c, int32_t round)
{
    cell_work *w = &st->w;
    if (raw_faces(st, c, &w->faces))
        return -1;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        int64_t n = steiner_face_size(w, f);
        if (n < 4)
            continue;
        if (grow((void **)&w->key, &w->key_cap, n, sizeof *w->key))
            return -1;
        uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], n);
        int64_t at = tpk_face_table_find(&st->table, w->key, (int32_t)n, hash);
        if (at >= 0 && st->table.entries[at].round == round)
            return 1;
    }
    return 0;
}

/* Decide the hard cells, then, while some cell asked for new face points, every cell on those faces
 * again (cells whose plain split was kept become S_FORCED). Returns 0 or -1 (out of memory). */
int steiner_run_rounds(stage *st, const int64_t *hard, int64_t hard_count)
{
    int64_t *work = malloc(sizeof *work * (size_t)(hard_count ? hard_count : 1)), work_count = hard_count;
    int64_t work_cap = hard_count ? hard_count : 1;
    if (!work)
        return -1;
    memcpy(work, hard, sizeof *work * (size_t)hard_count);
    for (int32_t round = 0;; round++) {
        int64_t added_faces = 0;
        for (int64_t i = 0; i < work_count; i++)
            if (decide(st, work[i], round, 1, &added_faces)) {
                free(work);
                return -1;
            }
        if (added_faces == 0)
            break;
        work_count = 0;
        for (int64_t c = 0; c < st->src->cell_count; c++) {
            if (!is_split_type(st->src->cell_types[c]))
                continue;
            int touches = touches_round(st, c, round);
            if (touches < 0 || (touches && grow((void **)&work, &work_cap, work_count + 1, sizeof *work))) {
                free(work);
                return -1;
            }
            if (!touches)
                continue;
            if ((st->state[c] & S_MODE) == S_NONE)
                st->state[c] = S_FORCED | S_PENDING;
            work[work_count++] = c;
        }
    }
    free(work);
    return 0;
}

/* Drop the plain tets of cells that now take a face point; they are split again below. */
void steiner_drop_forced_tets(stage *st)
{
    tpk_tetmesh *out = st->out;
    int64_t kept = 0;
    for (int64_t t = 0; t < out->tet_count;) {
        int32_t c = out->tet_source[t];
        int64_t end = t;
        while (end < out->tet_count && out->tet_source[end] == c)
            end++;
        if (st->state[c] & S_FORCED) {
            out->cells_into[end - t]--;
            out->mirrored_cells -= (st->state[c] & S_MIRRORED) != 0; /* counted again if it splits */
        } else {
            memmove(out->tets + 4 * kept, out->tets + 4 * t, sizeof *out->tets * 4 * (size_t)(end - t));
            memmove(out->tet_source + kept, out->tet_source + t, sizeof *out->tet_source * (size_t)(end - t));
            kept += end - t;
        }
        t = end;
    }
    out->tet_count = kept;
}

/* The first bad cell is an error naming it and saying why, unless bad cells are skipped. */
int steiner_report_bad(stage *st, tpk_diag *diag)
{
    int64_t first = -1;
    for (int64_t c = 0; c < st->src->cell_count; c++)
        if ((st->state[c] & S_MODE) == S_BAD) {
            st->out->bad_cells_skipped++;
            first = first < 0 ? c : first;
        }
    if (first < 0 || (st->flags & TPK_TETRA_SKIP_BAD_CELLS))
        return 0;
    int64_t none = 0;
    if (decide(st, first, -1, 1, &none)) /* again, for the reason */
        return -1;
    tpk_diag_fail(diag, "cell %lld (a %s) is too warped, non-convex or degenerate to split: %s; pass "
                  "--skip-bad-cells to leave such cells out", (long long)first,
                  tpk_cell_type(st->src->cell_types[first])->name, st->w.why);
    return -2;
}
