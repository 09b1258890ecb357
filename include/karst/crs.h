/**
 * @file crs.h
 * @brief Coordinate systems of survey data (thin C interface over
 *        GeographicLib in src/crs/geographiclib_shim.cpp).
 */
#ifndef KARST_CRS_H
#define KARST_CRS_H

#include <stddef.h>

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
 * supported"); a point outside the projection fails with KARST_ERANGE. Magnetic declination is not
 * handled here: Survex's cavern applies it when it reduces the survey.
 */
karst_error_t karst_crs_convergence(karst_ctx_t *ctx, const char *crs, double x, double y,
                                    double *degrees);

/* ------------------------------------------------------------------------ */
/* The coordinate reference system of a scenario (src/crs/crs_frame.c)       */
/* ------------------------------------------------------------------------ */

/** Longest CRS text accepted (bytes, with the terminating NUL). */
#define KARST_CRS_TEXT_MAX 1024

/** A parsed coordinate reference system (opaque). */
typedef struct karst_crs karst_crs_t;

/** Parse a CRS: a UTM zone ("UTM 30N"), "UPS N|S", an EPSG code, a PROJ string, WKT, or Survex's
 *  "LONG-LAT" / "OSGB:XY". See crs_frame.c. */
karst_error_t karst_crs_create(karst_ctx_t *ctx, const char *text, karst_crs_t **out);
void karst_crs_free(karst_crs_t *c);
/** The CRS as given (trimmed). */
const char *karst_crs_text(const karst_crs_t *c);
/** Its authority code ("EPSG:32630"), or NULL when it has none. */
const char *karst_crs_id(const karst_crs_t *c);
/** Non-zero when its coordinates are longitude, latitude (degrees). */
int karst_crs_is_geographic(const karst_crs_t *c);
/** The CRS as WKT2:2019; caller frees. */
karst_error_t karst_crs_wkt(karst_ctx_t *ctx, const karst_crs_t *c, char **wkt);
/** The CRS as a PROJ string; caller frees. */
karst_error_t karst_crs_proj_string(karst_ctx_t *ctx, const karst_crs_t *c, char **s);

/** Convert @p n points (x, y, z triples, z unchanged) from @p src to @p dst in place. */
karst_error_t karst_crs_transform(karst_ctx_t *ctx, const karst_crs_t *src, const karst_crs_t *dst,
                                  karst_int_t n, double *xyz);
/** WGS 84 longitude, latitude (2 per point) of @p n points (3 per point) of @p crs. */
karst_error_t karst_crs_to_lonlat(karst_ctx_t *ctx, const karst_crs_t *crs, karst_int_t n,
                                  const double *xyz, double *lonlat);
/** x, y of @p n points of @p crs (3 per point, z untouched) from WGS 84 longitude, latitude. */
karst_error_t karst_crs_from_lonlat(karst_ctx_t *ctx, const karst_crs_t *crs, karst_int_t n,
                                    const double *lonlat, double *xyz);
/** The method and accuracy (m; 0 exact, -1 unknown) of converting (x, y) from @p src to @p dst. */
karst_error_t karst_crs_describe(karst_ctx_t *ctx, const karst_crs_t *src, const karst_crs_t *dst,
                                 double x, double y, char *what, size_t size, double *accuracy);
/** Geodesic distance (m) and azimuths (degrees) between two WGS 84 points (GeographicLib). */
karst_error_t karst_crs_geodesic(karst_ctx_t *ctx, double lat1, double lon1, double lat2,
                                 double lon2, double *s12, double *azi1, double *azi2);

#ifdef __cplusplus
}
#endif
#endif
