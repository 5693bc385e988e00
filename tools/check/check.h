/* tetpack check: the validator. Every check has a stable numeric id, a snake_case name and a severity
 * (the registry, check_registry.c); a run collects, per check, how many offending items it found and
 * the first few as examples (lowest ids first), plus statistics (quality histograms, components, field
 * ranges) for the report. All geometric decisions use exact predicates; tolerances only where the user
 * sets them (near-duplicate vertices, quality thresholds).
 *
 * Groups, each in its own file:
 *   1xx vertices      check_vertices.c      2xx cells         check_cells.c
 *   3xx connectivity  check_topo_*.c        4xx shell         check_shell.c, check_shell_cgal.cpp
 *   5xx fields        check_fields.c        6xx .tpk files    check_tpk.c, check_tpk_mesh.c
 * The driver check.c (tpk_check_path) calls the groups; below them all, check_report.c (the report and
 * its output), check_registry.c and check_progress.c (tpk_check_progress), which call no group.
 */
#ifndef TPK_CHECK_H
#define TPK_CHECK_H

#include <stdint.h>
#include <stdio.h>

#include "base/diag.h"
#include "mesh/mesh.h"
#include "base/strbuf.h"

typedef enum tpk_severity { TPK_SEV_INFO = 0, TPK_SEV_WARNING = 1, TPK_SEV_ERROR = 2 } tpk_severity;

typedef struct tpk_check_def {
    int id;                  /* stable: never reused, never renumbered */
    const char *name;        /* stable snake_case word, e.g. "inverted_cell" */
    tpk_severity severity;
    const char *group;       /* "vertices", "cells", "connectivity", "shell", "fields", "file" */
    const char *explanation; /* one line for `tetpack check --list` */
} tpk_check_def;

/* Every check, in id order; *count set to their number. */
const tpk_check_def *tpk_check_registry(int *count);
/* The check with this id or name; NULL when there is none. */
const tpk_check_def *tpk_check_by_id(int id);
const tpk_check_def *tpk_check_by_name(const char *name);

#define TPK_CHECK_MAX_IDS 8

/* One offending item. `kind` says what ids[] names: "vertex", "cell", "face", "edge", "tet", "component",
 * "field", "chunk", ... ids[0] is the item's own id (the cell, the first vertex of a duplicate pair...),
 * the rest related ids (the cell's vertices, the other cell, ...). */
typedef struct tpk_example {
    const char *kind;
    int id_count;
    int64_t ids[TPK_CHECK_MAX_IDS];
    int has_point;
    double point[3];          /* a location in world coordinates (e.g. a vertex, a cell's centre) */
    char note[160];           /* short free text: values, angles, what is wrong */
} tpk_example;

typedef struct tpk_finding {
    const tpk_check_def *check;
    int64_t count;            /* how many offending items (0: the check ran and found nothing) */
    int example_count;
    tpk_example *examples;    /* up to max_examples */
    char summary[200];        /* optional one-line summary (e.g. "3 components: 14487, 14487, 2") */
} tpk_finding;

/* A histogram for quality statistics: `bins` equal bins over [lo, hi]. */
#define TPK_HIST_BINS 18
typedef struct tpk_histogram {
    const char *name;         /* "min_dihedral_deg", ... */
    double lo, hi;
    int64_t bins[TPK_HIST_BINS];
    int64_t count;
    double min, max, sum;
} tpk_histogram;

typedef struct tpk_check_options {
    double tol;               /* near-duplicate tolerance relative to the bounding-box diagonal; 0: off,
                                 default 1e-9 */
    double sliver_deg;        /* tets with minimum dihedral angle below this are slivers (default 0.1) */
    double warp_deg;          /* quad faces whose two triangles' normals differ by more than this are
                                 non-planar (default 20) */
    double radius_ratio_min;  /* tets with radius ratio (3 r_in / r_circ, 1 for regular) below this are
                                 counted as poorly shaped (default 0.1) */
    int max_examples;         /* examples kept per finding (default 5) */
    int threads;              /* <= 0: all cores */
    int progress;             /* print a progress bar on stderr */
    int skip_shell_intersections; /* --fast: skip the O(n log n) shell self-intersection test */
} tpk_check_options;

void tpk_check_options_default(tpk_check_options *options);

#define TPK_CHECK_MAX_HISTOGRAMS 8
#define TPK_CHECK_MAX_FIELD_STATS 64

typedef struct tpk_field_stat {
    char name[TPK_NAME_MAX];
    int association, components, step;
    double min, max;
    int64_t nonfinite;
} tpk_field_stat;

typedef struct tpk_check_report {
    tpk_check_options options;
    char input[512];
    char format[32];
    int64_t vertices, cells, tets;   /* tets: only for .tpk input (else 0) */
    int64_t cell_type_counts[256];
    tpk_finding *findings;           /* one per registry entry, in registry order */
    int finding_count;
    tpk_histogram histograms[TPK_CHECK_MAX_HISTOGRAMS];
    int histogram_count;
    tpk_field_stat field_stats[TPK_CHECK_MAX_FIELD_STATS];
    int field_stat_count;
    int64_t component_count;
    int64_t component_sizes[16];     /* largest first, cells per component */
    int ran[7];                      /* groups that ran: index 1..6 = 1xx..6xx */
    double seconds[7];
} tpk_check_report;

