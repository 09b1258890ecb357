/*
 * GeoPackage export (include/karst/export.h), read back with GDAL/OGR's reader: hand-built
 * networks (empty, a single node, two disconnected edges, collinear nodes, a two-component
 * attribute, an attribute whose name clashes with a fixed field, NaN attribute values, labels),
 * their coordinate system or the undefined Cartesian one, refusals (bad names, non-finite
 * coordinates, edges naming missing nodes, unknown coordinate systems) that leave no file and
 * keep a previous one, and the QGIS styles: one category per palette category of tunnel_type
 * and kind, with the palette's names and colours.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include "karst.h"
#include "test_util.h"

static char dir[256];

static int setup(void **state) {
  (void)state;
  snprintf(dir, sizeof dir, "%s/test_export.%d", KARST_BINARY_DIR, (int)getpid());
  mkdir(dir, 0755);
  GDALAllRegister();
  return 0;
}

static int teardown(void **state) {
  (void)state;
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  return system(cmd) == 0 ? 0 : -1;
}

static const char *path_in(const char *name) {
  static char p[2][512];
  static int k;
  k ^= 1;
  snprintf(p[k], sizeof p[k], "%s/%s", dir, name);
  return p[k];
}

/* A network of two disconnected edges 0-1 and 2-3, nodes 1 and 2 collinear with 0. */
static void two_edges(karst_export_source_t *s) {
  karst_export_source_init(s);
  karst_network_t *n = &s->net;
  const double p[4][3] = {{0, 0, 10}, {3, 4, 10}, {6, 8, 20}, {100, 0, -5}};
  for (int i = 0; i < 4; i++)
    assert_int_equal(karst_network_add_node(n, p[i][0], p[i][1], p[i][2], NULL), 0);
  assert_int_equal(karst_network_add_edge(n, 0, 1, NULL), 0);
  assert_int_equal(karst_network_add_edge(n, 2, 3, NULL), 0);
  double *d;
  assert_int_equal(karst_network_attr_add(n, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &d), 0);
  d[0] = KARST_TUNNEL_CANYON, d[1] = KARST_TUNNEL_CHAMBER;
  assert_int_equal(karst_network_attr_add(n, KARST_ATTR_EDGE, "radius", 1, 0, &d), 0);
  d[0] = 1.25, d[1] = NAN;
  assert_int_equal(karst_network_attr_add(n, KARST_ATTR_EDGE, "length", 1, 0, &d), 0);
  d[0] = -1, d[1] = -2; /* clashes with the computed length: written as attr_length */
  assert_int_equal(karst_network_attr_add(n, KARST_ATTR_NODE, "lrud", 2, 0, &d), 0);
  for (int i = 0; i < 8; i++)
    d[i] = 0.5 * i;
  assert_int_equal(karst_network_attr_add(n, KARST_ATTR_NODE, "kind", 1, 1, &d), 0);
  d[0] = KARST_NODE_SINK, d[3] = KARST_NODE_SPRING;
  assert_int_equal(karst_network_set_label(n, 3, "spring A"), 0);
  s->key_points = calloc(2, sizeof *s->key_points);
  assert_non_null(s->key_points);
  s->n_key_points = 2;
  snprintf(s->key_points[0].name, 64, "sink1");
  s->key_points[0].type = KARST_KEYPOINT_SINK;
  s->key_points[0].node = 0;
  snprintf(s->key_points[1].name, 64, "way");
  s->key_points[1].type = KARST_KEYPOINT_WAYPOINT;
  s->key_points[1].p[0] = 50, s->key_points[1].p[1] = 50, s->key_points[1].p[2] = 1;
  s->key_points[1].node = -1;
  s->network_path = strdup("hand-built");
  assert_non_null(s->network_path);
}

static OGRLayerH layer(GDALDatasetH ds, const char *name) {
  OGRLayerH l = GDALDatasetGetLayerByName(ds, name);
  assert_non_null(l);
  return l;
}

