/* The parts of a set as the arrays of one mesh (spec §15), for renderers that take one file's arrays
 * (the Vulkan renderer, the CPU reference's lighting): rays then cross the cuts as they cross any face.
 *   - Vertices: each part's vertices are slots; the two faces of every link join their slots by equal
 *     positions (union-find). The classes are numbered by a merge of the parts' own orders (each part's
 *     vertices in its id order, a shared vertex emitted once every part holding it has reached it), so
 *     every tet's and face's vertices compare as in each part, and so as in the file the set was cut
 *     from (§15.4): the marcher's decisions, made in id order, are that file's.
 *   - Tets: part after part; a face on a cut gets the tet across it (base of the other part + its tet).
 *   - Shell: the faces with no link into an open part, with the merged ids.
 * Untrusted input: the parts' arrays are checked by tpk_load_arrays and the walk of recover.c; each link
 * is checked both ways (the other part's record points back, the faces' positions are the same). */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal_file.h"
#include "internal_mesh.h"
#include "internal_threads.h"

struct set_field {
    char name[64];         /* "" for tpk_set_mesh_arrays' NULL */
    uint32_t step;
    int tet;               /* a tet field (else point) */
    float *values;         /* NULL: the point field is missing from a part */
};

struct tpk_set_mesh {
    tpk_partset *set;
    uint32_t part_count;
    tpk_layout layout;
    tpk_layout *source;    /* per part: the layout read (Tet32 where present: no walk) */
    uint64_t *slot_base;   /* part_count + 1: part p's vertices are slots [slot_base[p], slot_base[p + 1]) */
    uint64_t *tet_base;    /* part_count + 1 */
    int32_t *slot_id;      /* per slot: its merged vertex id */
    uint64_t vertex_count, shell_count;
    double origin[3];
    float *positions;
    void *tets;
    tpk_shell_face *shell;
    struct set_field *fields; /* every field handed out, kept (and handed out again) until destroy */
    size_t field_count;
};

static tpk_layout source_layout(tpk_file *file)
{
    uint64_t i;
    if (tpk_find_chunk(file, TPK_TAG_TT32, 0, 0, &i) == TPK_OK)
        return TPK_LAYOUT_TET32;
    if (tpk_find_chunk(file, TPK_TAG_TT20, 0, 0, &i) == TPK_OK)
        return TPK_LAYOUT_TET20;
    return TPK_LAYOUT_TET16;
}

/* Part p's arrays (positions, tets, shell; the point field asked, or none) in its source layout. */
static tpk_result part_arrays(const tpk_set_mesh *m, uint32_t p, const char *field, uint32_t step,
                              tpk_mesh_arrays *out, char *err, size_t cap)
{
    tpk_file *file = tpk_partset_file(m->set, p);
    tpk_result r = tpk_load_arrays(file, m->source[p], field, step, out);
    return r == TPK_OK ? r : tpki_text_fail(err, cap, r, "part %u: %s", p, tpk_error_text(file));
}

static int open_part(const tpk_set_mesh *m, uint32_t p)
{
    return tpk_partset_file(m->set, p) != NULL;
}

/* ---- Vertices ------------------------------------------------------------------------------------ */

static int32_t find(int32_t *parent, int32_t s)
{
    while (parent[s] != s) {
        parent[s] = parent[parent[s]];
        s = parent[s];
    }
    return s;
}

static int compare_link_face(const void *key, const void *elem)
{
    int32_t face = *(const int32_t *)key, other = ((const tpk_link *)elem)->face;
    return (face > other) - (face < other);
}

