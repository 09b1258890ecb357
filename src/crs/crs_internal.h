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

/**
 * WGS 84 latitude/longitude (degrees) to UTM (@p zone 1..60) or UPS (@p zone 0) grid coordinates
 * in the hemisphere @p northp (GeographicLib::UTMUPS::Forward with the zone forced, Karney 2011).
 * Returns KARST_ERANGE (with the point in the message) outside the projection's domain.
 */
karst_error_t karst_i_geo_utm_forward(karst_ctx_t *ctx, int zone, int northp, double lat,
                                      double lon, double *x, double *y);

/** The inverse of karst_i_geo_utm_forward: grid coordinates to WGS 84 latitude/longitude. */
karst_error_t karst_i_geo_utm_reverse(karst_ctx_t *ctx, int zone, int northp, double x, double y,
                                      double *lat, double *lon);

/**
 * The geodesic between two WGS 84 points (GeographicLib::Geodesic, Karney 2013, J. Geodesy 87,
 * 43-55): distance @p s12 (m) and azimuths @p azi1, @p azi2 (degrees clockwise from north).
 */
karst_error_t karst_i_geo_inverse(karst_ctx_t *ctx, double lat1, double lon1, double lat2,
                                  double lon2, double *s12, double *azi1, double *azi2);

#ifdef __cplusplus
}
#endif
#endif
