/* Shell export: the boundary faces of a .tpk as a binary little-endian PLY, with only the vertices
 * the shell uses (renumbered in ascending id order, world coordinates as doubles), faces in the file's
 * outward order, and each face's tet. Written atomically. */
#include <stdlib.h>
#include <string.h>

#include "export_io.h"
#include "exporters.h"

int tpk_export_shell_ply(tpk_file *file, const char *path, tpk_diag *diag)
{
    if (!file || !path)
        return tpk_diag_fail(diag, "tpk_export_shell_ply: no file or output path given");
    tpk_file_info info;
    tpk_result r = tpk_get_info(file, &info);
    if (r != TPK_OK)
        return tpk_diag_fail(diag, "%s: cannot export: %s", path, tpk_result_string(r));
    const void *pos_data = NULL, *shell_data = NULL;
    void *pos_owned = NULL, *shell_owned = NULL;
    int32_t *remap = NULL;
    int rc = -1;
    int got = tpk_export_load_chunk(file, TPK_TAG_POS3, 0, 0, 12, info.vertex_count, &pos_data, &pos_owned, path, diag);
    if (got == 0)
        tpk_diag_fail(diag, "%s: cannot export the shell: the file has no POS3 (positions) chunk", path);
    if (got <= 0)
        goto done;
    got = tpk_export_load_chunk(file, TPK_TAG_SHEL, 0, 0, 16, info.shell_face_count, &shell_data, &shell_owned, path,
                                diag);
    if (got == 0)
        tpk_diag_fail(diag, "%s: cannot export the shell: the file has no SHEL (shell faces) chunk", path);
    if (got <= 0)
        goto done;
    const float *pos = pos_data;
    const tpk_shell_face *faces = shell_data;
    uint64_t nv = info.vertex_count, nf = info.shell_face_count;
    remap = malloc(sizeof(int32_t) * (size_t)(nv ? nv : 1));
    if (!remap) {
        tpk_diag_fail(diag, "%s: out of memory", path);
        goto done;
    }
    memset(remap, 0xff, sizeof(int32_t) * (size_t)nv);
    for (uint64_t f = 0; f < nf; f++) {
        const int32_t ids[3] = {faces[f].a, faces[f].b, faces[f].c};
        for (int k = 0; k < 3; k++) {
            if (ids[k] < 0 || (uint64_t)ids[k] >= nv) {
                tpk_diag_fail(diag, "%s: cannot export: shell face %llu names vertex %d, the file has %llu vertices",
                              path, (unsigned long long)f, ids[k], (unsigned long long)nv);
                goto done;
            }
            remap[ids[k]] = 0;
        }
        if (faces[f].t < 0 || (uint64_t)faces[f].t >= info.tet_count) {
            tpk_diag_fail(diag, "%s: cannot export: shell face %llu names tet %d, the file has %llu tets", path,
                          (unsigned long long)f, faces[f].t, (unsigned long long)info.tet_count);
            goto done;
        }
    }
    int32_t used = 0;
    for (uint64_t v = 0; v < nv; v++)
        if (remap[v] == 0)
            remap[v] = used++;

    tpk_out o;
    if (tpk_out_open(&o, path, diag) != 0)
        goto done;
    tpk_out_printf(&o, "ply\nformat binary_little_endian 1.0\ncomment tetpack shell: outward faces, tet = owning tet\n"
                       "element vertex %d\nproperty double x\nproperty double y\nproperty double z\n"
                       "element face %llu\nproperty list uchar int vertex_indices\nproperty int tet\nend_header\n",
                   used, (unsigned long long)nf);
    for (uint64_t v = 0; v < nv; v++) {
        if (remap[v] < 0)
            continue;
        double xyz[3];
        for (int k = 0; k < 3; k++)
            xyz[k] = info.origin[k] + (double)pos[3 * v + k];
        tpk_out_f64le(&o, xyz, 3);
    }
    for (uint64_t f = 0; f < nf; f++) {
        unsigned char three = 3;
        int32_t rec[4] = {remap[faces[f].a], remap[faces[f].b], remap[faces[f].c], faces[f].t};
        tpk_out_write(&o, &three, 1);
        tpk_out_i32le(&o, rec, 4);
    }
    rc = tpk_out_commit(&o, diag);
done:
    free(remap);
    free(pos_owned);
    free(shell_owned);
    return rc;
}
