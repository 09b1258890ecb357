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
/* Print "karst CMD: message" from ctx (or the error code) to stderr; returns CLI_ERROR. */
int cli_fail(const char *cmd, const karst_ctx_t *ctx, karst_error_t err);
/* A writer failed on the temporary file of @p output (its message names the temporary, which
 * is gone): reword ctx's message as "writing OUTPUT: message; no output was kept". */
void cli_note_failed_output(karst_ctx_t *ctx, karst_error_t err, const char *output);
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
/* Print the usage text of a command on stdout. */
void cli_print_help(const cli_command_t *cmd);

#endif
