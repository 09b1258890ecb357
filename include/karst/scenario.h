/**
 * @file scenario.h
 * @brief Everything the generation pipeline of Paris et al. 2021 (§3–5)
 *        needs, read from a YAML scenario file. Every key, unit and default
 *        is documented in docs/scenario.md. Lengths are metres, angles degrees.
 */
#ifndef KARST_SCENARIO_H
#define KARST_SCENARIO_H

#include <math.h>

#include "karst/common.h"
#include "karst/network.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Deepest nesting of the permeability tree accepted from a file (guards against cycles made with
 * YAML aliases). */
#define KARST_SCENARIO_PERM_MAX_DEPTH 64
/** Most permeability-tree nodes accepted from a file (guards against alias blow-up). */
#define KARST_SCENARIO_PERM_MAX_NODES 100000
/** Deepest nesting of [ ] and { } accepted in a scenario file (libyaml slows down quadratically).
 */
#define KARST_SCENARIO_MAX_NESTING 256
/** Largest scenario file read, in bytes (64 MiB): a scenario is a few kilobytes of YAML. */
#define KARST_SCENARIO_MAX_BYTES (64LL << 20)
/** Largest heightfield file read, in bytes (2 GiB). */
#define KARST_HEIGHTFIELD_MAX_BYTES (2LL << 30)
/** Most cells (ncols x nrows) of a heightfield (1e8 cells, 800 MB of elevations). */
#define KARST_HEIGHTFIELD_MAX_CELLS 100000000LL
/** Largest point cloud file read (sampling.points), in bytes (1 GiB). */
#define KARST_POINTS_MAX_BYTES (1LL << 30)
/** Most points of a point cloud file (sampling.points): 20 M, 480 MB of coordinates. */
#define KARST_POINTS_MAX_POINTS 20000000
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

typedef enum {
  KARST_KEYPOINT_SINK = 0,
  KARST_KEYPOINT_SPRING = 1,
  KARST_KEYPOINT_WAYPOINT = 2
} karst_keypoint_type_t;

/** Names a scenario gives to things (key points, strata, faults, exclusions) fit in this many
 * bytes. */
#define KARST_SCENARIO_NAME_MAX 64
/** Most springs a sink may list in drains_to (and most springs of a scenario,
 * KARST_SCENARIO_MAX_SPRINGS). */
#define KARST_SCENARIO_MAX_SPRINGS 64

struct karst_surface; /* include/karst/surface.h: a grid or triangulated surface read from a file */

/**
 * A geological surface z = f(x, y) as the scenario gives it (docs/scenario.md, "Surfaces"): a plane
 * through (origin, elevation) that descends by tan(dip) per metre towards dip_direction, or a file:
 * an ESRI ASCII grid (.asc) or a GOCAD TSurf (.ts), resolved relative to the scenario.
 */
typedef struct karst_surface_def {
  int given;            /**< 0 when the file gave none (the default applies) */
  double elevation;     /**< plane: elevation at origin (m) */
  double dip;           /**< plane: degrees, [0, 90) */
  double dip_direction; /**< plane: degrees clockwise from north, [0, 360) */
  double origin[2];     /**< plane: (x, y) where the elevation is given; default: domain centre */
  char *path;           /**< file surface as resolved, or NULL for a plane */
  struct karst_surface *surface; /**< the file's surface once read, or NULL for a plane */
  int line, column; /**< position of the entry in the file (1-based), 0 if built in code */
} karst_surface_def_t;

