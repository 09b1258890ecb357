/* Helpers of the benchmarks: running the karst program as a user runs it (whole process:
 * bench_peers.c, bench_massif.c), reading its run.json, and their scratch directories. */
#ifndef KARST_BENCH_SPAWN_H
#define KARST_BENCH_SPAWN_H

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>

extern char **environ;

/* A fresh scratch directory from @p tmpl ("/tmp/NAME_XXXXXX", overwritten), or NULL with a
 * message naming @p who. */
static inline char *bench_mkdtemp(char *tmpl, const char *who) {
  char *d = mkdtemp(tmpl);
  if (!d) fprintf(stderr, "%s: cannot create %s: %s\n", who, tmpl, strerror(errno));
  return d;
}

/* Remove the scratch directory @p dir and everything in it. */
static inline void bench_remove_dir(const char *dir, const char *who) {
  char cmd[4200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "%s: could not remove %s\n", who, dir);
}

/* @p x in the shortest of %.15g, %.16g, %.17g that reads back as @p x (round-trip digits, as
 * Python's repr writes them). */
static inline void bench_shortest_double(char *buf, size_t size, double x) {
  for (int digits = 15; digits <= 17; digits++) {
    snprintf(buf, size, "%.*g", digits, x);
    if (strtod(buf, NULL) == x) return;
  }
}

static inline double bench_now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Run @p argv (argv[0] the program) to completion, its standard output to /dev/null when
 * @p quiet: its wall time in seconds, its peak resident memory (KiB, *rss_kib) and its page
 * faults (*faults, minor and major; may be NULL), or -1 when it could not start or did not exit
 * with 0. The peak is the child's ru_maxrss, which Linux starts from this process's resident set
 * at the spawn (it carries over execve): it is the child's own only when this process is small
 * (bench_peers, bench_massif); bench_generate, large by then, ignores it and lets the child
 * print its own (VmHWM). */
static inline double bench_run_counted(char *const argv[], int quiet, long *rss_kib, long *faults) {
  posix_spawn_file_actions_t fa;
  if (posix_spawn_file_actions_init(&fa) != 0) return -1;
  if (quiet) posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  double t0 = bench_now_s();
  pid_t pid;
  int started = posix_spawn(&pid, argv[0], &fa, NULL, argv, environ) == 0;
  posix_spawn_file_actions_destroy(&fa);
  if (!started) return -1;
  int status;
  struct rusage ru;
  if (wait4(pid, &status, 0, &ru) < 0) return -1;
  double t = bench_now_s() - t0;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
  *rss_kib = ru.ru_maxrss;
  if (faults) *faults = ru.ru_minflt + ru.ru_majflt;
  return t;
}

/* bench_run_counted without the page faults, output shown. */
static inline double bench_run(char *const argv[], long *rss_kib) {
  return bench_run_counted(argv, 0, rss_kib, NULL);
}

/* DIR/run.json as a string (static storage, overwritten by the next call), or NULL. */
static inline const char *bench_run_json(const char *dir) {
  static char buf[1 << 20];
  char path[4096];
  snprintf(path, sizeof path, "%s/run.json", dir);
  FILE *f = fopen(path, "r");
  if (!f) return NULL;
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = '\0';
  return buf;
}

/* The number after "key": within the object "section" of @p json, or NAN. */
static inline double bench_json_number(const char *json, const char *section, const char *key) {
  char pat[128];
  if (!json) return NAN;
  snprintf(pat, sizeof pat, "\"%s\"", section);
  const char *p = strstr(json, pat);
  snprintf(pat, sizeof pat, "\"%s\":", key);
  p = p ? strstr(p, pat) : NULL;
  return p ? strtod(p + strlen(pat), NULL) : NAN;
}

#endif
