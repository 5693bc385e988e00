/* Check 614 and the 6xx checks of every part of a part set (spec §15): the parts must open and match
 * the manifest (else the set is unusable: exit 2), each part must keep every MUST of a .tpk, and every
 * link must be answered by the same face from the other side. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "tetpack.h"

typedef struct part_view {
    tpk_file *file;
    tpk_mesh_arrays arrays;
    const tpk_link *links;
    uint64_t link_count;
    double origin[3];
} part_view;

static void world(const part_view *v, int32_t id, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = v->origin[k] + (double)v->arrays.positions[3 * (int64_t)id + k];
}

/* The link of part q for shell face s, or NULL. */
static const tpk_link *link_for(const part_view *q, int32_t s)
{
    int64_t lo = 0, hi = (int64_t)q->link_count - 1;
    while (lo <= hi) {
        int64_t mid = (lo + hi) / 2;
        if (q->links[mid].face == s)
            return &q->links[mid];
        if (q->links[mid].face < s)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return NULL;
}

/* What is wrong with link l of part p, or NULL (spec §15.4). */
static const char *link_problem(const part_view *parts, uint32_t p, const tpk_link *l)
{
    const part_view *q = &parts[l->part];
    const tpk_shell_face *mine = &parts[p].arrays.shell[l->face], *theirs = &q->arrays.shell[l->other_face];
    if (theirs->t != l->other_tet)
        return "other_tet is not the tet of the other face";
    const tpk_link *back = link_for(q, l->other_face);
    if (!back || back->part != (int32_t)p || back->other_face != l->face || back->other_tet != mine->t)
        return "the other part does not link the face back";
    const int32_t a[3] = {mine->a, mine->b, mine->c}, b[3] = {theirs->a, theirs->b, theirs->c};
    int match[3];
    for (int i = 0; i < 3; i++) {
        double pa[3], pb[3];
        world(&parts[p], a[i], pa);
        match[i] = -1;
        for (int j = 0; j < 3; j++) {
            world(q, b[j], pb);
            if (pa[0] == pb[0] && pa[1] == pb[1] && pa[2] == pb[2])
                match[i] = j;
        }
        if (match[i] < 0)
            return "a vertex of the face has no vertex at the same position across the cut";
    }
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if ((a[i] < a[j]) != (b[match[i]] < b[match[j]]))
                return "the face's vertex ids are not in the same order on both sides";
    return NULL;
}

static void check_links(tpk_check_report *report, const part_view *parts, uint32_t count)
{
    tpk_check_count(report, 614, 0);
    for (uint32_t p = 0; p < count; p++)
        for (uint64_t k = 0; k < parts[p].link_count; k++) {
            const tpk_link *l = &parts[p].links[k];
            const char *why = link_problem(parts, p, l);
            if (!why)
                continue;
            tpk_example *ex = tpk_check_hit(report, 614, "face");
            if (ex) {
                int64_t ids[5] = {l->face, p, l->part, l->other_face, l->other_tet};
                tpk_example_ids(ex, 5, ids);
                tpk_example_note(ex, "shell face %d of part %u: %s", l->face, p, why);
            }
        }
}

static int load_part(tpk_partset *set, uint32_t p, part_view *v, tpk_diag *diag)
{
    v->file = tpk_partset_file(set, p);
    tpk_partset_origin(set, v->origin);
    tpk_result r = tpk_load_arrays(v->file, TPK_LAYOUT_TET16, NULL, 0, &v->arrays);
    if (r == TPK_ERR_NOT_FOUND)
        r = tpk_load_arrays(v->file, TPK_LAYOUT_TET20, NULL, 0, &v->arrays);
    if (r == TPK_ERR_NOT_FOUND)
        r = tpk_load_arrays(v->file, TPK_LAYOUT_TET32, NULL, 0, &v->arrays);
    if (r == TPK_OK)
        r = tpk_partset_links(set, p, &v->links, &v->link_count);
    if (r != TPK_OK)
        return tpk_diag_fail(diag, "part %u: %s", p, tpk_error_text(v->file));
    return 0;
}

int tpk_check_set(const char *path, tpk_check_report *report, tpk_diag *diag)
{
    tpk_partset *set = NULL;
    char err[1024] = "";
    tpk_result r = tpk_partset_open(&set, path, NULL, NULL, NULL, err, sizeof err);
    if (r != TPK_OK)
        return tpk_diag_fail(diag, "%s", err[0] ? err : tpk_result_string(r));
    snprintf(report->format, sizeof report->format, "tpkset");
    uint32_t count = tpk_partset_part_count(set);
    part_view *parts = calloc(count, sizeof *parts);
    int rc = parts ? 0 : tpk_diag_fail(diag, "out of memory");
    for (uint32_t p = 0; rc == 0 && p < count; p++) {
        tpk_part_record rec;
        tpk_partset_get_part(set, p, &rec);
        rc = tpk_check_tpk_file(rec.file, tpk_partset_file(set, p), report, diag); /* 600..613, per part */
        report->vertices += (int64_t)rec.vertex_count;
        report->tets += (int64_t)rec.tet_count;
        report->cells += (int64_t)rec.tet_count;
    }
    int usable = rc == 0;
    for (int id = 600; usable && id <= 613; id++)
        usable = tpk_check_finding(report, id)->count == 0; /* links are read only from sound parts */
    for (uint32_t p = 0; usable && p < count; p++)
        rc = load_part(set, p, &parts[p], diag);
    if (usable && rc == 0)
        check_links(report, parts, count);
    report->ran[6] = 1;
    free(parts);
    tpk_partset_close(set);
    return rc;
}
