/* Benchmark (not a test): what two threads get of the memory compared with one, the ceiling of
 * the speed-up of a stage limited by memory (issue 17, item 1: >= 1.85x on 2 threads).
 * - stream: each thread sums its own 512 MiB array, 4 passes (the reads of a sweep over arcs);
 * - lines: each thread sums 2 x 32 M entries of its own 1 GiB array at random independent indices,
 *   one 64-byte line each (the node records a search relaxes: many misses in flight).
 * The same work per thread on 1 and on 2 threads: the ratio of the throughputs is the speed-up
 * the memory allows. Each figure is the fastest of 3 runs, the arrays filled (faulted in) first.
 * Usage: bench_memory [--threads T] (default 2). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/parallel_internal.h"
#include "generate/generate_internal.h"

#define STREAM_WORDS ((size_t)1 << 26) /* 512 MiB of uint64_t per thread */
#define LINE_WORDS ((size_t)1 << 27)   /* 1 GiB per thread */
#define LINE_LOADS ((size_t)1 << 25)

typedef struct {
  uint64_t *a[KARST_I_MAX_THREADS];
  uint32_t *idx;
  int lines;
  uint64_t sum[KARST_I_MAX_THREADS];
} job_t;

static void task(void *arg, int tid, int nth) {
  (void)nth;
  job_t *J = arg;
  const uint64_t *a = J->a[tid];
  uint64_t s = 0;
  if (J->lines) {
    for (int rep = 0; rep < 2; rep++)
      for (size_t i = 0; i < LINE_LOADS; i++)
        s += a[J->idx[i]];
  } else {
    for (int rep = 0; rep < 4; rep++) {
      __asm__ volatile("" ::: "memory"); /* four passes, not one times four */
      for (size_t i = 0; i < STREAM_WORDS; i++)
        s += a[i];
    }
  }
  J->sum[tid] = s;
}

int main(int argc, char **argv) {
  int threads = 2;
  for (int i = 1; i < argc; i++)
    if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) threads = atoi(argv[++i]);
  if (threads < 2 || threads > 8) threads = 2;
  static job_t J;
  J.idx = malloc(LINE_LOADS * sizeof *J.idx);
  if (!J.idx) return printf("bench_memory: out of memory\n"), 0;
  uint64_t r = 88172645463325252ULL; /* xorshift64: indices spread over the whole array */
  for (size_t i = 0; i < LINE_LOADS; i++) {
    r ^= r << 13, r ^= r >> 7, r ^= r << 17;
    J.idx[i] = (uint32_t)(r % LINE_WORDS) & ~(uint32_t)7; /* the first word of a line */
  }
  for (int lines = 0; lines <= 1; lines++) {
    const size_t words = lines ? LINE_WORDS : STREAM_WORDS;
    for (int t = 0; t < threads; t++) {
      J.a[t] = malloc(words * sizeof(uint64_t));
      if (!J.a[t]) return printf("bench_memory: out of memory\n"), 0;
      for (size_t i = 0; i < words; i++)
        J.a[t][i] = i;
    }
    J.lines = lines;
    double best[2] = {1e30, 1e30};
    for (int run = 0; run < 3; run++)
      for (int k = 0; k < 2; k++) {
        double t0 = karst_i_now();
        karst_i_parallel_run(k ? threads : 1, task, &J);
        double dt = karst_i_now() - t0;
        if (dt < best[k]) best[k] = dt;
      }
    const double bytes = lines ? 2.0 * (double)LINE_LOADS * 64 : 4.0 * (double)words * 8;
    printf("memory %-6s 1 thread %.3f s (%.1f GB/s), %d threads %.3f s (%.1f GB/s): "
           "throughput x%.2f\n",
           lines ? "lines" : "stream", best[0], bytes / best[0] / 1e9, threads, best[1],
           threads * bytes / best[1] / 1e9, threads * best[0] / best[1]);
    for (int t = 0; t < threads; t++)
      free(J.a[t]);
  }
  free(J.idx);
  return 0;
}
