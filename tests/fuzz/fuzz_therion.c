/**
 * @file fuzz_therion.c
 * @brief Fuzz target: Therion SQL export reader (karst_read_therion_sql on the input written to a
 * scratch ".sql" file).
 */
#include "fuzz_util.h"
#include "karst/network.h"
#include "karst/readers.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.sql", data, size);
  karst_network_t net;
  karst_network_init(&net);
  karst_fuzz_report(&ctx, karst_read_therion_sql(&ctx, path, &net));
  karst_network_destroy(&net);
  return 0;
}
