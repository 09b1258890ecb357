/**
 * @file fuzz_calibrate_param.c
 * @brief Fuzz target: calibrate's --param specification parser (karst_calibrate_param_parse on
 *        the input as a C string, e.g. "skeleton.gamma=log:0.5:3").
 */
#include <stdlib.h>

#include "fuzz_util.h"
#include "karst/calibrate.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  char *text = karst_fuzz_cstr(data, size);
  karst_calibrate_param_t p;
  karst_fuzz_report(&ctx, karst_calibrate_param_parse(&ctx, text, &p));
  free(text);
  return 0;
}
