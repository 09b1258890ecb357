/* TEMPORARY weak placeholders for the sampling / graph / cost stages (branch
 * `sampling`); the real, strong definitions replace them when that branch
 * lands. Remove this file then. */
#include "generate/pending_sampling.h"

__attribute__((weak)) karst_error_t karst_sampling_run(karst_ctx_t *ctx,
                                                       const karst_scenario_t *sc,
                                                       karst_rng_t *rng, karst_samples_t *out) {
  (void)sc, (void)rng, (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "sampling is not available yet");
}

__attribute__((weak)) karst_error_t karst_graph_build(karst_ctx_t *ctx,
                                                      const karst_scenario_t *sc,
                                                      const karst_samples_t *samples,
                                                      karst_graph_t *out) {
  (void)sc, (void)samples, (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "the sample graph is not available yet");
}

__attribute__((weak)) double karst_cost_lower_bound_per_metre(const karst_scenario_t *sc) {
  return sc->cost.w0 * (sc->n_prescribed > 0 ? sc->cost.prescribed : 1.0);
}
