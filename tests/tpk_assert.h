/* The writer's promise, asserted the same way by every test that converts a file: convert, open the
 * result with libtetpack, run the format's MUSTs (`tetpack check` 600..613) on it, and fail when any
 * fires. Use tpk_convert_checked wherever a test would call tpk_convert. */
#ifndef TPK_TEST_ASSERT_H
#define TPK_TEST_ASSERT_H

#include <stddef.h>

#include "convert/convert.h"

/* The 6xx checks on the .tpk at `path`: 0 when the file opens and none fires; otherwise nonzero with the
 * first finding (id, name, count, first example) or why the checks could not run in msg. */
int tpk_assert_file_valid(const char *path, char *msg, size_t cap);

/* tpk_convert, then tpk_assert_file_valid on the written file. Returns tpk_convert's result when it fails
 * (diag as it left it), 1 when the written file breaks a MUST (diag->message says which, and that the
 * converter wrote it), 0 when all is well. */
int tpk_convert_checked(const tpk_convert_options *options, tpk_convert_report *report, tpk_diag *diag);

#endif
