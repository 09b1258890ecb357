/* Placeholder until the GeographicLib shim exists. */
#include "karst/crs.h"

karst_error_t karst_crs_convergence(karst_ctx_t *ctx, const char *crs, double x, double y,
                                    double *degrees) {
  (void)x, (void)y, (void)degrees;
  return karst_set_error(ctx, KARST_ENOTIMPL, "coordinate system '%s': conversion is not available yet", crs ? crs : "");
}
