/* Benchmark (not a test): what conditioning on a survey adds to a run (issue 12: at most 10 %).
 * datasets/scenarios/dowprov_extension.yaml (689 surveyed legs of DowProv.3d) is generated with
 * its conditioning, and without it: the same scenario with the survey dropped after loading,
 * keeping every key point (the entrance sinks and the survey pieces' waypoints stay where the
 * stations are), so both runs route between the same points and differ only by the stations as
 * samples and the legs as edges. Wall time of karst_generate, median of R alternating runs each,
 * at the shipped sampling and at a finer one (fill_radius / 1.5).
 * Usage: bench_conditioning [--runs R] [--threads N] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "generate/generate_internal.h"
#include "karst.h"
#include "karst/conditioning.h"

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double run_once(const karst_scenario_t *sc, int threads, karst_generate_stats_t *st) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  if (threads > 0) ctx.nthreads = threads;
  karst_network_t net;
  karst_network_init(&net);
  double t = karst_i_now();
  karst_error_t err = karst_generate(&ctx, sc, sc->seed, 0, &net, NULL, st);
  t = karst_i_now() - t;
  if (err) {
    fprintf(stderr, "bench_conditioning: %s\n", ctx.errmsg);
    exit(1);
  }
  karst_network_destroy(&net);
  return t;
}

static void bench(const char *label, double radius_scale, int runs, int threads) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_scenario_t with, without;
  karst_scenario_init(&with);
  karst_scenario_init(&without);
  const char *path = KARST_SOURCE_DIR "/datasets/scenarios/dowprov_extension.yaml";
  if (karst_scenario_load(&ctx, path, &with) || karst_scenario_load(&ctx, path, &without)) {
    fprintf(stderr, "bench_conditioning: %s\n", ctx.errmsg);
    exit(1);
  }
  for (int i = 0; i < 2; i++) {
    karst_scenario_t *s = i ? &without : &with;
    s->sampling.fill_radius /= radius_scale;
    s->sampling.feature_radius /= radius_scale;
  }
  karst_survey_set_free(without.conditioning.data);
  without.conditioning.data = NULL;
  double *tw = malloc(sizeof(double) * (size_t)runs), *to = malloc(sizeof(double) * (size_t)runs);
  karst_generate_stats_t sw, so;
  for (int r = 0; r < runs; r++) {
    tw[r] = run_once(&with, threads, &sw);
    to[r] = run_once(&without, threads, &so);
  }
  qsort(tw, (size_t)runs, sizeof *tw, cmp_double);
  qsort(to, (size_t)runs, sizeof *to, cmp_double);
  double mw = tw[runs / 2], mo = to[runs / 2];
  printf("%-28s samples %7lld / %7lld  legs %4lld  conditioned %.3f s  unconditioned %.3f s  "
         "(median of %d)  overhead %+.1f %%\n",
         label, (long long)sw.n_samples, (long long)so.n_samples, (long long)sw.n_observed_edges,
         mw, mo, runs, 100.0 * (mw - mo) / mo);
  free(tw), free(to);
  karst_scenario_destroy(&with);
  karst_scenario_destroy(&without);
}

int main(int argc, char **argv) {
  int runs = 5, threads = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--runs") && i + 1 < argc)
      runs = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
      threads = atoi(argv[++i]);
  }
  if (runs < 1) runs = 1;
  printf("bench_conditioning: dowprov_extension.yaml with and without its DowProv conditioning\n");
  bench("shipped sampling", 1.0, runs, threads);
  bench("finer sampling (r / 1.5)", 1.5, runs, threads);
  return 0;
}
