/**
 * @file skeleton.h
 * @brief The large-scale skeleton of Paris et al. 2021, §5.1: the γ-skeleton
 *        of the key points under the least-cost metric, realised as the union
 *        of the kept least-cost paths on the sample graph.
 */
#ifndef KARST_SKELETON_H
#define KARST_SKELETON_H

#include <stdint.h>

#include "karst/common.h"
#include "karst/graph.h"
#include "karst/network.h"
#include "karst/paths.h"
#include "karst/routing.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * A network growing on a sample graph: each node is a graph vertex, each
 * edge a graph edge, added path by path (skeleton, then amplification).
 * The network carries node attribute "kind" and edge attributes "cost",
 * "branch_id" (index of the path that first laid the edge),
 * "amplification_step" (0 for the skeleton, s for amplification step s) and "spring"
 * (node and edge: the index among the springs of the spring the first route laying it drains
 * to, -1 unknown).
 */
/** Called by karst_skeleton_add_route after each path it lays (in laying order). */
typedef karst_error_t (*karst_skeleton_path_fn)(void *arg, const karst_path_t *path);

typedef struct karst_skeleton {
  karst_network_t net;
  karst_int_t n_graph;         /**< vertices of the graph the network lives on */
  karst_int_t *node_of_vertex; /**< n_graph entries, -1 when the vertex is not a node */
  karst_int_t *vertex_of_node; /**< graph vertex of each node */
  karst_int_t vertex_cap;      /**< allocated entries of vertex_of_node */
  karst_int_t n_paths;         /**< paths added so far (the next branch id) */
  uint64_t *edge_keys;         /**< open-addressing set of node pairs (min << 32 | max) + 1 */
  size_t edge_set_cap;
  karst_skeleton_path_fn on_path; /**< NULL, or told of every path laid (src/generations/) */
  void *on_path_arg;
} karst_skeleton_t;

karst_error_t karst_skeleton_init(karst_ctx_t *ctx, karst_skeleton_t *sk, const karst_graph_t *g);
void karst_skeleton_destroy(karst_skeleton_t *sk);

karst_error_t karst_skeleton_gamma_keep(karst_ctx_t *ctx, karst_int_t n, const double *dist,
                                        double gamma, unsigned char *keep);

karst_error_t karst_skeleton_add_path(karst_ctx_t *ctx, karst_skeleton_t *sk,
                                      const karst_graph_t *g, const karst_path_t *path,
                                      int amplification_step);

karst_error_t karst_skeleton_add_route(karst_ctx_t *ctx, karst_skeleton_t *sk,
                                       const karst_graph_t *g, const karst_path_t *path,
                                       int amplification_step, int spring);

karst_error_t karst_skeleton_mark_node(karst_ctx_t *ctx, karst_skeleton_t *sk,
                                       const karst_graph_t *g, karst_int_t vertex,
                                       karst_node_kind_t kind);

void karst_skeleton_mark_junctions(karst_skeleton_t *sk);

karst_error_t karst_skeleton_build(karst_ctx_t *ctx, const karst_graph_t *g, karst_int_t n_keys,
                                   const karst_int_t *keys, const double *dist, const int32_t *pred,
                                   const float *bound, double gamma, double reuse,
                                   double lb_per_metre, karst_skeleton_t *sk, karst_int_t *n_kept);

karst_error_t karst_skeleton_build_routes(karst_ctx_t *ctx, const karst_graph_t *g,
                                          const karst_routing_plan_t *plan, double reuse,
                                          double lb_per_metre, karst_skeleton_t *sk,
                                          karst_int_t *n_kept);

#ifdef __cplusplus
}
#endif
#endif
