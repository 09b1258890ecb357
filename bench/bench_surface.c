/* Benchmark (not a test): queries on geological surfaces (src/geology/). Builds
 * TINs of about 1e4, 1e5 and 1e6 triangles (a jittered lattice carrying a fold,
 * checked as karst_surface_create_tin checks any TIN) and grids of 1e4 and 1e6
 * cells, then times karst_surface_z at random points inside them and
 * karst_surface_segment_below on random 10 m segments (graph-edge sized). The
 * bucket index makes a TIN query O(1) expected: the rate should not fall with
 * the size beyond what the caches cost: the same points are also queried in a
 * coherent order (sorted by 20 m bands of y, then x, as a sweep over the samples
 * of a domain would be), where the caches hold what a query needs. Each timing
 * is the fastest of `repeat`
 * runs, in CPU time (the process is single-threaded); the load average tells
 * how busy the machine was.
 * Usage: bench_surface [--repeat N] [--small]   (--small skips the 1e6 cases). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "geology/surface_internal.h"
#include "karst.h"

#define N_QUERIES 2000000
#define N_SEGMENTS 500000

/* CPU time of this (single-threaded) process: on a shared machine it leaves out
 * the time other processes hold the core, though not their use of the caches. */
static double cpu_now(void) {
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void print_load(const char *when) {
  double l[3] = {0, 0, 0};
  if (getloadavg(l, 3) == 3) printf("load average %s: %.2f %.2f %.2f\n", when, l[0], l[1], l[2]);
}

/* Order of the coherent sweep: 20 m bands of y, then x (of a point, or of a
 * segment's first end). */
static int cmp_sweep(const void *pa, const void *pb) {
  const double *a = pa, *b = pb;
  double ba = floor(a[1] / 20), bb = floor(b[1] / 20);
  if (ba != bb) return ba < bb ? -1 : 1;
  return a[0] < b[0] ? -1 : (a[0] > b[0]);
}

static double fold(double x, double y) {
  return 250 + 40 * cos(2 * M_PI / 800 * (x * 0.866 + y * 0.5)) + 0.01 * y;
}

/* A lattice of n x n nodes over [0, L]^2 jittered by 0.2 of a cell: 2 (n-1)^2 triangles. */
static karst_surface_t *make_tin(karst_ctx_t *ctx, int n, double L, double *build_s) {
  double h = L / (n - 1);
  karst_rng_t rng;
  karst_rng_init(&rng, 1, (uint64_t)n);
  double *xyz = malloc((size_t)n * n * 3 * sizeof *xyz);
  karst_int_t *tri = malloc((size_t)(n - 1) * (n - 1) * 6 * sizeof *tri);
  if (!xyz || !tri) return NULL;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      double *q = xyz + 3 * ((size_t)j * n + i);
      q[0] = i * h + (i > 0 && i < n - 1 ? karst_rng_uniform_range(&rng, -0.2, 0.2) * h : 0);
      q[1] = j * h + (j > 0 && j < n - 1 ? karst_rng_uniform_range(&rng, -0.2, 0.2) * h : 0);
      q[2] = fold(q[0], q[1]);
    }
  karst_int_t m = 0;
  for (int j = 0; j + 1 < n; j++)
    for (int i = 0; i + 1 < n; i++) {
      karst_int_t a = (karst_int_t)j * n + i, b = a + 1, c = a + n, d = c + 1;
      karst_int_t t[6] = {a, b, d, a, d, c};
      memcpy(tri + 3 * m, t, sizeof t);
      m += 2;
    }
  karst_surface_t *s = NULL;
  double t0 = cpu_now();
  karst_error_t err = karst_surface_create_tin(ctx, (karst_int_t)n * n, xyz, m, tri, &s);
  *build_s = cpu_now() - t0;
  free(xyz);
  free(tri);
  if (err) fprintf(stderr, "bench_surface: %s\n", ctx->errmsg);
  return s;
}

static karst_surface_t *make_grid(karst_ctx_t *ctx, int n, double L) {
  double h = L / (n - 1);
  double *z = malloc((size_t)n * n * sizeof *z);
  if (!z) return NULL;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++)
      z[(size_t)j * n + i] = fold(i * h, j * h);
  karst_surface_t *s = NULL;
  if (karst_surface_create_grid(ctx, n, n, 0, 0, h, z, &s))
    fprintf(stderr, "bench_surface: %s\n", ctx->errmsg);
  free(z);
  return s;
}

/* Fastest of `repeat` runs of N z-queries at the points pts; returns queries / s. */
static double time_z(const karst_surface_t *s, const double *pts, int repeat, double *sink) {
  double best = 1e300;
  for (int r = 0; r < repeat; r++) {
    double t0 = cpu_now(), acc = 0;
    for (int k = 0; k < N_QUERIES; k++)
      acc += karst_surface_z(s, pts[2 * k], pts[2 * k + 1]);
    double t = cpu_now() - t0;
    *sink += acc;
    if (t < best) best = t;
  }
  return N_QUERIES / best;
}

