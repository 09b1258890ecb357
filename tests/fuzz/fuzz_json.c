/**
 * @file fuzz_json.c
 * @brief Fuzz target: karst_json_parse on the input bytes, from memory (not NUL-terminated).
 */
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "karst/json.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  /* An exact-size heap copy, so that ASan sees any read past the end. */
  char *text = malloc(size ? size : 1);
  if (!text) {
    abort();
  }
  if (size > 0) {
    memcpy(text, data, size);
  }
  karst_json_t *v = NULL;
  if (karst_fuzz_report(&ctx, karst_json_parse(&ctx, "fuzz.json", text, size, &v)) ==
      KARST_SUCCESS) {
    karst_json_free(v);
  }
  free(text);
  return 0;
}
