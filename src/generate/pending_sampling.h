/* TEMPORARY: the sampling / graph / cost API (branch `sampling`, issue 3)
 * until that branch is on main: its own headers when present, otherwise the
 * agreed prototypes. Delete this file and pending_sampling.c then. */
#ifndef KARST_PENDING_SAMPLING_H
#define KARST_PENDING_SAMPLING_H

#include "karst/graph.h"
#include "karst/scenario.h"

#if __has_include("karst/sampling.h")
#include "karst/sampling.h"
#else
karst_error_t karst_sampling_run(karst_ctx_t *ctx, const karst_scenario_t *sc, karst_rng_t *rng,
                                 karst_samples_t *out);
karst_error_t karst_graph_build(karst_ctx_t *ctx, const karst_scenario_t *sc,
                                const karst_samples_t *samples, karst_graph_t *out);
#endif
#if __has_include("karst/cost.h")
#include "karst/cost.h"
#else
double karst_cost_lower_bound_per_metre(const karst_scenario_t *sc);
#endif

#endif
