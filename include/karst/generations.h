/**
 * @file generations.h
 * @brief Several speleogenetic phases in one realisation (docs/generation.md, "Generations"):
 *        each generation routes its own key points towards its own base level on the one sample
 *        graph, and sees the conduits of the generations before it at a cost factor (KarstNSim's
 *        polyphasic cohesion factor, Gouy et al. 2024), so a falling base level leaves
 *        multi-level caves whose younger conduits reuse the older ones where that is cheaper.
 */
#ifndef KARST_GENERATIONS_H
#define KARST_GENERATIONS_H

#include "karst/common.h"
#include "karst/graph.h"
#include "karst/paths.h"
#include "karst/scenario.h"
#include "karst/skeleton.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Number of generations a run of @p sc makes: max(1, sc->n_generations). O(1). */
int karst_generation_count(const karst_scenario_t *sc);

/**
 * The scenario as generation @p g (1-based) sees it: a shallow copy of @p sc whose routing,
 * skeleton.gamma, skeleton.reuse and amplification are the generation's and whose
 * active_generation is @p g. Without generations, @p g = 1 gives @p sc itself (active 0). The
 * view shares every pointer with @p sc: never destroy it. O(1).
 */
void karst_generation_view(const karst_scenario_t *sc, int g, karst_scenario_t *view);

/** Whether key point @p k takes part in the generation @p sc routes (active_generation). O(1). */
int karst_generation_key_active(const karst_scenario_t *sc, int k);

/** The cost factor generation @p g (1-based) applies to earlier conduits (1 for the first). */
double karst_generation_cohesion(const karst_scenario_t *sc, int g);

/** The base costs of graph arcs changed for one generation, to be put back exactly. */
typedef struct karst_inherited {
  karst_int_t n, cap;
  karst_int_t *arc; /**< arc indices into the graph's CSR arrays */
  double *cost;     /**< their costs before the change */
} karst_inherited_t;

void karst_inherited_init(karst_inherited_t *h);
void karst_inherited_destroy(karst_inherited_t *h);

/**
 * Multiply by @p factor the base cost of both arcs of every simulated edge of @p sk (edge
 * attribute "generation" > 0, "observed" = 0), remembering the old costs in @p saved. The
 * lower bound of the cost per metre becomes min(1, factor) times what it was.
 * Time complexity: O(edges × log degree).
 */
karst_error_t karst_generation_discount(karst_ctx_t *ctx, karst_graph_t *g,
                                        const karst_skeleton_t *sk, double factor,
                                        karst_inherited_t *saved);

/** Put back the costs @p saved holds (bit for bit) and empty it. O(saved). */
void karst_generation_restore(karst_graph_t *g, karst_inherited_t *saved);

/** What one generation added to a network (run.json "generations"). */
typedef struct karst_generation_stats {
  karst_int_t n_routes;       /**< routes its plan laid */
  karst_int_t n_new_edges;    /**< edges it added */
  double new_length;          /**< their length (m) */
  double reactivated_length;  /**< length (m) of earlier or surveyed conduits its paths follow */
} karst_generation_stats_t;

/**
 * Record, while generation @p g lays its paths into @p sk, which edges they follow; afterwards
 * karst_generation_track_finish sets the edge attribute "generation" = @p g on the edges it
 * added, "reactivated" = @p g on the earlier (or surveyed) edges its paths followed, and fills
 * @p stats. O(path lengths) while laying, O(edges) to finish.
 */
typedef struct karst_generation_track {
  int g;
  karst_int_t e0;           /**< edges before the generation */
  karst_int_t n, cap;
  karst_int_t *pairs;       /**< 2 per step of a path: graph vertices */
} karst_generation_track_t;

void karst_generation_track_begin(karst_generation_track_t *t, karst_skeleton_t *sk, int g);
karst_error_t karst_generation_track_finish(karst_ctx_t *ctx, karst_generation_track_t *t,
                                            karst_skeleton_t *sk,
                                            karst_generation_stats_t *stats);

#ifdef __cplusplus
}
#endif
#endif /* KARST_GENERATIONS_H */
