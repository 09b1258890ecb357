/**
 * @file fuzz_scenario.c
 * @brief Fuzz target: scenario loading (karst_scenario_load on a scratch "fuzz.yaml": YAML,
 *        schema walk, cross-field rules; files it names are looked up beside it, in the scratch
 *        directory, where there are none).
 */
#include "fuzz_util.h"
#include "karst/scenario.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.yaml", data, size);
  karst_scenario_t sc;
  karst_scenario_init(&sc);
  karst_fuzz_report(&ctx, karst_scenario_load(&ctx, path, &sc));
  karst_scenario_destroy(&sc);
  return 0;
}
