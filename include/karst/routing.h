/**
 * @file routing.h
 * @brief Which key points connect, and how water flows between them: two-stage vadose /
 *        phreatic routing towards each spring's water table, sinks draining to springs under a
 *        connectivity matrix, waypoints passed on the way, and the γ rule of Paris et al. 2021
 *        (§5.1) applied within these rules. The result is the ordered list of routes the
 *        skeleton lays (src/skeleton/). Model and proofs: docs/generation.md, "Routing".
 */
#ifndef KARST_ROUTING_H
#define KARST_ROUTING_H

#include <stdint.h>

#include "karst/common.h"
#include "karst/geology.h"
#include "karst/graph.h"
#include "karst/paths.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Memory (bytes) a plan may spend on tabulated routed arc costs (8 bytes per arc per spring,
 *  karst_route_tabulate); beyond it the searches evaluate the same formula per arc (same values,
 *  slower: on the looping cave the tables take the routing searches from 0.33 to 0.22 s and the
 *  skeleton's from 0.58 to 0.35 s, 2 threads). 256 MiB: about 33 M arcs with one spring. */
#define KARST_ROUTING_ARC_BUDGET ((size_t)1 << 28)
/** A spring's costs are tabulated before its waypoints' routing rows when at least this many
 *  rows use them (a row relaxes every arc once; tabulating costs about two), */
#define KARST_ROUTING_TABULATE_MIN_ROWS 3
/** or, with path sharing, before the skeleton when at least this many routes drain to it (each
 *  A* search relaxes a thin shell of the graph; on the looping cave 990 routes relax 97 M arcs,
 *  against 2.3 M tabulated). */
#define KARST_ROUTING_TABULATE_MIN_ROUTES 64

/** One route: a least-cost path to lay from key point @c src to key point @c dst. */
typedef struct karst_route_pair {
  double d;     /**< least routed cost from src to dst (before path sharing) */
  int src, dst; /**< key-point indices (graph vertices src, dst) */
  int target;   /**< index of dst among the plan's targets (its rows) */
  int spring;   /**< the spring the route drains to (index among springs) */
  int required; /**< 1: a required connection (connectivity 2 or drains_to), never pruned */
} karst_route_pair_t;

/** What karst_routing_plan computes for one realisation. */
typedef struct karst_routing_plan {
  int n_keys, n_springs, n_targets;
  float *dz;             /**< 2 n per spring: depth below its water table, z (karst_route_t) */
  karst_route_t *routes; /**< one per spring */
  karst_arc_cost_t **arc_costs; /**< per spring: its route's tabulated costs (2 n_arcs: arc_fwd then
                              arc_bwd), or NULL (too few searches, or beyond the budget: all
                              together stay within KARST_ROUTING_ARC_BUDGET) */
  int *targets;          /**< key-point index of each target: springs first, then waypoints */
  float *bound;          /**< n_targets x n lower-bound rows (path-sharing heuristic), or NULL */
  int32_t *succ;         /**< n_targets x n successor rows (plain union), or NULL */
  unsigned char *closed; /**< n flags: sinks and springs, which a path may not pass through */
  int *key_spring;       /**< per key point: the spring it drains to (a spring: itself), -1 */
  unsigned char *active; /**< per key point: 1 when it takes part in the generation routed
                              (scenario.active_generation; without generations every one) */
  int n_pairs;           /**< kept routes, in the order they are laid: increasing d */
  karst_route_pair_t *pairs;
  int n_candidates; /**< routes the rules allowed, before the γ rule */
} karst_routing_plan_t;

void karst_routing_plan_init(karst_routing_plan_t *plan);
void karst_routing_plan_destroy(karst_routing_plan_t *plan);

/** Free the plan's rows (bound, succ), which only the skeleton reads, so that the stages after
 *  it (the amplification's workspaces) do not add to them: n × targets × 4 bytes. O(1). */
void karst_routing_plan_drop_rows(karst_routing_plan_t *plan);

/** The route (routed costs) of spring @p spring in @p plan. */
const karst_route_t *karst_routing_route(const karst_routing_plan_t *plan, int spring);

/**
 * Build the routing plan of graph @p g (whose vertices 0 .. n_keys − 1 are the scenario's key
 * points) under geology @p geo, for the key points of the generation the geology's scenario
 * routes (karst_generation_key_active; the others are plain vertices): per spring the vertex depths
 * below its water table; one backward search per spring, then one per waypoint (each waypoint
 * drains to the spring it reaches most cheaply); each sink's springs (required ones from the
 * connectivity matrix or drains_to, else the cheapest allowed one); the candidate routes sink →
 * spring, sink → waypoint (whose spring the sink may drain to), waypoint → its spring, waypoint →
 * waypoint of the same spring; then the γ rule with waypoints as the only intermediates. @p
 * want_succ asks for successor rows (plain union, skeleton.reuse = 1), otherwise lower-bound rows
 * are kept for path sharing.
 * @return KARST_SUCCESS; KARST_EUNREACHABLE naming the key points (FILE:LINE:COLUMN) when a
 *         required connection, a sink's every allowed spring, or a waypoint's every spring is out
 *         of reach; KARST_EINVAL, KARST_ENOMEM, KARST_EINTERRUPTED.
 * Time complexity: O(targets (m + n) log n) for the searches, O(k³) for the γ rule.
 */
karst_error_t karst_routing_plan(karst_ctx_t *ctx, const karst_geology_t *geo,
                                 const karst_graph_t *g, int want_succ, karst_routing_plan_t *plan);

#ifdef __cplusplus
}
#endif
#endif /* KARST_ROUTING_H */
