/* Shared pieces of the tetpack subcommands. */
#ifndef TPK_CLI_H
#define TPK_CLI_H

#include <stdio.h>

#define TPK_EXIT_OK 0
#define TPK_EXIT_PROBLEMS 1
#define TPK_EXIT_USAGE 2 /* unusable input or usage */

struct tpk_file;

int tpk_cmd_convert(int argc, char **argv);
int tpk_cmd_info(int argc, char **argv);
int tpk_cmd_render(int argc, char **argv);
int tpk_cmd_view(int argc, char **argv);
int tpk_cmd_extract(int argc, char **argv);
int tpk_cmd_export(int argc, char **argv);
int tpk_cmd_iso(int argc, char **argv);
int tpk_cmd_check(int argc, char **argv);
int tpk_cmd_formats(int argc, char **argv);
/* `tetpack info` on a part set's manifest (cmd_info_set.c); json: --json. Returns the exit code. */
int tpk_cli_info_set(const char *path, int json);

/* The input formats, one line each (name, extensions, title), for the --help of convert and check. */
void tpk_cli_print_formats(FILE *out);

/* Print "tetpack <cmd>: error: ..." to stderr and return TPK_EXIT_USAGE. */
int tpk_cli_fail(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Parse exactly `count` comma-separated doubles; 0 on success. */
int tpk_cli_parse_doubles(const char *text, double *out, int count);
/* Parse a non-negative int in [lo, hi]; 0 on success. */
int tpk_cli_parse_int(const char *text, int lo, int hi, int *out);
/* Value of option argv[*i] ("--opt value" or "--opt=value"); advances *i. NULL if missing. */
const char *tpk_cli_value(int argc, char **argv, int *i, const char *name);
/* "tetpack" and the arguments joined by spaces, leaving out the argument `skip` (pointer identity; the
 * output path), --threads and --progress/--no-progress, so the recorded command does not depend on where
 * the file goes, on how many threads made it or on whether a terminal watched. Static buffer. */
const char *tpk_cli_joined(int argc, char **argv, const char *skip);

/* Print "tetpack <cmd>: error: PATH: why" (just "why" when it already names PATH) and return
 * TPK_EXIT_USAGE: every refusal of an input names the file. */
int tpk_cli_fail_file(const char *cmd, const char *path, const char *why);
struct tpk_output_input;
/* Check output `path`, given as `arg`, against the files the command reads (`inputs`) before any work
 * (tpk_output_check): 0, or print "tetpack <cmd>: error: ..." and return TPK_EXIT_USAGE. */
int tpk_cli_check_output(const char *cmd, const char *arg, const char *path, const struct tpk_output_input *inputs,
                         size_t count);
/* The same for a conversion's output (convert's OUTPUT, render's --save-tpk: `arg`) against every file
 * INPUT consists of (TetGen siblings, .pvd pieces). */
int tpk_cli_check_convert_output(const char *cmd, const char *arg, const char *input, const char *format,
                                 const char *output);

/* Open a .tpk; on failure print "tetpack <cmd>: error: PATH: why" and return TPK_EXIT_USAGE. */
int tpk_cli_open(const char *cmd, const char *path, struct tpk_file **out);

#endif
