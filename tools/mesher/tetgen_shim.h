/* TetGen 1.5 (libtet, AGPL-3, optional: TETPACK_WITH_TETGEN) behind a C interface. The one C++ unit
 * that includes tetgen.h; it catches TetGen's thrown error codes and keeps its printing off stdout. */
#ifndef TPK_TETGEN_SHIM_H
#define TPK_TETGEN_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tpk_tetgen_input {
    int32_t point_count;
    const double *points;        /* 3 * point_count */
    int32_t face_count;          /* 0: a point cloud (Delaunay, no 'p' switch) */
    const int64_t *face_offsets; /* face_count + 1 */
    const int32_t *face_conn;    /* polygon corners, 0-based */
} tpk_tetgen_input;

/* A field added here must also cross from TetGen's child process to its parent: tetgen_child.c. */
typedef struct tpk_tetgen_output {
    int32_t point_count;
    double *points;              /* 3 * point_count; the input points first, in input order */
    int64_t tet_count;
    int32_t *tets;               /* 4 * tet_count, 0-based; det[b-a, c-a, d-a] > 0 */
    int32_t triangle_count;
    int32_t *triangles;          /* with 'd': 3 point ids per triangle of an intersecting face */
} tpk_tetgen_output;

/* TetGen's error codes (terminatetetgen in tetgen.h), and ours for anything else thrown. */
enum {
    TPK_TETGEN_OUT_OF_MEMORY = 1,
    TPK_TETGEN_INTERNAL_ERROR = 2,
    TPK_TETGEN_SELF_INTERSECTION = 3,
    TPK_TETGEN_SMALL_FEATURE = 4,
    TPK_TETGEN_CLOSE_FACETS = 5,
    TPK_TETGEN_INPUT_ERROR = 10,
    TPK_TETGEN_OTHER_ERROR = 99,
    /* tpk_tetgen_run_guarded (tetgen_guard.h): TetGen's process died of a signal (an assert, a bad
     * access), ran past its time limit, or could not be started. */
    TPK_TETGEN_CRASHED = 100,
    TPK_TETGEN_TIMED_OUT = 101,
    TPK_TETGEN_NOT_STARTED = 102
};

/* Run TetGen with `switches` (the caller adds Q and checks them: this passes them through). Returns 0
 * with *out filled (free with tpk_tetgen_output_free), or a TPK_TETGEN_* code with `message` (cap
 * bytes) saying what went wrong, including what TetGen printed. Not thread-safe: TetGen's printing is
 * caught by redirecting file descriptor 1 for the duration of the call. */
int tpk_tetgen_run(const char *switches, const tpk_tetgen_input *in, tpk_tetgen_output *out, char *message,
                   size_t cap);
void tpk_tetgen_output_free(tpk_tetgen_output *out);

/* tpk_tetgen_run with TetGen's printing appended to print_fd (a readable, writable file) instead of a
 * temporary file, so that a parent process can still read it when TetGen crashes (tetgen_child.c);
 * print_fd < 0: as tpk_tetgen_run. */
int tpk_tetgen_run_printing_to(int print_fd, const char *switches, const tpk_tetgen_input *in,
                               tpk_tetgen_output *out, char *message, size_t cap);
/* The last few non-empty lines of what TetGen printed (size bytes), joined by "; ", into buf. */
void tpk_tetgen_last_words(const char *printed, size_t size, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif

#endif
