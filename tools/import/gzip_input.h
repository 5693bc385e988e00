/* Gzip-compressed inputs (FILE.msh.gz, FILE.vtu.gz, ...): the whole file inflated into memory, for a
 * format's memory reader (the registry, registry.c, picks the format from the name without ".gz"). */
#ifndef TPK_GZIP_INPUT_H
#define TPK_GZIP_INPUT_H

#include <stddef.h>

#include "base/diag.h"

/* The most bytes an input inflates to by default: half the memory available now, at least 64 MiB. The
 * gzip trailer's size field is the size modulo 2^32, so it only sizes the first buffer. */
size_t tpk_gzip_default_limit(void);

/* Inflate every gzip member of data[0..size) into a malloc'ed buffer (*out, *out_size; free it), more
 * than `limit` bytes (0: tpk_gzip_default_limit()) refused. Bytes after the last member that do not start
 * another are ignored with a warning, as gzip does. 0, or -1 with a message naming `name` and the byte
 * offset in the compressed data. Safe on untrusted input. */
int tpk_gzip_inflate(const char *name, const char *data, size_t size, size_t limit, char **out, size_t *out_size,
                     tpk_diag *diag);

/* The same for a file. */
int tpk_gzip_inflate_file(const char *path, size_t limit, char **out, size_t *out_size, tpk_diag *diag);

/* Up to `cap` first inflated bytes of the file, for sniffing its format; the count read, 0 when none. */
size_t tpk_gzip_head(const char *path, char *head, size_t cap);

#endif
