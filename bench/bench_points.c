/*
 * Benchmark (not a test): reading a point cloud for sampling.points (karst_points_load), the
 * step a regional cloud of millions of points costs before any sampling. Writes a cloud of N
 * random points over a 5 x 5 km x 500 m block (the massif's extent) in a scratch directory, in
 * two spellings: shortest round-trip digits (what Python's repr or a careful exporter writes:
 * mostly 16-17 significant digits) and millimetres (%.3f, what a surveying export writes), then
 * prints the fastest of R reads of each: seconds, points per second and nanoseconds per number.
 *
 *   bench_points [N] [--repeat R]      (default N = 2 000 000, R = 3)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_spawn.h"
#include "karst.h"

static int write_cloud(const char *path, long n, int mm, karst_rng_t *rng) {
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  fputs("x y z\n", f);
  const double lo[3] = {600000, 4800000, 0}, ext[3] = {5000, 5000, 500};
  for (long i = 0; i < n; i++) {
    char c[3][32];
    for (int a = 0; a < 3; a++) {
      double x = lo[a] + ext[a] * karst_rng_uniform(rng);
      if (mm)
        snprintf(c[a], sizeof c[a], "%.3f", x);
      else
        bench_shortest_double(c[a], sizeof c[a], x);
    }
    fprintf(f, "%s %s %s\n", c[0], c[1], c[2]);
  }
  return fclose(f) == 0 ? 0 : -1;
}

int main(int argc, char **argv) {
  long n = 2000000;
  int repeat = 3;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc)
      repeat = atoi(argv[++i]);
    else
      n = atol(argv[i]);
  }
  if (n < 1 || n > KARST_POINTS_MAX_POINTS || repeat < 1) {
    fprintf(stderr, "usage: bench_points [N in 1..%d] [--repeat R >= 1]\n",
            KARST_POINTS_MAX_POINTS);
    return 2;
  }
  char dir[] = "/tmp/karst_bench_points_XXXXXX";
  if (!bench_mkdtemp(dir, "bench_points")) return 1;
  int status = 0;
  karst_rng_t rng;
  karst_rng_init(&rng, 17, 0);
  printf("bench_points: karst_points_load, %ld points, fastest of %d\n", n, repeat);
  for (int mm = 0; mm <= 1; mm++) {
    char path[256];
    snprintf(path, sizeof path, "%s/cloud_%s.xyz", dir, mm ? "mm" : "shortest");
    if (write_cloud(path, n, mm, &rng) != 0) {
      fprintf(stderr, "bench_points: cannot write %s\n", path);
      status = 1;
      break;
    }
    double best = 1e300;
    for (int r = 0; r < repeat; r++) {
      karst_ctx_t ctx;
      karst_ctx_init(&ctx);
      double *xyz = NULL;
      karst_int_t got = 0;
      double t0 = bench_now_s();
      karst_error_t err = karst_points_load(&ctx, path, &xyz, &got, NULL);
      double t = bench_now_s() - t0;
      free(xyz);
      if (err != KARST_SUCCESS || got != n) {
        fprintf(stderr, "bench_points: %s: %s (%lld points)\n", path, ctx.errmsg, (long long)got);
        status = 1;
        break;
      }
      if (t < best) best = t;
    }
    if (status) break;
    printf("%-34s %.3f s, %.2f M points/s, %.0f ns per coordinate\n",
           mm ? "millimetres (%.3f)" : "shortest round-trip digits", best, n / best / 1e6,
           1e9 * best / (3.0 * (double)n));
  }
  bench_remove_dir(dir, "bench_points");
  return status;
}
