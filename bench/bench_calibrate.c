/*
 * Benchmark (not a test): karst calibrate of the branchwork preset against the DowProv survey
 * (issue 13, item 5): 3 parameters (skeleton.gamma 0.5-3, tortuosity 0-1, amplification.steps
 * 0-5), 200 particles per generation, 5 SMC generations after the prior sample, the real
 * pipeline for every particle, the best-fit ensemble left out. Prints the wall time (target
 * <= 10 minutes on the 2-core project machine), particles (simulations) per second, the
 * acceptance rate and tolerance of every generation, the process's CPU time (on a busy machine
 * wall time / threads is no measure; CPU time per simulation is) and the load average before
 * and after, so that a busy machine shows.
 *   bench_calibrate [PARTICLES] [GENERATIONS] [THREADS]     (defaults 200, 5 and 2)
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "karst.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

typedef struct {
  double t_last;
} bench_state_t;

static void on_generation(void *user, const karst_calibrate_generation_t *g) {
  bench_state_t *s = user;
  double t = now_s();
  printf("bench_calibrate: generation %d: %" PRId64 " simulations in %.1f s (%.2f per second), "
         "acceptance %s%.3f, tolerance %.4g, ESS %.1f\n",
         g->generation, g->simulations, t - s->t_last, (double)g->simulations / (t - s->t_last),
         g->generation == 0 ? "(prior sample) " : "", g->generation == 0 ? 1.0 : g->acceptance,
         g->tolerance, g->ess);
  fflush(stdout);
  s->t_last = t;
}

int main(int argc, char **argv) {
  int particles = argc > 1 ? atoi(argv[1]) : 200;
  int generations = argc > 2 ? atoi(argv[2]) : 5;
  int threads = argc > 3 ? atoi(argv[3]) : 2;
  if (particles < 4 || generations < 0 || threads < 1) {
    fprintf(stderr, "usage: bench_calibrate [PARTICLES >= 4] [GENERATIONS >= 0] [THREADS >= 1]\n");
    return 2;
  }
  const char *scenario = KARST_SOURCE_DIR "/datasets/scenarios/branchwork.yaml";
  const char *survey = KARST_SOURCE_DIR "/datasets/surveys/dowprov/DowProv.3d";
  static const char *const specs[] = {"skeleton.gamma=0.5:3", "tortuosity=0:1",
                                      "amplification.steps=0:5"};
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_calibrate_param_t params[3];
  for (int k = 0; k < 3; k++)
    if (karst_calibrate_param_parse(&ctx, specs[k], &params[k])) {
      fprintf(stderr, "bench_calibrate: %s\n", ctx.errmsg);
      return 1;
    }
  char dir[] = "/tmp/karst_bench_calibrate_XXXXXX";
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  karst_calibrate_options_t opt;
  karst_calibrate_options_init(&opt);
  opt.scenario_path = scenario;
  opt.survey_path = survey;
  opt.n_params = 3;
  opt.params = params;
  opt.particles = particles;
  opt.generations = generations;
  opt.min_acceptance = 0; /* always the 5 generations */
  opt.best_members = 0;
  opt.seed = 2021;
  opt.nthreads = threads;
  opt.use_mpi = 0;
  bench_state_t st;
  opt.on_generation = on_generation;
  opt.on_generation_user = &st;
  double load0[3] = {0}, load1[3] = {0};
  getloadavg(load0, 3);
  long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  printf("bench_calibrate: branchwork vs DowProv, 3 parameters, %d particles, %d generations, %d "
         "threads, %ld cores online, load average %.2f before\n",
         particles, generations, threads, ncpu, load0[0]);
  karst_calibrate_summary_t sum;
  double t0 = now_s();
  st.t_last = t0;
  karst_error_t err = karst_calibrate_run(&ctx, dir, &opt, &sum);
  double wall = now_s() - t0;
  getloadavg(load1, 3);
  int status = 1;
  if (err) {
    fprintf(stderr, "bench_calibrate: %s\n", ctx.errmsg);
  } else {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
                 (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
    printf("bench_calibrate: %" PRId64 " simulations in %.1f s wall: %.2f particles per second "
           "(target: the whole run <= 600 s); load average %.2f after; final tolerance %.4g\n",
           sum.simulations, wall, (double)sum.simulations / wall, load1[0], sum.tolerance);
    printf("bench_calibrate: CPU time %.1f s (%.3f s per simulation; %d threads on an idle "
           "machine: about %.0f s wall), peak RSS %.1f MiB\n",
           cpu, cpu / (double)sum.simulations, threads, cpu / threads, ru.ru_maxrss / 1024.0);
    for (int k = 0; k < 3; k++)
      printf("bench_calibrate:   %s: median %.4g, 90 %% interval [%.4g, %.4g]\n", params[k].key,
             sum.median[k], sum.low[k], sum.high[k]);
    status = 0;
  }
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "bench_calibrate: could not remove %s\n", dir);
  return status;
}
