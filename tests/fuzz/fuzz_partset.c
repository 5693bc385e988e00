/* Fuzz target for part sets (libtetpack/partset.c): the input is split into files (support.h: the
 * manifest set.tpkset first, then "@@ NAME" before each part file), written to a fresh folder on tmpfs,
 * and opened as `tetpack info`/`render` open a set: whole and with a box, each part's record, handle and
 * links read, and the open parts taken as one mesh (libtetpack/set_mesh.c) in a layout that changes with
 * the box, with its arrays, a tet field and a marcher over them. Any result code is fine; a crash, an
 * overread or a leak is a bug. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "support.h"
#include "tetpack.h"

/* The parts as one mesh: what the renderers build and march, so its arrays must be safe to march. */
static void use_set_mesh(tpk_partset *set, tpk_layout layout)
{
    tpk_set_mesh *mesh = NULL;
    char err[256];
    if (tpk_set_mesh_create(&mesh, set, layout, err, sizeof err) != TPK_OK) {
        if (mesh)
            abort(); /* a failure leaves nothing made */
        return;
    }
    tpk_mesh_arrays arrays;
    const float *tet_values;
    tpk_set_mesh_tet_field(mesh, "f", 0, &tet_values, err, sizeof err);
    if (tpk_set_mesh_arrays(mesh, NULL, 0, &arrays, err, sizeof err) == TPK_OK) {
        tpk_marcher *marcher = NULL;
        if (tpk_marcher_create(&marcher, &arrays) == TPK_OK) {
            static const double org[3] = {-3, -2.5, -2}, dir[3] = {1, 0.83, 0.71};
            tpk_march_ray(marcher, org, dir, 0, 1e30, NULL, NULL, NULL);
            tpk_marcher_destroy(marcher);
        }
    }
    tpk_set_mesh_destroy(mesh);
}

static void use_set(tpk_partset *set, tpk_layout layout)
{
    double origin[3];
    tpk_partset_origin(set, origin);
    for (uint32_t i = 0; i < tpk_partset_part_count(set); i++) {
        tpk_part_record record;
        tpk_partset_get_part(set, i, &record);
        tpk_file *part = tpk_partset_file(set, i);
        if (!part)
            continue;
        const tpk_link *links;
        uint64_t link_count;
        tpk_partset_links(set, i, &links, &link_count);
        tpk_partset_links(set, i, &links, &link_count); /* the second call hands out what the first decoded */
    }
    use_set_mesh(set, layout);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *dir = tpk_fuzz_fresh_dir("set");
    if (tpk_fuzz_split_files(dir, "set.tpkset", data, size) == 0)
        return 0;
    char manifest[512];
    snprintf(manifest, sizeof manifest, "%s/set.tpkset", dir);
    static const double box_min[3] = {-0.25, -0.25, -0.25}, box_max[3] = {0.5, 0.5, 0.5};
    tpk_open_options options = {.size = sizeof options,
                                .limits = {.max_chunks = 256, .max_chunk_bytes = 1u << 20, .max_total_bytes = 4u << 20}};
    for (int boxed = 0; boxed < 2; boxed++) {
        tpk_partset *set = NULL;
        char err[256];
        if (tpk_partset_open(&set, manifest, &options, boxed ? box_min : NULL, boxed ? box_max : NULL, err,
                             sizeof err) != TPK_OK) {
            if (set)
                abort(); /* a failure leaves nothing open */
            continue;
        }
        use_set(set, boxed ? TPK_LAYOUT_TET32 : TPK_LAYOUT_TET16);
        tpk_partset_close(set);
    }
    return 0;
}
