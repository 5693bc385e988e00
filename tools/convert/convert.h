/* The whole conversion: import -> tetrahedralize -> orient -> reorder -> connect -> layouts -> shell
 * -> write a .tpk atomically. Used by `tetpack convert` and by tests and benchmarks. */
#ifndef TPK_CONVERT_H
#define TPK_CONVERT_H

#include <stdint.h>

#include "base/diag.h"

/* The most levels of detail convert makes (--levels), and render and view open of a file (spec §16). */
#define TPK_MAX_LEVELS 8

#define TPK_LAYOUT_BIT_TET16 1u
#define TPK_LAYOUT_BIT_TET20 2u
#define TPK_LAYOUT_BIT_TET32 4u

typedef struct tpk_convert_options {
    const char *input;            /* source mesh path */
    const char *output;           /* .tpk path, written atomically; with output_fd, only its name in messages */
    int output_fd;                /* > 0: write the .tpk into this open, empty, seekable file instead (a memfd:
                                     render converts in memory); the caller owns it. Not with parts */
    const char *format;           /* NULL/"auto" or a forced importer name */
    unsigned layouts;             /* TPK_LAYOUT_BIT_*; 0 means Tet16 */
    const char *const *fields;    /* NULL: all scalar point fields */
    int field_count;
    int zstd_level;               /* 0: uncompressed (zero-copy); 1..22: zstd */
    int no_reorder;               /* keep source order (default: Hilbert reorder) */
    int cull;                     /* write the CULL chunk (spec §17, format 1.4): blocks of tets with the seeds
                                     of a walk inside each and the vertex ids they use, so that an iso render
                                     decodes only the blocks that may hold the surface */
    /* Repairs: never silent. Without them the problem is an error naming the first case and the count;
     * with them it is fixed and counted in the report, the summary and META's "repairs" object.
     * Orientation is the exception: a tet's or a mirrored cell's node order is a labeling, so inverted
     * tets and cells whose every tet is negative are turned over (and counted) unless strict_orientation.
     * A tet that, turned over, would fold against a neighbour is a bad cell instead (skip_bad_cells). */
    int strict_orientation;       /* inverted tets and mirrored cells are an error instead of turned over */
    int cut_folds;                /* cut the adjacency at folded faces (two shell faces) instead of failing */
    int drop_degenerate;          /* drop zero-volume tets and cells collapsed by merging, instead of failing */
    int merge_duplicates;         /* merge duplicate points before tetrahedralizing */
    double merge_tolerance;       /* 0: exactly equal coordinates; > 0: within this times the bbox diagonal */
    int skip_bad_cells;           /* leave out cells whose split would fold, and inverted tets that would fold
                                     if turned over, instead of failing */
    int cell_to_point;            /* average cell fields to points (and keep them without --field) */
    int higher_order_corners;     /* reduce higher-order cells to their corners instead of splitting them
                                     whole (mesh/higher_order.h) */
    double max_error;             /* > 0 (below 1): refine until every bounded point field is within this
                                     fraction of its range of each source cell's own interpolant, and the
                                     geometry within it of the bounds diagonal (convert/refine.h); 0: off.
                                     Not with higher_order_corners, merge_duplicates, parts */
    const char *const *max_error_fields; /* the point fields bounded; NULL: all */
    int max_error_field_count;
    int subdivide;                /* > 0 (not with max_error): every tet cut into 8 at its edges' midpoints
                                     (every edge halved) this many times, and the
                                     bound over the result proved and recorded (uniform subdivision, what
                                     --max-error is compared with) */
    int threads;                  /* <= 0: all cores */
    int parts;                    /* 0: one .tpk; >= 1: output is a part set manifest of this many parts
                                     (spec §15), cut along the Hilbert order */
    int levels;                   /* levels of detail to add (spec §16; 0: none; not with parts) */
    double level_shell_error;     /* how far a level's shell may lie inside the file's, times the bounding
                                     box diagonal (the CLI's default: TPK_LEVEL_SHELL_ERROR); 0: shell
                                     vertices move only within flat pieces, so the shell stays exactly */
    const char *command_line;     /* recorded in META; may be NULL */
    const struct tpk_tetgen_options *tetgen; /* surfaces and point clouds (surface.h); NULL: defaults */
} tpk_convert_options;

