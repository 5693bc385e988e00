/* Transfer functions for volume rendering: piecewise-linear color and opacity over a normalized scalar,
 * from built-in presets or a small text file. */
#ifndef TPK_TRANSFER_FUNCTION_H
#define TPK_TRANSFER_FUNCTION_H

#include "base/diag.h"

#define TPK_TF_MAX_POINTS 256

/* One control point. s: normalized scalar in [0,1]; r,g,b in [0,1]; a: opacity per unit distance
 * in [0,1] (the renderer's unit_distance): the extinction coefficient is a / unit_distance, so a slab
 * one unit thick of constant a has opacity 1 - exp(-a) (about a for small a). */
typedef struct tpk_tf_point {
    double s, r, g, b, a;
} tpk_tf_point;

/* Control points with strictly increasing s (at least 2). Below the first and above the last point the
 * end values hold. Plain value type: copy freely, nothing to free. */
typedef struct tpk_transfer_function {
    int count;
    tpk_tf_point points[TPK_TF_MAX_POINTS];
    char name[64]; /* preset name or file name, for messages */
} tpk_transfer_function;

/* Load a preset by name (see tpk_tf_preset_names) or, if `preset_or_path` is not a preset name, a
 * text file: one control point per line as five numbers `s r g b a`, `#` starts a comment, blank lines
 * are ignored, s strictly increasing in [0,1], at least 2 and at most TPK_TF_MAX_POINTS points.
 * Returns 0, or -1 with a message naming the file, line, what was expected and what was found. */
int tpk_tf_load(const char *preset_or_path, tpk_transfer_function *out, tpk_diag *diag);

/* Parse the text format from memory; `name` is used in messages. */
int tpk_tf_parse(const char *name, const char *text, tpk_transfer_function *out, tpk_diag *diag);

/* The preset names, comma separated, for --help: "viridis, cool-warm, inferno, grayscale". */
const char *tpk_tf_preset_names(void);

/* The i-th preset's name (i from 0), or NULL past the last: the one list that names presets. */
const char *tpk_tf_preset(int i);

/* 1 when `name` is exactly a preset's name (the empty string is none), else 0. */
int tpk_tf_is_preset(const char *name);

/* Color and opacity at normalized scalar s (clamped to the end points). rgba[3] is the `a` column. */
void tpk_tf_eval(const tpk_transfer_function *tf, double s, double rgba[4]);

#endif
