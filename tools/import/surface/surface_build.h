/* Helpers shared by the surface and point-cloud readers (private to tools/import_*.c for surfaces). */
#ifndef TPK_SURFACE_BUILD_H
#define TPK_SURFACE_BUILD_H

#include <stdint.h>

#include "mesh/mesh.h"

/* Allocate points (3 * point_count doubles), face types and offsets (face_count) and conn_count
 * corners; sets the counts, offsets[0] = 0. Returns 0 or -1 (out of memory; arrays freed by
 * tpk_mesh_free). */
int tpk_surf_alloc(tpk_mesh *m, int64_t point_count, int64_t face_count, int64_t conn_count);

/* Triangles given by corner coordinates (9 doubles each, as in STL) -> shared vertices: corners with
 * identical coordinates become one point, numbered in order of first use. Fills m's points, faces and
 * connectivity. Returns 0 or -1 (out of memory). */
int tpk_surf_from_corners(tpk_mesh *m, const double *corners, int64_t triangle_count);

/* Read an unsigned / signed 32-bit integer, float32 or float64 stored little- or big-endian. */
uint32_t tpk_surf_u32(const unsigned char *p, int big_endian);
float tpk_surf_f32(const unsigned char *p, int big_endian);
double tpk_surf_f64(const unsigned char *p, int big_endian);

#endif
