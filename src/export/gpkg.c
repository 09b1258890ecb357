/* GeoPackage export through GDAL/OGR's C API (include/karst/export.h, docs/gis.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "export/gdal_api_internal.h"
#include "karst/arrays.h"
#include "karst/export.h"
#include "karst/io.h"
#include "karst/palette.h"
#include "karst/version.h"

/** The GeoPackage's undefined Cartesian coordinate system (srs_id -1, OGC 12-128r18 §1.1.2.1.1),
 *  as GDAL's GPKG driver recognises it. */
#define UNDEFINED_CARTESIAN_WKT "LOCAL_CS[\"Undefined Cartesian SRS\"]"

/** Features written between two checks of ctx->interrupt and two progress reports. */
#define EXPORT_CHECK_EVERY 4096

void karst_export_options_init(karst_export_options_t *opt) {
  memset(opt, 0, sizeof *opt);
  opt->timestamp = KARST_EXPORT_TIME_NOW;
}

/* ------------------------------------------------------------------------ */
/* GDAL's messages into the context                                         */
/* ------------------------------------------------------------------------ */

typedef struct {
  karst_ctx_t *ctx;
  int failed;
  char msg[1024]; /* the last CE_Failure / CE_Fatal message */
} gdal_errors_t;

static void CPL_STDCALL on_gdal_error(CPLErr cls, CPLErrorNum num, const char *msg) {
  (void)num;
  gdal_errors_t *g = karst_i_gdal.CPLGetErrorHandlerUserData();
  if (!g) return;
  if (cls >= CE_Failure) {
    g->failed = 1;
    snprintf(g->msg, sizeof g->msg, "%s", msg ? msg : "unknown GDAL error");
  } else if (cls == CE_Warning) {
    karst_log(g->ctx, KARST_LOG_WARNING, "GDAL: %s", msg ? msg : "");
  }
}

static karst_error_t gdal_fail(karst_ctx_t *ctx, const gdal_errors_t *g, const char *path,
                               const char *what) {
  return karst_set_error(ctx, KARST_EEXTERNAL, "%s: %s: %s", path, what,
                         g->failed ? g->msg : "GDAL gave no reason");
}

/* ------------------------------------------------------------------------ */
/* Fields                                                                    */
/* ------------------------------------------------------------------------ */

/* One attribute component as a field: its name and where its values are. */
typedef struct {
  char name[80];
  const karst_attr_t *attr;
  int comp;
  const karst_palette_t *names; /* a categorical palette entry: also write NAME_name */
} field_t;

typedef struct {
  int n;
  field_t *f;
} fields_t;

static int reserved(const char *name, const char *const *taken) {
  for (; *taken; taken++)
    if (strcmp(name, *taken) == 0) return 1;
  return 0;
}

/* The fields of @p n attributes: one per component ("lrud_0" ... for several), a name that
 * clashes with a fixed field of the layer gets "attr_" in front. */
static karst_error_t plan_fields(karst_ctx_t *ctx, const karst_attr_t *attrs, int n,
                                 const char *const *taken, fields_t *out) {
  int total = 0;
  for (int i = 0; i < n; i++)
    total += attrs[i].ncomp > 0 ? attrs[i].ncomp : 0;
  out->n = 0;
  out->f = calloc((size_t)total + 1, sizeof *out->f);
  if (!out->f) return karst_set_error(ctx, KARST_ENOMEM, "out of memory");
  for (int i = 0; i < n; i++) {
    const karst_attr_t *a = &attrs[i];
    for (int c = 0; c < a->ncomp; c++) {
      field_t *f = &out->f[out->n++];
      char base[64];
      if (a->ncomp == 1)
        snprintf(base, sizeof base, "%s", a->name);
      else
        snprintf(base, sizeof base, "%s_%d", a->name, c);
      snprintf(f->name, sizeof f->name, "%s%s", reserved(base, taken) ? "attr_" : "", base);
      f->attr = a;
      f->comp = c;
      const karst_palette_t *p = karst_palette_find(a->name);
      if (a->integer && a->ncomp == 1 && p && p->kind == KARST_PALETTE_CATEGORICAL) f->names = p;
    }
  }
  return KARST_SUCCESS;
}

static int add_field(OGRLayerH layer, const char *name, OGRFieldType type) {
  OGRFieldDefnH d = karst_i_gdal.OGR_Fld_Create(name, type);
  int ok = karst_i_gdal.OGR_L_CreateField(layer, d, TRUE) == OGRERR_NONE;
  karst_i_gdal.OGR_Fld_Destroy(d);
  return ok;
}

