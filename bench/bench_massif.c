/*
 * Benchmark (not a test): the regional-scale scenario datasets/scenarios/massif.yaml (a 5 x 5 km
 * karst massif 500 m thick, about 10 million samples, k = 40, 80 sinks, 3 springs, 3 horizons,
 * 3 fracture families; written by datasets/scenarios/massif/make_massif.py), run as a user runs
 * it: `karst generate massif.yaml -o DIR --threads T` (progress shown when standard error is a
 * terminal). Prints the wall time, the peak resident memory and the stage times and counts of
 * DIR/run.json. Targets (issue 17): <= 5 minutes and <= 12 GB on the 2-core project machine.
 *
 *   bench_massif [THREADS]     (default 2)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "bench_spawn.h"

int main(int argc, char **argv) {
  const char *threads = argc > 1 ? argv[1] : "2";
  if (atoi(threads) < 1) {
    fprintf(stderr, "usage: bench_massif [THREADS >= 1]\n");
    return 2;
  }
  char dir[] = "/tmp/karst_bench_massif_XXXXXX";
  if (!bench_mkdtemp(dir, "bench_massif")) return 1;
  char *run[] = {(char *)KARST_CLI,
                 "generate",
                 KARST_SOURCE_DIR "/datasets/scenarios/massif.yaml",
                 "-o",
                 dir,
                 "--threads",
                 (char *)threads,
                 NULL};
  long rss = 0;
  double wall = bench_run(run, &rss);
  int status = 0;
  if (wall < 0) {
    fprintf(stderr, "bench_massif: karst generate failed\n");
    status = 1;
  } else {
    const char *json = bench_run_json(dir);
    static const char *stages[] = {"sampling", "graph",         "paths",
                                   "skeleton", "amplification", "classification"};
    printf("bench_massif: massif.yaml, %s threads: %.1f s wall (target <= 300 s), peak RSS %.2f "
           "GiB (target <= 12 GB = 11.18 GiB); %.0f samples, %.0f graph edges, %.0f key points, "
           "%.0f network edges\n",
           threads, wall, rss / 1048576.0, bench_json_number(json, "counts", "samples"),
           bench_json_number(json, "counts", "graph_edges"),
           bench_json_number(json, "counts", "key_points"),
           bench_json_number(json, "counts", "network_edges"));
    printf("bench_massif: stages");
    for (int s = 0; s < 6; s++)
      printf(" %s %.2f s", stages[s], bench_json_number(json, "stage_seconds", stages[s]));
    printf("\n");
  }
  bench_remove_dir(dir, "bench_massif");
  return status;
}