static double time_segments(const karst_surface_t *s, const double *seg, int repeat, long *sink) {
  double best = 1e300;
  for (int r = 0; r < repeat; r++) {
    double t0 = cpu_now();
    long below = 0;
    for (int k = 0; k < N_SEGMENTS; k++)
      below += karst_surface_segment_below(s, seg + 6 * k, seg + 6 * k + 3);
    double t = cpu_now() - t0;
    *sink += below;
    if (t < best) best = t;
  }
  return N_SEGMENTS / best;
}

int main(int argc, char **argv) {
  int repeat = 3, small = 0;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc)
      repeat = atoi(argv[++i]);
    else if (strcmp(argv[i], "--small") == 0)
      small = 1;
    else {
      fprintf(stderr, "usage: bench_surface [--repeat N] [--small]\n");
      return 2;
    }
  }
  if (repeat < 1) repeat = 1;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  const double L = 2000;
  print_load("before");
  double *pts = malloc((size_t)N_QUERIES * 2 * sizeof *pts);
  double *seg = malloc((size_t)N_SEGMENTS * 6 * sizeof *seg);
  if (!pts || !seg) return 1;
  karst_rng_t rng;
  karst_rng_init(&rng, 2, 0);
  for (int k = 0; k < N_QUERIES; k++) {
    pts[2 * k] = karst_rng_uniform_range(&rng, 0, L);
    pts[2 * k + 1] = karst_rng_uniform_range(&rng, 0, L);
  }
  for (int k = 0; k < N_SEGMENTS; k++) { /* 10 m long, a few metres below or across the fold */
    double *a = seg + 6 * k, *b = a + 3, d[3];
    karst_rng_unit_vector(&rng, d);
    a[0] = karst_rng_uniform_range(&rng, 10, L - 10),
    a[1] = karst_rng_uniform_range(&rng, 10, L - 10);
    a[2] = fold(a[0], a[1]) - karst_rng_uniform_range(&rng, 0, 8);
    for (int c = 0; c < 3; c++)
      b[c] = a[c] + 10 * d[c];
  }
  double *swept = malloc((size_t)N_QUERIES * 2 * sizeof *swept);
  if (!swept) return 1;
  memcpy(swept, pts, (size_t)N_QUERIES * 2 * sizeof *swept);
  qsort(swept, N_QUERIES, 2 * sizeof *swept, cmp_sweep);
  double *seg_swept = malloc((size_t)N_SEGMENTS * 6 * sizeof *seg_swept);
  if (!seg_swept) return 1;
  memcpy(seg_swept, seg, (size_t)N_SEGMENTS * 6 * sizeof *seg);
  qsort(seg_swept, N_SEGMENTS, 6 * sizeof *seg_swept, cmp_sweep);
  double sink = 0;
  long ssink = 0;
  printf("CPU time per call. karst_surface_z: %d points, in random order and swept; "
         "segment_below: %d random 10 m segments\n",
         N_QUERIES, N_SEGMENTS);
  const int tin_n[3] = {72, 225, 708};
  for (int c = 0; c < (small ? 2 : 3); c++) {
    double build;
    karst_surface_t *s = make_tin(&ctx, tin_n[c], L, &build);
    if (!s) return 1;
    double per_bucket = (double)s->bstart[s->bnx * s->bny] / (double)(s->bnx * s->bny);
    double zq = time_z(s, pts, repeat, &sink), zs = time_z(s, swept, repeat, &sink);
    double sq = time_segments(s, seg, repeat, &ssink),
           ss = time_segments(s, seg_swept, repeat, &ssink);
    printf(
        "TIN  %8lld triangles: built and checked in %.3f s CPU, %.2f triangles per bucket\n"
        "     z random %6.1f ns, swept %6.1f ns; segment_below random %7.1f ns, swept %7.1f ns\n",
        (long long)s->nt, build, per_bucket, 1e9 / zq, 1e9 / zs, 1e9 / sq, 1e9 / ss);
    karst_surface_free(s);
  }
  const int grid_n[2] = {101, 1001};
  for (int c = 0; c < (small ? 1 : 2); c++) {
    karst_surface_t *s = make_grid(&ctx, grid_n[c], L);
    if (!s) return 1;
    double zq = time_z(s, pts, repeat, &sink), zs = time_z(s, swept, repeat, &sink);
    double sq = time_segments(s, seg, repeat, &ssink),
           ss = time_segments(s, seg_swept, repeat, &ssink);
    printf(
        "grid %8lld cells\n"
        "     z random %6.1f ns, swept %6.1f ns; segment_below random %7.1f ns, swept %7.1f ns\n",
        (long long)grid_n[c] * grid_n[c], 1e9 / zq, 1e9 / zs, 1e9 / sq, 1e9 / ss);
    karst_surface_free(s);
  }
  karst_surface_t *p = NULL;
  karst_surface_create_plane(&ctx, 250, 5, 30, (const double[2]){1000, 1000}, &p);
  double zq = time_z(p, pts, repeat, &sink), sq = time_segments(p, seg, repeat, &ssink);
  printf("plane\n     z random %6.1f ns; segment_below %7.1f ns\n", 1e9 / zq, 1e9 / sq);
  karst_surface_free(p);
  print_load("after");
  printf("(checksums %.6g %ld)\n", sink, ssink);
  free(pts);
  free(swept);
  free(seg);
  free(seg_swept);
  return 0;
}
