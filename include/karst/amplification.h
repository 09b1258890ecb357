/**
 * @file amplification.h
 * @brief Network amplification of Paris et al. 2021, §5.2: new dead-end and
 *        interior points connected to the skeleton by least-cost paths, then
 *        stochastic midpoint displacement controlled by the tortuosity θ.
 */
#ifndef KARST_AMPLIFICATION_H
#define KARST_AMPLIFICATION_H

#include "karst/common.h"
#include "karst/graph.h"
#include "karst/network.h"
#include "karst/scenario.h"
#include "karst/skeleton.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Constants of the amplification stage; karst_amplification_options_init gives the documented
 * defaults. */
typedef struct karst_amplification_options {
  double ratio_at_theta1; /**< largest midpoint displacement as a fraction of the piece split, for
                               θ = 1: 0.5 (so pieces never fold back); ρ(θ) = θ × this */
  double min_segment;     /**< segments shorter than 2 × this (m) are not subdivided: 1.0 */
  int max_levels; /**< recursion depth of the subdivision: 3 (an edge becomes ≤ 8 pieces) */
  int max_tries;  /**< rejection-sampling attempts for a point in the bedrock: 32 */
  double loop_separation; /**< an interior point's second path must end farther than
                               this × |p − first end| from the first end: 1.0 */
  long threaded_from;     /**< the ramification uses ctx->nthreads threads on graphs of at least
                               this many vertices, one below (the points' searches there cost
                               less than handing them between threads): 200 000. The network
                               does not depend on it. */
} karst_amplification_options_t;

void karst_amplification_options_init(karst_amplification_options_t *opt);

/** Largest midpoint displacement as a fraction of the piece split, for tortuosity θ ∈ [0, 1]. */
double karst_amplification_displacement_ratio(const karst_amplification_options_t *opt,
                                              double theta);

karst_error_t karst_amplification_ramify(karst_ctx_t *ctx, const karst_geology_t *geo,
                                         const karst_graph_t *g, const karst_routing_plan_t *plan,
                                         karst_rng_t *rng, const karst_amplification_options_t *opt,
                                         karst_skeleton_t *sk, karst_int_t *n_points,
                                         karst_int_t *n_paths);

karst_error_t karst_amplification_displace(karst_ctx_t *ctx, const karst_geology_t *geo,
                                           double theta, karst_rng_t *rng,
                                           const karst_amplification_options_t *opt,
                                           const karst_network_t *in, karst_network_t *out);

/** Non-zero when @p p is in the bedrock and strictly below the terrain. */
int karst_amplification_in_bedrock(const karst_geology_t *g, const double p[3]);

#ifdef __cplusplus
}
#endif
#endif
