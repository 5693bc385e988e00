/* tetpack check OUT.tpk --against SOURCE: a converted file measured against its source. Points are
 * sampled inside every source cell through the cell's own map (mesh/cell_map.h), located in the
 * converted tets, and each point field shared by both (by name, scalar) compared there: the file's
 * linear interpolant against the source cell's own interpolant, as a fraction of the field's range. */
#ifndef TPK_CHECK_AGAINST_H
#define TPK_CHECK_AGAINST_H

#include <stdint.h>

#include "base/diag.h"

#define TPK_AGAINST_MAX_FIELDS 32

typedef struct tpk_against_field {
    char name[64];
    int steps;                 /* steps compared (the fewer of the two) */
    double range;              /* max - min over the source's nodes, every step compared */
    double max_error, rms_error; /* |source - file| / range, over every sample and step */
    int bounded;               /* META's bound holds for it (every field, or one max_error_fields names) */
} tpk_against_field;

typedef struct tpk_against_report {
    int64_t cells;             /* source cells sampled (volume cells whose map mesh/cell_map.h knows) */
    int64_t cells_skipped;     /* volume cells of other kinds (polyhedra, Lagrange cells...) */
    int64_t samples;           /* points sampled */
    int64_t outside;           /* samples in no tet of the file (farther than 1e-9 of a tet's size) */
    int field_count;
    tpk_against_field fields[TPK_AGAINST_MAX_FIELDS];
    int has_bound;             /* META records "max_error" (a bound the converter promised) */
    double bound;
    int bound_exceeded;        /* some field's max_error is above the bound */
} tpk_against_report;

/* Measure `tpk_path` against `source` (read whole, as convert reads it; `format` may force the reader):
 * `per_axis` samples per parametric axis (a hexahedron gets per_axis^3 at cell-centred lattice points,
 * the other shapes those of that lattice inside them). 0, or -1 with a message (unreadable file or
 * source, a file without TMAP, out of memory). */
int tpk_check_against(const char *tpk_path, const char *source, const char *format, int per_axis,
                      tpk_against_report *out, tpk_diag *diag);

#endif
