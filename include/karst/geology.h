/**
 * @file geology.h
 * @brief The geological model of a scenario: one place that answers "what is the rock here".
 *        Terrain, strata and inception horizons, the water table of each spring, fractures
 *        (families and discrete fracture networks) and faults, exclusion zones and
 *        permeability, built once per realisation from a parsed scenario. Sampling, costs,
 *        routing, classification and amplification ask it; they do not re-derive it.
 *        Every quantity is documented in docs/scenario.md and docs/generation.md.
 */
#ifndef KARST_GEOLOGY_H
#define KARST_GEOLOGY_H

#include <stdint.h>

#include "karst/common.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Fields of the parsed scenario, evaluated directly                        */
/* ------------------------------------------------------------------------ */

/** Terrain elevation at (x, y) (bilinear on the grid, clamped at its border). O(1). */
double karst_terrain_height(const karst_terrain_t *t, double x, double y);

/** Elevation of horizon @p h at (x, y) (its plane or its surface file). */
double karst_horizon_elevation(const karst_horizon_t *h, double x, double y);

/** Elevation of a scenario surface at (x, y); NAN when @p s is not given or not defined there. */
double karst_surface_def_z(const karst_surface_def_t *s, double x, double y);

/** Unit normal (x east, y north, z up) of a plane given by dip direction and dip (degrees). */
void karst_plane_normal(double dip_direction, double dip, double n[3]);

/** Resistance π(p) in [0, 1] from the permeability tree (§4.2). */
double karst_permeability_eval(const karst_permeability_t *perm, const double p[3]);

/* ------------------------------------------------------------------------ */
/* Zones relative to a water table                                           */
/* ------------------------------------------------------------------------ */

/** Water-table zones (docs/generation.md, "Routing"), X-macro: code, name. */
#define KARST_ZONE_LIST(X)                                                                         \
  X(KARST_ZONE_VADOSE, "vadose")                                                                   \
  X(KARST_ZONE_EPIPHREATIC, "epiphreatic")                                                         \
  X(KARST_ZONE_PHREATIC, "phreatic")

/** Zone of a point: above the epiphreatic band of a water table, within it, below it. */
typedef enum {
#define KARST_X_ENUM(code, name) code,
  KARST_ZONE_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_ZONE_COUNT
} karst_zone_t;

/** Name of a zone ("vadose", "epiphreatic", "phreatic"), "unknown" out of range. */
const char *karst_zone_name(int zone);

/* ------------------------------------------------------------------------ */
/* The model                                                                 */
/* ------------------------------------------------------------------------ */

/** A disc in space: a realised fracture of a discrete fracture network, or a fault disc. */
typedef struct karst_disc {
  double c[3]; /**< centre (m) */
  double n[3]; /**< unit normal (pole), z >= 0 */
  double r;    /**< radius (m); INFINITY for an unbounded plane */
  int family;  /**< index of the fracture family (or of the fault) it belongs to */
} karst_disc_t;

/** What karst_geology_exclusion_at reports: an exclusion zone, or an insoluble stratum. */
typedef enum {
  KARST_EXCLUDED_NONE = 0,
  KARST_EXCLUDED_ZONE = 1,
  KARST_EXCLUDED_STRATUM = 2
} karst_excluded_t;

typedef struct karst_geology karst_geology_t;

/**
 * Build the geological model of @p sc for realisation @p realisation of base seed @p seed: the
 * surfaces it needs (the terrain, horizons, strata, each spring's water table), the discs of
 * every discrete fracture network, drawn from the realisation's own stream (so the same seed
 * gives the same discs whatever the thread count), and the spatial indices its queries use.
 * Checks what only the geology can say: every key point in the bedrock and outside every
 * exclusion zone (FILE:LINE:COLUMN of the key point), each water table and stratum surface
 * defined over the domain. @p sc must outlive the model.
 * @return KARST_SUCCESS, KARST_EINVAL / KARST_ERANGE with the rule broken, KARST_ENOMEM.
 */
karst_error_t karst_geology_create(karst_ctx_t *ctx, const karst_scenario_t *sc, uint64_t seed,
                                   uint64_t realisation, karst_geology_t **out);
void karst_geology_free(karst_geology_t *g);

