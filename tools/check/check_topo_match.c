/* Face matching for `tetpack check` (301, 302, 305, components, the shell): the face matcher
 * (mesh/face_match.h) in its runs mode, for any volume cell (tets by the fast path: their sign in each
 * bucket entry). One face is shell, two are neighbours (orientation and fold-over are checked, the cells
 * joined), more is a non-manifold face. Workers take contiguous cell and bucket ranges and their results
 * are merged in order, so counts, examples and the shell order (by sorted vertex ids) do not depend on
 * the thread count. */
#include <stdlib.h>
#include <string.h>

#include "check_topo.h"
#include "base/parallel.h"
#include "base/predicates.h"
#include "mesh/face_match.h"

enum { HIT_NONMANIFOLD, HIT_ORIENTATION, HIT_FOLDED, HIT_KINDS };
static const int HIT_IDS[HIT_KINDS] = {301, 302, 305};

typedef struct worker_out {
    int64_t counts[HIT_KINDS];
    int kept[HIT_KINDS];
    tpk_example *examples[HIT_KINDS]; /* max_examples each: the worker's first hits */
    tpk_bface *shell;
    int64_t shell_count, shell_cap;
    double *centres; /* of the worker's boundary polygons, numbered -2 - k in its shell until merged */
    int64_t centre_count, centre_cap;
    int failed; /* out of memory */
} worker_out;

typedef struct match_job {
    const tpk_mesh *mesh;
    int threads, max_examples;
    int tets_only; /* every cell a tet at offset 4 c: the matcher's tet path, each tet's sign in its entries */
    uint32_t *parent;
    int polygons; /* some face has more than 4 vertices: runs are split by the whole face (match_run) */
    worker_out out[TPK_MAX_THREADS];
} match_job;

/* The distinct smallest ids of a cell's faces (the buckets the cell goes to). */
static int face_mins(const tpk_topo_face *faces, int count, int32_t *mins)
{
    int n = 0;
    for (int f = 0; f < count; f++) {
        int32_t m = faces[f].v[tpk_topo_min_index(&faces[f])], seen = 0;
        for (int i = 0; i < n && !seen; i++)
            seen = mins[i] == m;
        if (!seen)
            mins[n++] = m;
    }
    return n;
}

/* Matcher callbacks (mesh/face_match.h). Counting pass: cells the checks skip get no set. */
static int keep_cell(void *user, int64_t c)
{
    match_job *job = user;
    if (tpk_topo_face_count(job->mesh, c) == 0 || !tpk_check_cell_usable(job->mesh, c)) {
        job->parent[c] = TPK_UF_NONE;
        return 0;
    }
    job->parent[c] = (uint32_t)c;
    if (job->mesh->cell_types[c] == TPK_CELL_POLYHEDRON && !__atomic_load_n(&job->polygons, __ATOMIC_RELAXED)) {
        tpk_topo_face faces[TPK_TOPO_MAX_CELL_FACES];
        int n = tpk_topo_cell_faces(job->mesh, c, faces);
        for (int f = 0; f < n; f++)
            if (faces[f].n > 4)
                __atomic_store_n(&job->polygons, 1, __ATOMIC_RELAXED);
    }
    return 1;
}

/* Bucketing pass: a tet's exact orientation + 1 goes into its entries (for 305), read ahead 8 tets. */
static int cell_tag(void *user, int64_t c)
{
    match_job *job = user;
    const tpk_mesh *mesh = job->mesh;
    if (job->parent[c] == TPK_UF_NONE)
        return -1;
    if (!job->tets_only)
        return 0;
    const int32_t *v = mesh->cell_conn + 4 * c;
    if (c + 8 < mesh->cell_count)
        for (int k = 0; k < 4; k++)
            __builtin_prefetch(mesh->points + 3 * (int64_t)v[32 + k]);
    return tpk_topo_orient(mesh->points, v[0], v[1], v[2], v[3]) + 1;
}

static int cell_buckets(void *user, int64_t c, int32_t *mins)
{
    const match_job *job = user;
    tpk_topo_face faces[TPK_TOPO_MAX_CELL_FACES];
    return face_mins(faces, tpk_topo_cell_faces(job->mesh, c, faces), mins);
}

