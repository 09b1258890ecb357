/* Benchmark: random stream throughput (draws per second). */
#include <stdio.h>
#include <time.h>

#include "karst.h"

int main(void) {
  karst_rng_t r;
  karst_rng_init(&r, 1, 0);
  const long n = 100000000;
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  double s = 0;
  for (long i = 0; i < n; i++) s += karst_rng_uniform(&r);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  double dt = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  printf("bench_rng: %ld uniform draws in %.3f s (%.1f M/s), mean %.6f\n", n, dt, n / dt / 1e6, s / n);
  return 0;
}
