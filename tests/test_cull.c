/* Culling blocks (spec §17, format 1.4) in libtetpack: a real mesh converted with --cull, then
 * tpk_recover_block gives every block's tets as tpk_recover_tets gives them, in each layout; damaged
 * blocks (a seed's n3, its vertices, an interval too short) fail by name
 * rather than giving other tets; a bvh over the blocks selects the tets a bvh over all tets selects, for
 * any thread count, and answers only what it selected. Converter and check side: test_check_tpk's
 * cull tests and tests/cli/render_iso_culling.sh. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "convert/convert.h"
#include "harness.h"
#include "tetpack.h"
#include "tpk_assert.h"

static tpk_file *converted(const char *name, const char *source)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = tpk_data_path(source);
    o.output = tpk_temp_path(name);
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET20 | TPK_LAYOUT_BIT_TET32;
    o.cull = 1;
    o.threads = 2;
    tpk_diag diag = {0};
    tpk_convert_report rep;
    if (tpk_convert_checked(&o, &rep, &diag) != 0)
        return NULL;
    tpk_file *f = NULL;
    char err[256];
    return tpk_open_path(&f, o.output, NULL, err, sizeof err) == TPK_OK ? f : NULL;
}

/* A writable copy of the blocks' words, and a tpk_cull over it. */
typedef struct cull_copy {
    int32_t *words;
    tpk_cull cull;
} cull_copy;

static void copy_cull(const tpk_cull *c, cull_copy *out)
{
    size_t n = 4 + 2 * (c->block_count + 1) + TPK_CULL_SEED_WORDS * c->seed_count + 2 * c->interval_count;
    out->words = malloc(sizeof *out->words * n);
    memcpy(out->words, c->seed_start - 4, sizeof *out->words * n);
    out->cull = *c;
    out->cull.seed_start = out->words + 4;
    out->cull.interval_start = out->cull.seed_start + c->block_count + 1;
    out->cull.seeds = out->cull.interval_start + c->block_count + 1;
    out->cull.intervals = out->cull.seeds + TPK_CULL_SEED_WORDS * c->seed_count;
}

TPK_TEST(blocks_recover_as_the_walk)
{
    tpk_file *f = converted("cull_exo.tpk", "seacas/exomerge_unit_test.e");
    CHECK(f);
    tpk_cull cull;
    CHECK(tpk_load_cull(f, &cull) == TPK_OK);
    CHECK(cull.block_tets == 256 && cull.block_count > 8 && cull.seed_count >= cull.block_count);
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET16, TPK_LAYOUT_TET20, TPK_LAYOUT_TET32};
    for (int k = 0; k < 3; k++) {
        tpk_mesh_arrays m;
        CHECK(tpk_load_arrays(f, layouts[k], NULL, 0, &m) == TPK_OK);
        size_t q = 16 * (size_t)m.tet_count;
        int32_t *all = malloc(q), *blocks = malloc(q);
        CHECK(tpk_recover_tets(&m, all) == TPK_OK);
        memset(blocks, 0x5a, q);
        for (uint64_t b = 0; b < cull.block_count; b++)
            CHECK_MSG(tpk_recover_block(&m, &cull, b, blocks + 4 * b * cull.block_tets) == TPK_OK,
                      "Tet%d block %llu", (int)layouts[k], (unsigned long long)b);
        CHECK_MSG(!memcmp(all, blocks, q), "Tet%d: the blocks' tets are not the walk's", (int)layouts[k]);
        CHECK(tpk_recover_block(&m, &cull, cull.block_count, blocks) == TPK_ERR_INVALID_ARGUMENT);
        free(all);
        free(blocks);
    }
    tpk_close(f);
}

TPK_TEST(damaged_blocks_fail)
{
    tpk_file *f = converted("cull_damage.tpk", "seacas/exomerge_unit_test.e");
    CHECK(f);
    tpk_cull cull;
    tpk_mesh_arrays m;
    CHECK(tpk_load_cull(f, &cull) == TPK_OK && tpk_load_arrays(f, TPK_LAYOUT_TET16, NULL, 0, &m) == TPK_OK);
    int32_t *dst = malloc(16 * (size_t)cull.block_tets);
    uint64_t b = cull.block_count / 2; /* an inner block */
    int32_t s = cull.seed_start[b];
    cull_copy c;
    struct {
        const char *what;
        int word;     /* of the seed (0..5), or -1: the block's last interval one id shorter */
        int32_t delta;
    } damage[] = {{"n3 of another tet", 5, 1}, {"a vertex replaced", 1, 1}, {"an interval too short", -1, -1}};
    for (size_t d = 0; d < sizeof damage / sizeof damage[0]; d++) {
        copy_cull(&cull, &c);
        if (damage[d].word >= 0) {
            int32_t *w = c.words + 4 + 2 * (cull.block_count + 1) + TPK_CULL_SEED_WORDS * (size_t)s;
            w[damage[d].word] += damage[d].delta;
            if (damage[d].word == 1 && (w[1] == w[2] || w[1] == w[3] || w[1] == w[4]))
                w[1] += 1;
        } else {
            int32_t *iv = c.words + 4 + 2 * (cull.block_count + 1) + TPK_CULL_SEED_WORDS * cull.seed_count +
                          2 * (size_t)(cull.interval_start[b + 1] - 1);
            iv[1] += damage[d].delta; /* its last vertex falls out */
        }
        tpk_result r = tpk_recover_block(&m, &c.cull, b, dst);
        CHECK_MSG(r == TPK_ERR_MESH || r == TPK_ERR_CORRUPT, "%s: %s", damage[d].what, tpk_result_string(r));
        free(c.words);
    }
    free(dst);
    tpk_close(f);
}

