/* Shared by the exporters: an output file (base/output_file.h) put in place whole on success (never a
 * half-written file at `path`, nothing left behind a killed process), little-endian array writers,
 * and chunk loading from an open .tpk with size checks. All defined in export_io.c, which calls no
 * other exporter file. (The shell loader the shell writers share, tpk_shell_load/tpk_shell_free, is
 * declared in exporters.h and defined in export_shell_load.c.) */
#ifndef TPK_EXPORT_IO_H
#define TPK_EXPORT_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "base/diag.h"
#include "base/output_file.h"
#include "tetpack.h"

typedef struct tpk_out {
    tpk_output file; /* base/output_file.h: unnamed until commit */
    FILE *f;
    const char *path;
    int failed;     /* a write failed; commit reports it */
} tpk_out;

int tpk_out_open(tpk_out *o, const char *path, tpk_diag *diag);
void tpk_out_write(tpk_out *o, const void *data, size_t size);
void tpk_out_printf(tpk_out *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Little-endian writers (values converted through a small buffer). */
void tpk_out_u64le(tpk_out *o, uint64_t v);
void tpk_out_i32le(tpk_out *o, const int32_t *v, size_t count);
void tpk_out_f32le(tpk_out *o, const float *v, size_t count);
void tpk_out_f64le(tpk_out *o, const double *v, size_t count);
void tpk_out_i64le(tpk_out *o, const int64_t *v, size_t count);
/* Flush, sync and put in place; on any failure nothing is left but what was at the path. 0 or -1. */
int tpk_out_commit(tpk_out *o, tpk_diag *diag);
void tpk_out_abort(tpk_out *o);

/* The layout the tets are exported from: Tet32, else Tet20, else Tet16 (the first the file has), or -1 with
 * "path: cannot export: the file has no tet layout". */
int tpk_export_pick_layout(tpk_file *file, const char *path, tpk_layout *out, tpk_diag *diag);

/* Load chunk (tag, index, step) whose elements must be elem_size bytes and exactly expected_count of
 * them. *data views the mapped file (uncompressed) or *owned (decoded; free it). Returns 1 when
 * loaded, 0 when the file has no such chunk, -1 on error (message names `path` and the chunk). */
int tpk_export_load_chunk(tpk_file *file, uint32_t tag, uint32_t index, uint32_t step, uint32_t elem_size,
                          uint64_t expected_count, const void **data, void **owned, const char *path,
                          tpk_diag *diag);

#endif
