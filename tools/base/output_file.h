/* An output file of the tetpack command (a .tpk, VTU, shell, PNG): checked before any work is done,
 * written where nothing can see it, and put in place whole at the end. Every writer of the tools goes
 * through here, so the rules live once:
 *   - the path must be a file path (not empty, not a directory) in an existing, writable directory;
 *   - an existing file there must be a regular file (a device, a FIFO, a symbolic link is refused);
 *   - it must not be any file the command reads (same device and inode; siblings and pieces too);
 *   - the data goes to an unnamed temporary file in the target directory (O_TMPFILE), linked into
 *     place only when complete, so a killed process leaves nothing behind; where the filesystem cannot
 *     make one, a named temporary "<path>.tmp.XXXXXX" that SIGINT, SIGTERM and SIGHUP remove.
 * Not thread safe: one thread opens and commits outputs (the signal table is global, with room for 4
 * named temporary files at once). Test hooks, read from the environment (output_file.c):
 * TPK_TEST_OUTPUT_HOLD=FLAG waits before putting a complete output in place, TPK_TEST_OUTPUT_NAMED=1
 * takes the named fallback. */
#ifndef TPK_OUTPUT_FILE_H
#define TPK_OUTPUT_FILE_H

#include <stdio.h>

#include "base/diag.h"

/* A file the command reads, for the same-file check and its message. */
typedef struct tpk_output_input {
    const char *arg;   /* how the command line names the input: "INPUT", "FILE.tpk", "--tf" */
    const char *given; /* the path as given */
    const char *file;  /* the file read: `given` itself, or one it brings along (TetGen's sibling, a .pvd
                          piece); NULL means `given` */
} tpk_output_input;

/* Check output `path`, named `arg` in messages ("OUTPUT", "--vtu", "-o"), before any work: 0, or -1
 * with a message in diag that names the argument and says what to do, e.g.
 * "OUTPUT 'x.vtk' is the input file (same file as INPUT 'x.vtk'); choose another output path".
 * `inputs` may be NULL when count is 0. */
int tpk_output_check(const char *arg, const char *path, const tpk_output_input *inputs, size_t count,
                     tpk_diag *diag);

typedef struct tpk_output {
    char *path;   /* the target (a copy) */
    char *temp;   /* a named temporary file, while one exists; NULL when the data has no name yet */
    int fd;       /* the data; -1 when closed */
    FILE *stream; /* tpk_output_stream's stdio view of fd; NULL until asked for */
} tpk_output;

/* Create the temporary file for `path` (checked with tpk_output_check first: this only says why the
 * directory refuses a file). 0, or -1 with a message naming `path`. */
int tpk_output_open(tpk_output *out, const char *path, tpk_diag *diag);
/* A buffered stdio stream over out->fd, owned by `out` (commit flushes and closes it); NULL with a
 * message when out of memory. */
FILE *tpk_output_stream(tpk_output *out, tpk_diag *diag);
/* Flush to disk and put the file at its path (replacing a regular file there atomically). Closes
 * everything, in every case; on failure nothing is left but what was at the path before. 0 or -1. */
int tpk_output_commit(tpk_output *out, tpk_diag *diag);
/* Drop the data (nothing appears at the path) and close everything. Safe again after a failed open,
 * a commit or an abort. */
void tpk_output_abort(tpk_output *out);

#endif
