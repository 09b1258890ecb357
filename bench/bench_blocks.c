/* Benchmark (not a test): one tile of each block type with the defaults of
 * Paris et al. 2020 (20 m, about 14 500 points), as Table 1 of the paper,
 * and the two radius-graph searches (our periodic grid, FLANN on ghosts) on
 * the same points. Prints, per type, #P, #D, #B, mean points per block and
 * the fastest wall time of `repeat` runs (on a shared machine the minimum is
 * the least disturbed), the CPU time and the load average.
 * Usage: bench_blocks [threads] [--repeat N] [--csv FILE] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "blocks/blocks_internal.h"
#include "karst.h"
#include "karst/blocks.h"

/** Blocks with fewer sample points than this are counted apart ("#B>=10"). */
#define KARST_BENCH_BLOCKS_SMALL 10

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

int main(int argc, char **argv) {
  int threads = 2, repeat = 3;
  const char *csv = NULL;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--csv") && i + 1 < argc)
      csv = argv[++i];
    else
      threads = atoi(argv[i]);
  }
  if (threads < 1) threads = 1;
  if (repeat < 1) repeat = 1;
  double l[3] = {0, 0, 0};
  if (getloadavg(l, 3) == 3) printf("load average before: %.2f %.2f %.2f\n", l[0], l[1], l[2]);
  printf("bench_blocks: one tile per type (Paris et al. 2020, Table 1), %d threads, best of %d\n",
         threads, repeat);
  printf("%-16s %7s %4s %5s %7s %6s %7s %9s %9s\n", "type", "#P", "#D", "#B", "mean P", "#B>=10",
         "mean", "wall (s)", "CPU (s)");
  FILE *out = csv ? fopen(csv, "w") : NULL;
  if (out)
    fprintf(out,
            "type,points,discs,blocks,mean_points,blocks_10,mean_points_10,seconds,cpu_seconds,"
            "threads\n");
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = threads;
  int status = 0;
  for (int type = 0; type < KARST_BLOCK_TYPE_COUNT; type++) {
    double best = 1e300, cpu = 0;
    karst_blocks_tile_stats_t st;
    memset(&st, 0, sizeof st);
    long long big = 0, big_points = 0;
    for (int r = 0; r < repeat; r++) {
      karst_blocks_tile_params_t p;
      karst_blocks_tile_params_init(&p, type);
      karst_blocks_tile_t *T = NULL;
      double c0 = cpu_seconds(), t0 = now();
      if (karst_blocks_tile_create(&ctx, &p, &T)) {
        fprintf(stderr, "bench_blocks: %s\n", ctx.errmsg);
        status = 1;
        break;
      }
      double w = now() - t0;
      double c = cpu_seconds() - c0;
      if (w < best) {
        best = w, cpu = c, st = T->stats, big = big_points = 0;
        for (karst_int_t b = 0; b < T->n_blocks; b++)
          if (T->blocks[b].n_points >= KARST_BENCH_BLOCKS_SMALL)
            big++, big_points += T->blocks[b].n_points;
      }
      karst_blocks_tile_free(T);
    }
    double big_mean = big ? (double)big_points / (double)big : 0;
    printf("%-16s %7lld %4lld %5lld %7.0f %6lld %7.0f %9.3f %9.3f\n", karst_block_type_name(type),
           (long long)st.n_points, (long long)st.n_discs, (long long)st.n_blocks, st.mean_points,
           big, big_mean, best, cpu);
    if (out)
      fprintf(out, "%s,%lld,%lld,%lld,%.1f,%lld,%.1f,%.3f,%.3f,%d\n", karst_block_type_name(type),
              (long long)st.n_points, (long long)st.n_discs, (long long)st.n_blocks, st.mean_points,
              big, big_mean, best, cpu, threads);
  }
  /* the radius graph: grid against FLANN on the same 20 m tile of points */
  karst_rng_t rng;
  karst_rng_init(&rng, 1, 1);
  double *x = NULL;
  karst_int_t n = 0;
  karst_blocks_tile_params_t p;
  karst_blocks_tile_params_init(&p, 0);
  if (karst_i_blocks_poisson(&ctx, p.size, p.poisson_radius, p.dart_passes, &rng, &x, &n) == 0) {
    for (int m = 0; m < 2; m++) {
      double best = 1e300;
      karst_int_t ne = 0;
      for (int r = 0; r < repeat; r++) {
        karst_i_edge_t *e = NULL;
        double t0 = now();
        karst_error_t err =
            m ? karst_i_blocks_radius_graph_flann(&ctx, x, n, p.size, p.graph_radius, &e, &ne)
              : karst_i_blocks_radius_graph(&ctx, x, n, p.size, p.graph_radius, &e, &ne);
        double w = now() - t0;
        if (!err && w < best) best = w;
        free(e);
      }
      printf("radius graph (%s): %lld points, %lld edges, %.4f s\n", m ? "FLANN + ghosts" : "grid",
             (long long)n, (long long)ne, best);
    }
  }
  free(x);
  if (out) fclose(out);
  if (getloadavg(l, 3) == 3) printf("load average after: %.2f %.2f %.2f\n", l[0], l[1], l[2]);
  return status;
}