static int create_fields(OGRLayerH layer, const fields_t *fs) {
  for (int i = 0; i < fs->n; i++) {
    const field_t *f = &fs->f[i];
    if (!add_field(layer, f->name, f->attr->integer ? OFTInteger64 : OFTReal)) return 0;
    if (f->names) {
      char nm[96];
      snprintf(nm, sizeof nm, "%s_name", f->name);
      if (!add_field(layer, nm, OFTString)) return 0;
    }
  }
  return 1;
}

/* Set the fields of item @p i (NAN: a null field). */
static void set_fields(OGRFeatureH feat, OGRFeatureDefnH defn, const fields_t *fs, karst_int_t i) {
  for (int k = 0; k < fs->n; k++) {
    const field_t *f = &fs->f[k];
    int idx = karst_i_gdal.OGR_FD_GetFieldIndex(defn, f->name);
    double v = f->attr->data[(size_t)i * (size_t)f->attr->ncomp + (size_t)f->comp];
    if (!isfinite(v)) {
      karst_i_gdal.OGR_F_SetFieldNull(feat, idx);
    } else if (f->attr->integer) {
      karst_i_gdal.OGR_F_SetFieldInteger64(feat, idx, (GIntBig)v);
    } else {
      karst_i_gdal.OGR_F_SetFieldDouble(feat, idx, v);
    }
    if (f->names) {
      char nm[96];
      snprintf(nm, sizeof nm, "%s_name", f->name);
      const karst_palette_category_t *c =
          isfinite(v) ? karst_palette_category(f->names, (int)v) : NULL;
      int j = karst_i_gdal.OGR_FD_GetFieldIndex(defn, nm);
      if (c)
        karst_i_gdal.OGR_F_SetFieldString(feat, j, c->name);
      else
        karst_i_gdal.OGR_F_SetFieldNull(feat, j);
    }
  }
}

/* ------------------------------------------------------------------------ */
/* Layers                                                                    */
/* ------------------------------------------------------------------------ */

static OGRLayerH create_layer(GDALDatasetH ds, const char *name, OGRSpatialReferenceH srs,
                              OGRwkbGeometryType type, const char *description) {
  char desc[512];
  snprintf(desc, sizeof desc, "DESCRIPTION=%s", description);
  char *options[] = {"FID=fid", "GEOMETRY_NAME=geom", desc, NULL};
  return karst_i_gdal.GDALDatasetCreateLayer(ds, name, srs, type, options);
}

typedef struct {
  karst_ctx_t *ctx;
  const char *path; /* the final name, for messages */
  gdal_errors_t *g;
  double done, total;
} writer_t;

/* After each feature: progress and interruption every EXPORT_CHECK_EVERY features. */
static karst_error_t tick(writer_t *w) {
  w->done += 1;
  if (fmod(w->done, EXPORT_CHECK_EVERY) != 0) return KARST_SUCCESS;
  karst_progress(w->ctx, "export", w->done, w->total);
  if (karst_interrupted(w->ctx))
    return karst_set_error(w->ctx, KARST_EINTERRUPTED, "%s: interrupted; nothing was written",
                           w->path);
  return KARST_SUCCESS;
}

static karst_error_t put_feature(writer_t *w, OGRLayerH layer, OGRFeatureH feat) {
  if (karst_i_gdal.OGR_L_CreateFeature(layer, feat) != OGRERR_NONE)
    return gdal_fail(w->ctx, w->g, w->path, "writing a feature");
  return tick(w);
}

