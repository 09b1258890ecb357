/*
 * Benchmark (not a test): karst on the same work as the two peer generators whose figures
 * docs/performance.md records, whole process (`karst generate SCENARIO -o DIR --threads 1`,
 * the CLI as a user runs it: start-up, parsing, every stage, every output file), one thread.
 *
 *   1. Karst-Synthesis (Paris et al. 2021's code, aparis69/Karst-Synthesis at 386b243), its
 *      rectilinear scene (Code/Source/main.cpp, RectilinearMazeNetwork): about 23 450 samples in
 *      2000 x 2000 x 250 m, k = 32, the scene's 7 sinks, 5 springs and the 10 waypoints that lie
 *      in the sampled slab, three axis-aligned fracture directions of weight 10, gamma 2, plain
 *      union of the least-cost paths, 10 amplification points (half dead ends); one uniform
 *      cloud, as the peer's, with no layer sampled finely around the springs' water tables
 *      (sampling.refine: [], since the peer has no water table).
 *   2. KarstNSim (Gouy et al. 2024, ISSKA/KarstNSim_Public at fd31889), its shipped example
 *      (Input_files/instructions.txt): about 115 000 samples, k = 100, 5 sinks all draining to
 *      spring 1 (its connectivity matrix), 2 springs each with its own water table, 2 inception
 *      horizons, 2 vertical fracture families (azimuths 0 and 60 degrees, weight 0.5), gamma 2,
 *      15 dead ends and 20 loops of amplification; its no-karst spheres off (the example
 *      crashes with them on).
 * What differs from the peers' own runs is listed in docs/performance.md.
 *
 *   bench_peers [--runs R] [--keep DIR] [--karst-synthesis KS]
 *
 * (default 5 runs; --keep writes the scenarios to DIR; KS is a Karst-Synthesis checkout with
 * KS/ks_rect built as docs/performance.md says, run R times from KS/G++ on this machine.)
 *
 * With --karst-synthesis, karst also runs the rectilinear scene on Karst-Synthesis's own sample
 * cloud (its KS/Data/poissonSamples3d.dat, the cloud it loads instead of sampling, written as
 * a sampling.points file), and the three runs alternate: karst on its own samples, karst on the
 * peer's cloud, the peer.
 *
 * Prints first what every karst process pays before any work (`karst --version`: median wall
 * time of 30 runs, page faults, peak memory); then, per scene, the sample and edge counts of the
 * run, the fastest and median wall time of R runs, the peak resident memory, the page faults of
 * a run, and the ratio to the peer's time: measured now with
 * --karst-synthesis, otherwise the figure docs/performance.md records (measured on another
 * machine of the CI type: a ratio to it holds only there).
 */
#define _GNU_SOURCE /* posix_spawn_file_actions_addchdir_np (glibc >= 2.29) */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench_spawn.h"

/* Karst-Synthesis's rectilinear key points (main.cpp l.159-186), y up in its frame: here
 * (x, z, y) so that z is up. Four of its 14 waypoints lie 164-336 m above every sample and get
 * no edge there (its Results/rectilinear_nodes.dat has none of them); they are left out. The
 * five waypoints whose height is an uninitialised 4.9e-313 are at 0. */
static const double KS_SINKS[7][3] = {{60.4311, 261.446, 52.6541},  {-101.237, 219.241, 52.1485},
                                      {-255.377, 138.243, 44.3283}, {-289.637, 358.579, 37.8691},
                                      {-86.1126, 382.429, 37.8371}, {-446.468, 383.381, 30.5388},
                                      {328.728, 414.128, 48.0858}};
static const double KS_SPRINGS[5][3] = {{225.946, -324.888, 37.5715},
                                        {95.9676, -337.74, 37.9612},
                                        {-110.653, -373.92, 35.7709},
                                        {-275.73, -314.632, 34.0925},
                                        {472.035, -456.167, 46.3118}};
static const double KS_WAYPOINTS[10][3] = {{-40, -42, 45},
                                           {-262.777, -35, 30.5283},
                                           {311.746, -35, -129.463},
                                           {0, -25, 0},
                                           {412.401, -14, 57.8162},
                                           {0, -65, 0},
                                           {99.8656, -17, 1.7859},
                                           {0, -26, 0},
                                           {0, -40, 0},
                                           {0, -29, 0}};

