/* Lazy loading: a render of one layout of a file that holds three reads only the chunks it uses
 * (POS3, that layout, SHEL, one FDAT step, and FDSC at open), counted with tpk_get_chunk_use, for
 * uncompressed (zero-copy) and zstd (decoded) files. */
#include <string.h>

#include "convert/convert.h"
#include "harness.h"
#include "render/render.h"
#include "tetpack.h"
#include "tpk_assert.h"

/* The bundled sample converted with all three layouts and a point field. */
static int convert_three_layouts(const char *output, int zstd_level, char *msg, size_t cap)
{
    tpk_convert_options o;
    memset(&o, 0, sizeof o);
    o.input = TPK_SOURCE_DIR "/samples/cylinder.vtk";
    o.output = output;
    o.layouts = TPK_LAYOUT_BIT_TET16 | TPK_LAYOUT_BIT_TET20 | TPK_LAYOUT_BIT_TET32;
    o.zstd_level = zstd_level;
    tpk_convert_report report;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_convert_checked(&o, &report, &diag) != 0) {
        snprintf(msg, cap, "%s", diag.message);
        return -1;
    }
    return 0;
}

/* "POS3 TT20 SHEL FDSC FDAT" : the tags of the chunks read so far, in directory order. */
static void chunks_read(const tpk_file *file, char *out, size_t cap)
{
    tpk_file_info info;
    tpk_get_info(file, &info);
    out[0] = 0;
    for (uint64_t i = 0; i < info.chunk_count; i++) {
        tpk_dir_entry e;
        uint32_t use = 0;
        if (tpk_get_chunk(file, i, &e) != TPK_OK || tpk_get_chunk_use(file, i, &use) != TPK_OK || !(use & TPK_CHUNK_USE_READ))
            continue;
        char tag[5] = {(char)(e.tag & 0xff), (char)((e.tag >> 8) & 0xff), (char)((e.tag >> 16) & 0xff), (char)(e.tag >> 24), 0};
        snprintf(out + strlen(out), cap - strlen(out), "%s%s", out[0] ? " " : "", tag);
    }
}

static int render_small(const tpk_file *file, const tpk_mesh_arrays *mesh)
{
    tpk_transfer_function tf;
    tpk_diag diag;
    memset(&diag, 0, sizeof diag);
    if (tpk_tf_load("viridis", &tf, &diag) != 0)
        return -1;
    tpk_file_info info;
    tpk_get_info(file, &info);
    tpk_render_options opt;
    tpk_render_options_default(&opt);
    opt.width = opt.height = 32;
    opt.tf = &tf;
    opt.range_min = 290;
    opt.range_max = 381;
    tpk_camera_default(info.bounds_min, info.bounds_max, &opt.camera);
    uint8_t rgba[32 * 32 * 4];
    tpk_render_stats stats;
    return tpk_render_cpu(mesh, &opt, rgba, &stats, &diag) == 0 && stats.tet_steps > 0 ? 0 : -1;
}

static void check_one_layout(int zstd_level)
{
    char msg[1024] = "", read[256];
    const char *path = tpk_temp_path(zstd_level ? "three_zstd.tpk" : "three.tpk");
    CHECK_MSG(convert_three_layouts(path, zstd_level, msg, sizeof msg) == 0, "%s", msg);
    tpk_file *file = NULL;
    CHECK_MSG(tpk_open_path(&file, path, NULL, msg, sizeof msg) == TPK_OK, "%s", msg);
    chunks_read(file, read, sizeof read);
    CHECK_MSG(!strcmp(read, "FDSC"), "after open: %s", read); /* the field descriptors only */
    tpk_mesh_arrays mesh;
    CHECK(tpk_load_arrays(file, TPK_LAYOUT_TET20, NULL, 0, &mesh) == TPK_OK);
    CHECK(render_small(file, &mesh) == 0);
    chunks_read(file, read, sizeof read);
    /* Not TT16, TT32, TMAP, VMAP or META. */
    CHECK_MSG(!strcmp(read, "POS3 TT20 SHEL FDSC FDAT"), "after loading Tet20 and rendering: %s", read);
    uint64_t i;
    uint32_t use;
    CHECK(tpk_find_chunk(file, TPK_TAG_TT20, 0, 0, &i) == TPK_OK);
    CHECK(tpk_get_chunk_use(file, i, &use) == TPK_OK && use == (TPK_CHUNK_USE_READ | TPK_CHUNK_USE_VERIFIED));
    CHECK(tpk_find_chunk(file, TPK_TAG_TT32, 0, 0, &i) == TPK_OK);
    CHECK(tpk_get_chunk_use(file, i, &use) == TPK_OK && use == 0);
    tpk_close(file);
}

TPK_TEST(render_reads_one_layout)
{
    check_one_layout(0);
}

TPK_TEST(render_reads_one_layout_zstd)
{
    check_one_layout(3);
}

TPK_TEST(verify_reads_everything)
{
    char msg[1024] = "", read[256];
    const char *path = tpk_temp_path("three_verify.tpk");
    CHECK_MSG(convert_three_layouts(path, 0, msg, sizeof msg) == 0, "%s", msg);
    tpk_file *file = NULL;
    CHECK_MSG(tpk_open_path(&file, path, NULL, msg, sizeof msg) == TPK_OK, "%s", msg);
    CHECK(tpk_verify(file) == TPK_OK);
    chunks_read(file, read, sizeof read);
    CHECK_MSG(!strcmp(read, "POS3 TT16 TT20 TT32 SHEL FDSC FDAT TMAP VMAP META"), "after tpk_verify: %s", read);
    uint32_t use;
    CHECK(tpk_get_chunk_use(file, 1000, &use) == TPK_ERR_INVALID_ARGUMENT);
    tpk_close(file);
}
