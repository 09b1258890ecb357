/**
 * @file fuzz_published.c
 * @brief Fuzz target: published-metrics table reader of compare (karst_published_read on a
 *        scratch "fuzz.csv").
 */
#include "fuzz_util.h"
#include "karst/compare.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.csv", data, size);
  karst_published_t p;
  karst_published_init(&p);
  karst_fuzz_report(&ctx, karst_published_read(&ctx, path, &p));
  karst_published_destroy(&p);
  return 0;
}
