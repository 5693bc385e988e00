/* Levels of detail (levels_internal.h): a level's tetmesh out of the simplifier's live tets: the kept
 * vertices numbered in their full-mesh order, the tets renumbered, the fields and maps gathered. */
#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "levels_internal.h"
#include "tetpack.h"

/* level_mesh's copies, over the level's vertices (one job) or tets (the other), side by side. */
typedef struct level_fill {
    const simplifier *s;
    tpk_tetmesh *out;
    const int32_t *renum, *vertex_old;
} level_fill;

static void fill_vertices(void *ctx, int64_t begin, int64_t end, int worker)
{
    const level_fill *f = ctx;
    const tpk_tetmesh *m = f->s->mesh;
    tpk_tetmesh *out = f->out;
    (void)worker;
    for (int64_t i = begin; i < end; i++) {
        int32_t v = f->vertex_old[i];
        memcpy(out->points + 3 * (size_t)i, m->points + 3 * (size_t)v, 3 * sizeof(double));
        out->vertex_source[i] = m->vertex_source ? m->vertex_source[v] : v;
        for (int fi = 0; fi < m->field_count; fi++)
            if (m->fields[fi].association == TPK_ASSOC_POINT)
                for (int st = 0; st < m->fields[fi].step_count; st++)
                    out->fields[fi].values[(size_t)st * (size_t)out->vertex_count + (size_t)i] =
                        m->fields[fi].values[(size_t)st * (size_t)m->vertex_count + (size_t)v];
    }
}

static void fill_tets(void *ctx, int64_t begin, int64_t end, int worker)
{
    const level_fill *f = ctx;
    const simplifier *s = f->s;
    const tpk_tetmesh *m = s->mesh;
    tpk_tetmesh *out = f->out;
    (void)worker;
    for (int64_t t = begin; t < end; t++) {
        for (int k = 0; k < 4; k++)
            out->tets[4 * t + k] = f->renum[s->tets[4 * t + k]];
        out->tet_source[t] = m->tet_source ? m->tet_source[s->origin[t]] : s->origin[t];
        for (int fi = 0; fi < m->field_count; fi++)
            if (m->fields[fi].association != TPK_ASSOC_POINT)
                for (int st = 0; st < m->fields[fi].step_count; st++)
                    out->fields[fi].values[(size_t)st * (size_t)out->tet_count + (size_t)t] =
                        m->fields[fi].values[(size_t)st * (size_t)m->tet_count + (size_t)s->origin[t]];
    }
}

/* level_mesh's numbering on all threads: phase 0 over the live tets marks the vertices they use (renum 0;
 * two workers may mark one, both with 0: relaxed atomic stores); phase 1 over the full mesh's vertices
 * counts the marked; phase 2 numbers them from the offsets the counts before make, in id order as one
 * thread does, and fills vertex_old. */
typedef struct level_numbers {
    const simplifier *s;
    int32_t *renum, *vertex_old;
    int phase;
    int64_t count[TPK_MAX_THREADS + 1];
} level_numbers;

static void number_range(void *ctx, int64_t begin, int64_t end, int worker)
{
    level_numbers *j = ctx;
    int32_t *renum = j->renum;
    if (j->phase == 0) {
        for (int64_t i = 4 * begin; i < 4 * end; i++)
            __atomic_store_n(&renum[j->s->tets[i]], 0, __ATOMIC_RELAXED);
    } else if (j->phase == 1) {
        int64_t n = 0;
        for (int64_t v = begin; v < end; v++)
            n += renum[v] == 0;
        j->count[worker] = n;
    } else {
        int64_t n = j->count[worker];
        for (int64_t v = begin; v < end; v++)
            if (renum[v] == 0) {
                j->vertex_old[n] = (int32_t)v;
                renum[v] = (int32_t)n++;
            }
    }
}

/* The level's tetmesh: kept vertices (those its tets use) in their full-mesh order, the tets renumbered,
 * the fields gathered (tet fields through the tet each level tet descends from), maps through. */
int levels_mesh(const simplifier *s, tpk_tetmesh *out, int32_t **vertex_old, tpk_diag *diag)
{
    const tpk_tetmesh *m = s->mesh;
    memset(out, 0, sizeof *out);
    int32_t *renum = malloc(sizeof *renum * (size_t)(m->vertex_count ? m->vertex_count : 1));
    if (!renum)
        return tpk_diag_fail(diag, "levels: out of memory");
    levels_fill_i32(renum, m->vertex_count, -1, s->threads);
    level_numbers num = {s, renum, NULL, 0, {0}};
    tpk_parallel_for(s->tet_count, tpk_threads_for(s->tet_count, s->threads, 1 << 16), number_range, &num);
    int parts = tpk_threads_for(m->vertex_count, s->threads, 1 << 16);
    num.phase = 1;
    tpk_parallel_for(m->vertex_count, parts, number_range, &num);
    levels_offsets(num.count, parts);
    int64_t n = num.count[parts];
    out->vertex_count = n;
    out->tet_count = s->tet_count;
    memcpy(out->origin, m->origin, sizeof out->origin);
    out->points = malloc(sizeof *out->points * 3 * (size_t)(n ? n : 1));
    out->vertex_source = malloc(sizeof(int32_t) * (size_t)(n ? n : 1));
    *vertex_old = malloc(sizeof(int32_t) * (size_t)(n ? n : 1));
    out->tets = malloc(sizeof *out->tets * 4 * (size_t)(s->tet_count ? s->tet_count : 1));
    out->tet_source = malloc(sizeof *out->tet_source * (size_t)(s->tet_count ? s->tet_count : 1));
    out->field_count = m->field_count;
    out->fields = m->field_count ? calloc((size_t)m->field_count, sizeof *out->fields) : NULL;
    int rc = out->points && out->vertex_source && *vertex_old && out->tets && out->tet_source &&
                     (!m->field_count || out->fields) ? 0 : -1;
    if (rc == 0) { /* the numbers, and vertex_old */
        num.vertex_old = *vertex_old;
        num.phase = 2;
        tpk_parallel_for(m->vertex_count, parts, number_range, &num);
    }
    for (int f = 0; rc == 0 && f < m->field_count; f++) {
        const tpk_src_field *src = &m->fields[f];
        tpk_src_field *dst = &out->fields[f];
        *dst = *src;
        size_t per = (size_t)(src->association == TPK_ASSOC_POINT ? n : s->tet_count);
        if (!(dst->values = malloc(sizeof *dst->values * (per ? per : 1) * (size_t)src->step_count)))
            rc = -1;
    }
    if (rc == 0) { /* the copies, on all threads (one took long on grid 200: bench/README) */
        level_fill fill = {s, out, renum, *vertex_old};
        tpk_parallel_for(n, tpk_threads_for(n, s->threads, 1 << 14), fill_vertices, &fill);
        tpk_parallel_for(s->tet_count, tpk_threads_for(s->tet_count, s->threads, 1 << 16), fill_tets, &fill);
    }
    out->step_count = m->step_count;
    out->times = m->times; /* borrowed */
    free(renum);
    return rc == 0 ? 0 : tpk_diag_fail(diag, "levels: out of memory for a level of %lld tets", (long long)s->tet_count);
}

void levels_mesh_free(tpk_tetmesh *m)
{
    free(m->points);
    free(m->vertex_source);
    free(m->tets);
    free(m->tet_source);
    for (int f = 0; m->fields && f < m->field_count; f++)
        free(m->fields[f].values);
    free(m->fields);
    memset(m, 0, sizeof *m);
}
