/* Coordinate systems of survey data: which strings we understand (EPSG codes,
 * Survex *cs names, PROJ strings) and the meridian convergence through the
 * GeographicLib shim. */
#include "karst/crs.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "crs_internal.h"

/* UTM (Snyder 1987, "Map Projections: A Working Manual", USGS PP 1395, ch. 8). */
#define UTM_K0 0.9996
#define UTM_FE 500000.0
#define UTM_FN_SOUTH 10000000.0

/* British National Grid, OSGB36 (Ordnance Survey, "A guide to coordinate
 * systems in Great Britain", 2020, Annex A/C): Airy 1830 ellipsoid, true
 * origin 49N 2W, scale 0.9996012717, false origin E 400000 m, N -100000 m. */
#define BNG_FE 400000.0
#define BNG_FN (-100000.0)

typedef struct ellipsoid {
  const char *name;
  double a, rf; /* semi-major axis (m), inverse flattening */
} ellipsoid_t;

/* PROJ's ellipsoid names (PROJ's src/ellps.cpp defines them by a and rf or
 * b; those given by b are converted with rf = a / (a - b)). */
static const ellipsoid_t ELLIPSOIDS[] = {
    {"WGS84", 6378137.0, 298.257223563},
    {"GRS80", 6378137.0, 298.257222101},
    {"airy", 6377563.396, 6377563.396 / (6377563.396 - 6356256.910)},
    {"mod_airy", 6377340.189, 6377340.189 / (6377340.189 - 6356034.446)},
    {"intl", 6378388.0, 297.0},
    {"bessel", 6377397.155, 299.1528128},
    {"clrk66", 6378206.4, 6378206.4 / (6378206.4 - 6356583.8)},
    {"clrk80", 6378249.145, 293.4663},
    {"krass", 6378245.0, 298.3},
};
/* PROJ datum names that fix the ellipsoid. */
static const struct {
  const char *datum, *ellps;
} DATUMS[] = {{"WGS84", "WGS84"},         {"NAD83", "GRS80"},    {"NAD27", "clrk66"},
              {"OSGB36", "airy"},         {"potsdam", "bessel"}, {"ire65", "mod_airy"},
              {"hermannskogel", "bessel"}};

/* EPSG geographic (latitude/longitude) systems: WGS 84 (2-D, 3-D), ETRS89
 * (2-D, 3-D), NAD83, NAD27, OSGB36, ED50. */
static const int EPSG_GEOGRAPHIC[] = {4326, 4979, 4258, 4937, 4269, 4267, 4277, 4230};

static const ellipsoid_t *find_ellipsoid(const char *name) {
  for (size_t i = 0; i < sizeof ELLIPSOIDS / sizeof *ELLIPSOIDS; i++)
    if (strcasecmp(name, ELLIPSOIDS[i].name) == 0) return &ELLIPSOIDS[i];
  return NULL;
}

static void set_utm_tmerc(karst_i_crs_t *c, int zone, int south, const ellipsoid_t *e) {
  c->kind = KARST_I_CRS_TMERC;
  c->a = e->a;
  c->f = 1.0 / e->rf;
  c->k0 = UTM_K0;
  c->lat0 = 0;
  c->lon0 = 6.0 * zone - 183.0;
  c->fe = UTM_FE;
  c->fn = south ? UTM_FN_SOUTH : 0;
}

/* Whole-string integer parse; returns 0 on success. */
static int parse_int(const char *s, long *v) {
  char *end;
  if (!*s) return -1;
  *v = strtol(s, &end, 10);
  return *end ? -1 : 0;
}

static int parse_num(const char *s, double *v) {
  char *end;
  if (!*s) return -1;
  *v = strtod(s, &end);
  return (*end || !isfinite(*v)) ? -1 : 0;
}

#define UNSUPPORTED 1
#define BAD_VALUE 2

