/* The whole conversion: import -> tetrahedralize -> orient -> reorder -> connect -> layouts -> shell
 * -> write a .tpk atomically. Used by `tetpack convert` and by tests and benchmarks. */
#ifndef TPK_CONVERT_H
#define TPK_CONVERT_H

#include <stdint.h>

#include "diag.h"

#define TPK_LAYOUT_BIT_TET16 1u
#define TPK_LAYOUT_BIT_TET20 2u
#define TPK_LAYOUT_BIT_TET32 4u

typedef struct tpk_convert_options {
    const char *input;            /* source mesh path */
    const char *output;           /* .tpk path, written atomically */
    const char *format;           /* NULL/"auto" or a forced importer name */
    unsigned layouts;             /* TPK_LAYOUT_BIT_*; 0 means Tet16 */
    const char *const *fields;    /* NULL: all scalar point fields */
    int field_count;
    int zstd_level;               /* 0: uncompressed (zero-copy); 1..22: zstd */
    int no_reorder;               /* keep source order (default: Hilbert reorder) */
    int drop_degenerate;          /* drop zero-volume tets instead of failing */
    int skip_bad_cells;           /* leave out cells whose split would fold, instead of failing */
    int cell_to_point;            /* average cell fields to points (and keep them without --field) */
    int threads;                  /* <= 0: all cores */
    const char *command_line;     /* recorded in META; may be NULL */
    const struct tpk_tetgen_options *tetgen; /* surfaces and point clouds (surface.h); NULL: defaults */
} tpk_convert_options;

typedef struct tpk_convert_report {
    int64_t source_points, source_cells;
    int64_t vertices, tets, shell_faces;
    int64_t inverted_fixed, degenerate_dropped;
    int64_t cells_into[7];       /* source cells that gave k tets (1 tetra, 2 pyramid, 3 wedge, 5/6 hex) */
    int64_t mirrored_cells, steiner_cells, bad_cells_skipped;
    int field_count, step_count;
    uint64_t output_bytes;
    /* seconds per stage */
    double t_import, t_tetrahedralize, t_orient, t_reorder, t_connect, t_write, t_total; /* layouts and shell are built while writing */
} tpk_convert_report;

/* Progress callback: stage name when a stage starts. May be NULL. */
typedef void (*tpk_stage_fn)(void *user, const char *stage);

int tpk_convert(const tpk_convert_options *options, tpk_convert_report *report, tpk_stage_fn stage,
                void *stage_user, tpk_diag *diag);

#endif