typedef struct karst_keypoint {
  char name[KARST_SCENARIO_NAME_MAX]; /**< unique; generated ("sink1", ...) when the file gives none
                                       */
  karst_keypoint_type_t type;
  double p[3];
  int line;   /**< line of the entry in the scenario file (for messages), 0 if built in code */
  int column; /**< column of the entry (1-based), 0 if built in code */
  /** Springs: this spring's own water table (its base level). When not given, the scenario's
   *  water_table if the file has one, else the horizontal plane through the spring. */
  karst_surface_def_t water_table;
  /** Sinks: the springs this sink drains to (key-point indices, all required), from drains_to. */
  int n_drains_to;
  int drains_to[KARST_SCENARIO_MAX_SPRINGS];
  int drains_line, drains_column; /**< position of drains_to in the file, 0 when not given */
  /** The generation (speleogenetic phase, 1-based) the key point belongs to; 0: every generation
   *  (a top-level key point, or a scenario without generations). */
  int generation;
  /** latitude, longitude (degrees, WGS 84) and elevation (m, the scenario's vertical datum) when
   *  the file gave those instead of position; NAN otherwise. Converted into p at load. */
  double geographic[3];
  char *station; /**< the survey station the key point sits on (conditioning), or NULL */
  karst_int_t station_index; /**< its index among the conditioning stations, -1 when none */
} karst_keypoint_t;

/** Terrain: flat, or an ESRI ASCII grid heightfield (bilinear interpolation). */
typedef struct karst_terrain {
  int is_grid;      /**< 0: flat at @c elevation; 1: heightfield */
  double elevation; /**< flat elevation (m) */
  char *path;       /**< heightfield file as resolved (relative to the scenario), or NULL */
  karst_int_t ncols, nrows;
  double xll, yll, cellsize;     /**< lower-left corner of the grid (cell centres, ESRI "xllcenter"
                                    convention after reading) */
  double *z;                     /**< nrows*ncols elevations, row 0 = southernmost row */
  double zmin, zmax;             /**< range of the heightfield */
  struct karst_surface *surface; /**< a terrain read from a surface file (terrain.surface: a TSurf
                                      or a grid), or NULL; is_grid is then 0 */
  double lipschitz; /**< max slope |grad h| of the bilinear surface (for implicit terrain, Appendix
                       A) */
} karst_terrain_t;

/**
 * Inception horizon (§4.2): the plane z = elevation at @c origin, tilted by dip towards
 * dip_direction, or, with @c path, any single-valued surface z = f(x, y) read from a grid or
 * TSurf file (a folded horizon).
 */
typedef struct karst_horizon {
  char name[KARST_SCENARIO_NAME_MAX]; /**< optional, for messages and geology.vtp */
  char *path; /**< surface file (grid or TSurf) as resolved, or NULL for a plane */
  struct karst_surface *surface; /**< the file's surface once read, or NULL */
  double elevation;              /**< elevation at origin (m) */
  double dip;                    /**< degrees, [0, 90) */
  double dip_direction;          /**< degrees clockwise from north, [0, 360) */
  double origin[2];              /**< (x, y) where the elevation is given; default: domain centre */
  double radius;                 /**< influence radius r of the smooth step (m), > 0 */
  int line;
  int column; /**< position of the entry in the file (1-based), 0 if built in code */
} karst_horizon_t;

/**
 * Fracture family (§4.2): mean plane orientation and weight w_k, optionally with a Fisher
 * dispersion κ of the poles about the mean pole, and optionally realised as a discrete fracture
 * network (DFN) of discs (docs/scenario.md, "Fractures").
 */
typedef struct karst_fracture {
  double dip_direction; /**< degrees clockwise from north, [0, 360) */
  double dip;           /**< degrees, [0, 90] */
  double weight;        /**< w_k >= 0 */
  double kappa;         /**< Fisher concentration κ > 0 of the poles; 0 (default): no dispersion */
  int dfn;              /**< 1: realise the family as discs (the fields below) */
  double p32;           /**< DFN: fracture area per unit volume (m²/m³), > 0 */
  double size_exponent; /**< DFN: radii follow a power law p(r) ∝ r^-a on [r_min, r_max], a > 1 */
  double r_min, r_max;  /**< DFN: disc radius range (m), 0 < r_min <= r_max */
  double factor;        /**< DFN: cost factor along a disc, (0, 1] (1: the disc changes nothing) */
  double influence; /**< DFN: an edge within this distance of a disc's plane (m) lies in it; default
                         sampling.feature_radius */
  int line;
  int column; /**< position of the entry in the file (1-based), 0 if built in code */
} karst_fracture_t;

