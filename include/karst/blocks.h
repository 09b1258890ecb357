/**
 * @file blocks.h
 * @brief Rock blocks from fractured periodic tiles and their replication
 *        over a terrain (Paris et al. 2020, "Modeling rocky scenery using
 *        implicit blocks", §4–5).
 *
 * A tile is a cube of side s, periodic in x, y and z. Poisson-disc points
 * sample it, a neighbour graph joins points closer than the graph radius,
 * fracture discs drawn per block type (§4.1) cut edges, and the remaining
 * graph falls into clusters that are split until every two points of a
 * cluster see each other (no disc crosses their segment, §4.1–4.2). Each
 * cluster becomes a convex block: the cell bounded by the fracture planes
 * around it, intersected with its convex hull grown by a margin (CGAL,
 * src/geometry/cgal_shim.cpp), whose planes are combined by the smooth
 * intersection of src/implicit/ (§4.2). Degenerate clusters become thick
 * points, segments or polygons. The replication operator (§5) repeats the
 * blocks of one tile per stratum wherever their anchor points pass the
 * presence criteria, as one external field of a construction tree.
 *
 * Sign convention as in implicit.h: fields are negative inside the rock and
 * 1-Lipschitz. docs/blocks.md explains every parameter and where this
 * implementation departs from the paper.
 */
#ifndef KARST_BLOCKS_H
#define KARST_BLOCKS_H

#include "karst/common.h"
#include "karst/implicit.h"
#include "karst/vtk.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The block types of Paris et al. 2020, Fig. 2 and §4.1 (Palmström 2001). */
#define KARST_BLOCK_TYPE_LIST(X)                                                                   \
  X(KARST_BLOCK_EQUIDIMENSIONAL, "equidimensional")                                                \
  X(KARST_BLOCK_PRISMATIC, "prismatic")                                                            \
  X(KARST_BLOCK_POLYHEDRAL, "polyhedral")                                                          \
  X(KARST_BLOCK_RHOMBOHEDRAL, "rhombohedral")                                                      \
  X(KARST_BLOCK_TABULAR, "tabular")                                                                \
  X(KARST_BLOCK_COLUMNAR, "columnar")

typedef enum {
#define KARST_X_ENUM(code, name) code,
  KARST_BLOCK_TYPE_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_BLOCK_TYPE_COUNT
} karst_block_type_t;

/** Name of a block type ("equidimensional", ...), or "unknown". */
const char *karst_block_type_name(int type);
/** The type named @p name, or -1. */
int karst_block_type_from_name(const char *name);
/** The names of the types, in enum order (KARST_BLOCK_TYPE_COUNT of them). */
const char *const *karst_block_type_names(void);

/** A fracture disc D(c, r, n) (§4.1): centre, unit normal, radius. */
typedef struct karst_blocks_disc {
  double c[3], n[3], radius;
} karst_blocks_disc_t;

/** Where the relief of the blocks' warping comes from (the warp node of implicit.h). */
typedef enum {
  KARST_BLOCKS_RELIEF_NONE = 0, /**< no warping */
  KARST_BLOCKS_RELIEF_NOISE,    /**< procedural value-noise turbulence */
  KARST_BLOCKS_RELIEF_IMAGE     /**< a greyscale image (PGM or PNG, karst_image_read) */
} karst_blocks_relief_kind_t;

/** The relief d of the gradient-based warping ω⁻¹ of each block (§4.3). */
typedef struct karst_blocks_warp {
  karst_blocks_relief_kind_t relief; /**< none (default), procedural noise, or an image */
  double amplitude;                  /**< largest displacement (m), default 0.15 */
  double wavelength; /**< noise wavelength, or the ground size of the image (m), default 2 */
  const char *image; /**< PGM or PNG path for KARST_BLOCKS_RELIEF_IMAGE (borrowed) */
} karst_blocks_warp_t;

/**
 * Parameters of one tile. karst_blocks_tile_params_init fills every field
 * with the defaults of a type (docs/blocks.md lists them with their source).
 */
