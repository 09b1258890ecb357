/* karst completion: a shell completion script generated from the command table. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

static int run(int argc, char **argv) {
  if (argc < 2) return cli_usage_error("completion", "no shell given (bash)");
  if (argc > 2) return cli_usage_error("completion", "one shell only, got '%s'", argv[2]);
  if (strcmp(argv[1], "bash") != 0)
    return cli_usage_error("completion", "unknown shell '%s' (bash is supported)", argv[1]);
  cli_doc_bash_completion(stdout);
  if (fflush(stdout) != 0 || ferror(stdout)) {
    fprintf(stderr, "karst completion: cannot write the script to standard output\n");
    return CLI_ERROR;
  }
  return CLI_OK;
}

const cli_command_t cli_cmd_completion = {
    "completion", run, "print a shell completion script (bash)",
    "usage: karst completion bash\n\n"
    "Prints a bash completion script made from the command table, the same table as\n"
    "`karst --help` and the man page: command names, each command's options, and their\n"
    "values (scenario .yaml files, directories, formats). Use it for this shell with\n"
    "  source <(karst completion bash)\n"
    "or for every shell: `cmake --install` puts it in share/bash-completion/completions/karst.\n"};
