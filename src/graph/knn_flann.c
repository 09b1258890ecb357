/*
 * The k nearest neighbours through FLANN's exact single k-d tree
 * (FLANN_INDEX_KDTREE_SINGLE), the search Paris et al. 2021 §4.1 name; selected by
 * sampling.knn = flann. The default grid search (knn.c) returns the same sets and is
 * much faster on Poisson samples (bench/bench_knn: 1.5 M points, k = 100, 2 cores:
 * FLANN 23.7 s, grid 1.7 s), so this backend is kept for comparison and as the
 * independent check of the grid search in tests/unit/test_knn.c.
 */
#include <stdlib.h>

#include "graph/flann_api_internal.h"
#include "graph/graph_internal.h"

typedef struct {
  double d;
  int32_t i;
} cand_t;

static int cand_cmp(const void *pa, const void *pb) {
  const cand_t *a = pa, *b = pb;
  if (karst_i_knn_less(a->d, a->i, b->d, b->i)) return -1;
  if (karst_i_knn_less(b->d, b->i, a->d, a->i)) return 1;
  return 0;
}

/**
 * Same contract as karst_i_knn (graph_internal.h), through FLANN: each point's
 * k + 1 nearest points are asked for (itself included), distances are
 * recomputed with karst_i_dist2 and ordered with ties broken by index, and
 * the point itself is dropped. The set equals the grid search's unless several
 * points tie exactly at the k-th distance (FLANN then decides which one is
 * returned). FLANN's log is silenced; its query runs on @p nthreads cores.
 * Time complexity: O(n log n) to build, about O(n k log n) to query.
 */
karst_error_t karst_i_knn_flann(karst_ctx_t *ctx, const double *xyz, karst_int_t n, int k,
                                int nthreads, int32_t *nbr, double *kd2, int32_t *kidx) {
  karst_error_t err = karst_i_flann_load(ctx);
  if (err != KARST_SUCCESS) return err;
  int kq = k + 1 <= n ? k + 1 : (int)n;
  int *ind = malloc(sizeof(int) * (size_t)n * (size_t)kq);
  double *dist = malloc(sizeof(double) * (size_t)n * (size_t)kq);
  cand_t *c = malloc(sizeof(cand_t) * (size_t)kq);
  flann_index_t index = NULL;
  if (!ind || !dist || !c) {
    err = karst_set_error(ctx, KARST_ENOMEM, "kNN (FLANN): out of memory for %lld points",
                          (long long)n);
    goto cleanup;
  }
  struct FLANNParameters p = *karst_i_flann.defaults;
  p.algorithm = FLANN_INDEX_KDTREE_SINGLE;
  p.log_level = FLANN_LOG_NONE;
  p.checks = FLANN_CHECKS_UNLIMITED; /* exact search */
  p.cores = nthreads > 0 ? nthreads : 1;
  karst_i_flann.flann_log_verbosity(FLANN_LOG_NONE);
  float speedup;
  index = karst_i_flann.flann_build_index_double((double *)xyz, (int)n, 3, &speedup, &p);
  if (!index || karst_i_flann.flann_find_nearest_neighbors_index_double(
                    index, (double *)xyz, (int)n, ind, dist, kq, &p) != 0) {
    err = karst_set_error(ctx, KARST_EEXTERNAL, "kNN (FLANN): the search failed for %lld points",
                          (long long)n);
    goto cleanup;
  }
  for (karst_int_t v = 0; v < n; v++) {
    int m = 0;
    for (int j = 0; j < kq; j++) {
      int32_t u = ind[(size_t)v * kq + j];
      if (u == v || u < 0) continue;
      c[m].d = karst_i_dist2(xyz + 3 * v, xyz + 3 * u);
      c[m].i = u;
      m++;
    }
    qsort(c, (size_t)m, sizeof *c, cand_cmp);
    if (m > k) m = k;
    for (int j = 0; j < m; j++)
      nbr[(size_t)v * k + j] = c[j].i;
    kd2[v] = c[m - 1].d;
    kidx[v] = c[m - 1].i;
  }
cleanup:
  if (index) karst_i_flann.flann_free_index_double(index, &p);
  free(ind);
  free(dist);
  free(c);
  return err;
}
