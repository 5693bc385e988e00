/* Fuzz target for part sets (libtetpack/partset.c): the input is split into files (support.h: the
 * manifest set.tpkset first, then "@@ NAME" before each part file), written to a fresh folder on tmpfs,
 * and opened as `tetpack info`/`render` open a set: whole and with a box, each part's record, handle and
 * links read. Any result code is fine; a crash, an overread or a leak is a bug. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "support.h"
#include "tetpack.h"

static void use_set(tpk_partset *set)
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
        use_set(set);
        tpk_partset_close(set);
    }
    return 0;
}
