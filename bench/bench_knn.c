/* Benchmark (not a test): the kNN graph for 100 k samples with k = 40, and a
 * 1.5-million-sample domain with k = 100 (sampling + kNN + edge costs), as in
 * issue 3, item 11. Prints wall times per stage and the peak resident memory.
 * Usage: bench_knn [threads] [--small]  (--small skips the 1.5 M run). */
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

static double peak_rss_mib(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0; /* Linux: KiB */
}

/* The graph stage reports "edge costs" 0 when the neighbour search and the
 * symmetrisation are done: record that instant to split the two. */
typedef struct {
  double t_costs;
} marks_t;
static void on_progress(void *user, const char *stage, double done, double total) {
  (void)total;
  if (strcmp(stage, "edge costs") == 0 && done == 0) ((marks_t *)user)->t_costs = now();
}

static int run_graph(karst_ctx_t *ctx, const karst_scenario_t *sc, const karst_samples_t *s,
                     const char *label) {
  marks_t m = {0};
  ctx->progress = on_progress, ctx->progress_user = &m;
  karst_graph_t g;
  karst_graph_init(&g);
  double t0 = now(), c0 = cpu_seconds();
  karst_error_t e = karst_graph_build(ctx, sc, s, &g);
  double t1 = now(), c1 = cpu_seconds();
  if (e != KARST_SUCCESS) {
    fprintf(stderr, "bench_knn: %s\n", ctx->errmsg);
    return 1;
  }
  printf("%-28s n = %lld, k = %d, %lld edges: kNN + undirected %.3f s, costs %.3f s, "
         "total %.3f s (CPU %.3f s)\n",
         label, (long long)s->n, sc->sampling.k, (long long)karst_graph_edge_count(&g),
         m.t_costs - t0, t1 - m.t_costs, t1 - t0, c1 - c0);
  karst_graph_destroy(&g);
  return 0;
}

int main(int argc, char **argv) {
  int threads = argc > 1 ? atoi(argv[1]) : 2, small = argc > 2 && strcmp(argv[2], "--small") == 0;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = threads > 0 ? threads : 1;
  printf("bench_knn: %d thread(s)\n", ctx.nthreads);

  /* 1. 100 k uniform random samples, k = 40, cost w0 only. */
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  sc.terrain.elevation = 1000;
  sc.sampling.k = 40;
  sc.cost.horizon = sc.cost.fracture = sc.cost.permeability = 0;
  karst_samples_t s;
  karst_samples_init(&s);
  karst_rng_t r;
  karst_rng_init(&r, 1, 0);
  for (int i = 0; i < 100000; i++) {
    double p[3] = {karst_rng_uniform_range(&r, 0, 100), karst_rng_uniform_range(&r, 0, 100),
                   karst_rng_uniform_range(&r, 0, 100)};
    karst_samples_add(&s, p, KARST_SAMPLE_FILL);
  }
  if (run_graph(&ctx, &sc, &s, "100k random order, k = 40")) return 1;
  karst_samples_destroy(&s);
  /* The same size from the sampler (Morton-ordered, as the pipeline sees it):
   * a 300 x 300 x 100 m box at fill radius 3.9 m. */
  sc.domain_max[0] = sc.domain_max[1] = 300;
  sc.sampling.fill_radius = 3.9;
  sc.water_table = -100;
  karst_samples_init(&s);
  double ts = now(), cs = cpu_seconds();
  if (karst_sampling_run(&ctx, &sc, &r, &s) != KARST_SUCCESS) {
    fprintf(stderr, "bench_knn: %s\n", ctx.errmsg);
    return 1;
  }
  printf("%-28s %lld samples in %.3f s (CPU %.3f s)\n", "sampling (fill only)", (long long)s.n,
         now() - ts, cpu_seconds() - cs);
  if (run_graph(&ctx, &sc, &s, "sampled ~100k, k = 40")) return 1;
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
  printf("peak RSS so far: %.0f MiB\n", peak_rss_mib());
  if (small) return 0;

  /* 2. A 2 x 2 km x 250 m limestone plateau under a flat terrain at 200 m:
   * one inception horizon, the water table, three fracture families, a
   * permeable sphere; fill radius chosen for about 1.5 M samples. */
  karst_scenario_init(&sc);
  sc.domain_max[0] = 2000, sc.domain_max[1] = 2000, sc.domain_max[2] = 250;
  sc.domain_min[2] = 0;
  sc.terrain.elevation = 200;
  sc.water_table = 60;
  sc.sampling.fill_radius = 7.2, sc.sampling.feature_radius = 5, sc.sampling.feature_band = 1;
  sc.sampling.k = 100;
  sc.n_horizons = 1;
  sc.horizons = calloc(1, sizeof(karst_horizon_t));
  sc.horizons[0].elevation = 120, sc.horizons[0].radius = 10, sc.horizons[0].dip = 3;
  sc.horizons[0].dip_direction = 45, sc.horizons[0].origin[0] = 1000,
  sc.horizons[0].origin[1] = 1000;
  sc.n_fractures = 3;
  sc.fractures = calloc(3, sizeof(karst_fracture_t));
  const double F[3][3] = {{0, 90, 0.5}, {90, 90, 0.5}, {30, 70, 0.3}};
  for (int i = 0; i < 3; i++)
    sc.fractures[i].dip_direction = F[i][0], sc.fractures[i].dip = F[i][1],
    sc.fractures[i].weight = F[i][2];
  sc.permeability.root = calloc(1, sizeof(karst_perm_node_t));
  karst_perm_node_t *sp = sc.permeability.root;
  sp->kind = KARST_PERM_SPHERE, sp->center[0] = 600, sp->center[1] = 1400, sp->center[2] = 80;
  sp->radius = 40, sp->falloff = 20, sp->resistance = 0.1;
  karst_samples_init(&s);
  karst_rng_init(&r, 2, 0);
  double t0 = now(), c0 = cpu_seconds();
  if (karst_sampling_run(&ctx, &sc, &r, &s) != KARST_SUCCESS) {
    fprintf(stderr, "bench_knn: %s\n", ctx.errmsg);
    return 1;
  }
  double t1 = now();
  int count[KARST_SAMPLE_SOURCE_COUNT] = {0};
  for (karst_int_t i = 0; i < s.n; i++)
    count[s.source[i]]++;
  printf("%-28s %lld samples (%d horizon, %d water table, %d permeability, %d fill) in %.3f s "
         "(CPU %.3f s)\n",
         "1.5M domain sampling", (long long)s.n, count[KARST_SAMPLE_HORIZON],
         count[KARST_SAMPLE_WATER_TABLE], count[KARST_SAMPLE_PERMEABILITY],
         count[KARST_SAMPLE_FILL], t1 - t0, cpu_seconds() - c0);
  if (run_graph(&ctx, &sc, &s, "1.5M domain, k = 100")) return 1;
  printf("1.5M domain: sampling + graph %.3f s, peak RSS %.0f MiB\n", now() - t0, peak_rss_mib());
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
  return 0;
}