static void test_two_edges_read_back(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_export_source_t s;
  two_edges(&s);
  karst_export_options_t opt;
  karst_export_options_init(&opt);
  opt.crs = "EPSG:32634";
  opt.qml_path = path_in("two.qml");
  karst_error_t err = karst_export_gpkg(&ctx, path_in("two.gpkg"), &s, &opt);
  if (err) print_error("%s\n", ctx.errmsg);
  assert_int_equal(err, KARST_SUCCESS);
  GDALDatasetH ds = GDALOpenEx(path_in("two.gpkg"), GDAL_OF_VECTOR, NULL, NULL, NULL);
  assert_non_null(ds);
  OGRLayerH c = layer(ds, "conduits");
  assert_int_equal(OGR_L_GetFeatureCount(c, TRUE), 2);
  assert_int_equal(OGR_L_GetGeomType(c), wkbLineString25D);
  const char *auth = OSRGetAuthorityCode(OGR_L_GetSpatialRef(c), NULL);
  assert_non_null(auth);
  assert_string_equal(auth, "32634");
  OGRFeatureDefnH d = OGR_L_GetLayerDefn(c);
  assert_true(OGR_FD_GetFieldIndex(d, "attr_length") >= 0);
  OGR_L_ResetReading(c);
  for (int e = 0; e < 2; e++) {
    OGRFeatureH f = OGR_L_GetNextFeature(c);
    assert_non_null(f);
    assert_int_equal(OGR_F_GetFieldAsInteger64(f, OGR_FD_GetFieldIndex(d, "edge")), e);
    assert_int_equal(OGR_F_GetFieldAsInteger64(f, OGR_FD_GetFieldIndex(d, "from_node")), 2 * e);
    assert_int_equal(OGR_F_GetFieldAsInteger64(f, OGR_FD_GetFieldIndex(d, "to_node")), 2 * e + 1);
    /* Lengths by hand: |(3, 4, 0)| = 5, |(94, -8, -25)| = sqrt(8836 + 64 + 625). */
    assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(d, "length")),
                 e ? sqrt(9525.0) : 5.0, 1e-12);
    assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(d, "attr_length")), -1 - e, 0);
    assert_string_equal(OGR_F_GetFieldAsString(f, OGR_FD_GetFieldIndex(d, "tunnel_type_name")),
                        e ? "chamber" : "canyon");
    int ir = OGR_FD_GetFieldIndex(d, "radius");
    if (e)
      assert_true(OGR_F_IsFieldNull(f, ir));
    else
      assert_close(OGR_F_GetFieldAsDouble(f, ir), 1.25, 0);
    OGRGeometryH g = OGR_F_GetGeometryRef(f);
    assert_int_equal(OGR_G_GetPointCount(g), 2);
    assert_close(OGR_G_GetZ(g, 1), e ? -5.0 : 10.0, 0);
    OGR_F_Destroy(f);
  }
  OGRLayerH n = layer(ds, "nodes");
  assert_int_equal(OGR_L_GetFeatureCount(n, TRUE), 4);
  d = OGR_L_GetLayerDefn(n);
  assert_true(OGR_FD_GetFieldIndex(d, "lrud_0") >= 0 && OGR_FD_GetFieldIndex(d, "lrud_1") >= 0);
  OGRFeatureH f = OGR_L_GetFeature(n, 4); /* fids count from 1 */
  assert_non_null(f);
  assert_string_equal(OGR_F_GetFieldAsString(f, OGR_FD_GetFieldIndex(d, "label")), "spring A");
  assert_close(OGR_F_GetFieldAsDouble(f, OGR_FD_GetFieldIndex(d, "lrud_1")), 3.5, 0);
  assert_string_equal(OGR_F_GetFieldAsString(f, OGR_FD_GetFieldIndex(d, "kind_name")), "spring");
  OGR_F_Destroy(f);
  OGRLayerH k = layer(ds, "key_points");
  assert_int_equal(OGR_L_GetFeatureCount(k, TRUE), 2);
  d = OGR_L_GetLayerDefn(k);
  f = OGR_L_GetFeature(k, 2);
  assert_string_equal(OGR_F_GetFieldAsString(f, OGR_FD_GetFieldIndex(d, "name")), "way");
  assert_string_equal(OGR_F_GetFieldAsString(f, OGR_FD_GetFieldIndex(d, "type")), "waypoint");
  assert_int_equal(OGR_F_GetFieldAsInteger(f, OGR_FD_GetFieldIndex(d, "kind")),
                   KARST_NODE_WAYPOINT);
  assert_true(OGR_F_IsFieldNull(f, OGR_FD_GetFieldIndex(d, "node")));
  OGR_F_Destroy(f);
  assert_string_equal(GDALGetMetadataItem(ds, "karst_version", NULL), karst_version());
  assert_string_equal(GDALGetMetadataItem(ds, "crs", NULL), "EPSG:32634");
  GDALClose(ds);
  struct stat st;
  assert_int_equal(stat(path_in("two.qml"), &st), 0);
  karst_export_source_destroy(&s);
}

