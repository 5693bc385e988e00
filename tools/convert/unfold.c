/* Connect with the writer's promise for TPK-M06 (pipeline stage 4, docs/ARCHITECTURE.md §4): neighbours,
 * then the folds among them (folds.c), and the policy for each kind. A tet orient turned over that folds
 * against a neighbour is a bad cell (refused, or left out and the rest connected again); a fold between
 * tets as the source listed them is an overlap in the source (refused by name, or cut). What comes out
 * has no two neighbours on the same side of their face. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "pipeline.h"

/* A tet that orient turned over and that lies on the same side of a face as its neighbour: turned over,
 * it folds against that neighbour; left as it was, it is inverted. Either way its geometry overlaps the
 * mesh (a sliver pushed through its own face, or one inverted by rounding to float32), so it is a bad
 * cell, not a labeling (docs/ARCHITECTURE.md §4). Marks them in `bad` and returns how many. */
static int64_t mark_folding_turned(const int32_t *neighbors, const uint8_t *turned_over, const int64_t *folds,
                                   int64_t fold_count, uint8_t *bad)
{
    int64_t count = 0;
    for (int64_t i = 0; i < fold_count; i++) {
        int64_t t = folds[i] / 4, u = neighbors[folds[i]];
        if (turned_over[t] && !bad[t])
            bad[t] = 1, count++;
        if (turned_over[u] && !bad[u])
            bad[u] = 1, count++;
    }
    return count;
}

static int refuse_folding_turned(const tpk_tetmesh *mesh, const int32_t *neighbors, const uint8_t *turned_over,
                                 const int64_t *folds, int64_t fold_count, int64_t bad_count, tpk_diag *diag)
{
    int64_t first = -1, t = -1; /* the bad tet of the lowest source cell, as first_fold does */
    for (int64_t i = 0; i < fold_count; i++)
        for (int side = 0; side < 2; side++) {
            int64_t x = side ? neighbors[folds[i]] : folds[i] / 4;
            if (turned_over[x] && (t < 0 || (mesh->tet_source && mesh->tet_source[x] < mesh->tet_source[t])))
                first = i, t = x;
        }
    char fold[1200];
    tpk_describe_fold(mesh, neighbors, folds[first], fold, sizeof fold);
    return tpk_diag_fail(diag, "cell %d is inverted, and turning it over would fold it against its neighbour: %s; "
                         "%lld inverted tets are such bad cells (not a node-order question: their geometry "
                         "overlaps the mesh); --skip-bad-cells leaves them out",
                         mesh->tet_source ? mesh->tet_source[t] : (int32_t)t, fold, (long long)bad_count);
}

/* The fold between the lowest source cells (tets may have been reordered), so that the message names
 * the same face whatever the order. */
static int64_t first_fold(const tpk_tetmesh *mesh, const int32_t *neighbors, const int64_t *folds, int64_t fold_count)
{
    int64_t first = 0, best_lo = INT64_MAX, best_hi = INT64_MAX;
    for (int64_t i = 0; mesh->tet_source && i < fold_count; i++) {
        int64_t a = mesh->tet_source[folds[i] / 4], b = mesh->tet_source[neighbors[folds[i]]];
        int64_t lo = a < b ? a : b, hi = a < b ? b : a;
        if (lo < best_lo || (lo == best_lo && hi < best_hi))
            first = i, best_lo = lo, best_hi = hi;
    }
    return folds[first];
}

static int refuse_folds(const tpk_tetmesh *mesh, const int32_t *neighbors, const int64_t *folds, int64_t fold_count,
                        tpk_diag *diag)
{
    char fold[1200];
    tpk_describe_fold(mesh, neighbors, first_fold(mesh, neighbors, folds, fold_count), fold, sizeof fold);
    return tpk_diag_fail(diag, "%lld folded faces (tets on the same side of a face they share: overlapping cells, "
                         "which a file must not link as neighbours, spec TPK-M06); the first: %s; --cut-folds "
                         "cuts the adjacency there (both faces become shell faces, both cells are kept)",
                         (long long)fold_count, fold);
}

/* The bad tets (if any) refused or left out; then connected again, so the folds left are the source's. */
static int drop_folding_turned(tpk_tetmesh *mesh, const uint8_t *turned_over, int flags, int threads,
                               int32_t *neighbors, int64_t **folds, int64_t *fold_count, int64_t *bad_tets,
                               tpk_diag *diag)
{
    uint8_t *bad = calloc((size_t)mesh->tet_count, 1);
    if (!bad)
        return tpk_diag_fail(diag, "out of memory for %lld tets", (long long)mesh->tet_count);
    int64_t count = mark_folding_turned(neighbors, turned_over, *folds, *fold_count, bad);
    int rc = 0;
    if (count > 0 && !(flags & TPK_UNFOLD_SKIP_BAD_TETS)) {
        rc = refuse_folding_turned(mesh, neighbors, turned_over, *folds, *fold_count, count, diag);
    } else if (count > 0) {
        tpk_drop_tets(mesh, bad);
        *bad_tets = count;
        free(*folds);
        *folds = NULL;
        *fold_count = 0;
        if (mesh->tet_count == 0)
            rc = tpk_diag_fail(diag, "no tetrahedra left to write (all %lld were inverted tets that would fold)",
                               (long long)count);
        else if (tpk_connect_folds(mesh->tets, mesh->tet_count, mesh->vertex_count, mesh->points, neighbors, threads,
                                   folds, fold_count, diag) != 0)
            rc = -1;
    }
    free(bad);
    return rc;
}

int tpk_connect_unfolded(tpk_tetmesh *mesh, const uint8_t *turned_over, int flags, int threads, int32_t *neighbors,
                         tpk_unfold_stats *stats, tpk_diag *diag)
{
    int64_t *folds = NULL, fold_count = 0;
    stats->bad_tets = stats->folds_cut = 0;
    int rc = tpk_connect_folds(mesh->tets, mesh->tet_count, mesh->vertex_count, mesh->points, neighbors, threads,
                               &folds, &fold_count, diag) != 0 ? -1 : 0;
    if (rc == 0 && fold_count > 0 && turned_over)
        rc = drop_folding_turned(mesh, turned_over, flags, threads, neighbors, &folds, &fold_count,
                                 &stats->bad_tets, diag);
    if (rc == 0 && fold_count > 0 && !(flags & TPK_UNFOLD_CUT_FOLDS))
        rc = refuse_folds(mesh, neighbors, folds, fold_count, diag);
    if (rc == 0) {
        tpk_cut_folds(mesh->tets, neighbors, folds, fold_count);
        stats->folds_cut = fold_count;
    }
    free(folds);
    return rc;
}