/** Stratum (docs/scenario.md, "Strata"): the rock between two surfaces. */
typedef struct karst_stratum {
  char name[KARST_SCENARIO_NAME_MAX]; /**< unique among strata */
  karst_surface_def_t top;            /**< upper surface; not given: the terrain */
  karst_surface_def_t bottom;         /**< lower surface; not given: the domain bottom */
  int soluble; /**< 0: insoluble (no sample, no edge crosses it), default 1 */
  int line, column;
} karst_stratum_t;

/** Shape of an exclusion zone (docs/scenario.md, "Exclusions"). */
typedef enum {
  KARST_EXCLUSION_BOX = 0,
  KARST_EXCLUSION_SPHERE = 1,
  KARST_EXCLUSION_PRISM = 2
} karst_exclusion_kind_t;

/** Most vertices of an exclusion prism's polygon. */
#define KARST_SCENARIO_PRISM_MAX_VERTICES 4096

/** Exclusion zone: holds no sample and is crossed by no edge. */
typedef struct karst_exclusion {
  char name[KARST_SCENARIO_NAME_MAX]; /**< optional */
  int kind;                           /**< karst_exclusion_kind_t */
  double min[3], max[3];              /**< box corners (m) */
  double center[3], radius;           /**< sphere */
  int n_vertices;                     /**< prism: vertices of its x-y polygon (>= 3) */
  double *polygon;                    /**< prism: 2 * n_vertices coordinates, in order */
  double bottom, top;                 /**< prism: z range (m), bottom < top */
  int line, column;
} karst_exclusion_t;

/** Fault (docs/scenario.md, "Faults"): a plane, or a disc of finite radius, with a damage zone. */
typedef struct karst_fault {
  char name[KARST_SCENARIO_NAME_MAX]; /**< optional */
  double center[3];                   /**< a point of the fault plane (the disc centre) */
  double dip_direction, dip;          /**< orientation (degrees) */
  double radius;                      /**< disc radius (m); INFINITY: an unbounded plane */
  double damage_zone;                 /**< width (m) of the damage zone centred on the plane, > 0 */
  int barrier;          /**< 0: a conduit (cheaper along it), 1: a barrier (costly to cross) */
  double factor;        /**< conduit: cost factor along the fault inside the damage zone, (0, 1] */
  double crossing_cost; /**< barrier: cost added to an edge crossing the plane, >= 0 */
  int line, column;
} karst_fault_t;

/** Sink–spring connectivity (docs/scenario.md, "Connectivity"), as KarstNSim's matrix. */
typedef struct karst_connectivity {
  int given;              /**< 0: every sink may drain to every spring (default) */
  int n_sinks, n_springs; /**< rows and columns */
  int *sinks, *springs;   /**< key-point index of each row / column */
  unsigned char *matrix;  /**< n_sinks x n_springs: 0 never, 1 allowed, 2 required */
  int line, column;
} karst_connectivity_t;

/**
 * Two-stage routing (docs/generation.md, "Routing"): a vadose stage above a spring's water table,
 * where travel costs vadose_factor times more and rising costs rise_cost per metre, then a
 * phreatic stage below it, where the cost per metre grows by 1/phreatic_depth per metre of depth
 * below the epiphreatic band, and from which a path may not rise back into the vadose zone.
 */
typedef struct karst_routing {
  double vadose_factor;    /**< >= 1, default 2 */
  double rise_cost;        /**< >= 0, cost per metre of rise in the vadose zone, default 4 */
  double phreatic_depth;   /**< > 0 m, default 50 */
  double water_table_band; /**< >= 0 m: half-thickness of the epiphreatic band, default 5 */
} karst_routing_t;