/* Link l of part p, into open part q: the same face both ways; its three vertices joined. */
static tpk_result join_link(const tpk_set_mesh *m, uint32_t p, const tpk_mesh_arrays *mp, const tpk_link *l,
                            const tpk_mesh_arrays *mq, const tpk_link *q_links, uint64_t q_count, int32_t *parent,
                            char *err, size_t cap)
{
    uint32_t q = (uint32_t)l->part;
    if (l->face < 0 || (uint64_t)l->face >= mp->shell_face_count || l->other_face < 0 ||
        (uint64_t)l->other_face >= mq->shell_face_count || mq->shell[l->other_face].t != l->other_tet)
        return tpki_text_fail(err, cap, TPK_ERR_MESH, "part %u: the link of shell face %d names face %d of part %u, which is "
                    "not that part's shell face of tet %d (spec §15.5)", p, l->face, l->other_face, q, l->other_tet);
    const tpk_link *back = bsearch(&l->other_face, q_links, (size_t)q_count, sizeof *q_links, compare_link_face);
    if (!back || (uint32_t)back->part != p || back->other_face != l->face ||
        back->other_tet != mp->shell[l->face].t)
        return tpki_text_fail(err, cap, TPK_ERR_MESH, "part %u: shell face %d links to face %d of part %u, which does not link "
                    "back to it (spec §15.4)", p, l->face, l->other_face, q);
    const tpk_shell_face *f = &mp->shell[l->face], *g = &mq->shell[l->other_face];
    const int32_t fv[3] = {f->a, f->b, f->c}, gv[3] = {g->a, g->b, g->c};
    int used = 0;
    for (int i = 0; i < 3; i++) {
        int j = 0;
        while (j < 3 && ((used >> j & 1) ||
                         memcmp(&mp->positions[3 * (int64_t)fv[i]], &mq->positions[3 * (int64_t)gv[j]], 12) != 0))
            j++;
        if (j == 3)
            return tpki_text_fail(err, cap, TPK_ERR_MESH, "part %u: shell face %d and face %d of part %u, linked, do not have the "
                        "same three positions (spec §15.4)", p, l->face, l->other_face, q);
        used |= 1 << j;
        int32_t a = find(parent, (int32_t)(m->slot_base[p] + (uint64_t)fv[i]));
        int32_t b = find(parent, (int32_t)(m->slot_base[q] + (uint64_t)gv[j]));
        if (a != b)
            parent[a > b ? a : b] = a < b ? a : b;
    }
    return TPK_OK;
}

/* Vertex classes numbered by a merge of the parts' orders (Kahn's algorithm over the parts' lists):
 * need[c] counts the slots of class c, at[c] the parts whose next vertex is c, waiting[c] lists them
 * (through next_waiting[p]); c is emitted once every part holding it waits on it. A stack of ready
 * classes (at most one per part, as each part waits on one class) keeps a part's run of vertices of its
 * own together. */
typedef struct numbering {
    const uint64_t *slot_base;
    int32_t *parent, *need, *at, *waiting, *next_waiting, *ready;
    uint64_t *head;
    int64_t top;
} numbering;

/* Part q's next vertex, if any, waits; 0, or -1 when its class was emitted already (two of q's vertices
 * joined by links). */
static int arrive(numbering *n, uint32_t q)
{
    uint64_t s = n->slot_base[q] + n->head[q];
    if (s == n->slot_base[q + 1])
        return 0;
    int32_t c = n->parent[s];
    if (n->at[c] < 0)
        return -1;
    n->next_waiting[q] = n->waiting[c];
    n->waiting[c] = (int32_t)q;
    if (++n->at[c] == n->need[c])
        n->ready[n->top++] = c;
    return 0;
}