/** The scenario the model was built from. */
const karst_scenario_t *karst_geology_scenario(const karst_geology_t *g);

/** Terrain elevation at (x, y). O(1) (grid) or O(1) expected (triangulated). */
double karst_geology_terrain(const karst_geology_t *g, double x, double y);

/**
 * Whether @p p is in the karstifiable bedrock: inside the closed domain box, at or below the
 * terrain, outside every exclusion zone and every insoluble stratum. O(exclusions + strata).
 */
int karst_geology_in_bedrock(const karst_geology_t *g, const double p[3]);

/**
 * Whether every point of the segment [a, b] is in the bedrock (exact: the terrain test on the
 * surface's pieces, exact segment–box, –sphere, –prism and –stratum tests). The ends may lie on
 * the ground; the interior must be strictly below it.
 */
int karst_geology_segment_in_bedrock(const karst_geology_t *g, const double a[3],
                                     const double b[3]);

/**
 * Which exclusion holds @p p: KARST_EXCLUDED_ZONE (exclusions[*index]), KARST_EXCLUDED_STRATUM
 * (strata[*index], insoluble) or KARST_EXCLUDED_NONE. @p index may be NULL.
 */
karst_excluded_t karst_geology_exclusion_at(const karst_geology_t *g, const double p[3],
                                            int *index);

/** The stratum holding @p p (index into the scenario's strata, the first that holds it), or -1. */
int karst_geology_stratum_at(const karst_geology_t *g, const double p[3]);

/** Horizon term cL(p) in [0, 1] (1 without horizons; Paris et al. 2021, §4.2). */
double karst_geology_horizon_term(const karst_geology_t *g, const double p[3]);

/** Resistance π(p) in [0, 1] (permeability tree, §4.2). */
double karst_geology_permeability(const karst_geology_t *g, const double p[3]);

/** Number of springs; spring i is key point karst_geology_spring_key(g, i). */
int karst_geology_n_springs(const karst_geology_t *g);
int karst_geology_spring_key(const karst_geology_t *g, int spring);
/** Spring index of key point @p key, or -1 when it is not a spring. */
int karst_geology_spring_of_key(const karst_geology_t *g, int key);

/** Elevation at (x, y) of the water table of spring @p spring. */
double karst_geology_water_table(const karst_geology_t *g, int spring, double x, double y);

/** Zone of @p p relative to the water table of @p spring and routing.water_table_band. */
karst_zone_t karst_geology_zone(const karst_geology_t *g, int spring, const double p[3]);

/** The discs of the realised discrete fracture networks (all families), and their count. */
const karst_disc_t *karst_geology_discs(const karst_geology_t *g, karst_int_t *n);

/**
 * Write the model as polygons for ParaView: the terrain, horizons, water tables and strata
 * surfaces over the domain, the fault and fracture discs and the exclusion zones, with cell
 * arrays "feature" (karst_geology_feature names, in field data "feature_names") and
 * "feature_id" (index within its kind). Atomic.
 */
karst_error_t karst_geology_write_vtp(karst_ctx_t *ctx, const karst_geology_t *g, const char *path);

/** Kinds of object in geology.vtp, X-macro: code, name. */
#define KARST_GEOLOGY_FEATURE_LIST(X)                                                              \
  X(KARST_FEATURE_TERRAIN, "terrain")                                                              \
  X(KARST_FEATURE_HORIZON, "horizon")                                                              \
  X(KARST_FEATURE_WATER_TABLE, "water_table")                                                      \
  X(KARST_FEATURE_STRATUM, "stratum_boundary")                                                     \
  X(KARST_FEATURE_FAULT, "fault")                                                                  \
  X(KARST_FEATURE_FRACTURE, "fracture")                                                            \
  X(KARST_FEATURE_EXCLUSION, "exclusion")

typedef enum {
#define KARST_X_ENUM(code, name) code,
  KARST_GEOLOGY_FEATURE_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_GEOLOGY_FEATURE_COUNT
} karst_geology_feature_t;

/** Name of a geology.vtp feature kind, "unknown" out of range. */
const char *karst_geology_feature_name(int feature);

#ifdef __cplusplus
}
#endif
#endif /* KARST_GEOLOGY_H */
