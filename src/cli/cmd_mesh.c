/* karst mesh: not available yet (see the open issues). */
#include <stdio.h>

#include "cli.h"

static int run(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "karst mesh: not available yet in karst %s.\n", karst_version());
  return CLI_ERROR;
}

const cli_command_t cli_cmd_mesh = {"mesh", run, "polygonize the conduits of a network (not available yet)",
                                  "usage: karst mesh NETWORK.vtp -o cave.vtp [--voxel 0.5] [--box x0,y0,z0,x1,y1,z1]\n"};
