/* The coordinate reference system of a scenario and conversions into it (include/karst/crs.h,
 * docs/scenario.md "Coordinates"): UTM/UPS zones and WGS 84 latitude/longitude through
 * GeographicLib (src/crs/geographiclib_shim.cpp, Karney 2011), everything that needs an EPSG
 * definition or a datum shift through PROJ's C API with the data Debian's proj-data installs
 * (network access disabled, so a run never depends on what a grid server would send). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "crs/proj_api_internal.h"
#include "crs_internal.h"
#include "karst/crs.h"

/** How a CRS is evaluated. */
typedef enum {
  CRS_LONLAT = 0, /* WGS 84 longitude, latitude (degrees): GeographicLib */
  CRS_UTM,        /* WGS 84 / UTM zone (1..60) or UPS (zone 0): GeographicLib */
  CRS_PROJ        /* anything else: PROJ */
} crs_kind_t;

struct karst_crs {
  char text[KARST_CRS_TEXT_MAX]; /* as given, trimmed */
  crs_kind_t kind;
  int zone, northp; /* CRS_UTM */
  double dx, dy;    /* added to the given coordinates to get the CRS's (Survex OSGB:XY) */
  char def[KARST_CRS_TEXT_MAX + 16]; /* what PROJ is given for this CRS */
  char id[32];                       /* "EPSG:32630", or "" when the CRS has no authority code */
  int geographic;                    /* coordinates are longitude, latitude in degrees */
};

/* A PROJ context of our own per operation (PROJ loaded on first use): no shared state between
 * threads, no network, no log on stderr (errors come back through proj_context_errno). */
static karst_error_t new_context(karst_ctx_t *ctx, PJ_CONTEXT **out) {
  *out = NULL;
  karst_error_t err = karst_i_proj_load(ctx);
  if (err != KARST_SUCCESS) return err;
  PJ_CONTEXT *p = karst_i_proj.proj_context_create();
  if (!p) return karst_set_error(ctx, KARST_EEXTERNAL, "PROJ: cannot create a context");
  karst_i_proj.proj_context_set_enable_network(p, 0);
  karst_i_proj.proj_log_level(p, PJ_LOG_NONE);
  *out = p;
  return KARST_SUCCESS;
}

static const char *proj_reason(PJ_CONTEXT *p) {
  int e = karst_i_proj.proj_context_errno(p);
  const char *s = e ? karst_i_proj.proj_context_errno_string(p, e) : NULL;
  return s ? s : "PROJ gave no reason";
}

static void trim_copy(const char *s, char *out, size_t n) {
  while (isspace((unsigned char)*s))
    s++;
  size_t len = strlen(s);
  while (len && isspace((unsigned char)s[len - 1]))
    len--;
  if (len >= n) len = n - 1;
  memcpy(out, s, len);
  out[len] = '\0';
}

/* "UTM 30N", "UTM30N", "UTM zone 30 N", "utm 30 south": 1 and the zone, else 0. */
static int parse_utm(const char *s, int *zone, int *northp) {
  if (strncasecmp(s, "UTM", 3)) return 0;
  s += 3;
  while (*s == ' ')
    s++;
  if (!strncasecmp(s, "zone", 4)) s += 4;
  while (*s == ' ')
    s++;
  if (!isdigit((unsigned char)*s)) return 0;
  char *end;
  long z = strtol(s, &end, 10);
  if (z < 1 || z > 60) return 0;
  s = end;
  while (*s == ' ')
    s++;
  if (!strcasecmp(s, "N") || !strcasecmp(s, "north"))
    *northp = 1;
  else if (!strcasecmp(s, "S") || !strcasecmp(s, "south"))
    *northp = 0;
  else
    return 0;
  *zone = (int)z;
  return 1;
}

/* "UPS N", "UPS north", "UPS S", "UPS south". */
static int parse_ups(const char *s, int *northp) {
  if (strncasecmp(s, "UPS", 3)) return 0;
  s += 3;
  while (*s == ' ')
    s++;
  if (!strcasecmp(s, "N") || !strcasecmp(s, "north")) return *northp = 1, 1;
  if (!strcasecmp(s, "S") || !strcasecmp(s, "south")) return *northp = 0, 1;
  return 0;
}