/** Permeability construction tree (§4.2): leaves are primitives, inner nodes combine children. */
typedef enum {
  KARST_PERM_SPHERE = 0,  /**< resistance inside a sphere, smooth falloff to the outside value */
  KARST_PERM_STRATUM = 1, /**< resistance between two elevations */
  KARST_PERM_UNION = 2,   /**< min of children (most permeable wins) */
  KARST_PERM_INTERSECTION = 3, /**< max of children */
  KARST_PERM_BLEND = 4         /**< weighted mean of children (weights = child weight) */
} karst_perm_kind_t;

typedef struct karst_perm_node {
  karst_perm_kind_t kind;
  double resistance;        /**< leaf value in [0, 1] */
  double center[3], radius; /**< sphere */
  double falloff;     /**< sphere: width (m) of the smooth transition outside the radius (>= 0) */
  double bottom, top; /**< stratum elevations (m), bottom < top */
  double weight;      /**< weight of this node inside a blend (> 0, default 1) */
  int n_children;
  struct karst_perm_node *children;
  int line;
  int column; /**< position of the node in the file (1-based), 0 if built in code */
} karst_perm_node_t;

typedef struct karst_permeability {
  double background;       /**< resistance where no primitive applies, [0, 1], default 1 */
  karst_perm_node_t *root; /**< NULL: uniform background */
} karst_permeability_t;

/** Prescribed path (§4.2): a pair of key points whose connecting edges get a low cost. */
typedef struct karst_prescribed_path {
  int a, b; /**< indices into key_points */
  int line;
  int column; /**< position of the pair in the file (1-based), 0 if built in code */
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
  double w0;            /**< base cost per metre, > 0 (keeps A* admissible and paths finite) */
  double horizon;       /**< wL >= 0 */
  double fracture;      /**< wF >= 0 */
  double permeability;  /**< wπ >= 0 */
  double prescribed;    /**< cost per metre multiplier on prescribed paths, in (0, 1] */
  int fracture_combine; /**< karst_fracture_combine_t, default KARST_FRACTURE_SUM */
} karst_cost_weights_t;

/**
 * Which features sampling.refine samples at feature_radius (docs/scenario.md): bits of
 * karst_sampling_t.refine. The key points and prescribed paths are always sampled.
 */
typedef enum {
  KARST_REFINE_HORIZONS = 1,     /**< "horizons": a layer ±feature_band around each horizon */
  KARST_REFINE_WATER_TABLE = 2,  /**< "water_table": a layer around each spring's water table */
  KARST_REFINE_PERMEABILITY = 4, /**< "permeability": where π < permeable_threshold */
  KARST_REFINE_ALL = 7           /**< the default */
} karst_refine_t;

/**
 * Write the names of the bits of @p refine (karst_refine_t) as the scenario spells them, in
 * karst_refine_t's order and separated by @p sep, into @p buf (always terminated); e.g.
 * "horizons, permeability"; "" for none. Returns @p buf. O(1).
 */
char *karst_refine_names(unsigned refine, const char *sep, char *buf, size_t size);

typedef struct karst_sampling {
  double fill_radius;    /**< Poisson radius of the fill samples (m), > 0 */
  double feature_radius; /**< Poisson radius on horizons, water table, permeable zones (m), > 0 */
  double
      permeable_threshold; /**< resistance below which space is sampled at feature radius, [0,1] */
  double feature_band; /**< half-thickness of the sampled layer around horizons/water table (m) */
  int k;               /**< neighbours in the kNN graph, >= 1, default 40 */
  int knn;             /**< karst_knn_method_t: grid (default) or flann */
  unsigned refine;     /**< karst_refine_t bits: the features sampled at feature_radius */
  karst_int_t max_samples; /**< safety cap, default 5e6 */
  char *points;            /**< sampling.points: the point cloud file as resolved, or NULL */
  double *points_xyz;      /**< its points (3 coordinates each), read with the scenario */
  karst_int_t n_points;    /**< how many */
} karst_sampling_t;

