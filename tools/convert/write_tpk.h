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
/* Write `mesh` (stored frame, positive tets, their neighbors) to o->output atomically, with the layouts
 * o->layouts asks for, the shell, fields, maps and META; part may be NULL; levels (NULL: none) adds a
 * LEVL chunk per level (spec §16) and their figures to META. hdr gives origin and bounds; its counts are
 * filled here, and rep's shell_faces and output_bytes. */
int tpk_write_tpk(const tpk_convert_options *o, const tpk_tetmesh *mesh, const int32_t *neighbors,
                  tpk_header_fields *hdr, tpk_convert_report *rep, const char *source_format,
                  const tpk_part_extras *part, const struct tpk_levels *levels, tpk_diag *diag);

#endif