typedef struct karst_blocks_tile_params {
  int type;              /**< karst_block_type_t */
  double size;           /**< s: side of the cubic tile (m), default 20 (§4) */
  double poisson_radius; /**< r: smallest distance between sample points (m), default 0.69 */
  double graph_radius;   /**< points closer than this are neighbours (m), default 2 r */
  double smooth_radius;  /**< R of the smooth intersection (m), default 0.25 (§4.2) */
  double aperture;       /**< joint aperture: faces move in by half of it (m), default 0.04 */
  double hull_margin; /**< Δ: the hull of a cluster is grown by this (m), default graph_radius */
  double degenerate_radius; /**< thickness of point/segment/polygon blocks (m), default r */
  int n_discs;              /**< random fracture discs drawn, type default */
  double disc_spacing;      /**< Poisson radius of the disc centres (m), type default (§4.1) */
  double disc_radius_min;   /**< radius range of the type's ordinary discs (m) */
  double disc_radius_max;
  double tilt;            /**< degrees: prismatic irregularity, rhombohedral obliquity */
  int n_bedding;          /**< tabular bedding planes / columnar cross joints */
  double bedding_spacing; /**< smallest distance between bedding planes (m) */
  int dart_passes;        /**< Poisson dart passes per background cell, default 8 */
  uint64_t seed;          /**< seed of the tile's random streams, default 1 */
  const karst_blocks_disc_t
      *user_discs; /**< discs placed by the user (tile coordinates), borrowed */
  int n_user_discs;
  /** User-authored blocks: nodes of @p authored (borrowed, tile coordinates,
   *  any construction tree). Sample points inside them are theirs; the
   *  other blocks are cut so as not to enter them. */
  const karst_sdf_t *authored;
  const karst_int_t *authored_nodes;
  int n_authored;
  karst_blocks_warp_t warp; /**< small-scale relief (§4.3), default none */
} karst_blocks_tile_params_t;

/** The defaults of @p type (Paris et al. 2020, §4.1 and Table 1; docs/blocks.md). */
void karst_blocks_tile_params_init(karst_blocks_tile_params_t *par, int type);
/**
 * Another tile side and Poisson radius for @p par: the fracture discs' spacing, radii and
 * bedding spacing scale with the side (the paper's distributions are for 20 m, §4.1; the disc
 * counts stay), the graph radius and hull margin become 2 r and the degenerate radius r
 * (docs/blocks.md). Smooth radius and aperture are left as they are. O(1).
 */
void karst_blocks_tile_params_resize(karst_blocks_tile_params_t *par, double size,
                                     double poisson_radius);
/** Check a parameter set: every value finite and in range, with a message naming it. */
karst_error_t karst_blocks_tile_params_check(karst_ctx_t *ctx, const karst_blocks_tile_params_t *p);

/** How a block's field is made. */
typedef enum {
  KARST_BLOCK_CONVEX = 0, /**< smooth intersection of the polytope's planes */
  KARST_BLOCK_THICK,      /**< degenerate cluster: thick point, segment or polygon */
  KARST_BLOCK_AUTHORED    /**< a user-authored construction tree */
} karst_block_kind_t;

typedef struct karst_blocks_block {
  karst_block_kind_t kind;
  /** its sample points: tile->members[first .. first+n_points); an authored block's
   *  n_points counts the points inside it, which are not in tile->members */
  karst_int_t first, n_points;
  karst_int_t node;     /**< its field in tile->sdf (authored: in par.authored) */
  double box[6];        /**< box of its solid, tile coordinates (may leave [0, s)³) */
  double anchor[3];     /**< centroid of its points, inside [0, s)³ */
  double volume;        /**< polytope volume, divergence theorem on its triangles */
  double cgal_volume;   /**< the same measured by CGAL (PMP::volume) */
  karst_int_t n_planes; /**< planes of its smooth intersection */
} karst_blocks_block_t;

/** The statistics of Table 1 of Paris et al. 2020, and a few more. */
typedef struct karst_blocks_tile_stats {
  karst_int_t n_points, n_discs, n_blocks;
  double mean_points;   /**< sample points per block (authored blocks excluded) */
  karst_int_t n_edges;  /**< graph edges */
  karst_int_t n_cut;    /**< edges cut by a disc */
  karst_int_t n_splits; /**< visibility and periodicity splits */
  karst_int_t n_thick;  /**< degenerate blocks */
  double seconds;       /**< wall-clock time of karst_blocks_tile_create */
} karst_blocks_tile_stats_t;

