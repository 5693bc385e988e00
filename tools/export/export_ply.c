/* Shell export as a binary little-endian PLY: world coordinates as doubles, faces in the file's outward
 * order, and each face's tet (a property OpenMesh's PLY writer has no place for). Written atomically. */
#include "export_io.h"
#include "exporters.h"

int tpk_export_shell_ply(tpk_file *file, const char *path, tpk_diag *diag)
{
    tpk_shell_mesh shell;
    if (tpk_shell_load(file, path, &shell, diag) != 0)
        return -1;
    tpk_out o;
    int rc = tpk_out_open(&o, path, diag);
    if (rc == 0) {
        tpk_out_printf(&o, "ply\nformat binary_little_endian 1.0\ncomment tetpack shell: outward faces, tet = owning tet\n"
                           "element vertex %lld\nproperty double x\nproperty double y\nproperty double z\n"
                           "element face %lld\nproperty list uchar int vertex_indices\nproperty int tet\nend_header\n",
                       (long long)shell.vertex_count, (long long)shell.face_count);
        tpk_out_f64le(&o, shell.xyz, 3 * (size_t)shell.vertex_count);
        for (int64_t f = 0; f < shell.face_count; f++) {
            unsigned char three = 3;
            int32_t rec[4] = {shell.tri[3 * f], shell.tri[3 * f + 1], shell.tri[3 * f + 2], shell.tet[f]};
            tpk_out_write(&o, &three, 1);
            tpk_out_i32le(&o, rec, 4);
        }
        rc = tpk_out_commit(&o, diag);
    }
    tpk_shell_free(&shell);
    return rc;
}
