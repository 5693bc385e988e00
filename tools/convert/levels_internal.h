/* Internal to the levels of detail (levels.h): what the files of tools/convert/levels*.c share.
 *
 * Who defines what. levels.c, the entry (tpk_make_levels), sits on top: it sets the simplifier up and,
 * level by level, simplifies (levels_blocks.c), extracts the level (levels_extract.c), checks its
 * domain (levels_domain.c), writes it (levels_memfd.c) and measures it (levels_shell_distance.c,
 * levels_measure.c). Below it, one algorithm per file, each calling only down this list:
 *   levels_blocks.c          the passes: blocks side by side with prefetch, then the sweep
 *   levels_collapse.c        one collapse: the moved tets' rules, the target's choice
 *   levels_shell_moves.c     the rules for a shell vertex: its ring, flat or inward moves, witnesses
 *   levels_stars.c           the stars of the vertices a pass may collapse, a star's neighbours
 *   levels_extract.c         a level's tetmesh out of the live tets
 *   levels_measure.c         the field's error at the removed vertices
 *   levels_shell_distance.c  the shell's distance at the removed shell vertices
 *   levels_domain.c          a level's volume and shell area against the full mesh's
 *   levels_memfd.c           a level written into an unnamed file in memory, its bytes mapped
 *   levels_geometry.c        a tet's shape, a point's distance to a triangle
 *   levels_fill.c            fill, zero, bounds and offsets on all threads
 * The small helpers every file reads in its inner loops (point, edge, survivor) are inline here. The
 * results do not depend on the thread count. */
#ifndef TPK_CONVERT_LEVELS_INTERNAL_H
#define TPK_CONVERT_LEVELS_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "convert.h"
#include "levels.h"
#include "mesh/mesh.h"

#define TPK_LEVEL_QUALITY 0.02 /* 6 V / L^3 of a new tet (a regular tet: 0.707) */
/* Each level aims at a sixth of the tets of the one before. A level costs more bytes per tet than its
 * file (its TMAP and the shell it keeps whole; grid 55: 27 B against 24 B), so a fifth made the levels
 * 31% of the file; a sixth makes them 28%, for an RMS error 13% higher on level 1 (0.0774 against
 * 0.0683) and a frame time that tets^(1/3) predicts 6% lower. */
#define TPK_LEVEL_RATIO 6
#define STAR_MAX 512
#define NEIGHBOURS_MAX 128
#define RING_MAX 64 /* shell faces around one vertex; past it the vertex stays */

/* What a collapse reads of each vertex it meets, side by side: its position, field value and mark
 * (star_neighbours), so that a neighbour costs one cache line, not three. */
typedef struct level_vertex {
    double p[3];
    float field;  /* s->field's value, or 0 */
    int32_t seen; /* -1, or the vertex whose neighbours star_neighbours is listing */
} level_vertex;

typedef struct simplifier {
    const tpk_tetmesh *mesh;
    int threads;
    const float *field;  /* the first point field at its step of widest range (field_step), or NULL */
    int field_step;
    uint8_t *boundary;   /* per vertex: on the shell */
    uint8_t *pinned;     /* per vertex: never moves (on the shell of a mesh with cut folds) */
    double shell_tolerance; /* how far the shell may move from the full mesh's, stored frame units */
    int32_t *chain_head, *chain_next; /* per live shell vertex (with a tolerance): the removed shell
                            vertices it owns (needs_witness), linked through chain_next; -1 ends */
    uint8_t *removed;    /* per vertex */
    int32_t *onto;       /* per removed vertex: the vertex it was moved onto (levels_measure() follows these) */
    int32_t *tets;       /* 4 per live tet, full mesh vertex ids, positive */
    int32_t *origin;     /* per live tet: the full mesh tet it descends from */
    int64_t tet_count;
    int64_t *star_start, *star_end; /* per live vertex: its tets in star, [start, end) (-1, -1: not kept) */
    int32_t *alive;      /* the vertices not removed, in id order, as of the last build_stars */
    int64_t alive_count;
    int32_t *alive_next; /* build_stars writes the new list here, then swaps it with alive */
    int32_t *star;
    uint8_t *locked, *dead;
    uint8_t *stuck;      /* per vertex: no valid target, and its star has not changed since */
    level_vertex *vert;  /* per vertex */
    int32_t *active;     /* the vertices this pass may collapse, in id order (build_stars) */
    int64_t active_count;
    float *tet_quality;  /* per live tet: its shape (levels_quality(); a moved tet's from its test in choose_target) */
} simplifier;

static inline const double *point(const simplifier *s, int32_t v)
{
    return s->vert[v].p;
}

/* The squared length of b - a, and b - a in e. */
static inline double edge(const double *a, const double *b, double e[3])
{
    e[0] = b[0] - a[0], e[1] = b[1] - a[1], e[2] = b[2] - a[2];
    return e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
}

/* The level vertex a removed vertex ended on, at the end of the chain of the vertices it was moved onto. */
static inline int32_t survivor(const simplifier *s, int32_t u)
{
    while (s->removed[u])
        u = s->onto[u];
    return u;
}

/* What a level must keep of the full mesh: its volume and its shell's area (sums of 6V and of twice the
 * face areas, in the stored frame). Equal up to rounding when the domain is the same; a bug that lost
 * or doubled a piece would show. */
