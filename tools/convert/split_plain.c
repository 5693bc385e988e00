/* The plain split of every cell, on all cores (split_plain.h). Each worker takes a contiguous range of
 * cells and writes its tets where that range's upper bound (the most tets its cells can give) puts them;
 * the blocks are then moved down to close the gaps, so the result is that of one pass in cell order.
 * Hexahedra split into 5 tets (and refused cells) leave the only gaps: usually none. */
#include "split_plain.h"

#include <stdlib.h>
#include <string.h>

#include "base/parallel.h"
#include "cell_split.h"
#include "mesh/cell_types.h"

static int plain_max_tets(int type)
{
    return type == TPK_CELL_TETRA ? 1 : tpk_split_max_tets(type);
}

typedef struct split_worker {
    int64_t start;               /* where its tets go: the sum of plain_max_tets over the cells before */
    tpk_plain_split found;       /* tet_count: how many it wrote */
    int out_of_memory;
} split_worker;

typedef struct split_job {
    const tpk_mesh *src;
    const double *points;
    const tpk_tetra_progress *progress;
    int32_t *tets, *tet_source;
    split_worker *workers;
} split_job;

static int remember_hard(tpk_plain_split *f, int64_t c, int64_t *capacity)
{
    if (f->hard_count == *capacity) {
        *capacity = *capacity ? 2 * *capacity : 64;
        int64_t *grown = realloc(f->hard, sizeof *grown * (size_t)*capacity);
        if (!grown)
            return -1;
        f->hard = grown;
    }
    f->hard[f->hard_count++] = c;
    return 0;
}

static void split_range(void *ctx, int64_t begin, int64_t end, int w)
{
    split_job *job = ctx;
    const tpk_mesh *src = job->src;
    split_worker *me = &job->workers[w];
    tpk_plain_split *f = &me->found;
    int64_t t = me->start, hard_capacity = 0;
    for (int64_t c = begin; c < end; c++) {
        /* Every 2^16 cells: a few hundred reports for 10M cells; worker 0 speaks for all. */
        if (w == 0 && job->progress && !((c - begin) & 0xffff))
            job->progress->fn(job->progress->user, (double)(c - begin) / (double)(end - begin));
        int type = src->cell_types[c];
        const int32_t *nodes = src->cell_conn + src->cell_offsets[c];
        if (!plain_max_tets(type) && type != TPK_CELL_POLYHEDRON) /* lower-dimensional */
            continue;
        int made = -1, mirrored = 0;
        if (type == TPK_CELL_TETRA) {
            memcpy(job->tets + 4 * t, nodes, 4 * sizeof *nodes); /* orientation: tpk_orient */
            made = 1;
        } else if (type != TPK_CELL_POLYHEDRON) {
            made = tpk_split_cell(type, nodes, job->points, job->tets + 4 * t, &mirrored);
        }
        if (made < 0) {
            if (remember_hard(f, c, &hard_capacity))
                me->out_of_memory = 1;
            continue;
        }
        if (mirrored && f->mirrored_cells++ == 0)
            f->first_mirrored_cell = c;
        f->cells_into[made]++;
        for (int i = 0; i < made; i++) {
            job->tet_source[t + i] = (int32_t)c;
            f->flat_tets += type != TPK_CELL_TETRA && tpk_tet_is_flat(job->points, job->tets + 4 * (t + i));
        }
        t += made;
    }
    f->tet_count = t - me->start;
}

/* Worker by worker in cell order: blocks moved down next to each other, counts and lists merged. */
static int merge_workers(split_job *job, int threads, tpk_plain_split *res)
{
    int64_t hard_total = 0, t = 0;
    for (int w = 0; w < threads; w++)
        hard_total += job->workers[w].found.hard_count;
    res->hard = malloc(sizeof *res->hard * (size_t)(hard_total ? hard_total : 1));
    int failed = !res->hard;
    for (int w = 0; w < threads; w++) {
        split_worker *k = &job->workers[w];
        failed |= k->out_of_memory;
        if (k->start != t) {
            memmove(job->tets + 4 * t, job->tets + 4 * k->start, sizeof *job->tets * 4 * (size_t)k->found.tet_count);
            memmove(job->tet_source + t, job->tet_source + k->start, sizeof *job->tet_source * (size_t)k->found.tet_count);
        }
        t += k->found.tet_count;
        for (int i = 0; i < 7; i++)
            res->cells_into[i] += k->found.cells_into[i];
        if (k->found.mirrored_cells && res->mirrored_cells == 0)
            res->first_mirrored_cell = k->found.first_mirrored_cell;
        res->mirrored_cells += k->found.mirrored_cells;
        res->flat_tets += k->found.flat_tets;
        if (res->hard && k->found.hard_count)
            memcpy(res->hard + res->hard_count, k->found.hard, sizeof *res->hard * (size_t)k->found.hard_count);
        res->hard_count += k->found.hard_count;
        free(k->found.hard);
    }
    res->tet_count = t;
    return failed ? -1 : 0;
}

int tpk_split_plain(const tpk_mesh *src, const double *points, int threads, const tpk_tetra_progress *progress,
                    int32_t *tets, int32_t *tet_source, tpk_plain_split *res)
{
    memset(res, 0, sizeof *res);
    threads = tpk_threads_for(src->cell_count, tpk_thread_count(threads), 65536);
    split_worker workers[TPK_MAX_THREADS];
    memset(workers, 0, sizeof workers);
    int64_t start = 0;
    for (int w = 0; w < threads; w++) {
        int64_t begin, end;
        tpk_parallel_range(src->cell_count, threads, w, &begin, &end);
        workers[w].start = start;
        for (int64_t c = begin; c < end; c++)
            start += plain_max_tets(src->cell_types[c]);
    }
    split_job job = {src, points, progress, tets, tet_source, workers};
    tpk_parallel_for(src->cell_count, threads, split_range, &job);
    if (merge_workers(&job, threads, res)) {
        free(res->hard);
        res->hard = NULL;
        return -1;
    }
    return 0;
}
