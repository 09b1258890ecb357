/* karst metrics: not available yet (see the open issues). */
#include <stdio.h>

#include "cli.h"

static int run(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "karst metrics: not available yet in karst %s.\n", karst_version());
  return CLI_ERROR;
}

const cli_command_t cli_cmd_metrics = {"metrics", run, "compute Collon et al. 2017 metrics of networks and surveys (not available yet)",
                                  "usage: karst metrics FILE... [--format table|csv|json] [-o OUT] [--observed]\n"};
