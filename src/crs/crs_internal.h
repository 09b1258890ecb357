/**
 * @file crs_internal.h
 * @brief Private interface between the coordinate-system parser (crs.c, C)
 *        and the thin GeographicLib shim (geographiclib_shim.cpp).
 */
#ifndef KARST_CRS_INTERNAL_H
#define KARST_CRS_INTERNAL_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How grid coordinates map to the ellipsoid. */
typedef enum {
  KARST_I_CRS_GEOGRAPHIC = 0, /**< x, y are longitude, latitude: grid north is true north */
  KARST_I_CRS_UTM,            /**< UTM on WGS84 (GeographicLib::UTMUPS) */
  KARST_I_CRS_OSGB,           /**< British National Grid (GeographicLib::OSGB) */
  KARST_I_CRS_TMERC           /**< any transverse Mercator (GeographicLib::TransverseMercator) */
} karst_i_crs_kind_t;

typedef struct karst_i_crs {
  karst_i_crs_kind_t kind;
  int zone, northp;  /**< UTM */
  double a, f;       /**< TMERC ellipsoid: semi-major axis (m), flattening */
  double k0;         /**< TMERC scale on the central meridian */
  double lat0, lon0; /**< TMERC origin (degrees) */
  double fe, fn;     /**< false easting / northing (m), added to every coordinate */
} karst_i_crs_t;

/**
 * Meridian convergence (degrees; GeographicLib's gamma, the bearing of grid
 * north measured clockwise from true north) at grid point (@p x, @p y) of a
 * UTM, OSGB or TMERC system. @p name is the CRS string for messages.
 * Returns KARST_ERANGE when the point is outside the projection's domain.
 */
karst_error_t karst_i_geo_convergence(karst_ctx_t *ctx, const char *name, const karst_i_crs_t *crs,
                                      double x, double y, double *gamma);

#ifdef __cplusplus
}
#endif
#endif
