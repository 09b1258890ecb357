/* Placeholders until the readers exist (each moves to its own file). */
#include "karst/readers.h"

#define KARST_STUB_READER(fn, what)                                                      \
  karst_error_t fn(karst_ctx_t *ctx, const char *path, karst_network_t *net) {           \
    (void)net;                                                                           \
    return karst_set_error(ctx, KARST_ENOTIMPL, "%s: " what " is not available yet", path); \
  }
KARST_STUB_READER(karst_read_karstnet, "the Karstnet reader")
KARST_STUB_READER(karst_read_pline, "the GOCAD PLine reader")
KARST_STUB_READER(karst_read_therion_sql, "the Therion SQL reader")
KARST_STUB_READER(karst_read_survex3d, "the Survex .3d reader")
KARST_STUB_READER(karst_read_svx, "the Survex .svx reader")

karst_error_t karst_read_network(karst_ctx_t *ctx, const char *path, karst_format_t format,
                                 karst_network_t *net) {
  (void)format, (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: reading networks is not available yet", path);
}
karst_error_t karst_write_karstnet(karst_ctx_t *ctx, const char *prefix, const karst_network_t *net) {
  (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: the Karstnet writer is not available yet", prefix);
}