static void set_utm(karst_crs_t *c, int zone, int northp) {
  c->kind = CRS_UTM;
  c->zone = zone;
  c->northp = northp;
  /* EPSG's WGS 84 / UTM zone nnN = 326nn, nnS = 327nn; UPS North 32661, South 32761. */
  int code = zone ? (northp ? 32600 : 32700) + zone : (northp ? 32661 : 32761);
  snprintf(c->id, sizeof c->id, "EPSG:%d", code);
  snprintf(c->def, sizeof c->def, "EPSG:%d", code);
}

/* The horizontal part of @p crs (the first member of a compound CRS), or a clone of it. */
static PJ *horizontal(PJ_CONTEXT *p, PJ *crs) {
  if (karst_i_proj.proj_get_type(crs) == PJ_TYPE_COMPOUND_CRS)
    return karst_i_proj.proj_crs_get_sub_crs(p, crs, 0);
  return karst_i_proj.proj_clone(p, crs);
}

/**
 * karst_crs_create: parse a coordinate reference system.
 *
 * Accepted (docs/scenario.md, "Coordinates"): a UTM zone ("UTM 30N", "UTM30S", "UTM zone 30 N"),
 * "UPS N" / "UPS S", Survex's "LONG-LAT" and "OSGB:XY" (coordinates relative to the south-west
 * corner of 100 km square XY of the British National Grid), and whatever PROJ accepts as a CRS:
 * "EPSG:nnnn" and other authority codes, PROJ strings ("+proj=... ", as Survex writes them in
 * *cs), WKT. WGS 84 UTM/UPS zones (also as EPSG:326nn, 327nn, 32661, 32761) and WGS 84
 * latitude/longitude (EPSG:4326, 4979) are evaluated by GeographicLib, the others by PROJ.
 *
 * @param ctx  errors: KARST_EINVAL "coordinate system 'X' is not understood: PROJ says ..."
 * @param text the CRS as the user wrote it
 * @param out  receives the CRS (karst_crs_free)
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ENOMEM, KARST_EEXTERNAL (no PROJ context).
 * Time complexity: O(1) for GeographicLib systems; one PROJ database look-up otherwise.
 */
