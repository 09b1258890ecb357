/**
 * @file scenario.h
 * @brief Everything the generation pipeline of Paris et al. 2021 (§3–5)
 *        needs, read from a YAML scenario file. Every key, unit and default
 *        is documented in docs/scenario.md. Lengths are metres, angles degrees.
 */
#ifndef KARST_SCENARIO_H
#define KARST_SCENARIO_H

#include "karst/common.h"
#include "karst/network.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Deepest nesting of the permeability tree accepted from a file (guards against cycles made with YAML aliases). */
#define KARST_SCENARIO_PERM_MAX_DEPTH 64
/** Most permeability-tree nodes accepted from a file (guards against alias blow-up). */
#define KARST_SCENARIO_PERM_MAX_NODES 100000
/** Deepest nesting of [ ] and { } accepted in a scenario file (libyaml slows down quadratically). */
#define KARST_SCENARIO_MAX_NESTING 256
/** Largest scenario file read, in bytes (64 MiB): a scenario is a few kilobytes of YAML. */
#define KARST_SCENARIO_MAX_BYTES (64LL << 20)
/** Largest heightfield file read, in bytes (2 GiB). */
#define KARST_HEIGHTFIELD_MAX_BYTES (2LL << 30)
/** Most cells (ncols x nrows) of a heightfield (1e8 cells, 800 MB of elevations). */
#define KARST_HEIGHTFIELD_MAX_CELLS 100000000LL
/**
 * A heightfield covers the domain when its cells (edges, not centres) span the
 * domain's x-y extent; it may fall short by this fraction of a cell, so that
 * rounding in corner + n * cellsize does not reject an exact fit.
 */
#define KARST_SCENARIO_GRID_COVER_SLACK 1e-6

/**
 * Default of skeleton.reuse (docs/generation.md, "Path sharing"): edges already in the network
 * cost this fraction of their cost while later skeleton paths are laid (Galin et al. 2011).
 */
#define KARST_SCENARIO_DEFAULT_REUSE 0.5

typedef enum { KARST_KEYPOINT_SINK = 0, KARST_KEYPOINT_SPRING = 1, KARST_KEYPOINT_WAYPOINT = 2 } karst_keypoint_type_t;

typedef struct karst_keypoint {
  char name[64];               /**< unique; generated ("sink1", ...) when the file gives none */
  karst_keypoint_type_t type;
  double p[3];
  int line;                    /**< line of the entry in the scenario file (for messages), 0 if built in code */
  int column;                  /**< column of the entry (1-based), 0 if built in code */
} karst_keypoint_t;

/** Terrain: flat, or an ESRI ASCII grid heightfield (bilinear interpolation). */
typedef struct karst_terrain {
  int is_grid;                 /**< 0: flat at @c elevation; 1: heightfield */
  double elevation;            /**< flat elevation (m) */
  char *path;                  /**< heightfield file as resolved (relative to the scenario), or NULL */
  karst_int_t ncols, nrows;
  double xll, yll, cellsize;   /**< lower-left corner of the grid (cell centres, ESRI "xllcenter" convention after reading) */
  double *z;                   /**< nrows*ncols elevations, row 0 = southernmost row */
  double zmin, zmax;           /**< range of the heightfield */
  double lipschitz;            /**< max slope |grad h| of the bilinear surface (for implicit terrain, Appendix A) */
} karst_terrain_t;

/** Inception horizon (§4.2): plane z = elevation at @c origin, tilted by dip towards dip_direction. */
typedef struct karst_horizon {
  double elevation;            /**< elevation at origin (m) */
  double dip;                  /**< degrees, [0, 90) */
  double dip_direction;        /**< degrees clockwise from north, [0, 360) */
  double origin[2];            /**< (x, y) where the elevation is given; default: domain centre */
  double radius;               /**< influence radius r of the smooth step (m), > 0 */
  int line;
  int column;                  /**< position of the entry in the file (1-based), 0 if built in code */
} karst_horizon_t;

