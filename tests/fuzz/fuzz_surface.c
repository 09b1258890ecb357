/**
 * @file fuzz_surface.c
 * @brief Fuzz target: surface reader (karst_surface_load on a scratch "fuzz.ts": a GOCAD TSurf,
 *        or an ESRI grid, told apart by content).
 */
#include "fuzz_util.h"
#include "karst/surface.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.ts", data, size);
  karst_surface_t *s = NULL;
  if (karst_fuzz_report(&ctx, karst_surface_load(&ctx, path, &s)) == KARST_SUCCESS)
    karst_surface_free(s);
  return 0;
}