/* The fill radius that gives Karst-Synthesis's sample count: its baked cloud holds 23 434
 * points (spacing >= 30 m) and the scene 23 446 graph nodes; at 30.8 m karst places about as
 * many in the same slab (the bench prints the count it got). */
#define KS_FILL_RADIUS 30.8
/* KarstNSim's example: about 115 000 samples in its box; its box file is not in the public
 * snapshot, so the box here is 990 x 790 x 500 m (the later v1.3 example's plan, topped at
 * 500 m above every sink) and 12.8 m gives about 117 000 samples. */
#define KNS_FILL_RADIUS 12.8

/* The rectilinear scene; with @p points, on that point cloud (sampling.points) instead of
 * karst's own fill. */
static int write_ks_scene(const char *path, const char *points) {
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  fprintf(f, "# Karst-Synthesis's rectilinear scene as karst scenario (bench/bench_peers.c)\n"
             "name: ks_rectilinear\nunits: m\n"
             "domain: {min: [-1000, -1000, -200], max: [1000, 1000, 60]}\n"
             "terrain: {elevation: 60}\n"
             "fractures:\n"
             "  - {dip_direction: 90, dip: 90, weight: 1.0}\n"
             "  - {dip_direction: 0, dip: 90, weight: 1.0}\n"
             "  - {dip_direction: 0, dip: 0, weight: 1.0}\n"
             "key_points:\n");
  for (int i = 0; i < 7; i++)
    fprintf(f, "  - {name: sink%d, type: sink, position: [%.6g, %.6g, %.6g]}\n", i + 1,
            KS_SINKS[i][0], KS_SINKS[i][1], KS_SINKS[i][2]);
  for (int i = 0; i < 5; i++)
    fprintf(f, "  - {name: spring%d, type: spring, position: [%.6g, %.6g, %.6g]}\n", i + 1,
            KS_SPRINGS[i][0], KS_SPRINGS[i][1], KS_SPRINGS[i][2]);
  for (int i = 0; i < 10; i++)
    fprintf(f, "  - {name: way%d, type: waypoint, position: [%.6g, %.6g, %.6g]}\n", i + 1,
            KS_WAYPOINTS[i][0], KS_WAYPOINTS[i][1], KS_WAYPOINTS[i][2]);
  fprintf(f,
          "cost: {w0: 1, fracture: 10, fracture_combine: min}\n"
          "# Karst-Synthesis samples (or loads) one uniform cloud: no water-table layer\n"
          "sampling: {fill_radius: %g, feature_radius: %g, k: 32, refine: []%s%s}\n"
          "skeleton: {gamma: 2, reuse: 1}\n"
          "amplification: {steps: 1, points: 10, dead_end_fraction: 0.5}\n",
          KS_FILL_RADIUS, KS_FILL_RADIUS, points ? ", points: " : "", points ? points : "");
  return fclose(f) == 0 ? 0 : -1;
}

static int write_ks(const char *path) {
  return write_ks_scene(path, NULL);
}

/* Karst-Synthesis's baked Poisson cloud (KS/Data/poissonSamples3d.dat: a size_t count, then
 * that many Vector3 of 3 doubles, y up) as a sampling.points file in karst's frame (x, z, y).
 * Returns the number of points, or -1. */
