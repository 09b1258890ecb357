/**
 * @file fuzz_observed.c
 * @brief Fuzz target: published-metrics table as ranges (karst_metrics_observed_load on a
 *        scratch "fuzz.csv").
 */
#include "fuzz_util.h"
#include "karst/metrics.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.csv", data, size);
  karst_metrics_observed_t obs;
  karst_fuzz_report(&ctx, karst_metrics_observed_load(&ctx, path, &obs));
  return 0;
}