typedef struct domain_size {
    double volume, area;
} domain_size;

/* ---- levels_fill.c ---------------------------------------------------------------------------------- */
/* a[0..n) = value, on all threads. */
void levels_fill_i32(int32_t *a, int64_t n, int32_t value, int threads);
/* a[0..n) = 0, bytes, on all threads. */
void levels_zero_bytes(uint8_t *a, int64_t n, int threads);
/* The bounds of n points (each origin + point, origin NULL: 0), the same whatever the thread count. */
void levels_bounds_of(const double *points, const double *origin, int64_t n, int threads, double lo[3], double hi[3]);
/* Counts per worker into offsets: c[w] becomes the sum of c[0..w), c[parts] the total. */
void levels_offsets(int64_t *c, int parts);

/* ---- levels_geometry.c ------------------------------------------------------------------------------ */
/* 6 V / L^3 of the tet (a, b, c, d): 0 flat, 0.707 regular; negative when inverted. */
double levels_quality(const double *a, const double *b, const double *c, const double *d);
/* The distance from p to the triangle (a, b, c). */
double levels_point_triangle(const double *p, const double *a, const double *b, const double *c);

/* ---- levels_stars.c --------------------------------------------------------------------------------- */
/* The vertices a pass may collapse (not pinned, not removed, not stuck), in id order, and their stars. */
void levels_build_stars(simplifier *s);
/* u's neighbours over its live star, each once, with their costs (field difference, else squared
 * distance): the count; -1 past NEIGHBOURS_MAX; -2 when lo < hi and one lies outside [lo, hi). */
int levels_star_neighbours(simplifier *s, int32_t u, const int32_t *star, int n, int32_t lo, int32_t hi,
                           int32_t *nb, double *cost);

/* ---- levels_shell_moves.c --------------------------------------------------------------------------- */
/* Shell vertex u's ring of shell faces (ring[i] = {a, b, fourth corner}): their count when they form one
 * ring, else -1 (then u stays). */
int levels_shell_ring(const simplifier *s, int32_t u, const int32_t *star, int n, int32_t ring[RING_MAX][3]);
/* Whether shell vertex u may move onto v: on its ring, flat or (with a tolerance) inward. */
int levels_shell_move_ok(const simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m);
/* With a tolerance: whether every removed shell vertex keeps a witness when u moves onto v. */
int levels_witnesses_kept(const simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m);
/* After u moved onto v: the chains of removed shell vertices that v now owns. */
void levels_move_chains(simplifier *s, int32_t u, int32_t v, const int32_t ring[][3], int m);

/* ---- levels_collapse.c ------------------------------------------------------------------------------ */
/* Collapse u if it may go and has a valid target (with lo < hi: only inside the block [lo, hi)): the
 * tets it kills, or -1 when it stays. */
int64_t levels_try_collapse(simplifier *s, int32_t u, int32_t lo, int32_t hi);

/* ---- levels_blocks.c -------------------------------------------------------------------------------- */
/* Simplify to about `target` live tets (or as far as passes go). */
void levels_simplify_to(simplifier *s, int64_t target);

/* ---- levels_extract.c ------------------------------------------------------------------------------- */
/* The level's tetmesh (kept vertices in full-mesh order, tets renumbered, fields and maps gathered) and
 * *vertex_old, each level vertex's full-mesh id (malloc'd). 0, or -1 with a message. */
int levels_mesh(const simplifier *s, tpk_tetmesh *out, int32_t **vertex_old, tpk_diag *diag);
void levels_mesh_free(tpk_tetmesh *m);

/* ---- levels_domain.c -------------------------------------------------------------------------------- */
/* The domain's 6V and twice its shell's area, the same sums whatever the thread count. */
domain_size levels_size_of(const double *points, const int32_t *tets, const int32_t *neighbors, int64_t tet_count,
                           int threads);
/* Whether a level's size is the full mesh's, up to rounding or what the shell tolerance allows. */
int levels_same_size(domain_size full, domain_size level, double tolerance);

/* ---- levels_shell_distance.c ------------------------------------------------------------------------ */
/* How far the full mesh's shell lies from the level's at the removed shell vertices (at most too
 * large); near_tet[u] gets the level tet of u's nearest face found. */
double levels_shell_distance(const simplifier *s, const tpk_tetmesh *lvl, const int32_t *vertex_old,
                             const int32_t *neighbors, int32_t *near_tet);

/* ---- levels_measure.c ------------------------------------------------------------------------------- */
/* The field's error at the vertices the level removed: r's error_samples, error_max and error_rms. */
void levels_measure(const simplifier *s, const tpk_tetmesh *lvl, const int32_t *vertex_old, const int32_t *neighbors,
                    const int32_t *near_tet, tpk_level *r);

/* ---- levels_memfd.c --------------------------------------------------------------------------------- */
/* Level k's mesh written as a whole .tpk into an unnamed file in memory, its bytes into r (data, size,
 * mapped). 0, or -1 with a message. */
int levels_write_file(const tpk_convert_options *o, const tpk_tetmesh *lvl, const int32_t *neighbors, int threads,
                      int k, const char *source_format, const tpk_convert_report *source, tpk_level *r,
                      tpk_diag *diag);

#endif