static void sort_ids(int32_t *v, int n)
{
    for (int i = 1; i < n; i++) {
        int32_t x = v[i];
        int j = i;
        for (; j > 0 && x < v[j - 1]; j--)
            v[j] = v[j - 1];
        v[j] = x;
    }
}

/* The key of a face: its second and third smallest ids, then the fourth of a quad, or for a larger polygon
 * a hash of its count and its other ids (match_run compares those in full, so a collision costs time,
 * never a wrong match). */
static void make_rec(tpk_match_face *r, const tpk_topo_face *f, uint32_t local)
{
    int32_t s[TPK_TOPO_MAX_FACE_VERTS];
    memcpy(s, f->v, sizeof(int32_t) * (size_t)f->n);
    sort_ids(s, f->n);
    r->key = (uint64_t)(uint32_t)s[1] << 32 | (uint32_t)s[2];
    r->key3 = f->n == 4 ? (uint32_t)s[3] : UINT32_MAX;
    if (f->n > 4) {
        uint64_t h = 0x9E3779B97F4A7C15ull * (uint64_t)f->n;
        for (int i = 3; i < f->n; i++)
            h = (h ^ (uint32_t)s[i]) * 0x100000001B3ull;
        r->key3 = (uint32_t)(h ^ h >> 32);
    }
    r->local = (uint16_t)local;
}

/* The face `local` of a cell in outward order. */
static void face_of(const match_job *job, uint32_t cell, uint32_t local, tpk_topo_face *out)
{
    if (!job->tets_only) {
        tpk_topo_cell_face(job->mesh, cell, (int)local, out);
        return;
    }
    const int32_t *v = job->mesh->cell_conn + 4 * (int64_t)cell; /* no offsets or types to read */
    out->n = 3;
    for (int i = 0; i < 3; i++)
        out->v[i] = v[tpk_tet_faces[local][i]];
}

/* The faces of cell c whose smallest id is v. */
static int cell_faces(void *user, int64_t c, int32_t v, tpk_match_face *r)
{
    const match_job *job = user;
    tpk_topo_face faces[TPK_TOPO_MAX_CELL_FACES];
    int nf = tpk_topo_cell_faces(job->mesh, c, faces), n = 0;
    for (int f = 0; f < nf; f++)
        if (faces[f].v[tpk_topo_min_index(&faces[f])] == v)
            make_rec(&r[n++], &faces[f], (uint32_t)f);
    return n;
}

/* Side of the triangle (a, b, c) that cell `cell` lies on: the sign every vertex of the cell off the
 * face shares, or 0 when they do not agree (a cell that is itself warped or flat: the cell checks say
 * so). With `first_only`, the sign of the first vertex off the face. */
static int cell_side(const tpk_mesh *mesh, uint32_t cell, const tpk_topo_face *face, const double *tri[3],
                     int first_only)
{
    int pos = 0, neg = 0;
    for (int64_t i = mesh->cell_offsets[cell]; i < mesh->cell_offsets[cell + 1]; i++) {
        int32_t p = mesh->cell_conn[i], on_face = 0;
        for (int k = 0; k < face->n; k++)
            on_face |= face->v[k] == p;
        if (on_face)
            continue;
        const double *q = mesh->points + 3 * (int64_t)p;
        int s = tpk_orient3d_filter(tri[0], tri[1], tri[2], q);
        s = s ? s : tpk_orient3d_exact(tri[0], tri[1], tri[2], q);
        if (first_only)
            return s;
        pos |= s > 0;
        neg |= s < 0;
    }
    return pos && !neg ? 1 : neg && !pos ? -1 : 0;
}

/* A polyhedron's face is the surface OpenFOAM makes of it: triangles from its centre to each edge (a
 * non-planar quad split along a diagonal can fold where the face itself does not); so is every polygon
 * of more than 4 vertices. The faces of the other cells are cut as the converter cuts them. */