karst_error_t karst_crs_create(karst_ctx_t *ctx, const char *text, karst_crs_t **out) {
  *out = NULL;
  if (!text) return karst_set_error(ctx, KARST_EINVAL, "no coordinate system given");
  karst_crs_t *c = calloc(1, sizeof *c);
  if (!c) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  trim_copy(text, c->text, sizeof c->text);
  if (strlen(text) >= sizeof c->text) {
    free(c);
    return karst_set_error(ctx, KARST_EINVAL,
                           "coordinate system '%.40s...' is longer than %d characters", text,
                           KARST_CRS_TEXT_MAX - 1);
  }
  if (!c->text[0]) {
    free(c);
    return karst_set_error(ctx, KARST_EINVAL, "the coordinate system is an empty string");
  }
  int zone = 0, northp = 1;
  long code = 0;
  char *end = NULL;
  if (parse_utm(c->text, &zone, &northp)) {
    set_utm(c, zone, northp);
  } else if (parse_ups(c->text, &northp)) {
    set_utm(c, 0, northp);
  } else if (!strncasecmp(c->text, "EPSG:", 5) && (code = strtol(c->text + 5, &end, 10), !*end) &&
             ((code > 32600 && code <= 32660) || (code > 32700 && code <= 32760) || code == 32661 ||
              code == 32761)) {
    if (code == 32661 || code == 32761)
      set_utm(c, 0, code == 32661);
    else
      set_utm(c, (int)(code % 100), code < 32700);
  } else if (!strcasecmp(c->text, "LONG-LAT") || !strcasecmp(c->text, "EPSG:4326") ||
             !strcasecmp(c->text, "EPSG:4979")) {
    c->kind = CRS_LONLAT;
    c->geographic = 1;
    snprintf(c->id, sizeof c->id, "EPSG:%s", strstr(c->text, "4979") ? "4979" : "4326");
    snprintf(c->def, sizeof c->def, "EPSG:4326");
  } else {
    c->kind = CRS_PROJ;
    if (!strncasecmp(c->text, "OSGB:", 5) && strlen(c->text) == 7) {
      /* Survex: the south-west corner of a 100 km square of the National Grid; two letters of
       * the 5 x 5 grid of A-Z without I, the first for 500 km squares with S at the false origin
       * (Ordnance Survey, "A guide to coordinate systems in Great Britain", 2020). */
      int l1 = toupper((unsigned char)c->text[5]), l2 = toupper((unsigned char)c->text[6]);
      if (l1 < 'A' || l1 > 'Z' || l2 < 'A' || l2 > 'Z' || l1 == 'I' || l2 == 'I') {
        karst_error_t err = karst_set_error(
            ctx, KARST_EINVAL, "coordinate system '%s': '%c%c' is not a National Grid square",
            c->text, l1, l2);
        free(c);
        return err;
      }
      int i1 = l1 - 'A' - (l1 > 'I'), i2 = l2 - 'A' - (l2 > 'I');
      c->dx = (i1 % 5 - 2) * 500000.0 + (i2 % 5) * 100000.0;
      c->dy = (3 - i1 / 5) * 500000.0 + (4 - i2 / 5) * 100000.0;
      snprintf(c->def, sizeof c->def, "EPSG:27700");
    } else if (c->text[0] == '+' && !strstr(c->text, "type=crs")) {
      snprintf(c->def, sizeof c->def, "%s +type=crs", c->text); /* PROJ strings as CRSs */
    } else {
      snprintf(c->def, sizeof c->def, "%s", c->text);
    }
    PJ_CONTEXT *p;
    karst_error_t perr = new_context(ctx, &p);
    if (perr != KARST_SUCCESS) {
      free(c);
      return perr;
    }
    PJ *crs = karst_i_proj.proj_create(p, c->def);
    karst_error_t err = KARST_SUCCESS;
    if (!crs || !karst_i_proj.proj_is_crs(crs)) {
      err = karst_set_error(ctx, KARST_EINVAL,
                            "coordinate system '%s' is not understood: %s (give a UTM zone such "
                            "as 'UTM 30N', an EPSG code such as 'EPSG:27700', or a PROJ string)",
                            c->text,
                            crs ? "it is not a coordinate reference system" : proj_reason(p));
    } else {
      const char *auth = karst_i_proj.proj_get_id_auth_name(crs, 0),
                 *cd = karst_i_proj.proj_get_id_code(crs, 0);
      if (auth && cd && !c->dx && !c->dy) snprintf(c->id, sizeof c->id, "%s:%s", auth, cd);
      PJ *h = horizontal(p, crs);
      PJ_TYPE t = h ? karst_i_proj.proj_get_type(h) : PJ_TYPE_UNKNOWN;
      c->geographic = t == PJ_TYPE_GEOGRAPHIC_2D_CRS || t == PJ_TYPE_GEOGRAPHIC_3D_CRS;
      if (!h || (!c->geographic && t != PJ_TYPE_PROJECTED_CRS))
        err = karst_set_error(ctx, KARST_EUNSUPPORTED,
                              "coordinate system '%s' is neither projected nor geographic "
                              "(a geocentric or engineering CRS cannot hold a scenario)",
                              c->text);
      karst_i_proj.proj_destroy(h);
    }
    karst_i_proj.proj_destroy(crs);
    karst_i_proj.proj_context_destroy(p);
    if (err) {
      free(c);
      return err;
    }
  }
  *out = c;
  return KARST_SUCCESS;
}

void karst_crs_free(karst_crs_t *c) {
  free(c);
}

const char *karst_crs_text(const karst_crs_t *c) {
  return c ? c->text : NULL;
}

const char *karst_crs_id(const karst_crs_t *c) {
  return c && c->id[0] ? c->id : NULL;
}

int karst_crs_is_geographic(const karst_crs_t *c) {
  return c && c->geographic;
}

/* WKT2:2019 or the PROJ string of @p c, copied. */
static karst_error_t export_as(karst_ctx_t *ctx, const karst_crs_t *c, int wkt, char **out) {
  *out = NULL;
  PJ_CONTEXT *p;
  karst_error_t perr = new_context(ctx, &p);
  if (perr != KARST_SUCCESS) return perr;
  PJ *crs = karst_i_proj.proj_create(p, c->def);
  const char *s = NULL;
  if (crs)
    s = wkt ? karst_i_proj.proj_as_wkt(p, crs, PJ_WKT2_2019, NULL)
            : karst_i_proj.proj_as_proj_string(p, crs, PJ_PROJ_5, NULL);
  karst_error_t err = KARST_SUCCESS;
  if (!s)
    err = karst_set_error(ctx, KARST_EEXTERNAL,
                          "coordinate system '%s': PROJ cannot write it as %s: %s", c->text,
                          wkt ? "WKT" : "a PROJ string", proj_reason(p));
  else if (!(*out = strdup(s)))
    err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  karst_i_proj.proj_destroy(crs);
  karst_i_proj.proj_context_destroy(p);
  return err;
}

