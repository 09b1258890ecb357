/* Placeholder until the metrics exist. */
#include "karst/metrics.h"

karst_error_t karst_metrics_compute(karst_ctx_t *ctx, const karst_network_t *net,
                                    const karst_metrics_options_t *opt, karst_metrics_t *out) {
  (void)net, (void)opt, (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "metrics are not available yet");
}
