/* tetpack check driver: read any input the importers know (or a .tpk), run the groups in order. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/clock.h"
#include "check.h"
#include "import/importers.h"
#include "mesher/mesher.h"
#include "tetpack.h"

static int is_tpk(const char *path)
{
    size_t len = strlen(path);
    if (len >= 4 && !strcasecmp(path + len - 4, ".tpk"))
        return 1; /* so a damaged magic is reported by the .tpk reader, not as an unknown format */
    static const unsigned char magic[8] = {0x89, 'T', 'P', 'K', 0x0D, 0x0A, 0x1A, 0x0A};
    unsigned char head[8] = {0};
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    size_t got = fread(head, 1, sizeof head, f);
    fclose(f);
    return got == 8 && !memcmp(head, magic, 8);
}

typedef int (*group_fn)(const tpk_check_input *, tpk_check_report *, tpk_diag *);

static int run_group(int index, group_fn fn, const tpk_check_input *in, tpk_check_report *report,
                     tpk_diag *diag)
{
    static const char *names[7] = {"", "vertices", "cells", "topology", "", "fields", "file"};
    double t0 = tpk_now_seconds();
    tpk_check_progress(report, names[index], 0.0);
    int rc = fn(in, report, diag);
    tpk_check_progress(report, names[index], 1.0);
    report->seconds[index] += tpk_now_seconds() - t0;
    report->ran[index] = 1;
    return rc;
}

int tpk_check_path(const char *path, const char *format, tpk_check_report *report, tpk_diag *diag)
{
    tpk_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    snprintf(report->input, sizeof report->input, "%s", path);
    int have_mesh = 0;
    if ((format && !strcasecmp(format, "tpk")) || ((!format || !*format || !strcasecmp(format, "auto")) &&
                                                    is_tpk(path))) {
        tpk_file *file = NULL;
        char err[1024] = "";
        tpk_result r = tpk_open_path(&file, path, NULL, err, sizeof err);
        if (r != TPK_OK) {
            const char *why = err[0] ? err : tpk_result_string(r);
            if (strstr(why, path))
                return tpk_diag_fail(diag, "%s", why);
            return tpk_diag_fail(diag, "%s: %s", path, why);
        }
        uint64_t part_chunk;
        if (tpk_find_chunk(file, TPK_TAG_PART, 0, 0, &part_chunk) == TPK_OK) { /* a part set's manifest */
            tpk_close(file);
            double t0 = tpk_now_seconds();
            int rc = tpk_check_set(path, report, diag);
            report->seconds[6] = tpk_now_seconds() - t0;
            return rc;
        }
        snprintf(report->format, sizeof report->format, "tpk");
        double t0 = tpk_now_seconds();
        int32_t *tets = NULL; /* recovered by the 6xx walk, handed to the mesh build */
        int rc = tpk_check_tpk_file_tets(path, file, report, &tets, diag);
        if (rc == 0)
            rc = tpk_check_levels(path, file, report, diag);
        report->seconds[6] = tpk_now_seconds() - t0;
        report->ran[6] = 1;
        tpk_file_info info;
        if (tpk_get_info(file, &info) == TPK_OK) { /* the header's counts, also when a chunk is damaged */
            report->tets = (int64_t)info.tet_count;
            report->vertices = (int64_t)info.vertex_count;
            report->cells = (int64_t)info.tet_count;
        }
        if (rc == 0) {
            tpk_diag sub = *diag;
            if (tpk_check_tpk_mesh_tets(file, tets, &mesh, &sub) == 0)
                have_mesh = 1;
            /* else: the 6xx findings say why the tets could not be recovered */
        }
        tpk_close(file);
        if (rc != 0) {
            tpk_mesh_free(&mesh);
            return -1;
        }
    } else {
        diag->lenient_fields = 1;
        /* A surface or point cloud goes through TetGen with its defaults and a progress line per stage. */
        tpk_tetgen_options tetgen = {0};
        tetgen.progress = report->options.progress;
        int rc = tpk_import_any_with(path, format, &tetgen, &mesh, diag);
        diag->lenient_fields = 0;
        if (rc != 0)
            return -1;
        snprintf(report->format, sizeof report->format, "%s", mesh.format);
        have_mesh = 1;
    }
    int rc = 0;
    if (have_mesh) {
        report->vertices = mesh.point_count;
        report->cells = mesh.cell_count;
        for (int64_t c = 0; c < mesh.cell_count; c++)
            report->cell_type_counts[mesh.cell_types[c]]++;
        tpk_check_input in = {&mesh, path, diag};
        if (run_group(1, tpk_check_vertices, &in, report, diag) || run_group(2, tpk_check_cells, &in, report, diag) ||
            run_group(3, tpk_check_topology, &in, report, diag) || run_group(5, tpk_check_fields, &in, report, diag))
            rc = -1;
        report->ran[4] = report->ran[3];
    }
    tpk_mesh_free(&mesh);
    return rc;
}
