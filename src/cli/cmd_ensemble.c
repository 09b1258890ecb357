/* karst ensemble: not available yet (see the open issues). */
#include <stdio.h>

#include "cli.h"

static int run(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "karst ensemble: not available yet in karst %s.\n", karst_version());
  return CLI_ERROR;
}

const cli_command_t cli_cmd_ensemble = {"ensemble", run, "generate an ensemble of realisations (not available yet)",
                                  "usage: karst ensemble SCENARIO.yaml -n N -o DIR [-j THREADS] [--seed S]\n"};