/** Where a hierarchical amplification step anchors its points (amplification.anchor). */
typedef enum {
  KARST_ANCHOR_PREVIOUS = 0, /**< along the paths the previous step added (tributaries of
                                  tributaries: a Horton-Strahler hierarchy, branchwork caves) */
  KARST_ANCHOR_NETWORK = 1   /**< along the whole network grown so far (passages opened along
                                  every existing passage: mazes, looping caves) */
} karst_amplification_anchor_t;

typedef struct karst_amplification {
  int steps;                /**< >= 0 */
  int points;               /**< new points of the first step, >= 0 */
  double dead_end_fraction; /**< [0, 1] */
  double reach;             /**< m, >= 0: 0 draws each step's points in the network's bounding box
                                 (Paris et al. 2021, §5.2); > 0 draws the first step's within this
                                 distance of the network, and each later step's within reach_ratio of
                                 the previous step's (a Horton hierarchy of tributaries) */
  double reach_ratio;       /**< (0, 1], default 0.5: reach of step s+1 / reach of step s */
  double points_ratio;      /**< > 0, default 1: points of step s+1 / points of step s */
  int anchor; /**< karst_amplification_anchor_t, default KARST_ANCHOR_PREVIOUS (reach > 0) */
} karst_amplification_t;

/** Largest number of amplification points over all steps (karst_scenario_check refuses more). */
#define KARST_SCENARIO_MAX_AMPLIFICATION_POINTS 1000000

/**
 * Points of all amplification steps together, and in *@p largest (may be NULL) those of the
 * largest step, by the rule of karst_amplification_step_points; stops at the first step with no
 * point or once the total exceeds @p cap. O(steps), where calling karst_amplification_step_points
 * for every step would be O(steps²).
 */
static inline double karst_amplification_points_total(const karst_amplification_t *am, double cap,
                                                      double *largest) {
  double n = am->points, total = 0, big = 0;
  for (int s = 1; s <= am->steps && n >= 0.5 && total <= cap; s++) {
    double k = floor(n + 0.5);
    total += k;
    if (k > big) big = k;
    n *= am->points_ratio;
  }
  if (largest) *largest = big;
  return total;
}

/** Points of amplification step @p step (1-based): round(points × points_ratio^(step − 1)).
 *  O(step). */
static inline double karst_amplification_step_points(const karst_amplification_t *am, int step) {
  double n = am->points;
  for (int s = 1; s < step && n >= 0.5; s++)
    n *= am->points_ratio;
  return floor(n + 0.5);
}

/** Radius range per tunnel type (uniform draw in [min, max]). */
typedef struct karst_radius_range {
  double min, max;
} karst_radius_range_t;

typedef struct karst_classification {
  double vertical_angle;     /**< segments steeper than this (degrees) are vertical, default 60 */
  double epikarst_depth;     /**< depth below terrain (m) of the epikarst zone, default 10 */
  double chamber_resistance; /**< resistance below this makes a chamber, default 0.05 */
  double radius_correlation; /**< correlation length (m) of the radius field along and across
                                  conduits, default 100 (Frantz et al. 2021: 50-200 m); 0 draws
                                  every segment independently */
  karst_radius_range_t radius[KARST_TUNNEL_TYPE_COUNT]; /**< indexed by karst_tunnel_type_t */
} karst_classification_t;

struct karst_blocks_section; /* include/karst/blocks.h */

/**
 * Wall details of one tunnel type (geometry.details.<type>, docs/geometry.md):
 * the anisotropic surface Gabor noise of Zanni et al. 2012 (§2-4).
 */
typedef struct karst_wall_details {
  double amplitude;      /**< largest displacement of the wall (m), >= 0; 0: smooth walls */
  double wavelength;     /**< wavelength 1/F of the Gabor kernels (m), > 0 */
  double bandwidth;      /**< a (1/m), > 0: the kernels' window radius is 1/a */
  double orientation;    /**< ω (degrees, [-90, 90]): from the skeleton direction t towards b */
  double anisotropy;     /**< [0, 1]: 1 every kernel along ω, 0 random directions (isotropic) */
  double tilt;           /**< α (degrees, [0, 60]): projection direction tilted off the normal */
  double tilt_direction; /**< θ (degrees): direction of the tilt in the frame, from t towards b */
} karst_wall_details_t;

