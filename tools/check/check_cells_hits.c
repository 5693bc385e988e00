/* Per-worker findings of the cells group, merged in worker order so examples stay lowest-id first. */
#include <stdlib.h>
#include <string.h>

#include "check_cells_internal.h"

static tpk_example *next_slot(tpk_cell_hits *hits, int k)
{
    if (hits->example_count[k] >= hits->max_examples)
        return NULL;
    if (hits->example_count[k] == hits->example_cap[k]) {
        int cap = hits->example_cap[k] ? 2 * hits->example_cap[k] : 4;
        if (cap > hits->max_examples)
            cap = hits->max_examples;
        tpk_example *grown = realloc(hits->examples[k], (size_t)cap * sizeof *grown);
        if (!grown)
            return NULL; /* examples are best effort; the count stays right */
        hits->examples[k] = grown;
        hits->example_cap[k] = cap;
    }
    tpk_example *ex = &hits->examples[k][hits->example_count[k]++];
    memset(ex, 0, sizeof *ex);
    return ex;
}

tpk_example *tpk_cell_hit(tpk_cell_hits *hits, int id, int64_t cell)
{
    int k = id - TPK_CELLS_FIRST_ID;
    hits->count[k]++;
    tpk_example *ex = next_slot(hits, k);
    if (ex) {
        ex->kind = "cell";
        ex->id_count = 1;
        ex->ids[0] = cell;
    }
    return ex;
}

void tpk_cell_hits_append(tpk_cell_hits *into, tpk_cell_hits *from)
{
    for (int k = 0; k < TPK_CELLS_ID_COUNT; k++) {
        into->count[k] += from->count[k];
        for (int i = 0; i < from->example_count[k]; i++) {
            tpk_example *ex = next_slot(into, k);
            if (!ex)
                break;
            *ex = from->examples[k][i];
        }
    }
    tpk_cell_hits_free(from);
}

void tpk_cell_hits_report(tpk_cell_hits *hits, tpk_check_report *report)
{
    for (int k = 0; k < TPK_CELLS_ID_COUNT; k++) {
        int id = TPK_CELLS_FIRST_ID + k;
        int64_t with_example = hits->example_count[k];
        for (int i = 0; i < hits->example_count[k]; i++) {
            tpk_example *ex = tpk_check_hit(report, id, hits->examples[k][i].kind);
            if (ex)
                *ex = hits->examples[k][i];
        }
        tpk_check_count(report, id, hits->count[k] - with_example);
    }
    tpk_cell_hits_free(hits);
}

void tpk_cell_hits_free(tpk_cell_hits *hits)
{
    for (int k = 0; k < TPK_CELLS_ID_COUNT; k++) {
        free(hits->examples[k]);
        hits->examples[k] = NULL;
        hits->example_count[k] = hits->example_cap[k] = 0;
    }
}

void tpk_cell_example_vertices(tpk_example *ex, const tpk_mesh *mesh, int64_t cell)
{
    if (!ex)
        return;
    int64_t b = mesh->cell_offsets[cell], e = mesh->cell_offsets[cell + 1];
    ex->ids[0] = cell;
    ex->id_count = 1;
    for (int64_t i = b; i < e && ex->id_count < TPK_CHECK_MAX_IDS; i++)
        ex->ids[ex->id_count++] = mesh->cell_conn[i];
}

void tpk_cell_centre(const tpk_mesh *mesh, int64_t cell, double centre[3])
{
    int64_t b = mesh->cell_offsets[cell], e = mesh->cell_offsets[cell + 1];
    centre[0] = centre[1] = centre[2] = 0;
    for (int64_t i = b; i < e; i++)
        for (int k = 0; k < 3; k++)
            centre[k] += mesh->points[3 * (int64_t)mesh->cell_conn[i] + k];
    for (int k = 0; e > b && k < 3; k++)
        centre[k] /= (double)(e - b);
}
