/* Benchmark (not a test): adaptive Poisson sampling alone, on the ~100 k
 * fill-only box of bench_knn and on its 1.5-million-sample domain (horizon,
 * water table, three fracture families, permeable sphere). Prints the
 * fastest wall time of `repeat` runs with its process CPU time, the sample
 * counts, whether the samples are identical for 1 thread and for the
 * requested threads, and the machine's load average.
 * Usage: bench_sampling [threads] [--small] [--repeat N] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "karst.h"

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double cpu_seconds(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec +
         1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

static void print_load(const char *when) {
  double l[3] = {0, 0, 0};
  if (getloadavg(l, 3) == 3) printf("load average %s: %.2f %.2f %.2f\n", when, l[0], l[1], l[2]);
}

static int run(karst_ctx_t *ctx, const karst_scenario_t *sc, const char *label, int repeat) {
  karst_geology_t *geo = NULL;
  if (karst_geology_create(ctx, sc, 0, 0, &geo) != KARST_SUCCESS) {
    fprintf(stderr, "%s\n", ctx->errmsg);
    return 1;
  }
  double best = 1e300, best_cpu = 0;
  karst_samples_t s, s1;
  karst_samples_init(&s), karst_samples_init(&s1);
  for (int r = 0; r < repeat; r++) {
    karst_rng_t rng;
    karst_rng_init(&rng, 7, 0);
    double t0 = now(), c0 = cpu_seconds();
    if (karst_sampling_run(ctx, geo, &rng, &s) != KARST_SUCCESS) {
      fprintf(stderr, "bench_sampling: %s\n", ctx->errmsg);
      return 1;
    }
    double t = now() - t0, c = cpu_seconds() - c0;
    if (t < best) best = t, best_cpu = c;
  }
  /* The same stream with one thread must give the same samples. */
  karst_ctx_t one = *ctx;
  one.nthreads = 1;
  karst_rng_t rng;
  karst_rng_init(&rng, 7, 0);
  if (karst_sampling_run(&one, geo, &rng, &s1) != KARST_SUCCESS) return 1;
  int same = s.n == s1.n && memcmp(s.xyz, s1.xyz, sizeof(double) * 3 * (size_t)s.n) == 0;
  int count[KARST_SAMPLE_SOURCE_COUNT] = {0};
  for (karst_int_t i = 0; i < s.n; i++)
    count[s.source[i]]++;
  printf("%s: %lld samples (%d horizon, %d water table, %d permeability, %d fill)\n", label,
         (long long)s.n, count[KARST_SAMPLE_HORIZON], count[KARST_SAMPLE_WATER_TABLE],
         count[KARST_SAMPLE_PERMEABILITY], count[KARST_SAMPLE_FILL]);
  printf("  fastest of %d: wall %.3f s, CPU %.3f s; identical to 1 thread: %s\n", repeat, best,
         best_cpu, same ? "yes" : "NO");
  karst_samples_destroy(&s), karst_samples_destroy(&s1);
  karst_geology_free(geo);
  return same ? 0 : 1;
}

int main(int argc, char **argv) {
  int threads = 2, small = 0, repeat = 3;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--small") == 0)
      small = 1;
    else if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc)
      repeat = atoi(argv[++i]);
    else
      threads = atoi(argv[i]);
  }
  if (repeat < 1) repeat = 1;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = threads > 0 ? threads : 1;
  printf("bench_sampling: %d thread(s)\n", ctx.nthreads);
  print_load("at start");

  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.terrain.elevation = 1000;
  sc.domain_max[0] = sc.domain_max[1] = 300;
  sc.sampling.fill_radius = 3.9;
  if (run(&ctx, &sc, "300 x 300 x 100 m, fill only", repeat)) return 1;
  karst_scenario_destroy(&sc);
  if (!small) {
    karst_scenario_init(&sc);
    sc.domain_max[0] = 2000, sc.domain_max[1] = 2000, sc.domain_max[2] = 250;
    sc.terrain.elevation = 200;
    sc.water_table.given = 1, sc.water_table.elevation = 60;
    /* One spring, whose water table the feature samples follow. */
    sc.n_key_points = 1;
    sc.key_points = calloc(1, sizeof *sc.key_points);
    sc.key_points[0].type = KARST_KEYPOINT_SPRING;
    sc.key_points[0].p[0] = 1000, sc.key_points[0].p[1] = 1000, sc.key_points[0].p[2] = 60;
    strcpy(sc.key_points[0].name, "spring");
    sc.sampling.fill_radius = 7.2, sc.sampling.feature_radius = 5, sc.sampling.feature_band = 1;
    sc.n_horizons = 1;
    sc.horizons = calloc(1, sizeof(karst_horizon_t));
    sc.horizons[0].elevation = 120, sc.horizons[0].radius = 10, sc.horizons[0].dip = 3;
    sc.horizons[0].dip_direction = 45, sc.horizons[0].origin[0] = 1000,
    sc.horizons[0].origin[1] = 1000;
    sc.permeability.root = calloc(1, sizeof(karst_perm_node_t));
    karst_perm_node_t *sp = sc.permeability.root;
    sp->kind = KARST_PERM_SPHERE, sp->center[0] = 600, sp->center[1] = 1400, sp->center[2] = 80;
    sp->radius = 40, sp->falloff = 20, sp->resistance = 0.1;
    if (run(&ctx, &sc, "1.5M domain (2 x 2 km x 250 m)", 1)) return 1;
    karst_scenario_destroy(&sc);
  }
  print_load("at end");
  return 0;
}