/* "EPSG:nnnn" */
static int parse_epsg(long code, karst_i_crs_t *c) {
  for (size_t i = 0; i < sizeof EPSG_GEOGRAPHIC / sizeof *EPSG_GEOGRAPHIC; i++)
    if (code == EPSG_GEOGRAPHIC[i]) {
      c->kind = KARST_I_CRS_GEOGRAPHIC;
      return 0;
    }
  if (code == 27700 || code == 7405) { /* OSGB36 / British National Grid (+ ODN height) */
    c->kind = KARST_I_CRS_OSGB;
    return 0;
  }
  if ((code > 32600 && code <= 32660) || (code > 32700 && code <= 32760)) { /* WGS 84 / UTM */
    c->kind = KARST_I_CRS_UTM;
    c->zone = (int)(code % 100);
    c->northp = code < 32700;
    return 0;
  }
  if (code >= 25828 && code <= 25838) { /* ETRS89 / UTM zones 28N-38N (GRS80) */
    set_utm_tmerc(c, (int)(code - 25800), 0, find_ellipsoid("GRS80"));
    return 0;
  }
  return UNSUPPORTED;
}

/* "+proj=... +key=value ..." (PROJ's parameter syntax). */
static int parse_proj(const char *s, karst_i_crs_t *c, char *bad, size_t nbad) {
  char buf[512];
  if (strlen(s) >= sizeof buf) return UNSUPPORTED;
  strcpy(buf, s);
  const char *proj = NULL, *ellps = NULL, *datum = NULL;
  double a = NAN, b = NAN, rf = NAN, f = NAN, lat0 = 0, lon0 = 0, k0 = 1, x0 = 0, y0 = 0;
  long zone = 0;
  int south = 0;
  for (char *save = NULL, *tok = strtok_r(buf, " \t\r\n", &save); tok;
       tok = strtok_r(NULL, " \t\r\n", &save)) {
    if (*tok != '+') return UNSUPPORTED;
    tok++;
    char *val = strchr(tok, '=');
    if (val) *val++ = '\0';
    const char *v = val ? val : "";
    int r = 0;
    if (!strcmp(tok, "proj"))
      proj = v;
    else if (!strcmp(tok, "ellps"))
      ellps = v;
    else if (!strcmp(tok, "datum"))
      datum = v;
    else if (!strcmp(tok, "zone"))
      r = parse_int(v, &zone) || zone < 1 || zone > 60;
    else if (!strcmp(tok, "south"))
      south = 1;
    else if (!strcmp(tok, "a"))
      r = parse_num(v, &a);
    else if (!strcmp(tok, "b"))
      r = parse_num(v, &b);
    else if (!strcmp(tok, "rf"))
      r = parse_num(v, &rf);
    else if (!strcmp(tok, "f"))
      r = parse_num(v, &f);
    else if (!strcmp(tok, "lat_0"))
      r = parse_num(v, &lat0);
    else if (!strcmp(tok, "lon_0"))
      r = parse_num(v, &lon0);
    else if (!strcmp(tok, "k") || !strcmp(tok, "k_0"))
      r = parse_num(v, &k0);
    else if (!strcmp(tok, "x_0"))
      r = parse_num(v, &x0);
    else if (!strcmp(tok, "y_0"))
      r = parse_num(v, &y0);
    else if (!strcmp(tok, "units")) {
      if (strcmp(v, "m")) return UNSUPPORTED; /* grid units other than metres */
    } else if (!strcmp(tok, "to_meter")) {
      double m;
      if (parse_num(v, &m) || m != 1.0) return UNSUPPORTED;
    } else if (!strcmp(tok, "axis")) {
      if (strcmp(v, "enu")) return UNSUPPORTED; /* swapped or reversed axes */
    } else if (!strcmp(tok, "pm")) {
      if (strcmp(v, "greenwich") && strcmp(v, "0")) return UNSUPPORTED;
    }
    /* Anything else (+no_defs, +type=crs, +towgs84, +nadgrids, +wktext,
     * +vunits ...) does not change the convergence measurably: a datum shift
     * moves a point by at most a few hundred metres. */
    if (r) {
      snprintf(bad, nbad, "+%s=%s", tok, v);
      return BAD_VALUE;
    }
  }
  if (!proj) return UNSUPPORTED;
  if (!strcmp(proj, "longlat") || !strcmp(proj, "latlong") || !strcmp(proj, "lonlat") ||
      !strcmp(proj, "latlon")) {
    c->kind = KARST_I_CRS_GEOGRAPHIC;
    return 0;
  }
  /* The ellipsoid: +a with +b/+rf/+f, else +ellps, else +datum, else PROJ's default GRS80. */
  ellipsoid_t custom = {"custom", a, NAN};
  const ellipsoid_t *e = NULL;
  if (!isnan(a)) {
    custom.rf = !isnan(rf) ? rf : !isnan(f) ? 1.0 / f : !isnan(b) ? a / (a - b) : NAN;
    if (!(a > 0) || !(custom.rf > 1)) {
      snprintf(bad, nbad, "+a=%g with no valid +b, +rf or +f", a);
      return BAD_VALUE;
    }
    e = &custom;
  } else if (ellps) {
    if (!(e = find_ellipsoid(ellps))) return UNSUPPORTED;
  } else if (datum) {
    for (size_t i = 0; i < sizeof DATUMS / sizeof *DATUMS && !e; i++)
      if (!strcasecmp(datum, DATUMS[i].datum)) e = find_ellipsoid(DATUMS[i].ellps);
    if (!e) return UNSUPPORTED;
  } else {
    e = find_ellipsoid("GRS80");
  }
  if (!strcmp(proj, "utm")) {
    if (!zone) {
      snprintf(bad, nbad, "+proj=utm without +zone");
      return BAD_VALUE;
    }
    set_utm_tmerc(c, (int)zone, south, e);
    return 0;
  }
  if (!strcmp(proj, "tmerc")) {
    if (!(k0 > 0) || fabs(lat0) > 90) {
      snprintf(bad, nbad, "+proj=tmerc with +k=%g +lat_0=%g", k0, lat0);
      return BAD_VALUE;
    }
    c->kind = KARST_I_CRS_TMERC;
    c->a = e->a;
    c->f = 1.0 / e->rf;
    c->k0 = k0;
    c->lat0 = lat0;
    c->lon0 = lon0;
    c->fe = x0;
    c->fn = y0;
    return 0;
  }
  return UNSUPPORTED;
}

