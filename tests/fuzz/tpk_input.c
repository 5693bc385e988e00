/* The work of the .tpk fuzz targets (tpk_input.h). */
#include "tpk_input.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "render/level_set.h"
#include "support.h"
#include "tetpack.h"

static void read_chunks(tpk_file *file, uint64_t chunk_count)
{
    for (uint64_t i = 0; i < chunk_count; i++) {
        tpk_dir_entry e;
        if (tpk_get_chunk(file, i, &e) != TPK_OK || e.raw_size > FUZZ_MAX_CHUNK_BYTES)
            continue;
        void *dst = malloc(e.raw_size ? (size_t)e.raw_size : 1);
        if (dst)
            tpk_read_chunk(file, i, dst, e.raw_size);
        free(dst);
        const void *view;
        uint64_t view_size;
        tpk_view_chunk(file, i, &view, &view_size);
    }
}

void tpk_fuzz_use_tpk(tpk_file *file)
{
    static const tpk_layout layouts[3] = {TPK_LAYOUT_TET32, TPK_LAYOUT_TET20, TPK_LAYOUT_TET16};
    tpk_verify(file);
    tpk_cull cull; /* culling blocks (spec §17): the structure checked on load, each block walked */
    int have_cull = tpk_load_cull(file, &cull) == TPK_OK;
    for (int k = 0; k < 3; k++) {
        tpk_mesh_arrays arrays;
        if (tpk_load_arrays(file, layouts[k], NULL, 0, &arrays) != TPK_OK || !have_cull)
            continue;
        int32_t *tets = malloc(16 * (size_t)cull.block_tets);
        for (uint64_t b = 0; tets && b < cull.block_count && b < 64; b++)
            tpk_recover_block(&arrays, &cull, b, tets);
        free(tets);
    }
    for (uint32_t f = 0; f < tpk_field_count(file); f++) {
        tpk_field_desc desc;
        double time;
        if (tpk_get_field(file, f, &desc) == TPK_OK)
            tpk_get_time(file, desc.step_count - 1, &time);
    }
    tpk_file_info info;
    if (tpk_get_info(file, &info) == TPK_OK)
        read_chunks(file, info.chunk_count);
}

/* Levels of detail (spec §16): each opened over the file's bytes and used as a file (check_file runs
 * check 615 on them); then as render and view open them, with META's level figures (level_set.c). */
static void use_levels(tpk_file *file, const tpk_open_options *options)
{
    for (uint32_t k = 1; k <= tpk_level_count(file) && k <= TPK_MAX_LEVELS; k++) {
        tpk_file *level = NULL;
        char err[256];
        if (tpk_open_level(file, k, options, &level, err, sizeof err) == TPK_OK)
            tpk_fuzz_use_tpk(level);
        tpk_close(level);
    }
    tpk_level_set levels;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = tpk_fuzz_ignore;
    tpk_level_set_open(&levels, file, "fuzz.tpk", &diag);
    tpk_level_set_close(&levels);
}

/* `tetpack check` on the handle: the 6xx groups, then the mesh groups on the tets they recovered. */
static void check_file(tpk_file *file)
{
    tpk_check_options options;
    tpk_check_options_default(&options);
    options.threads = 1;
    tpk_check_report report;
    if (tpk_check_report_init(&report, &options) != 0)
        return;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    diag.warn = tpk_fuzz_ignore;
    int32_t *tets = NULL;
    tpk_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    /* as the driver (check.c): the levels after the 6xx groups; the recovered tets are the mesh build's
     * from here, on every path */
    int rc = tpk_check_tpk_file_tets("fuzz.tpk", file, &report, &tets, &diag);
    if (rc == 0)
        tpk_check_levels("fuzz.tpk", file, &report, &diag);
    if (rc == 0 && tpk_check_tpk_mesh_tets(file, tets, &mesh, &diag) == 0) {
        tpk_check_input in = {&mesh, "fuzz.tpk", &diag};
        if (tpk_check_vertices(&in, &report, &diag) == 0 && tpk_check_cells(&in, &report, &diag) == 0 &&
            tpk_check_topology(&in, &report, &diag) == 0)
            tpk_check_fields(&in, &report, &diag);
    }
    tpk_mesh_free(&mesh);
    tpk_check_report_free(&report);
}

void tpk_fuzz_tpk_input(const uint8_t *data, size_t size)
{
    static const uint32_t flag_sets[2] = {0, TPK_OPEN_VERIFY_ALL};
    for (int k = 0; k < 2; k++) {
        tpk_open_options options = {.size = sizeof options, .flags = flag_sets[k],
                                    .limits = {.max_chunks = 256,
                                               .max_chunk_bytes = FUZZ_MAX_CHUNK_BYTES,
                                               .max_total_bytes = 4 * FUZZ_MAX_CHUNK_BYTES}};
        tpk_file *file = NULL;
        char err[256];
        if (tpk_open_memory(&file, data, size, &options, err, sizeof err) != TPK_OK)
            continue;
        tpk_fuzz_use_tpk(file);
        use_levels(file, &options);
        if (k == 0)
            check_file(file);
        tpk_close(file);
    }
}