/* On return parent[s] is slot s's merged id. */
static tpk_result number_classes(tpk_set_mesh *m, int32_t *parent, char *err, size_t cap)
{
    uint64_t slots = m->slot_base[m->part_count], cells = slots ? slots : 1;
    uint32_t np = m->part_count;
    numbering n = {m->slot_base, parent, calloc(cells, sizeof(int32_t)), calloc(cells, sizeof(int32_t)),
                   malloc(cells * sizeof(int32_t)), malloc(np * sizeof(int32_t)), malloc(np * sizeof(int32_t)),
                   calloc(np, sizeof(uint64_t)), 0};
    tpk_result r = TPK_OK;
    if (!n.need || !n.at || !n.waiting || !n.next_waiting || !n.ready || !n.head)
        r = tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for %llu vertices", (unsigned long long)slots);
    for (uint64_t s = 0; r == TPK_OK && s < slots; s++) {
        parent[s] = find(parent, (int32_t)s);
        n.need[parent[s]]++;
        n.waiting[s] = -1;
    }
    int joined = 0;
    for (uint32_t p = 0; r == TPK_OK && p < np; p++)
        joined |= arrive(&n, p);
    int32_t next_id = 0;
    while (r == TPK_OK && !joined && n.top > 0) {
        int32_t c = n.ready[--n.top], w = n.waiting[c];
        n.need[c] = next_id++; /* need[c] is not read again: it holds c's id from here on */
        n.at[c] = -1;
        while (w >= 0 && !joined) {
            uint32_t q = (uint32_t)w;
            w = n.next_waiting[q];
            n.head[q]++;
            joined |= arrive(&n, q);
        }
    }
    for (uint32_t p = 0; r == TPK_OK && p < np; p++)
        if (joined || n.head[p] != m->slot_base[p + 1] - m->slot_base[p])
            r = tpki_text_fail(err, cap, TPK_ERR_MESH, "%s (spec §15.4)", joined ? "the links join two vertices of one part"
                     : "the parts order the vertices they share differently");
    for (uint64_t s = 0; r == TPK_OK && s < slots; s++)
        parent[s] = n.need[parent[s]];
    if (r == TPK_OK)
        m->vertex_count = (uint64_t)next_id;
    free(n.need);
    free(n.at);
    free(n.waiting);
    free(n.next_waiting);
    free(n.ready);
    free(n.head);
    return r;
}

/* Slots joined by the links, numbered; the merged positions. */
static tpk_result merge_vertices(tpk_set_mesh *m, const tpk_mesh_arrays *parts, const tpk_link **links,
                                 const uint64_t *link_counts, char *err, size_t cap)
{
    uint64_t slots = m->slot_base[m->part_count];
    int32_t *parent = malloc((slots ? slots : 1) * sizeof *parent);
    if (!parent)
        return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for %llu vertices", (unsigned long long)slots);
    for (uint64_t s = 0; s < slots; s++)
        parent[s] = (int32_t)s;
    tpk_result r = TPK_OK;
    for (uint32_t p = 0; p < m->part_count && r == TPK_OK; p++)
        for (uint64_t k = 0; open_part(m, p) && k < link_counts[p] && r == TPK_OK; k++) {
            const tpk_link *l = &links[p][k];
            if (open_part(m, (uint32_t)l->part)) /* checked in range by tpk_partset_links */
                r = join_link(m, p, &parts[p], l, &parts[l->part], links[l->part], link_counts[l->part], parent, err,
                              cap);
        }
    if (r == TPK_OK)
        r = number_classes(m, parent, err, cap);
    if (r == TPK_OK && !(m->positions = malloc(3 * sizeof *m->positions * (m->vertex_count ? m->vertex_count : 1))))
        r = tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for %llu vertices",
                 (unsigned long long)m->vertex_count);
    for (uint32_t p = 0; p < m->part_count && r == TPK_OK; p++)
        for (uint64_t a = 0; a < m->slot_base[p + 1] - m->slot_base[p]; a++)
            memcpy(&m->positions[3 * (int64_t)parent[m->slot_base[p] + a]], &parts[p].positions[3 * a], 12);
    if (r != TPK_OK) {
        free(parent);
        return r;
    }
    m->slot_id = parent;
    return TPK_OK;
}

/* ---- Tets and shell ------------------------------------------------------------------------------ */

static int rank_in(const int32_t *q, int k)
{
    return (q[0] < q[k]) + (q[1] < q[k]) + (q[2] < q[k]) + (q[3] < q[k]);
}

/* Tet t (merged id) from its merged vertices q (positive order) and neighbors by rank n, in m's layout. */
static void encode_tet(const tpk_set_mesh *m, uint64_t t, const int32_t q[4], const int32_t n[4])
{
    int32_t vx = q[0] ^ q[1] ^ q[2] ^ q[3];
    if (m->layout == TPK_LAYOUT_TET32) {
        tpk_tet32 *r = (tpk_tet32 *)m->tets + t;
        memcpy(r->v, q, sizeof r->v);
        r->vx = vx;
        for (int k = 0; k < 4; k++)
            r->n[k] = n[rank_in(q, k)];
    } else if (m->layout == TPK_LAYOUT_TET20) {
        tpk_tet20 *r = (tpk_tet20 *)m->tets + t;
        r->vx = vx;
        memcpy(r->n, n, sizeof r->n);
    } else {
        tpk_tet16 *r = (tpk_tet16 *)m->tets + t;
        r->vx = vx;
        for (int k = 0; k < 3; k++)
            r->nx[k] = n[k] ^ n[3];
    }
}

