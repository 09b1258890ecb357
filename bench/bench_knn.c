/* Benchmark (not a test): the kNN graph for 100 k samples with k = 40, and a
 * 1.5-million-sample domain with k = 100 (sampling + kNN + undirected + edge
 * costs), as in issue 3, item 11. Prints, per stage, the wall time and the
 * process CPU time (all threads), the peak resident memory, and the load
 * average of the machine (other processes share its cores: compare wall
 * with CPU / threads). Each case runs `repeat` times and the fastest wall
 * time is printed (on a loaded machine the minimum is the least disturbed).
 * For each graph it also prints how much its coded neighbour indices take and how fast
 * they decode (adjacency_figures).
 * Usage: bench_knn [threads] [--small] [--repeat N]   (--small skips the 1.5 M run). */
#include <stdint.h>
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

static void print_load(const char *when) {
  double l[3] = {0, 0, 0};
  if (getloadavg(l, 3) == 3) printf("load average %s: %.2f %.2f %.2f\n", when, l[0], l[1], l[2]);
}

/* Stage boundaries of karst_graph_build, taken from its progress reports:
 * "neighbours" n/n when the search is done, "edge costs" 0 when the
 * symmetric structure is done, "edge costs" 1 at the end. */
enum { T_START, T_KNN, T_SYM, T_END, N_MARKS };
typedef struct {
  double wall[N_MARKS], cpu[N_MARKS];
} marks_t;
static void mark(marks_t *m, int i) {
  m->wall[i] = now(), m->cpu[i] = cpu_seconds();
}
static void on_progress(void *user, const char *stage, double done, double total) {
  marks_t *m = user;
  if (strcmp(stage, "neighbours") == 0 && done == total) mark(m, T_KNN);
  if (strcmp(stage, "edge costs") == 0 && done == 0) mark(m, T_SYM);
}

static void print_stage(const char *name, const marks_t *m, int a, int b) {
  printf("  %-22s wall %7.3f s  CPU %7.3f s\n", name, m->wall[b] - m->wall[a],
         m->cpu[b] - m->cpu[a]);
}

/* How the graph stores its neighbour indices (include/karst/graph.h: runs of one-byte gaps after
 * a run's first head): bytes per arc (a byte an arc, 4 per run, and the 8-byte row offset per
 * vertex), the arcs per run, and the time of one pass over all rows decoding them
 * (karst_arc_next) against reading a 32-bit copy (the fastest of the 2 passes after the one that
 * makes the copy, the sums of the indices compared), as one line in @p line. */
static void adjacency_figures(const karst_graph_t *g, char *line, size_t cap) {
  if (g->n_arcs == 0) {
    snprintf(line, cap, "  %-22s no arcs\n", "neighbour indices");
    return;
  }
  int32_t *adj = malloc(sizeof *adj * ((size_t)g->n_arcs + 1));
  if (!adj) {
    snprintf(line, cap, "  %-22s no memory for a 32-bit copy\n", "neighbour indices");
    return;
  }
  double t32 = 1e300, tcode = 1e300;
  uint64_t sum32 = 0, sumcode = 0;
  for (int r = 0; r < 3; r++) {
    double t0 = now();
    uint64_t s = 0;
    for (karst_int_t v = 0; v < g->n; v++) {
      karst_arc_reader_t rd = karst_graph_arcs(g, v);
      for (karst_int_t a = g->offsets[v]; a < g->offsets[v + 1]; a++) {
        karst_int_t w = karst_arc_next(&rd);
        s += (uint64_t)w;
        if (r == 0) adj[a] = (int32_t)w;
      }
    }
    double t1 = now();
    if (r > 0 && t1 - t0 < tcode) tcode = t1 - t0;
    sumcode = s;
    if (r == 0) continue;
    s = 0;
    for (karst_int_t a = 0; a < g->n_arcs; a++)
      s += (uint32_t)adj[a];
    double t2 = now();
    if (t2 - t1 < t32) t32 = t2 - t1;
    sum32 = s;
  }
  /* Every arc takes a byte; every run 4 more (its first head). */
  double runs = (double)(g->code_off[g->n] - g->n_arcs) / 4;
  snprintf(line, cap,
           "  %-22s coded %.3f B/arc (1 byte an arc, %.3f for the runs' first heads, %.3f for the "
           "rows' offsets) against 4 B/arc 32-bit; %.2f arcs a run; one pass %.2f ns/arc (32-bit "
           "copy), %.2f ns/arc (coded)%s\n",
           "neighbour indices", (g->code_off[g->n] + 8.0 * (g->n + 1)) / (double)g->n_arcs,
           4 * runs / (double)g->n_arcs, 8.0 * (g->n + 1) / (double)g->n_arcs,
           (double)g->n_arcs / runs, 1e9 * t32 / (double)g->n_arcs, 1e9 * tcode / (double)g->n_arcs,
           sum32 == sumcode ? "" : " -- the indices differ!");
  free(adj);
}

