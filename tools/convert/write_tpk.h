/* Writing one .tpk from the pipeline's tet mesh (shared by the whole-file and the part-set converter). */
#ifndef TPK_WRITE_TPK_H
#define TPK_WRITE_TPK_H

#include <stdint.h>

#include "base/diag.h"
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

struct tpk_levels;
/* The levels of a file (spec §16), made while it is written: once its own chunks are (positions,
 * layouts, shell, fields, maps), before META, which describes them. make() fills *levels; by then
 * nothing reads the mesh's tets or the neighbors again, so it may use them as scratch (levels.c does:
 * its working tets and stars, not 1.5 GB of fresh pages on a 48M-tet mesh). 0, or -1 with a message. */
typedef struct tpk_levels_maker {
    int (*make)(void *ctx, struct tpk_levels *levels, tpk_diag *diag);
    void *ctx;
    struct tpk_levels *levels;
} tpk_levels_maker;

/* Write `mesh` (stored frame, positive tets, their neighbors) to o->output atomically, with the layouts
 * o->layouts asks for, the shell, fields, maps and META; part may be NULL; maker (NULL: no levels) makes
 * the levels, and a LEVL chunk per level (spec §16) and their figures in META follow. hdr gives origin and
 * bounds; its counts are filled here, and rep's shell_faces and output_bytes. */
int tpk_write_tpk(const tpk_convert_options *o, const tpk_tetmesh *mesh, const int32_t *neighbors,
                  tpk_header_fields *hdr, tpk_convert_report *rep, const char *source_format,
                  const tpk_part_extras *part, const tpk_levels_maker *maker, tpk_diag *diag);

#endif
