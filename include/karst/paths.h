/**
 * @file paths.h
 * @brief Least-cost paths on the sample graph (Paris et al. 2021, §4): A*
 *        with an admissible Euclidean heuristic, Dijkstra from one or many
 *        sources with early stop on targets, and the key-point distance
 *        matrix the γ-skeleton (§5.1) is built from.
 */
#ifndef KARST_PATHS_H
#define KARST_PATHS_H

#include <stdint.h>

#include "karst/common.h"
#include "karst/graph.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A path as graph vertex indices from its source to its target, and its cost. */
typedef struct karst_path {
  karst_int_t n, cap;
  karst_int_t *v; /**< n vertex indices, v[0] = source, v[n-1] = target */
  double cost;    /**< sum of the arc costs along the path */
} karst_path_t;

void karst_path_init(karst_path_t *p);
void karst_path_destroy(karst_path_t *p);

/**
 * Reusable search state over one graph (distances, predecessors, heap). A
 * search only touches the vertices it reaches, so thousands of local searches
 * on a million-vertex graph cost what they visit, not O(n) each.
 * Not thread-safe: one per thread.
 */
typedef struct karst_search karst_search_t;

karst_error_t karst_search_create(karst_ctx_t *ctx, const karst_graph_t *g, karst_search_t **out);
void karst_search_free(karst_search_t *s);

/** Distance of @p v in the last search (INFINITY when not reached or not settled). */
double karst_search_dist(const karst_search_t *s, karst_int_t v);
/** Number of vertices the last search settled (for benchmarks). */
karst_int_t karst_search_settled(const karst_search_t *s);
/** Path from the last search's nearest source to @p v (which must have been settled). */
karst_error_t karst_search_path_to(karst_ctx_t *ctx, const karst_search_t *s, karst_int_t v,
                                   karst_path_t *path);

karst_error_t karst_paths_astar(karst_ctx_t *ctx, karst_search_t *s, karst_int_t source,
                                karst_int_t target, double lb_per_metre, karst_path_t *path);

karst_error_t karst_paths_dijkstra(karst_ctx_t *ctx, karst_search_t *s, karst_int_t n_sources,
                                   const karst_int_t *sources, const unsigned char *blocked,
                                   const unsigned char *is_target, karst_int_t stop_after,
                                   karst_int_t *last_target);

/**
 * Relative safety margin subtracted from the heuristic of karst_paths_astar_reuse so that
 * rounding in its sums can never make it overestimate. Default 1e-9 (rounding is ~1e-15).
 */
#define KARST_PATHS_HEURISTIC_MARGIN 1e-9

/**
 * Path sharing (Galin et al. 2011; Paris et al. 2021, §5.1): arcs of the network already laid
 * cost @c factor times their cost.
 */
typedef struct karst_reuse {
  double factor;               /**< r in (0, 1] */
  const unsigned char *reused; /**< n_arcs flags, set on both arcs of each network edge, or NULL */
  const double *dist_to_net;   /**< n lower bounds of the least original cost to the nearest network
                                    vertex that change by at most the arc cost along an arc: the
                                    exact costs (INFINITY while the network is empty), or those
                                    capped at any constant; NULL: taken as 0 (always safe) */
  int (*cancelled)(void *arg); /**< polled every 256 settled vertices: non-zero abandons the search
                                    with KARST_EINTERRUPTED; NULL: never */
  void *cancel_arg;            /**< passed to @c cancelled */
} karst_reuse_t;

karst_error_t karst_paths_astar_reuse(karst_ctx_t *ctx, karst_search_t *s, karst_int_t source,
                                      karst_int_t target, double lb_per_metre,
                                      const float *target_bound, const karst_reuse_t *reuse,
                                      karst_path_t *path);

karst_error_t karst_paths_lower_distances(karst_ctx_t *ctx, karst_search_t *s,
                                          karst_int_t n_sources, const karst_int_t *sources,
                                          double *dist);

/** How the key-point distance matrix is computed. */
typedef enum {
  KARST_PATHS_DIJKSTRA_MULTI = 0, /**< one multi-target Dijkstra per key point (default) */
  KARST_PATHS_ASTAR_PAIRS = 1     /**< one A* per pair of key points */
} karst_paths_method_t;

karst_error_t karst_paths_keypoint_distances(karst_ctx_t *ctx, const karst_graph_t *g,
                                             karst_int_t n_keys, const karst_int_t *keys,
                                             double lb_per_metre, karst_paths_method_t method,
                                             double *dist);

karst_error_t karst_paths_keypoint_trees(karst_ctx_t *ctx, const karst_graph_t *g,
                                         karst_int_t n_keys, const karst_int_t *keys, double *dist,
                                         int32_t *pred);

karst_error_t karst_paths_keypoint_bounds(karst_ctx_t *ctx, const karst_graph_t *g,
                                          karst_int_t n_keys, const karst_int_t *keys, double *dist,
                                          float *bound);

karst_error_t karst_paths_tree_path(karst_ctx_t *ctx, const karst_graph_t *g,
                                    const int32_t *pred_row, karst_int_t source, karst_int_t target,
                                    karst_path_t *path);

#ifdef __cplusplus
}
#endif
#endif