static karst_error_t write_conduits(writer_t *w, GDALDatasetH ds, OGRSpatialReferenceH srs,
                                    const karst_network_t *net) {
  static const char *const taken[] = {"fid",     "geom",   "edge", "from_node",
                                      "to_node", "length", NULL};
  fields_t fs = {0, NULL};
  karst_error_t err = plan_fields(w->ctx, net->edge_attrs, net->n_edge_attrs, taken, &fs);
  if (err) return err;
  OGRLayerH layer = create_layer(ds, KARST_EXPORT_LAYER_CONDUITS, srs, wkbLineString25D,
                                 "karst network: one 3-D line per edge, in edge order "
                                 "(network.vtp cell order); length in metres");
  if (!layer || !add_field(layer, "edge", OFTInteger64) ||
      !add_field(layer, "from_node", OFTInteger64) || !add_field(layer, "to_node", OFTInteger64) ||
      !add_field(layer, "length", OFTReal) || !create_fields(layer, &fs)) {
    free(fs.f);
    return gdal_fail(w->ctx, w->g, w->path, "creating the conduits layer");
  }
  OGRFeatureDefnH defn = karst_i_gdal.OGR_L_GetLayerDefn(layer);
  int i_edge = karst_i_gdal.OGR_FD_GetFieldIndex(defn, "edge"),
      i_from = karst_i_gdal.OGR_FD_GetFieldIndex(defn, "from_node");
  int i_to = karst_i_gdal.OGR_FD_GetFieldIndex(defn, "to_node"),
      i_len = karst_i_gdal.OGR_FD_GetFieldIndex(defn, "length");
  for (karst_int_t e = 0; e < net->n_edges && !err; e++) {
    OGRFeatureH feat = karst_i_gdal.OGR_F_Create(defn);
    OGRGeometryH g = karst_i_gdal.OGR_G_CreateGeometry(wkbLineString25D);
    for (int k = 0; k < 2; k++) {
      const double *p = &net->xyz[3 * net->edges[2 * e + k]];
      karst_i_gdal.OGR_G_AddPoint(g, p[0], p[1], p[2]);
    }
    karst_i_gdal.OGR_F_SetGeometryDirectly(feat, g);
    karst_i_gdal.OGR_F_SetFieldInteger64(feat, i_edge, e);
    karst_i_gdal.OGR_F_SetFieldInteger64(feat, i_from, net->edges[2 * e]);
    karst_i_gdal.OGR_F_SetFieldInteger64(feat, i_to, net->edges[2 * e + 1]);
    karst_i_gdal.OGR_F_SetFieldDouble(feat, i_len, karst_network_edge_length(net, e));
    set_fields(feat, defn, &fs, e);
    err = put_feature(w, layer, feat);
    karst_i_gdal.OGR_F_Destroy(feat);
  }
  free(fs.f);
  return err;
}

static karst_error_t write_nodes(writer_t *w, GDALDatasetH ds, OGRSpatialReferenceH srs,
                                 const karst_network_t *net) {
  static const char *const taken[] = {"fid", "geom", "node", "label", NULL};
  fields_t fs = {0, NULL};
  karst_error_t err = plan_fields(w->ctx, net->node_attrs, net->n_node_attrs, taken, &fs);
  if (err) return err;
  OGRLayerH layer = create_layer(ds, KARST_EXPORT_LAYER_NODES, srs, wkbPoint25D,
                                 "karst network nodes (stations of a survey), in node order");
  if (!layer || !add_field(layer, "node", OFTInteger64) ||
      (net->node_labels && !add_field(layer, "label", OFTString)) || !create_fields(layer, &fs)) {
    free(fs.f);
    return gdal_fail(w->ctx, w->g, w->path, "creating the nodes layer");
  }
  OGRFeatureDefnH defn = karst_i_gdal.OGR_L_GetLayerDefn(layer);
  int i_node = karst_i_gdal.OGR_FD_GetFieldIndex(defn, "node"),
      i_label = karst_i_gdal.OGR_FD_GetFieldIndex(defn, "label");
  for (karst_int_t i = 0; i < net->n_nodes && !err; i++) {
    OGRFeatureH feat = karst_i_gdal.OGR_F_Create(defn);
    OGRGeometryH g = karst_i_gdal.OGR_G_CreateGeometry(wkbPoint25D);
    karst_i_gdal.OGR_G_SetPoint(g, 0, net->xyz[3 * i], net->xyz[3 * i + 1], net->xyz[3 * i + 2]);
    karst_i_gdal.OGR_F_SetGeometryDirectly(feat, g);
    karst_i_gdal.OGR_F_SetFieldInteger64(feat, i_node, i);
    if (net->node_labels && net->node_labels[i])
      karst_i_gdal.OGR_F_SetFieldString(feat, i_label, net->node_labels[i]);
    set_fields(feat, defn, &fs, i);
    err = put_feature(w, layer, feat);
    karst_i_gdal.OGR_F_Destroy(feat);
  }
  free(fs.f);
  return err;
}

