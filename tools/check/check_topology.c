/* The connectivity (3xx) and shell (4xx) groups of `tetpack check`: face matching (301, 302, 305),
 * the shell (303, 401..406) and the face-connected components (304: as checkMesh's regions; cells on
 * either side of a non-conforming interface are in different components, which 304's summary notes). Cells that are not volume cells,
 * or that tpk_check_cell_usable() rejects, take no part. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_topo.h"

/* Points every cell straight at its root. Roots are their set's smallest id and parent[c] < c for
 * every other cell, so one ascending pass suffices. */
static void flatten(uint32_t *parent, int64_t count)
{
    for (int64_t c = 0; c < count; c++)
        if (parent[c] != TPK_UF_NONE && parent[c] != (uint32_t)c)
            parent[c] = parent[parent[c]];
}

static void keep_largest(tpk_check_report *report, int64_t size)
{
    int64_t kept = report->component_count < 16 ? report->component_count : 16;
    int64_t i = kept;
    if (kept == 16) {
        if (size <= report->component_sizes[15])
            return;
        i = 15;
    }
    for (; i > 0 && report->component_sizes[i - 1] < size; i--)
        report->component_sizes[i] = report->component_sizes[i - 1];
    report->component_sizes[i] = size;
}

/* "3 components: 14487, 14487, 2" (largest first; ", ..." past the 16 kept or the line's room). */
static void component_summary(tpk_check_report *report, tpk_finding *finding)
{
    int64_t shown = report->component_count < 16 ? report->component_count : 16;
    char *out = finding->summary;
    size_t room = sizeof finding->summary - 6, used = 0; /* 6: room for ", ..." */
    used = (size_t)snprintf(out, room, "%lld components: ", (long long)report->component_count);
    int64_t i = 0;
    for (; i < shown; i++) {
        char item[32];
        int wrote = snprintf(item, sizeof item, "%s%lld", i ? ", " : "", (long long)report->component_sizes[i]);
        if (wrote < 0 || used + (size_t)wrote >= room)
            break;
        memcpy(out + used, item, (size_t)wrote + 1);
        used += (size_t)wrote;
    }
    if (i < report->component_count)
        strcat(out, ", ...");
}

static void cell_centre(const tpk_mesh *mesh, int64_t cell, double out[3])
{
    int64_t b = mesh->cell_offsets[cell], e = mesh->cell_offsets[cell + 1];
    for (int k = 0; k < 3; k++) {
        double sum = 0;
        for (int64_t i = b; i < e; i++)
            sum += mesh->points[3 * (int64_t)mesh->cell_conn[i] + k];
        out[k] = sum / (double)(e - b);
    }
}

/* 304: sizes largest first; the finding (info) only when there is more than one component, with one
 * example per component in order of its smallest cell id. */
static int report_components(const tpk_mesh *mesh, uint32_t *parent, tpk_check_report *report, tpk_diag *diag)
{
    flatten(parent, mesh->cell_count);
    size_t cells = mesh->cell_count > 0 ? (size_t)mesh->cell_count : 1; /* < 2^31: face matching checked */
    uint32_t *size = calloc(cells, sizeof *size);
    if (!size)
        return tpk_diag_fail(diag, "check: out of memory (components of %lld cells)", (long long)mesh->cell_count);
    for (int64_t c = 0; c < mesh->cell_count; c++)
        if (parent[c] != TPK_UF_NONE)
            size[parent[c]]++;
    report->component_count = 0;
    for (int64_t c = 0; c < mesh->cell_count; c++)
        if (size[c] > 0) {
            keep_largest(report, size[c]);
            report->component_count++;
        }
    if (report->component_count > 1) {
        for (int64_t c = 0; c < mesh->cell_count; c++) {
            if (size[c] == 0)
                continue;
            tpk_example *ex = tpk_check_hit(report, 304, "component");
            if (!ex)
                break;
            tpk_example_ids(ex, 1, &c);
            double centre[3];
            cell_centre(mesh, c, centre);
            tpk_example_point(ex, centre);
            tpk_example_note(ex, "%u cells; ids: its smallest cell id", size[c]);
        }
        tpk_finding *finding = tpk_check_finding(report, 304);
        finding->count = report->component_count;
        component_summary(report, finding);
    }
    free(size);
    return 0;
}

/* Components joined by the shell checks' non-conforming pairs (303): said in 304's summary, the count
 * itself stays the face-connected one, as checkMesh's regions. */
static void note_joined(const tpk_mesh *mesh, uint32_t *parent, tpk_check_report *report)
{
    int64_t roots = 0;
    for (int64_t c = 0; c < mesh->cell_count; c++)
        roots += parent[c] != TPK_UF_NONE && tpk_uf_find(parent, (uint32_t)c) == (uint32_t)c;
    tpk_finding *finding = tpk_check_finding(report, 304);
    size_t used = strlen(finding->summary);
    if (roots < report->component_count && used + 1 < sizeof finding->summary)
        snprintf(finding->summary + used, sizeof finding->summary - used,
                 "; %lld once joined across faces that lie against each other (303)", (long long)roots);
}

int tpk_check_topology(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag)
{
    tpk_topo_match m;
    if (tpk_topo_match_faces(in->mesh, report, &m, diag))
        return -1;
    /* face-connected components first: the shell's 303 pairs union cells across an interface next */
    int rc = report_components(in->mesh, m.parent, report, diag);
    if (rc == 0)
        rc = tpk_check_shell(in->mesh, &m, report, diag);
    if (rc == 0 && report->component_count > 1)
        note_joined(in->mesh, m.parent, report);
    tpk_topo_match_free(&m);
    return rc;
}
