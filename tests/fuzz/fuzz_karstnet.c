/**
 * @file fuzz_karstnet.c
 * @brief Fuzz target: Karstnet pair reader (karst_read_karstnet). The input is split at the
 *        first "\n@@links@@\n": what precedes it becomes the scratch fuzz_nodes.dat, what
 *        follows fuzz_links.dat (an input without the separator gives an empty links file).
 */
#include <string.h>

#include "fuzz_util.h"
#include "karst/network.h"
#include "karst/readers.h"

static const char SEP[] = "\n@@links@@\n";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const size_t sep_len = sizeof SEP - 1;
  size_t cut = size;
  for (size_t i = 0; i + sep_len <= size; i++) {
    if (memcmp(data + i, SEP, sep_len) == 0) {
      cut = i;
      break;
    }
  }
  const size_t rest = cut < size ? cut + sep_len : size;
  karst_ctx_t ctx;
  karst_fuzz_ctx(&ctx);
  (void)karst_fuzz_file("fuzz_links.dat", data + rest, size - rest);
  const char *path = karst_fuzz_file("fuzz_nodes.dat", data, cut);
  karst_network_t net;
  karst_network_init(&net);
  karst_fuzz_report(&ctx, karst_read_karstnet(&ctx, path, &net));
  karst_network_destroy(&net);
  return 0;
}
