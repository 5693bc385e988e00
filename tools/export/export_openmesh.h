/* C face of the OpenMesh shim (export_openmesh.cpp): a triangle mesh written by OpenMesh's own writers.
 * Built only with TETPACK_WITH_OPENMESH (TPK_HAVE_OPENMESH defined). */
#ifndef TPK_EXPORT_OPENMESH_H
#define TPK_EXPORT_OPENMESH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tpk_openmesh_result {
    void *bytes;          /* the file's contents (malloc; the caller frees) */
    size_t size;
    int64_t split_faces;  /* faces OpenMesh's halfedge mesh refused (a non-manifold vertex or edge of
                             the shell), added again on their own copies of their 3 vertices */
    char error[256];      /* why, when the call returns -1 */
} tpk_openmesh_result;

/* `format`: "obj", "off" (ASCII, 17 significant digits) or "stl" (binary). OpenMesh 9's writers take
 * positions through float32 in every format (BaseExporter::point is Vec3f), so the file holds float32
 * positions even though xyz is double and the mesh stores Vec3d. Triangles `tri`
 * (3 ids per face, counter-clockwise seen from outside, kept so) over `xyz` (3 doubles per vertex).
 * Returns 0, or -1 with result->error. Thread safety: none (OpenMesh's writer registry is global). */
int tpk_openmesh_write(const char *format, const double *xyz, int64_t vertex_count, const int32_t *tri,
                       int64_t face_count, tpk_openmesh_result *result);

#ifdef __cplusplus
}
#endif

#endif
