/* 6xx: every MUST of spec/tetpack-format.md on an opened .tpk file. First the reader rules (tpk_verify,
 * check 600): a file that breaks one is refused by every reader, so nothing past it is read and the
 * finding says so. Then the mesh invariants TPK-M01..M13 (601..613) on the verified arrays, and the
 * culling blocks TPK-B01 (616) against the same reference; see check_tpk_internal.h for how the layouts
 * are covered. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_tpk_internal.h"
#include "base/parallel.h"

/* The rule a tpk_verify result breaks: open already applied rules 1-15, so what is left is the
 * content of a chunk (16: checksum, decoding; 17: ids). */
static const char *verify_rule(tpk_result r)
{
    switch (r) {
    case TPK_ERR_CHUNK_CHECKSUM:
    case TPK_ERR_DECOMPRESS: return "TPK-R16";
    case TPK_ERR_CORRUPT: return "TPK-R17";
    default: return "reader rule";
    }
}

/* Check 600. Returns 1 when the file passed, 0 when it broke a rule (reported), -1 out of memory. */
static int check_reader_rules(tpk_file *file, tpk_check_report *report, tpk_diag *diag)
{
    tpk_result r = tpk_verify(file);
    if (r == TPK_OK)
        return 1;
    if (r == TPK_ERR_OUT_OF_MEMORY)
        return tpk_diag_fail(diag, "out of memory verifying the file: %s", tpk_error_text(file));
    const char *text = tpk_error_text(file);
    tpk_example *ex = tpk_check_hit(report, 600, "chunk");
    uint64_t chunk;
    if (sscanf(text, "chunk %" SCNu64, &chunk) == 1)
        tpk_example_ids(ex, 1, (const int64_t[]){(int64_t)chunk});
    tpk_example_note(ex, "%s: %s", verify_rule(r), text);
    int where = (int)strcspn(text, ":"); /* "chunk 6 'FDAT' at offset 640" */
    tpk_finding *finding = tpk_check_finding(report, 600);
    snprintf(finding->summary, sizeof finding->summary,
             "%s (%s) in %.*s; checks 601-613 not run: readers refuse the file", verify_rule(r),
             tpk_result_string(r), where < 80 ? where : 80, text);
    return 0;
}

static int find_layout(tpk_file *file, uint32_t tag)
{
    uint64_t i;
    return tpk_find_chunk(file, tag, 0, 0, &i) == TPK_OK;
}

/* Views of positions, shell and every layout present (zero-copy, or decoded once by the handle). */
static int load_arrays(tpkc *c, tpk_diag *diag)
{
    static const struct {
        uint32_t tag;
        tpk_layout layout;
    } layouts[3] = {{TPK_TAG_TT32, TPK_LAYOUT_TET32}, {TPK_TAG_TT20, TPK_LAYOUT_TET20},
                    {TPK_TAG_TT16, TPK_LAYOUT_TET16}};
    c->ref = 0;
    for (int k = 0; k < 3; k++) {
        if (!find_layout(c->file, layouts[k].tag))
            continue;
        tpk_mesh_arrays m;
        tpk_result r = tpk_load_arrays(c->file, layouts[k].layout, NULL, 0, &m);
        if (r != TPK_OK)
            return tpk_diag_fail(diag, "cannot load the %s arrays of a verified file: %s",
                                 tpkc_layout_name(layouts[k].layout), tpk_error_text(c->file));
        c->pos = m.positions;
        c->shell = m.shell;
        c->tet32 = m.tet32 ? m.tet32 : c->tet32;
        c->tet20 = m.tet20 ? m.tet20 : c->tet20;
        c->tet16 = m.tet16 ? m.tet16 : c->tet16;
        if (!c->ref)
            c->ref = layouts[k].layout;
    }
    if (!c->ref)
        return tpk_diag_fail(diag, "a verified file without a tet layout"); /* rule 14 forbids it */
    return 0;
}

static void free_context(tpkc *c)
{
    free(c->walked);
    free(c->face_class);
    free(c->covered);
}

