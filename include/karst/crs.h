/**
 * @file crs.h
 * @brief Coordinate systems of survey data (thin C interface over
 *        GeographicLib in src/crs/geographiclib_shim.cpp).
 */
#ifndef KARST_CRS_H
#define KARST_CRS_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Meridian convergence (degrees, the angle from grid north to true north,
 * positive when true north is west... see docs/metrics.md for the sign
 * convention) at grid point (x, y) of the coordinate system described by
 * @p crs (a Survex CS string such as "+proj=utm +zone=34 ..." or "EPSG:32634",
 * or a latitude/longitude system, where it is 0). Systems that cannot be
 * converted offline fail with KARST_EUNSUPPORTED and a message naming them.
 */
karst_error_t karst_crs_convergence(karst_ctx_t *ctx, const char *crs, double x, double y,
                                    double *degrees);

#ifdef __cplusplus
}
#endif
#endif
