/* Shared pieces of the thin command-line program: the command table entry,
 * terminal logging and progress, and exit codes. No algorithm lives here. */
#ifndef KARST_CLI_H
#define KARST_CLI_H

#include <stdio.h>

#include "karst.h"

enum { CLI_OK = 0, CLI_ERROR = 1, CLI_USAGE = 2 };

typedef struct cli_command {
  const char *name;
  int (*run)(int argc, char **argv); /* argv[0] is the command name */
  const char *summary;
  const char *usage; /* full help text printed by `karst help NAME` */
} cli_command_t;

/* Set up a context for a command: logger on stderr, progress on a terminal,
 * Ctrl-C sets ctx->interrupt. `quiet` silences progress and info. */
void cli_ctx_init(karst_ctx_t *ctx, int quiet, int verbose);
/* Progress of a count of runs (the members of an ensemble, of a calibration's generation):
 * on a terminal a redrawn bar "STAGE [####....] done/total  rate/s  time left" that starts
 * afresh whenever the stage changes; elsewhere, when `lines` is set, a plain line
 * "karst COMMAND: done of total NOUN, rate per second, time left" at most every 10 s or 10 %
 * of the work, and at the end; otherwise nothing. */
typedef struct cli_count_progress {
  const char *command, *noun;
  int tty, lines;
  double t0, last, last_fraction;
  char stage[48];
} cli_count_progress_t;
void cli_count_progress_init(cli_count_progress_t *ps, const char *command, const char *noun,
                             int lines);
/* A karst_progress_fn: user is a cli_count_progress_t. */
void cli_count_progress(void *user, const char *stage, double done, double total);
/* Print "karst CMD: message" from ctx (or the error code) to stderr; returns CLI_ERROR. */
int cli_fail(const char *cmd, const karst_ctx_t *ctx, karst_error_t err);
/* The exit status of a resumable run (karst ensemble, karst calibrate): KARST_EINTERRUPTED
 * prints, on MPI rank 0 only, "karst CMD: interrupted; " and the formatted note (what is kept,
 * how to continue); any other error is cli_fail's. Returns CLI_OK or CLI_ERROR. */
int cli_resumable_status(const char *cmd, const karst_ctx_t *ctx, karst_error_t err, int rank,
                         const char *fmt, ...) __attribute__((format(printf, 5, 6)));
/* A writer failed on the temporary file of @p output (its message names the temporary, which
 * is gone): reword ctx's message as "writing OUTPUT: message; no output was kept". */
void cli_note_failed_output(karst_ctx_t *ctx, karst_error_t err, const char *output);
/* Check that @p path can be written and add it to @p outs (written to *tmp,
 * renamed on commit; the temporary keeps the extension). */
karst_error_t cli_add_output(karst_ctx_t *ctx, karst_fileset_t *outs, const char *path,
                             const char **tmp);
/* When @p out names the same file as one of the @p n inputs (by device and inode, so symlinks
 * and ./paths count), print "karst CMD: the output OUT is the input IN; it would be replaced" and
 * return CLI_USAGE, before any work; CLI_OK otherwise (also when OUT does not exist yet). */
int cli_refuse_output_over_input(const char *cmd, const char *out, const char *const *inputs,
                                 int n);
/* Print a usage error and the command's usage line; returns CLI_USAGE. */
int cli_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Look up a command by name (NULL if none). */
const cli_command_t *cli_find_command(const char *name);
/* The command table, `help` first, in the order of the pipeline; *n receives its size. */
const cli_command_t *const *cli_commands(size_t *n);
/* What karst is, the paragraph of `karst --help` and of the man page's DESCRIPTION. */
extern const char cli_description[];
/* The bash completion script and the karst(1) man page, generated from the command table
 * (src/cli/cli_doc.c). */
void cli_doc_bash_completion(FILE *fp);
void cli_doc_man(FILE *fp);
/* Parse a number argument strictly; returns 0 on success. */
int cli_parse_u64(const char *s, uint64_t *out);
int cli_parse_int(const char *s, int *out);
int cli_parse_double(const char *s, double *out);
/* Non-zero when argv[i] is -h or --help. */
int cli_is_help(const char *arg);

/* The process's heap policy, set once before a command runs (cli_memory.c): allocations below
 * 32 MiB stay in a heap backed by transparent huge pages and are reused from stage to stage. */
void cli_memory_policy(void);
/* Print the usage text of a command on stdout. */
void cli_print_help(const cli_command_t *cmd);

#endif
