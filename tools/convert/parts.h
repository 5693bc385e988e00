/* Part sets (spec §15) written by the converter: a mesh cut into parts along its Hilbert order, each
 * part a complete .tpk with LINK records across the cuts, and the manifest that lists them. */
#ifndef TPK_PARTS_H
#define TPK_PARTS_H

#include <stdint.h>

#include "base/diag.h"
#include "convert.h"
#include "mesh/mesh.h"
#include "tetpack.h"

/* Write o->output (the manifest) and its o->parts part files beside it ("<stem>-<p>.tpk") from the
 * whole converted mesh (stored frame, Hilbert order, positive tets and their neighbors; `whole` gives the
 * origin every part keeps). The parts are balanced by tets; a part keeps the vertex order of the whole.
 * rep gets the bytes of all files and the outer shell's face count. The manifest is written last. */
int tpk_write_part_set(const tpk_convert_options *o, const tpk_tetmesh *mesh, const int32_t *neighbors,
                       const tpk_header_fields *whole, tpk_convert_report *rep, const char *source_format,
                       tpk_diag *diag);

/* The manifest alone (atomically): no mesh, `origin`, the PART table of `count` records, META. Also used
 * by tetpack-mpi's rank 0. */
int tpk_write_manifest(const char *path, const double origin[3], const tpk_part_record *records, int count,
                       const char *meta_json, tpk_diag *diag);

/* "<dir>/<stem>-<p>.tpk" (malloc'd, *out) for the manifest "<dir>/<stem>.tpkset"; record->file gets
 * "<stem>-<p>.tpk", p zero-padded to the width of count - 1. */
int tpk_part_path(const char *manifest, int p, int count, tpk_part_record *record, char **out, tpk_diag *diag);
/* The header_checksum of the .tpk at path (the manifest binds each part by it). */
int tpk_read_header_checksum(const char *path, uint64_t *out, tpk_diag *diag);

#endif
