/**
 * @file export.h
 * @brief Networks for GIS (thin C interface over GDAL/OGR in src/export/): a
 *        GeoPackage that QGIS opens with the conduits as 3-D LineStrings
 *        carrying every edge attribute, the nodes and the key points as 3-D
 *        points, the coordinate system of the scenario or survey, and QGIS
 *        styles (.qml, also stored in the GeoPackage's layer_styles table so
 *        that QGIS applies them on opening) that colour tunnel types and node
 *        kinds with the shared palette (include/karst/palette.h). docs/gis.md.
 */
#ifndef KARST_EXPORT_H
#define KARST_EXPORT_H

#include <stdint.h>

#include "karst/common.h"
#include "karst/network.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Layer names of the GeoPackage. */
#define KARST_EXPORT_LAYER_CONDUITS "conduits"
#define KARST_EXPORT_LAYER_NODES "nodes"
#define KARST_EXPORT_LAYER_KEY_POINTS "key_points"

/** A key point as its run.json (or ensemble.json) records it. */
typedef struct karst_export_keypoint {
  char name[64];
  karst_keypoint_type_t type;
  double p[3];      /**< position (m) */
  karst_int_t node; /**< the network node at exactly that position, or -1 */
} karst_export_keypoint_t;

/** What is exported: a network and what its provenance file says about it. */
typedef struct karst_export_source {
  karst_network_t net;
  int n_key_points;
  karst_export_keypoint_t *key_points;
  char *crs;             /**< the coordinate system ("EPSG:2154", WKT, PROJ string), or NULL */
  char *crs_where;       /**< where it was read, for messages ("DIR/run.json:3:10"), or NULL */
  char *network_path;    /**< the network file read */
  char *provenance_path; /**< run.json or ensemble.json read, or NULL */
  char *scenario;        /**< scenario path recorded there, or NULL */
  char *scenario_hash;   /**< its hash, or NULL */
  int have_seed;
  uint64_t seed;      /**< seed of the realisation (run.json, or the member's metrics.csv) */
  karst_int_t member; /**< ensemble member index, or -1 */
} karst_export_source_t;

void karst_export_source_init(karst_export_source_t *s);
void karst_export_source_destroy(karst_export_source_t *s);

/**
 * Read what @p path holds: a directory written by `karst generate` (network.vtp and
 * run.json), an ensemble member directory DIR/realisations/NNNN (network.vtp, its
 * metrics.csv and DIR/ensemble.json), or any network or survey file karst_read_network
 * reads (its own coordinate system, no key points). The coordinate system is the "crs" member
 * of run.json / ensemble.json (top level, else in "parameters"; a string or an EPSG number),
 * else the network's own (a survey's CS, a .vtp's "crs" field data), else none.
 * Errors name the file (and line and column for JSON).
 */
karst_error_t karst_export_source_load(karst_ctx_t *ctx, const char *path,
                                       karst_export_source_t *s);

/** karst_export_options_t.timestamp: stamp the GeoPackage with the time of the export. */
#define KARST_EXPORT_TIME_NOW (-1)

/** How to write the GeoPackage. */
typedef struct karst_export_options {
  const char *crs;      /**< overrides the source's coordinate system; NULL: the source's */
  const char *qml_path; /**< where to write the conduits' QGIS style; NULL: none */
  /** The GeoPackage's only clock readings (gpkg_contents.last_change, layer_styles.update_time),
   * in seconds since 1970-01-01 UTC: a fixed time (e.g. SOURCE_DATE_EPOCH) makes the same
   * input give a byte-identical file; KARST_EXPORT_TIME_NOW (the default): the export's time. */
  int64_t timestamp;
} karst_export_options_t;

void karst_export_options_init(karst_export_options_t *opt);

/**
 * Write @p src as the GeoPackage @p path (and the style @p opt->qml_path), both to temporary
 * names first and renamed into place together, so a failure leaves neither: layers
 * "conduits" (3-D LineStrings, one per edge, in edge order), "nodes" and "key_points" (3-D
 * points), metadata naming karst's and the libraries' versions and the provenance, styles in
 * layer_styles. A coordinate system GDAL/PROJ does not know is an error naming it.
 */
karst_error_t karst_export_gpkg(karst_ctx_t *ctx, const char *path,
                                const karst_export_source_t *src,
                                const karst_export_options_t *opt);

/** The layers' styles */
typedef enum {
  KARST_EXPORT_STYLE_CONDUITS = 0,  /**< lines by tunnel_type (one colour when absent) */
  KARST_EXPORT_STYLE_NODES = 1,     /**< points by node kind (one colour when absent) */
  KARST_EXPORT_STYLE_KEY_POINTS = 2 /**< points by node kind */
} karst_export_style_t;

/**
 * The QGIS style (QML) of one layer: a categorised renderer on the palette's array
 * (tunnel_type, kind), one category per palette category with its name and colour, or a single
 * symbol when @p categorised is 0 (the layer has no such field). Caller frees; NULL when out
 * of memory.
 */
char *karst_export_qml(karst_export_style_t style, int categorised);

#ifdef __cplusplus
}
#endif
#endif /* KARST_EXPORT_H */
