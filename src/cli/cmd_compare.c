/* karst compare: not available yet (see the open issues). */
#include <stdio.h>

#include "cli.h"

static int run(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "karst compare: not available yet in karst %s.\n", karst_version());
  return CLI_ERROR;
}

const cli_command_t cli_cmd_compare = {"compare", run, "compare an ensemble with field surveys (not available yet)",
                                  "usage: karst compare ENSEMBLE_DIR --survey FILE... [--format table|csv|json]\n"};
