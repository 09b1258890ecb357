/**
 * @file fuzz_crs.c
 * @brief Fuzz target: CRS parsing (karst_crs_create on the input as a C string: UTM/UPS zones,
 *        EPSG codes, PROJ strings, WKT, Survex's names; PROJ underneath).
 */
#include <stdlib.h>

#include "fuzz_util.h"
#include "karst/crs.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  char *text = karst_fuzz_cstr(data, size);
  karst_crs_t *c = NULL;
  if (karst_fuzz_report(&ctx, karst_crs_create(&ctx, text, &c)) == KARST_SUCCESS) karst_crs_free(c);
  free(text);
  return 0;
}
