/* VTKHDF importer: the partitions of a step as one mesh. Each partition's point ids are its own; points
 * of different partitions with the same coordinates (== on each axis) become one point, the first one's,
 * as a partitioned writer repeats the points on the boundaries between partitions. Points repeated
 * inside one partition stay apart (that is the file's own mesh: `convert --merge-duplicates` merges
 * them). Cells are kept (higher-order ones whole) or dropped by tpk_cell_rule_for, as the VTU reader does. */
#include <stdlib.h>
#include <string.h>

#include "import_vtkhdf_internal.h"
#include "base/parallel.h"
#include "mesh/cell_types.h"
#include "mesh/polyhedron.h"

/* Sums of counts[0 .. n) before each entry, into a malloc'd array of n + 1; NULL on overflow or memory. */
static int64_t *starts_of(const int64_t *counts, int64_t n, int64_t extra)
{
    int64_t *s = malloc(sizeof *s * (size_t)(n + 1));
    if (!s)
        return NULL;
    s[0] = 0;
    for (int64_t i = 0; i < n; i++) {
        if (counts[i] < 0 || counts[i] > INT64_MAX / 4 - s[i] - extra) {
            free(s);
            return NULL;
        }
        s[i + 1] = s[i] + counts[i] + extra;
    }
    return s;
}

static int read_counts(vh_reader *r, const char *name, int64_t **counts, int64_t **starts, int64_t extra)
{
    if (vh_read_ints(r, name, r->partitions, counts, NULL))
        return -1;
    for (int64_t p = 0; p < r->partitions; p++)
        if ((*counts)[p] < 0)
            return vh_fail(r, "/VTKHDF/%s: expected counts of 0 or more, found %lld for partition %lld", name,
                           (long long)(*counts)[p], (long long)p);
    if (!(*starts = starts_of(*counts, r->partitions, extra)))
        return vh_fail(r, "/VTKHDF/%s: the counts add up to more than a file holds", name);
    return 0;
}

int vh_read_partitions(vh_reader *r)
{
    int64_t *unused = NULL;
    if (vh_read_ints(r, "NumberOfPoints", -1, &r->part_points, &r->partitions))
        return -1;
    int rc = read_counts(r, "NumberOfPoints", &unused, &r->point_start, 0);
    free(unused);
    if (rc || read_counts(r, "NumberOfCells", &r->part_cells, &r->cell_start, 0) ||
        read_counts(r, "NumberOfConnectivityIds", &r->part_conn, &r->conn_start, 0))
        return -1;
    r->polyhedra = vh_exists(r->root, "FaceConnectivity") || vh_exists(r->root, "PolyhedronToFaces");
    if (r->polyhedra && (read_counts(r, "NumberOfFaces", &r->part_faces, &r->face_start, 0) ||
                         read_counts(r, "NumberOfFaceConnectivityIds", &r->part_face_conn, &r->face_conn_start, 0) ||
                         read_counts(r, "NumberOfPolyhedronToFaceIds", &r->part_poly_faces, &r->poly_face_start, 0)))
        return -1;
    return 0;
}

/* ---- points ---------------------------------------------------------------------------------------- */

typedef struct point_key {
    double x[3];
    int64_t raw;  /* index among the step's points, in partition order */
    int64_t part;
} point_key;

static int compare_keys(const void *pa, const void *pb)
{
    const point_key *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a->x[k] != b->x[k])
            return a->x[k] < b->x[k] ? -1 : 1;
    return (a->raw > b->raw) - (a->raw < b->raw);
}

/* merged[raw] for every raw point; returns the merged count (or -1 out of memory). NaN coordinates
 * compare as neither smaller nor larger: such points keep their own id (sorted anywhere, they match
 * nothing, as x != x). */
