/* karst report: not available yet (see the open issues). */
#include <stdio.h>

#include "cli.h"

static int run(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "karst report: not available yet in karst %s.\n", karst_version());
  return CLI_ERROR;
}

const cli_command_t cli_cmd_report = {"report", run, "write an HTML report of an ensemble (not available yet)",
                                  "usage: karst report ENSEMBLE_DIR [--survey FILE...] -o report.html\n"};
