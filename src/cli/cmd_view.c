/* karst view: open the ParaView script karst wrote beside its outputs. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli.h"

/* The ParaView program: $KARST_PARAVIEW when set, else "paraview" on PATH (NULL if none). */
static char *find_paraview(void) {
  const char *env = getenv("KARST_PARAVIEW");
  if (env && *env) return access(env, X_OK) == 0 ? strdup(env) : NULL;
  const char *path = getenv("PATH");
  if (!path) return NULL;
  for (const char *p = path; *p;) {
    const char *colon = strchr(p, ':');
    size_t len = colon ? (size_t)(colon - p) : strlen(p);
    char cand[PATH_MAX];
    if (len > 0 && len + 10 < sizeof cand) {
      snprintf(cand, sizeof cand, "%.*s/paraview", (int)len, p);
      if (access(cand, X_OK) == 0) return strdup(cand);
    }
    p += len + (colon ? 1 : 0);
  }
  return NULL;
}

/* @p s for a POSIX shell: as it is when it holds only safe characters, else in single quotes. */
static void put_quoted(FILE *out, const char *s) {
  const char *safe = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./+,:@=";
  if (*s && strspn(s, safe) == strlen(s)) {
    fputs(s, out);
    return;
  }
  fputc('\'', out);
  for (const char *p = s; *p; p++)
    if (*p == '\'')
      fputs("'\\''", out);
    else
      fputc(*p, out);
  fputc('\'', out);
}

/* The command line a user types: the script runs in its own directory (ParaView's --script
 * gives it no __file__, so it finds its files there). */
static void print_command(FILE *out, const char *dir, const char *name, const char *paraview) {
  fputs("cd ", out);
  put_quoted(out, dir);
  fputs(" && ", out);
  put_quoted(out, paraview);
  fputs(" ", out);
  char arg[PATH_MAX + 16];
  snprintf(arg, sizeof arg, "--script=%s", name);
  put_quoted(out, arg);
  fputc('\n', out);
}

static int run(int argc, char **argv) {
  const char *target = NULL;
  int print_only = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (strcmp(a, "--print") == 0)
      print_only = 1;
    else if (a[0] == '-' && a[1] != '\0')
      return cli_usage_error("view", "unknown option '%s'", a);
    else if (!target)
      target = a;
    else
      return cli_usage_error("view", "more than one directory or file given ('%s' and '%s')",
                             target, a);
  }
  if (!target) return cli_usage_error("view", "no directory or file given");
  karst_ctx_t ctx;
  cli_ctx_init(&ctx, 1, 0);
  char *script = NULL, *paraview = NULL;
  int status = CLI_OK;
  karst_error_t err = karst_view_find_script(&ctx, target, &script);
  if (err) {
    status = cli_fail("view", &ctx, err);
    goto cleanup;
  }
  char *slash = strrchr(script, '/');
  const char *name = slash ? slash + 1 : script;
  if (slash) *slash = '\0';
  const char *dir = slash ? (script[0] ? script : "/") : ".";
  paraview = print_only ? NULL : find_paraview();
  if (!paraview) {
    if (!print_only)
      printf("ParaView is not installed here (no 'paraview' on PATH; Debian: apt-get install "
             "paraview). To view, run:\n  ");
    print_command(stdout, dir, name, "paraview");
    goto cleanup;
  }
  fflush(stdout);
  pid_t pid = fork();
  if (pid < 0) {
    fprintf(stderr, "karst view: cannot start %s: %s\n", paraview, strerror(errno));
    status = CLI_ERROR;
    goto cleanup;
  }
  if (pid == 0) {
    char arg[PATH_MAX + 16];
    snprintf(arg, sizeof arg, "--script=%s", name);
    if (chdir(dir) != 0) {
      fprintf(stderr, "karst view: %s: %s\n", dir, strerror(errno));
      _exit(127);
    }
    execl(paraview, paraview, arg, (char *)NULL);
    fprintf(stderr, "karst view: cannot run %s: %s\n", paraview, strerror(errno));
    _exit(127);
  }
  int ws = 0;
  while (waitpid(pid, &ws, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(ws) || WEXITSTATUS(ws) != 0) {
    fprintf(stderr, "karst view: %s exited with %s %d\n", paraview,
            WIFEXITED(ws) ? "status" : "signal", WIFEXITED(ws) ? WEXITSTATUS(ws) : WTERMSIG(ws));
    status = CLI_ERROR;
  }
cleanup:
  free(paraview);
  free(script);
  return status;
}

const cli_command_t cli_cmd_view = {
    "view", run, "open an output directory in ParaView with karst's colours and units",
    "usage: karst view DIR|FILE [--print]\n\n"
    "Runs ParaView on the script karst wrote beside its outputs (network.paraview.py by\n"
    "karst generate, ensemble.paraview.py by karst ensemble, STEM.paraview.py by karst mesh):\n"
    "categorical arrays (tunnel_type, kind, source, ...) are coloured by category with their\n"
    "names in the legend, continuous ones with a colour bar titled with the unit.\n"
    "DIR must hold exactly one script; FILE is a script or an output with a script beside it.\n"
    "When ParaView is not installed ($KARST_PARAVIEW or 'paraview' on PATH), prints the\n"
    "command to run instead.\n\n"
    "  --print   only print the command\n"};
