/* In-memory meshes of the converter: the source mesh as read (cells of any type, with fields) and the
 * tet mesh the pipeline builds from it. Plain structs of arrays. */
#ifndef TPK_MESH_H
#define TPK_MESH_H

#include <stdint.h>

/* VTK cell type codes; the importers translate their formats' types to these. */
enum {
    TPK_CELL_TETRA = 10,
    TPK_CELL_VOXEL = 11,
    TPK_CELL_HEXAHEDRON = 12,
    TPK_CELL_WEDGE = 13,
    TPK_CELL_PYRAMID = 14,
    TPK_CELL_POLYHEDRON = 42
};

#define TPK_NAME_MAX 64
/* A tet with a dihedral angle under this (degrees) is flat: tetpack check's sliver_tet default. */
#define TPK_FLAT_TET_DEG 0.1

typedef struct tpk_src_field {
    char name[TPK_NAME_MAX];
    int association;     /* TPK_ASSOC_POINT or TPK_ASSOC_TET (= per source cell here) */
    int components;      /* 1 for scalars, 3 for vectors, ... */
    int step_count;      /* >= 1 */
    float *values;       /* step_count * (points or cells) * components, step-major */
} tpk_src_field;

typedef struct tpk_mesh {
    int64_t point_count;
    double *points;         /* 3 * point_count */
    int64_t cell_count;
    uint8_t *cell_types;    /* TPK_CELL_* per cell */
    int64_t *cell_offsets;  /* cell_count + 1; cell c uses cell_conn[cell_offsets[c] .. [c+1]) */
    int32_t *cell_conn;     /* 0-based point ids, in VTK node order; a polyhedron's distinct point ids,
                               ascending (its faces are in `faces`) */
    /* Polyhedra (VTK type 42): NULL when no cell is one. Cell c's VTK face stream is
     * faces[face_offsets[c] .. [c+1]) (empty for other cells): nfaces, then per face npts and npts point ids,
     * the faces of one cell forming a closed surface (VTK asks for outward faces; the tetrahedralizer
     * orients them itself). The importers check the stream's counts and ids (tools/mesh/polyhedron.h). */
    int64_t *face_offsets;  /* cell_count + 1 */
    int32_t *faces;
    int field_count;
    tpk_src_field *fields;
    int step_count;         /* number of time steps (1 when static) */
    double *times;          /* step_count values, or NULL */
    char format[32];        /* "vtk-legacy-ascii", "tetgen", ... */
    /* Set by a caller that converts one piece of a larger mesh (tetpack-mpi): the origin of the whole,
     * so TPK_TETRA_FILE_GRID snaps every piece onto the same float32 grid. 0: from this mesh's box. */
    int has_grid_origin;
    double grid_origin[3];
    /* Per point: its 0-based id in the whole mesh the file is a piece of, exact (int64), or NULL. Set by
     * importers whose files carry one (Exodus: the node number map, minus 1); tetpack-mpi identifies the
     * points of pieces by it. The single-file converter ignores it. */
    int64_t *global_point_ids;
    /* Per cell: its 0-based id in the whole mesh, or NULL (Exodus: the element number map, minus 1; it
     * counts the elements of every block, kept or not). tetpack-mpi numbers the parts' source cells (TMAP)
     * by it. */
    int64_t *global_cell_ids;
} tpk_mesh;

void tpk_mesh_free(tpk_mesh *mesh);
/* The same points (bit for bit) and cells (types and connectivity) in both: the mesh of a time series'
 * steps. Fields are not compared. */
int tpk_mesh_same_cells(const tpk_mesh *a, const tpk_mesh *b);
/* qsort/bsearch order of int32 ids (vertex or cell ids), ascending. */
int tpk_compare_int32(const void *a, const void *b);
/* Append a field; takes ownership of values. Returns 0 or -1 on allocation failure. */
int tpk_mesh_add_field(tpk_mesh *mesh, const char *name, int association, int components,
                       int step_count, float *values);

/* The tet mesh of the pipeline. */
typedef struct tpk_tetmesh {
    int64_t vertex_count;
    double *points;            /* 3 * vertex_count: absolute coordinates until the converter moves them
                                  into the stored frame (relative to origin, float32-exact) */
    double origin[3];          /* add to points for world coordinates (0 until then) */
    int on_grid;               /* TPK_TETRA_FILE_GRID: points lie on the float32 grid relative to grid_origin */
    int positive_known;        /* every tet was split from a cell whose tets the split found positive, exactly,
                                  on these grid points (which the stored frame only translates): orient has
                                  nothing to turn or drop. 0: unknown (tpk_orient finds out) */
    double grid_origin[3];     /* (world coordinates still; tools/convert/convert.c's quantize_points uses it) */
    int32_t *vertex_source;    /* source point id per vertex */
    int64_t tet_count;
    int32_t *tets;             /* 4 * tet_count vertex ids; positive orientation after tpk_orient */
    int32_t *tet_source;       /* source cell id per tet */
    int field_count;
    tpk_src_field *fields;     /* scalar (components 1) fields: per vertex or per tet */
    int step_count;
    double *times;
    /* What tpk_tetrahedralize did with the source cells. */
    int64_t cells_into[7];     /* cells that gave k tets (k = 1..6: tets 1, pyramids 2, wedges 3, hexes 5 or 6) */
    int64_t mirrored_cells;    /* cells given in mirrored node order, turned over */
    int64_t first_mirrored_cell; /* the lowest mirrored cell's id (meaningful when mirrored_cells > 0) */
    int64_t steiner_cells;     /* cells split from a point added at their centre (vertex_source -1) */
    int64_t face_steiner_points; /* points added at the centre of a (non-planar or non-convex) face with 4 or
                                  more corners, shared by the cells on both sides (vertex_source -1) */
    int64_t thin_faces_recut;  /* faces of 4 or more corners whose plain cut (a fan from the smallest id)
                                  left a near-flat triangle, cut along the other diagonal or at a point */
    int64_t flat_tets;         /* tets of split cells with a dihedral angle under TPK_FLAT_TET_DEG */
    int64_t polyhedra;         /* polyhedra (VTK 42) tetrahedralized: as a cone from their smallest vertex
                                  where valid, else from a centre point (counted in steiner_cells too) */
    int64_t fixed_boundary_cells; /* cells no centre or face points fit, tetrahedralized inside their boundary
                                     triangles by TetGen (interior points vertex_source -1) */
    int64_t bad_cells_skipped; /* cells not even that could split, left out (TPK_TETRA_SKIP_BAD_CELLS) */
} tpk_tetmesh;

void tpk_tetmesh_free(tpk_tetmesh *mesh);

/* The file's origin for points[0 .. 3 count) (spec §6.8): per axis 0 when the bounding box straddles
 * 0, else the number in the box with the fewest significant bits (0 for no points). */
void tpk_points_origin(const double *points, int64_t count, double origin[3]);
/* The same on `threads` threads (tpk_thread_count's rule); the same origin for any count. */
/* The first i in [0, count) with ids[i] < 0 or >= limit, or -1; on `threads` threads (tpk_thread_count's
 * rule), the same answer for any count. */
int64_t tpk_first_id_out_of_range(const int32_t *ids, int64_t count, int64_t limit, int threads);
void tpk_points_origin_threads(const double *points, int64_t count, int threads, double origin[3]);

#endif
