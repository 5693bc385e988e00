/* Writing one .tpk from the pipeline's tet mesh (shared by the whole-file and the part-set converter). */
#ifndef TPK_WRITE_TPK_H
#define TPK_WRITE_TPK_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"
#include "base/output_file.h"
#include "convert.h"
#include "mesh/mesh.h"
#include "tetpack.h"

/* What a part of a part set adds to its file (spec §15): its LINK records and its place in the set,
 * recorded in META as "part_set":{"index":i,"parts":n}. */
typedef struct tpk_part_extras {
    const tpk_link *links;
    int64_t link_count;
    int index, count;
} tpk_part_extras;

/* Move the points into the stored frame: relative to the origin (hdr->origin: the grid origin the
 * tetrahedralizer decided on, else tpk_points_origin's), rounded to float32; sets the origin and the
 * bounds of hdr. Fails naming a point that is not finite or too far for float32. */
int tpk_quantize_points(tpk_tetmesh *mesh, tpk_header_fields *hdr, tpk_diag *diag);

/* One level of detail (spec §16) as the file stores it: the bytes of its whole .tpk (levels.c makes
 * them), and the figures META gives for it. */
typedef struct tpk_level {
    void *data; /* the whole .tpk: mapped from the file it was written into (mapped), or malloc'd */
    size_t size;
    int mapped;
    int64_t vertices, tets;
    char field[64];          /* the field the error is measured on ("" without a point field) */
    int field_step;          /* at this step: the one of widest range */
    int64_t error_samples;   /* the full mesh's vertices this level removed: the error is sampled there */
    double error_max, error_rms; /* |level - full| at those points, field units */
    double shell_distance;   /* of the full mesh's shell from the level's, measured at the shell vertices the
                                level removed (levels_shell_distance.c): 0 when the shell moved only within
                                flat pieces */
    double shell_tolerance;  /* what it was allowed (convert's level_shell_error times the bbox diagonal) */
    double seconds;          /* simplifying and writing it */
} tpk_level;

typedef struct tpk_levels {
    int count;
    tpk_level level[TPK_MAX_LEVELS];
} tpk_levels;

/* A .tpk being written, in two steps so that the caller can make the levels between them (convert.c):
 * tpk_write_begin writes the file's own chunks (positions, layouts, shell, fields, maps); by then nothing
 * reads the mesh's tets or the neighbors again, so the caller may use them as scratch (levels.c does: its
 * working tets and stars, not 1.5 GB of fresh pages on a 48M-tet mesh), while the system writes the chunks
 * out. tpk_write_end then writes META, which describes the levels, a LEVL chunk per level and LINK, and
 * commits the file; tpk_write_abort drops it instead. The writer calls nothing of the levels. */
typedef struct tpk_write_session {
    tpk_writer *writer;
    tpk_output out;
    int named; /* o->output opened here (else the caller's o->output_fd) */
    tpk_diag *diag;
    int queued; /* 1 while the writer's calls run on a thread of their own (write_tpk.c) */
} tpk_write_session;

/* Open o->output atomically and write `mesh` (stored frame, positive tets, their neighbors) with the
 * layouts o->layouts asks for, the shell, fields and maps. hdr gives origin and bounds; its counts are
 * filled here. 0, or -1 with a message (the output dropped). */
int tpk_write_begin(tpk_write_session *ws, const tpk_convert_options *o, const tpk_tetmesh *mesh,
                    const int32_t *neighbors, tpk_header_fields *hdr, tpk_diag *diag);
/* META, then a LEVL chunk per level of `levels` (NULL: none) and their figures in META, then a part's LINK
 * (part may be NULL), and the file committed; rep's shell_faces and output_bytes filled. 0, or -1 with a
 * message (the output dropped). */
int tpk_write_end(tpk_write_session *ws, const tpk_convert_options *o, tpk_header_fields *hdr,
                  tpk_convert_report *rep, const char *source_format, const tpk_part_extras *part,
                  const tpk_levels *levels, tpk_diag *diag);
/* Drop a file that tpk_write_begin began. */
void tpk_write_abort(tpk_write_session *ws);

/* tpk_write_begin, then tpk_write_end without levels: a whole file (a part's, a level's, one without
 * levels). */
int tpk_write_tpk(const tpk_convert_options *o, const tpk_tetmesh *mesh, const int32_t *neighbors,
                  tpk_header_fields *hdr, tpk_convert_report *rep, const char *source_format,
                  const tpk_part_extras *part, tpk_diag *diag);

#endif