/** Speleothems of one tunnel type (geometry.speleothems.<type>, docs/geometry.md). */
typedef struct karst_speleothem_rule {
  double density;     /**< stalactites per m² of conduit floor, >= 0; 0: none */
  double clearance;   /**< free height kept under a stalactite and over a stalagmite (m), >= 0 */
  double pair_height; /**< where floor to ceiling is lower than this (m), a stalagmite is paired */
  double min_length;  /**< shortest stalactite (m), > 0 */
  double max_length;  /**< longest stalactite (m), >= min_length */
} karst_speleothem_rule_t;

/** Conduit geometry of `karst mesh` (the scenario's geometry section, docs/geometry.md). */
typedef struct karst_geometry {
  double blend;              /**< smooth-union width at junctions (m); < 0 (default): blend_factor
                                  times the smallest radius there; 0: hard union */
  double blend_factor;       /**< > 0, default 1 */
  double continuation_angle; /**< degrees: at a junction two edges turning by at most this continue
                                  each other (their sections interpolate across it), default 45 */
  karst_wall_details_t details[KARST_TUNNEL_TYPE_COUNT];
  karst_speleothem_rule_t speleothems[KARST_TUNNEL_TYPE_COUNT];
  double speleothem_relief; /**< amplitude of the dripstone relief of speleothems (m), >= 0 */
  double fracture_relief;   /**< depth of wall grooves along the fracture families (m); 0: none */
  double fracture_spacing;  /**< mean distance between grooves of a family (m), > 0 */
  double fracture_width;    /**< half-width of a groove (m), > 0 */
} karst_geometry_t;

/** Fill @p g with the documented defaults (docs/geometry.md). */
void karst_geometry_init(karst_geometry_t *g);
/**
 * A speleogenetic phase (docs/generation.md, "Generations"): its own base level (water_table: the
 * default water table of its springs), key points (karst_keypoint_t.generation), routing and
 * skeleton parameters, and the cost factor at which it follows the conduits of the phases before
 * it (KarstNSim's polyphasic cohesion factor, Gouy et al. 2024).
 */
typedef struct karst_generation {
  char name[KARST_SCENARIO_NAME_MAX];  /**< "generation1", ... when the file gives none */
  karst_surface_def_t water_table;     /**< default water table of its springs; not given: the
                                            scenario's water_table rule */
  karst_routing_t routing;             /**< default: the scenario's routing */
  double gamma, reuse;                 /**< default: the scenario's skeleton.gamma, .reuse */
  karst_amplification_t amplification; /**< default: the scenario's amplification */
  double cohesion; /**< cost factor of the earlier generations' conduits, (0, 1], default
                        KARST_SCENARIO_DEFAULT_COHESION */
  int line, column;
} karst_generation_t;

/** Default of generations[i].cohesion (KarstNSim's fraction_old_karst_perm default, 0.5). */
#define KARST_SCENARIO_DEFAULT_COHESION 0.5
/** Most generations of a scenario. */
#define KARST_SCENARIO_MAX_GENERATIONS 16

/** A survey file the realisations are conditioned on (docs/scenario.md, "Conditioning"). */
typedef struct karst_survey_def {
  char *path; /**< as resolved relative to the scenario */
  char *crs;  /**< its CRS when the scenario states it (it overrides the file's), or NULL */
  int line, column;
} karst_survey_def_t;

/** Which survey stations become sinks (conditioning.sinks). */
typedef enum {
  KARST_CONDITIONING_SINKS_NONE = 0,      /**< none (default) */
  KARST_CONDITIONING_SINKS_ENTRANCES = 1, /**< every station the survey flags as an entrance */
  KARST_CONDITIONING_SINKS_LIST = 2       /**< the stations named in sink_stations */
} karst_conditioning_sinks_t;