/* Survex's own *cs names: UTMnn[NS], LONG-LAT, LAT-LONG, OSGB:XY. */
static int parse_survex(const char *s, karst_i_crs_t *c, double *dx, double *dy) {
  if (!strcasecmp(s, "LONG-LAT") || !strcasecmp(s, "LAT-LONG")) {
    c->kind = KARST_I_CRS_GEOGRAPHIC;
    return 0;
  }
  if (!strncasecmp(s, "UTM", 3)) {
    char *end;
    long zone = strtol(s + 3, &end, 10);
    if (end == s + 3 || zone < 1 || zone > 60 || !end[0] || end[1] ||
        (toupper((unsigned char)end[0]) != 'N' && toupper((unsigned char)end[0]) != 'S'))
      return UNSUPPORTED;
    c->kind = KARST_I_CRS_UTM;
    c->zone = (int)zone;
    c->northp = toupper((unsigned char)end[0]) == 'N';
    return 0;
  }
  if (!strncasecmp(s, "OSGB:", 5) && strlen(s) == 7) {
    /* Coordinates relative to the south-west corner of a 100 km square of the
     * National Grid: two letters from the 5x5 grid of A-Z without I, the
     * first for 500 km squares with S at the false origin (OS guide, Annex). */
    int l1 = toupper((unsigned char)s[5]), l2 = toupper((unsigned char)s[6]);
    if (l1 < 'A' || l1 > 'Z' || l2 < 'A' || l2 > 'Z' || l1 == 'I' || l2 == 'I') return UNSUPPORTED;
    int i1 = l1 - 'A' - (l1 > 'I'), i2 = l2 - 'A' - (l2 > 'I');
    double e500 = (i1 % 5 - 2) * 500000.0, n500 = (3 - i1 / 5) * 500000.0;
    double e100 = (i2 % 5) * 100000.0, n100 = (4 - i2 / 5) * 100000.0;
    c->kind = KARST_I_CRS_OSGB;
    *dx = e500 + e100;
    *dy = n500 + n100;
    return 0;
  }
  return UNSUPPORTED;
}