typedef struct karst_blocks_tile {
  karst_blocks_tile_params_t par; /**< as given (user discs and authored trees borrowed) */
  karst_int_t n_points;
  double *xyz; /**< 3 n_points sample points in [0, s)³ */
  int n_discs;
  karst_blocks_disc_t *discs; /**< random discs then the user's */
  karst_int_t n_blocks;
  karst_blocks_block_t *blocks;
  karst_int_t *members; /**< sample indices of the blocks, block by block */
  double *unwrapped;    /**< 3 per member: its position in the block's frame */
  karst_mesh_t *hulls;  /**< per block: the polytope's triangles (empty for other kinds) */
  karst_sdf_t *sdf;     /**< the blocks' fields */
  karst_blocks_tile_stats_t stats;
  void *internal; /**< relief and evaluation data */
} karst_blocks_tile_t;

/**
 * Make a tile: sampling, graph, discs, clusters, blocks (Paris et al. 2020,
 * §4). Heavy steps run on ctx->nthreads; the tile is the same for any thread
 * count. Progress stage "blocks". Time: O(N (k + D')) for N points, k
 * neighbours and D' discs near an edge, plus the hulls.
 * @param out receives the tile (karst_blocks_tile_free)
 */
karst_error_t karst_blocks_tile_create(karst_ctx_t *ctx, const karst_blocks_tile_params_t *par,
                                       karst_blocks_tile_t **out);
void karst_blocks_tile_free(karst_blocks_tile_t *tile);

/** Field of block @p i at @p p (tile coordinates, not periodic), its authored
 *  neighbours carved out. 1-Lipschitz. */
double karst_blocks_block_eval(const karst_blocks_tile_t *tile, karst_int_t i, const double p[3]);
/** Periodic field of the whole tile: the union of every block at p + s Z³. */
double karst_blocks_tile_eval(const karst_blocks_tile_t *tile, const double p[3]);
/**
 * 1 when the segment a–b (tile coordinates, any frame) crosses no disc of
 * the tile nor any periodic copy of one, and no authored block. The brute-
 * force check of mutual visibility (§4.1). O(discs × images).
 */
int karst_blocks_segment_visible(const karst_blocks_tile_t *tile, const double a[3],
                                 const double b[3]);

/**
 * Polygonize every block of the tile separately at @p voxel metres into
 * @p out (initialised, emptied first), closed and manifold block by block,
 * with the cell array "block_id" (the block's index) in out->tri_label.
 */
karst_error_t karst_blocks_tile_mesh(karst_ctx_t *ctx, const karst_blocks_tile_t *tile,
                                     double voxel, karst_mesh_t *out);

/**
 * Write run.json: every parameter of the @p n tiles and their Table 1
 * statistics (points, discs, blocks, mean points per block, seconds);
 * @p extra (may be NULL) adds JSON members to the top object. Atomic.
 */
karst_error_t karst_blocks_write_run(karst_ctx_t *ctx, const char *path,
                                     const karst_blocks_tile_t *const *tiles, int n,
                                     const char *command, const char *extra);

/* ------------------------------------------------------------------------ */
/* Replication over a terrain (§5).                                          */
/* ------------------------------------------------------------------------ */

/** Stratum of a point: an index into the caller's stratum table, or -1. */
typedef int (*karst_blocks_stratum_fn)(void *arg, const double p[3]);

/** The presence criteria of §5, tested at the anchor points of a block copy. */
typedef struct karst_blocks_presence {
  double dist_min, dist_max; /**< [v_a, v_b]: terrain field at the anchor (m), default [-1, 2] */
  double max_slope; /**< ε: |g.u_z| must be below it, default 0.5 (wall steeper than 60°) */
  int n_anchors;    /**< anchor points per block, default 8 */
  double quorum;    /**< fraction that must pass, strictly more than it, default 0.5 */
} karst_blocks_presence_t;

void karst_blocks_presence_init(karst_blocks_presence_t *p);

/** A terrain replicated with blocks: build with karst_blocks_replicate. */
typedef struct karst_blocks_replica karst_blocks_replica_t;

/**
 * Prepare the replication operator t of §5 over @p region (lo, hi): for every
 * cell of the virtual grid of side s meeting the region and every block of
 * every tile, whether the block is present (more than quorum × n_anchors of
 * its anchors a + s C have the terrain field in [v_a, v_b], |g.u_z| < ε and
 * a stratum whose tile is this one). The terrain field is node @p terrain of
 * @p tree (borrowed); @p stratum_tile[k] is the tile index of stratum k
 * (-1: no blocks). All tiles must have the same size. Presence is computed on
 * ctx->nthreads threads, identically for any count.
 */
