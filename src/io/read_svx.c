/* Survex .svx reader: Survex's own `cavern` (Debian package survex) reduces
 * the survey (loop closure, declination, coordinate systems) to a temporary
 * .3d file, which the native .3d reader then reads. */
#include "karst/readers.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "io/input_internal.h"
#include "survey_internal.h"

extern char **environ;

#define CAVERN "cavern"
#define INSTALL_HINT "install it with: apt-get install --no-install-recommends survex"
/* At most this much of cavern's output is quoted in an error message. */
#define MAX_QUOTED_OUTPUT 1200

/* Full path of @p prog found on PATH (caller frees), or NULL. */
static char *find_on_path(const char *prog) {
  const char *path = getenv("PATH");
  if (!path || !*path) return NULL;
  size_t plen = strlen(prog);
  for (const char *p = path;;) {
    const char *colon = strchr(p, ':');
    size_t dlen = colon ? (size_t)(colon - p) : strlen(p);
    char *full = malloc(dlen + plen + 3);
    if (!full) return NULL;
    snprintf(full, dlen + plen + 3, "%.*s/%s", (int)dlen, dlen ? p : ".", prog);
    struct stat st;
    if (stat(full, &st) == 0 && S_ISREG(st.st_mode) && access(full, X_OK) == 0) return full;
    free(full);
    if (!colon) return NULL;
    p = colon + 1;
  }
}

static char *join(const char *dir, const char *name) {
  size_t n = strlen(dir) + strlen(name) + 2;
  char *s = malloc(n);
  if (s) snprintf(s, n, "%s/%s", dir, name);
  return s;
}

/* Remove @p dir and the files cavern left in it. */
static void remove_tree(const char *dir) {
  DIR *d = opendir(dir);
  if (d) {
    struct dirent *e;
    while ((e = readdir(d)))
      if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
        char *f = join(dir, e->d_name);
        if (f) unlink(f);
        free(f);
      }
    closedir(d);
  }
  rmdir(dir);
}

/* The first MAX_QUOTED_OUTPUT bytes of cavern's output (its errors come first). */
static void quote_output(const char *log, char *buf, size_t size) {
  buf[0] = '\0';
  FILE *fp;
  if (karst_i_open_regular(NULL, log, "cavern log", KARST_SURVEY_MAX_BYTES, &fp)) return;
  size_t n = fread(buf, 1, size - 1, fp);
  buf[n] = '\0';
  while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == ' '))
    buf[--n] = '\0';
  if (!feof(fp) && n == size - 1) memcpy(buf + size - 5, "\n...", 5);
  fclose(fp);
}

/**
 * karst_read_svx: read a Survex .svx survey by running Survex's `cavern`.
 *
 * Runs `cavern --quiet --no-auxiliary-files --output=TMP/survey.3d FILE` in
 * a private temporary directory (under $TMPDIR, else /tmp), reads the .3d
 * with karst_read_survex3d() (same dropping and keying rules), and removes
 * the temporary files whatever happens. cavern applies magnetic declination
 * and coordinate-system conversion itself (*declination, *cs); nothing of
 * that is redone here.
 *
 * @param ctx  context for the error message
 * @param path the top-level .svx file (its *include files are found by cavern)
 * @param net  initialised network, replaced on success, left empty on failure
 * @return KARST_SUCCESS; KARST_ENOTFOUND when cavern is not on PATH (the
 *         message says what to install); KARST_EEXTERNAL when cavern fails
 *         (the message quotes its output); KARST_EIO; the .3d reader's errors.
 *
 * Time complexity: that of cavern (network adjustment) plus the .3d read.
 */
karst_error_t karst_read_svx(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  karst_error_t err = KARST_SUCCESS;
  char *cavern = NULL, *dir = NULL, *out = NULL, *log = NULL, *arg_out = NULL;
  char quoted[MAX_QUOTED_OUTPUT];
  int have_actions = 0, status = 0;
  posix_spawn_file_actions_t fa;
  /* cavern opens the file itself: refuse a FIFO or device before it blocks on one. */
  if ((err = karst_i_check_regular(ctx, path, "survey", KARST_SURVEY_MAX_BYTES))) goto cleanup;
  if (access(path, R_OK) != 0) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot open: %s", path, strerror(errno));
    goto cleanup;
  }
  if (!(cavern = find_on_path(CAVERN))) {
    err = karst_set_error(ctx, KARST_ENOTFOUND,
                          "%s: reading a .svx survey needs Survex's '" CAVERN
                          "', which is not on PATH; " INSTALL_HINT,
                          path);
    goto cleanup;
  }
  const char *tmp = getenv("TMPDIR");
  if (!tmp || !*tmp) tmp = "/tmp";
  if (!(dir = join(tmp, "karst-svx-XXXXXX"))) goto nomem;
  if (!mkdtemp(dir)) {
    err = karst_set_error(ctx, KARST_EIO, "%s: cannot create a temporary directory under %s: %s",
                          path, tmp, strerror(errno));
    free(dir);
    dir = NULL;
    goto cleanup;
  }
  if (!(out = join(dir, "survey.3d")) || !(log = join(dir, "cavern.log"))) goto nomem;
  size_t n_arg = strlen(out) + sizeof "--output=";
  if (!(arg_out = malloc(n_arg))) goto nomem;
  snprintf(arg_out, n_arg, "--output=%s", out);
  char *argv[] = {CAVERN, "--quiet", "--no-auxiliary-files", arg_out, "--", (char *)path, NULL};
  int rc = posix_spawn_file_actions_init(&fa);
  have_actions = rc == 0;
  if (!rc) rc = posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  if (!rc) rc = posix_spawn_file_actions_addopen(&fa, 1, log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (!rc) rc = posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid;
  if (!rc) rc = posix_spawn(&pid, cavern, &fa, NULL, argv, environ);
  if (rc) {
    err =
        karst_set_error(ctx, KARST_EEXTERNAL, "%s: cannot run %s: %s", path, cavern, strerror(rc));
    goto cleanup;
  }
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      err = karst_set_error(ctx, KARST_EEXTERNAL, "%s: waiting for %s: %s", path, cavern,
                            strerror(errno));
      goto cleanup;
    }
  quote_output(log, quoted, sizeof quoted);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || access(out, R_OK) != 0) {
    char how[64];
    if (WIFEXITED(status))
      snprintf(how, sizeof how, "exit status %d", WEXITSTATUS(status));
    else
      snprintf(how, sizeof how, "killed by signal %d", WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    err = karst_set_error(ctx, KARST_EEXTERNAL, "%s: cavern failed (%s):\n%s", path, how, quoted);
    goto cleanup;
  }
  karst_log(ctx, KARST_LOG_DEBUG, "%s: cavern says:\n%s", path, quoted);
  if ((err = karst_read_survex3d(ctx, out, net))) {
    char inner[KARST_ERRMSG_MAX];
    snprintf(inner, sizeof inner, "%s", ctx ? ctx->errmsg : "");
    err = karst_set_error(ctx, err, "%s: reading cavern's output: %s", path, inner);
  }
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
cleanup:
  if (have_actions) posix_spawn_file_actions_destroy(&fa);
  if (dir) remove_tree(dir);
  free(cavern);
  free(dir);
  free(out);
  free(log);
  free(arg_out);
  return err;
}
