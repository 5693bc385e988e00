/* The input of `tetpack render` and `tetpack view`: a .tpk (or a part set's manifest) opened as it is, or
 * any mesh that `tetpack convert` reads, converted first with convert's defaults. Owner: render_input.c. */
#ifndef TPK_CLI_RENDER_INPUT_H
#define TPK_CLI_RENDER_INPUT_H

#include <stddef.h>

#include "tetpack.h"

typedef struct render_input {
    tpk_file *file;
    int converted;       /* 1: the input was a mesh, converted here */
    const char *tpk_path; /* the .tpk on disk (the input, or --save-tpk); NULL for an in-memory conversion */
    void *bytes;         /* the in-memory conversion's mapping (owned), else NULL */
    size_t size;
    double convert_seconds;
    long long tets;
} render_input;

/* Open `path`: a .tpk as it is; any other mesh `tetpack convert` reads (a file, an OpenFOAM case, a TetGen
 * stem) converted with convert's defaults (Tet16, every scalar point field, Hilbert order) into memory
 * (an anonymous memfd: nothing is written to disk) or, with save_tpk, into that file (atomically; it is
 * kept). A file that is neither gets a message saying what render takes and what to do. `threads` as
 * convert's (<= 0: all cores). 0, or a message naming `cmd` and TPK_EXIT_USAGE. */
int render_input_open(const char *cmd, const char *path, const char *save_tpk, int threads, render_input *in);

/* Is `path` a .tpk (it starts with the format's magic)? Directories and unreadable paths are not. */
int render_input_is_tpk(const char *path);

/* Close the file and free the conversion's memory; safe on a zeroed or half-opened input. */
void render_input_close(render_input *in);

#endif