static karst_error_t write_key_points(writer_t *w, GDALDatasetH ds, OGRSpatialReferenceH srs,
                                      const karst_export_source_t *src) {
  OGRLayerH layer =
      create_layer(ds, KARST_EXPORT_LAYER_KEY_POINTS, srs, wkbPoint25D,
                   "karst key points of the scenario: sinks, springs and waypoints; node is the "
                   "network node at the key point");
  if (!layer || !add_field(layer, "name", OFTString) || !add_field(layer, "type", OFTString) ||
      !add_field(layer, "kind", OFTInteger) || !add_field(layer, "kind_name", OFTString) ||
      !add_field(layer, "node", OFTInteger64))
    return gdal_fail(w->ctx, w->g, w->path, "creating the key_points layer");
  OGRFeatureDefnH defn = karst_i_gdal.OGR_L_GetLayerDefn(layer);
  karst_error_t err = KARST_SUCCESS;
  for (int k = 0; k < src->n_key_points && !err; k++) {
    const karst_export_keypoint_t *kp = &src->key_points[k];
    static const karst_node_kind_t kinds[] = {KARST_NODE_SINK, KARST_NODE_SPRING,
                                              KARST_NODE_WAYPOINT};
    static const char *const types[] = {"sink", "spring", "waypoint"};
    int t = kp->type >= KARST_KEYPOINT_SINK && kp->type <= KARST_KEYPOINT_WAYPOINT ? kp->type : 2;
    OGRFeatureH feat = karst_i_gdal.OGR_F_Create(defn);
    OGRGeometryH g = karst_i_gdal.OGR_G_CreateGeometry(wkbPoint25D);
    karst_i_gdal.OGR_G_SetPoint(g, 0, kp->p[0], kp->p[1], kp->p[2]);
    karst_i_gdal.OGR_F_SetGeometryDirectly(feat, g);
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "name"),
                                      kp->name);
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "type"),
                                      types[t]);
    karst_i_gdal.OGR_F_SetFieldInteger(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "kind"),
                                       kinds[t]);
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "kind_name"),
                                      karst_node_kind_name(kinds[t]));
    if (kp->node >= 0)
      karst_i_gdal.OGR_F_SetFieldInteger64(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "node"),
                                           kp->node);
    else
      karst_i_gdal.OGR_F_SetFieldNull(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "node"));
    err = put_feature(w, layer, feat);
    karst_i_gdal.OGR_F_Destroy(feat);
  }
  return err;
}

/* QGIS's layer_styles table (the "QGIS GeoPackage styling extension", as QGIS itself writes
 * it): QGIS applies the row marked useAsDefault of a layer when it opens that layer. */
static karst_error_t write_styles(writer_t *w, GDALDatasetH ds, const char *const qml[3],
                                  const char *const layers[3], const struct tm *utc) {
  char *options[] = {"FID=id", NULL};
  OGRLayerH layer = karst_i_gdal.GDALDatasetCreateLayer(ds, "layer_styles", NULL, wkbNone, options);
  static const char *const text[] = {"f_table_catalog", "f_table_schema",
                                     "f_table_name",    "f_geometry_column",
                                     "styleName",       "styleQML",
                                     "styleSLD",        "description",
                                     "owner",           "ui"};
  int ok = layer != NULL;
  for (size_t i = 0; ok && i < sizeof text / sizeof text[0]; i++)
    ok = add_field(layer, text[i], OFTString);
  if (ok) {
    OGRFieldDefnH d = karst_i_gdal.OGR_Fld_Create("useAsDefault", OFTInteger);
    karst_i_gdal.OGR_Fld_SetSubType(d, OFSTBoolean);
    ok = karst_i_gdal.OGR_L_CreateField(layer, d, TRUE) == OGRERR_NONE;
    karst_i_gdal.OGR_Fld_Destroy(d);
  }
  if (ok) ok = add_field(layer, "update_time", OFTDateTime);
  if (!ok) return gdal_fail(w->ctx, w->g, w->path, "creating the layer_styles table");
  OGRFeatureDefnH defn = karst_i_gdal.OGR_L_GetLayerDefn(layer);
  karst_error_t err = KARST_SUCCESS;
  for (int i = 0; i < 3 && !err; i++) {
    OGRFeatureH feat = karst_i_gdal.OGR_F_Create(defn);
    karst_i_gdal.OGR_F_SetFieldString(
        feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "f_table_catalog"), "");
    karst_i_gdal.OGR_F_SetFieldString(
        feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "f_table_schema"), "");
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "f_table_name"),
                                      layers[i]);
    karst_i_gdal.OGR_F_SetFieldString(
        feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "f_geometry_column"), "geom");
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "styleName"),
                                      layers[i]);
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "styleQML"),
                                      qml[i]);
    karst_i_gdal.OGR_F_SetFieldString(feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "description"),
                                      "karst palette (include/karst/palette.h)");
    karst_i_gdal.OGR_F_SetFieldInteger(feat,
                                       karst_i_gdal.OGR_FD_GetFieldIndex(defn, "useAsDefault"), 1);
    karst_i_gdal.OGR_F_SetFieldDateTime(
        feat, karst_i_gdal.OGR_FD_GetFieldIndex(defn, "update_time"), utc->tm_year + 1900,
        utc->tm_mon + 1, utc->tm_mday, utc->tm_hour, utc->tm_min, utc->tm_sec, 100);
    err = put_feature(w, layer, feat);
    karst_i_gdal.OGR_F_Destroy(feat);
  }
  return err;
}

