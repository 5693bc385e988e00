/* Warped cells and polyhedra into tets from added points (tools/convert/steiner.h): per cell a cone or a star,
 * checked with the exact predicate; face points shared through a face table, in rounds until no cell
 * asks for another. */
#include "steiner.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/cell_types.h"
#include "face_table.h"
#include "pipeline.h"
#include "mesh/polyhedron.h"

/* Per-cell state: a mode, and flags. */
enum { S_NONE, S_PENDING, S_STAR, S_CONE, S_BAD, S_MODE = 7, S_FORCED = 8, S_MIRRORED = 16 };
enum { NEEDS_CENTRE = -2 }; /* cell_work.entry: a face this cell wants split at its centre */

typedef struct cell_work {
    tpk_polygons faces;   /* the cell's boundary, outward */
    int64_t *entry;       /* per face: its face-table entry, -1, or NEEDS_CENTRE */
    int64_t entry_cap;
    int32_t *key;         /* one face's ids, ascending */
    int64_t key_cap;
    int mirrored;
    double centre[3];
    char why[320];
} cell_work;

typedef struct stage {
    const tpk_mesh *src;
    tpk_tetmesh *out;
    tpk_added_points *added;
    int64_t *tet_capacity;
    int64_t point_capacity;
    int flags;
    uint8_t *state;
    tpk_face_table table;
    cell_work w;
} stage;

void tpk_added_points_free(tpk_added_points *added)
{
    free(added->corner_start);
    free(added->corners);
    free(added->cells);
    memset(added, 0, sizeof *added);
}

static const double *point_at(const stage *st, int32_t id)
{
    return st->out->points + 3 * (int64_t)id;
}

/* Is the outward triangle (a, b, c) seen from inside by `apex`: det[a, c, b, apex] > 0, exactly. */
static int sees(const stage *st, int32_t a, int32_t b, int32_t c, const double *apex)
{
    return tpk_orient3d_exact(point_at(st, a), point_at(st, c), point_at(st, b), apex) > 0;
}

static int64_t face_size(const cell_work *w, int64_t f)
{
    return w->faces.starts[f + 1] - w->faces.starts[f];
}

/* Position within face f of its smallest id: fans start there, so both cells on a face cut it alike. */
static int64_t smallest_at(const cell_work *w, int64_t f)
{
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t best = 0;
    for (int64_t i = 1; i < face_size(w, f); i++)
        if (v[i] < v[best])
            best = i;
    return best;
}

/* Fan triangle i (0 .. n-3) of face f from its smallest id, outward. */
static void fan_triangle(const cell_work *w, int64_t f, int64_t m, int64_t i, int32_t tri[3])
{
    const int32_t *v = w->faces.ids + w->faces.starts[f];
    int64_t n = face_size(w, f);
    tri[0] = v[m];
    tri[1] = v[(m + i + 1) % n];
    tri[2] = v[(m + i + 2) % n];
}

/* "points 3 8 9 12" (the first few) for messages. */
static const char *face_points(const cell_work *w, int64_t f, char *text, size_t cap)
{
    size_t used = (size_t)snprintf(text, cap, "points");
    int64_t n = face_size(w, f);
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

/* The centre of a face from its sorted ids: the same bits whichever cell computes it. */
static void key_centre(const stage *st, const int32_t *sorted, int64_t n, double q[3])
{
    q[0] = q[1] = q[2] = 0;
    for (int64_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++)
            q[a] += point_at(st, sorted[i])[a];
    for (int a = 0; a < 3; a++)
        q[a] /= (double)n;
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
static int load_cell(stage *st, int64_t c)
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
    int64_t longest = 0;
    for (int64_t f = 0; f < w->faces.face_count; f++)
        longest = face_size(w, f) > longest ? face_size(w, f) : longest;
    if (grow((void **)&w->entry, &w->entry_cap, w->faces.face_count, sizeof *w->entry) ||
        grow((void **)&w->key, &w->key_cap, longest, sizeof *w->key))
        return -1;
    return 0;
}

/* w->entry per face from the face table; returns how many faces carry a centre point. */
static int64_t lookup_faces(stage *st)
{
    cell_work *w = &st->w;
    int64_t found = 0;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        int64_t n = face_size(w, f);
        w->entry[f] = -1;
        if (n >= 4 && st->table.count) {
            uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], n);
            w->entry[f] = tpk_face_table_find(&st->table, w->key, (int32_t)n, hash);
            found += w->entry[f] >= 0;
        }
    }
    return found;
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
        for (int64_t i = 0; i < face_size(w, f); i++)
            touches |= w->faces.ids[w->faces.starts[f] + i] == apex;
        for (int64_t i = 0; !touches && i + 2 < face_size(w, f); i++) {
            int32_t t[3];
            fan_triangle(w, f, m, i, t);
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
    int64_t n = face_size(w, f);
    for (int64_t i = 0; i < n; i++) {
        const double *a = point_at(st, v[i]), *b = point_at(st, v[(i + 1) % n]);
        if (tpk_orient3d_exact(a, q, b, w->centre) <= 0)
            return 0;
    }
    return 1;
}

