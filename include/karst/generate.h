/**
 * @file generate.h
 * @brief One realisation of the generation pipeline of Paris et al. 2021
 *        (§4–5): scenario -> sampling -> graph -> paths -> skeleton ->
 *        amplification -> classification -> network.
 */
#ifndef KARST_GENERATE_H
#define KARST_GENERATE_H

#include <stdio.h>

#include "karst/common.h"
#include "karst/generations.h"
#include "karst/graph.h"
#include "karst/network.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Timed stages of a realisation (karst_generate_stats_t.stage_seconds). The edge costs are
 * computed with the kNN graph (karst_graph_build) and timed as part of "graph". */
enum {
  KARST_STAGE_SAMPLING,
  KARST_STAGE_GRAPH,
  KARST_STAGE_PATHS,
  KARST_STAGE_SKELETON,
  KARST_STAGE_AMPLIFICATION,
  KARST_STAGE_CLASSIFICATION,
  KARST_STAGE_COUNT
};

/** What a realisation produced besides the network: counts and per-stage wall times. */
typedef struct karst_generate_stats {
  karst_int_t n_samples, n_graph_edges, n_key_points, n_skeleton_paths;
  karst_int_t n_points_kept; /**< samples taken from sampling.points (0 without it) */
  karst_int_t n_nodes, n_edges;
  double total_length;
  karst_int_t n_skeleton_nodes; /**< graph vertices on the skeleton S before amplification (#S of
                                   Table 1): surveyed legs and key-point routes, not the
                                   ramified branches */
  double skeleton_length;       /**< total length (m) of S before amplification (the same) */
  double stage_seconds[KARST_STAGE_COUNT];
  size_t peak_bytes; /**< peak resident memory of the process (VmHWM), for benchmarks */
  uint64_t seed, realisation; /**< of the realisation */
  int n_generations;          /**< generations run (1 without a generations section) */
  karst_generation_stats_t generations[KARST_SCENARIO_MAX_GENERATIONS];
  karst_int_t n_observed_edges; /**< surveyed legs in the network (edge attribute observed = 1) */
  double observed_length;       /**< their length (m) */
} karst_generate_stats_t;

/**
 * Generate realisation @p realisation of @p sc with base seed @p seed.
 * Every random draw comes from streams derived from (seed, realisation), so
 * the result does not depend on threads or processes. On success @p net
 * (initialised by the caller) holds the network with node attributes
 * "kind" (karst_node_kind_t), "water_table_distance" (m, positive above),
 * and edge attributes "tunnel_type", "radius", "cost", "vadose" (1 above the
 * water table), "branch_id", "amplification_step". When @p samples is not
 * NULL it receives the sample cloud. @p stats may be NULL.
 * A key point that cannot be connected fails with KARST_EUNREACHABLE and
 * names the key point in ctx->errmsg.
 */
karst_error_t karst_generate(karst_ctx_t *ctx, const karst_scenario_t *sc, uint64_t seed,
                             uint64_t realisation, karst_network_t *net, karst_samples_t *samples,
                             karst_generate_stats_t *stats);

/**
 * Write DIR/run.json-style provenance for one realisation to @p path,
 * atomically: scenario path and hash, seed, realisation, every effective
 * parameter, counts and stage wall times (the only place timings appear).
 */
karst_error_t karst_generate_write_run(karst_ctx_t *ctx, const char *path,
                                       const karst_scenario_t *sc, uint64_t seed,
                                       uint64_t realisation, const karst_generate_stats_t *stats);

/**
 * Write the effective parameters of @p sc as the members (no braces) of a JSON
 * object, one per line, 4-space indent: shared by run.json and ensemble.json.
 */
void karst_generate_write_parameters(FILE *fp, const karst_scenario_t *sc);

/** Name of a stage ("sampling", "graph", ...). */
const char *karst_stage_name(int stage);

#ifdef __cplusplus
}
#endif
#endif