static int64_t merge_points(const double *xyz, const int64_t *part_of, int64_t n, int32_t *merged)
{
    point_key *keys = malloc(sizeof *keys * (size_t)(n ? n : 1));
    int64_t *rep = malloc(sizeof *rep * (size_t)(n ? n : 1));
    if (!keys || !rep) {
        free(keys);
        free(rep);
        return -1;
    }
    for (int64_t i = 0; i < n; i++) {
        memcpy(keys[i].x, xyz + 3 * i, sizeof keys[i].x);
        keys[i].raw = i;
        keys[i].part = part_of[i];
        rep[i] = i;
    }
    qsort(keys, (size_t)n, sizeof *keys, compare_keys);
    for (int64_t g = 0; g < n;) {
        int64_t e = g + 1;
        while (e < n && !memcmp(keys[e].x, keys[g].x, sizeof keys[g].x) && keys[g].x[0] == keys[g].x[0])
            e++;
        /* keys[g] is the group's first point (lowest raw id, so lowest partition): points of other
         * partitions join it. */
        for (int64_t i = g + 1; i < e; i++)
            if (keys[i].part != keys[g].part)
                rep[keys[i].raw] = keys[g].raw;
        g = e;
    }
    int64_t kept = 0;
    for (int64_t i = 0; i < n; i++)
        merged[i] = rep[i] == i ? (int32_t)kept++ : merged[rep[i]];
    free(keys);
    free(rep);
    return kept;
}

/* The step's points, merged: out->points, merged_of (raw -> merged), first_raw (merged -> raw). */
static int read_points(vh_reader *r, const vh_step *s, tpk_mesh *out, int32_t **merged_of, int64_t **first_raw,
                       int64_t *raw_count)
{
    int64_t first = r->point_start[s->part0], n = r->point_start[s->part0 + s->parts] - first;
    if (n > INT32_MAX)
        return vh_fail(r, "/VTKHDF/Points: %lld points in a step, more than tetpack holds (2^31 - 1)", (long long)n);
    double *xyz = malloc(sizeof *xyz * 3 * (size_t)(n ? n : 1));
    int64_t *part_of = malloc(sizeof *part_of * (size_t)(n ? n : 1));
    *merged_of = malloc(sizeof **merged_of * (size_t)(n ? n : 1));
    *first_raw = malloc(sizeof **first_raw * (size_t)(n ? n : 1));
    if (!xyz || !part_of || !*merged_of || !*first_raw) {
        free(xyz);
        free(part_of);
        return vh_fail(r, "out of memory for %lld points", (long long)n);
    }
    char what[64];
    snprintf(what, sizeof what, "the points of partitions %lld to %lld", (long long)s->part0,
             (long long)(s->part0 + s->parts - 1));
    int rc = vh_read_rows(r, "Points", first, n, 3, H5T_NATIVE_DOUBLE, xyz, what);
    for (int64_t p = s->part0; rc == 0 && p < s->part0 + s->parts; p++)
        for (int64_t i = r->point_start[p]; i < r->point_start[p + 1]; i++)
            part_of[i - first] = p;
    int64_t kept = rc ? 0 : s->parts > 1 ? merge_points(xyz, part_of, n, *merged_of) : n;
    if (rc == 0 && kept < 0)
        rc = vh_fail(r, "out of memory merging %lld points", (long long)n);
    if (rc == 0 && s->parts <= 1)
        for (int64_t i = 0; i < n; i++)
            (*merged_of)[i] = (int32_t)i;
    if (rc == 0) {
        for (int64_t i = n - 1; i >= 0; i--)
            (*first_raw)[(*merged_of)[i]] = i;
        for (int64_t i = 0; i < kept; i++)
            memcpy(xyz + 3 * i, xyz + 3 * (*first_raw)[i], 3 * sizeof *xyz);
        out->point_count = kept;
        out->points = xyz;
        *raw_count = n;
        xyz = NULL;
    }
    free(xyz);
    free(part_of);
    return rc;
}

/* ---- cells ------------------------------------------------------------------------------------------ */

/* One partition's cell arrays, its ids local to it. */
typedef struct part_cells {
    int64_t cells, conn_count;
    uint8_t *types;
    int64_t *offsets, *conn;
    int64_t faces, face_conn_count, poly_face_count;
    int64_t *poly_offsets, *poly_faces, *face_offsets, *face_conn;
} part_cells;

static void part_cells_free(part_cells *c)
{
    free(c->types);
    free(c->offsets);
    free(c->conn);
    free(c->poly_offsets);
    free(c->poly_faces);
    free(c->face_offsets);
    free(c->face_conn);
    memset(c, 0, sizeof *c);
}

