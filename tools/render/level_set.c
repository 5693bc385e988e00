/* The levels of detail of an open file (level_set.h): opened over it, with META's figures read by cJSON. */
#include "level_set.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "tetpack_format.h"

/* A number of a level's META entry; NaN when it is missing or not a number (null: not finite). */
static double meta_number(const cJSON *entry, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(entry, key);
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

/* The level figures the converter wrote in META ("levels": [{level, error_max, error_rms, shell_distance}]). */
static void level_errors(tpk_file *file, tpk_level_set *ls)
{
    for (int k = 0; k < ls->count; k++)
        ls->error_max[k] = ls->error_rms[k] = ls->shell_distance[k] = k == 0 ? 0 : NAN;
    uint64_t i;
    tpk_dir_entry e;
    if (tpk_find_chunk(file, TPK_TAG_META, 0, 0, &i) != TPK_OK || tpk_get_chunk(file, i, &e) != TPK_OK ||
        e.raw_size > (1u << 24))
        return;
    char *text = malloc(e.raw_size + 1);
    if (!text || tpk_read_chunk(file, i, text, e.raw_size) != TPK_OK) {
        free(text);
        return;
    }
    cJSON *meta = cJSON_ParseWithLength(text, (size_t)e.raw_size);
    free(text);
    const cJSON *entry;
    cJSON_ArrayForEach(entry, cJSON_GetObjectItemCaseSensitive(meta, "levels")) {
        const cJSON *level = cJSON_GetObjectItemCaseSensitive(entry, "level");
        int k = cJSON_IsNumber(level) ? level->valueint : 0;
        if (k < 1 || k >= ls->count)
            continue;
        ls->error_max[k] = meta_number(entry, "error_max");
        ls->error_rms[k] = meta_number(entry, "error_rms");
        ls->shell_distance[k] = meta_number(entry, "shell_distance");
    }
    cJSON_Delete(meta);
}

int tpk_level_set_open(tpk_level_set *ls, tpk_file *file, const char *path, tpk_diag *diag)
{
    memset(ls, 0, sizeof *ls);
    ls->files[0] = file;
    tpk_file_info info;
    tpk_get_info(file, &info);
    ls->tets[0] = (int64_t)info.tet_count;
    ls->count = 1;
    uint32_t n = tpk_level_count(file);
    for (uint32_t k = 1; k <= n && k <= TPK_MAX_LEVELS; k++) {
        char err[512] = "";
        if (tpk_open_level(file, k, NULL, &ls->files[k], err, sizeof err) != TPK_OK)
            return tpk_diag_fail(diag, "%s: %s", path, err);
        tpk_get_info(ls->files[k], &info);
        ls->tets[k] = (int64_t)info.tet_count;
        ls->count++;
    }
    level_errors(file, ls);
    return 0;
}

void tpk_level_set_close(tpk_level_set *ls)
{
    for (int k = 1; k < ls->count; k++)
        tpk_close(ls->files[k]);
    ls->count = 1;
}

int tpk_level_set_choose(const tpk_level_set *ls, const tpk_cost_model *model, double pixels, double budget)
{
    return model->n > 0 ? tpk_cost_model_pick(model, pixels, ls->tets, ls->count, budget) : ls->count - 1;
}