/** Fracture family (§4.2): plane orientation and weight w_k. */
typedef struct karst_fracture {
  double dip_direction;        /**< degrees clockwise from north, [0, 360) */
  double dip;                  /**< degrees, [0, 90] */
  double weight;               /**< w_k >= 0 */
  int line;
  int column;                  /**< position of the entry in the file (1-based), 0 if built in code */
} karst_fracture_t;

/** Permeability construction tree (§4.2): leaves are primitives, inner nodes combine children. */
typedef enum {
  KARST_PERM_SPHERE = 0,       /**< resistance inside a sphere, smooth falloff to the outside value */
  KARST_PERM_STRATUM = 1,      /**< resistance between two elevations */
  KARST_PERM_UNION = 2,        /**< min of children (most permeable wins) */
  KARST_PERM_INTERSECTION = 3, /**< max of children */
  KARST_PERM_BLEND = 4         /**< weighted mean of children (weights = child weight) */
} karst_perm_kind_t;

typedef struct karst_perm_node {
  karst_perm_kind_t kind;
  double resistance;           /**< leaf value in [0, 1] */
  double center[3], radius;    /**< sphere */
  double falloff;              /**< sphere: width (m) of the smooth transition outside the radius (>= 0) */
  double bottom, top;          /**< stratum elevations (m), bottom < top */
  double weight;               /**< weight of this node inside a blend (> 0, default 1) */
  int n_children;
  struct karst_perm_node *children;
  int line;
  int column;                  /**< position of the node in the file (1-based), 0 if built in code */
} karst_perm_node_t;

typedef struct karst_permeability {
  double background;           /**< resistance where no primitive applies, [0, 1], default 1 */
  karst_perm_node_t *root;     /**< NULL: uniform background */
} karst_permeability_t;

/** Prescribed path (§4.2): a pair of key points whose connecting edges get a low cost. */
typedef struct karst_prescribed_path {
  int a, b;                    /**< indices into key_points */
  int line;
  int column;                  /**< position of the pair in the file (1-based), 0 if built in code */
} karst_prescribed_path_t;

/** A position in the scenario file (1-based line and column; 0 when not read from a file). */
typedef struct karst_srcpos {
  int line, column;
} karst_srcpos_t;

/**
 * How the fracture families combine into cF(d) (cost.fracture_combine, docs/scenario.md):
 * SUM is the paper's Σ_k w_k (n_k·d)² (§4.2); MIN makes a direction cheap when it follows any
 * one family, min_k [W − w_k (1 − (n_k·d)²)] with W = max_k w_k (see src/cost/cost.c).
 */
typedef enum { KARST_FRACTURE_SUM = 0, KARST_FRACTURE_MIN = 1 } karst_fracture_combine_t;

/**
 * The exact k-nearest-neighbour search behind the graph (sampling.knn, docs/scenario.md): the
 * uniform-grid search of src/graph/knn.c (default, ~14x faster than FLANN on 1.5 M samples with
 * k = 100), or FLANN's exact single k-d tree (FLANN_INDEX_KDTREE_SINGLE). Both give the same
 * neighbour sets except for exact distance ties at the k-th neighbour.
 */
typedef enum { KARST_KNN_GRID = 0, KARST_KNN_FLANN = 1 } karst_knn_method_t;

/** Cost weights of c(p, d) = w0 + wL cL(p) + wF cF(d) + wπ cπ(p) (§4.2). */
typedef struct karst_cost_weights {
  double w0;                   /**< base cost per metre, > 0 (keeps A* admissible and paths finite) */
  double horizon;              /**< wL >= 0 */
  double fracture;             /**< wF >= 0 */
  double permeability;         /**< wπ >= 0 */
  double prescribed;           /**< cost per metre multiplier on prescribed paths, in (0, 1] */
  int fracture_combine;        /**< karst_fracture_combine_t, default KARST_FRACTURE_SUM */
} karst_cost_weights_t;

