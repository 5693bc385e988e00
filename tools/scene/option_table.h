/* The options of a render, one row each: the table that the command line (cli/render_args.c: its option
 * parser, its messages, render's and view's --help), the scene reader and writer (scene_parse.c,
 * scene_write.c: every key, and the ranges and choices of the values, the command line's too) and the
 * scene spec's key table (spec/scene-json.md §2, compared row by row by tests/test_option_table.c) all
 * come from. It lives here, the lowest folder the command line and the
 * scene files share; which values a renderer accepts is render/'s tpk_render_check_options. */
#ifndef TPK_SCENE_OPTION_TABLE_H
#define TPK_SCENE_OPTION_TABLE_H

#include <stddef.h>

/* One id per row, in the table's order (the scene spec's order, then the options of the command line
 * alone). */
typedef enum tpk_option_id {
    TPK_OPT_VERSION,
    TPK_OPT_CAMERA,
    TPK_OPT_CAMERA_EYE,
    TPK_OPT_CAMERA_AT,
    TPK_OPT_CAMERA_UP,
    TPK_OPT_CAMERA_FOVY,
    TPK_OPT_TF,
    TPK_OPT_TF_PRESET,
    TPK_OPT_TF_FILE,
    TPK_OPT_TF_POINTS,
    TPK_OPT_FIELD,
    TPK_OPT_STEP,
    TPK_OPT_STEPS,
    TPK_OPT_RANGE,
    TPK_OPT_UNIT_DISTANCE,
    TPK_OPT_CLIP_BOX,
    TPK_OPT_PROBE,
    TPK_OPT_ISO,
    TPK_OPT_ISO_OPACITY,
    TPK_OPT_EFFECTS,
    TPK_OPT_SHADING,
    TPK_OPT_SHADOWS,
    TPK_OPT_LIGHT,
    TPK_OPT_AO_RAYS,
    TPK_OPT_AO_RADIUS,
    TPK_OPT_OCCLUSION,
    TPK_OPT_LAYOUT,
    TPK_OPT_SIZE,
    TPK_OPT_BACKEND,
    TPK_OPT_INTEGRATION,
    TPK_OPT_OUTPUT,
    TPK_OPT_THREADS,
    TPK_OPT_SCENE,
    TPK_OPT_SAVE_SCENE,
    TPK_OPT_JSON,
    TPK_OPT_LEGEND,
    TPK_OPT_SAVE_TPK,
    TPK_OPT_VERBOSE,
    TPK_OPT_ISO_RASTER,
    TPK_OPT_LEVEL,
    TPK_OPT_MAX_MS,
    TPK_OPT_MAX_PIXEL_STEP,
    TPK_OPT_COUNT
} tpk_option_id;

/* The rule a value obeys, the same for the command line and the scene reader: both check it through
 * tpk_option_int_ok, tpk_option_number_ok and tpk_option_choice, so the two accept the same values. */
typedef enum tpk_option_kind {
    TPK_OPT_KIND_OTHER = 0, /* checked by its own parser (lists, files, names) */
    TPK_OPT_KIND_INT,       /* an integer in [lo, hi] */
    TPK_OPT_KIND_NUMBER,    /* a finite number in lo..hi, each end open or closed */
    TPK_OPT_KIND_CHOICE     /* one of `choices` */
} tpk_option_kind;

typedef struct tpk_option_row {
    tpk_option_id id;
    /* Command line (flag NULL: none). */
    const char *flag;      /* "--iso-opacity" */
    const char *alias;     /* a short form ("-o"), or NULL */
    const char *metavar;   /* the value in --help ("A"); NULL: a switch, no value */
    const char *expects;   /* the value's type and range in messages: "--iso-opacity expects EXPECTS, found 'x'" */
    const char *help;      /* --help text, lines split by '\n' */
    int help_rank;         /* --help order, 1 first */
    int effect;            /* a render effect (render.h): --help points at their definitions after the last */
    int render_only;       /* render only: view refuses it */
    /* Scene file (scene_key NULL: none); the other four are the spec table's columns. */
    const char *scene_key; /* "effects.ao_rays": a key of the object in key "effects" */
    const char *scene_type, *meaning, *scene_default, *constraint;
    /* The value's rule (both front ends). */
    tpk_option_kind kind;
    double lo, hi;          /* INT and NUMBER */
    int lo_open, hi_open;   /* NUMBER: lo < v (not <=), v < hi */
    const char *choices;    /* CHOICE: space-separated, in the order of the values they stand for */
} tpk_option_row;

/* The table: TPK_OPT_COUNT rows, row i has id i. */
extern const tpk_option_row tpk_option_table[TPK_OPT_COUNT];

/* v is an integer within the row's [lo, hi] (TPK_OPT_KIND_INT). */
int tpk_option_int_ok(tpk_option_id id, double v);
/* v is a finite number within the row's range (TPK_OPT_KIND_NUMBER). */
int tpk_option_number_ok(tpk_option_id id, double v);
/* The index of `text` among the row's choices (TPK_OPT_KIND_CHOICE), or -1. */
int tpk_option_choice(tpk_option_id id, const char *text);
/* The row's choice `index` into buf (cap bytes); "" past the last. */
const char *tpk_option_choice_name(tpk_option_id id, int index, char *buf, size_t cap);

/* The leaf of a row's scene key ("ao_rays" for "effects.ao_rays"); NULL when it has none. */
const char *tpk_option_scene_leaf(tpk_option_id id);

/* The leaves of the scene keys directly in object `parent` ("" the top level, "effects", "camera",
 * "tf"), in table order, into names (at most cap); returns how many. */
int tpk_option_scene_keys(const char *parent, const char **names, int cap);

#endif