static int read_part_array(vh_reader *r, const char *path, int64_t first, int64_t count, hid_t type, size_t size,
                           void **dst, int64_t p)
{
    char what[64];
    snprintf(what, sizeof what, "partition %lld", (long long)p);
    if (!(*dst = malloc(size * (size_t)(count ? count : 1))))
        return vh_fail(r, "/VTKHDF/%s: %s: out of memory for %lld values", path, what, (long long)count);
    return vh_read_rows(r, path, first, count, 1, type, *dst, what);
}

/* Offsets must start at 0, never decrease and end at `total`. */
static int check_offsets(vh_reader *r, const char *path, const int64_t *offsets, int64_t cells, int64_t total,
                         int64_t p)
{
    for (int64_t c = 0; c <= cells; c++) {
        int64_t want_min = c ? offsets[c - 1] : 0;
        if ((c == 0 && offsets[0] != 0) || offsets[c] < want_min || offsets[c] > total ||
            (c == cells && offsets[c] != total))
            return vh_fail(r, "/VTKHDF/%s: partition %lld, entry %lld: expected %s, found %lld", path, (long long)p,
                           (long long)c,
                           c == 0 ? "0" : c == cells ? "the partition's id count" : "offsets that never decrease",
                           (long long)offsets[c]);
    }
    (void)total;
    return 0;
}

static int read_part_cells(vh_reader *r, int64_t p, part_cells *c)
{
    memset(c, 0, sizeof *c);
    c->cells = r->part_cells[p];
    c->conn_count = r->part_conn[p];
    int64_t off0 = r->cell_start[p] + p; /* each partition's Offsets has one entry more than cells */
    if (read_part_array(r, "Types", r->cell_start[p], c->cells, H5T_NATIVE_UINT8, 1, (void **)&c->types, p) ||
        read_part_array(r, "Offsets", off0, c->cells + 1, H5T_NATIVE_INT64, 8, (void **)&c->offsets, p) ||
        read_part_array(r, "Connectivity", r->conn_start[p], c->conn_count, H5T_NATIVE_INT64, 8, (void **)&c->conn, p) ||
        check_offsets(r, "Offsets", c->offsets, c->cells, c->conn_count, p))
        return -1;
    if (!r->polyhedra)
        return 0;
    c->faces = r->part_faces[p];
    c->face_conn_count = r->part_face_conn[p];
    c->poly_face_count = r->part_poly_faces[p];
    if (read_part_array(r, "PolyhedronOffsets", off0, c->cells + 1, H5T_NATIVE_INT64, 8, (void **)&c->poly_offsets, p) ||
        read_part_array(r, "PolyhedronToFaces", r->poly_face_start[p], c->poly_face_count, H5T_NATIVE_INT64, 8,
                        (void **)&c->poly_faces, p) ||
        read_part_array(r, "FaceOffsets", r->face_start[p] + p, c->faces + 1, H5T_NATIVE_INT64, 8,
                        (void **)&c->face_offsets, p) ||
        read_part_array(r, "FaceConnectivity", r->face_conn_start[p], c->face_conn_count, H5T_NATIVE_INT64, 8,
                        (void **)&c->face_conn, p) ||
        check_offsets(r, "PolyhedronOffsets", c->poly_offsets, c->cells, c->poly_face_count, p) ||
        check_offsets(r, "FaceOffsets", c->face_offsets, c->faces, c->face_conn_count, p))
        return -1;
    return 0;
}

/* Growable output arrays. */
typedef struct cell_out {
    int64_t count, cap, off_cap, conn_count, conn_cap;
    uint8_t *types;
    int64_t *offsets;
    int32_t *conn;
    uint8_t *kept;  /* per source cell of the step */
    int64_t source_cells;
} cell_out;

static int grow(void **p, int64_t *cap, int64_t need, size_t size)
{
    if (need <= *cap)
        return 0;
    int64_t n = *cap ? *cap : 1024;
    while (n < need)
        n *= 2;
    void *g = realloc(*p, size * (size_t)n);
    if (!g)
        return -1;
    *p = g;
    *cap = n;
    return 0;
}

static int put_id(vh_reader *r, cell_out *o, int64_t p, int64_t id, int64_t base,
                  const int32_t *merged_of, const char *path, int64_t at)
{
    if (id < 0 || id >= r->part_points[p])
        return vh_fail(r, "/VTKHDF/%s: partition %lld, entry %lld: expected a point id below %lld (the "
                       "partition's NumberOfPoints), found %lld", path, (long long)p, (long long)at,
                       (long long)r->part_points[p], (long long)id);
    o->conn[o->conn_count++] = merged_of[base + id];
    return 0;
}

