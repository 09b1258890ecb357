/* Placeholder until this reader exists. */
#include "karst/readers.h"

karst_error_t karst_read_survex3d(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: the Survex .3d reader is not available yet", path);
}