#define TPK_LEVEL_SHELL_ERROR 0.002

typedef struct tpk_convert_report {
    int64_t source_points, source_cells;
    int64_t higher_order_cells;   /* source cells of higher order: split whole, or reduced to corners */
    int64_t higher_order_points;  /* points added where split cells lack a face or cell centre */
    int higher_order_split;       /* 1: split whole; 0: reduced to corners (with higher_order_cells > 0) */
    int64_t vertices, tets, shell_faces;
    int64_t inverted_fixed, degenerate_dropped; /* inverted tets turned over; zero-volume tets dropped */
    int64_t merged_vertices, collapsed_cells_dropped; /* --merge-duplicates; cells it collapsed, dropped */
    int64_t cells_into[7];       /* source cells that gave k tets (1 tetra, 2 pyramid, 3 wedge, 5/6 hex) */
    int64_t face_steiner_points, polyhedra; /* points added at face centres; polyhedra split */
    int64_t thin_faces_recut, flat_tets;    /* tpk_tetmesh's: faces cut otherwise to avoid a near-flat
                                               triangle; flat tets of the split cells (TPK_FLAT_TET_DEG) */
    int64_t mirrored_cells, steiner_cells, bad_cells_skipped; /* mirrored: turned over; bad: left out (cells,
                                                                 and inverted tets that would fold) */
    int64_t folds_cut;            /* folded faces whose adjacency was cut (cut_folds) */
    int64_t fixed_boundary_cells; /* tetrahedralized inside their boundary triangles (TetGen) */
    int field_count, step_count;
    struct {                      /* --max-error (max_error > 0) */
        double requested;         /* the bound asked for */
        double field_error;       /* the largest proven bound over the tets, a fraction of the field's range */
        double geometry_error;    /* the same for the geometry, a fraction of the bounds diagonal */
        char worst_field[64];
        int fields;               /* point fields bounded */
        int64_t tets_before, vertices_added;
        int passes;
        int subdivide;            /* the levels of --subdivide, or 0 */
        double seconds;
    } max_error;
    uint64_t output_bytes;
    int level_count;              /* levels of detail written (may be fewer than asked: levels.h) */
    struct {
        int64_t vertices, tets, error_samples;
        double error_max, error_rms, shell_distance, shell_tolerance, seconds;
        uint64_t bytes;
    } level[TPK_MAX_LEVELS];
    double t_levels;
    /* seconds per stage */
    double t_import, t_tetrahedralize, t_orient, t_reorder, t_connect, t_write, t_total; /* layouts and shell are built while writing */
} tpk_convert_report;

/* Progress callback: the stage name with fraction 0 when a stage starts, then again with the fraction
 * done where the stage can tell (import: bytes read, by the readers of base/text_scan.h, per section or
 * block; tetrahedralize: source cells split); a stage is done when the next
 * starts or tpk_convert returns. Called from the calling thread. May be NULL. */
typedef void (*tpk_stage_fn)(void *user, const char *stage, double fraction);

struct tpk_strbuf;
/* Appends the "repairs" JSON object (what was asked for and what was done), as META records it:
 * {"reorient":{"requested":B,"inverted_tets":N,"mirrored_cells":N},
 *  "drop_degenerate":{"requested":B,"degenerate_tets":N,"collapsed_cells":N},
 *  "merge_duplicates":{"requested":B,"tolerance":X,"merged_vertices":N},
 *  "cut_folds":{"requested":B,"folded_faces":N}}
 * reorient.requested is true unless strict_orientation (turning over is the default).
 * tolerance: 0 for exactly equal coordinates, else relative to the bounding-box diagonal. */
void tpk_convert_repairs_json(struct tpk_strbuf *sb, const tpk_convert_options *options,
                              const tpk_convert_report *report);

int tpk_convert(const tpk_convert_options *options, tpk_convert_report *report, tpk_stage_fn stage,
                void *stage_user, tpk_diag *diag);

#endif