/* A polyhedron's VTK face stream (nfaces, then npts and ids per face) into o->conn. */
static int put_polyhedron(vh_reader *r, cell_out *o, const part_cells *pc, int64_t p, int64_t c, int64_t base,
                          const int32_t *merged_of)
{
    int64_t f0 = pc->poly_offsets[c], f1 = pc->poly_offsets[c + 1], need = 1;
    for (int64_t k = f0; k < f1; k++) {
        int64_t f = pc->poly_faces[k];
        if (f < 0 || f >= pc->faces)
            return vh_fail(r, "/VTKHDF/PolyhedronToFaces: partition %lld, entry %lld: expected a face id below %lld "
                           "(NumberOfFaces), found %lld", (long long)p, (long long)k, (long long)pc->faces, (long long)f);
        need += 1 + pc->face_offsets[f + 1] - pc->face_offsets[f];
    }
    if (need > INT32_MAX || grow((void **)&o->conn, &o->conn_cap, o->conn_count + need, sizeof *o->conn))
        return vh_fail(r, "out of memory for polyhedron %lld of partition %lld", (long long)c, (long long)p);
    int64_t start = o->conn_count;
    o->conn[o->conn_count++] = (int32_t)(f1 - f0);
    for (int64_t k = f0; k < f1; k++) {
        int64_t f = pc->poly_faces[k];
        o->conn[o->conn_count++] = (int32_t)(pc->face_offsets[f + 1] - pc->face_offsets[f]);
        for (int64_t j = pc->face_offsets[f]; j < pc->face_offsets[f + 1]; j++)
            if (put_id(r, o, p, pc->face_conn[j], base, merged_of, "FaceConnectivity", j))
                return -1;
    }
    char why[160];
    int64_t bad_at;
    if (tpk_face_stream_check(o->conn + start, need, INT32_MAX, &bad_at, why, sizeof why))
        return vh_fail(r, "partition %lld, cell %lld (a polyhedron): its faces: %s", (long long)p, (long long)c, why);
    return 0;
}

/* A partition without polyhedra whose every cell reads cleanly, on all threads (HDF5 itself reads one
 * call at a time: this library build is thread-safe by one global lock, so hyperslabs read on several
 * threads would wait on each other; the conversion after the read is what runs in parallel). First each
 * worker checks its cells (rule, point count, ids) and counts what it keeps; then, the offsets known,
 * each writes its cells where add_part_cells would. Any cell that needs a message leaves the whole
 * partition to add_part_cells, which words it. */
typedef struct fast_cells {
    const part_cells *pc;
    cell_out *o;
    const int32_t *merged_of;
    int64_t base, points;
    tpk_cell_rule rule[256];
    int64_t count0, conn0, source0; /* o's counts before the partition */
    int bad[TPK_MAX_THREADS];
    int64_t kept[TPK_MAX_THREADS], ids[TPK_MAX_THREADS];
    int64_t dropped[TPK_MAX_THREADS][256];
} fast_cells;

static void fast_check(void *ctx, int64_t begin, int64_t end, int w)
{
    fast_cells *f = ctx;
    const part_cells *pc = f->pc;
    int64_t kept = 0, ids = 0;
    for (int64_t c = begin; c < end; c++) {
        int type = pc->types[c];
        const tpk_cell_rule *rule = &f->rule[type];
        int64_t n = pc->offsets[c + 1] - pc->offsets[c];
        if (rule->kind == TPK_RULE_DROP) {
            f->dropped[w][type]++;
            continue;
        }
        if (rule->kind != TPK_RULE_KEEP || type == TPK_CELL_POLYHEDRON ||
            (rule->nodes > 0 && n != rule->nodes) || (rule->nodes < 0 && n < -rule->nodes)) {
            f->bad[w] = 1;
            return;
        }
        const int64_t *id = pc->conn + pc->offsets[c];
        int ok = 1;
        for (int64_t j = 0; j < n; j++)
            ok &= id[j] >= 0 && id[j] < f->points;
        if (!ok) {
            f->bad[w] = 1;
            return;
        }
        kept++;
        ids += n;
    }
    f->kept[w] = kept;
    f->ids[w] = ids;
}