/**
 * karst_crs_convergence: meridian convergence of a survey's coordinate system.
 *
 * Sign convention (GeographicLib's gamma): @p degrees is the bearing of grid
 * north measured clockwise from true north, i.e. the rotation to ADD to a
 * grid azimuth to obtain the true azimuth:
 *     true azimuth = grid azimuth + degrees.
 * It is positive east of the central meridian in the northern hemisphere
 * (there grid north lies east of true north) and approximately
 * (lon - lon0) sin(lat) (Snyder 1987; exact values from Karney 2011 through
 * GeographicLib's TransverseMercator, UTMUPS and OSGB classes).
 *
 * Understood: "EPSG:326NN" / "EPSG:327NN" (WGS 84 / UTM), "EPSG:25828".."25838"
 * (ETRS89 / UTM), "EPSG:27700" and "EPSG:7405" (British National Grid),
 * geographic EPSG codes (4326, 4979, 4258, 4937, 4269, 4267, 4277, 4230),
 * Survex names "UTMnnN|S", "OSGB:XY", "LONG-LAT", and PROJ strings with
 * +proj=utm, +proj=tmerc (+lat_0 +lon_0 +k +x_0 +y_0, +ellps / +datum / +a
 * +b|+rf|+f, metres only) or +proj=longlat. Latitude/longitude systems give 0.
 *
 * @param ctx     context for the error message
 * @param crs     the coordinate-system string (e.g. a .3d file's CS string)
 * @param x, y    grid coordinates of the point (metres; longitude, latitude
 *                in degrees for geographic systems)
 * @param degrees output: the convergence in degrees
 * @return KARST_SUCCESS; KARST_EUNSUPPORTED "coordinate system 'X' is not
 *         convertible offline: only UTM, ... are supported" for anything else
 *         (or no CS at all);
 *         KARST_EINVAL for a non-finite point or a malformed PROJ value;
 *         KARST_ERANGE for a point outside the projection's domain.
 *
 * Time complexity: O(1).
 */
karst_error_t karst_crs_convergence(karst_ctx_t *ctx, const char *crs, double x, double y,
                                    double *degrees) {
  karst_i_crs_t c;
  char bad[160] = "";
  char name[256];
  double dx = 0, dy = 0;
  memset(&c, 0, sizeof c);
  if (!crs || !*crs)
    return karst_set_error(ctx, KARST_EUNSUPPORTED,
                           "no coordinate system: grid north cannot be related to true north");
  /* Trim blanks around the string. */
  while (isspace((unsigned char)*crs))
    crs++;
  size_t n = strlen(crs);
  while (n && isspace((unsigned char)crs[n - 1]))
    n--;
  if (n >= sizeof name) n = sizeof name - 1;
  memcpy(name, crs, n);
  name[n] = '\0';
  if (!isfinite(x) || !isfinite(y))
    return karst_set_error(ctx, KARST_EINVAL,
                           "coordinate system '%s': point (%g, %g) is not finite", name, x, y);
  int r;
  long code;
  if (!strncasecmp(name, "EPSG:", 5))
    r = parse_int(name + 5, &code) ? UNSUPPORTED : parse_epsg(code, &c);
  else if (name[0] == '+')
    r = parse_proj(name, &c, bad, sizeof bad);
  else
    r = parse_survex(name, &c, &dx, &dy);
  if (r == BAD_VALUE)
    return karst_set_error(ctx, KARST_EINVAL, "coordinate system '%s': bad parameter %s", name,
                           bad);
  if (r)
    return karst_set_error(ctx, KARST_EUNSUPPORTED,
                           "coordinate system '%s' is not convertible offline: only UTM, the "
                           "British National Grid, PROJ +proj=tmerc and latitude/longitude "
                           "systems are supported",
                           name);
  if (c.kind == KARST_I_CRS_GEOGRAPHIC) {
    *degrees = 0.0;
    return KARST_SUCCESS;
  }
  double g;
  karst_error_t err = karst_i_geo_convergence(ctx, name, &c, x + dx, y + dy, &g);
  if (err) return err;
  if (!isfinite(g))
    return karst_set_error(ctx, KARST_ERANGE,
                           "coordinate system '%s': point (%.3f, %.3f) is outside the projection",
                           name, x, y);
  *degrees = g;
  return KARST_SUCCESS;
}