/* The fields karst adds itself: title (quantity and unit) and meaning. */
static const struct {
  const char *column, *title, *description;
} fixed_columns[] = {
    {"edge", "edge index", "index of the edge in the network (0-based; network.vtp cell order)"},
    {"from_node", "first node index", "index (0-based) of the node the edge starts at"},
    {"to_node", "second node index", "index (0-based) of the node the edge ends at"},
    {"length", "conduit length (m)", "3-D length of the edge in metres"},
    {"node", "node index",
     "index (0-based) of the network node (for a key point: the node at "
     "exactly its position, null when none)"},
    {"name", "key point name", "name of the key point in the scenario"},
    {"type", "key point type", "sink, spring or waypoint"},
};

/* Write @p s as an SQL string literal into @p out (quotes doubled); 0 when it does not fit. */
static int sql_quote(char *out, size_t size, const char *s) {
  size_t k = 0;
  if (size < 3) return 0;
  out[k++] = '\'';
  for (; *s; s++) {
    if (k + 3 >= size) return 0;
    if (*s == '\'') out[k++] = '\'';
    out[k++] = *s;
  }
  out[k++] = '\'';
  out[k] = '\0';
  return 1;
}

/* Title and meaning of field @p col: a fixed field, or an array of include/karst/arrays.h
 * (with "attr_" in front, "_name" or "_K" behind), or the column's name and "not described"
 * for an array arrays.h does not know. */
static void describe_column(const char *col, char *title, size_t tsize, const char **description) {
  for (size_t i = 0; i < sizeof fixed_columns / sizeof fixed_columns[0]; i++)
    if (strcmp(col, fixed_columns[i].column) == 0) {
      snprintf(title, tsize, "%s", fixed_columns[i].title);
      *description = fixed_columns[i].description;
      return;
    }
  char base[96];
  snprintf(base, sizeof base, "%s", strncmp(col, "attr_", 5) == 0 ? col + 5 : col);
  const karst_array_info_t *info = karst_arrays_find(base);
  size_t n = strlen(base);
  if (!info && n > 5 && strcmp(base + n - 5, "_name") == 0) {
    base[n - 5] = '\0';
    if ((info = karst_arrays_find(base))) {
      snprintf(title, tsize, "%s (name)", info->title);
      *description = info->meaning;
      return;
    }
  }
  char *us = strrchr(base, '_');
  if (!info && us && us[1] && strspn(us + 1, "0123456789") == strlen(us + 1)) {
    int comp = atoi(us + 1);
    *us = '\0';
    if ((info = karst_arrays_find(base))) {
      snprintf(title, tsize, "%s [%d]", info->title, comp);
      *description = info->meaning;
      return;
    }
  }
  /* As the .vtp's array_units says of an array karst does not describe. */
  snprintf(title, tsize, "%s", info ? info->title : col);
  *description = info ? info->meaning : "not described by karst (docs/arrays.md)";
}

/*
 * Each field's quantity, unit and meaning in the file itself: the GeoPackage schema extension's
 * gpkg_data_columns (OGC 12-128r18 F.9), title "conduit radius (m)", description the sentence
 * of include/karst/arrays.h with its sign convention (docs/arrays.md), which GIS programs show
 * as the field's alias and description.
 */
