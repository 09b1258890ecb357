/**
 * @file fuzz_image.c
 * @brief Fuzz target: relief image reader (karst_image_read, which tells PGM P2/P5 from PNG by
 *        content; the scratch file is named .png or .pgm to match).
 */
#include <string.h>

#include "fuzz_util.h"
#include "karst/image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const int png = size >= 4 && memcmp(data, "\x89PNG", 4) == 0;
  const char *path = karst_fuzz_file(png ? "fuzz.png" : "fuzz.pgm", data, size);
  karst_image_t img;
  karst_image_init(&img);
  karst_fuzz_report(&ctx, karst_image_read(&ctx, path, &img));
  karst_image_destroy(&img);
  return 0;
}
