/* Placeholder until the generation pipeline exists. */
#include "karst/generate.h"

karst_error_t karst_generate(karst_ctx_t *ctx, const karst_scenario_t *sc, uint64_t seed,
                             uint64_t realisation, karst_network_t *net, karst_samples_t *samples,
                             karst_generate_stats_t *stats) {
  (void)sc, (void)seed, (void)realisation, (void)net, (void)samples, (void)stats;
  return karst_set_error(ctx, KARST_ENOTIMPL, "network generation is not available yet");
}
