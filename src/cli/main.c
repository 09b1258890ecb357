/* karst: git-style command dispatcher. Each subcommand lives in cmd_<name>.c. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* Each cmd_<name>.c defines its table entry (name, function, summary, usage). */
extern const cli_command_t cli_cmd_validate, cli_cmd_generate, cli_cmd_metrics, cli_cmd_ensemble,
    cli_cmd_compare, cli_cmd_report, cli_cmd_mesh, cli_cmd_view, cli_cmd_blocks;
extern const cli_command_t cli_cmd_calibrate;
extern const cli_command_t cli_cmd_export;
extern const cli_command_t cli_cmd_completion;
static int cmd_help(int argc, char **argv);
static const cli_command_t cli_cmd_help = {
    "help", cmd_help, "show help for a command",
    "usage: karst help [COMMAND] [--man]\n\n"
    "Without COMMAND: the commands. With COMMAND: its options.\n"
    "  --man    print the karst(1) man page (roff) made from the help of every command;\n"
    "           read it with: karst help --man | man -l -\n"};

/* The command table, in the order of the pipeline (one line per added command). */
// clang-format off
static const cli_command_t *const commands[] = {
    &cli_cmd_help,     &cli_cmd_validate, &cli_cmd_generate, &cli_cmd_metrics,
    &cli_cmd_ensemble, &cli_cmd_compare,  &cli_cmd_report,   &cli_cmd_mesh,
    &cli_cmd_view,       // ParaView on the script beside the outputs
    &cli_cmd_blocks,     // rock blocks (Paris et al. 2020)
    &cli_cmd_calibrate,  // fit a scenario to a survey (ABC-SMC)
    &cli_cmd_export,     // GeoPackage for QGIS
    &cli_cmd_completion, // shell completion from this table
};
// clang-format on
static const size_t n_commands = sizeof commands / sizeof commands[0];

const char cli_description[] =
    "karst generates 3-D karst cave networks from geology (Paris et al. 2021),\n"
    "measures networks and cave surveys (Collon et al. 2017) and builds conduit geometry.\n";

const cli_command_t *const *cli_commands(size_t *n) {
  *n = n_commands;
  return commands;
}

const cli_command_t *cli_find_command(const char *name) {
  for (size_t i = 0; i < n_commands; i++)
    if (strcmp(commands[i]->name, name) == 0) return commands[i];
  return NULL;
}

static void print_main_help(FILE *out) {
  fprintf(out, "usage: karst [--version] [--help] COMMAND [ARGS]\n\n%s\nCommands:\n",
          cli_description);
  for (size_t i = 1; i < n_commands; i++)
    fprintf(out, "  %-10s %s\n", commands[i]->name, commands[i]->summary);
  fprintf(out, "\nRun 'karst help COMMAND' for the options of one command.\n");
}

static int cmd_help(int argc, char **argv) {
  if (argc >= 2 && strcmp(argv[1], "--man") == 0) {
    if (argc > 2) return cli_usage_error("help", "--man takes no command");
    cli_doc_man(stdout);
    return fflush(stdout) == 0 && !ferror(stdout) ? CLI_OK : CLI_ERROR;
  }
  if (argc < 2) {
    print_main_help(stdout);
    return CLI_OK;
  }
  const cli_command_t *c = cli_find_command(argv[1]);
  if (!c) return cli_usage_error("help", "unknown command '%s'", argv[1]);
  cli_print_help(c);
  return CLI_OK;
}

/* `karst --version`: karst's version on the first line, then the compiler and every library
 * (the list that run.json, ensemble.json and the .vtp field data carry). */
static int print_version(void) {
  char *text = karst_versions_text();
  if (!text) {
    fprintf(stderr, "karst: out of memory\n");
    return CLI_ERROR;
  }
  fputs(text, stdout);
  free(text);
  return CLI_OK;
}

/* Results printed on standard output that did not reach it (a full device, a closed pipe) are
 * an error, not a success: every command's output is checked here, once, at exit. */
static int stdout_status(const char *cmd) {
  errno = 0;
  if (fflush(stdout) == 0 && !ferror(stdout)) return CLI_OK;
  int e = errno;
  fprintf(stderr, "karst %s: writing standard output: %s\n", cmd, e ? strerror(e) : "write error");
  return CLI_ERROR;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    print_main_help(stderr);
    return CLI_USAGE;
  }
  if (cli_is_help(argv[1])) {
    print_main_help(stdout);
    return stdout_status("help");
  }
  if (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "version") == 0) {
    int status = print_version();
    return status ? status : stdout_status("version");
  }
  const cli_command_t *c = cli_find_command(argv[1]);
  if (!c) {
    if (argv[1][0] == '-')
      fprintf(stderr,
              "karst: unknown option '%s' (the options before a command are --help and "
              "--version). See 'karst --help'.\n",
              argv[1]);
    else
      fprintf(stderr, "karst: '%s' is not a karst command. See 'karst --help'.\n", argv[1]);
    return CLI_USAGE;
  }
  for (int i = 2; i < argc; i++)
    if (cli_is_help(argv[i])) {
      cli_print_help(c);
      return stdout_status(c->name);
    }
  cli_memory_policy();
  /* VTK's own threads (vtkSMPTools, TBB in Debian's VTK 9.1) only compute the ranges of the
   * arrays a file writer stores; with TBB every command that wrote a .vtp started a TBB worker
   * thread, so `--threads 1` ran two threads, and `karst ensemble -j N` N + 1. Sequential keeps
   * the thread counts the user asked for; a VTK_SMP_BACKEND_IN_USE set by the user wins. */
  setenv("VTK_SMP_BACKEND_IN_USE", "Sequential", 0);
  int status = c->run(argc - 1, argv + 1);
  int out = stdout_status(c->name);
  return out ? out : status;
}