static int centre_cut(const tpk_mesh *mesh, const tpk_topo_face *f, uint32_t cell)
{
    return f->n > 4 || (f->n == 4 && mesh->cell_types[cell] == TPK_CELL_POLYHEDRON);
}

/* 305: both cells on the same side of a triangle of the face (quads: the smallest-id diagonal split, or
 * about the centre by centre_cut). One vertex of each strictly on opposite sides already rules it out:
 * the usual case, two tests. */
static int folded(const tpk_mesh *mesh, uint32_t cell_a, const tpk_topo_face *fa, uint32_t cell_b)
{
    int centred = centre_cut(mesh, fa, cell_a) || centre_cut(mesh, fa, cell_b);
    int triangles = centred ? fa->n : fa->n - 2;
    double centre[3];
    if (centred)
        tpk_topo_face_centre(mesh->points, fa, centre);
    for (int t = 0; t < triangles; t++) {
        const double *tri[3];
        if (centred) {
            tri[0] = centre;
            tri[1] = mesh->points + 3 * (int64_t)fa->v[t];
            tri[2] = mesh->points + 3 * (int64_t)fa->v[(t + 1) % fa->n];
        } else {
            int32_t ids[3];
            tpk_topo_face_triangle(fa, t, ids);
            for (int k = 0; k < 3; k++)
                tri[k] = mesh->points + 3 * (int64_t)ids[k];
        }
        if (cell_side(mesh, cell_a, fa, tri, 1) * cell_side(mesh, cell_b, fa, tri, 1) < 0)
            continue;
        int sa = cell_side(mesh, cell_a, fa, tri, 0);
        if (sa != 0 && sa == cell_side(mesh, cell_b, fa, tri, 0))
            return 1;
    }
    return 0;
}

static int consistent(const tpk_topo_face *a, const tpk_topo_face *b);

/* 305 for two tets from their exact orientations: a positive tet lies on the negative side of its own
 * outward face order, so a sits on side -sign(a) of its order of the face, and b on side sign(b) when
 * it traverses the face the other way (consistent), else -sign(b). */
static int tets_folded(const tpk_match_face *a, const tpk_match_face *b, int consistent_order)
{
    int sign_a = a->tag - 1, sign_b = b->tag - 1; /* the tets' orientations, from cell_tag */
    int side_a = -sign_a, side_b = consistent_order ? sign_b : -sign_b;
    return side_a != 0 && side_a == side_b;
}

/* 302: neighbours must traverse the shared face in opposite directions (b is a reversed). */
static int consistent(const tpk_topo_face *a, const tpk_topo_face *b)
{
    int n = a->n, ia = tpk_topo_min_index(a), ib = tpk_topo_min_index(b);
    for (int k = 1; k < n; k++) {
        int i = ia + k, j = ib - k;
        if (a->v[i >= n ? i - n : i] != b->v[j < 0 ? j + n : j])
            return 0;
    }
    return 1;
}

static tpk_example *worker_hit(match_job *job, worker_out *o, int kind)
{
    o->counts[kind]++;
    if (o->kept[kind] >= job->max_examples)
        return NULL;
    tpk_example *ex = &o->examples[kind][o->kept[kind]++];
    memset(ex, 0, sizeof *ex);
    ex->kind = "face";
    return ex;
}

/* Example ids: the face's sorted vertex ids, then cells as long as they fit. */
static void face_example(const tpk_mesh *mesh, tpk_example *ex, const tpk_topo_face *face, const tpk_match_face *r,
                         int64_t cells_n)
{
    int64_t ids[TPK_CHECK_MAX_IDS];
    int n = 0;
    int32_t s[TPK_TOPO_MAX_FACE_VERTS];
    memcpy(s, face->v, sizeof(int32_t) * (size_t)face->n);
    sort_ids(s, face->n);
    for (int i = 0; i < face->n && n < TPK_CHECK_MAX_IDS; i++)
        ids[n++] = s[i];
    for (int64_t i = 0; i < cells_n && n < TPK_CHECK_MAX_IDS; i++)
        ids[n++] = r[i].item;
    tpk_example_ids(ex, n, ids);
    double centre[3];
    tpk_topo_face_centre(mesh->points, face, centre);
    tpk_example_point(ex, centre);
}