/* Worker w's cells, its first kept cell and id slot in kept[w] and ids[w] (prefix sums by then). */
static void fast_fill(void *ctx, int64_t begin, int64_t end, int w)
{
    fast_cells *f = ctx;
    const part_cells *pc = f->pc;
    cell_out *o = f->o;
    int64_t k = f->count0 + f->kept[w], at = f->conn0 + f->ids[w];
    for (int64_t c = begin; c < end; c++) {
        int type = pc->types[c];
        const tpk_cell_rule *rule = &f->rule[type];
        o->kept[f->source0 + c] = rule->kind == TPK_RULE_KEEP;
        if (rule->kind != TPK_RULE_KEEP)
            continue;
        const int64_t *id = pc->conn + pc->offsets[c];
        int64_t n = pc->offsets[c + 1] - pc->offsets[c];
        for (int64_t j = 0; j < n; j++)
            o->conn[at + j] = f->merged_of[f->base + id[j]];
        at += n;
        o->types[k] = (uint8_t)rule->out_type;
        o->offsets[++k] = at;
    }
}

/* 1: left to add_part_cells (a cell needs a message, or polyhedra); 0: added; -1: out of memory. */
static int add_part_cells_fast(vh_reader *r, cell_out *o, const part_cells *pc, int64_t p, int64_t base,
                               const int32_t *merged_of, int64_t *dropped)
{
    /* two passes over the ids cost more than one: on one thread the one-pass loop is quicker */
    int threads = tpk_threads_for(pc->cells, tpk_thread_count(0), 65536);
    if (r->polyhedra || threads < 2)
        return 1;
    fast_cells *f = calloc(1, sizeof *f);
    if (!f)
        return 1;
    *f = (fast_cells){.pc = pc, .o = o, .merged_of = merged_of, .base = base, .points = r->part_points[p],
                      .count0 = o->count, .conn0 = o->conn_count, .source0 = o->source_cells};
    for (int t = 0; t < 256; t++)
        f->rule[t] = tpk_cell_rule_for(t);
    tpk_parallel_for(pc->cells, threads, fast_check, f);
    int64_t kept = 0, ids = 0;
    int bad = 0;
    for (int w = 0; w < threads; w++) {
        bad |= f->bad[w];
        int64_t k = f->kept[w], n = f->ids[w];
        f->kept[w] = kept, f->ids[w] = ids;
        kept += k, ids += n;
    }
    int rc = 1;
    if (!bad) {
        rc = -1;
        if (!grow((void **)&o->types, &o->cap, o->count + kept, 1) &&
            !grow((void **)&o->offsets, &o->off_cap, o->count + kept + 1, sizeof *o->offsets) &&
            !grow((void **)&o->conn, &o->conn_cap, o->conn_count + ids, sizeof *o->conn)) {
            tpk_parallel_for(pc->cells, threads, fast_fill, f);
            for (int w = 0; w < threads; w++)
                for (int t = 0; t < 256; t++)
                    dropped[t] += f->dropped[w][t];
            o->count += kept;
            o->conn_count += ids;
            o->source_cells += pc->cells;
            rc = 0;
        }
    }
    free(f);
    return rc < 0 ? vh_fail(r, "out of memory for the cells") : rc;
}