/**
 * The CRS as WKT2:2019 (ISO 19162:2019), what GIS software reads unambiguously; the Survex
 * OSGB:XY offset is not part of it (it describes the full-coordinate CRS). Caller frees.
 * Time complexity: one PROJ database look-up.
 */
karst_error_t karst_crs_wkt(karst_ctx_t *ctx, const karst_crs_t *c, char **wkt) {
  return export_as(ctx, c, 1, wkt);
}

/** The CRS as a PROJ string (PROJ 5 conventions). Caller frees. One PROJ database look-up. */
karst_error_t karst_crs_proj_string(karst_ctx_t *ctx, const karst_crs_t *c, char **s) {
  return export_as(ctx, c, 0, s);
}

/* Whether two CRSs are the same system with the same offsets (then no conversion at all). */
static int same_crs(const karst_crs_t *a, const karst_crs_t *b) {
  return !strcmp(a->def, b->def) && a->kind == b->kind && a->zone == b->zone &&
         a->northp == b->northp;
}

/* GeographicLib: longitude/latitude <-> a CRS_LONLAT or CRS_UTM system, in place on xy. */
static karst_error_t geo_to_lonlat(karst_ctx_t *ctx, const karst_crs_t *c, double *x, double *y) {
  if (c->kind == CRS_LONLAT) return KARST_SUCCESS;
  double lat, lon;
  karst_error_t err = karst_i_geo_utm_reverse(ctx, c->zone, c->northp, *x, *y, &lat, &lon);
  if (!err) *x = lon, *y = lat;
  return err;
}
static karst_error_t geo_from_lonlat(karst_ctx_t *ctx, const karst_crs_t *c, double *x, double *y) {
  if (c->kind == CRS_LONLAT) return KARST_SUCCESS;
  return karst_i_geo_utm_forward(ctx, c->zone, c->northp, *y, *x, x, y);
}

/* A PROJ operation from the horizontal part of @p src to that of @p dst, axes in
 * easting/northing and longitude/latitude order. */
static PJ *proj_operation(PJ_CONTEXT *p, const karst_crs_t *src, const karst_crs_t *dst) {
  PJ *a = karst_i_proj.proj_create(p, src->def), *b = karst_i_proj.proj_create(p, dst->def);
  PJ *ha = a ? horizontal(p, a) : NULL, *hb = b ? horizontal(p, b) : NULL;
  PJ *op = ha && hb ? karst_i_proj.proj_create_crs_to_crs_from_pj(p, ha, hb, NULL, NULL) : NULL;
  PJ *norm = op ? karst_i_proj.proj_normalize_for_visualization(p, op) : NULL;
  karst_i_proj.proj_destroy(op);
  karst_i_proj.proj_destroy(ha);
  karst_i_proj.proj_destroy(hb);
  karst_i_proj.proj_destroy(a);
  karst_i_proj.proj_destroy(b);
  return norm;
}

/**
 * karst_crs_transform: convert @p n points from @p src to @p dst, in place.
 *
 * @p xyz holds 3 values per point (x, y, z): x, y are the horizontal coordinates (easting,
 * northing in metres, or longitude, latitude in degrees), z a height that is passed through
 * unchanged (it enters the horizontal datum shift as cs2cs lets it): the heights of a scenario and
 * of its surveys are taken in one vertical datum (docs/scenario.md, "Coordinates": Debian's
 * proj-data has no geoid grids, so PROJ itself would leave an ODN height unchanged going to WGS 84,
 * a "ballpark" vertical transformation). Between WGS 84 UTM/UPS and latitude/longitude the
 * conversion is GeographicLib's (Karney 2011, accurate to nanometres); whenever PROJ's CRS is
 * involved it is PROJ's proj_create_crs_to_crs on the horizontal parts, the operation cs2cs uses,
 * with the data installed (e.g. OSGB36 <-> WGS 84 by the EPSG Helmert transformation "OSGB36 to WGS
 * 84 (6)", quoted at 2 m, since the OSTN15 grid is not in proj-data).
 *
 * @return KARST_SUCCESS; KARST_ERANGE naming the first point that cannot be converted;
 *         KARST_EEXTERNAL when PROJ has no operation between the two.
 * Time complexity: O(n) after one PROJ set-up.
 */
