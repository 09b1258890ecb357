/* Terminal logging, progress display, interruption and argument parsing for the CLI. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

static volatile int interrupt_flag;
static void on_signal(int sig) {
  (void)sig;
  interrupt_flag = 1;
}

static void log_stderr(void *user, karst_log_level_t level, const char *msg) {
  (void)user;
  static const char *const tag[] = {"error", "warning", "info", "debug"};
  fprintf(stderr, "karst: %s: %s\n", tag[level], msg);
}

typedef struct {
  int tty;
  double t0, last;
  char stage[64];
} progress_state_t;
static progress_state_t progress_state;

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* On a terminal: one redrawn bar with rate and time left. Elsewhere: silent. */
static void progress_terminal(void *user, const char *stage, double done, double total) {
  progress_state_t *ps = user;
  double t = now_s();
  if (strncmp(ps->stage, stage, sizeof ps->stage - 1) != 0) {
    snprintf(ps->stage, sizeof ps->stage, "%s", stage);
    ps->t0 = t;
    ps->last = 0;
  }
  int finished = total > 0 && done >= total;
  if (!finished && t - ps->last < 0.1) return;
  ps->last = t;
  double frac = total > 0 ? done / total : 0;
  if (frac > 1) frac = 1;
  int width = 30, filled = (int)(frac * width);
  char bar[64];
  for (int i = 0; i < width; i++)
    bar[i] = i < filled ? '#' : '.';
  bar[width] = '\0';
  double el = t - ps->t0, left = frac > 0 ? el * (1 - frac) / frac : NAN;
  fprintf(stderr, "\r%-16s [%s] %5.1f%%  %6.0fs left ", stage, bar, 100 * frac,
          isfinite(left) ? left : 0.0);
  if (finished) fputc('\n', stderr);
  fflush(stderr);
}

void cli_count_progress_init(cli_count_progress_t *ps, const char *command, const char *noun,
                             int lines) {
  memset(ps, 0, sizeof *ps);
  ps->command = command;
  ps->noun = noun;
  ps->tty = isatty(STDERR_FILENO);
  ps->lines = lines;
}

void cli_count_progress(void *user, const char *stage, double done, double total) {
  cli_count_progress_t *ps = user;
  double t = now_s();
  if (ps->t0 == 0 || strncmp(ps->stage, stage, sizeof ps->stage - 1) != 0) {
    snprintf(ps->stage, sizeof ps->stage, "%s", stage);
    ps->t0 = t;
    ps->last = 0;
    ps->last_fraction = 0;
  }
  double el = t - ps->t0, rate = el > 0 ? done / el : 0;
  double left = rate > 0 ? (total - done) / rate : NAN;
  double frac = total > 0 ? done / total : 1;
  int finished = done >= total;
  char eta[32];
  if (finished)
    snprintf(eta, sizeof eta, "done");
  else if (isfinite(left))
    snprintf(eta, sizeof eta, "%.0f s left", left);
  else
    snprintf(eta, sizeof eta, "time left unknown");
  if (ps->tty) {
    if (!finished && t - ps->last < 0.1) return;
    ps->last = t;
    char bar[31];
    int filled = (int)(frac * 30);
    for (int i = 0; i < 30; i++)
      bar[i] = i < filled ? '#' : '.';
    bar[30] = '\0';
    fprintf(stderr, "\r%-12s [%s] %.0f/%.0f  %.2f/s  %-18s", ps->stage, bar, done, total, rate,
            eta);
    if (finished) fputc('\n', stderr);
  } else {
    if (!ps->lines || done == 0) return;
    if (!finished && t - ps->last < 10 && frac - ps->last_fraction < 0.1) return;
    ps->last = t;
    ps->last_fraction = frac;
    fprintf(stderr, "karst %s: %.0f of %.0f %s, %.2f per second, %s\n", ps->command, done, total,
            ps->noun, rate, eta);
  }
  fflush(stderr);
}

void cli_ctx_init(karst_ctx_t *ctx, int quiet, int verbose) {
  karst_ctx_init(ctx);
  ctx->log = log_stderr;
  ctx->verbosity = quiet ? KARST_LOG_ERROR : (verbose ? KARST_LOG_DEBUG : KARST_LOG_WARNING);
  long n = sysconf(_SC_NPROCESSORS_ONLN);
  ctx->nthreads = n > 0 ? (int)n : 1;
  memset(&progress_state, 0, sizeof progress_state);
  progress_state.tty = isatty(STDERR_FILENO);
  if (!quiet && progress_state.tty) {
    ctx->progress = progress_terminal;
    ctx->progress_user = &progress_state;
  }
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
  ctx->interrupt = &interrupt_flag;
}

