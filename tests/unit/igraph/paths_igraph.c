/* The all-sources quantities of src/metrics/paths.c computed with igraph 0.10 (paths_igraph.h). */
#include "paths_igraph.h"

#include <igraph.h>
#include <stdlib.h>

karst_error_t karst_i_paths_igraph(karst_ctx_t *ctx, const karst_i_csr_t *g, double *betweenness,
                                   karst_int_t *dist_sum) {
  /* igraph's default handler aborts the program: we check every return code instead. */
  igraph_set_error_handler(igraph_error_handler_ignore);
  karst_error_t err = KARST_SUCCESS;
  igraph_t graph;
  igraph_vector_int_t el;
  igraph_vector_t res;
  igraph_matrix_t dist;
  int have_graph = 0, have_el = 0, have_res = 0, have_dist = 0;
  const karst_int_t n = g->n;
  if (igraph_vector_int_init(&el, 0)) goto fail;
  have_el = 1;
  for (karst_int_t v = 0; v < n; v++)
    for (karst_int_t k = g->off[v]; k < g->off[v + 1]; k++)
      if (v < g->adj[k]) {
        if (igraph_vector_int_push_back(&el, v) || igraph_vector_int_push_back(&el, g->adj[k]))
          goto fail;
      }
  if (igraph_create(&graph, &el, n, IGRAPH_UNDIRECTED)) goto fail;
  have_graph = 1;
  if (igraph_vector_init(&res, n)) goto fail;
  have_res = 1;
  if (igraph_betweenness(&graph, &res, igraph_vss_all(), IGRAPH_UNDIRECTED, NULL)) goto fail;
  /* igraph counts each unordered pair once; paths.c (like networkx) counts it from both ends. */
  for (karst_int_t v = 0; v < n; v++)
    betweenness[v] = 2.0 * VECTOR(res)[v];
  if (dist_sum) {
    if (igraph_matrix_init(&dist, 1, n)) goto fail;
    have_dist = 1;
    for (karst_int_t s = 0; s < n; s++) {
      if (igraph_distances(&graph, &dist, igraph_vss_1(s), igraph_vss_all(), IGRAPH_ALL)) goto fail;
      karst_int_t sum = 0;
      for (karst_int_t t = 0; t < n; t++) {
        igraph_real_t d = MATRIX(dist, 0, t);
        if (d != IGRAPH_INFINITY) sum += (karst_int_t)d;
      }
      dist_sum[s] = sum;
    }
  }
  goto cleanup;
fail:
  err =
      karst_set_error(ctx, KARST_EEXTERNAL, "igraph failed on a graph of %lld nodes", (long long)n);
cleanup:
  if (have_dist) igraph_matrix_destroy(&dist);
  if (have_res) igraph_vector_destroy(&res);
  if (have_graph) igraph_destroy(&graph);
  if (have_el) igraph_vector_int_destroy(&el);
  return err;
}