/* Every ray's pieces: a hash of (tet, t_in, t_out) in order, for the selected value. */
typedef struct piece_hash {
    uint64_t h, pieces;
} piece_hash;

static int on_piece(void *user, const tpk_segment *s)
{
    piece_hash *p = user;
    uint64_t w[3];
    w[0] = (uint64_t)s->tet;
    memcpy(&w[1], &s->t_in, 8);
    memcpy(&w[2], &s->t_out, 8);
    for (int i = 0; i < 3; i++)
        p->h = (p->h ^ w[i]) * 1099511628211ull;
    p->pieces++;
    return 0;
}

static piece_hash rays(const tpk_range_bvh *b, const double *lo, const double *hi, double value)
{
    piece_hash p = {1469598103934665603ull, 0};
    for (int i = 0; i < 24; i++)
        for (int j = 0; j < 24; j++) {
            double org[3] = {lo[0] + (hi[0] - lo[0]) * (i + 0.5) / 24, lo[1] + (hi[1] - lo[1]) * (j + 0.5) / 24,
                             hi[2] + (hi[2] - lo[2])};
            double dir[3] = {0.01 * (i - 12) / 24, 0.013 * (j - 12) / 24, -1};
            if (tpk_march_ray_values(b, org, dir, 0, 1e30, &value, 1, on_piece, &p, NULL) != TPK_OK)
                p.pieces = UINT64_MAX;
        }
    return p;
}

TPK_TEST(selected_as_from_all_tets)
{
    tpk_file *f = converted("cull_select.tpk", "seacas/exomerge_unit_test.e");
    CHECK(f);
    tpk_cull cull;
    tpk_mesh_arrays m;
    CHECK(tpk_load_cull(f, &cull) == TPK_OK);
    CHECK(tpk_load_arrays(f, TPK_LAYOUT_TET16, "disp_z", 4, &m) == TPK_OK);
    tpk_marcher *marcher = NULL;
    CHECK(tpk_marcher_create(&marcher, &m) == TPK_OK);
    tpk_file_info info;
    CHECK(tpk_get_info(f, &info) == TPK_OK);
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++)
        lo[k] = info.bounds_min[k], hi[k] = info.bounds_max[k];
    const double values[] = {-0.0195, -0.012, -0.002};
    for (size_t v = 0; v < 3; v++) {
        tpk_range_bvh *all = NULL;
        CHECK(tpk_range_bvh_create_threads(&all, marcher, 1) == TPK_OK);
        CHECK(tpk_range_bvh_select(all, &values[v], 1) == TPK_OK);
        piece_hash want = rays(all, lo, hi, values[v]);
        CHECK(want.pieces > 0 && want.pieces != UINT64_MAX);
        for (int threads = 1; threads <= 3; threads++) {
            tpk_range_bvh *blocks = NULL;
            CHECK(tpk_range_bvh_create_cull(&blocks, marcher, &cull, threads) == TPK_OK);
            double share = tpk_range_bvh_active(blocks, &values[v], 1);
            CHECK(share > 0 && share <= 1);
            CHECK(tpk_range_bvh_select(blocks, &values[v], 1) == TPK_OK);
            piece_hash got = rays(blocks, lo, hi, values[v]);
            CHECK_MSG(got.h == want.h && got.pieces == want.pieces,
                      "iso %g, %d threads: %llu pieces against %llu from all tets", values[v], threads,
                      (unsigned long long)got.pieces, (unsigned long long)want.pieces);
            double other = values[(v + 1) % 3];
            CHECK(tpk_march_ray_values(blocks, lo, hi, 0, 1, &other, 1, on_piece, &got, NULL) ==
                  TPK_ERR_INVALID_ARGUMENT); /* no file-order tree to answer an unselected value */
            CHECK(tpk_range_bvh_tets(blocks) == NULL && tpk_range_bvh_heap(blocks, NULL) == 0);
            tpk_range_bvh_destroy(blocks);
        }
        tpk_range_bvh_destroy(all);
    }
    tpk_marcher_destroy(marcher);
    tpk_close(f);
}