int cli_fail(const char *cmd, const karst_ctx_t *ctx, karst_error_t err) {
  if (ctx && ctx->errmsg[0])
    fprintf(stderr, "karst %s: %s\n", cmd, ctx->errmsg);
  else
    fprintf(stderr, "karst %s: %s\n", cmd, karst_strerror(err));
  return CLI_ERROR;
}

int cli_resumable_status(const char *cmd, const karst_ctx_t *ctx, karst_error_t err, int rank,
                         const char *fmt, ...) {
  if (!err) return CLI_OK;
  if (err != KARST_EINTERRUPTED) return cli_fail(cmd, ctx, err);
  if (rank == 0) {
    fprintf(stderr, "karst %s: interrupted; ", cmd);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
  }
  return CLI_ERROR;
}

void cli_note_failed_output(karst_ctx_t *ctx, karst_error_t err, const char *output) {
  if (!ctx->errmsg[0]) return;
  char msg[KARST_ERRMSG_MAX];
  snprintf(msg, sizeof msg, "%s", ctx->errmsg);
  karst_set_error(ctx, err, "writing %s: %s; no output was kept", output, msg);
}

int cli_usage_error(const char *cmd, const char *fmt, ...) {
  fprintf(stderr, "karst %s: ", cmd);
  va_list ap;
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
  fputc('\n', stderr);
  const cli_command_t *c = cli_find_command(cmd);
  if (c) {
    const char *nl = strchr(c->usage, '\n');
    fprintf(stderr, "%.*s\n", nl ? (int)(nl - c->usage) : (int)strlen(c->usage), c->usage);
  }
  fprintf(stderr, "Run 'karst help %s' for its options, 'karst --help' for the commands.\n", cmd);
  return CLI_USAGE;
}

void cli_print_help(const cli_command_t *cmd) {
  printf("karst %s: %s\n\n%s", cmd->name, cmd->summary, cmd->usage);
}

int cli_is_help(const char *arg) {
  return strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0;
}

/* Digits only (strtoull alone would take " -5" as 2^64 - 5 and "+5" as 5). */
int cli_parse_u64(const char *s, uint64_t *out) {
  if (!s || !*s) return -1;
  for (const char *c = s; *c; c++)
    if (*c < '0' || *c > '9') return -1;
  char *end;
  errno = 0;
  unsigned long long v = strtoull(s, &end, 10);
  if (errno || *end) return -1;
  *out = (uint64_t)v;
  return 0;
}

int cli_parse_int(const char *s, int *out) {
  if (!s || !*s) return -1;
  const char *c = s + (*s == '-');
  if (!*c) return -1;
  for (; *c; c++)
    if (*c < '0' || *c > '9') return -1;
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  if (errno || *end || v < -2147483647L || v > 2147483647L) return -1;
  *out = (int)v;
  return 0;
}

int cli_parse_double(const char *s, double *out) {
  if (!s || !*s) return -1;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (errno || *end || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

/* Check that @p path can be written, before any work, and add it to the
 * outputs committed together; its temporary keeps the extension, by which
 * the writers choose the format. */
karst_error_t cli_add_output(karst_ctx_t *ctx, karst_fileset_t *outs, const char *path,
                             const char **tmp) {
  karst_error_t err = karst_check_writable(ctx, path);
  if (err) return err;
  char *t = karst_temp_name_ext(path);
  if (!t) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  err = karst_fileset_add(ctx, outs, path, t, tmp);
  free(t);
  return err;
}

int cli_refuse_output_over_input(const char *cmd, const char *out, const char *const *inputs,
                                 int n) {
  struct stat so, si;
  if (!out || stat(out, &so) != 0) return CLI_OK;
  for (int i = 0; i < n; i++)
    if (inputs[i] && stat(inputs[i], &si) == 0 && si.st_dev == so.st_dev && si.st_ino == so.st_ino)
      return cli_usage_error(
          cmd,
          "the output %s is the input %s; it would be replaced (write the output "
          "elsewhere)",
          out, inputs[i]);
  return CLI_OK;
}
