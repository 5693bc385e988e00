/* Polyhedron cells (VTK type 42): checking the face streams the importers read, moving them into
 * tpk_mesh.faces, and a cell's boundary as a set of polygons (closed, consistently oriented, outward)
 * for the tetrahedralizer. */
#ifndef TPK_POLYHEDRON_H
#define TPK_POLYHEDRON_H

#include <stddef.h>
#include <stdint.h>

#include "mesh.h"

/* Check one cell's VTK face stream stream[0 .. n): a face count >= 4, then per face a point count >= 3
 * and that many ids in [0, point_count), using exactly n entries. Returns 0, or -1 with `why` saying
 * what was expected and found, and *bad_at the index (within the stream) of the entry at fault. Safe on
 * untrusted input. */
int tpk_face_stream_check(const int32_t *stream, int64_t n, int64_t point_count, int64_t *bad_at, char *why,
                          size_t why_cap);

/* For importers that read each polyhedron's face stream into cell_conn (both VTK readers do): move the
 * streams into mesh->faces / mesh->face_offsets and replace each polyhedron's cell_conn entries by its
 * distinct point ids, ascending. Streams must have passed tpk_face_stream_check. Leaves a mesh without
 * polyhedra unchanged. Returns 0, or -1 when out of memory (the mesh is then unchanged). */
int tpk_mesh_take_face_streams(tpk_mesh *mesh);

/* A cell's boundary: face f is ids[starts[f] .. starts[f+1]). Growable; zero-initialise, then reuse. */
typedef struct tpk_polygons {
    int64_t face_count;
    int64_t *starts;   /* face_count + 1 */
    int32_t *ids;
    int64_t face_cap, id_cap;
    void *scratch;     /* for tpk_polygons_orient */
    size_t scratch_bytes;
} tpk_polygons;

void tpk_polygons_free(tpk_polygons *p);
/* Faces of a checked face stream. Returns 0 or -1 (out of memory). */
int tpk_polygons_from_stream(tpk_polygons *p, const int32_t *stream, int64_t n);
/* Faces of a voxel, hexahedron, wedge or pyramid (tpk_cell_faces, cell_types.h). Returns 0 or -1. */
int tpk_polygons_from_cell(tpk_polygons *p, int type, const int32_t *nodes);

/* Turn faces over so that every edge is walked once in each direction (a consistently oriented closed
 * surface). Returns 0; 1 with `why` when the faces cannot form one: a face repeats a point, an edge
 * lies on other than two faces, the surface is not orientable, or the faces form separate surfaces;
 * -1 when out of memory. */
int tpk_polygons_orient(tpk_polygons *p, char *why, size_t why_cap);

/* 6 x the signed volume enclosed (divergence theorem), each face fanned from its first point: positive
 * for outward faces. Not exact; use for orientation and checks, not for decisions at zero. */
double tpk_polygons_volume6(const tpk_polygons *p, const double *points);

/* Reverse every face. */
void tpk_polygons_flip(tpk_polygons *p);

#endif
