/* Levels of detail (format 1.3, spec §16): a LEVL chunk holds a complete file of one coarser level,
 * stored uncompressed, so a level opens over the parent's mapping without a copy. */
#include <stdio.h>

#include "tetpack.h"

uint32_t tpk_level_count(const tpk_file *file)
{
    tpk_file_info info;
    if (!file || tpk_get_info(file, &info) != TPK_OK)
        return 0;
    uint32_t n = 0;
    for (uint64_t i = 0; i < info.chunk_count; i++) {
        tpk_dir_entry e;
        if (tpk_get_chunk(file, i, &e) == TPK_OK && e.tag == TPK_TAG_LEVL)
            n++;
    }
    return n;
}

tpk_result tpk_open_level(tpk_file *file, uint32_t level, const tpk_open_options *options, tpk_file **out,
                          char *err_text, size_t err_cap)
{
    if (out)
        *out = NULL;
    if (!file || !out || level == 0) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "level %u: levels are numbered from 1 (level 0 is the file itself)", level);
        return TPK_ERR_INVALID_ARGUMENT;
    }
    uint64_t i;
    if (tpk_find_chunk(file, TPK_TAG_LEVL, level, 0, &i) != TPK_OK) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "no level %u: the file has %u level%s of detail", level,
                     tpk_level_count(file), tpk_level_count(file) == 1 ? "" : "s");
        return TPK_ERR_NOT_FOUND;
    }
    const void *data;
    uint64_t size;
    tpk_result r = tpk_view_chunk(file, i, &data, &size);
    if (r != TPK_OK) {
        if (err_text && err_cap)
            snprintf(err_text, err_cap, "level %u: %s", level, tpk_error_text(file));
        return r;
    }
    char inner[512] = "";
    r = tpk_open_memory(out, data, (size_t)size, options, inner, sizeof inner);
    if (r != TPK_OK && err_text && err_cap)
        snprintf(err_text, err_cap, "level %u (its LEVL chunk): %s", level, inner);
    return r;
}
