/* The periodic radius graph of a tile through FLANN's radius search (exact
 * single k-d tree), the independent check of the grid search in points.c
 * (tests/unit/test_blocks.c) and its rival in bench/bench_blocks.c. The
 * torus is handled by ghosts: the copies x + s L (L in {-1, 0, 1}³) that
 * fall within the graph radius of the cube are indexed with the points. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "blocks/blocks_internal.h"
#include "graph/flann_api_internal.h"

/* Neighbours asked of FLANN per query: far above the ~20 a Poisson sample
 * has within 2 r (a point has at most (2 rg / r + 1)³ within rg). */
static int max_neighbours(double s, double rg, double r_min) {
  double m = pow(2 * rg / r_min + 1, 3);
  (void)s;
  return m > 4096 ? 4096 : (int)m + 1;
}

/**
 * Same contract as karst_i_blocks_radius_graph (blocks_internal.h), through
 * flann_radius_search_double on points and ghosts; distances are recomputed
 * in double as the grid search does, so the two agree pair for pair.
 * Time complexity: O(n log n) to build, O(n (log n + k)) to query.
 */
karst_error_t karst_i_blocks_radius_graph_flann(karst_ctx_t *ctx, const double *xyz, karst_int_t n,
                                                double s, double radius, karst_i_edge_t **edges,
                                                karst_int_t *n_edges) {
  *edges = NULL;
  *n_edges = 0;
  if (!(radius > 0) || !(radius < s / 3))
    return karst_set_error(
        ctx, KARST_EINVAL,
        "tile graph (FLANN): radius %g must be within (0, s/3) for a tile of %g m", radius, s);
  karst_error_t err = karst_i_flann_load(ctx);
  if (err != KARST_SUCCESS) return err;
  karst_int_t cap = 27 * n + 1, ng = 0, ne = 0, ecap = 0;
  double *g = malloc(3 * (size_t)cap * sizeof *g);
  int32_t *gi = malloc((size_t)cap * sizeof *gi);
  int8_t *gl = malloc(3 * (size_t)cap * sizeof *gl);
  int kmax = max_neighbours(s, radius, radius / 4);
  int *ind = malloc((size_t)kmax * sizeof *ind);
  double *dist = malloc((size_t)kmax * sizeof *dist);
  karst_i_edge_t *e = NULL;
  flann_index_t index = NULL;
  struct FLANNParameters p = *karst_i_flann.defaults;
  if (!g || !gi || !gl || !ind || !dist) goto nomem;
  for (karst_int_t i = 0; i < n; i++)
    for (int lz = -1; lz <= 1; lz++)
      for (int ly = -1; ly <= 1; ly++)
        for (int lx = -1; lx <= 1; lx++) {
          int L[3] = {lx, ly, lz}, ok = 1;
          for (int a = 0; a < 3; a++) {
            double x = xyz[3 * i + a] + s * L[a];
            if (x < -radius || x >= s + radius) ok = 0;
          }
          if (!ok) continue;
          for (int a = 0; a < 3; a++) {
            g[3 * ng + a] = xyz[3 * i + a] + s * L[a];
            gl[3 * ng + a] = (int8_t)L[a];
          }
          gi[ng++] = (int32_t)i;
        }
  p.algorithm = FLANN_INDEX_KDTREE_SINGLE;
  p.log_level = FLANN_LOG_NONE;
  p.checks = FLANN_CHECKS_UNLIMITED;
  p.cores = 1;
  karst_i_flann.flann_log_verbosity(FLANN_LOG_NONE);
  float speedup;
  index = karst_i_flann.flann_build_index_double(g, (int)ng, 3, &speedup, &p);
  if (!index) {
    err = karst_set_error(ctx, KARST_EEXTERNAL, "tile graph (FLANN): the index failed");
    goto cleanup;
  }
  for (karst_int_t i = 0; i < n; i++) {
    double q[3] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    /* FLANN's L2 radius is squared; ask slightly wider and decide in double below */
    int m = karst_i_flann.flann_radius_search_double(index, q, ind, dist, kmax,
                                                     (float)(radius * radius) * 1.001f, &p);
    if (m < 0) {
      err = karst_set_error(ctx, KARST_EEXTERNAL, "tile graph (FLANN): the search failed");
      goto cleanup;
    }
    if (m > kmax) m = kmax;
    for (int k = 0; k < m; k++) {
      int h = ind[k];
      if (h < 0 || h >= ng || gi[h] <= i) continue;
      double d2 = 0;
      for (int a = 0; a < 3; a++) {
        double d = xyz[3 * gi[h] + a] - q[a] + s * gl[3 * h + a];
        d2 += d * d;
      }
      if (!(d2 < radius * radius)) continue;
      if (ne == ecap) {
        ecap = ecap ? 2 * ecap : 1024;
        karst_i_edge_t *t = realloc(e, (size_t)ecap * sizeof *t);
        if (!t) goto nomem;
        e = t;
      }
      memset(&e[ne], 0, sizeof e[ne]);
      e[ne].u = (int32_t)i, e[ne].v = gi[h];
      for (int a = 0; a < 3; a++)
        e[ne].L[a] = gl[3 * h + a];
      e[ne].fam[0] = e[ne].fam[1] = -1;
      ne++;
    }
  }
  karst_i_blocks_sort_edges(e, ne);
  *edges = e;
  *n_edges = ne;
  e = NULL;
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "tile graph (FLANN): out of memory");
cleanup:
  if (index) karst_i_flann.flann_free_index_double(index, &p);
  free(g);
  free(gi);
  free(gl);
  free(ind);
  free(dist);
  free(e);
  return err;
}
