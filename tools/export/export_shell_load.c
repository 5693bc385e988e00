/* The shell of a .tpk as a triangle mesh (tpk_shell_load, tpk_shell_free): boundary faces checked
 * against the file's counts, only the vertices they use, in world coordinates. Shared by every shell
 * writer (export_ply.c, and export_shell.c's OpenMesh path); calls neither. */
#include <stdlib.h>
#include <string.h>

#include "export_io.h"
#include "exporters.h"

void tpk_shell_free(tpk_shell_mesh *shell)
{
    free(shell->xyz);
    free(shell->tri);
    free(shell->tet);
    memset(shell, 0, sizeof *shell);
}

/* Every face's vertices and tet in range; marks the used vertices in remap (0), others stay -1. */
static int check_faces(const tpk_shell_face *faces, uint64_t nf, const tpk_file_info *info, int32_t *remap,
                       const char *path, tpk_diag *diag)
{
    for (uint64_t f = 0; f < nf; f++) {
        const int32_t ids[3] = {faces[f].a, faces[f].b, faces[f].c};
        for (int k = 0; k < 3; k++) {
            if (ids[k] < 0 || (uint64_t)ids[k] >= info->vertex_count)
                return tpk_diag_fail(diag, "%s: cannot export: shell face %llu names vertex %d, the file has %llu "
                                     "vertices", path, (unsigned long long)f, ids[k],
                                     (unsigned long long)info->vertex_count);
            remap[ids[k]] = 0;
        }
        if (faces[f].t < 0 || (uint64_t)faces[f].t >= info->tet_count)
            return tpk_diag_fail(diag, "%s: cannot export: shell face %llu names tet %d, the file has %llu tets", path,
                                 (unsigned long long)f, faces[f].t, (unsigned long long)info->tet_count);
    }
    return 0;
}

static int fill_shell(const float *pos, const tpk_shell_face *faces, const tpk_file_info *info, int32_t *remap,
                      tpk_shell_mesh *shell)
{
    int64_t used = 0;
    for (uint64_t v = 0; v < info->vertex_count; v++)
        if (remap[v] == 0)
            remap[v] = (int32_t)used++;
    shell->vertex_count = used;
    shell->face_count = (int64_t)info->shell_face_count;
    shell->xyz = malloc(sizeof *shell->xyz * 3 * (size_t)(used ? used : 1));
    shell->tri = malloc(sizeof *shell->tri * 3 * (size_t)(shell->face_count ? shell->face_count : 1));
    shell->tet = malloc(sizeof *shell->tet * (size_t)(shell->face_count ? shell->face_count : 1));
    if (!shell->xyz || !shell->tri || !shell->tet)
        return -1;
    for (uint64_t v = 0; v < info->vertex_count; v++)
        for (int k = 0; remap[v] >= 0 && k < 3; k++)
            shell->xyz[3 * (int64_t)remap[v] + k] = info->origin[k] + (double)pos[3 * v + k];
    for (int64_t f = 0; f < shell->face_count; f++) {
        shell->tri[3 * f] = remap[faces[f].a];
        shell->tri[3 * f + 1] = remap[faces[f].b];
        shell->tri[3 * f + 2] = remap[faces[f].c];
        shell->tet[f] = faces[f].t;
    }
    return 0;
}

int tpk_shell_load(tpk_file *file, const char *path, tpk_shell_mesh *shell, tpk_diag *diag)
{
    memset(shell, 0, sizeof *shell);
    if (!file || !path)
        return tpk_diag_fail(diag, "shell export: no file or output path given");
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
    remap = malloc(sizeof(int32_t) * (size_t)(info.vertex_count ? info.vertex_count : 1));
    if (!remap) {
        tpk_diag_fail(diag, "%s: out of memory", path);
        goto done;
    }
    memset(remap, 0xff, sizeof(int32_t) * (size_t)info.vertex_count);
    if (check_faces(shell_data, info.shell_face_count, &info, remap, path, diag) != 0)
        goto done;
    if (fill_shell(pos_data, shell_data, &info, remap, shell) != 0) {
        tpk_diag_fail(diag, "%s: out of memory for %llu shell faces", path, (unsigned long long)info.shell_face_count);
        goto done;
    }
    rc = 0;
done:
    if (rc != 0)
        tpk_shell_free(shell);
    free(remap);
    free(pos_owned);
    free(shell_owned);
    return rc;
}