/* Build the graph `repeat` times; print the stages of the fastest run. */
static int run_graph(karst_ctx_t *ctx, const karst_scenario_t *sc, const karst_samples_t *s,
                     const char *label, int repeat) {
  karst_geology_t *geo = NULL;
  if (karst_geology_create(ctx, sc, 0, 0, &geo) != KARST_SUCCESS) {
    fprintf(stderr, "%s\n", ctx->errmsg);
    return 1;
  }
  marks_t best;
  memset(&best, 0, sizeof best);
  best.wall[T_END] = 1e300;
  karst_int_t edges = 0;
  char coded[512] = "";
  for (int r = 0; r < repeat; r++) {
    marks_t m;
    memset(&m, 0, sizeof m);
    ctx->progress = on_progress, ctx->progress_user = &m;
    karst_graph_t g;
    karst_graph_init(&g);
    mark(&m, T_START);
    karst_error_t e = karst_graph_build(ctx, geo, s, &g);
    mark(&m, T_END);
    ctx->progress = NULL;
    if (e != KARST_SUCCESS) {
      fprintf(stderr, "bench_knn: %s\n", ctx->errmsg);
      return 1;
    }
    edges = karst_graph_edge_count(&g);
    if (r == 0) adjacency_figures(&g, coded, sizeof coded);
    karst_graph_destroy(&g);
    if (m.wall[T_END] - m.wall[T_START] < best.wall[T_END] - best.wall[T_START]) best = m;
  }
  printf("%s: n = %lld, k = %d, %lld undirected edges (fastest of %d)\n", label, (long long)s->n,
         sc->sampling.k, (long long)edges, repeat);
  print_stage("kNN search", &best, T_START, T_KNN);
  print_stage("undirected (CSR)", &best, T_KNN, T_SYM);
  print_stage("edge costs", &best, T_SYM, T_END);
  print_stage("graph total", &best, T_START, T_END);
  fputs(coded, stdout);
  karst_geology_free(geo);
  return 0;
}

static int run_sampling(karst_ctx_t *ctx, const karst_scenario_t *sc, uint64_t seed,
                        karst_samples_t *s, const char *label, int repeat) {
  karst_geology_t *geo = NULL;
  if (karst_geology_create(ctx, sc, 0, 0, &geo) != KARST_SUCCESS) {
    fprintf(stderr, "%s\n", ctx->errmsg);
    return 1;
  }
  double best = 1e300, best_cpu = 0;
  for (int r = 0; r < repeat; r++) {
    karst_rng_t rng;
    karst_rng_init(&rng, seed, 0);
    double t0 = now(), c0 = cpu_seconds();
    if (karst_sampling_run(ctx, geo, &rng, s) != KARST_SUCCESS) {
      fprintf(stderr, "bench_knn: %s\n", ctx->errmsg);
      return 1;
    }
    double t = now() - t0, c = cpu_seconds() - c0;
    if (t < best) best = t, best_cpu = c;
  }
  int count[KARST_SAMPLE_SOURCE_COUNT] = {0};
  for (karst_int_t i = 0; i < s->n; i++)
    count[s->source[i]]++;
  printf("%s: %lld samples (%d horizon, %d water table, %d permeability, %d fill) "
         "(fastest of %d)\n",
         label, (long long)s->n, count[KARST_SAMPLE_HORIZON], count[KARST_SAMPLE_WATER_TABLE],
         count[KARST_SAMPLE_PERMEABILITY], count[KARST_SAMPLE_FILL], repeat);
  printf("  %-22s wall %7.3f s  CPU %7.3f s\n", "sampling", best, best_cpu);
  karst_geology_free(geo);
  return 0;
}

int main(int argc, char **argv) {
  int threads = 2, small = 0, repeat = 1;
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
  printf("bench_knn: %d thread(s), karst %s\n", ctx.nthreads, karst_version());
  print_load("at start");

  /* 1. 100 k uniform random samples in random order, k = 40, cost w0 only. */
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
  if (run_graph(&ctx, &sc, &s, "100k uniform, random order", repeat)) return 1;
  karst_samples_destroy(&s);
  /* The same size from the sampler (Morton-ordered, as the pipeline sees it):
   * a 300 x 300 x 100 m box at fill radius 3.9 m. */
  sc.domain_max[0] = sc.domain_max[1] = 300;
  sc.sampling.fill_radius = 3.9;
  karst_samples_init(&s);
  if (run_sampling(&ctx, &sc, 1, &s, "~100k sampled (fill only)", repeat)) return 1;
  if (run_graph(&ctx, &sc, &s, "~100k sampled", repeat)) return 1;
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
  printf("peak RSS so far: %.0f MiB\n", peak_rss_mib());
  if (small) {
    print_load("at end");
    return 0;
  }

  /* 2. A 2 x 2 km x 250 m limestone plateau under a flat terrain at 200 m:
   * one inception horizon, the water table, three fracture families, a
   * permeable sphere; fill radius chosen for about 1.5 M samples. */
  karst_scenario_init(&sc);
  sc.domain_max[0] = 2000, sc.domain_max[1] = 2000, sc.domain_max[2] = 250;
  sc.domain_min[2] = 0;
  sc.terrain.elevation = 200;
  sc.water_table.given = 1, sc.water_table.elevation = 60;
  /* One spring, whose water table the feature samples follow. */
  sc.n_key_points = 1;
  sc.key_points = calloc(1, sizeof *sc.key_points);
  sc.key_points[0].type = KARST_KEYPOINT_SPRING;
  sc.key_points[0].p[0] = 1000, sc.key_points[0].p[1] = 1000, sc.key_points[0].p[2] = 60;
  strcpy(sc.key_points[0].name, "spring");
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
  double t0 = now(), c0 = cpu_seconds();
  if (run_sampling(&ctx, &sc, 2, &s, "1.5M domain", 1)) return 1;
  if (run_graph(&ctx, &sc, &s, "1.5M domain", 1)) return 1;
  printf("1.5M domain: sampling + graph wall %.3f s, CPU %.3f s, peak RSS %.0f MiB\n", now() - t0,
         cpu_seconds() - c0, peak_rss_mib());
  karst_samples_destroy(&s);
  karst_scenario_destroy(&sc);
  print_load("at end");
  return 0;
}
