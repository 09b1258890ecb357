/**
 * @file fuzz_vtp.c
 * @brief Fuzz target: .vtp network reader (karst_vtk_read_network on a scratch "fuzz.vtp": the
 *        C structure check of src/io/vtp_check.c, then VTK's XML reader on what passes it).
 */
#include "fuzz_util.h"
#include "karst/network.h"
#include "karst/vtk.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  const char *path = karst_fuzz_file("fuzz.vtp", data, size);
  karst_network_t net;
  karst_network_init(&net);
  karst_fuzz_report(&ctx, karst_vtk_read_network(&ctx, path, &net));
  karst_network_destroy(&net);
  return 0;
}
