// Thin extern "C" shim over GeographicLib (C. F. F. Karney, "Transverse
// Mercator with an accuracy of a few nanometers", J. Geodesy 85, 475-485,
// 2011): the meridian convergence of UTM, the British National Grid and
// general transverse Mercator grids. All parsing lives in crs.c.
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
