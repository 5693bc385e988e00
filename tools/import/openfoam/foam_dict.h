/* OpenFOAM dictionaries as tutorials and users write them: entries and sub-dictionaries, `$var`, `${var}`
 * and scoped macros (`$..var`, `$:a.b`, `$a.b`), #include, #includeEtc, #includeIfPresent, #inputMode and
 * #remove; #calc and #codeStream are refused by name, since they compile C++. Macros are expanded as
 * OpenFOAM does while reading (an entry sees the definitions above it), but only when an entry is
 * asked for, so a boundary condition that tetpack never reads cannot stop a field from converting.
 * A list such as `List<scalar> N (...)` or `N{v}` is one token naming its bytes: it is read in place by
 * tpk_foam_scalars, never tokenized number by number. */
#ifndef TPK_FOAM_DICT_H
#define TPK_FOAM_DICT_H

#include <stddef.h>

#include "foam_file.h"

enum {
    TPK_FOAM_WORD,      /* a word or a number */
    TPK_FOAM_STRING,    /* "..." with its quotes */
    TPK_FOAM_PUNCT,     /* one of ( ) [ ] { } ; */
    TPK_FOAM_VARIABLE,  /* $name, ${name}, $..name, $:a.b */
    TPK_FOAM_DIRECTIVE, /* #name */
    TPK_FOAM_VERBATIM,  /* #{ ... #} */
    TPK_FOAM_LIST       /* a sized list, N(...) or N{v}, read in place */
};

typedef struct tpk_foam_token {
    int kind;
    int file;        /* index into the dictionary's files */
    size_t pos, len; /* its bytes in that file */
} tpk_foam_token;

typedef struct tpk_foam_dict tpk_foam_dict;

/* Parse the body of `top` (an opened file, pos after its FoamFile header) as a dictionary. `case_dir`
 * resolves $FOAM_CASE and <case>. The dictionary takes `top` over (closes it). NULL with diag's message
 * set on a syntax error, an include cycle or a refused directive. */
tpk_foam_dict *tpk_foam_dict_parse(tpk_foam_file *top, const char *case_dir, tpk_diag *diag);
void tpk_foam_dict_free(tpk_foam_dict *d);

/* The top-level entry `key`'s value with every macro expanded: *tokens (malloc'ed) and *count. -1 with a
 * message naming the file and line when the entry is missing, is a dictionary, or a macro it uses cannot
 * be resolved. */
int tpk_foam_dict_value(tpk_foam_dict *d, const char *key, tpk_foam_token **tokens, int *count);

/* A token's file (with the path and the binary flag its bytes were read with), for reading it in place:
 * set file->pos to token->pos and call the list readers. */
tpk_foam_file *tpk_foam_dict_file(tpk_foam_dict *d, const tpk_foam_token *t);

/* Are the token's bytes exactly s? */
int tpk_foam_token_is(tpk_foam_dict *d, const tpk_foam_token *t, const char *s);

/* Fail with "PATH:LINE: " at a token. Returns -1. */
int tpk_foam_dict_fail(tpk_foam_dict *d, const tpk_foam_token *t, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