/* The empty network and a single node: valid GeoPackages with empty layers, undefined CRS. */
static void test_empty_and_single(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (int single = 0; single < 2; single++) {
    karst_export_source_t s;
    karst_export_source_init(&s);
    s.network_path = strdup("hand-built");
    if (single) assert_int_equal(karst_network_add_node(&s.net, 1, 2, 3, NULL), 0);
    const char *p = path_in(single ? "single.gpkg" : "empty.gpkg");
    assert_int_equal(karst_export_gpkg(&ctx, p, &s, NULL), KARST_SUCCESS);
    GDALDatasetH ds = GDALOpenEx(p, GDAL_OF_VECTOR, NULL, NULL, NULL);
    assert_non_null(ds);
    assert_int_equal(OGR_L_GetFeatureCount(layer(ds, "conduits"), TRUE), 0);
    assert_int_equal(OGR_L_GetFeatureCount(layer(ds, "nodes"), TRUE), single);
    assert_int_equal(OGR_L_GetFeatureCount(layer(ds, "key_points"), TRUE), 0);
    OGRSpatialReferenceH srs = OGR_L_GetSpatialRef(layer(ds, "nodes"));
    assert_non_null(srs);
    assert_string_equal(OSRGetName(srs), "Undefined Cartesian SRS");
    assert_string_equal(GDALGetMetadataItem(ds, "crs", NULL), "undefined");
    GDALClose(ds);
    karst_export_source_destroy(&s);
  }
}

static int exists(const char *p) {
  struct stat st;
  return stat(p, &st) == 0;
}

/* Refusals: a message naming the problem, no output, no temporary, a previous file intact. */
static void test_refusals(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_export_source_t s;
  two_edges(&s);
  char keep[512];
  snprintf(keep, sizeof keep, "%s", path_in("keep.gpkg"));
  assert_int_equal(karst_export_gpkg(&ctx, keep, &s, NULL), KARST_SUCCESS);
  struct stat before;
  assert_int_equal(stat(keep, &before), 0);

  karst_export_options_t opt;
  karst_export_options_init(&opt);
  opt.crs = "EPSG:99999";
  assert_int_equal(karst_export_gpkg(&ctx, keep, &s, &opt), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "--crs: coordinate system 'EPSG:99999' is not one GDAL/PROJ"));
  s.crs = strdup("+proj=nonsense");
  s.crs_where = strdup("run.json:3:10");
  assert_int_equal(karst_export_gpkg(&ctx, keep, &s, NULL), KARST_EPARSE);
  assert_non_null(strstr(ctx.errmsg, "run.json:3:10: coordinate system '+proj=nonsense'"));

  assert_int_equal(karst_export_gpkg(&ctx, path_in("x.shp"), &s, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "must end in .gpkg"));
  assert_int_equal(karst_export_gpkg(&ctx, path_in("none/x.gpkg"), &s, NULL), KARST_EIO);

  free(s.crs), free(s.crs_where);
  s.crs = s.crs_where = NULL;
  s.net.xyz[7] = NAN;
  assert_int_equal(karst_export_gpkg(&ctx, keep, &s, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "node 2 has a coordinate that is not finite"));
  s.net.xyz[7] = 8;
  s.net.edges[3] = 9;
  assert_int_equal(karst_export_gpkg(&ctx, keep, &s, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "edge 1 names node 9, outside [0, 4)"));

  struct stat after;
  assert_int_equal(stat(keep, &after), 0);
  assert_int_equal(after.st_ino, before.st_ino);
  assert_int_equal(after.st_mtime, before.st_mtime);
  assert_false(exists(path_in("x.shp")));
  char cmd[600];
  snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -q tmp", dir);
  assert_int_not_equal(system(cmd), 0);
  karst_export_source_destroy(&s);
}

