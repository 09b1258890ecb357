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
 * Meridian convergence, in degrees, at grid point (x, y) of the coordinate
 * system described by @p crs (a .3d CS string such as "EPSG:32634",
 * "EPSG:7405", "+proj=utm +zone=34 +datum=WGS84", a Survex name such as
 * "UTM34N" or "OSGB:SD", or a latitude/longitude system, where it is 0).
 *
 * Sign convention (GeographicLib's gamma): the bearing of grid north measured
 * clockwise from true north, i.e. the rotation to ADD to a grid azimuth to
 * obtain a true azimuth: true = grid + degrees. Positive east of the central
 * meridian in the northern hemisphere; about (lon - lon0) sin(lat).
 *
 * Systems that cannot be converted offline fail with KARST_EUNSUPPORTED
 * ("coordinate system 'X' is not convertible offline: only UTM, the British
 * National Grid, PROJ +proj=tmerc and latitude/longitude systems are
 * supported"); a point outside the projection fails with KARST_ERANGE. Magnetic declination is not handled
 * here: Survex's cavern applies it when it reduces the survey.
 */
karst_error_t karst_crs_convergence(karst_ctx_t *ctx, const char *crs, double x, double y,
                                    double *degrees);

#ifdef __cplusplus
}
#endif
#endif