static long write_ks_cloud(const char *ks, const char *path) {
  char in[4096];
  snprintf(in, sizeof in, "%s/Data/poissonSamples3d.dat", ks);
  FILE *f = fopen(in, "rb");
  if (!f) {
    fprintf(stderr, "bench_peers: %s: %s\n", in, strerror(errno));
    return -1;
  }
  uint64_t n = 0;
  struct stat st;
  if (fstat(fileno(f), &st) != 0 || fread(&n, sizeof n, 1, f) != 1 || n == 0 || n > 100000000 ||
      (uint64_t)st.st_size != 8 + 24 * n) {
    fprintf(stderr, "bench_peers: %s: not a count and that many 3-double points\n", in);
    fclose(f);
    return -1;
  }
  FILE *o = fopen(path, "w");
  if (!o) {
    fclose(f);
    return -1;
  }
  fprintf(o, "# Karst-Synthesis's baked cloud (Data/poissonSamples3d.dat), (x, y, z) = its (x, z, "
             "y)\nx y z\n");
  long written = 0;
  for (uint64_t i = 0; i < n; i++) {
    double p[3];
    if (fread(p, sizeof p, 1, f) != 1) break;
    char a[32], b[32], c[32];
    bench_shortest_double(a, sizeof a, p[0]), bench_shortest_double(b, sizeof b, p[2]),
        bench_shortest_double(c, sizeof c, p[1]);
    fprintf(o, "%s %s %s\n", a, b, c);
    written++;
  }
  fclose(f);
  if (fclose(o) != 0 || written != (long)n) return -1;
  return written;
}

static int write_kns(const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  fprintf(f,
          "# KarstNSim's shipped example as karst scenario (bench/bench_peers.c)\n"
          "name: karstnsim_example\nunits: m\n"
          "domain: {min: [0, 0, 0], max: [990, 790, 500]}\n"
          "terrain: {elevation: 500}\n"
          "# its two inception surfaces (z 404-481 and 239-371) as planes at their mid-heights,\n"
          "# within its max_inception_surface_distance of 50 m\n"
          "horizons:\n"
          "  - {elevation: 442, dip: 0, dip_direction: 0, radius: 50}\n"
          "  - {elevation: 305, dip: 0, dip_direction: 0, radius: 50}\n"
          "# fracture azimuths 0 and 60 degrees: vertical planes striking N and N60E\n"
          "fractures:\n"
          "  - {dip_direction: 90, dip: 90, weight: 0.5}\n"
          "  - {dip_direction: 150, dip: 90, weight: 0.5}\n"
          "# each spring's water table: the plane through it (its own base level)\n"
          "key_points:\n"
          "  - {name: sink1, type: sink, position: [299.795, 108.19, 482.581]}\n"
          "  - {name: sink2, type: sink, position: [137.711, 316.738, 472.322]}\n"
          "  - {name: sink3, type: sink, position: [157.161, 544.737, 474.809]}\n"
          "  - {name: sink4, type: sink, position: [373.274, 733.836, 466.029]}\n"
          "  - {name: sink5, type: sink, position: [411.093, 613.893, 421.587]}\n"
          "  - {name: spring1, type: spring, position: [608.498, 583.364, 355.684]}\n"
          "  - {name: spring2, type: spring, position: [777.934, 409.003, 249.472]}\n"
          "connectivity:\n"
          "  matrix: [[1, 0], [1, 0], [1, 0], [1, 0], [1, 0]]\n"
          "sampling: {fill_radius: %g, feature_radius: %g, k: 100}\n"
          "skeleton: {gamma: 2, reuse: 1}\n"
          "# 15 dead ends and 20 loops\n"
          "amplification: {steps: 1, points: 35, dead_end_fraction: 0.43}\n",
          KNS_FILL_RADIUS, KNS_FILL_RADIUS);
  return fclose(f) == 0 ? 0 : -1;
}

/* One whole-process run: wall time and peak RSS (KiB), or -1 on failure. */
static double run_once(const char *scenario, const char *out, long *rss_kib, long *faults) {
  char *argv[] = {(char *)KARST_CLI, "generate", (char *)scenario, "-o", (char *)out,
                  "--threads",       "1",        "--quiet",        NULL};
  return bench_run_counted(argv, 0, rss_kib, faults);
}

