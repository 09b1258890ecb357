/* Placeholder until the format dispatcher and the Karstnet writer exist. */
#include "karst/readers.h"

karst_error_t karst_read_network(karst_ctx_t *ctx, const char *path, karst_format_t format,
                                 karst_network_t *net) {
  (void)format, (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: reading networks is not available yet", path);
}
karst_error_t karst_write_karstnet(karst_ctx_t *ctx, const char *prefix, const karst_network_t *net) {
  (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: the Karstnet writer is not available yet", prefix);
}