static void nonmanifold_face(match_job *job, worker_out *o, const tpk_match_face *r, int64_t n)
{
    for (int64_t i = 1; i < n; i++)
        tpk_uf_union(job->parent, r[0].item, r[i].item);
    tpk_example *ex = worker_hit(job, o, HIT_NONMANIFOLD);
    if (!ex)
        return;
    tpk_topo_face face;
    face_of(job, r[0].item, r[0].local, &face);
    face_example(job->mesh, ex, &face, r, n);
    tpk_example_note(ex, "face of %lld cells (at most 2 allowed); ids: the face's vertices, then cells",
                     (long long)n);
}

static void shared_face(match_job *job, worker_out *o, const tpk_match_face *r)
{
    tpk_uf_union(job->parent, r[0].item, r[1].item);
    tpk_topo_face fa, fb;
    face_of(job, r[0].item, r[0].local, &fa);
    face_of(job, r[1].item, r[1].local, &fb);
    if (!consistent(&fa, &fb)) {
        tpk_example *ex = worker_hit(job, o, HIT_ORIENTATION);
        if (ex) {
            face_example(job->mesh, ex, &fa, r, 2);
            tpk_example_note(ex, "cells %u and %u traverse this face in the same direction; one of them is "
                             "turned over", r[0].item, r[1].item);
        }
    }
    if (job->tets_only ? tets_folded(&r[0], &r[1], consistent(&fa, &fb))
                       : folded(job->mesh, r[0].item, &fa, r[1].item)) {
        tpk_example *ex = worker_hit(job, o, HIT_FOLDED);
        if (ex) {
            face_example(job->mesh, ex, &fa, r, 2);
            tpk_example_note(ex, "cells %u and %u lie on the same side of this face (exact orientation)",
                             r[0].item, r[1].item);
        }
    }
}

static int push_shell(worker_out *o, const int32_t *v, int n, const tpk_match_face *r)
{
    if (o->shell_count == o->shell_cap) {
        int64_t cap = 2 * o->shell_cap + 256;
        tpk_bface *grown = realloc(o->shell, sizeof *grown * (size_t)cap);
        if (!grown)
            return -1;
        o->shell = grown;
        o->shell_cap = cap;
    }
    tpk_bface *s = &o->shell[o->shell_count++];
    for (int i = 0; i < 4; i++)
        s->v[i] = i < n ? v[i] : -1;
    s->cell = r->item;
    s->local = r->local;
    return 0;
}

/* A shell face: a triangle or a quad as it is, or by centre_cut the triangles from its centre (the mean
 * of its corners, OpenFOAM's decomposition) to each of its edges, whose inner edges each two of them
 * share. */
static int add_shell_face(const match_job *job, worker_out *o, const tpk_match_face *r)
{
    tpk_topo_face face;
    face_of(job, r->item, r->local, &face);
    if (job->tets_only || !centre_cut(job->mesh, &face, r->item))
        return push_shell(o, face.v, face.n, r);
    if (o->centre_count == o->centre_cap) {
        int64_t cap = 2 * o->centre_cap + 64;
        double *grown = realloc(o->centres, sizeof *grown * 3 * (size_t)cap);
        if (!grown)
            return -1;
        o->centres = grown;
        o->centre_cap = cap;
    }
    tpk_topo_face_centre(job->mesh->points, &face, o->centres + 3 * o->centre_count);
    int32_t centre = (int32_t)(-2 - o->centre_count++);
    for (int i = 0; i < face.n; i++) {
        int32_t tri[3] = {centre, face.v[i], face.v[(i + 1) % face.n]};
        if (push_shell(o, tri, 3, r) != 0)
            return -1;
    }
    return 0;
}

static void face_run(match_job *job, worker_out *o, const tpk_match_face *faces, int64_t n)
{
    if (n == 1)
        o->failed |= add_shell_face(job, o, faces) != 0;
    else if (n == 2)
        shared_face(job, o, faces);
    else
        nonmanifold_face(job, o, faces, n);
}

