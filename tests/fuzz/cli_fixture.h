/* A small .tpk for the fuzz targets that drive a `tetpack` subcommand on a fuzzed scene (render,
 * extract): eight hexahedra (a 3x3x3 point grid) with two point fields and a cell field, converted once
 * per process with every layout. Not a target itself (no fuzz_ prefix). */
#ifndef TPK_FUZZ_CLI_FIXTURE_H
#define TPK_FUZZ_CLI_FIXTURE_H

#include <stddef.h>

/* The fixture's path (made on first use in the scratch folder, support.h); abort()s when it cannot be
 * made. */
const char *tpk_fuzz_fixture_tpk(void);
/* Write a fuzz input as the scene file `name` of a fresh work folder; returns its path, or NULL for an
 * input that could name a file to read (a "tf" "file" key, spelt directly or with \u escapes: /dev/zero
 * would never end, and reading files is not these targets' business). */
const char *tpk_fuzz_scene_file(const char *name, const char *data, size_t size);

#endif
