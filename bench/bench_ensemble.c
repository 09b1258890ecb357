/*
 * Benchmark (not a test): a 100-member ensemble of the branchwork preset on 2
 * threads, the real pipeline (karst_generate, VTK and Karstnet files,
 * metrics), wall time and peak resident memory, then what one member costs (its stages,
 * the rest of the generation, its files, its metrics) and the throughput that implies on 64
 * cores. Targets: <= 60 s on the 2-core project machine (issue 5), <= 8 s (issue 17).
 *   bench_ensemble [MEMBERS] [THREADS]     (defaults 100 and 2)
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "karst.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* What one member costs, one thread, in the ensemble's own order: karst_generate (its stages
 * from the statistics, and the rest: the realisation's geology, allocations; the pipeline's
 * realise hook is this call without the statistics), then the pipeline's own hooks for the
 * member's files and its metrics. Mean of @p n members; then the throughput they imply on a
 * 64-core machine. */
static int per_member_costs(karst_ctx_t *ctx, const karst_scenario_t *sc,
                            const karst_ensemble_hooks_t *hooks, const char *dir, int n,
                            double wall, int members, int threads) {
  double stages[KARST_STAGE_COUNT] = {0}, gen = 0, out = 0, met = 0;
  double values[KARST_ENSEMBLE_MAX_METRICS];
  char mdir[4200];
  snprintf(mdir, sizeof mdir, "%s/member", dir);
  if (mkdir(mdir, 0777) != 0) {
    perror("bench_ensemble: member directory");
    return 1;
  }
  int saved = ctx->nthreads;
  ctx->nthreads = 1;
  for (int i = 0; i < n; i++) {
    karst_network_t net;
    karst_network_init(&net);
    karst_generate_stats_t st;
    double t0 = now_s();
    karst_error_t err = karst_generate(ctx, sc, 1000 + (uint64_t)i, 0, &net, NULL, &st);
    double t1 = now_s();
    if (!err) err = hooks->write(ctx, hooks->user, mdir, &net);
    double t2 = now_s();
    if (!err) err = hooks->measure(ctx, hooks->user, &net, values);
    double t3 = now_s();
    karst_network_destroy(&net);
    if (err) {
      fprintf(stderr, "bench_ensemble: member %d: %s\n", i, ctx->errmsg);
      ctx->nthreads = saved;
      return 1;
    }
    for (int k = 0; k < KARST_STAGE_COUNT; k++)
      stages[k] += st.stage_seconds[k];
    gen += t1 - t0, out += t2 - t1, met += t3 - t2;
  }
  ctx->nthreads = saved;
  double sum = 0;
  for (int k = 0; k < KARST_STAGE_COUNT; k++)
    sum += stages[k] / n;
  const double member = (gen + out + met) / n;
  printf("bench_ensemble: one member, one thread (mean of %d): %.4f s = stages %.4f s (sampling "
         "%.4f, graph %.4f, paths %.4f, skeleton %.4f, amplification %.4f, classification "
         "%.4f) + rest of karst_generate (geology, allocation) %.4f s + files %.4f s + metrics "
         "%.4f s\n",
         n, member, sum, stages[KARST_STAGE_SAMPLING] / n, stages[KARST_STAGE_GRAPH] / n,
         stages[KARST_STAGE_PATHS] / n, stages[KARST_STAGE_SKELETON] / n,
         stages[KARST_STAGE_AMPLIFICATION] / n, stages[KARST_STAGE_CLASSIFICATION] / n,
         gen / n - sum, out / n, met / n);
  /* Members are independent: T threads (or ranks) run T at a time; the measured run gives the
   * efficiency of T on this machine, which the estimate assumes for 64 cores (docs/ensembles.md).
   */
  double eff = member * members / (wall * threads);
  printf("bench_ensemble: %d threads ran at %.0f %% of %d x one member; 64 cores at that "
         "efficiency: about %.0f members per second (%.1f s for 10 000)\n",
         threads, 100 * eff, threads, 64 * eff / member, 10000 * member / (64 * eff));
  return 0;
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
         "(%.3f s per member, target <= 8 s for 100 on 2 threads), peak RSS %.1f MiB\n",
         members, threads, ncpu, wall, wall / members, ru.ru_maxrss / 1024.0);
  status =
      per_member_costs(&ctx, &sc, &hooks, dir, members < 20 ? members : 20, wall, members, threads);
cleanup : {
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) fprintf(stderr, "bench_ensemble: could not remove %s\n", dir);
}
  free(params);
  karst_scenario_destroy(&sc);
  return status;
}