static int fan_seen(stage *st, int64_t f)
{
    cell_work *w = &st->w;
    int64_t m = smallest_at(w, f);
    for (int64_t i = 0; i + 2 < face_size(w, f); i++) {
        int32_t t[3];
        fan_triangle(w, f, m, i, t);
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
        int64_t n = face_size(w, f);
        double q[3];
        if (w->entry[f] >= 0) {
            const tpk_face_entry *e = &st->table.entries[w->entry[f]];
            key_centre(st, st->table.keys + e->key_at, e->size, q);
        } else if (fan_seen(st, f)) {
            continue;
        } else if (n >= 4 && may_add) {
            face_key(w, w->faces.ids + w->faces.starts[f], n);
            key_centre(st, w->key, n, q);
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

/* Decide cell c's split against the face table; with may_add, register the face points it needs
 * (counted in *added_faces, tagged with `round`). Returns 0 or -1 (out of memory). */
static int decide(stage *st, int64_t c, int32_t round, int may_add, int64_t *added_faces)
{
    cell_work *w = &st->w;
    uint8_t keep = st->state[c] & S_FORCED;
    int rc = load_cell(st, c);
    if (rc < 0)
        return -1;
    if (rc > 0) {
        st->state[c] = keep | S_BAD;
        return 0;
    }
    keep |= w->mirrored ? S_MIRRORED : 0;
    int64_t centred = lookup_faces(st);
    if (st->src->cell_types[c] == TPK_CELL_POLYHEDRON && centred == 0 && cone_is_valid(st, c)) {
        st->state[c] = keep | S_CONE;
        return 0;
    }
    if (star_is_valid(st, may_add)) {
        st->state[c] = keep | S_BAD;
        return 0;
    }
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        if (w->entry[f] != NEEDS_CENTRE)
            continue;
        int64_t n = face_size(w, f);
        uint64_t hash = face_key(w, w->faces.ids + w->faces.starts[f], n);
        int64_t at = tpk_face_table_find(&st->table, w->key, (int32_t)n, hash);
        if (at < 0 && tpk_face_table_add(&st->table, w->key, (int32_t)n, hash, round) < 0)
            return -1;
        *added_faces += at < 0;
    }
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
        int64_t n = face_size(w, f);
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
static int run_rounds(stage *st, const int64_t *hard, int64_t hard_count)
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
static void drop_forced_tets(stage *st)
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
static int report_bad(stage *st, tpk_diag *diag)
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

/* ---- Emission -------------------------------------------------------------------------------------- */

static int push_tet(stage *st, int32_t a, int32_t b, int32_t c, int32_t d, int64_t cell)
{
    tpk_tetmesh *out = st->out;
    if (out->tet_count == *st->tet_capacity) {
        int64_t cap = 2 * *st->tet_capacity + 64;
        int32_t *tets = realloc(out->tets, sizeof *tets * 4 * (size_t)cap);
        if (tets)
            out->tets = tets;
        int32_t *source = realloc(out->tet_source, sizeof *source * (size_t)cap);
        if (source)
            out->tet_source = source;
        if (!tets || !source)
            return -1;
        *st->tet_capacity = cap;
    }
    int32_t *t = out->tets + 4 * out->tet_count;
    t[0] = a, t[1] = b, t[2] = c, t[3] = d;
    out->tet_source[out->tet_count++] = (int32_t)cell;
    return 0;
}

/* A new vertex at q, the mean of `corners`, serving `cell`. Returns its id, or -1 (out of memory or
 * past the 2^31-1 vertex limit). */
static int32_t push_point(stage *st, const double q[3], const int32_t *corners, int64_t count, int64_t cell)
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
static int32_t face_point(stage *st, int64_t at, int64_t c)
{
    tpk_face_entry *e = &st->table.entries[at];
    if (e->point >= 0) {
        int64_t added = e->point - st->src->point_count;
        if (e->cells[0] != c)
            e->cells[1] = st->added->cells[2 * added + 1] = (int32_t)c;
        return e->point;
    }
    double q[3];
    key_centre(st, st->table.keys + e->key_at, e->size, q);
    int32_t id = push_point(st, q, st->table.keys + e->key_at, e->size, c);
    e = &st->table.entries[at];
    if (id >= 0) {
        e->point = id;
        e->cells[0] = (int32_t)c;
        st->out->face_steiner_points++;
    }
    return id;
}

/* Tets of a decided cell: its cone, or its star (adding its centre and any new face points). */
static int emit_cell(stage *st, int64_t c, int cone)
{
    cell_work *w = &st->w;
    const tpk_mesh *src = st->src;
    const int32_t *corners = src->cell_conn + src->cell_offsets[c];
    int64_t corner_count = src->cell_offsets[c + 1] - src->cell_offsets[c];
    if (load_cell(st, c))
        return -1; /* it loaded when decided: only memory can fail now */
    lookup_faces(st);
    int32_t apex = corners[0];
    for (int64_t k = 1; cone && k < corner_count; k++)
        apex = corners[k] < apex ? corners[k] : apex;
    if (!cone && (apex = push_point(st, w->centre, corners, corner_count, c)) < 0)
        return -1;
    for (int64_t f = 0; f < w->faces.face_count; f++) {
        const int32_t *v = w->faces.ids + w->faces.starts[f];
        int64_t n = face_size(w, f), m = smallest_at(w, f), touches = 0;
        if (w->entry[f] >= 0) {
            int32_t q = face_point(st, w->entry[f], c);
            if (q < 0)
                return -1;
            v = w->faces.ids + w->faces.starts[f]; /* face_point may not move it, but be plain */
            for (int64_t i = 0; i < n; i++)
                if (push_tet(st, v[i], q, v[(i + 1) % n], apex, c))
                    return -1;
            continue;
        }
        for (int64_t i = 0; i < n; i++)
            touches |= v[i] == apex;
        for (int64_t i = 0; !touches && i + 2 < n; i++) {
            int32_t t[3];
            fan_triangle(w, f, m, i, t);
            if (push_tet(st, t[0], t[2], t[1], apex, c))
                return -1;
        }
    }
    st->out->steiner_cells += !cone;
    st->out->polyhedra += src->cell_types[c] == TPK_CELL_POLYHEDRON;
    if (w->mirrored && (st->out->mirrored_cells == 0 || c < st->out->first_mirrored_cell))
        st->out->first_mirrored_cell = c;
    st->out->mirrored_cells += w->mirrored;
    return 0;
}

int tpk_steiner_stage(const tpk_mesh *src, const int64_t *hard, int64_t hard_count, int flags,
                      int64_t *tet_capacity, tpk_tetmesh *out, tpk_added_points *added, tpk_diag *diag)
{
    stage st;
    memset(&st, 0, sizeof st);
    st.src = src, st.out = out, st.added = added, st.flags = flags;
    st.tet_capacity = tet_capacity;
    st.point_capacity = out->vertex_count;
    st.state = calloc((size_t)(src->cell_count ? src->cell_count : 1), 1);
    int rc = st.state ? 0 : -1;
    for (int64_t i = 0; rc == 0 && i < hard_count; i++)
        st.state[hard[i]] = S_PENDING;
    if (rc == 0)
        rc = run_rounds(&st, hard, hard_count);
    if (rc == 0) {
        drop_forced_tets(&st);
        rc = report_bad(&st, diag);
    }
    for (int64_t c = 0; rc == 0 && c < src->cell_count; c++) {
        int mode = st.state[c] & S_MODE;
        if (mode == S_STAR || mode == S_CONE)
            rc = emit_cell(&st, c, mode == S_CONE);
    }
    if (rc == -1 && out->vertex_count >= INT32_MAX) {
        tpk_diag_fail(diag, "the points added to split cells pass the limit of 2^31-1 vertices per file; split "
                      "the mesh into parts");
        rc = -2;
    }
    free(st.state);
    tpk_face_table_free(&st.table);
    tpk_polygons_free(&st.w.faces);
    free(st.w.entry);
    free(st.w.key);
    return rc;
}
