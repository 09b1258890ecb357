/*
 * Benchmark (not a test): a 100-member ensemble of the branchwork preset on 2
 * threads, the real pipeline (karst_generate, VTK and Karstnet files,
 * metrics), wall time and peak resident memory. Target (issue 5): <= 60 s on
 * the 2-core project machine.
 *   bench_ensemble [MEMBERS] [THREADS]     (defaults 100 and 2)
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

int main(int argc, char **argv) {
  int members = argc > 1 ? atoi(argv[1]) : 100;
  int threads = argc > 2 ? atoi(argv[2]) : 2;
  const char *scenario = KARST_SOURCE_DIR "/datasets/scenarios/branchwork.yaml";
  if (members < 1 || threads < 1) {
    fprintf(stderr, "usage: bench_ensemble [MEMBERS >= 1] [THREADS >= 1]\n");
    return 2;
  }
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  int status = 1;
  char dir[] = "/tmp/karst_bench_ensemble_XXXXXX";
  char *params = NULL;
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  karst_error_t err = karst_scenario_load(&ctx, scenario, &sc);
  if (err) {
    printf("bench_ensemble: skipped: %s\n", ctx.errmsg);
    status = 0;
    goto cleanup;
  }
  params = karst_ensemble_parameters_json(&sc);
  karst_ensemble_options_t opt;
  karst_ensemble_options_init(&opt);
  opt.n = members;
  opt.seed = 1;
  opt.nthreads = threads;
  opt.use_mpi = 0;
  opt.scenario_path = scenario;
  opt.parameters_json = params;
  karst_ensemble_hooks_t hooks;
  karst_ensemble_pipeline_t pipe;
  karst_ensemble_summary_t sum;
  err = karst_ensemble_hooks_pipeline(&ctx, &hooks, &pipe, &sc);
  double t0 = now_s();
  if (!err) err = karst_ensemble_run(&ctx, dir, &opt, &hooks, &sum);
  double wall = now_s() - t0;
  if (err == KARST_ENOTIMPL) {
    printf("bench_ensemble: skipped: %s\n", ctx.errmsg);
    status = 0;
    goto cleanup;
  }
  if (err) {
    fprintf(stderr, "bench_ensemble: %s\n", ctx.errmsg);
    goto cleanup;
  }
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  printf("bench_ensemble: branchwork, %d members, %d threads, %ld cores online: %.2f s wall "
         "(%.3f s per member, target <= 60 s for 100), peak RSS %.1f MiB\n",
         members, threads, ncpu, wall, wall / members, ru.ru_maxrss / 1024.0);
  status = 0;
cleanup : {
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "bench_ensemble: could not remove %s\n", dir);
}
  free(params);
  karst_scenario_destroy(&sc);
  return status;
}