struct karst_survey_set; /* include/karst/conditioning.h: stations and legs in the scenario frame */

/** Conditioning on surveyed passages (docs/scenario.md, "Conditioning"). */
typedef struct karst_conditioning {
  int n_surveys;
  karst_survey_def_t *surveys;
  double cost_factor; /**< a surveyed metre costs this times the cheapest metre of rock, (0, 1],
                           default KARST_SCENARIO_DEFAULT_LEG_COST_FACTOR */
  int sinks;          /**< karst_conditioning_sinks_t */
  int n_sink_stations;
  char **sink_stations; /**< station names (sinks: [names]) */
  int generation;       /**< generation (1-based) whose routes join the survey; 0: the last */
  struct karst_survey_set *data; /**< the surveys as read, in the scenario frame, or NULL */
  int line, column;
} karst_conditioning_t;

/** Default of conditioning.cost_factor: a surveyed metre costs 1 % of the cheapest metre of rock.
 */
#define KARST_SCENARIO_DEFAULT_LEG_COST_FACTOR 0.01

typedef struct karst_scenario {
  char *path; /**< file the scenario was read from (NULL if built in code) */
  char *name;
  double domain_min[3], domain_max[3];
  karst_terrain_t terrain;
  /** The water table of springs that give none of their own (water_table:); not given: each
   *  spring's water table is the horizontal plane through it. */
  karst_surface_def_t water_table;
  int n_horizons;
  karst_horizon_t *horizons;
  int n_fractures;
  karst_fracture_t *fractures;
  karst_permeability_t permeability;
  int n_strata;
  karst_stratum_t *strata;
  int n_exclusions;
  karst_exclusion_t *exclusions;
  int n_faults;
  karst_fault_t *faults;
  karst_connectivity_t connectivity;
  karst_routing_t routing;
  int n_key_points;
  karst_keypoint_t *key_points;
  int n_prescribed;
  karst_prescribed_path_t *prescribed;
  karst_cost_weights_t cost;
  karst_sampling_t sampling;
  double gamma; /**< γ-skeleton parameter, > 0 (§5.1) */
  double reuse; /**< skeleton.reuse: cost factor of graph edges already in the
                     network while later paths are laid, (0, 1], default
                     KARST_SCENARIO_DEFAULT_REUSE (1 = plain union of paths) */
  karst_amplification_t amplification;
  double tortuosity; /**< θ in [0, 1] (§5.2) */
  karst_classification_t classification;
  uint64_t seed;
  int realisations; /**< >= 1 */
  /* Where blocks named by cross-field messages were given (0 when defaulted or built in code). */
  karst_srcpos_t pos_domain;        /**< the domain map */
  karst_srcpos_t pos_terrain;       /**< terrain.elevation or terrain.heightfield value */
  karst_srcpos_t pos_amplification; /**< the amplification map */
  karst_srcpos_t pos_water_table;   /**< the water_table map */
  karst_srcpos_t pos_key_points;    /**< the key_points list */
  karst_srcpos_t pos_sampling;      /**< the sampling map */
  /* Where the keys behind the resource estimate were given (include/karst/budget.h). */
  karst_srcpos_t pos_fill_radius, pos_feature_radius, pos_k, pos_max_samples, pos_points;
  karst_srcpos_t pos_amplification_steps, pos_amplification_points;
  karst_geometry_t geometry;           /**< `karst mesh`: blending, wall details, speleothems */
  struct karst_blocks_section *blocks; /**< the blocks section (karst blocks), NULL when absent */
  /** The coordinate reference system of every coordinate of the file (crs:, docs/scenario.md,
   *  "Coordinates"), as given, or NULL: a local frame. */
  char *crs;
  struct karst_crs *crs_frame; /**< crs parsed (include/karst/crs.h), or NULL */
  karst_srcpos_t pos_crs;
  int n_generations; /**< 0: one phase with the top-level parameters */
  karst_generation_t *generations;
  karst_conditioning_t conditioning;
  /** The generation a view of the scenario routes (karst_generation_view): its key points and
   *  the top-level ones take part; 0 (a loaded scenario): every key point. */
  int active_generation;
} karst_scenario_t;