karst_error_t karst_blocks_replicate(karst_ctx_t *ctx, const karst_sdf_t *tree, karst_int_t terrain,
                                     const karst_blocks_tile_t *const *tiles, int n_tiles,
                                     karst_blocks_stratum_fn stratum_of, void *stratum_arg,
                                     const int *stratum_tile, int n_strata,
                                     const karst_blocks_presence_t *presence,
                                     const double region[6], karst_blocks_replica_t **out);
void karst_blocks_replica_free(karst_blocks_replica_t *rep);
/** Replicated block copies (presences). */
karst_int_t karst_blocks_replica_count(const karst_blocks_replica_t *rep);

/**
 * Add to @p tree the field of the replication t(p) = min over present copies
 * of b_i(p - s C) (§5; min because fields are negative inside), capped at
 * s/4 far from every block, as an external node (the replica is borrowed
 * and must outlive the tree's use). Labels encode the block (below).
 */
karst_error_t karst_blocks_replica_node(karst_ctx_t *ctx, const karst_blocks_replica_t *rep,
                                        karst_sdf_t *tree, karst_int_t *node);

/* ------------------------------------------------------------------------ */
/* The blocks section of a scenario (read by src/scenario/scenario.c).       */
/* ------------------------------------------------------------------------ */

/** The node kinds of an authored block's construction tree (blocks.authored, docs/blocks.md). */
typedef enum {
  KARST_BLOCKS_SHAPE_SPHERE = 0,   /**< centre a, radius */
  KARST_BLOCKS_SHAPE_BOX,          /**< corners a (min) and b (max) */
  KARST_BLOCKS_SHAPE_UNION,        /**< of its children */
  KARST_BLOCKS_SHAPE_INTERSECTION, /**< of its children */
  KARST_BLOCKS_SHAPE_DIFFERENCE    /**< first child minus the others */
} karst_blocks_shape_kind_t;

/** A node of an authored block, in tile coordinates (m). */
typedef struct karst_blocks_shape {
  int kind; /**< karst_blocks_shape_kind_t */
  double a[3], b[3], radius;
  int n_children;
  struct karst_blocks_shape *children;
  int line, column; /**< where the node is in the scenario */
} karst_blocks_shape_t;

/** A user-authored block (§4.1) of the tile of type @c tile. */
typedef struct karst_blocks_authored {
  int tile; /**< karst_block_type_t */
  karst_blocks_shape_t shape;
  int line, column;
} karst_blocks_authored_t;

/** Bounding box lo[3], hi[3] of @p s (empty: lo > hi). O(nodes). */
void karst_blocks_shape_box(const karst_blocks_shape_t *s, double box[6]);

/** A user-placed fracture disc (§4.1) of the tile of type @c tile (blocks.user_discs). */
typedef struct karst_blocks_user_disc {
  int tile;                 /**< karst_block_type_t */
  karst_blocks_disc_t disc; /**< tile coordinates; the normal as given (the tile normalises it) */
  int line, column;
} karst_blocks_user_disc_t;

/** A stratum by elevation band: below @c below (the last may be unbounded). */
typedef struct karst_blocks_stratum {
  char *name;
  double below; /**< top of the band (m); +infinity when not given */
  int tile;     /**< karst_block_type_t of its blocks */
  int line, column;
} karst_blocks_stratum_t;

/** The `blocks` section: tile parameters shared by the tiles, presence, strata. */
typedef struct karst_blocks_section {
  double tile_size, poisson_radius, graph_radius, smooth_radius, aperture, hull_margin;
  double voxel;      /**< polygonization of terrain_blocks.vtp (m), default 0.5 */
  double tile_voxel; /**< polygonization of tiles/<type>.vtp (m), default 0.1 */
  uint64_t seed;
  int has_seed;     /**< else the scenario's random.seed */
  double region[4]; /**< x0, y0, x1, y1 of the amplified part of the terrain */
  int has_region;   /**< else the scenario's domain */
  karst_blocks_presence_t presence;
  int warp_relief; /**< karst_relief_kind_t */
  double warp_amplitude, warp_wavelength;
  char *warp_image; /**< resolved relative to the scenario's directory */
  int n_strata;
  karst_blocks_stratum_t *strata;
  int n_authored;                       /**< user-authored blocks (blocks.authored) */
  karst_blocks_authored_t *authored;    /**< in tile coordinates, each in its type's tile */
  int n_user_discs;                     /**< user-placed fracture discs (blocks.user_discs) */
  karst_blocks_user_disc_t *user_discs; /**< in tile coordinates, each in its type's tile */
  int line, column;                     /**< where the section starts */
} karst_blocks_section_t;

