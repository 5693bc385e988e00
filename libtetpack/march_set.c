/* Marching rays across the parts of a part set (spec §15): a BVH per part over the faces on no cut finds
 * where a ray enters; where it leaves a part through a linked face it continues in the other part at the
 * linked face, with no search. The parts share one origin, so the ray frame and every projected vertex
 * are bit-identical on both sides of a cut. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_march.h"

/* A linked face of a part, found from the tet a ray leaves and the xor of the face's three ids (the xor
 * tells the four faces of a tet apart: it is vx xor the opposite vertex). */
typedef struct link_key {
    uint64_t key;
    int64_t link;
} link_key;

typedef struct set_part {
    tpk_marcher *marcher;      /* over the outer faces; NULL when the part has none or is not loaded */
    tpk_mesh_arrays mesh;      /* the caller's arrays; shell = all faces (the marcher's copy: outer only) */
    tpk_shell_face *outer;
    const tpk_link *links;
    link_key *keys;            /* the usable links, sorted by key */
    int64_t key_count;
} set_part;

struct tpk_set_marcher {
    uint32_t part_count;
    set_part *parts;
    double origin[3];
    uint64_t total_tets;
};

static uint64_t face_key(int32_t tet, int32_t a, int32_t b, int32_t c)
{
    return ((uint64_t)(uint32_t)tet << 32) | (uint32_t)(a ^ b ^ c);
}

static int compare_keys(const void *x, const void *y)
{
    const link_key *a = x, *b = y;
    return (a->key > b->key) - (a->key < b->key);
}

static int loaded(const tpk_mesh_arrays *m)
{
    return m->tet_count > 0;
}

/* Keys of part p's links into loaded parts; outer faces are the rest. */
static tpk_result index_links(tpk_set_marcher *sm, uint32_t p, uint64_t link_count)
{
    set_part *part = &sm->parts[p];
    const tpk_mesh_arrays *mesh = &part->mesh;
    uint8_t *linked = calloc(mesh->shell_face_count ? mesh->shell_face_count : 1, 1);
    part->keys = malloc(sizeof *part->keys * (link_count ? link_count : 1));
    part->outer = malloc(sizeof *part->outer * (mesh->shell_face_count ? mesh->shell_face_count : 1));
    if (!linked || !part->keys || !part->outer) {
        free(linked);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    for (uint64_t l = 0; l < link_count; l++) {
        const tpk_link *k = &part->links[l];
        if (k->face < 0 || (uint64_t)k->face >= mesh->shell_face_count || k->part < 0 ||
            (uint32_t)k->part >= sm->part_count || (uint32_t)k->part == p) {
            free(linked);
            return TPK_ERR_MESH;
        }
        const tpk_mesh_arrays *other = &sm->parts[k->part].mesh;
        if (!loaded(other))
            continue; /* a ray leaves here as through the outer shell */
        if (k->other_face < 0 || (uint64_t)k->other_face >= other->shell_face_count ||
            other->shell[k->other_face].t != k->other_tet) {
            free(linked);
            return TPK_ERR_MESH;
        }
        const tpk_shell_face *f = &mesh->shell[k->face];
        linked[k->face] = 1;
        part->keys[part->key_count++] = (link_key){face_key(f->t, f->a, f->b, f->c), (int64_t)l};
    }
    qsort(part->keys, (size_t)part->key_count, sizeof *part->keys, compare_keys);
    uint64_t outer = 0;
    for (uint64_t s = 0; s < mesh->shell_face_count; s++)
        if (!linked[s])
            part->outer[outer++] = mesh->shell[s];
    free(linked);
    tpk_mesh_arrays own = *mesh;
    own.shell = part->outer;
    own.shell_face_count = outer;
    return tpk_marcher_create(&part->marcher, &own);
}

tpk_result tpk_set_marcher_create(tpk_set_marcher **out, uint32_t part_count, const tpk_mesh_arrays *parts,
                                  const tpk_link *const *links, const uint64_t *link_counts)
{
    if (!out)
        return TPK_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!parts || part_count == 0 || (!links && link_counts) || (links && !link_counts))
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_set_marcher *sm = calloc(1, sizeof *sm);
    if (!sm || !(sm->parts = calloc(part_count, sizeof *sm->parts))) {
        free(sm);
        return TPK_ERR_OUT_OF_MEMORY;
    }
    sm->part_count = part_count;
    int have_origin = 0;
    for (uint32_t p = 0; p < part_count; p++) {
        sm->parts[p].mesh = parts[p];
        sm->parts[p].links = links ? links[p] : NULL;
        if (!loaded(&parts[p]))
            continue;
        if (have_origin && memcmp(sm->origin, parts[p].origin, sizeof sm->origin) != 0) {
            tpk_set_marcher_destroy(sm);
            return TPK_ERR_INVALID_ARGUMENT; /* the frames would differ across a cut */
        }
        memcpy(sm->origin, parts[p].origin, sizeof sm->origin);
        have_origin = 1;
        sm->total_tets += parts[p].tet_count;
    }
    for (uint32_t p = 0; p < part_count; p++) {
        if (!loaded(&parts[p]))
            continue;
        tpk_result r = index_links(sm, p, links && links[p] ? link_counts[p] : 0);
        if (r != TPK_OK) {
            tpk_set_marcher_destroy(sm);
            return r;
        }
    }
    *out = sm;
    return TPK_OK;
}

