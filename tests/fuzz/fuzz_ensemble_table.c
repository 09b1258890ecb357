/**
 * @file fuzz_ensemble_table.c
 * @brief Fuzz target: an ensemble's metrics.csv reader (karst_ensemble_table_read on a scratch
 *        "metrics.csv").
 */
#include "fuzz_util.h"
#include "karst/ensemble.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("metrics.csv", data, size);
  karst_ensemble_table_t t;
  karst_ensemble_table_init(&t);
  karst_fuzz_report(&ctx, karst_ensemble_table_read(&ctx, path, &t));
  karst_ensemble_table_destroy(&t);
  return 0;
}
