/* Coordinate systems: meridian convergence (karst_crs_convergence).
 *
 * Expected values are independent of GeographicLib:
 *  - grid coordinates of a chosen latitude/longitude come from the Ordnance
 *    Survey's published worked example (BNG) or from Snyder's ellipsoidal
 *    transverse Mercator series implemented below (Snyder 1987, "Map
 *    Projections: A Working Manual", USGS PP 1395, eqs. 3-21, 8-9, 8-10;
 *    millimetre-accurate within a few degrees of the central meridian);
 *  - the convergence at that latitude/longitude comes from the classical
 *    series gamma = dl sin(phi) [1 + dl^2 cos^2(phi) (1 + 3 eta^2 + 2 eta^4) / 3
 *    + dl^4 cos^4(phi) (2 - tan^2(phi)) / 15] (Redfearn 1948), whose
 *    truncation error is below 1e-7 degrees here; and, to ~0.01 degree, from
 *    the spherical approximation gamma = dl sin(phi).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "karst.h"
#include "test_util.h"

#define DEG (M_PI / 180.0)

typedef struct ellps {
  double a, f;
} ellps_t;
static const ellps_t WGS84 = {6378137.0, 1 / 298.257223563};
/* Airy 1830 as defined by the Ordnance Survey: a = 6377563.396, b = 6356256.909. */
static const ellps_t AIRY = {6377563.396, (6377563.396 - 6356256.909) / 6377563.396};

/* Redfearn's series for the convergence (degrees) at (lat, lon), central meridian lon0. */
static double series_gamma(ellps_t e, double lat, double lon, double lon0) {
  double e2 = e.f * (2 - e.f), ep2 = e2 / (1 - e2);
  double p = lat * DEG, l = (lon - lon0) * DEG, c = cos(p), t = tan(p), eta2 = ep2 * c * c;
  return l * sin(p) *
         (1 + l * l * c * c * (1 + 3 * eta2 + 2 * eta2 * eta2) / 3 +
          pow(l, 4) * pow(c, 4) * (2 - t * t) / 15) /
         DEG;
}

/* Snyder's meridian distance (eq. 3-21). */
static double snyder_m(ellps_t e, double p) {
  double e2 = e.f * (2 - e.f), e4 = e2 * e2, e6 = e4 * e2;
  return e.a * ((1 - e2 / 4 - 3 * e4 / 64 - 5 * e6 / 256) * p -
                (3 * e2 / 8 + 3 * e4 / 32 + 45 * e6 / 1024) * sin(2 * p) +
                (15 * e4 / 256 + 45 * e6 / 1024) * sin(4 * p) - (35 * e6 / 3072) * sin(6 * p));
}

/* Snyder's ellipsoidal transverse Mercator forward (eqs. 8-9, 8-10). */
static void snyder_tm(ellps_t e, double k0, double lat0, double lon0, double fe, double fn,
                      double lat, double lon, double *x, double *y) {
  double e2 = e.f * (2 - e.f), ep2 = e2 / (1 - e2), p = lat * DEG;
  double n = e.a / sqrt(1 - e2 * sin(p) * sin(p)), t = tan(p) * tan(p);
  double c = ep2 * cos(p) * cos(p), a = (lon - lon0) * DEG * cos(p);
  *x = fe + k0 * n *
                (a + (1 - t + c) * pow(a, 3) / 6 +
                 (5 - 18 * t + t * t + 72 * c - 58 * ep2) * pow(a, 5) / 120);
  *y = fn + k0 * (snyder_m(e, p) - snyder_m(e, lat0 * DEG) +
                  n * tan(p) *
                      (a * a / 2 + (5 - t + 9 * c + 4 * c * c) * pow(a, 4) / 24 +
                       (61 - 58 * t + t * t + 600 * c - 330 * ep2) * pow(a, 6) / 720));
}

static double conv(const char *crs, double x, double y) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double g = NAN;
  karst_error_t err = karst_crs_convergence(&ctx, crs, x, y, &g);
  if (err) print_error("%s: %s\n", crs, ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  return g;
}