static int same_face(const tpk_topo_face *a, const tpk_topo_face *b)
{
    if (a->n != b->n)
        return 0;
    int32_t sa[TPK_TOPO_MAX_FACE_VERTS], sb[TPK_TOPO_MAX_FACE_VERTS];
    memcpy(sa, a->v, sizeof(int32_t) * (size_t)a->n);
    memcpy(sb, b->v, sizeof(int32_t) * (size_t)b->n);
    sort_ids(sa, a->n);
    sort_ids(sb, b->n);
    return memcmp(sa, sb, sizeof(int32_t) * (size_t)a->n) == 0;
}

/* Equal keys of polygons with more than 4 vertices are equal faces only when all their ids are: the run
 * is cut into groups of equal faces, each matched on its own (in the run's order, so the results do not
 * depend on the thread count). */
static void polygon_run(match_job *job, worker_out *o, const tpk_match_face *faces, int64_t n)
{
    enum { MOST = 16 };
    if (n > MOST) { /* more cells on one face than any real mesh has: as one run, a non-manifold face */
        face_run(job, o, faces, n);
        return;
    }
    tpk_topo_face face[MOST];
    int done[MOST] = {0};
    for (int64_t i = 0; i < n; i++)
        face_of(job, faces[i].item, faces[i].local, &face[i]);
    for (int64_t i = 0; i < n; i++) {
        if (done[i])
            continue;
        tpk_match_face group[MOST];
        int64_t g = 0;
        for (int64_t j = i; j < n; j++)
            if (!done[j] && same_face(&face[i], &face[j])) {
                done[j] = 1;
                group[g++] = faces[j];
            }
        face_run(job, o, group, g);
    }
}

static void match_run(void *user, int worker, int64_t bucket, const tpk_match_face *faces, int64_t n)
{
    match_job *job = user;
    worker_out *o = &job->out[worker];
    (void)bucket;
    if (job->polygons && n > 1)
        polygon_run(job, o, faces, n);
    else
        face_run(job, o, faces, n);
}

/* Worker results in worker order = bucket order: the first examples overall, exact totals. */
static void merge_hits(match_job *job, tpk_check_report *report)
{
    for (int kind = 0; kind < HIT_KINDS; kind++) {
        for (int w = 0; w < job->threads; w++) {
            worker_out *o = &job->out[w];
            for (int i = 0; i < o->kept[kind]; i++) {
                tpk_example *ex = tpk_check_hit(report, HIT_IDS[kind], "face");
                if (ex)
                    *ex = o->examples[kind][i];
            }
            tpk_check_count(report, HIT_IDS[kind], o->counts[kind] - o->kept[kind]);
        }
    }
}

/* The workers' shells in worker order; their polygon centres numbered after the mesh's points. */
static int merge_shell(match_job *job, tpk_topo_match *out)
{
    int64_t total = 0, centres = 0;
    for (int w = 0; w < job->threads; w++) {
        total += job->out[w].shell_count;
        centres += job->out[w].centre_count;
    }
    out->shell = malloc(sizeof *out->shell * (size_t)(total ? total : 1));
    if (!out->shell)
        return -1;
    out->points = job->mesh->points;
    out->point_count = job->mesh->point_count;
    if (centres) {
        if (out->point_count + centres > INT32_MAX ||
            !(out->own_points = malloc(sizeof(double) * 3 * (size_t)(out->point_count + centres))))
            return -1;
        memcpy(out->own_points, job->mesh->points, sizeof(double) * 3 * (size_t)out->point_count);
        out->points = out->own_points;
    }
    for (int w = 0; w < job->threads; w++) {
        worker_out *o = &job->out[w];
        for (int64_t f = 0; f < o->shell_count; f++)
            for (int i = 0; i < 4; i++)
                if (o->shell[f].v[i] <= -2)
                    o->shell[f].v[i] = (int32_t)(out->point_count - 2 - o->shell[f].v[i]);
        if (o->centre_count)
            memcpy(out->own_points + 3 * out->point_count, o->centres, sizeof(double) * 3 * (size_t)o->centre_count);
        out->point_count += o->centre_count;
        if (o->shell_count == 0) /* its list may never have been allocated */
            continue;
        memcpy(out->shell + out->shell_count, o->shell, sizeof *out->shell * (size_t)o->shell_count);
        out->shell_count += o->shell_count;
    }
    return 0;
}

