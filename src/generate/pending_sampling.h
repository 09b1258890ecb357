/* TEMPORARY: declarations of the sampling / graph / cost API (branch
 * `sampling`, see issue 3) until that branch lands on main; remove this file
 * and pending_sampling.c then. The prototypes are the agreed ones. */
#ifndef KARST_PENDING_SAMPLING_H
#define KARST_PENDING_SAMPLING_H

#include "karst/graph.h"
#include "karst/scenario.h"

karst_error_t karst_sampling_run(karst_ctx_t *ctx, const karst_scenario_t *sc, karst_rng_t *rng,
                                 karst_samples_t *out);
karst_error_t karst_graph_build(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                const karst_samples_t *samples, karst_graph_t *out);
double karst_cost_lower_bound_per_metre(const karst_scenario_t *sc);

#endif