/* Part p's tets into the merged layout: its vertices and neighbors recovered, the faces on links into
 * open parts given the tet across, ranks taken again on the merged ids. */
static tpk_result merge_part_tets(tpk_set_mesh *m, uint32_t p, const tpk_mesh_arrays *mp, const tpk_link *links,
                                  uint64_t link_count, char *err, size_t cap)
{
    uint64_t n = mp->tet_count;
    int32_t *quad = malloc(4 * sizeof *quad * (n ? n : 1)), *nbr = malloc(4 * sizeof *nbr * (n ? n : 1));
    tpk_result r = quad && nbr ? tpki_recover_tets_neighbors(mp, quad, nbr) : TPK_ERR_OUT_OF_MEMORY;
    if (r != TPK_OK) {
        free(quad);
        free(nbr);
        return tpki_text_fail(err, cap, r, "part %u: cannot recover its tets' vertices and neighbors: %s", p, tpk_result_string(r));
    }
    const int64_t base = (int64_t)m->tet_base[p];
    for (uint64_t i = 0; i < 4 * n; i++)
        nbr[i] = nbr[i] < 0 ? -1 : (int32_t)(base + nbr[i]);
    for (uint64_t k = 0; k < link_count && r == TPK_OK; k++) {
        const tpk_link *l = &links[k];
        if (!open_part(m, (uint32_t)l->part))
            continue;
        const tpk_shell_face *f = &mp->shell[l->face]; /* checked by join_link */
        const int32_t *q = quad + 4 * (int64_t)f->t;
        int apex = -1, matched = 0;
        for (int k = 0; k < 4; k++) {
            int in_face = q[k] == f->a || q[k] == f->b || q[k] == f->c;
            matched += in_face;
            apex = in_face ? apex : k;
        }
        int32_t *slot = matched == 3 ? &nbr[4 * (int64_t)f->t + rank_in(q, apex)] : NULL;
        if (!slot || *slot != -1)
            r = tpki_text_fail(err, cap, TPK_ERR_MESH, "part %u: linked shell face %d is not a face of tet %d without a "
                     "neighbor", p, l->face, f->t);
        else
            *slot = (int32_t)(m->tet_base[l->part] + (uint64_t)l->other_tet);
    }
    for (uint64_t t = 0; t < n && r == TPK_OK; t++) {
        const int32_t *lq = quad + 4 * t, *ln = nbr + 4 * t;
        int32_t q[4], byface[4], g[4];
        for (int k = 0; k < 4; k++) {
            q[k] = m->slot_id[m->slot_base[p] + (uint64_t)lq[k]];
            byface[k] = ln[rank_in(lq, k)];
        }
        for (int k = 0; k < 4; k++)
            g[rank_in(q, k)] = byface[k];
        encode_tet(m, m->tet_base[p] + t, q, g);
    }
    free(quad);
    free(nbr);
    return r;
}

/* The outer shell: part p's faces with no link into an open part. */
static tpk_result merge_part_shell(tpk_set_mesh *m, uint32_t p, const tpk_mesh_arrays *mp, const tpk_link *links,
                                   uint64_t link_count, uint64_t *count)
{
    uint8_t *linked = calloc(mp->shell_face_count ? mp->shell_face_count : 1, 1);
    if (!linked)
        return TPK_ERR_OUT_OF_MEMORY;
    for (uint64_t k = 0; k < link_count; k++)
        if (open_part(m, (uint32_t)links[k].part))
            linked[links[k].face] = 1;
    const int32_t *id = m->slot_id + m->slot_base[p];
    for (uint64_t s = 0; s < mp->shell_face_count; s++) {
        const tpk_shell_face *f = &mp->shell[s];
        if (!linked[s])
            m->shell[(*count)++] = (tpk_shell_face){id[f->a], id[f->b], id[f->c], (int32_t)(m->tet_base[p] + (uint64_t)f->t)};
    }
    free(linked);
    return TPK_OK;
}