/** Defaults (docs/blocks.md). */
void karst_blocks_section_init(karst_blocks_section_t *b);
/** Release what the section holds and the section itself (NULL allowed). */
void karst_blocks_section_free(karst_blocks_section_t *b);
/** The elevation-band stratum of @p p (a karst_blocks_stratum_fn; @p arg is the section). */
int karst_blocks_section_stratum(void *arg, const double p[3]);
/** Tile parameters of type @p type from the section (defaults of the type, the section's values).
 */
void karst_blocks_section_tile_params(const karst_blocks_section_t *b, int type, uint64_t seed,
                                      karst_blocks_tile_params_t *par);

/**
 * The user-placed discs of the section @p b whose tile is @p type, copied to @p discs
 * (capacity b->n_user_discs); returns their count. O(discs).
 */
int karst_blocks_section_user_discs(const karst_blocks_section_t *b, int type,
                                    karst_blocks_disc_t *discs);

/**
 * Add the authored blocks of the section @p b whose tile is @p type to @p tree: their node
 * indices go to @p nodes (capacity b->n_authored), *n their count. O(nodes).
 */
karst_error_t karst_blocks_section_authored(karst_ctx_t *ctx, const karst_blocks_section_t *b,
                                            int type, karst_sdf_t *tree, karst_int_t *nodes,
                                            int *n);

/* ------------------------------------------------------------------------ */
/* A scenario's terrain amplified with blocks.                               */
/* ------------------------------------------------------------------------ */

typedef struct karst_blocks_amplified karst_blocks_amplified_t;

/**
 * Tiles of the section's strata, their replication over the scenario's
 * terrain in the section's region (default the domain) and T ∪ R added to
 * @p tree as *node (see amplify.c). @p sc and @p tree must outlive *out.
 */
karst_error_t karst_blocks_amplify(karst_ctx_t *ctx, const karst_scenario_t *sc, karst_sdf_t *tree,
                                   karst_blocks_amplified_t **out, karst_int_t *node);
void karst_blocks_amplified_free(karst_blocks_amplified_t *a);
/** The tiles (one per distinct type, in the order of the strata); returns their count. */
int karst_blocks_amplified_tiles(const karst_blocks_amplified_t *a,
                                 const karst_blocks_tile_t *const **tiles);
const karst_blocks_replica_t *karst_blocks_amplified_replica(const karst_blocks_amplified_t *a);
/** The amplified region (lo, hi): region × the domain's z range. */
void karst_blocks_amplified_box(const karst_blocks_amplified_t *a, double box[6]);
/** Step inside a triangle, in units of its mean edge, at which karst_blocks_relabel_mesh
 *  asks the tree for the deciding primitive. */
#define KARST_BLOCKS_RELABEL_DEPTH 0.25
/** Per-triangle block_id and block_type (-1: no block) of a mesh polygonized from @p tree, and
 *  its tunnel_type labels with -1 on blocks (see amplify.c). */
void karst_blocks_relabel_mesh(karst_ctx_t *ctx, const karst_sdf_t *tree, karst_mesh_t *m, int *id,
                               int *type);

/** Labels of block triangles: KARST_BLOCKS_LABEL_BASE + type << 20 | block id. */
#define KARST_BLOCKS_LABEL_BASE (1 << 24)
#define KARST_BLOCKS_LABEL(type, id) (KARST_BLOCKS_LABEL_BASE + ((type) << 20) + (int)(id))
/** Decode a label: 1 and the type and id for a block label, else 0 (-1, -1). */
int karst_blocks_label_decode(int label, int *type, int *id);

#ifdef __cplusplus
}
#endif
#endif /* KARST_BLOCKS_H */