static karst_error_t write_data_columns(writer_t *w, GDALDatasetH ds, const char *const *layers,
                                        int n_layers) {
  static const char *const create[] = {
      "CREATE TABLE gpkg_data_columns (table_name TEXT NOT NULL, column_name TEXT NOT NULL, "
      "name TEXT, title TEXT, description TEXT, mime_type TEXT, constraint_name TEXT, "
      "CONSTRAINT pk_gdc PRIMARY KEY (table_name, column_name), "
      "CONSTRAINT gdc_tn UNIQUE (table_name, name))",
      "INSERT INTO gpkg_extensions (table_name, column_name, extension_name, definition, scope) "
      "VALUES ('gpkg_data_columns', NULL, 'gpkg_schema', "
      "'http://www.geopackage.org/spec121/#extension_schema', 'read-write')"};
  for (size_t i = 0; i < sizeof create / sizeof create[0]; i++) {
    karst_i_gdal.GDALDatasetExecuteSQL(ds, create[i], NULL, NULL);
    if (w->g->failed) return gdal_fail(w->ctx, w->g, w->path, "creating gpkg_data_columns");
  }
  for (int l = 0; l < n_layers; l++) {
    OGRLayerH layer = karst_i_gdal.GDALDatasetGetLayerByName(ds, layers[l]);
    if (!layer) continue;
    OGRFeatureDefnH defn = karst_i_gdal.OGR_L_GetLayerDefn(layer);
    for (int i = 0; i < karst_i_gdal.OGR_FD_GetFieldCount(defn); i++) {
      const char *col = karst_i_gdal.OGR_Fld_GetNameRef(karst_i_gdal.OGR_FD_GetFieldDefn(defn, i)),
                 *description = NULL;
      char title[192], q[5][640], sql[3400];
      describe_column(col, title, sizeof title, &description);
      if (!sql_quote(q[0], sizeof q[0], layers[l]) || !sql_quote(q[1], sizeof q[1], col) ||
          !sql_quote(q[2], sizeof q[2], title) || !sql_quote(q[3], sizeof q[3], description))
        continue;
      snprintf(sql, sizeof sql,
               "INSERT INTO gpkg_data_columns (table_name, column_name, name, title, description) "
               "VALUES (%s, %s, %s, %s, %s)",
               q[0], q[1], q[2], q[2], q[3]);
      karst_i_gdal.GDALDatasetExecuteSQL(ds, sql, NULL, NULL);
      if (w->g->failed) return gdal_fail(w->ctx, w->g, w->path, "describing the fields");
    }
  }
  return KARST_SUCCESS;
}

/* Dataset metadata: karst's and the libraries' versions and where the network came from. */
static void write_metadata(GDALDatasetH ds, const karst_export_source_t *src, const char *crs,
                           const char *versions) {
  char buf[64];
  karst_i_gdal.GDALSetMetadataItem(ds, "karst_version", karst_version(), NULL);
  karst_i_gdal.GDALSetMetadataItem(ds, "versions", versions, NULL);
  karst_i_gdal.GDALSetMetadataItem(ds, "network", src->network_path, NULL);
  if (src->provenance_path)
    karst_i_gdal.GDALSetMetadataItem(ds, "provenance", src->provenance_path, NULL);
  if (src->scenario) karst_i_gdal.GDALSetMetadataItem(ds, "scenario", src->scenario, NULL);
  if (src->scenario_hash)
    karst_i_gdal.GDALSetMetadataItem(ds, "scenario_hash", src->scenario_hash, NULL);
  if (src->have_seed) {
    snprintf(buf, sizeof buf, "%llu", (unsigned long long)src->seed);
    karst_i_gdal.GDALSetMetadataItem(ds, "seed", buf, NULL);
  }
  if (src->member >= 0) {
    snprintf(buf, sizeof buf, "%lld", (long long)src->member);
    karst_i_gdal.GDALSetMetadataItem(ds, "member", buf, NULL);
  }
  karst_i_gdal.GDALSetMetadataItem(ds, "crs", crs ? crs : "undefined", NULL);
  if (src->net.title) karst_i_gdal.GDALSetMetadataItem(ds, "title", src->net.title, NULL);
}

static int has_gpkg_extension(const char *path) {
  size_t n = strlen(path);
  return n > 5 && strcmp(path + n - 5, ".gpkg") == 0;
}

static karst_error_t check_source(karst_ctx_t *ctx, const char *path,
                                  const karst_export_source_t *src) {
  const karst_network_t *net = &src->net;
  for (karst_int_t i = 0; i < net->n_nodes; i++)
    for (int k = 0; k < 3; k++)
      if (!isfinite(net->xyz[3 * i + k]))
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: node %lld has a coordinate that is not finite (%g); nothing "
                               "was written",
                               path, (long long)i, net->xyz[3 * i + k]);
  for (karst_int_t e = 0; e < net->n_edges; e++)
    for (int k = 0; k < 2; k++)
      if (net->edges[2 * e + k] < 0 || net->edges[2 * e + k] >= net->n_nodes)
        return karst_set_error(
            ctx, KARST_EINVAL, "%s: edge %lld names node %lld, outside [0, %lld)", path,
            (long long)e, (long long)net->edges[2 * e + k], (long long)net->n_nodes);
  return KARST_SUCCESS;
}