/* Everything that depends on the reference ids: the walk (if any), then the passes over them. */
static int check_reference(tpkc *c, tpk_diag *diag)
{
    if (c->ref != TPK_LAYOUT_TET32 && tpkc_walk(c, diag))
        return -1;
    tpk_check_progress(c->report, "tpk", 0.3);
    if (tpkc_check_shell(c, diag) || tpkc_check_tets(c, diag))
        return -1;
    tpk_check_progress(c->report, "tpk", 0.6);
    if (tpkc_check_faces(c, diag) || tpkc_check_layouts(c, diag))
        return -1;
    tpk_check_progress(c->report, "tpk", 0.8);
    return 0;
}

/* A parallel walk is kept only for files without problems (check_tpk_walk.c): when the checks on it
 * found any, forget them and check again on the serial walk, whose findings do not depend on timing. */
static int found_reference_problems(const tpkc *c)
{
    for (int id = 601; id <= 610; id++)
        if (tpk_check_finding(c->report, id)->count)
            return 1;
    return 0;
}

static int recheck_serially(tpkc *c, tpk_diag *diag)
{
    for (int id = 601; id <= 610; id++) {
        tpk_finding *f = tpk_check_finding(c->report, id);
        free(f->examples);
        f->examples = NULL;
        f->count = 0;
        f->example_count = 0;
        f->summary[0] = 0;
    }
    memset(c->face_class, 0, (size_t)c->T);
    memset(c->covered, 0, (size_t)c->T);
    free(c->walked);
    c->walked = NULL;
    c->walked_in_parallel = 0;
    c->serial_walk = 1;
    return check_reference(c, diag);
}

static int run_invariants(tpkc *c, tpk_diag *diag)
{
    if (load_arrays(c, diag))
        return -1;
    c->face_class = calloc((size_t)c->T + 1, 1);
    c->covered = calloc((size_t)c->T + 1, 1);
    if (!c->face_class || !c->covered)
        return tpk_diag_fail(diag, "out of memory for per-tet flags (%" PRId64 " tets)", c->T);
    if (check_reference(c, diag))
        return -1;
    if (c->walked_in_parallel && found_reference_problems(c) && recheck_serially(c, diag))
        return -1;
    if (tpkc_check_values(c, diag) || tpkc_check_cull(c, diag))
        return -1;
    tpk_check_progress(c->report, "tpk", 1.0);
    return 0;
}

/* After a walk without findings: the walked ids, compacted from 5 to 4 per tet in place, handed over
 * (the walk enters each tet through a face outward from its neighbor or, from the shell, with the
 * record's order reversed, so with TPK-M02 and TPK-M06 holding every quadruple is positive). */
static int32_t *take_walked(tpkc *c)
{
    if (!c->walked || c->unrecovered)
        return NULL;
    for (int id = 600; id <= 613; id++)
        if (tpk_check_finding(c->report, id)->count)
            return NULL;
    for (int64_t t = 0; t < c->T; t++)
        memmove(c->walked + 4 * t, c->walked + 5 * t, 4 * sizeof *c->walked);
    int32_t *tets = realloc(c->walked, sizeof *tets * (size_t)(4 * c->T + 1));
    if (!tets)
        return NULL; /* the caller recovers them again */
    c->walked = NULL;
    return tets;
}

int tpk_check_tpk_file(const char *path, tpk_file *file, tpk_check_report *report, tpk_diag *diag)
{
    return tpk_check_tpk_file_tets(path, file, report, NULL, diag);
}

int tpk_check_tpk_file_tets(const char *path, tpk_file *file, tpk_check_report *report, int32_t **tets_out,
                            tpk_diag *diag)
{
    if (tets_out)
        *tets_out = NULL;
    (void)path; /* the handle is all the checks need; the driver names the file in the report */
    int ok = check_reader_rules(file, report, diag);
    if (ok <= 0)
        return ok;
    tpk_file_info info;
    if (tpk_get_info(file, &info) != TPK_OK)
        return tpk_diag_fail(diag, "cannot read the header of a verified file: %s", tpk_error_text(file));
    tpkc c;
    memset(&c, 0, sizeof c);
    c.file = file;
    c.report = report;
    c.threads = tpk_thread_count(report->options.threads);
    c.V = (int64_t)info.vertex_count;
    c.T = (int64_t)info.tet_count;
    c.S = (int64_t)info.shell_face_count;
    memcpy(c.origin, info.origin, sizeof c.origin);
    int rc = run_invariants(&c, diag);
    if (rc == 0 && tets_out)
        *tets_out = take_walked(&c);
    free_context(&c);
    return rc;
}
