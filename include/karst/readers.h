/**
 * @file readers.h
 * @brief Networks from files: karst's own .vtp, Karstnet node/link pairs,
 *        GOCAD PLine, Therion SQL exports, Survex .3d (v8) and .svx (through
 *        Debian's `cavern`). Every reader reports malformed input as
 *        "FILE:LINE: message" (or "FILE: byte OFFSET: message" for binary files).
 */
#ifndef KARST_READERS_H
#define KARST_READERS_H

#include "karst/common.h"
#include "karst/network.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  KARST_FORMAT_AUTO = 0,   /**< from the extension (and magic bytes) */
  KARST_FORMAT_VTP,        /**< .vtp */
  KARST_FORMAT_KARSTNET,   /**< X_nodes.dat + X_links.dat */
  KARST_FORMAT_PLINE,      /**< .pl */
  KARST_FORMAT_THERION_SQL,/**< .sql */
  KARST_FORMAT_SURVEX_3D,  /**< .3d */
  KARST_FORMAT_SURVEX_SVX  /**< .svx */
} karst_format_t;

/** Read any supported file into @p net (initialised by the caller). */
karst_error_t karst_read_network(karst_ctx_t *ctx, const char *path, karst_format_t format,
                                 karst_network_t *net);

/** Karstnet pair: @p path is either X_nodes.dat or X_links.dat; the other is found beside it. Links are 1-based. */
karst_error_t karst_read_karstnet(karst_ctx_t *ctx, const char *path, karst_network_t *net);
/** Write Karstnet X_nodes.dat / X_links.dat for @p net (prefix "DIR/network" gives DIR/network_nodes.dat ...), atomically. */
karst_error_t karst_write_karstnet(karst_ctx_t *ctx, const char *prefix, const karst_network_t *net);
/** GOCAD PLine (.pl): VRTX/PVRTX, ATOM aliases, SEG. */
karst_error_t karst_read_pline(karst_ctx_t *ctx, const char *path, karst_network_t *net);
/**
 * Therion SQL export: STATION and SHOT tables (columns located by the file's
 * "create table" statements); shots flagged 'srf', 'dpl' or 'spl' in
 * SHOT_FLAG and shots to splay stations named "." or "-" are dropped;
 * stations keyed by centimetre coordinates like the .3d reader; station names
 * in net->node_labels. Errors as "FILE:LINE: message".
 */
karst_error_t karst_read_therion_sql(karst_ctx_t *ctx, const char *path, karst_network_t *net);
/**
 * Survex .3d version 8 (Survex's doc/3dformat.htm): legs flagged splay,
 * surface or duplicate are dropped; stations keyed by centimetre coordinates
 * (which merges equated stations; a leg whose ends merge is dropped); nodes on
 * no kept leg are dropped; station names in net->node_labels; LRUD as node
 * attribute "lrud" (L, R, U, D in metres, NAN when absent); the CS string in
 * net->crs, the title in net->title. Errors as "FILE: byte OFFSET: message".
 */
karst_error_t karst_read_survex3d(karst_ctx_t *ctx, const char *path, karst_network_t *net);
/**
 * Survex .svx: run `cavern` (Debian package survex) to a temporary .3d and
 * read it as above; KARST_ENOTFOUND with what to install when cavern is
 * missing, KARST_EEXTERNAL quoting cavern's output when it fails.
 */
karst_error_t karst_read_svx(karst_ctx_t *ctx, const char *path, karst_network_t *net);

#ifdef __cplusplus
}
#endif
#endif
