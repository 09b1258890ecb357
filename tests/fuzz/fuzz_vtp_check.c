/**
 * @file fuzz_vtp_check.c
 * @brief Fuzz target: the C structure check of .vtp files (karst_i_vtp_check_buffer, which
 *        karst_vtk_read_network runs before VTK), from memory: many more inputs per second
 *        than the vtp target, which also starts VTK's reader.
 */
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/input_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  /* An exact-size heap copy, so that ASan sees any read past the end. */
  unsigned char *copy = malloc(size ? size : 1);
  if (!copy) abort();
  if (size > 0) memcpy(copy, data, size);
  karst_fuzz_report(&ctx, karst_i_vtp_check_buffer(&ctx, "fuzz.vtp", copy, size));
  free(copy);
  return 0;
}