/* Colour "#RRGGBB" as QML's "R,G,B,255". */
static void qml_colour(const char *hex, char out[32]) {
  double rgb[3];
  assert_int_equal(karst_palette_hex_rgb(hex, rgb), 0);
  snprintf(out, 32, "%d,%d,%d,255", (int)lround(rgb[0] * 255), (int)lround(rgb[1] * 255),
           (int)lround(rgb[2] * 255));
}

/* Each style: one category per palette category, in order, with its code, name and colour. */
static void test_qml_uses_the_palette(void **state) {
  (void)state;
  static const struct {
    karst_export_style_t style;
    const char *array, *colour_key;
  } cases[] = {{KARST_EXPORT_STYLE_CONDUITS, "tunnel_type", "line_color"},
               {KARST_EXPORT_STYLE_NODES, "kind", "color"},
               {KARST_EXPORT_STYLE_KEY_POINTS, "kind", "color"}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    char *q = karst_export_qml(cases[c].style, 1);
    assert_non_null(q);
    const karst_palette_t *p = karst_palette_find(cases[c].array);
    assert_non_null(p);
    char want[256];
    snprintf(want, sizeof want, "type=\"categorizedSymbol\" attr=\"%s\"", cases[c].array);
    assert_non_null(strstr(q, want));
    const char *at = q;
    for (int i = 0; i < p->n; i++) {
      snprintf(want, sizeof want, "symbol=\"%d\" value=\"%d\" label=\"%s\"", i,
               p->categories[i].code, p->categories[i].name);
      const char *hit = strstr(at, want);
      if (!hit) print_error("%s: no category '%s'\n", cases[c].array, want);
      assert_non_null(hit);
      at = hit;
    }
    for (int i = 0; i < p->n; i++) {
      char colour[32];
      qml_colour(p->categories[i].hex, colour);
      snprintf(want, sizeof want, "name=\"%d\" type=\"%s\">", i,
               cases[c].style == KARST_EXPORT_STYLE_CONDUITS ? "line" : "marker");
      const char *sym = strstr(q, want);
      assert_non_null(sym);
      snprintf(want, sizeof want, "<prop k=\"%s\" v=\"%s\"/>", cases[c].colour_key, colour);
      const char *prop = strstr(sym, want), *end = strstr(sym, "</symbol>");
      if (!prop || prop > end) print_error("%s %d: no %s\n", cases[c].array, i, want);
      assert_true(prop && prop < end);
    }
    free(q);
  }
  /* Without the field: a single symbol, in the survey colour for conduits. */
  char *q = karst_export_qml(KARST_EXPORT_STYLE_CONDUITS, 0);
  assert_non_null(q);
  assert_non_null(strstr(q, "type=\"singleSymbol\""));
  char colour[32], want[64];
  qml_colour(karst_palette_role(KARST_PALETTE_ROLE_SURVEY), colour);
  snprintf(want, sizeof want, "v=\"%s\"", colour);
  assert_non_null(strstr(q, want));
  free(q);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_two_edges_read_back),
      cmocka_unit_test(test_empty_and_single),
      cmocka_unit_test(test_refusals),
      cmocka_unit_test(test_qml_uses_the_palette),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
