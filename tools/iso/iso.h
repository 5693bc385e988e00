/* tetpack iso: isosurfaces of a point field as triangle meshes (marching tetrahedra), written as PLY,
 * OBJ or glTF 2.0 binary (.glb). Extraction (iso_march.c) works on plain arrays, so tests and other
 * rooms can call it without a file; tpk_iso_run (iso.c) reads a .tpk, extracts and writes. */
#ifndef TPK_ISO_H
#define TPK_ISO_H

#include <stdint.h>

#include "base/diag.h"
#include "tetpack.h"

#define TPK_ISO_MAX_VALUES 64

/* What the extraction reads: the stored mesh (positions relative to origin, positively oriented vertex
 * quadruples) and one value per vertex of the field, and optionally of a second field carried along. */
typedef struct tpk_iso_input {
    int64_t vertex_count, tet_count;
    double origin[3];
    const float *positions; /* 3 per vertex, relative to origin */
    const int32_t *tets;    /* 4 per tet, positively oriented (tpk_recover_tets), ids in range */
    const float *scalars;   /* the field: 1 per vertex */
    const float *colors;    /* a second point field interpolated onto the surface; NULL for none */
} tpk_iso_input;

/* The surface of every value, one after the other (value 0's triangles first).
 * - A vertex is a crossing of a tet edge (a, b), a < b mesh vertex ids, with the field: s_a < v <= s_b
 *   or s_b < v <= s_a (a vertex whose value equals v counts as above). It is made once per edge and
 *   value, whatever the number of tets around the edge, so the surface is watertight wherever the mesh
 *   is conforming: every edge of the surface inside the volume is in exactly two triangles; an edge in
 *   one triangle lies on a shell face of the mesh. Its position is p_a + t (p_b - p_a), t = (v - s_a) /
 *   (s_b - s_a), evaluated from the lower id; where v equals a vertex's value the vertex lies on that
 *   mesh vertex and triangles around it may have zero area (they are kept: dropping them would open the
 *   surface).
 * - Triangles are counter-clockwise seen from the side of higher values: (b - a) x (c - a) points toward
 *   increasing field. A tet with a NaN value makes no triangles.
 * - Order: triangles by value, then tet, then the fixed case table; vertices by value, then (a, b). Both
 *   are independent of the thread count, so outputs are byte-identical for any --threads. */
typedef struct tpk_iso_surface {
    int64_t vertex_count, triangle_count;
    double *xyz;       /* 3 per vertex, world coordinates (origin added) */
    float *normal;     /* 3 per vertex, unit: the sum of the area-weighted normals of its triangles (toward
                          increasing field); the direction of its edge toward the higher value where that
                          sum is zero */
    float *value;      /* per vertex: the iso value it belongs to (the field interpolated there) */
    float *color;      /* per vertex: the second field interpolated with the same t; NULL without one */
    int32_t *edge;     /* 2 per vertex: the mesh vertices (a < b) of the edge it lies on */
    uint32_t *tri;     /* 3 per triangle */
    int value_count;
    double values[TPK_ISO_MAX_VALUES];
    int64_t value_triangles[TPK_ISO_MAX_VALUES], value_vertices[TPK_ISO_MAX_VALUES];
} tpk_iso_surface;

/* Extract the isosurfaces of `values` (1..TPK_ISO_MAX_VALUES finite numbers) with `threads` workers (<= 0:
 * all cores) into *out (emptied first; free with tpk_iso_surface_free). 0, or -1 with a message (out of
 * memory, more than 2^31 - 1 vertices or triangles). */
int tpk_iso_extract(const tpk_iso_input *in, const double *values, int value_count, int threads,
                    tpk_iso_surface *out, tpk_diag *diag);
void tpk_iso_surface_free(tpk_iso_surface *s);

/* Where the triangles of one value come from: classification, prefix sum and emission of each tet's
 * triangles as corner keys ((a << 32) | b, a < b mesh vertex ids of the edge the corner lies on), 3 per
 * triangle, in tet order and then the case table's order (tpk_iso_case_table), a corner being on an
 * edge whose corners are on both sides of the value (at or above: s >= value, compared in double; a
 * tet with a NaN makes none). The CPU does this itself (NULL); the Vulkan backend (render_vk/vk_iso.c)
 * does it in compute shaders. Everything after (vertices shared by edge, positions, normals) is the
 * same code, so both give the same surface. */