void tpk_set_marcher_destroy(tpk_set_marcher *sm)
{
    if (!sm)
        return;
    for (uint32_t p = 0; p < sm->part_count; p++) {
        tpk_marcher_destroy(sm->parts[p].marcher);
        free(sm->parts[p].outer);
        free(sm->parts[p].keys);
    }
    free(sm->parts);
    free(sm);
}

/* ---- One ray ------------------------------------------------------------------------------------- */

typedef struct set_entry {
    double t;
    uint32_t part;
    int64_t face; /* in that part's marcher's face order */
} set_entry;

static int compare_entries(const void *x, const void *y)
{
    const set_entry *a = x, *b = y;
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    if (a->part != b->part)
        return a->part < b->part ? -1 : 1;
    return (a->face > b->face) - (a->face < b->face);
}

typedef struct set_ray {
    const tpk_set_marcher *sm;
    const tpk_ray_frame *frame;
    double tmin, tmax;
    tpk_segment_fn fn;
    void *user;
    uint32_t *segment_part;
    uint64_t steps;
    int stop;
    double exit_t;
} set_ray;

/* The link of the face the run left part p through, or NULL (an outer face). */
static const tpk_link *link_at(const set_part *part, const march_params *mp)
{
    const tpk_face_hit *f = &mp->exit_face;
    link_key probe = {face_key(mp->exit_tet, f->v[0], f->v[1], f->v[2]), 0};
    const link_key *hit = bsearch(&probe, part->keys, (size_t)part->key_count, sizeof probe, compare_keys);
    return hit ? &part->links[hit->link] : NULL;
}

/* Calls the user's callback with the part set for it. */
typedef struct part_callback {
    set_ray *ray;
    uint32_t part;
} part_callback;

static int forward_segment(void *user, const tpk_segment *segment)
{
    part_callback *cb = user;
    if (cb->ray->segment_part)
        *cb->ray->segment_part = cb->part;
    return cb->ray->fn(cb->ray->user, segment);
}

/* From an outer entry face, through as many parts as the links lead, until an outer face. */
static tpk_result run_chain(set_ray *ray, const set_entry *entry)
{
    const tpk_set_marcher *sm = ray->sm;
    uint32_t p = entry->part;
    const tpk_shell_face *face = &sm->parts[p].marcher->faces[entry->face];
    tpk_face_hit hit;
    if (!tpki_shell_face_entry(sm->parts[p].mesh.positions, ray->frame, face, &hit))
        return TPK_ERR_MESH;
    int32_t tet = face->t;
    for (uint64_t hops = 0;; hops++) {
        if (hops > sm->total_tets)
            return TPK_ERR_MESH; /* a loop through links: watertight marching never revisits a tet */
        const set_part *part = &sm->parts[p];
        part_callback cb = {ray, p};
        march_params mp = {.m = part->marcher, .frame = ray->frame, .tmin = ray->tmin, .tmax = ray->tmax,
                           .fn = ray->fn ? forward_segment : NULL, .user = &cb, .exit_t = hit.t, .exit_tet = -1};
        tpk_result r = tpki_march_run(&mp, &hit, tet);
        ray->steps += mp.steps;
        if (r != TPK_OK)
            return r;
        if (mp.stop) {
            ray->stop = 1;
            return TPK_OK;
        }
        ray->exit_t = mp.exit_t;
        if (mp.exit_tet < 0)
            return TPK_OK;
        const tpk_link *link = link_at(part, &mp);
        if (!link)
            return TPK_OK;
        const set_part *next = &sm->parts[link->part];
        if (!tpki_shell_face_entry(next->mesh.positions, ray->frame, &next->mesh.shell[link->other_face], &hit))
            return TPK_ERR_MESH; /* the linked face is not the same face (positions or id order differ) */
        p = (uint32_t)link->part;
        tet = link->other_tet;
    }
}

/* Entries at (nearly) one t meet at a shell vertex or edge: as in march.c, each is marched dry to learn
 * where it leaves, and they are reported in order of exit t. */