/* Snyder's forward itself reproduces the Ordnance Survey's worked example
 * (to 1 mm), which validates it as the independent source of grid points. */
static void test_snyder_reference(void **state) {
  (void)state;
  double lat = 52 + 39 / 60.0 + 27.2531 / 3600, lon = 1 + 43 / 60.0 + 4.5177 / 3600, x, y;
  snyder_tm(AIRY, 0.9996012717, 49, -2, 400000, -100000, lat, lon, &x, &y);
  assert_close(x, 651409.903, 1e-3);
  assert_close(y, 313177.270, 1e-3);
}

/* British National Grid: the OS worked example ("A guide to coordinate
 * systems in Great Britain", Annex C: 52°39'27.2531"N 1°43'4.5177"E is
 * E 651409.903 N 313177.270). Expected gamma from the series: 2.95737670 deg. */
static void test_bng(void **state) {
  (void)state;
  double lat = 52 + 39 / 60.0 + 27.2531 / 3600, lon = 1 + 43 / 60.0 + 4.5177 / 3600;
  double expect = series_gamma(AIRY, lat, lon, -2);
  assert_close(expect, 2.95737670, 1e-8); /* the series evaluated by hand (Python) */
  assert_close(conv("EPSG:27700", 651409.903, 313177.270), expect, 1e-6);
  assert_close(conv("EPSG:7405", 651409.903, 313177.270), expect, 1e-6);
  /* The same grid as a PROJ string, through the generic transverse Mercator. */
  assert_close(conv("+proj=tmerc +lat_0=49 +lon_0=-2 +k=0.9996012717 +x_0=400000 +y_0=-100000 "
                    "+a=6377563.396 +b=6356256.909 +units=m +no_defs",
                    651409.903, 313177.270),
               expect, 1e-6);
  /* Survex's OSGB:TG: coordinates relative to the SW corner of square TG (600 km E, 300 km N). */
  assert_close(conv("OSGB:TG", 51409.903, 13177.270), conv("EPSG:27700", 651409.903, 313177.270),
               1e-12);
  /* On the central meridian (2W) grid north is true north. */
  double x, y;
  snyder_tm(AIRY, 0.9996012717, 49, -2, 400000, -100000, 54.2, -2, &x, &y);
  assert_close(x, 400000, 1e-6);
  assert_close(conv("EPSG:27700", x, y), 0.0, 1e-9);
}

/* UTM 34N at 19.87E 49.25N (the Tatra caves): about -0.86 deg (tatra SOURCE.txt);
 * series -0.8560961344; spherical approximation (19.87-21) sin(49.25) = -0.85605. */
static void test_utm_north(void **state) {
  (void)state;
  double x, y;
  snyder_tm(WGS84, 0.9996, 0, 21, 500000, 0, 49.25, 19.87, &x, &y);
  double expect = series_gamma(WGS84, 49.25, 19.87, 21);
  assert_close(expect, -0.8560961344, 1e-9);
  const char *names[] = {"EPSG:32634", "UTM34N", "utm34n", " EPSG:32634 ",
                         "+proj=utm +zone=34 +datum=WGS84 +units=m +no_defs"};
  for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
    double g = conv(names[i], x, y);
    assert_close(g, expect, 1e-6);
    assert_close(g, -0.86, 0.005);
    assert_close(g, (19.87 - 21) * sin(49.25 * DEG), 0.01);
  }
  /* East of the central meridian in the north: positive (grid north is east of true north). */
  snyder_tm(WGS84, 0.9996, 0, 21, 500000, 0, 49.25, 22.5, &x, &y);
  assert_true(conv("EPSG:32634", x, y) > 0);
  assert_close(conv("EPSG:32634", x, y), series_gamma(WGS84, 49.25, 22.5, 21), 1e-6);
  /* ETRS89 / UTM 34N (GRS80) differs from WGS 84 by far less than 1e-6 deg. */
  assert_close(conv("EPSG:25834", x, y), conv("EPSG:32634", x, y), 1e-6);
}

/* Southern hemisphere (UTM 33S, 14E 20S): west of the meridian in the south,
 * dl < 0 and sin(phi) < 0, so the convergence is positive. */
