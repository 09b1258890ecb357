/**
 * @file network.h
 * @brief A cave network: 3-D nodes, undirected edges, and named per-node and
 *        per-edge attribute arrays (tunnel type, radius, LRUD, flags ...).
 *
 * This one type is what the generator writes, what every survey reader
 * produces, what the metrics consume and what the implicit geometry stage
 * builds conduits from.
 */
#ifndef KARST_NETWORK_H
#define KARST_NETWORK_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Node kinds written as point data (generator output). */
#define KARST_NODE_KIND_LIST(X)                                                \
  X(KARST_NODE_INTERIOR, "interior")                                           \
  X(KARST_NODE_SINK, "sink")                                                   \
  X(KARST_NODE_SPRING, "spring")                                               \
  X(KARST_NODE_WAYPOINT, "waypoint")                                           \
  X(KARST_NODE_JUNCTION, "junction")                                           \
  X(KARST_NODE_AMPLIFICATION, "amplification")

typedef enum {
#define KARST_X_ENUM(code, name) code,
  KARST_NODE_KIND_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_NODE_KIND_COUNT
} karst_node_kind_t;

/** Tunnel types of Paris et al. 2021, §5.3 and Fig. 11. */
#define KARST_TUNNEL_TYPE_LIST(X)                                              \
  X(KARST_TUNNEL_TUBE, "tube")                                                 \
  X(KARST_TUNNEL_KEYHOLE, "keyhole")                                           \
  X(KARST_TUNNEL_CANYON, "canyon")                                             \
  X(KARST_TUNNEL_BED, "bed")                                                   \
  X(KARST_TUNNEL_PASSAGE, "passage")                                           \
  X(KARST_TUNNEL_EPIKARST, "epikarst")                                         \
  X(KARST_TUNNEL_CHAMBER, "chamber")

typedef enum {
#define KARST_X_ENUM(code, name) code,
  KARST_TUNNEL_TYPE_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_TUNNEL_TYPE_COUNT
} karst_tunnel_type_t;

const char *karst_node_kind_name(karst_node_kind_t kind);
const char *karst_tunnel_type_name(karst_tunnel_type_t type);
/** Parse a tunnel type name; returns -1 when unknown. */
int karst_tunnel_type_from_name(const char *name);

typedef enum { KARST_ATTR_NODE = 0, KARST_ATTR_EDGE = 1 } karst_attr_domain_t;

/**
 * A named attribute array. Values are stored as doubles (ncomp per item);
 * @c integer marks arrays whose values are whole numbers (written as Int32
 * by the VTK writer, e.g. tunnel type).
 */
typedef struct karst_attr {
  char name[48];
  int ncomp;
  int integer;
  double *data; /**< ncomp * (n_nodes or n_edges) values */
} karst_attr_t;

/** A named list of strings written as field data (e.g. "spring_names": what code i stands for). */
typedef struct karst_strings {
  char name[48];
  int n;
  char **values;
} karst_strings_t;

typedef struct karst_network {
  karst_int_t n_nodes, n_edges;
  karst_int_t node_cap, edge_cap;
  double *xyz;        /**< 3 * n_nodes coordinates (x east, y north, z up), metres */
  karst_int_t *edges; /**< 2 * n_edges node indices (0-based) */
  int n_node_attrs, n_edge_attrs;
  karst_attr_t *node_attrs;
  karst_attr_t *edge_attrs;
  char *crs;          /**< coordinate system description (e.g. Survex CS string) or NULL */
  char *title;        /**< dataset title or NULL */
  char **node_labels; /**< optional station names (NULL, or n_nodes entries, each may be NULL) */
  int n_strings;
  karst_strings_t *strings; /**< named string lists, written as field data */
} karst_network_t;

/** Initialise an empty network (caller-owned storage). O(1). */
void karst_network_init(karst_network_t *net);
/** Release everything a network holds and leave it empty. */
void karst_network_destroy(karst_network_t *net);

/** Append a node; its index is written to @p index (may be NULL). Attributes get 0. Amortised O(1). */
karst_error_t karst_network_add_node(karst_network_t *net, double x, double y, double z,
                                     karst_int_t *index);
/** Append an undirected edge u–v (no deduplication here). Amortised O(1). */
karst_error_t karst_network_add_edge(karst_network_t *net, karst_int_t u, karst_int_t v,
                                     karst_int_t *index);

/**
 * Add (or find) a named attribute array on nodes or edges, zero-filled.
 * Returns a pointer to its data in @p data (valid until the next node/edge
 * addition, which may reallocate).
 */
karst_error_t karst_network_attr_add(karst_network_t *net, karst_attr_domain_t domain,
                                     const char *name, int ncomp, int integer, double **data);
/** The attribute named @p name, or NULL. */
karst_attr_t *karst_network_attr_find(const karst_network_t *net, karst_attr_domain_t domain,
                                      const char *name);
/** Set the label of node @p i (copied); allocates the label table on first use. */
karst_error_t karst_network_set_label(karst_network_t *net, karst_int_t i, const char *label);
/** Set the coordinate-system description (copied; NULL clears it). */
karst_error_t karst_network_set_crs(karst_network_t *net, const char *crs);

/** Set (or replace) the string list @p name to @p n copies of @p values. */
karst_error_t karst_network_set_strings(karst_network_t *net, const char *name, int n,
                                        const char *const *values);

/** Deep copy of @p src into @p dst (dst must be initialised or destroyed). */
karst_error_t karst_network_copy(karst_network_t *dst, const karst_network_t *src);

/** 3-D length of edge e. */
double karst_network_edge_length(const karst_network_t *net, karst_int_t e);

#ifdef __cplusplus
}
#endif
#endif /* KARST_NETWORK_H */
