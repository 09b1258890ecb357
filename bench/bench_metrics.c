/* Benchmark: metrics of Sakany (target <= 5 ms; Karstnet 1.2.0 takes 0.34 s) and of a
 * synthetic network of about one million edges (target <= 10 s on 2 cores), and the
 * all-sources BFS of src/metrics/paths.c against igraph 0.10 on reduced-graph-sized lattices. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "igraph/paths_igraph.h"
#include "karst.h"
#include "metrics/metrics_internal.h"

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A cave-like synthetic network: G x G junctions on a 100 m grid (jittered in 3-D), each
 * grid conduit kept with probability 0.9 and drawn as K survey shots through jittered
 * stations. The reduced graph is the kept junction lattice (about G^2 nodes). */
static int synthetic(karst_network_t *net, int G, int K, karst_int_t **conduits,
                     karst_int_t *nconduits) {
  karst_rng_t rng;
  karst_rng_init(&rng, 2021, 0);
  karst_network_init(net);
  *conduits = malloc(sizeof(karst_int_t) * 2 * 2 * G * G);
  *nconduits = 0;
  for (int j = 0; j < G; j++)
    for (int i = 0; i < G; i++)
      if (karst_network_add_node(net, 100.0 * i + karst_rng_uniform_range(&rng, -20, 20),
                                 100.0 * j + karst_rng_uniform_range(&rng, -20, 20),
                                 karst_rng_uniform_range(&rng, -50, 0), NULL))
        return -1;
  for (int j = 0; j < G; j++)
    for (int i = 0; i < G; i++)
      for (int d = 0; d < 2; d++) {
        int i2 = i + (d == 0), j2 = j + (d == 1);
        if (i2 >= G || j2 >= G || karst_rng_uniform(&rng) >= 0.9) continue;
        karst_int_t a = (karst_int_t)j * G + i, b = (karst_int_t)j2 * G + i2, prev = a;
        (*conduits)[2 * *nconduits] = a;
        (*conduits)[2 * *nconduits + 1] = b;
        (*nconduits)++;
        for (int k = 1; k < K; k++) {
          double t = (double)k / K;
          const double *pa = net->xyz + 3 * a, *pb = net->xyz + 3 * b;
          karst_int_t s;
          if (karst_network_add_node(net, pa[0] + t * (pb[0] - pa[0]) + karst_rng_gaussian(&rng),
                                     pa[1] + t * (pb[1] - pa[1]) + karst_rng_gaussian(&rng),
                                     pa[2] + t * (pb[2] - pa[2]) + karst_rng_gaussian(&rng), &s) ||
              karst_network_add_edge(net, prev, s, NULL))
            return -1;
          prev = s;
        }
        if (karst_network_add_edge(net, prev, b, NULL)) return -1;
      }
  return 0;
}

/* Own parallel BFS vs igraph on the G x G lattice (the reduced graph of the synthetic network). */
static void compare_igraph(karst_ctx_t *ctx, int G) {
  karst_network_t net;
  karst_int_t *cond, nc;
  if (synthetic(&net, G, 1, &cond, &nc)) return;
  karst_i_csr_t g;
  if (karst_i_csr_build(ctx, (karst_int_t)G * G, nc, cond, &g)) return;
  double *b = malloc(sizeof(double) * g.n);
  karst_int_t *d = malloc(sizeof(karst_int_t) * g.n);
  int saved = ctx->nthreads;
  double t0 = now();
  ctx->nthreads = 1;
  karst_i_paths_all_sources(ctx, &g, b, d);
  double t1 = now();
  ctx->nthreads = saved;
  karst_i_paths_all_sources(ctx, &g, b, d);
  double t2 = now();
  karst_i_paths_igraph(ctx, &g, b, d);
  double t3 = now();
  printf(
      "bench_metrics: reduced-graph-sized lattice N = %lld, S = %lld: own BFS %.3f s (1 thread), "
      "%.3f s (%d threads); igraph betweenness + distances %.3f s\n",
      (long long)g.n, (long long)nc, t1 - t0, t2 - t1, saved, t3 - t2);
  free(b);
  free(d);
  free(cond);
  karst_i_csr_destroy(&g);
  karst_network_destroy(&net);
}

int main(void) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  ctx.nthreads = ncpu > 1 ? (int)(ncpu < 2 ? ncpu : 2) : 1;
  printf("bench_metrics: %ld online cores, using %d threads\n", ncpu, ctx.nthreads);

  karst_network_t sak;
  karst_network_init(&sak);
  if (karst_read_karstnet(&ctx, KARST_SOURCE_DIR "/datasets/surveys/karstnet/Sakany_nodes.dat",
                          &sak)) {
    fprintf(stderr, "bench_metrics: %s\n", ctx.errmsg);
    return 1;
  }
  karst_metrics_t m;
  for (int threads = 1; threads <= ctx.nthreads; threads++) {
    karst_ctx_t c = ctx;
    c.nthreads = threads;
    const int reps = 200;
    double best = 1e30, total = 0;
    for (int r = 0; r < reps; r++) {
      double t0 = now();
      karst_metrics_compute(&c, &sak, NULL, &m);
      double dt = now() - t0;
      total += dt;
      if (dt < best) best = dt;
    }
    printf("bench_metrics: Sakany (%lld nodes, %lld edges; Gs %lld/%lld): metrics %.3f ms "
           "(mean of %d), best %.3f ms, %d thread%s [target <= 5 ms; Karstnet 0.34 s]\n",
           (long long)m.nodes, (long long)m.edges, (long long)m.reduced_nodes,
           (long long)m.reduced_edges, 1e3 * total / reps, reps, 1e3 * best, threads,
           threads > 1 ? "s" : "");
  }
  karst_network_destroy(&sak);

  compare_igraph(&ctx, 20);
  compare_igraph(&ctx, 100);

  karst_network_t big;
  karst_int_t *cond, nc;
  if (synthetic(&big, 100, 56, &cond, &nc)) {
    fprintf(stderr, "bench_metrics: out of memory\n");
    return 1;
  }
  free(cond);
  double t0 = now();
  if (karst_metrics_compute(&ctx, &big, NULL, &m)) {
    fprintf(stderr, "bench_metrics: %s\n", ctx.errmsg);
    return 1;
  }
  double dt = now() - t0;
  printf("bench_metrics: synthetic network %lld nodes, %lld edges (Gs %lld nodes, %lld edges, "
         "%lld cycles): metrics %.2f s with %d threads [target <= 10 s on 2 cores]\n",
         (long long)m.nodes, (long long)m.edges, (long long)m.reduced_nodes,
         (long long)m.reduced_edges, (long long)m.cycles, dt, ctx.nthreads);
  karst_network_destroy(&big);
  return 0;
}
