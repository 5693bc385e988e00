/* Shell export, the entry on top: the format chosen by the output's extension, PLY by our writer
 * (export_ply.c), OBJ/OFF/STL by OpenMesh's (export_openmesh.cpp), all written atomically. Both load
 * the shell with tpk_shell_load (export_shell_load.c), which calls back into neither. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "export_io.h"
#include "exporters.h"
#ifdef TPK_HAVE_OPENMESH
#include "export_openmesh.h"
#endif

#ifdef TPK_HAVE_OPENMESH
/* OpenMesh 9's writers (OBJ and OFF too, and its PLY) take positions through float32 whatever the mesh
 * stores (BaseExporter::point returns Vec3f). Harmless near the origin; far from it (a UTM frame) a vertex
 * moves by up to half a float32 ulp of its coordinate, so say so when that matters at the shell's scale. */
static void warn_float32(const tpk_shell_mesh *shell, const char *path, const char *format, tpk_diag *diag)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, moved = 0;
    for (int64_t i = 0; i < 3 * shell->vertex_count; i++) {
        double x = shell->xyz[i], error = fabs(x - (double)(float)x);
        moved = error > moved ? error : moved;
        lo[i % 3] = x < lo[i % 3] ? x : lo[i % 3];
        hi[i % 3] = x > hi[i % 3] ? x : hi[i % 3];
    }
    double diagonal = shell->vertex_count ? sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                                 (hi[2] - lo[2]) * (hi[2] - lo[2]))
                                          : 0.0;
    if (moved > 1e-6 * diagonal)
        tpk_diag_warn(diag, "%s: OpenMesh's %s writer stores float32 positions: vertices move by up to %.3g, %.2g of "
                      "the shell's diagonal (the mesh is far from the origin); a .ply shell keeps float64",
                      path, format, moved, diagonal > 0 ? moved / diagonal : 0.0);
}

static int export_with_openmesh(tpk_file *file, const char *path, const char *format, tpk_diag *diag)
{
    tpk_shell_mesh shell;
    if (tpk_shell_load(file, path, &shell, diag) != 0)
        return -1;
    warn_float32(&shell, path, format, diag);
    tpk_openmesh_result written;
    int rc = tpk_openmesh_write(format, shell.xyz, shell.vertex_count, shell.tri, shell.face_count, &written);
    if (rc != 0)
        tpk_diag_fail(diag, "%s: %s", path, written.error);
    else if (written.split_faces > 0)
        tpk_diag_warn(diag, "%s: the shell is not manifold: %lld faces meet others at a vertex or edge that a "
                      "halfedge mesh cannot share, and were written on their own copies of their vertices",
                      path, (long long)written.split_faces);
    tpk_out o;
    if (rc == 0 && (rc = tpk_out_open(&o, path, diag)) == 0) {
        tpk_out_write(&o, written.bytes, written.size);
        rc = tpk_out_commit(&o, diag);
    }
    free(written.bytes);
    tpk_shell_free(&shell);
    return rc;
}
#else
static int export_with_openmesh(tpk_file *file, const char *path, const char *format, tpk_diag *diag)
{
    (void)file;
    return tpk_diag_fail(diag, "%s: this tetpack was built without OpenMesh (TETPACK_WITH_OPENMESH=OFF), which "
                         "writes .%s shells; .ply needs no OpenMesh", path, format);
}
#endif

int tpk_export_shell(tpk_file *file, const char *path, tpk_diag *diag)
{
    static const char *const openmesh_formats[] = {"obj", "off", "stl"};
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    const char *ext = dot && (!slash || dot > slash) ? dot + 1 : "";
    if (!strcasecmp(ext, "ply"))
        return tpk_export_shell_ply(file, path, diag);
    for (size_t i = 0; i < sizeof openmesh_formats / sizeof openmesh_formats[0]; i++)
        if (!strcasecmp(ext, openmesh_formats[i]))
            return export_with_openmesh(file, path, openmesh_formats[i], diag);
    return tpk_diag_fail(diag, "%s: unknown shell format '.%s': the extension must be .ply, .obj, .off or .stl", path,
                         ext);
}