/* The parts' tets on up to one thread per core, a part at a time each (they write disjoint ranges; each
 * holds its part's vertices and neighbors, 32 bytes a tet, while it works): the same arrays for any
 * thread count. The failure reported is that of the lowest part that failed. */
typedef struct tets_job {
    tpk_set_mesh *m;
    const tpk_mesh_arrays *parts;
    const tpk_link **links;
    const uint64_t *link_counts;
    atomic_uint next;
    pthread_mutex_t lock;
    uint32_t failed_part;
    tpk_result result;
    char err[512];
} tets_job;

static void tets_worker(void *arg, int share, int shares)
{
    (void)share, (void)shares; /* parts are taken in turn, by whichever share is free */
    tets_job *job = arg;
    for (;;) {
        uint32_t p = atomic_fetch_add(&job->next, 1);
        if (p >= job->m->part_count)
            return;
        if (!open_part(job->m, p))
            continue;
        char err[512] = "";
        tpk_result r = merge_part_tets(job->m, p, &job->parts[p], job->links[p], job->link_counts[p], err, sizeof err);
        if (r == TPK_OK)
            continue;
        pthread_mutex_lock(&job->lock);
        if (job->result == TPK_OK || p < job->failed_part) {
            job->result = r;
            job->failed_part = p;
            memcpy(job->err, err, sizeof err);
        }
        pthread_mutex_unlock(&job->lock);
    }
}

static tpk_result merge_tets(tpk_set_mesh *m, const tpk_mesh_arrays *parts, const tpk_link **links,
                             const uint64_t *link_counts, char *err, size_t cap)
{
    tets_job job = {.m = m, .parts = parts, .links = links, .link_counts = link_counts, .result = TPK_OK};
    atomic_init(&job.next, 0);
    pthread_mutex_init(&job.lock, NULL);
    int cores = tpki_cores();
    tpki_run_threads((uint32_t)cores > m->part_count ? (int)m->part_count : cores, tets_worker, &job);
    pthread_mutex_destroy(&job.lock);
    if (job.result != TPK_OK)
        tpki_text_fail(err, cap, job.result, "%s", job.err);
    return job.result;
}

/* ---- Entry points -------------------------------------------------------------------------------- */

static tpk_result build(tpk_set_mesh *m, tpk_mesh_arrays *parts, const tpk_link **links, uint64_t *link_counts,
                        char *err, size_t cap)
{
    uint64_t shell_total = 0;
    for (uint32_t p = 0; p < m->part_count; p++) {
        m->slot_base[p + 1] = m->slot_base[p];
        m->tet_base[p + 1] = m->tet_base[p];
        if (!open_part(m, p))
            continue;
        m->source[p] = source_layout(tpk_partset_file(m->set, p));
        tpk_result r = part_arrays(m, p, NULL, 0, &parts[p], err, cap);
        if (r != TPK_OK)
            return r;
        if ((r = tpk_partset_links(m->set, p, &links[p], &link_counts[p])) != TPK_OK)
            return tpki_text_fail(err, cap, r, "part %u: %s", p, tpk_error_text(tpk_partset_file(m->set, p)));
        m->slot_base[p + 1] += parts[p].vertex_count;
        m->tet_base[p + 1] += parts[p].tet_count;
        shell_total += parts[p].shell_face_count;
        memcpy(m->origin, parts[p].origin, sizeof m->origin);
    }
    if (m->slot_base[m->part_count] > INT32_MAX || m->tet_base[m->part_count] > INT32_MAX ||
        shell_total > INT32_MAX)
        return tpki_text_fail(err, cap, TPK_ERR_LIMIT, "the set's parts hold %llu vertices, %llu tets and %llu shell faces: one "
                    "mesh of them holds at most 2^31 - 1 of each", (unsigned long long)m->slot_base[m->part_count],
                    (unsigned long long)m->tet_base[m->part_count], (unsigned long long)shell_total);
    tpk_result r = merge_vertices(m, parts, links, link_counts, err, cap);
    if (r != TPK_OK)
        return r;
    uint64_t tets = m->tet_base[m->part_count];
    size_t record = m->layout == TPK_LAYOUT_TET32 ? sizeof(tpk_tet32)
                    : m->layout == TPK_LAYOUT_TET20 ? sizeof(tpk_tet20) : sizeof(tpk_tet16);
    m->tets = malloc(record * (tets ? tets : 1));
    m->shell = malloc(sizeof *m->shell * (shell_total ? shell_total : 1));
    if (!m->tets || !m->shell)
        return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for %llu tets", (unsigned long long)tets);
    r = merge_tets(m, parts, links, link_counts, err, cap);
    for (uint32_t p = 0; p < m->part_count && r == TPK_OK; p++)
        if (open_part(m, p) && merge_part_shell(m, p, &parts[p], links[p], link_counts[p], &m->shell_count) != TPK_OK)
            r = tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for part %u's shell", p);
    return r;
}

