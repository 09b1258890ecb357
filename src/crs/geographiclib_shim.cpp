// Thin extern "C" shim over GeographicLib (C. F. F. Karney, "Transverse
// Mercator with an accuracy of a few nanometers", J. Geodesy 85, 475-485,
// 2011): the meridian convergence of UTM, the British National Grid and
// general transverse Mercator grids, UTM/UPS conversions (crs_frame.c) and
// geodesics on WGS 84 (Karney, "Algorithms for geodesics", J. Geodesy 87,
// 43-55, 2013). All parsing lives in crs.c and crs_frame.c.
#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/OSGB.hpp>
#include <GeographicLib/TransverseMercator.hpp>
#include <GeographicLib/UTMUPS.hpp>

#include <exception>

#include "crs_internal.h"

extern "C" karst_error_t karst_i_geo_convergence(karst_ctx_t *ctx, const char *name,
                                                 const karst_i_crs_t *crs, double x, double y,
                                                 double *gamma) {
  double lat = 0, lon = 0, g = 0, k = 0;
  try {
    switch (crs->kind) {
    case KARST_I_CRS_UTM:
      GeographicLib::UTMUPS::Reverse(crs->zone, crs->northp, x, y, lat, lon, g, k);
      break;
    case KARST_I_CRS_OSGB:
      GeographicLib::OSGB::Reverse(x, y, lat, lon, g, k);
      break;
    case KARST_I_CRS_TMERC: {
      const GeographicLib::TransverseMercator tm(crs->a, crs->f, crs->k0);
      // GeographicLib's northings start at the equator: add the projected
      // northing of the latitude of origin.
      double x0, y0;
      tm.Forward(crs->lon0, crs->lat0, crs->lon0, x0, y0);
      tm.Reverse(crs->lon0, x - crs->fe, y - crs->fn + y0, lat, lon, g, k);
      break;
    }
    default:
      g = 0;
      break;
    }
  } catch (const std::exception &e) {
    return karst_set_error(ctx, KARST_ERANGE,
                           "coordinate system '%s': point (%.3f, %.3f) cannot be converted: %s",
                           name, x, y, e.what());
  } catch (...) {
    return karst_set_error(ctx, KARST_ERANGE,
                           "coordinate system '%s': point (%.3f, %.3f) cannot be converted", name,
                           x, y);
  }
  *gamma = g;
  return KARST_SUCCESS;
}

extern "C" karst_error_t karst_i_geo_utm_forward(karst_ctx_t *ctx, int zone, int northp, double lat,
                                                 double lon, double *x, double *y) {
  try {
    int z = 0;
    bool n = false;
    double g = 0, k = 0;
    GeographicLib::UTMUPS::Forward(lat, lon, z, n, *x, *y, g, k, zone);
    // Forward chooses the hemisphere from the latitude; the scenario's grid fixes it.
    if (n != (northp != 0)) *y += (northp ? -1 : 1) * GeographicLib::UTMUPS::UTMShift();
  } catch (const std::exception &e) {
    return karst_set_error(ctx, KARST_ERANGE,
                           "latitude %.9f, longitude %.9f cannot be put in %s %d%s: %s", lat, lon,
                           zone ? "UTM zone" : "UPS", zone, northp ? "N" : "S", e.what());
  }
  return KARST_SUCCESS;
}

extern "C" karst_error_t karst_i_geo_utm_reverse(karst_ctx_t *ctx, int zone, int northp, double x,
                                                 double y, double *lat, double *lon) {
  try {
    double g = 0, k = 0;
    GeographicLib::UTMUPS::Reverse(zone, northp != 0, x, y, *lat, *lon, g, k);
  } catch (const std::exception &e) {
    return karst_set_error(ctx, KARST_ERANGE, "grid point (%.3f, %.3f) is outside %s %d%s: %s", x,
                           y, zone ? "UTM zone" : "UPS", zone, northp ? "N" : "S", e.what());
  }
  return KARST_SUCCESS;
}

extern "C" karst_error_t karst_i_geo_inverse(karst_ctx_t *ctx, double lat1, double lon1,
                                             double lat2, double lon2, double *s12, double *azi1,
                                             double *azi2) {
  try {
    GeographicLib::Geodesic::WGS84().Inverse(lat1, lon1, lat2, lon2, *s12, *azi1, *azi2);
  } catch (const std::exception &e) {
    return karst_set_error(ctx, KARST_ERANGE, "geodesic from (%g, %g) to (%g, %g): %s", lat1, lon1,
                           lat2, lon2, e.what());
  }
  return KARST_SUCCESS;
}
