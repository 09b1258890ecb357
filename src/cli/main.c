/* karst: git-style command dispatcher. Each subcommand lives in cmd_<name>.c. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* Each cmd_<name>.c defines its table entry (name, function, summary, usage). */
extern const cli_command_t cli_cmd_validate, cli_cmd_generate, cli_cmd_metrics, cli_cmd_ensemble,
    cli_cmd_compare, cli_cmd_report, cli_cmd_mesh, cli_cmd_calibrate;
static int cmd_help(int argc, char **argv);
static const cli_command_t cli_cmd_help = {"help", cmd_help, "show help for a command",
                                           "usage: karst help [COMMAND]\n"};

/* The command table, in the order of the pipeline. */
static const cli_command_t *const commands[] = {
    &cli_cmd_help,    &cli_cmd_validate,  &cli_cmd_generate, &cli_cmd_metrics, &cli_cmd_ensemble,
    &cli_cmd_compare, &cli_cmd_calibrate, &cli_cmd_report,   &cli_cmd_mesh,
};
static const size_t n_commands = sizeof commands / sizeof commands[0];

const cli_command_t *cli_find_command(const char *name) {
  for (size_t i = 0; i < n_commands; i++)
    if (strcmp(commands[i]->name, name) == 0) return commands[i];
  return NULL;
}

static void print_main_help(FILE *out) {
  fprintf(out,
          "usage: karst [--version] [--help] COMMAND [ARGS]\n\n"
          "karst generates 3-D karst cave networks from geology (Paris et al. 2021),\n"
          "measures networks and cave surveys (Collon et al. 2017) and builds conduit geometry.\n\n"
          "Commands:\n");
  for (size_t i = 1; i < n_commands; i++)
    fprintf(out, "  %-10s %s\n", commands[i]->name, commands[i]->summary);
  fprintf(out, "\nRun 'karst help COMMAND' for the options of one command.\n");
}

static int cmd_help(int argc, char **argv) {
  if (argc < 2) {
    print_main_help(stdout);
    return CLI_OK;
  }
  const cli_command_t *c = cli_find_command(argv[1]);
  if (!c) return cli_usage_error("help", "unknown command '%s'", argv[1]);
  cli_print_help(c);
  return CLI_OK;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    print_main_help(stderr);
    return CLI_USAGE;
  }
  if (cli_is_help(argv[1])) {
    print_main_help(stdout);
    return CLI_OK;
  }
  if (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "version") == 0) {
    printf("karst %s\n", karst_version());
    return CLI_OK;
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
      return CLI_OK;
    }
  return c->run(argc - 1, argv + 1);
}
