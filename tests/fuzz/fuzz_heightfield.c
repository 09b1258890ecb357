/**
 * @file fuzz_heightfield.c
 * @brief Fuzz target: ESRI ASCII grid reader (karst_terrain_load_grid on a scratch "fuzz.asc").
 */
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "karst/scenario.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.asc", data, size);
  karst_terrain_t t;
  memset(&t, 0, sizeof t);
  if (karst_fuzz_report(&ctx, karst_terrain_load_grid(&ctx, path, &t)) == KARST_SUCCESS) {
    free(t.z);
    free(t.path);
  }
  return 0;
}