/** Fill @p sc with every documented default (docs/scenario.md): no key points, flat terrain at 100
 * m. */
void karst_scenario_init(karst_scenario_t *sc);
/** Release what a scenario holds. */
void karst_scenario_destroy(karst_scenario_t *sc);

/**
 * Read and validate a YAML scenario. On failure returns an error code and
 * ctx->errmsg holds "FILE:LINE:COLUMN: message" naming the field and value.
 */
karst_error_t karst_scenario_load(karst_ctx_t *ctx, const char *path, karst_scenario_t *sc);

/**
 * Set an error about a value of @p sc: "FILE:LINE:COLUMN: message" when the
 * scenario came from a file (1:1 for a rule about something the file left
 * out, line <= 0), the bare message otherwise. Returns @p code. For the stages
 * that check a parsed scenario (geology, budget) so every such message has one
 * form. O(message).
 */
karst_error_t karst_scenario_fail_at(karst_ctx_t *ctx, const karst_scenario_t *sc, int line,
                                     int col, karst_error_t code, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));

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
 * document re-emitted by libyaml; every relative file path it reads (terrain.heightfield,
 * surfaces of the terrain, the water table, horizons, strata ...) is rewritten to resolve from
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

/**
 * The files scenario @p path reads besides itself (terrain.heightfield, surfaces of the
 * terrain, water tables, horizons, strata ...), as paths usable from the working directory,
 * into a new array *@p files of *@p n strings (free each and the array). Errors as
 * karst_scenario_load.
 */
karst_error_t karst_scenario_files(karst_ctx_t *ctx, const char *path, char ***files, int *n);

/** Check the cross-field rules (key points inside the domain and below the terrain, a spring
 * present ...). */
karst_error_t karst_scenario_check(karst_ctx_t *ctx, const karst_scenario_t *sc);

/**
 * Read a point cloud file (sampling.points, docs/scenario.md): one point "x y z" per line (m),
 * separated by blanks or commas, '#' comment lines, blank lines, an optional header "x y z".
 * @param xyz receives 3 × *@p n coordinates in the file's order (free() it).
 * @param lines if not NULL, receives each point's line in the file (free() it).
 * @return KARST_SUCCESS; KARST_EPARSE naming the file, line, column and field (x, y or z) for a
 *         field that is not a finite number, a missing or extra field, a line over 4096 bytes, a
 *         point repeating an earlier one (both lines given) or a file without points;
 *         KARST_ERANGE beyond KARST_POINTS_MAX_POINTS points or KARST_POINTS_MAX_BYTES bytes;
 *         KARST_EIO (missing, unreadable, not a regular file), KARST_ENOMEM. Nothing is returned
 *         on failure.
 * Time complexity: O(file size + n).
 */
karst_error_t karst_points_load(karst_ctx_t *ctx, const char *path, double **xyz, karst_int_t *n,
                                long **lines);

/** Read an ESRI ASCII grid (.asc) into @p t; errors name the file, line and field. */
karst_error_t karst_terrain_load_grid(karst_ctx_t *ctx, const char *path, karst_terrain_t *t);

/* The geological fields of a scenario (terrain height, horizons, permeability, water tables,
 * bedrock membership) are evaluated by the geology module: include/karst/geology.h. */

/** Stable hash (FNV-1a 64) of a file's bytes, as 16 hex digits in @p out (17 bytes). */
karst_error_t karst_file_hash(karst_ctx_t *ctx, const char *path, char out[17]);

#ifdef __cplusplus
}
#endif
#endif /* KARST_SCENARIO_H */
