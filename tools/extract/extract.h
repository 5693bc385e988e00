/* tetpack extract: a smaller, valid .tpk that keeps only what a scene needs: one tet layout, one field
 * and the steps shown, and the tets that meet a clip box, with the shell rebuilt where the box cuts the
 * mesh and TMAP/VMAP carried over so picks still name source cells and points. */
#ifndef TPK_EXTRACT_H
#define TPK_EXTRACT_H

#include <stdint.h>

#include "base/diag.h"
#include "render/render.h"
#include "tetpack.h"

typedef struct tpk_extract_options {
    const char *input, *output;
    tpk_layout layout;          /* 0: the one render picks (the first of Tet16, Tet20, Tet32 present) */
    const char *field;          /* NULL: the one render picks (the first point field; none if no point field) */
    int step_first, step_last;  /* steps of the field kept, renumbered from 0 (0, 0: the first step) */
    int clip;                   /* keep only the tets that meet [clip_min, clip_max] (see tpk_extract) */
    double clip_min[3], clip_max[3];
    int probe_count;            /* and only the tets that may show through these probes (tpk_probe_may_show) */
    tpk_probe probes[TPK_RENDER_MAX_PROBES];
    int level;                  /* 0: the file itself; k >= 1: its level of detail k (spec §16) */
    int zstd_level;             /* -1: each chunk as the source stored it (zstd at the default level or
                                   none); 0: uncompressed; 1..22: zstd at that level */
    int threads;                /* <= 0: all cores */
    const char *command_line;   /* recorded in META; may be NULL */
} tpk_extract_options;

typedef struct tpk_extract_report {
    uint64_t bytes_before, bytes_after;
    uint64_t vertices_before, vertices_after, tets_before, tets_after, shell_before, shell_after;
    tpk_layout layout;          /* the layout written */
    char field[64];             /* the field written ("" for none) */
    int field_is_tet;           /* 1 when it is a per-tet field */
    int steps;                  /* steps written */
    double field_min, field_max; /* the source field's range (FDSC), for a scene of the result */
    double bounds_min[3], bounds_max[3]; /* the source's bounds, for a scene of the result */
    double diagonal;            /* the source's box diagonal as the renderer measures it (its stored
                                   positions), whose defaults (unit distance, AO radius) follow it */
} tpk_extract_report;

/* Write options->output. A tet is kept when its axis-aligned bounding box (of its four stored
 * positions, origin added) meets the closed clip box: every tet that has a point in the box is kept,
 * so a render clipped to the box sees the same tets. Faces whose neighbour was left out become shell
 * faces; the neighbours, records and shell are rebuilt with the converter's stages (connect, folds,
 * layouts, shell) on the kept tets, whose vertices are renumbered in their old order; positions keep
 * the source's origin and float32 values, so orientation and the decisions of the marcher stay exactly
 * as they were. The field's min/max are those of the values kept. Returns 0, or -1 with a message (no
 * such field, step or layout, no tet in the box, an unreadable input, an output that cannot be written). */
int tpk_extract(const tpk_extract_options *options, tpk_extract_report *report, tpk_diag *diag);

#endif
