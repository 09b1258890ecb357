/* The exact grid k-nearest-neighbour search of the graph module (knn.c)
 * against brute force: the k smallest (squared distance, index) pairs,
 * computed by sorting all n − 1 others (an independent O(n² log n) method).
 * Covers ties on a lattice, clustered points, identical points, collinear and
 * coplanar points, n = 2, and independence of the thread count; and FLANN's
 * exact k-d tree (knn_flann.c) against the grid search. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "graph/graph_internal.h"
#include "karst.h"
#include "test_util.h"

typedef struct {
  double d;
  int32_t i;
} di_t;

static int cmp_di(const void *a, const void *b) {
  const di_t *x = a, *y = b;
  if (x->d != y->d) return (x->d > y->d) - (x->d < y->d);
  return (x->i > y->i) - (x->i < y->i);
}

static int cmp_i32(const void *a, const void *b) {
  int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

/* Run the search with `threads` threads and compare every list, its k-th
 * distance and index with brute force. */
static void check_knn(const double *xyz, int n, int k, int threads) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  int32_t *nbr = malloc(sizeof(int32_t) * (size_t)n * (size_t)k), *kidx = malloc(4 * (size_t)n);
  double *kd2 = malloc(sizeof(double) * (size_t)n);
  di_t *all = malloc(sizeof(di_t) * (size_t)n);
  int32_t *want = malloc(sizeof(int32_t) * (size_t)k), *got = malloc(sizeof(int32_t) * (size_t)k);
  assert_int_equal(karst_i_knn(&ctx, xyz, n, k, threads, nbr, kd2, kidx), KARST_SUCCESS);
  for (int v = 0; v < n; v++) {
    int m = 0;
    for (int u = 0; u < n; u++)
      if (u != v) all[m].d = karst_i_dist2(xyz + 3 * u, xyz + 3 * v), all[m++].i = u;
    qsort(all, (size_t)m, sizeof(di_t), cmp_di);
    for (int j = 0; j < k; j++)
      want[j] = all[j].i;
    memcpy(got, nbr + (size_t)v * k, sizeof(int32_t) * (size_t)k);
    qsort(want, (size_t)k, sizeof(int32_t), cmp_i32);
    qsort(got, (size_t)k, sizeof(int32_t), cmp_i32);
    assert_memory_equal(got, want, sizeof(int32_t) * (size_t)k);
    assert_true(kd2[v] == all[k - 1].d);
    assert_int_equal(kidx[v], all[k - 1].i);
  }
  free(nbr), free(kidx), free(kd2), free(all), free(want), free(got);
}

/* An integer lattice: every point has 6 neighbours at distance 1, 12 at
 * √2 and 8 at √3, so k = 7, 10 and 20 cut through ties that only the
 * index can break; the same with 1 and 3 threads. */
static void test_knn_lattice_ties(void **state) {
  (void)state;
  int n = 6 * 6 * 6;
  double *xyz = malloc(sizeof(double) * 3 * (size_t)n);
  for (int i = 0; i < n; i++)
    xyz[3 * i] = i % 6, xyz[3 * i + 1] = i / 6 % 6, xyz[3 * i + 2] = i / 36;
  for (int t = 1; t <= 3; t += 2) {
    check_knn(xyz, n, 7, t);
    check_knn(xyz, n, 10, t);
    check_knn(xyz, n, 20, t);
  }
  free(xyz);
}

/* Random points, half of them in a ball 100 times smaller than the box (the
 * grid refines its cells for the occupied part), at several k. */
static void test_knn_clustered(void **state) {
  (void)state;
  int n = 1500;
  double *xyz = malloc(sizeof(double) * 3 * (size_t)n);
  karst_rng_t r;
  karst_rng_init(&r, 3, 0);
  for (int i = 0; i < n; i++) {
    if (i % 2) {
      double u[3];
      karst_rng_unit_vector(&r, u);
      double rad = cbrt(karst_rng_uniform(&r));
      for (int a = 0; a < 3; a++)
        xyz[3 * i + a] = 500 + rad * u[a];
    } else {
      for (int a = 0; a < 3; a++)
        xyz[3 * i + a] = karst_rng_uniform_range(&r, 0, 1000);
    }
  }
  check_knn(xyz, n, 1, 2);
  check_knn(xyz, n, 12, 1);
  check_knn(xyz, n, 40, 3);
  free(xyz);
}

/* Degenerate geometry: identical points (all distances 0: the k smallest
 * other indices), collinear and coplanar points, and n = 2. */
static void test_knn_degenerate(void **state) {
  (void)state;
  int n = 60;
  double *xyz = malloc(sizeof(double) * 3 * (size_t)n);
  for (int i = 0; i < 3 * n; i++)
    xyz[i] = 1.25;
  check_knn(xyz, n, 10, 2);
  karst_rng_t r;
  karst_rng_init(&r, 4, 0);
  for (int i = 0; i < n; i++) {
    double t = karst_rng_uniform_range(&r, -50, 50);
    xyz[3 * i] = t, xyz[3 * i + 1] = 2 * t, xyz[3 * i + 2] = -t; /* one line */
  }
  check_knn(xyz, n, 5, 2);
  for (int i = 0; i < n; i++) /* one plane z = 7 */
    xyz[3 * i] = karst_rng_uniform_range(&r, 0, 10),
            xyz[3 * i + 1] = karst_rng_uniform_range(&r, 0, 10), xyz[3 * i + 2] = 7;
  check_knn(xyz, n, 8, 1);
  check_knn(xyz, 2, 1, 1);
  free(xyz);
}

/* FLANN's exact single k-d tree (sampling.knn = flann) and the grid search give the same
 * neighbour lists, k-th distances and k-th indices on 20 000 random points (no exact ties),
 * k = 40 as in Paris et al. 2021: two independent implementations of one definition. */
static void test_knn_flann_agrees(void **state) {
  (void)state;
  const int n = 20000, k = 40;
  double *xyz = malloc(sizeof(double) * 3 * (size_t)n);
  karst_rng_t r;
  karst_rng_init(&r, 17, 0);
  for (int i = 0; i < 3 * n; i++) xyz[i] = karst_rng_uniform_range(&r, 0, 500);
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  int32_t *a = malloc(sizeof(int32_t) * (size_t)n * k), *b = malloc(sizeof(int32_t) * (size_t)n * k);
  int32_t *ka = malloc(4 * (size_t)n), *kb = malloc(4 * (size_t)n);
  double *da = malloc(8 * (size_t)n), *db = malloc(8 * (size_t)n);
  assert_int_equal(karst_i_knn(&ctx, xyz, n, k, 2, a, da, ka), KARST_SUCCESS);
  assert_int_equal(karst_i_knn_flann(&ctx, xyz, n, k, 2, b, db, kb), KARST_SUCCESS);
  for (int v = 0; v < n; v++) {
    qsort(a + (size_t)v * k, k, sizeof(int32_t), cmp_i32);
    qsort(b + (size_t)v * k, k, sizeof(int32_t), cmp_i32);
    assert_memory_equal(a + (size_t)v * k, b + (size_t)v * k, sizeof(int32_t) * k);
    assert_true(da[v] == db[v]);
    assert_int_equal(ka[v], kb[v]);
  }
  free(xyz), free(a), free(b), free(ka), free(kb), free(da), free(db);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_knn_lattice_ties),
      cmocka_unit_test(test_knn_clustered),
      cmocka_unit_test(test_knn_degenerate),
      cmocka_unit_test(test_knn_flann_agrees),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
