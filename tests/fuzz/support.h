/* What the fuzz targets that read files by path share: a private scratch folder per process (on tmpfs
 * where there is one), inputs written into it, and inputs that carry several files (an OpenFOAM case, a
 * part set, a .pvd with its pieces) split into them. Not a target itself (no fuzz_ prefix). */
#ifndef TPK_FUZZ_SUPPORT_H
#define TPK_FUZZ_SUPPORT_H

#include <stddef.h>
#include <stdint.h>

/* Between the files of one input: a line "@@ NAME" starts the file NAME (relative, [A-Za-z0-9._-/] only,
 * no "..", at most 4 levels); text before the first such line goes to `first_name`. */
#define TPK_FUZZ_FILE_MARK "@@ "

/* This process's scratch folder (made on first use, removed at exit), e.g. /dev/shm/tpk-fuzz-PID; with
 * TPK_FUZZ_KEEP=DIR set, DIR, kept (./dev fuzz replays a finding so, to give its files to tetpack). */
const char *tpk_fuzz_scratch(void);
/* Empty the scratch folder's work/ subfolder, then make its subfolder `sub` (NULL: none); returns the
 * path of the (empty) folder, valid until the next call. Files elsewhere in the scratch folder stay. */
const char *tpk_fuzz_fresh_dir(const char *sub);
/* Write `size` bytes to `path`, making its parent folders; 0 or -1. */
int tpk_fuzz_write(const char *path, const void *data, size_t size);
/* Split the input into files under `dir` (see TPK_FUZZ_FILE_MARK); returns how many were written.
 * Names that are not allowed are skipped with their text. */
int tpk_fuzz_split_files(const char *dir, const char *first_name, const uint8_t *data, size_t size);
/* A message sink that drops warnings (tpk_diag.warn). */
void tpk_fuzz_ignore(void *user, const char *text);

#endif
