/**
 * @file fuzz_points.c
 * @brief Fuzz target: point cloud reader of sampling.points (karst_points_load on a scratch
 *        "fuzz.xyz").
 */
#include <stdlib.h>

#include "fuzz_util.h"
#include "karst/scenario.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.xyz", data, size);
  double *xyz = NULL;
  long *lines = NULL;
  karst_int_t n = 0;
  if (karst_fuzz_report(&ctx, karst_points_load(&ctx, path, &xyz, &n, &lines)) == KARST_SUCCESS) {
    /* every point finite, one line per point */
    for (karst_int_t i = 0; i < 3 * n; i++)
      if (!(xyz[i] - xyz[i] == 0)) abort();
    for (karst_int_t i = 1; i < n; i++)
      if (!(lines[i] > lines[i - 1])) abort();
    free(xyz);
    free(lines);
  }
  return 0;
}