static void test_utm_south(void **state) {
  (void)state;
  double x, y;
  snyder_tm(WGS84, 0.9996, 0, 15, 500000, 10000000, -20, 14, &x, &y);
  double expect = series_gamma(WGS84, -20, 14, 15);
  assert_true(expect > 0.34 && expect < 0.35); /* (14-15) sin(-20) = 0.342 */
  assert_close(conv("EPSG:32733", x, y), expect, 1e-6);
  assert_close(conv("UTM33S", x, y), expect, 1e-6);
  assert_close(conv("+proj=utm +zone=33 +south +ellps=WGS84", x, y), expect, 1e-6);
}

/* Latitude/longitude systems: grid north is true north. */
static void test_geographic(void **state) {
  (void)state;
  const char *names[] = {"EPSG:4326", "EPSG:4258", "LONG-LAT", "+proj=longlat +datum=WGS84",
                         "+proj=latlong +ellps=GRS80"};
  for (size_t i = 0; i < sizeof names / sizeof *names; i++)
    assert_true(conv(names[i], 19.87, 49.25) == 0.0);
}

static void expect_error(const char *crs, double x, double y, karst_error_t code,
                         const char *fragment) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double g = 12345;
  karst_error_t err = karst_crs_convergence(&ctx, crs, x, y, &g);
  if (err != code || !strstr(ctx.errmsg, fragment))
    print_error("'%s': got %s '%s', expected %s with '%s'\n", crs ? crs : "(null)",
                karst_error_name(err), ctx.errmsg, karst_error_name(code), fragment);
  assert_int_equal(err, code);
  assert_non_null(strstr(ctx.errmsg, fragment));
  assert_true(g == 12345); /* output untouched on failure */
}

static void test_errors(void **state) {
  (void)state;
  /* Not convertible offline: named in the message, never guessed. */
  expect_error("EPSG:3857", 0, 0, KARST_EUNSUPPORTED,
               "coordinate system 'EPSG:3857' is not convertible offline");
  expect_error("+proj=lcc +lat_1=49 +lat_2=44 +lon_0=3", 0, 0, KARST_EUNSUPPORTED,
               "is not convertible offline");
  expect_error("IJTSK", 0, 0, KARST_EUNSUPPORTED, "'IJTSK' is not convertible offline");
  /* ... and says why: what is understood offline (Poland's CS92, a transverse Mercator known
   * only by its EPSG code, is not). */
  expect_error("EPSG:2180", 500000, 400000, KARST_EUNSUPPORTED,
               "coordinate system 'EPSG:2180' is not convertible offline: only UTM, the British "
               "National Grid, PROJ +proj=tmerc and latitude/longitude systems are supported");
  expect_error("+proj=utm +zone=31 +units=us-ft", 0, 0, KARST_EUNSUPPORTED, "not convertible");
  expect_error("EPSG:32661", 0, 0, KARST_EUNSUPPORTED, "not convertible"); /* UPS north */
  expect_error("", 0, 0, KARST_EUNSUPPORTED, "no coordinate system");
  expect_error(NULL, 0, 0, KARST_EUNSUPPORTED, "no coordinate system");
  /* Malformed PROJ parameters. */
  expect_error("+proj=utm +zone=61", 500000, 0, KARST_EINVAL, "+zone=61");
  expect_error("+proj=utm", 500000, 0, KARST_EINVAL, "without +zone");
  expect_error("+proj=tmerc +lat_0=abc", 0, 0, KARST_EINVAL, "+lat_0=abc");
  /* Points that are not positions of the system. */
  expect_error("EPSG:32634", NAN, 0, KARST_EINVAL, "not finite");
  expect_error("EPSG:32634", 0, INFINITY, KARST_EINVAL, "not finite");
  expect_error("EPSG:32634", 1e8, 5e6, KARST_ERANGE, "cannot be converted");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_snyder_reference), cmocka_unit_test(test_bng),
      cmocka_unit_test(test_utm_north),        cmocka_unit_test(test_utm_south),
      cmocka_unit_test(test_geographic),       cmocka_unit_test(test_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