typedef struct karst_sampling {
  double fill_radius;          /**< Poisson radius of the fill samples (m), > 0 */
  double feature_radius;       /**< Poisson radius on horizons, water table, permeable zones (m), > 0 */
  double permeable_threshold;  /**< resistance below which space is sampled at feature radius, [0,1] */
  double feature_band;         /**< half-thickness of the sampled layer around horizons/water table (m) */
  int k;                       /**< neighbours in the kNN graph, >= 1, default 40 */
  int knn;                     /**< karst_knn_method_t: grid (default) or flann */
  karst_int_t max_samples;     /**< safety cap, default 5e6 */
} karst_sampling_t;

typedef struct karst_amplification {
  int steps;                   /**< >= 0 */
  int points;                  /**< new points per step, >= 0 */
  double dead_end_fraction;    /**< [0, 1] */
} karst_amplification_t;

/** Radius range per tunnel type (uniform draw in [min, max]). */
typedef struct karst_radius_range {
  double min, max;
} karst_radius_range_t;

typedef struct karst_classification {
  double vertical_angle;       /**< segments steeper than this (degrees) are vertical, default 60 */
  double water_table_band;     /**< |z - water table| below this (m) counts as "at the water table", default 5 */
  double epikarst_depth;       /**< depth below terrain (m) of the epikarst zone, default 10 */
  double chamber_resistance;   /**< resistance below this makes a chamber, default 0.05 */
  double radius_correlation;   /**< correlation length (m) of the radius field along and across
                                    conduits, default 100 (Frantz et al. 2021: 50-200 m); 0 draws
                                    every segment independently */
  karst_radius_range_t radius[KARST_TUNNEL_TYPE_COUNT]; /**< indexed by karst_tunnel_type_t */
} karst_classification_t;

typedef struct karst_scenario {
  char *path;                  /**< file the scenario was read from (NULL if built in code) */
  char *name;
  double domain_min[3], domain_max[3];
  karst_terrain_t terrain;
  double water_table;          /**< elevation (m); a file without water_table gets the domain bottom */
  int n_horizons;
  karst_horizon_t *horizons;
  int n_fractures;
  karst_fracture_t *fractures;
  karst_permeability_t permeability;
  int n_key_points;
  karst_keypoint_t *key_points;
  int n_prescribed;
  karst_prescribed_path_t *prescribed;
  karst_cost_weights_t cost;
  karst_sampling_t sampling;
  double gamma;                /**< γ-skeleton parameter, > 0 (§5.1) */
  double reuse;                /**< skeleton.reuse: cost factor of graph edges already in the
                                    network while later paths are laid, (0, 1], default
                                    KARST_SCENARIO_DEFAULT_REUSE (1 = plain union of paths) */
  karst_amplification_t amplification;
  double tortuosity;           /**< θ in [0, 1] (§5.2) */
  karst_classification_t classification;
  uint64_t seed;
  int realisations;            /**< >= 1 */
  /* Where blocks named by cross-field messages were given (0 when defaulted or built in code). */
  karst_srcpos_t pos_domain;      /**< the domain map */
  karst_srcpos_t pos_terrain;     /**< terrain.elevation or terrain.heightfield value */
  karst_srcpos_t pos_water_table; /**< water_table.elevation value */
  karst_srcpos_t pos_key_points;  /**< the key_points list */
  karst_srcpos_t pos_sampling;    /**< the sampling map */
} karst_scenario_t;

/** Fill @p sc with every documented default (docs/scenario.md): no key points, flat terrain at 100 m. */
void karst_scenario_init(karst_scenario_t *sc);
/** Release what a scenario holds. */
void karst_scenario_destroy(karst_scenario_t *sc);

/**
 * Read and validate a YAML scenario. On failure returns an error code and
 * ctx->errmsg holds "FILE:LINE:COLUMN: message" naming the field and value.
 */
karst_error_t karst_scenario_load(karst_ctx_t *ctx, const char *path, karst_scenario_t *sc);

/** Longest key path of an override ("fractures[0].weight"), in bytes without the NUL. */
#define KARST_SCENARIO_OVERRIDE_KEY_MAX 255