typedef struct tpk_iso_corners {
    /* *keys: malloc'ed, 3 * *triangles keys (the caller frees it). 0, or -1 with a message. */
    int (*emit)(void *user, const tpk_iso_input *in, double value, uint64_t **keys, int64_t *triangles,
                tpk_diag *diag);
    void *user;
} tpk_iso_corners;

/* tpk_iso_extract with the triangles from `corners` (NULL: the CPU's). */
int tpk_iso_extract_from(const tpk_iso_input *in, const double *values, int value_count, int threads,
                         const tpk_iso_corners *corners, tpk_iso_surface *out, tpk_diag *diag);

/* The case table, for tests: case `mask` (bit k: corner k at or above the value) makes *count triangles,
 * edges[3 i .. 3 i + 2] the tet edges of triangle i, edge k joining corners[k][0] and corners[k][1]. */
void tpk_iso_case_table(int mask, int *count, int edges[6], int corners[6][2]);

typedef enum tpk_iso_format {
    TPK_ISO_PLY = 1, /* binary little-endian PLY: float64 x y z, float32 nx ny nz value [color], int indices */
    TPK_ISO_OBJ,     /* ASCII OBJ: v, vn, f per value under an `o` line; no values (OBJ has no place) */
    TPK_ISO_GLB      /* glTF 2.0 binary: float32 POSITION (relative to the node's translation, the file's
                        origin), NORMAL, _VALUE [, _COLOR_FIELD], UNSIGNED_INT indices */
} tpk_iso_format;

/* The format of `path` from its extension (case-insensitive), or 0 for none of .ply, .obj, .glb. */
tpk_iso_format tpk_iso_format_of(const char *path);

/* What the writers say about the surface (the PLY and OBJ comments, the glTF extras). */
typedef struct tpk_iso_labels {
    const char *field, *color_field; /* color_field NULL without one */
    uint32_t step;
    double origin[3];                /* the glTF node's translation */
} tpk_iso_labels;

/* Write `s` to `path` in `format` atomically (base/output_file.h). 0 or -1 with a message. A .glb is
 * limited to 4 GiB (its header's length is 32 bits): beyond that, an error that suggests .ply. */
int tpk_iso_write(const tpk_iso_surface *s, const tpk_iso_labels *labels, tpk_iso_format format, const char *path,
                  tpk_diag *diag);

typedef struct tpk_iso_options {
    const char *input, *output;
    const char *field;       /* NULL: the first point field */
    const char *color_field; /* NULL: none */
    uint32_t step;           /* of the field; the color field at the same step, or at 0 when it has one */
    const double *values;
    int value_count;
    int threads;             /* <= 0: all cores */
    const tpk_iso_corners *corners; /* NULL: the CPU classifies and emits; else these (the Vulkan backend) */
} tpk_iso_options;

typedef struct tpk_iso_report {
    char field[64], color_field[64];
    float field_min, field_max; /* over all steps (FDSC) */
    int64_t tets, vertices, triangles;
    int threads;
    double seconds_load, seconds_extract, seconds_write;
    int value_count;
    double values[TPK_ISO_MAX_VALUES];
    int64_t value_triangles[TPK_ISO_MAX_VALUES], value_vertices[TPK_ISO_MAX_VALUES];
} tpk_iso_report;

/* Read options->input (the field at the step, the tets of its first layout: Tet32, else Tet20, Tet16),
 * extract and write options->output. Refuses a tet field (one value per tet has no crossing inside a
 * tet; `tetpack convert --cell-to-point` averages cell fields to points), a missing field or step, and
 * an unknown extension. A value that gives no triangle is a warning (naming the field's range when it
 * lies outside it); the file is still written. 0, or -1 with a message naming the file. */
int tpk_iso_run(const tpk_iso_options *options, tpk_iso_report *report, tpk_diag *diag);

#endif