/* The number @p key in the object @p section of DIR/run.json, or -1. */
static long run_value(const char *dir, const char *section, const char *key) {
  double v = bench_json_number(bench_run_json(dir), section, key);
  return isnan(v) ? -1 : (long)v;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double median(double *t, int n) {
  qsort(t, (size_t)n, sizeof *t, cmp_double);
  return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

/* Wall time of one run of KS/ks_rect started in KS/G++ (it reads ../Data/ and writes
 * ../Results/), its output discarded; -1 when it cannot run. */
static double run_karst_synthesis_once(const char *ks, long *peak_kib) {
  char prog[4096], cwd[4096];
  snprintf(prog, sizeof prog, "%s/ks_rect", ks);
  snprintf(cwd, sizeof cwd, "%s/G++", ks);
  posix_spawn_file_actions_t fa;
  if (posix_spawn_file_actions_init(&fa) != 0) return -1;
  posix_spawn_file_actions_addchdir_np(&fa, cwd);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  char *argv[] = {prog, NULL};
  double t0 = bench_now_s();
  pid_t pid;
  int err = posix_spawn(&pid, prog, &fa, NULL, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (err != 0) {
    fprintf(stderr, "bench_peers: cannot run %s: %s\n", prog, strerror(err));
    return -1;
  }
  int status;
  struct rusage ru;
  if (wait4(pid, &status, 0, &ru) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    fprintf(stderr, "bench_peers: %s (run in %s) failed\n", prog, cwd);
    return -1;
  }
  double t = bench_now_s() - t0;
  if (ru.ru_maxrss > *peak_kib) *peak_kib = ru.ru_maxrss;
  return t;
}

typedef struct {
  const char *name, *file;
  int (*write)(const char *);
  const char *peer;
  double peer_s; /* the peer's whole-process time, one thread (docs/performance.md) */
} scene_t;

/* What every karst process pays before any work: `karst --version`, median wall time of
 * @p n runs, and its page faults (docs/performance.md: libraries loaded at start-up). */
static int startup(int n) {
  double t[100];
  long rss = 0, faults = 0;
  char *argv[] = {(char *)KARST_CLI, "--version", NULL};
  for (int r = 0; r < n; r++)
    if ((t[r] = bench_run_counted(argv, 1, &rss, &faults)) < 0) {
      fprintf(stderr, "bench_peers: %s --version failed\n", KARST_CLI);
      return 1;
    }
  printf("%-28s karst --version: %.1f ms (median of %d), %ld page faults, peak RSS %.0f MiB\n",
         "start-up", 1e3 * median(t, n), n, faults, rss / 1024.0);
  return 0;
}

int main(int argc, char **argv) {
  int runs = 5;
  const char *keep = NULL, *ks = NULL;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--runs") == 0 && i + 1 < argc)
      runs = atoi(argv[++i]);
    else if (strcmp(argv[i], "--keep") == 0 && i + 1 < argc)
      keep = argv[++i];
    else if (strcmp(argv[i], "--karst-synthesis") == 0 && i + 1 < argc)
      ks = argv[++i];
    else {
      fprintf(stderr, "usage: bench_peers [--runs R >= 1] [--keep DIR] [--karst-synthesis KS]\n");
      return 2;
    }
  }
  if (runs < 1 || runs > 100) {
    fprintf(stderr, "bench_peers: --runs must be within [1, 100]\n");
    return 2;
  }
  if (keep && mkdir(keep, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "bench_peers: --keep %s: %s\n", keep, strerror(errno));
    return 1;
  }
  char tmp[] = "/tmp/karst_bench_peers_XXXXXX";
  if (!bench_mkdtemp(tmp, "bench_peers")) return 1;
  const char *dir = keep ? keep : tmp;
  const scene_t scenes[2] = {
      {"Karst-Synthesis rectilinear", "ks_rectilinear.yaml", write_ks,
       "Karst-Synthesis 386b243, g++ -O3 -march=native, 1 thread", 1.46},
      {"KarstNSim example", "karstnsim_example.yaml", write_kns,
       "KarstNSim fd31889 on its own example, 1 thread (no-karst spheres off)", 22.3},
  };
  int status = 0;
  printf("bench_peers: whole process (%s generate ... --threads 1), %d runs each\n", KARST_CLI,
         runs);
  if (startup(30) != 0) status = 1;
  for (int s = 0; s < 2; s++) {
    const scene_t *S = &scenes[s];
    char path[4096], out[4096];
    snprintf(path, sizeof path, "%s/%s", dir, S->file);
    snprintf(out, sizeof out, "%s/out_%d", tmp, s);
    if (S->write(path) != 0) {
      fprintf(stderr, "bench_peers: cannot write %s\n", path);
      status = 1;
      continue;
    }
    /* With a Karst-Synthesis checkout, its scene runs alternate with karst's (on its own
     * samples and on Karst-Synthesis's own cloud), so that the machine's drift hits all three
     * alike. */
    int with_ks = s == 0 && ks;
    char cloud_yaml[4096], cloud_out[4096];
    long n_cloud = 0;
    if (with_ks) {
      char cloud[4096];
      snprintf(cloud, sizeof cloud, "%s/ks_cloud.xyz", dir);
      snprintf(cloud_yaml, sizeof cloud_yaml, "%s/ks_rectilinear_cloud.yaml", dir);
      snprintf(cloud_out, sizeof cloud_out, "%s/out_cloud", tmp);
      if ((n_cloud = write_ks_cloud(ks, cloud)) < 0 ||
          write_ks_scene(cloud_yaml, "ks_cloud.xyz") != 0) {
        fprintf(stderr, "bench_peers: cannot write %s or %s\n", cloud, cloud_yaml);
        status = 1;
        with_ks = 0;
      }
    }
    double t[100], tc[100], tk[100];
    long rss = 0, peak = 0, faults = 0, crss = 0, cpeak = 0, cfaults = 0, ks_peak = 0;
    int ok = 1;
    for (int r = 0; r < runs && ok; r++) {
      t[r] = run_once(path, out, &rss, &faults);
      if (t[r] < 0) ok = 0;
      if (rss > peak) peak = rss;
      if (!with_ks || !ok) continue;
      tc[r] = run_once(cloud_yaml, cloud_out, &crss, &cfaults);
      if (crss > cpeak) cpeak = crss;
      tk[r] = run_karst_synthesis_once(ks, &ks_peak);
      if (tc[r] < 0 || tk[r] < 0) ok = 0;
    }
    if (!ok) {
      fprintf(stderr, "bench_peers: karst generate %s or its peer failed\n", path);
      status = 1;
      continue;
    }
    double fastest = t[0];
    for (int r = 1; r < runs; r++)
      if (t[r] < fastest) fastest = t[r];
    double med = median(t, runs);
    printf("%-28s samples %7ld  edges %8ld  k %3ld  key points %2ld: %.3f s fastest, %.3f s "
           "median, peak RSS %.0f MiB, %ld page faults\n",
           S->name, run_value(out, "counts", "samples"), run_value(out, "counts", "graph_edges"),
           run_value(out, "sampling", "k"), run_value(out, "counts", "key_points"), fastest, med,
           peak / 1024.0, faults);
    if (with_ks) {
      double cfast = tc[0];
      for (int r = 1; r < runs; r++)
        if (tc[r] < cfast) cfast = tc[r];
      double cmed = median(tc, runs), ks_med = median(tk, runs);
      printf("%-28s samples %7ld  edges %8ld  k %3ld  key points %2ld: %.3f s fastest, %.3f s "
             "median, peak RSS %.0f MiB, %ld page faults (sampling.points: %ld of its %ld "
             "points kept)\n",
             "  on Karst-Synthesis's cloud", run_value(cloud_out, "counts", "samples"),
             run_value(cloud_out, "counts", "graph_edges"), run_value(cloud_out, "sampling", "k"),
             run_value(cloud_out, "counts", "key_points"), cfast, cmed, cpeak / 1024.0, cfaults,
             run_value(cloud_out, "counts", "points_kept"), n_cloud);
      printf("%-28s %s, measured now, alternated with karst's runs (median of %d, peak RSS "
             "%.0f MiB): %.2f s: %.1fx karst's median on its own samples, %.1fx on the peer's "
             "cloud (target >= 10x)\n",
             "", S->peer, runs, ks_peak / 1024.0, ks_med, ks_med / med, ks_med / cmed);
    } else {
      printf("%-28s %s, recorded in docs/performance.md: %.2f s, %.1fx karst's median (target "
             ">= 10x; the ratio holds on the machine the figure was measured on)\n",
             "", S->peer, S->peer_s, S->peer_s / med);
    }
  }
  bench_remove_dir(tmp, "bench_peers");
  return status;
}
