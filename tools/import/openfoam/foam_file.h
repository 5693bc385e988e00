/* One OpenFOAM file (FoamFile header, then the body) read into memory, plain or gzipped, and the lists
 * a polyMesh and its fields hold, ASCII or `format binary` (arch "LSB;label=32;scalar=64" only). */
#ifndef TPK_FOAM_FILE_H
#define TPK_FOAM_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "base/diag.h"

typedef struct tpk_foam_file {
    char path[4096];     /* the file read (with .gz when it was compressed), for messages */
    char *data;          /* size bytes plus a NUL, so strtod/strtoll stop inside the buffer */
    size_t size;
    size_t pos;          /* parse position in data */
    int binary;          /* format binary */
    char class_name[128]; /* the header's class, e.g. faceCompactList, volScalarField */
    tpk_diag *diag;
} tpk_foam_file;

/* Read dir/name (or dir/name.gz when that exists instead) and parse its FoamFile header; on success pos
 * is just after the header. 0, 1 when neither file exists (nothing reported), -1 with a message. */
int tpk_foam_open(tpk_foam_file *f, const char *dir, const char *name, tpk_diag *diag);
/* Read a file that #include names: `path` (or path.gz), its FoamFile header parsed when it has one (an
 * included file often has none). 0, 1 when neither file exists, -1 with a message. */
int tpk_foam_read_any(tpk_foam_file *f, const char *path, tpk_diag *diag);
void tpk_foam_close(tpk_foam_file *f);

/* The line (from 1) that byte `pos` of the file lies on. */
int64_t tpk_foam_line(const tpk_foam_file *f, size_t pos);
/* Fail with "PATH:LINE: " (ASCII) or "PATH: byte N: " (binary) at the current position. Returns -1. */
int tpk_foam_fail(tpk_foam_file *f, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Skip blanks and C/C++ comments. */
void tpk_foam_skip_space(tpk_foam_file *f);
/* The next word (letters, digits, punctuation except ( ) ; { }) into buf; its length, 0 at end or before
 * a delimiter. */
size_t tpk_foam_word(tpk_foam_file *f, char *buf, size_t cap);

/* A list of `width` numbers per item: "N ( ... )" in ASCII (items of width > 1 in parentheses), or N then
 * '(' then N*width raw little-endian labels (int32) or scalars (float64) in binary. Sets *count and a
 * malloc'ed array (int32 for labels, double for scalars). `what` names the list in messages. */
int tpk_foam_labels(tpk_foam_file *f, int64_t *count, int32_t **out, const char *what);
int tpk_foam_scalars(tpk_foam_file *f, int width, int64_t *count, double **out, const char *what);
/* An ASCII faceList: N ( k(a b c ...) ... ) into CSR form: starts (count + 1) and ids. */
int tpk_foam_face_list(tpk_foam_file *f, int64_t *count, int64_t **starts, int32_t **ids);

#endif