/**
 * Write the GeoPackage @p path of @p src (see export.h).
 * @param ctx   context: errors, warnings from GDAL, progress ("export", features), interrupt.
 * @param path  the GeoPackage; must end in ".gpkg". Replaced atomically when it exists.
 * @param src   what to write (karst_export_source_load).
 * @param opt   coordinate system override, style file, timestamp; NULL: the defaults.
 * @return KARST_SUCCESS; KARST_EINVAL (a name not ending in .gpkg, a coordinate that is not
 *         finite, an edge naming a missing node, a timestamp before 1970 or after 9999);
 *         KARST_EPARSE (a coordinate system GDAL/PROJ does not know, naming where it came
 *         from); KARST_EIO (the directory cannot be written); KARST_EEXTERNAL (GDAL failed,
 *         quoting it); KARST_EINTERRUPTED; KARST_ENOMEM.
 * Time complexity: O(nodes + edges) features, each an SQLite insert (O(log features)).
 */
karst_error_t karst_export_gpkg(karst_ctx_t *ctx, const char *path,
                                const karst_export_source_t *src,
                                const karst_export_options_t *opt) {
  karst_export_options_t defaults;
  if (!opt) {
    karst_export_options_init(&defaults);
    opt = &defaults;
  }
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no GeoPackage name given");
  if (!has_gpkg_extension(path))
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: a GeoPackage name must end in .gpkg (QGIS and GDAL recognise "
                           "the format by it)",
                           path);
  if (!src) return karst_set_error(ctx, KARST_EINVAL, "%s: nothing to export", path);
  if (opt->timestamp < 0 && opt->timestamp != KARST_EXPORT_TIME_NOW)
    return karst_set_error(ctx, KARST_EINVAL, "%s: timestamp %lld is before 1970-01-01", path,
                           (long long)opt->timestamp);
  karst_error_t err = check_source(ctx, path, src);
  if (err) return err;
  if ((err = karst_check_writable(ctx, path))) return err;
  if (opt->qml_path && (err = karst_check_writable(ctx, opt->qml_path))) return err;
  if ((err = karst_i_gdal_load(ctx))) return err;

  gdal_errors_t g = {ctx, 0, ""};
  karst_i_gdal.CPLPushErrorHandlerEx(on_gdal_error, &g);
  OGRSpatialReferenceH srs = NULL;
  GDALDatasetH ds = NULL;
  karst_fileset_t files;
  karst_fileset_init(&files);
  char *qml[3] = {NULL, NULL, NULL}, *versions = NULL;
  const char *crs = opt->crs ? opt->crs : src->crs;
  const char *tmp = NULL;
  int stamped = 0;
  writer_t w = {ctx, path, &g, 0,
                (double)(src->net.n_edges + src->net.n_nodes + src->n_key_points)};

  if (crs) {
    srs = karst_i_gdal.OSRNewSpatialReference(NULL);
    if (!srs) goto nomem;
    if (karst_i_gdal.OSRSetFromUserInput(srs, crs) != OGRERR_NONE) {
      err =
          karst_set_error(ctx, KARST_EPARSE,
                          "%s: coordinate system '%s' is not one GDAL/PROJ "
                          "knows (%s)%s",
                          opt->crs ? "--crs" : (src->crs_where ? src->crs_where : "input"), crs,
                          g.failed ? g.msg : "unrecognised",
                          opt->crs ? "" : "; give the right one with --crs, e.g. --crs EPSG:2154");
      goto cleanup;
    }
    karst_i_gdal.OSRSetAxisMappingStrategy(srs, OAMS_TRADITIONAL_GIS_ORDER);
  } else {
    /* No coordinate system: the GeoPackage's "Undefined Cartesian SRS" (srs_id -1). Without
     * an SRS GDAL would write srs_id 0, "Undefined geographic SRS", and QGIS would take the
     * metres for degrees. */
    srs = karst_i_gdal.OSRNewSpatialReference(UNDEFINED_CARTESIAN_WKT);
    if (!srs) goto nomem;
  }
  const int have_type = karst_network_attr_find(&src->net, KARST_ATTR_EDGE, "tunnel_type") != NULL;
  const int have_kind = karst_network_attr_find(&src->net, KARST_ATTR_NODE, "kind") != NULL;
  qml[0] = karst_export_qml(KARST_EXPORT_STYLE_CONDUITS, have_type);
  qml[1] = karst_export_qml(KARST_EXPORT_STYLE_NODES, have_kind);
  qml[2] = karst_export_qml(KARST_EXPORT_STYLE_KEY_POINTS, 1);
  versions = karst_versions_json();
  if (!qml[0] || !qml[1] || !qml[2] || !versions) goto nomem;

  /* The GeoPackage and its style are one set: both to temporary names, renamed together. */
  char *tmp_name = karst_temp_name_ext(path);
  if (!tmp_name) goto nomem;
  err = karst_fileset_add(ctx, &files, path, tmp_name, &tmp);
  free(tmp_name);
  if (err) goto cleanup;

  /* The clock readings: layer_styles.update_time (ours) and gpkg_contents.last_change (GDAL's
   * GPKG driver reads the configuration option OGR_CURRENT_DATE; set for this thread only). */
  const time_t when = opt->timestamp == KARST_EXPORT_TIME_NOW ? time(NULL) : (time_t)opt->timestamp;
  struct tm utc;
  char stamp[32];
  if (!gmtime_r(&when, &utc) || utc.tm_year + 1900 > 9999 ||
      strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%S.000Z", &utc) == 0) {
    err = karst_set_error(ctx, KARST_EINVAL, "%s: timestamp %lld is not a date before year 10000",
                          path, (long long)when);
    goto cleanup;
  }
  karst_i_gdal.CPLSetThreadLocalConfigOption("OGR_CURRENT_DATE", stamp);
  stamped = 1;

  karst_i_gdal.GDALAllRegister();
  GDALDriverH drv = karst_i_gdal.GDALGetDriverByName("GPKG");
  if (!drv) {
    err = karst_set_error(ctx, KARST_EUNSUPPORTED,
                          "%s: this GDAL has no GPKG driver (install Debian's libgdal32)", path);
    goto cleanup;
  }
  ds = karst_i_gdal.GDALCreate(drv, tmp, 0, 0, 0, GDT_Unknown, NULL);
  if (!ds) {
    err = gdal_fail(ctx, &g, path, "creating the GeoPackage");
    goto cleanup;
  }
  if (karst_i_gdal.GDALDatasetStartTransaction(ds, FALSE) != OGRERR_NONE) {
    err = gdal_fail(ctx, &g, path, "starting a transaction");
    goto cleanup;
  }
  karst_progress(ctx, "export", 0, w.total);
  if ((err = write_conduits(&w, ds, srs, &src->net))) goto cleanup;
  if ((err = write_nodes(&w, ds, srs, &src->net))) goto cleanup;
  if ((err = write_key_points(&w, ds, srs, src))) goto cleanup;
  static const char *const layers[3] = {KARST_EXPORT_LAYER_CONDUITS, KARST_EXPORT_LAYER_NODES,
                                        KARST_EXPORT_LAYER_KEY_POINTS};
  if ((err = write_styles(&w, ds, (const char *const *)qml, layers, &utc))) goto cleanup;
  if ((err = write_data_columns(&w, ds, layers, 3))) goto cleanup;
  if (karst_i_gdal.GDALDatasetCommitTransaction(ds) != OGRERR_NONE) {
    err = gdal_fail(ctx, &g, path, "committing the transaction");
    goto cleanup;
  }
  write_metadata(ds, src, crs, versions);
  karst_i_gdal.GDALClose(ds);
  ds = NULL;
  if (g.failed) {
    err = gdal_fail(ctx, &g, path, "closing the GeoPackage");
    goto cleanup;
  }
  karst_progress(ctx, "export", w.total, w.total);
  if (opt->qml_path) {
    if ((err = karst_fileset_add(ctx, &files, opt->qml_path, NULL, &tmp))) goto cleanup;
    FILE *fp = fopen(tmp, "w");
    int ok = fp && fputs(qml[0], fp) >= 0;
    if (fp && fclose(fp) != 0) ok = 0;
    if (!ok) {
      err = karst_set_error(ctx, KARST_EIO, "%s: cannot write the style", opt->qml_path);
      goto cleanup;
    }
  }
  err = karst_fileset_commit(ctx, &files);
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "out of memory");
cleanup:
  if (ds) karst_i_gdal.GDALClose(ds);
  if (stamped) karst_i_gdal.CPLSetThreadLocalConfigOption("OGR_CURRENT_DATE", NULL);
  karst_fileset_abort(&files);
  if (srs) karst_i_gdal.OSRDestroySpatialReference(srs);
  karst_i_gdal.CPLPopErrorHandler();
  for (int i = 0; i < 3; i++)
    free(qml[i]);
  free(versions);
  return err;
}