tpk_result tpk_set_mesh_create(tpk_set_mesh **out, tpk_partset *set, tpk_layout layout, char *err, size_t cap)
{
    if (err && cap)
        err[0] = 0;
    if (!out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!set || (layout != TPK_LAYOUT_TET16 && layout != TPK_LAYOUT_TET20 && layout != TPK_LAYOUT_TET32))
        return TPK_ERR_INVALID_ARGUMENT;
    uint32_t np = tpk_partset_part_count(set);
    tpk_set_mesh *m = calloc(1, sizeof *m);
    tpk_mesh_arrays *parts = calloc(np, sizeof *parts);
    const tpk_link **links = calloc(np, sizeof *links);
    uint64_t *link_counts = calloc(np, sizeof *link_counts);
    tpk_result r = TPK_ERR_OUT_OF_MEMORY;
    if (m && parts && links && link_counts) {
        m->set = set;
        m->part_count = np;
        m->layout = layout;
        m->source = calloc(np, sizeof *m->source);
        m->slot_base = calloc(np + 1, sizeof *m->slot_base);
        m->tet_base = calloc(np + 1, sizeof *m->tet_base);
        r = m->source && m->slot_base && m->tet_base ? build(m, parts, links, link_counts, err, cap)
                                                     : TPK_ERR_OUT_OF_MEMORY;
    }
    free(parts);
    free(links);
    free(link_counts);
    if (r == TPK_ERR_OUT_OF_MEMORY && err && cap && !err[0])
        tpki_text_fail(err, cap, r, "out of memory for the set's arrays");
    if (r != TPK_OK) {
        tpk_set_mesh_destroy(m);
        return r;
    }
    *out = m;
    return TPK_OK;
}

void tpk_set_mesh_destroy(tpk_set_mesh *m)
{
    if (!m)
        return;
    for (size_t i = 0; i < m->field_count; i++)
        free(m->fields[i].values);
    free(m->fields);
    free(m->source);
    free(m->slot_base);
    free(m->tet_base);
    free(m->slot_id);
    free(m->positions);
    free(m->tets);
    free(m->shell);
    free(m);
}

/* The field kept for (name, step, kind), or NULL. */
static struct set_field *kept_field(tpk_set_mesh *m, const char *name, uint32_t step, int tet)
{
    for (size_t i = 0; i < m->field_count; i++)
        if (m->fields[i].step == step && m->fields[i].tet == tet && !strcmp(m->fields[i].name, name ? name : ""))
            return &m->fields[i];
    return NULL;
}

/* A new field entry with room for n floats (values NULL when n is 0), not counted until the caller has
 * filled it; NULL with nothing allocated when out of memory. */
static struct set_field *new_field(tpk_set_mesh *m, const char *name, uint32_t step, int tet, uint64_t n)
{
    struct set_field *list = realloc(m->fields, (m->field_count + 1) * sizeof *list);
    if (!list)
        return NULL;
    m->fields = list;
    struct set_field *f = &list[m->field_count];
    memset(f, 0, sizeof *f);
    snprintf(f->name, sizeof f->name, "%s", name ? name : "");
    f->step = step;
    f->tet = tet;
    if (n && !(f->values = malloc(sizeof *f->values * n)))
        return NULL;
    return f;
}

