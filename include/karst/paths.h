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

/**
 * The two-stage hydrological view of the graph towards one spring (Paris et al. 2021 §3 and
 * KarstNSim, Gouy et al. 2024; docs/generation.md, "Routing"): per vertex its depth below the
 * spring's water table and its elevation, so that an arc u → w of base cost c (the geology's line
 * integral) costs
 *   - vadose stage (w above the epiphreatic band, or u above it): c × vadose_factor plus
 *     rise_cost per metre that w lies above u, and INFINITY when u is at or below the band and w
 *     above it (no rising back into the vadose zone);
 *   - phreatic stage (u and w within or below the band): c × (1 + e / phreatic_depth), e the mean
 *     depth of the arc below the band (exact for a depth linear along the arc).
 * Every routed cost is >= c (vadose_factor >= 1), so the lower bounds of the base costs stay
 * lower bounds (karst_cost_lower_bound_per_metre, and the network distances of path sharing).
 */
typedef struct karst_route {
  const float *dz;           /**< 2 per vertex: depth below the water table (m, > 0 below), z (m) */
  float band;                /**< epiphreatic band half-thickness (m), >= 0 */
  double vadose_factor;      /**< >= 1 */
  double rise_cost;          /**< >= 0, per metre of rise */
  double inv_phreatic_depth; /**< 1 / phreatic_depth (1/m), >= 0 */
  /** Optional tables (karst_route_tabulate), NULL when not made: the routed cost of every arc a
   *  of the graph (from v to its head w) in fwd[a], and of its reverse (w to v) in bwd[a], the
   *  same values the formula gives (rounded to single precision like the base costs, by the
   *  formula too), so searches read one value per arc instead of evaluating the formula on two
   *  vertices' depths. Only valid while the graph's costs are unchanged. */
  const karst_arc_cost_t *arc_fwd, *arc_bwd;
} karst_route_t;

/** Routed cost of arc u → w whose base cost is @p base (see karst_route_t), rounded to single
 *  precision like the stored costs (include/karst/graph.h). O(1). */
double karst_route_arc_cost(const karst_route_t *r, double base, karst_int_t u, karst_int_t w);

/**
 * Fill @p fwd and @p bwd (g->n_arcs each) with the routed costs of every arc of @p g under @p r
 * in both directions (see karst_route_t: arc_fwd, arc_bwd), the vertices split over
 * ctx->nthreads. The values do not depend on the thread count.
 * Time complexity: O(n_arcs / threads).
 */
void karst_route_tabulate(const karst_ctx_t *ctx, const karst_graph_t *g, const karst_route_t *r,
                          karst_arc_cost_t *fwd, karst_arc_cost_t *bwd);

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
/**
 * Record, from the next search on, every vertex a search touches (gives a distance to) in a
 * list, the trail (n 32-bit entries, allocated here). karst_paths_astar_reuse and
 * karst_paths_lower_distances record it; what a path-sharing A* read of the mutable state (arc
 * flags of the vertices it expanded, network distances of the vertices it touched) lies within
 * its trail, which is what lets the skeleton keep a speculative search (src/skeleton/).
 * @return KARST_SUCCESS or KARST_ENOMEM.
 */
karst_error_t karst_search_record_trail(karst_ctx_t *ctx, karst_search_t *s);
/** The trail of the last search (karst_search_record_trail), *n entries; NULL when not
 *  recording. Valid until the next search. */
const int32_t *karst_search_trail(const karst_search_t *s, karst_int_t *n);
/** Path from the last search's nearest source to @p v (which must have been settled). */
karst_error_t karst_search_path_to(karst_ctx_t *ctx, const karst_search_t *s, karst_int_t v,
                                   karst_path_t *path);

karst_error_t karst_paths_astar(karst_ctx_t *ctx, karst_search_t *s, karst_int_t source,
                                karst_int_t target, double lb_per_metre, karst_path_t *path);

karst_error_t karst_paths_dijkstra(karst_ctx_t *ctx, karst_search_t *s, karst_int_t n_sources,
                                   const karst_int_t *sources, const unsigned char *blocked,
                                   const unsigned char *is_target, karst_int_t stop_after,
                                   karst_int_t *last_target);

/** karst_paths_dijkstra on the routed costs of @p route (NULL: the base costs). */
karst_error_t karst_paths_dijkstra_routed(karst_ctx_t *ctx, karst_search_t *s,
                                          const karst_route_t *route, karst_int_t n_sources,
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
  double factor; /**< r in (0, 1] */
  const unsigned char
      *reused; /**< n_arcs tags, non-zero on both arcs of each network edge, or NULL */
  const double *dist_to_net;   /**< n lower bounds of the least original cost to the nearest network
                                    vertex that change by at most the arc cost along an arc: the
                                    exact costs (INFINITY while the network is empty), or those
                                    capped at any constant; NULL: taken as 0 (always safe).
                                    Being lower bounds, they are 0 at network vertices: the
                                    search reads the tags of a vertex's arcs only where the
                                    bound is not positive */
  int (*cancelled)(void *arg); /**< polled every 256 settled vertices: non-zero abandons the search
                                    with KARST_EINTERRUPTED; NULL: never */
  void *cancel_arg;            /**< passed to @c cancelled */
  unsigned char tag;          /**< discount only arcs whose tag is this one (0: any non-zero tag) */
  const karst_route_t *route; /**< routed costs (NULL: the base costs) */
  const unsigned char
      *closed; /**< n flags: vertices a path may not enter unless it ends there, or NULL */
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

/**
 * Least routed costs from sources to targets: one backward Dijkstra per target (the routed costs
 * are directed), target i with route routes[i], stopped once every source is settled, targets
 * spread over ctx->nthreads threads (the result does not depend on the count).
 * @param n_targets, targets  target vertices.
 * @param routes    one route per target (NULL entries: base costs).
 * @param closed    n flags: vertices a path may end at but not pass through (NULL: none).
 * @param n_sources, sources  source vertices.
 * @param dist      n_targets x n_sources output: least cost from source j to target i, INFINITY
 *                  when none (0 when the source is the target).
 * @param bound     (NULL or) n_targets x n output: row i a lower bound of the least cost from
 *                  every vertex to target i that changes by at most the arc cost along an arc
 *                  (the exact cost where the search settled the vertex, else the largest settled
 *                  cost), rounded down to float: the heuristic of karst_paths_astar_reuse.
 * @param succ      (NULL or) n_targets x n output: row i the next vertex towards target i on a
 *                  least-cost path (-1 at the target, -2 where not settled); see
 *                  karst_paths_row_path.
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ENOMEM, KARST_EINTERRUPTED.
 * Time complexity: O(targets (m + n) log n) in the worst case.
 */
karst_error_t karst_paths_target_rows(karst_ctx_t *ctx, const karst_graph_t *g,
                                      karst_int_t n_targets, const karst_int_t *targets,
                                      const karst_route_t *const *routes,
                                      const unsigned char *closed, karst_int_t n_sources,
                                      const karst_int_t *sources, double *dist, float *bound,
                                      int32_t *succ);

/** The path from @p source to the target of a succ row of karst_paths_target_rows, with its
 *  routed cost under @p route. KARST_EUNREACHABLE when the source was not settled. */
karst_error_t karst_paths_row_path(karst_ctx_t *ctx, const karst_graph_t *g,
                                   const int32_t *succ_row, const karst_route_t *route,
                                   karst_int_t source, karst_path_t *path);

#ifdef __cplusplus
}
#endif
#endif