int tpk_check_report_init(tpk_check_report *report, const tpk_check_options *options);
void tpk_check_report_free(tpk_check_report *report);

/* The finding of check `id` (abort()s on an unknown id: a programming error). */
tpk_finding *tpk_check_finding(tpk_check_report *report, int id);
/* Count one offending item for check `id`; returns the example slot to fill when the finding keeps
 * fewer than max_examples, else NULL. Callers must report items in a deterministic order (lowest id
 * first) so the examples do not depend on thread count. Not thread-safe. */
tpk_example *tpk_check_hit(tpk_check_report *report, int id, const char *kind);
/* The next of at most `max` example slots of a list (*examples allocated on first use, *kept counted),
 * cleared and of `kind`; NULL when the list is full or out of memory (examples are best effort, counts
 * are kept by the caller). Shared by the report and the per-worker lists of the groups. */
tpk_example *tpk_example_slot(tpk_example **examples, int *kept, int max, const char *kind);
/* Add `n` items to the count without examples. */
void tpk_check_count(tpk_check_report *report, int id, int64_t n);
/* Helpers to fill an example. */
void tpk_example_ids(tpk_example *ex, int count, const int64_t *ids);
void tpk_example_point(tpk_example *ex, const double p[3]);
void tpk_example_note(tpk_example *ex, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
tpk_histogram *tpk_check_histogram(tpk_check_report *report, const char *name, double lo, double hi);
void tpk_histogram_add(tpk_histogram *h, double value);

/* The input the mesh-level checks see. For a .tpk file the tets become cells of type 10, with world
 * coordinates (origin + stored positions) and the file's fields. */
typedef struct tpk_check_input {
    const tpk_mesh *mesh;
    const char *path;
    const tpk_diag *import_diag; /* the importer's diag (field length problems), or NULL */
} tpk_check_input;

/* The groups. Each returns 0, or -1 (diag set) when it could not run at all (out of memory); problems
 * in the mesh are findings, never errors. The cells group must run before connectivity (it marks cells
 * whose ids are out of range or repeated; later groups skip them). */
int tpk_check_vertices(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag);
int tpk_check_cells(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag);
int tpk_check_topology(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag); /* 3xx+4xx */
int tpk_check_fields(const tpk_check_input *in, tpk_check_report *report, tpk_diag *diag);
/* 6xx: every MUST of the spec on an opened file (tpk_verify, then the mesh invariants TPK-M01..M13
 * with check ids 601..613 and the culling blocks TPK-B01, 616). */
struct tpk_file;
int tpk_check_tpk_file(const char *path, struct tpk_file *file, tpk_check_report *report, tpk_diag *diag);
/* Check 615 and 600..613 on every level of detail of the file (spec §16; check_levels.c). 0, or -1 with
 * a message when a check could not run. */
int tpk_check_levels(const char *path, struct tpk_file *file, tpk_check_report *report, tpk_diag *diag);
/* The file's mesh as a tpk_mesh for the mesh-level groups: tets as cells of type 10 (from TT32, else
 * recovered from Tet20/Tet16), world coordinates (origin + stored positions) and every field with all
 * steps. Returns -1 (diag set) when the tets cannot be recovered; the 6xx findings say why. */
int tpk_check_tpk_mesh(struct tpk_file *file, tpk_mesh *out, tpk_diag *diag);
/* The same pair for the driver, sparing a second walk: when the file has no Tet32 and the 6xx checks
 * found nothing, *tets_out receives the tets they recovered (4 positively oriented ids each, malloc'd,
 * else NULL), and tpk_check_tpk_mesh_tets takes them over (NULL: recover them itself). */
int tpk_check_tpk_file_tets(const char *path, struct tpk_file *file, tpk_check_report *report, int32_t **tets_out,
                            tpk_diag *diag);
int tpk_check_tpk_mesh_tets(struct tpk_file *file, int32_t *tets, tpk_mesh *out, tpk_diag *diag);

/* A part set's manifest (a .tpk with a PART chunk): the 6xx checks of every part, then 614 on the links.
 * Returns -1 (diag set) when the set cannot be opened (a part missing or not matching its record). */
int tpk_check_set(const char *path, tpk_check_report *report, tpk_diag *diag);

/* Cells usable by geometric/topological checks: every id in range and no id repeated. */
int tpk_check_cell_usable(const tpk_mesh *mesh, int64_t cell);

/* Run everything on a file of any format the importers read, or a .tpk. Returns 0 when the checks ran
 * (the report says what they found), -1 when the input could not be read (diag says why). */
int tpk_check_path(const char *path, const char *format, tpk_check_report *report, tpk_diag *diag);

/* Progress of a long group on a terminal (no-op unless options.progress): `fraction` in [0, 1] of
 * `stage`. Call from one thread only (worker 0), at most every few thousand items. */
void tpk_check_progress(tpk_check_report *report, const char *stage, double fraction);

/* Exit status: 1 when a finding of severity error (or warning, with warnings_as_errors) has count > 0. */
int tpk_check_has_problems(const tpk_check_report *report, int warnings_as_errors);

/* Output. */
void tpk_check_print_text(const tpk_check_report *report, FILE *out);
void tpk_check_write_json(const tpk_check_report *report, tpk_strbuf *sb);
void tpk_check_print_list(FILE *out);

#endif