/* Every open part's point field into one array by the merged ids; values NULL when a part lacks it. */
static tpk_result gather_point_field(tpk_set_mesh *m, const char *field_name, uint32_t step, float **out, char *err,
                                     size_t cap)
{
    float *scalars = malloc(sizeof *scalars * (m->vertex_count ? m->vertex_count : 1));
    if (!scalars)
        return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for the set's point field");
    for (uint32_t p = 0; p < m->part_count; p++) {
        if (!open_part(m, p))
            continue;
        tpk_mesh_arrays mp;
        tpk_result r = part_arrays(m, p, field_name, step, &mp, err, cap);
        if (r != TPK_OK || !mp.scalars) { /* a part without the field: none */
            free(scalars);
            *out = NULL;
            return r;
        }
        for (uint64_t a = 0; a < mp.vertex_count; a++)
            scalars[m->slot_id[m->slot_base[p] + a]] = mp.scalars[a];
    }
    *out = scalars;
    return TPK_OK;
}

tpk_result tpk_set_mesh_arrays(tpk_set_mesh *m, const char *field_name, uint32_t step, tpk_mesh_arrays *out,
                               char *err, size_t cap)
{
    if (err && cap)
        err[0] = 0;
    if (!m || !out)
        return TPK_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (field_name && strlen(field_name) >= sizeof m->fields->name)
        return tpki_text_fail(err, cap, TPK_ERR_NOT_FOUND, "no field named '%.63s...' (names are shorter, spec §7.1)", field_name);
    struct set_field *f = kept_field(m, field_name, step, 0);
    if (!f) {
        float *scalars = NULL;
        tpk_result r = gather_point_field(m, field_name, step, &scalars, err, cap);
        if (r != TPK_OK)
            return r;
        if (!(f = new_field(m, field_name, step, 0, 0))) {
            free(scalars);
            return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for the set's point field");
        }
        f->values = scalars;
        m->field_count++;
    }
    out->vertex_count = m->vertex_count;
    out->tet_count = m->tet_base[m->part_count];
    out->shell_face_count = m->shell_count;
    memcpy(out->origin, m->origin, sizeof out->origin);
    out->positions = m->positions;
    out->layout = m->layout;
    out->tet16 = m->layout == TPK_LAYOUT_TET16 ? m->tets : NULL;
    out->tet20 = m->layout == TPK_LAYOUT_TET20 ? m->tets : NULL;
    out->tet32 = m->layout == TPK_LAYOUT_TET32 ? m->tets : NULL;
    out->shell = m->shell;
    out->scalars = f->values;
    return TPK_OK;
}

tpk_result tpk_set_mesh_tet_field(tpk_set_mesh *m, const char *field_name, uint32_t step, const float **out,
                                  char *err, size_t cap)
{
    if (err && cap)
        err[0] = 0;
    if (!m || !out || !field_name)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (strlen(field_name) >= sizeof m->fields->name)
        return tpki_text_fail(err, cap, TPK_ERR_NOT_FOUND, "no field named '%.63s...' (names are shorter, spec §7.1)", field_name);
    struct set_field *kept = kept_field(m, field_name, step, 1);
    if (kept) {
        *out = kept->values;
        return TPK_OK;
    }
    struct set_field *f = new_field(m, field_name, step, 1, m->tet_base[m->part_count] ? m->tet_base[m->part_count] : 1);
    if (!f)
        return tpki_text_fail(err, cap, TPK_ERR_OUT_OF_MEMORY, "out of memory for the set's tet field '%.64s'", field_name);
    for (uint32_t p = 0; p < m->part_count; p++) {
        if (!open_part(m, p))
            continue;
        tpk_file *file = tpk_partset_file(m->set, p);
        const float *part = NULL;
        tpk_result r = tpk_load_tet_field(file, field_name, step, &part);
        if (r != TPK_OK) {
            free(f->values);
            return tpki_text_fail(err, cap, r, "part %u: %s", p, tpk_error_text(file));
        }
        memcpy(f->values + m->tet_base[p], part, sizeof *f->values * (m->tet_base[p + 1] - m->tet_base[p]));
    }
    m->field_count++;
    *out = f->values;
    return TPK_OK;
}

uint64_t tpk_set_mesh_tet_base(const tpk_set_mesh *m, uint32_t i)
{
    return m && i <= m->part_count ? m->tet_base[i] : 0;
}