karst_error_t karst_crs_transform(karst_ctx_t *ctx, const karst_crs_t *src, const karst_crs_t *dst,
                                  karst_int_t n, double *xyz) {
  karst_error_t err = KARST_SUCCESS;
  if (same_crs(src, dst)) {
    for (karst_int_t i = 0; i < n; i++)
      xyz[3 * i] += src->dx - dst->dx, xyz[3 * i + 1] += src->dy - dst->dy;
    return KARST_SUCCESS;
  }
  for (karst_int_t i = 0; i < n; i++)
    if (!isfinite(xyz[3 * i]) || !isfinite(xyz[3 * i + 1]))
      return karst_set_error(ctx, KARST_EINVAL, "point %lld (%g, %g) is not finite", (long long)i,
                             xyz[3 * i], xyz[3 * i + 1]);
  if (src->kind != CRS_PROJ && dst->kind != CRS_PROJ) {
    for (karst_int_t i = 0; i < n && !err; i++) {
      double *x = &xyz[3 * i], *y = &xyz[3 * i + 1];
      if (!(err = geo_to_lonlat(ctx, src, x, y))) err = geo_from_lonlat(ctx, dst, x, y);
    }
    return err;
  }
  PJ_CONTEXT *p;
  karst_error_t perr = new_context(ctx, &p);
  if (perr != KARST_SUCCESS) return perr;
  PJ *op = proj_operation(p, src, dst);
  if (!op) {
    err = karst_set_error(ctx, KARST_EEXTERNAL,
                          "PROJ finds no conversion from '%s' to '%s' with the data installed: %s",
                          src->text, dst->text, proj_reason(p));
    karst_i_proj.proj_context_destroy(p);
    return err;
  }
  for (karst_int_t i = 0; i < n && !err; i++) {
    /* The height goes in too, as cs2cs passes it: a Helmert datum shift acts on geocentric
     * coordinates, so the horizontal result moves by millimetres per 100 m of height. */
    PJ_COORD in = karst_i_proj.proj_coord(xyz[3 * i] + src->dx, xyz[3 * i + 1] + src->dy,
                                          isfinite(xyz[3 * i + 2]) ? xyz[3 * i + 2] : 0, HUGE_VAL);
    PJ_COORD o = karst_i_proj.proj_trans(op, PJ_FWD, in);
    if (!isfinite(o.xy.x) || !isfinite(o.xy.y) || o.xy.x == HUGE_VAL)
      err = karst_set_error(ctx, KARST_ERANGE,
                            "point (%.3f, %.3f) of '%s' cannot be converted to '%s': %s",
                            xyz[3 * i], xyz[3 * i + 1], src->text, dst->text, proj_reason(p));
    else
      xyz[3 * i] = o.xy.x - dst->dx, xyz[3 * i + 1] = o.xy.y - dst->dy;
  }
  karst_i_proj.proj_destroy(op);
  karst_i_proj.proj_context_destroy(p);
  return err;
}

/* The WGS 84 longitude/latitude frame (EPSG:4326) of the lon/lat conversions. */
static void wgs84(karst_crs_t *w) {
  memset(w, 0, sizeof *w);
  w->kind = CRS_LONLAT;
  w->geographic = 1;
  snprintf(w->text, sizeof w->text, "EPSG:4326");
  snprintf(w->def, sizeof w->def, "EPSG:4326");
}

/**
 * WGS 84 longitude/latitude (degrees) of @p n points of @p crs (3 values per point in, 2 out).
 * Time complexity: O(n).
 */
karst_error_t karst_crs_to_lonlat(karst_ctx_t *ctx, const karst_crs_t *crs, karst_int_t n,
                                  const double *xyz, double *lonlat) {
  karst_crs_t wgs;
  wgs84(&wgs);
  for (karst_int_t i = 0; i < n; i++) {
    double p[3] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    karst_error_t err = karst_crs_transform(ctx, crs, &wgs, 1, p);
    if (err) return err;
    lonlat[2 * i] = p[0], lonlat[2 * i + 1] = p[1];
  }
  return KARST_SUCCESS;
}

/**
 * Points of @p crs from WGS 84 longitude/latitude (degrees; 2 values per point in, @p xyz gets
 * x, y of each point in its first two of 3 values, z untouched). Time complexity: O(n).
 */
