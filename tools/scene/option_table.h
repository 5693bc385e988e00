/* The options of a render, one row each (declared in render/render_options.def): the table that the
 * command line (cli/render_args.c: its option parser, its messages, render's and view's --help), the scene
 * reader and writer (scene_parse.c, scene_write.c: every key, and the ranges and choices of the values,
 * the command line's too) and the scene spec's key table (spec/scene-json.md §2, compared row by row by
 * tests/test_option_table.c) all come from. It lives here, the lowest folder the command line and the
 * scene files share; which values a renderer accepts is render/'s tpk_render_check_options. */
#ifndef TPK_SCENE_OPTION_TABLE_H
#define TPK_SCENE_OPTION_TABLE_H

#include <stddef.h>

/* One id per row, in the table's order (the scene spec's order, then the options of the command line
 * alone). */
typedef enum tpk_option_id {
#define TPK_OPTION(ID, ...) TPK_OPT_##ID,
#include "render/render_options.def"
#undef TPK_OPTION
    TPK_OPT_COUNT
} tpk_option_id;

/* The rule a value obeys, the same for the command line and the scene reader: both check it through
 * tpk_option_int_ok, tpk_option_number_ok and tpk_option_choice, so the two accept the same values. */
typedef enum tpk_option_kind {
    TPK_OPT_KIND_OTHER = 0, /* checked by its own parser (lists, files, names) */
    TPK_OPT_KIND_INT,       /* an integer in [lo, hi] */
    TPK_OPT_KIND_NUMBER,    /* a finite number in lo..hi, each end open or closed */
    TPK_OPT_KIND_CHOICE,    /* one of `choices` */
    TPK_OPT_KIND_BOOL       /* a switch on the command line, true or false in a scene */
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
    const char *scene_expects; /* a NUMBER's rule in the scene reader's messages ("a positive length") */
    /* The value's rule (both front ends). */
    tpk_option_kind kind;
    double lo, hi;          /* INT and NUMBER */
    int lo_open, hi_open;   /* NUMBER: lo < v (not <=), v < hi */
    const char *choices;    /* CHOICE: space-separated, in the order of the values they stand for */
    /* Where the value goes: a field of tpk_render_options, render_args (cli/), tpk_scene. */
    int in_render, in_args, in_scene;
    int save_always;        /* a saved scene always has it (else when > 0 where it matters) */
    size_t scene_at;        /* in_scene: its offset in tpk_scene */
    double init;            /* render_args' default */
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
