/**
 * @file cost.h
 * @brief Geology-based cost of a path (Paris et al. 2021, §4.2): the cost per
 *        metre c(p, d) = w0 + wL cL(p) + wF cF(d) + wπ cπ(p), its line
 *        integral along a graph edge, the bedrock membership tests that
 *        exclude edges, and a proven lower bound of c for admissible A*.
 */
#ifndef KARST_COST_H
#define KARST_COST_H

#include "karst/common.h"
#include "karst/geology.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Sub-interval length of the composite Gauss–Legendre rule used for the
 * permeability term, as a fraction of the smallest permeability feature
 * (sphere radius, sphere falloff, stratum thickness). Default 0.25: with the
 * 3-point rule and the kinks of the tree's primitives used as break points,
 * the relative error on a smooth falloff is below 1e-6 (see cost.c).
 */
#define KARST_COST_STEP_FRACTION 0.25
/** Upper bound on the sub-intervals of one quadrature piece (bounds the work per edge). */
#define KARST_COST_MAX_SUBINTERVALS 256
/**
 * An edge lies on a prescribed path when both its ends are within
 * sampling.feature_radius of the key-point pair's segment and the angle
 * between the edge and the segment is at most this many degrees. Default 30.
 */
#define KARST_COST_PRESCRIBED_MAX_ANGLE 30.0
/**
 * Relative safety margin subtracted from karst_cost_lower_bound_per_metre so
 * that rounding can never make the A* heuristic overestimate: the eigenvalue
 * and the edge integrals (~1e-15 relative) and, above all, the single-precision
 * arc costs (include/karst/graph.h), each rounded at most three times (stored,
 * routed, scaled by a generation's cohesion), at most (1 + 2^-24)^3 - 1 < 1.8e-7
 * relative. Default 1e-6.
 */
#define KARST_COST_LB_MARGIN 1e-6

/** Non-zero when @p p is in the bedrock (karst_geology_in_bedrock). */
int karst_cost_in_bedrock(const karst_geology_t *g, const double p[3]);

/** Non-zero when every point of the segment [a, b] is in the bedrock (exact test). */
int karst_cost_segment_in_bedrock(const karst_geology_t *g, const double a[3], const double b[3]);

/** Horizon term cL(p) in [0, 1] (1 when the scenario has no horizon). */
double karst_cost_horizon_term(const karst_geology_t *g, const double p[3]);

/**
 * Fracture term cF(d) = Σ w_k (n_k·d)² for the unit direction of @p dir (cheap
 * along a fracture plane, w_k across it; see cost.c for why this is the 3-D
 * form of the paper's Σ w_k (1 − (n_k·d)²)); with cost.fracture_combine = min,
 * min_k [W − w_k (1 − (n_k·d)²)], W = max_k w_k (cheap along any one family).
 */
double karst_cost_fracture_term(const karst_geology_t *g, const double dir[3]);

/** Cost per metre c(p, d) at point @p p in direction @p dir (need not be unit). */
double karst_cost_point(const karst_geology_t *g, const double p[3], const double dir[3]);

/** Line integral of c along the segment [a, b]; INFINITY when the segment leaves the bedrock. */
double karst_cost_edge(const karst_geology_t *g, const double a[3], const double b[3]);

/** A proven lower bound of c(p, d) (times the prescribed-path factor) over all p and unit d. */
double karst_cost_lower_bound_per_metre(const karst_scenario_t *sc);

#ifdef __cplusplus
}
#endif
#endif /* KARST_COST_H */