karst_error_t karst_crs_from_lonlat(karst_ctx_t *ctx, const karst_crs_t *crs, karst_int_t n,
                                    const double *lonlat, double *xyz) {
  karst_crs_t wgs;
  wgs84(&wgs);
  for (karst_int_t i = 0; i < n; i++) {
    if (!(fabs(lonlat[2 * i + 1]) <= 90) || !(fabs(lonlat[2 * i]) <= 540))
      return karst_set_error(ctx, KARST_ERANGE,
                             "latitude %g, longitude %g: latitude must be within [-90, 90] and "
                             "longitude within [-540, 540] degrees",
                             lonlat[2 * i + 1], lonlat[2 * i]);
    double p[3] = {lonlat[2 * i], lonlat[2 * i + 1], 0};
    karst_error_t err = karst_crs_transform(ctx, &wgs, crs, 1, p);
    if (err) return err;
    xyz[3 * i] = p[0], xyz[3 * i + 1] = p[1];
  }
  return KARST_SUCCESS;
}

/**
 * What a conversion from @p src to @p dst does at (@p x, @p y) of @p src: the method in words
 * (GeographicLib's, or the name PROJ gives the operation it chose) in @p what and its accuracy
 * in metres in @p accuracy (0: exact to the nanometre; -1: PROJ does not know, as for a ballpark
 * operation). Time complexity: one PROJ set-up.
 */
karst_error_t karst_crs_describe(karst_ctx_t *ctx, const karst_crs_t *src, const karst_crs_t *dst,
                                 double x, double y, char *what, size_t size, double *accuracy) {
  if (same_crs(src, dst)) {
    snprintf(what, size, "none (the same coordinate system)");
    *accuracy = 0;
    return KARST_SUCCESS;
  }
  if (src->kind != CRS_PROJ && dst->kind != CRS_PROJ) {
    snprintf(what, size, "GeographicLib UTMUPS (Karney 2011, exact to nanometres)");
    *accuracy = 0;
    return KARST_SUCCESS;
  }
  PJ_CONTEXT *p;
  karst_error_t perr = new_context(ctx, &p);
  if (perr != KARST_SUCCESS) return perr;
  PJ *op = proj_operation(p, src, dst);
  karst_error_t err = KARST_SUCCESS;
  if (!op) {
    err = karst_set_error(ctx, KARST_EEXTERNAL, "PROJ finds no conversion from '%s' to '%s': %s",
                          src->text, dst->text, proj_reason(p));
  } else {
    PJ_COORD o = karst_i_proj.proj_trans(
        op, PJ_FWD, karst_i_proj.proj_coord(x + src->dx, y + src->dy, 0, HUGE_VAL));
    PJ *used = o.xy.x != HUGE_VAL ? karst_i_proj.proj_trans_get_last_used_operation(op) : NULL;
    const char *name = karst_i_proj.proj_get_name(used ? used : op);
    snprintf(what, size, "PROJ %s: %s", karst_i_proj.proj_info().release,
             name ? name : "unnamed operation");
    *accuracy = karst_i_proj.proj_coordoperation_get_accuracy(p, used ? used : op);
    karst_i_proj.proj_destroy(used);
  }
  karst_i_proj.proj_destroy(op);
  karst_i_proj.proj_context_destroy(p);
  return err;
}

/**
 * karst_crs_geodesic: the geodesic between two WGS 84 points (GeographicLib::Geodesic,
 * Karney 2013, "Algorithms for geodesics", J. Geodesy 87, 43-55; accurate to 15 nm): its length
 * @p s12 (m) and its azimuths at both ends (degrees clockwise from north; either may be NULL).
 * Time complexity: O(1).
 */
karst_error_t karst_crs_geodesic(karst_ctx_t *ctx, double lat1, double lon1, double lat2,
                                 double lon2, double *s12, double *azi1, double *azi2) {
  double a1, a2;
  if (!(fabs(lat1) <= 90) || !(fabs(lat2) <= 90) || !isfinite(lon1) || !isfinite(lon2))
    return karst_set_error(ctx, KARST_ERANGE,
                           "geodesic from (%g, %g) to (%g, %g): latitudes must be within [-90, 90]",
                           lat1, lon1, lat2, lon2);
  karst_error_t err = karst_i_geo_inverse(ctx, lat1, lon1, lat2, lon2, s12, &a1, &a2);
  if (!err && azi1) *azi1 = a1;
  if (!err && azi2) *azi2 = a2;
  return err;
}
