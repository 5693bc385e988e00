/* Check 615 (TPK-L01, spec §16) and the 6xx checks of every level of detail of a .tpk: each LEVL chunk
 * must open as a file of its own and keep every MUST of a .tpk (600..613, run on it with "LEVEL k" in
 * their examples), and the levels must be levels of this file: numbered 1..n, fewer tets at each level
 * (and fewer than the file), the same fields (name, association, steps) and layouts, positions within the
 * file's bounds, and no LEVL, PART or LINK of their own. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "tetpack.h"

static void level_hit(tpk_check_report *report, uint32_t level, const char *why)
{
    tpk_example *ex = tpk_check_hit(report, 615, "level");
    if (ex) {
        int64_t id = level;
        tpk_example_ids(ex, 1, &id);
        tpk_example_note(ex, "level %u: %s", level, why);
    }
}

static int has_chunk(tpk_file *f, uint32_t tag)
{
    uint64_t i;
    return tpk_find_chunk(f, tag, 0, 0, &i) == TPK_OK;
}

/* What is wrong with level `level` (open as `lf`) against the file and the level before, or NULL. */
static const char *level_problem(tpk_file *file, tpk_file *lf, const tpk_file_info *before, char *why, size_t cap)
{
    tpk_file_info fi, li;
    tpk_get_info(file, &fi);
    tpk_get_info(lf, &li);
    if (li.tet_count >= before->tet_count) {
        snprintf(why, cap, "%llu tets, not fewer than the %llu of the level before it", (unsigned long long)li.tet_count,
                 (unsigned long long)before->tet_count);
        return why;
    }
    for (int k = 0; k < 3; k++)
        if (li.bounds_min[k] < fi.bounds_min[k] || li.bounds_max[k] > fi.bounds_max[k]) {
            snprintf(why, cap, "its bounds on axis %c, [%.17g, %.17g], leave the file's [%.17g, %.17g]", "xyz"[k],
                     li.bounds_min[k], li.bounds_max[k], fi.bounds_min[k], fi.bounds_max[k]);
            return why;
        }
    uint32_t nf = tpk_field_count(file);
    if (tpk_field_count(lf) != nf) {
        snprintf(why, cap, "%u fields, the file has %u", tpk_field_count(lf), nf);
        return why;
    }
    for (uint32_t i = 0; i < nf; i++) {
        tpk_field_desc a, b;
        if (tpk_get_field(file, i, &a) != TPK_OK || tpk_get_field(lf, i, &b) != TPK_OK || strcmp(a.name, b.name) ||
            a.association != b.association || a.step_count != b.step_count) {
            snprintf(why, cap, "field %u is not the file's field %u (name, association and steps)", i, i);
            return why;
        }
    }
    static const uint32_t layouts[3] = {TPK_TAG_TT16, TPK_TAG_TT20, TPK_TAG_TT32};
    for (int k = 0; k < 3; k++)
        if (has_chunk(file, layouts[k]) != has_chunk(lf, layouts[k])) {
            snprintf(why, cap, "its layouts are not the file's (Tet%d %s)", k == 0 ? 16 : k == 1 ? 20 : 32,
                     has_chunk(lf, layouts[k]) ? "added" : "missing");
            return why;
        }
    if (tpk_level_count(lf) > 0 || has_chunk(lf, TPK_TAG_PART) || has_chunk(lf, TPK_TAG_LINK))
        return "it has levels, a part table or links of its own";
    return NULL;
}

int tpk_check_levels(const char *path, tpk_file *file, tpk_check_report *report, tpk_diag *diag)
{
    uint32_t n = tpk_level_count(file);
    tpk_check_count(report, 615, 0);
    tpk_file_info before;
    tpk_get_info(file, &before);
    for (uint32_t k = 1; k <= n; k++) {
        tpk_file *lf = NULL;
        char err[512] = "", why[512];
        if (tpk_open_level(file, k, NULL, &lf, err, sizeof err) != TPK_OK) {
            level_hit(report, k, err);
            continue;
        }
        char name[1200];
        snprintf(name, sizeof name, "%s LEVEL %u", path, k);
        int rc = tpk_check_tpk_file(name, lf, report, diag); /* 600..613 on the level */
        const char *problem = level_problem(file, lf, &before, why, sizeof why);
        if (problem)
            level_hit(report, k, problem);
        tpk_get_info(lf, &before);
        tpk_close(lf);
        if (rc != 0)
            return -1;
    }
    return 0;
}