static tpk_result run_tie_group(set_ray *ray, const set_entry *group, int64_t n, uint64_t *runs)
{
    typedef struct {
        double exit_t;
        int64_t index;
    } tie_run;
    tie_run *order = malloc((size_t)n * sizeof *order);
    if (!order)
        return TPK_ERR_OUT_OF_MEMORY;
    tpk_result r = TPK_OK;
    for (int64_t i = 0; i < n && r == TPK_OK; i++) {
        set_ray dry = {ray->sm, ray->frame, -INFINITY, INFINITY, NULL, NULL, NULL, 0, 0, group[i].t};
        r = run_chain(&dry, &group[i]);
        ray->steps += dry.steps;
        order[i].exit_t = dry.exit_t;
        order[i].index = i;
    }
    for (int64_t i = 1; i < n; i++) /* insertion sort: groups are tiny */
        for (int64_t j = i; j > 0 && (order[j].exit_t < order[j - 1].exit_t ||
                                      (order[j].exit_t == order[j - 1].exit_t && order[j].index < order[j - 1].index));
             j--) {
            tie_run swap = order[j];
            order[j] = order[j - 1];
            order[j - 1] = swap;
        }
    for (int64_t i = 0; i < n && r == TPK_OK && !ray->stop; i++) {
        (*runs)++;
        r = run_chain(ray, &group[order[i].index]);
    }
    free(order);
    return r;
}

/* Every part's entries that can matter for [tmin, tmax], merged in t order: those at or after the last
 * entry before tmin over all parts. */
static tpk_result collect_entries(const tpk_set_marcher *sm, const tpk_ray_frame *frame, const double dir[3],
                                  double tmin, double tmax, set_entry **out, int64_t *out_count)
{
    set_entry *all = NULL;
    int64_t count = 0, cap = 0;
    double t_low = -INFINITY;
    for (uint32_t p = 0; p < sm->part_count; p++) {
        const tpk_marcher *m = sm->parts[p].marcher;
        if (!m || m->face_count == 0)
            continue;
        tpk_entry small[64], *list = NULL;
        int64_t n = 0;
        tpk_result r = tpki_shell_entries(m, frame, dir, tmin, tmax, small, 64, &list, &n);
        if (r != TPK_OK) {
            free(all);
            return r;
        }
        if (count + n > cap) {
            cap = 2 * (count + n) + 16;
            set_entry *bigger = realloc(all, (size_t)cap * sizeof *all);
            if (!bigger) {
                free(all);
                if (list != small)
                    free(list);
                return TPK_ERR_OUT_OF_MEMORY;
            }
            all = bigger;
        }
        for (int64_t k = 0; k < n; k++) {
            all[count++] = (set_entry){list[k].t, p, list[k].face};
            if (list[k].t < tmin && list[k].t > t_low)
                t_low = list[k].t;
        }
        if (list != small)
            free(list);
    }
    int64_t kept = 0;
    for (int64_t k = 0; k < count; k++)
        if (all[k].t >= t_low)
            all[kept++] = all[k];
    if (kept > 1)
        qsort(all, (size_t)kept, sizeof *all, compare_entries);
    *out = all;
    *out_count = kept;
    return TPK_OK;
}

tpk_result tpk_set_march_ray(const tpk_set_marcher *sm, const double org[3], const double dir[3], double tmin,
                             double tmax, tpk_segment_fn fn, void *user, uint32_t *segment_part,
                             tpk_march_stats *stats)
{
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!sm || !org || !dir || isnan(tmin) || isnan(tmax))
        return TPK_ERR_INVALID_ARGUMENT;
    tpk_ray_frame frame;
    if (tpki_ray_frame_init(&frame, sm->origin, org, dir) != 0)
        return TPK_ERR_INVALID_ARGUMENT;
    if (tmax < tmin)
        return TPK_OK;
    set_entry *entries = NULL;
    int64_t entry_count = 0;
    tpk_result r = collect_entries(sm, &frame, dir, tmin, tmax, &entries, &entry_count);
    if (r != TPK_OK)
        return r;
    set_ray ray = {sm, &frame, tmin, tmax, fn, user, segment_part, 0, 0, 0.0};
    uint64_t runs = 0;
    double extent = 0;
    for (uint32_t p = 0; p < sm->part_count; p++)
        if (sm->parts[p].marcher && sm->parts[p].marcher->extent > extent)
            extent = sm->parts[p].marcher->extent;
    double dir_len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double tie_tol = 1e-12 * (extent + fabs(frame.org[0]) + fabs(frame.org[1]) + fabs(frame.org[2])) / dir_len;
    for (int64_t k = 0; k < entry_count && !ray.stop && r == TPK_OK; k++) {
        if (entries[k].t > tmax)
            break;
        int64_t end = k + 1;
        while (end < entry_count && entries[end].t - entries[end - 1].t <= tie_tol)
            end++;
        if (end - k > 1) {
            r = run_tie_group(&ray, &entries[k], end - k, &runs);
            k = end - 1;
        } else {
            runs++;
            r = run_chain(&ray, &entries[k]);
        }
    }
    free(entries);
    if (stats) {
        stats->tet_steps = ray.steps;
        stats->shell_entries = runs;
    }
    return r;
}