static void free_job(match_job *job)
{
    for (int w = 0; w < TPK_MAX_THREADS; w++) {
        free(job->out[w].shell);
        free(job->out[w].centres);
        for (int k = 0; k < HIT_KINDS; k++)
            free(job->out[w].examples[k]);
    }
    free(job);
}

static int alloc_job(match_job *job)
{
    for (int w = 0; w < job->threads; w++)
        for (int k = 0; k < HIT_KINDS; k++)
            if (!(job->out[w].examples[k] = calloc((size_t)job->max_examples + 1, sizeof(tpk_example))))
                return -1;
    return 0;
}

void tpk_topo_match_free(tpk_topo_match *m)
{
    free(m->parent);
    free(m->shell);
    free(m->own_points);
    memset(m, 0, sizeof *m);
}

int tpk_topo_match_faces(const tpk_mesh *mesh, tpk_check_report *report, tpk_topo_match *out,
                         tpk_diag *diag)
{
    memset(out, 0, sizeof *out);
    if (mesh->cell_count > INT32_MAX || mesh->point_count > INT32_MAX)
        return tpk_diag_fail(diag, "check: %lld cells and %lld points exceed the connectivity checks' limit "
                             "of 2^31-1", (long long)mesh->cell_count, (long long)mesh->point_count);
    match_job *job = calloc(1, sizeof *job);
    out->parent = tpk_alloc_large(sizeof *out->parent * (size_t)(mesh->cell_count ? mesh->cell_count : 1));
    if (!job || !out->parent) {
        free(job);
        tpk_topo_match_free(out);
        return tpk_diag_fail(diag, "check: out of memory (face matching, %lld cells)", (long long)mesh->cell_count);
    }
    job->mesh = mesh;
    job->parent = out->parent;
    job->max_examples = report->options.max_examples;
    job->threads = tpk_threads_for(mesh->cell_count, tpk_thread_count(report->options.threads), 16384);
    job->tets_only = 1;
    for (int64_t c = 0; c < mesh->cell_count && job->tets_only; c++)
        job->tets_only = mesh->cell_types[c] == TPK_CELL_TETRA && mesh->cell_offsets[c] == 4 * c;
    job->tets_only &= mesh->cell_offsets[mesh->cell_count] == 4 * mesh->cell_count;
    job->tets_only &= mesh->cell_count <= (int64_t)(UINT32_MAX >> 2); /* the entries' top bits hold the sign */
    tpk_face_matcher m = {.item_count = mesh->cell_count, .vertex_count = mesh->point_count,
                          .threads = job->threads, .user = job, .keep = keep_cell, .tag = cell_tag,
                          .tag_bits = job->tets_only ? 2 : 0, .run = match_run};
    if (job->tets_only) {
        m.tets = mesh->cell_conn;
    } else {
        m.cell_buckets = cell_buckets;
        m.cell_faces = cell_faces;
        m.max_cell_faces = TPK_TOPO_MAX_CELL_FACES;
    }
    int rc = alloc_job(job);
    if (rc == 0) {
        tpk_check_progress(report, "faces", 0.2);
        rc = tpk_face_match(&m, NULL) == TPK_MATCH_OK ? 0 : -1;
        for (int w = 0; w < job->threads; w++)
            rc |= job->out[w].failed ? -1 : 0;
    }
    if (rc == 0) {
        merge_hits(job, report);
        rc = merge_shell(job, out);
    }
    free_job(job);
    if (rc != 0) {
        tpk_topo_match_free(out);
        return tpk_diag_fail(diag, "check: out of memory (face matching, %lld cells)", (long long)mesh->cell_count);
    }
    tpk_check_progress(report, "faces", 1.0);
    return 0;
}
