/* karst generate: not available yet (see the open issues). */
#include <stdio.h>

#include "cli.h"

static int run(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "karst generate: not available yet in karst %s.\n", karst_version());
  return CLI_ERROR;
}

const cli_command_t cli_cmd_generate = {"generate", run, "generate a cave network from a scenario (not available yet)",
                                  "usage: karst generate SCENARIO.yaml -o DIR [--seed S] [--samples]\n"};