static int add_part_cells(vh_reader *r, cell_out *o, const part_cells *pc, int64_t p, int64_t base,
                          const int32_t *merged_of, int64_t *dropped)
{
    int fast = add_part_cells_fast(r, o, pc, p, base, merged_of, dropped);
    if (fast <= 0)
        return fast;
    for (int64_t c = 0; c < pc->cells; c++) {
        int type = pc->types[c];
        tpk_cell_rule rule = tpk_cell_rule_for(type);
        int64_t n = pc->offsets[c + 1] - pc->offsets[c];
        uint8_t *keep = &o->kept[o->source_cells++];
        *keep = 0;
        if (rule.kind == TPK_RULE_UNKNOWN)
            return vh_fail(r, "/VTKHDF/Types: partition %lld, cell %lld: unsupported cell type %d (%s)", (long long)p,
                           (long long)c, type, rule.name);
        if (rule.kind == TPK_RULE_DROP) {
            dropped[type]++;
            continue;
        }
        if (type == TPK_CELL_POLYHEDRON && !r->polyhedra)
            return vh_fail(r, "partition %lld, cell %lld: a polyhedron (type 42), but the file has no FaceConnectivity, "
                           "FaceOffsets, PolyhedronToFaces and PolyhedronOffsets", (long long)p, (long long)c);
        if (type != TPK_CELL_POLYHEDRON && ((rule.nodes > 0 && n != rule.nodes) || (rule.nodes < 0 && n < -rule.nodes)))
            return vh_fail(r, "/VTKHDF/Offsets: partition %lld, cell %lld (%s): expected %s%d points, found %lld",
                           (long long)p, (long long)c, rule.name, rule.nodes < 0 ? "at least " : "",
                           rule.nodes < 0 ? -rule.nodes : rule.nodes, (long long)n);
        if (grow((void **)&o->types, &o->cap, o->count + 1, 1) ||
            grow((void **)&o->offsets, &o->off_cap, o->count + 2, sizeof *o->offsets))
            return vh_fail(r, "out of memory for the cells");
        if (type == TPK_CELL_POLYHEDRON) {
            if (put_polyhedron(r, o, pc, p, c, base, merged_of))
                return -1;
        } else {
            if (grow((void **)&o->conn, &o->conn_cap, o->conn_count + n, sizeof *o->conn))
                return vh_fail(r, "out of memory for the cells");
            for (int64_t j = 0; j < n; j++)
                if (put_id(r, o, p, pc->conn[pc->offsets[c] + j], base, merged_of, "Connectivity",
                           pc->offsets[c] + j))
                    return -1;
        }
        *keep = 1;
        o->types[o->count] = rule.out_type;
        o->offsets[++o->count] = o->conn_count;
    }
    return 0;
}

int vh_read_geometry(vh_reader *r, int64_t step, int record, tpk_mesh *out)
{
    const vh_step *s = &r->steps[step];
    int32_t *merged_of = NULL;
    int64_t *first_raw = NULL, raw = 0;
    cell_out o;
    memset(&o, 0, sizeof o);
    int64_t source_cells = r->cell_start[s->part0 + s->parts] - r->cell_start[s->part0];
    int64_t dropped[256] = {0}, drop_total = 0;
    int rc = read_points(r, s, out, &merged_of, &first_raw, &raw);
    if (rc == 0 && (!(o.kept = malloc((size_t)(source_cells ? source_cells : 1))) ||
                    grow((void **)&o.offsets, &o.off_cap, 1, sizeof *o.offsets)))
        rc = vh_fail(r, "out of memory for %lld cells", (long long)source_cells);
    if (rc == 0)
        o.offsets[0] = 0;
    for (int64_t p = s->part0; rc == 0 && p < s->part0 + s->parts; p++) {
        part_cells pc;
        rc = read_part_cells(r, p, &pc);
        if (rc == 0)
            rc = add_part_cells(r, &o, &pc, p, r->point_start[p] - r->point_start[s->part0], merged_of, dropped);
        part_cells_free(&pc);
    }
    for (int t = 0; t < 256; t++)
        drop_total += dropped[t];
    if (rc == 0 && o.count > INT32_MAX)
        rc = vh_fail(r, "%lld cells in a step, more than tetpack holds (2^31 - 1)", (long long)o.count);
    if (rc == 0 && record && drop_total)
        tpk_warn_cell_counts(r->diag, r->name, dropped, drop_total, "dropped cells that are not volumes:");
    if (rc == 0) {
        out->cell_count = o.count;
        out->cell_types = o.types ? o.types : malloc(1);
        out->cell_offsets = o.offsets;
        out->cell_conn = o.conn ? o.conn : malloc(sizeof *out->cell_conn);
        o.types = NULL, o.offsets = NULL, o.conn = NULL;
        if (!out->cell_types || !out->cell_conn || tpk_mesh_take_face_streams(out))
            rc = vh_fail(r, "out of memory for the cells");
    }
    if (rc == 0 && record) {
        r->raw_points = raw;
        r->merged_of = merged_of;
        r->first_raw = first_raw;
        r->raw_cells = source_cells;
        r->kept = o.kept;
        merged_of = NULL, first_raw = NULL, o.kept = NULL;
    }
    free(merged_of);
    free(first_raw);
    free(o.types);
    free(o.offsets);
    free(o.conn);
    free(o.kept);
    return rc;
}