/**
 * One value given in place of the file's, by the key's path in the YAML document
 * (docs/scenario.md, "Overriding values"): map keys joined by dots, list items and vector
 * components by [index], e.g. "skeleton.gamma", "fractures[0].weight", "domain.max[2]".
 */
typedef struct karst_scenario_override {
  const char *key;    /**< the key's path */
  const char *value;  /**< YAML text of the value, e.g. "2.5" (read as a plain scalar) */
  const char *origin; /**< where it came from, for messages (e.g. "--vary skeleton.gamma=0.5:3");
                           NULL: "override KEY=VALUE" */
  int numeric;        /**< 1: the key must hold a number or an integer (refused otherwise) */
} karst_scenario_override_t;

/** What the parser read an override as (karst_scenario_load_with_overrides). */
typedef enum {
  KARST_OVERRIDE_UNREAD = 0,  /**< not read as a scalar value */
  KARST_OVERRIDE_NUMBER = 1,  /**< a real number */
  KARST_OVERRIDE_INTEGER = 2, /**< an integer key (sampling.k, amplification.steps ...) */
  KARST_OVERRIDE_TEXT = 3     /**< a string, name or enumeration */
} karst_override_type_t;

/**
 * karst_scenario_load with @p n values overridden: each is put into the YAML document
 * before the schema walk, so it is validated exactly like a value of the file (type, range,
 * cross-field rules, "did you mean" for unknown keys). @p types (NULL or @p n entries)
 * receives what each override was read as.
 */
karst_error_t karst_scenario_load_with_overrides(karst_ctx_t *ctx, const char *path,
                                                 const karst_scenario_override_t *ov, int n,
                                                 karst_override_type_t *types,
                                                 karst_scenario_t *sc);

/**
 * Write the scenario @p path with the @p n overrides applied to @p out (atomically), as a
 * file that loads on its own: the file's text with the overridden values replaced (its
 * comments kept) when every override replaces a value the file gives, else the whole
 * document re-emitted by libyaml; a relative terrain.heightfield is rewritten to resolve from
 * @p out's directory. @p header (NULL or "# ..." lines) is written first. The result is
 * loaded back before it replaces @p out.
 */
karst_error_t karst_scenario_write_with_overrides(karst_ctx_t *ctx, const char *path,
                                                  const karst_scenario_override_t *ov, int n,
                                                  const char *header, const char *out);

/**
 * The text of the value scenario @p path gives at key path @p key (as for overrides), into
 * @p out; KARST_ENOTFOUND when the file leaves the key to its default.
 */
karst_error_t karst_scenario_value_text(karst_ctx_t *ctx, const char *path, const char *key,
                                        char *out, size_t size);

/** Check the cross-field rules (key points inside the domain and below the terrain, a spring present ...). */
karst_error_t karst_scenario_check(karst_ctx_t *ctx, const karst_scenario_t *sc);

/** Terrain elevation at (x, y) (bilinear on the grid, clamped at its border). */
double karst_terrain_height(const karst_terrain_t *t, double x, double y);

/** Read an ESRI ASCII grid (.asc) into @p t; errors name the file, line and field. */
karst_error_t karst_terrain_load_grid(karst_ctx_t *ctx, const char *path, karst_terrain_t *t);

/** Elevation of horizon @p h at (x, y). */
double karst_horizon_elevation(const karst_horizon_t *h, double x, double y);

/** Unit normal (x east, y north, z up) of a plane given by dip direction and dip (degrees). */
void karst_plane_normal(double dip_direction, double dip, double n[3]);

/** Resistance π(p) in [0, 1] from the permeability tree (§4.2). */
double karst_permeability_eval(const karst_permeability_t *perm, const double p[3]);

/** Stable hash (FNV-1a 64) of a file's bytes, as 16 hex digits in @p out (17 bytes). */
karst_error_t karst_file_hash(karst_ctx_t *ctx, const char *path, char out[17]);

#ifdef __cplusplus
}
#endif
#endif /* KARST_SCENARIO_H */
